"""Hostile input: each bad URDF or experiment file gets its own error class and a clear message,
the command line answers with exit code 2 and one line, and docs/bad-inputs.md is up to date."""

import warnings
from pathlib import Path

import pytest

from nnrobust.cli import main
from nnrobust.exceptions import NNRobustError

from .bad_inputs import CASES, CONFIG_CASES, URDF_CASES, BuildExperiment, ReadConfig, message_of, render_table

DOCS = Path(__file__).resolve().parents[1] / "docs" / "bad-inputs.md"


@pytest.mark.parametrize("case", CASES, ids=[c.what for c in CASES])
def test_bad_input_gets_its_error_and_message(case, tmp_path):
    action = case.make(tmp_path)
    if case.error is None:
        with pytest.warns(case.warns, match=case.fragment):
            action()
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(case.error) as info:
            action()
    assert isinstance(info.value, NNRobustError)
    assert case.fragment in str(info.value)


@pytest.mark.parametrize("case", [c for c in URDF_CASES if c.error is not None and "frame" not in c.what],
                         ids=lambda c: c.what)
def test_command_line_answers_a_bad_urdf_with_one_line(case, tmp_path, capsys, monkeypatch):
    """The same URDFs named in an experiment file: exit code 2, one 'nnrobust: error:' line."""
    import nnrobust.model.loading as loading

    captured = {}

    def spy(source, *args, **kwargs):  # learn which source the case loads, then load it via the CLI
        captured["source"] = str(source)
        raise StopIteration

    monkeypatch.setattr(loading, "load_robot", spy)
    import nnrobust

    monkeypatch.setattr(nnrobust, "load_robot", spy)
    try:
        case.make(tmp_path)()
    except StopIteration:
        pass
    monkeypatch.undo()
    source = captured["source"]
    if source.lstrip().startswith("<"):
        path = tmp_path / "inline.urdf"
        path.write_text(source)
        source = str(path)
    experiment = tmp_path / "bad.toml"
    experiment.write_text(f'[robot]\nsource = "{source}"\n')
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["run", str(experiment), "--out", str(tmp_path / "run"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("nnrobust: error: "), err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("case", CONFIG_CASES, ids=[c.what for c in CONFIG_CASES])
def test_command_line_answers_a_bad_experiment_with_one_line(case, tmp_path, capsys):
    action = case.make(tmp_path)
    if isinstance(action, BuildExperiment):
        path = tmp_path / "experiment.toml"
        path.write_text(action.toml())
    else:
        assert isinstance(action, ReadConfig)
        path = action.path
    code = main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("nnrobust: error: ") and case.fragment in err[0], err
    assert not (tmp_path / "run").exists()


def test_docs_table_is_up_to_date(tmp_path):
    assert DOCS.read_text() == render_table(tmp_path), "run: python -m tests.bad_inputs"


def test_messages_are_single_lines(tmp_path):
    for case in CASES:
        assert "\n" not in message_of(case, tmp_path), case.what


def test_a_long_chain_is_checked_in_linear_time():
    """45 000 links (4.8 MB, near the element limit): the tree and cycle checks stay linear.
    A walk per link to the root took 59 s for 3000 links; the time bound guards against a hang."""
    import time

    from nnrobust.model.urdf_check import check_urdf

    n = 45_000
    parts = ['<robot name="r"><link name="l0"/>']
    parts += [f'<joint name="j{i}" type="fixed"><parent link="l{i - 1}"/><child link="l{i}"/></joint>'
              f'<link name="l{i}"/>' for i in range(1, n)]
    text = "".join(parts) + "</robot>"
    start = time.perf_counter()
    check_urdf(text, "<long chain>")
    assert time.perf_counter() - start < 10.0
