"""The loop closed, as docs/identification.md's walkthrough runs it ("From a log to a certified
law"): a synthetic log (examples/synthetic_log.py) -> ``nnrobust identify`` -> a study over the
identified box with the identified model as the controller's (examples/identified_study.toml) ->
its report's composed claim -> ``nnrobust export --tuned`` of the certified law, which a C program
replays to the certification's torques. And a box in a sweep file: merged, its keys refused where
the file gives them too."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("cvxpy")
pytest.importorskip("distributed")
pytest.importorskip("optuna")
pytest.importorskip("cma")

from nnrobust.cli import main  # noqa: E402
from nnrobust.config import load_config  # noqa: E402
from nnrobust.core.exceptions import ConfigError  # noqa: E402
from nnrobust.model.region import read_region  # noqa: E402
from nnrobust.run import compiled  # noqa: E402
from nnrobust.studies.base.plan import base_config, draw, experiment, load_sweep  # noqa: E402
from nnrobust.studies.study import load_study  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"
CUT = {"tune": 24, "validation": 4, "falsify": 4}
"""examples/identified_study.toml's budgets cut down for the suite (epsilon and beta as shipped)."""


@pytest.fixture(scope="module")
def walked(tmp_path_factory, scheduler):
    """The walkthrough's commands, from a folder laid out like the repository (examples/, out/)."""
    here = tmp_path_factory.mktemp("walk")
    (here / "examples").mkdir()
    shutil.copy(EXAMPLES / "identified.toml", here / "examples")
    study = (EXAMPLES / "identified_study.toml").read_text()
    for key, value in CUT.items():
        study = re.sub(rf"^{key} = .*$", f"{key} = {value}", study, flags=re.M)
    (here / "examples" / "identified_study.toml").write_text(study)
    walk = here / "out" / "walkthrough"
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / "synthetic_log.py"), str(walk), "--seconds", "30"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    identified = walk / "identified"
    argv = ["identify", str(walk / "log.csv"), "--robot", "three_link_planar", "--out", str(identified)]
    assert main([*argv, "--quiet"]) == 0
    out = walk / "study"
    argv = ["study", str(here / "examples" / "identified_study.toml"), "--out", str(out), "--quiet"]
    assert main([*argv, "--scheduler", scheduler]) == 0
    return here, walk, json.loads((out / "report.json").read_text())


def test_the_study_over_the_identified_box_states_the_composed_claim(walked):
    here, walk, report = walked
    claim = report["composed_claim"]
    assert claim["stated"] and claim["alpha"] == pytest.approx(0.05) and claim["beta"] == 0.05
    assert claim["together"] == pytest.approx(0.9) and claim["epsilon"] == 0.1
    box = walk / "identified" / "box.toml"
    assert claim["box"] == str(box) and report["identified_box"]["sha256"] == claim["box_sha256"]
    for c, entry in report["cases"]["identified"]["controllers"].items():
        whole = [x for x in entry["certificates"] if x["property"].startswith("all of")][0]
        assert claim["cases"]["identified"][c] == {k: whole[k] for k in ("holds", "p_upper", "N")}
    page = (walk / "study" / "report.html").read_text()
    assert "Composed with the identified box." in page and "1 - alpha - beta" in page
    # the study's rows are computed from the box, its region and the identified model: its inputs
    inputs = report["inputs"]
    for name in ("box.toml", "region.json", "nominal.json"):
        assert any(k.endswith(f"identified/{name}") for k in inputs), (name, list(inputs))
    # every certification draw is a point of the box, and the controller's model is the identified one
    region = read_region(walk / "identified" / "region.json")
    certify = load_sweep(walk / "study" / "cases" / "identified" / "certify.toml")
    assert certify.set["plant.region"] == str(walk / "identified" / "region.json")
    sample = draw(certify, 0)
    z = [sample.values[f"plant.region_coordinates[{i}]"] for i in range(region.dimension)]
    assert np.max(np.abs(z)) <= region.half_width
    config = base_config(certify)
    assert config.nominal.kind == "identified" and config.nominal.file == str(
        walk / "identified" / "nominal.json"
    )
    # this log's robot (truth.json) is in its box (a 95 % event at this seed; the coverage is
    # benchmarks/identify_calibration.py's and tests/studies/identify/test_confidence.py's)
    truth = json.loads((walk / "truth.json").read_text())
    phi = np.concatenate([truth["inertial"], truth["viscous"], truth["coulomb"]])
    assert np.max(np.abs(region.coordinates(region.projection @ phi))) <= region.half_width


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_the_certified_law_exports_and_replays_its_certification_draw(walked, tmp_path):
    from nnrobust.outputs.export import absurd_bounds, recorded_steps
    from nnrobust.run.experiment import build
    from tests.outputs.test_export import _compile_replay, _replay

    here, walk, report = walked
    law = tmp_path / "law"
    tuned = f"{walk / 'study' / 'report.json'}#identified"
    experiment_file = str(here / "examples" / "identified.toml")
    argv = ["export", experiment_file, "--controller", "nn", "--tuned", tuned, "--out", str(law), "--quiet"]
    assert main([*argv, "--set", "simulation.duration=6.0"]) == 0
    kept = report["cases"]["identified"]["controllers"]["nn"]["tuned"]["settings"]
    exported = load_config(law / "config.toml")
    assert exported.nominal.kind == "identified"
    for key, value in kept.items():
        section, name = key.split(".", 1)
        got = np.atleast_1d(getattr(getattr(exported, section), name))  # a gain given once: m entries
        np.testing.assert_allclose(got, np.broadcast_to(value, got.shape), rtol=1e-12, err_msg=key)
    certify = load_sweep(walk / "study" / "cases" / "identified" / "certify.toml")
    run = experiment(certify, base_config(certify), draw(certify, 0), "nn-tuned")
    inputs, torques = recorded_steps(run, 0.3)
    # bit for bit up to a command the export refuses as absurd (|tau| over 10 x the effort limit:
    # status 2, its state not advanced; docs/export.md), which a law tuned on the suite's cut
    # budget can reach on a draw, where the loop's law goes on
    bound = absurd_bounds(build(run))["command_bound"]
    over = np.flatnonzero(np.any(np.abs(torques) > bound, axis=1))
    last = over[0] + 1 if len(over) else len(torques)
    replayed = _replay(_compile_replay(law), inputs)
    np.testing.assert_array_equal(replayed[:last], torques[:last])
    assert last >= 100  # a tenth of a second at least


def test_a_box_in_a_sweep_file_is_merged_and_its_keys_are_the_boxs_alone(walked, tmp_path):
    here, walk, _ = walked
    box = walk / "identified" / "box.toml"
    text = f'name = "b"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\nsamples = 3\nbox = "{box}"\n'
    (tmp_path / "s.toml").write_text(text)
    spec = load_sweep(tmp_path / "s.toml")
    assert spec.box["file"] == str(box) and len(spec.vary) == 13 and spec.set["plant.friction"] == "urdf"
    assert "# box: " in spec.to_toml()
    for extra, key in (
        ('[set]\n"plant.region" = "x.json"\n', "set.plant.region"),
        ('[vary]\n"plant.region_coordinates[0]" = {uniform = [0, 1]}\n', "vary.plant.region_coordinates[0]"),
    ):
        (tmp_path / "s.toml").write_text(text + extra)
        with pytest.raises(ConfigError) as err:
            load_sweep(tmp_path / "s.toml")
        assert err.value.key.endswith(key) and "is also given by the box" in str(err.value)
    (tmp_path / "s.toml").write_text(text.replace("paper-ellipse", "panda-ellipse"))  # another robot's box
    with pytest.raises(ConfigError) as err:
        from nnrobust.studies.base.plan import base_values, check_controllers

        spec = load_sweep(tmp_path / "s.toml")
        check_controllers(spec, base_values(spec))
    assert err.value.key == "set: plant.region" and "are not the robot's" in str(err.value), str(err.value)
    (tmp_path / "s.toml").write_text(text.replace(str(box), "nothing/box.toml"))
    with pytest.raises(ConfigError, match="is not a file"):
        load_sweep(tmp_path / "s.toml")
    study = (here / "examples" / "identified_study.toml").read_text()
    case = '{name = "x", base = "identified.toml", set = {"plant.friction_scale" = 2.0}}'
    study = study.replace('cases = ["identified.toml"]', f"cases = [{case}]")
    (here / "examples" / "bad_study.toml").write_text(study)
    with pytest.raises(ConfigError, match="a case may not change the box"):
        load_study(here / "examples" / "bad_study.toml")
