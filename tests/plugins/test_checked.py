"""A trajectory, disturbance and self-motion criterion of one's own (docs/extending.md): built from
the experiment file as ``Class(robot, **params)``, checked against the contract, recorded and re-run.

The references are the built-in parts: ``tests/parts/again.py`` writes each again from the public
contract alone, and the runs must agree with the built-in ones.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config import load_config
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError
from nnrobust.outputs.run_folder import load_run
from nnrobust.run import compiled
from nnrobust.run.experiment import build, run_experiment

PARTS = Path(__file__).parents[1] / "parts" / "again.py"

ELLIPSE = """
[trajectory]
kind = "custom"
class = "parts.py:Ellipse"
params = {center = [0.30, 0.40], a = [0.20, 0.0], b = [0.0, 0.10]}
"""


def _experiment(folder: Path, body: str, base: str = "paper-ellipse", duration: float = 0.5) -> Path:
    """An experiment file beside a copy of the parts file, starting from a preset."""
    shutil.copy(PARTS, folder / "parts.py")
    path = folder / "experiment.toml"
    path.write_text(f'base = "{base}"\nname = "mine"\n{body}\n[simulation]\nduration = {duration}\n')
    return path


def _builtin(preset="paper-ellipse", duration=0.5, backend="auto", **sections):
    config = load_preset(preset).replace(simulation={"duration": duration, "backend": backend}, **sections)
    return run_experiment(config)


def test_a_trajectory_written_again_runs_as_the_shipped_ellipse(tmp_path):
    """Eq. (18) through the Trajectory contract tracks as the built-in ellipse, on the hybrid loop
    (the plant compiled, the controller in Python) where the extension is built."""
    mine = run_experiment(load_config(_experiment(tmp_path, ELLIPSE)))
    builtin = _builtin()
    assert mine.backend == ("hybrid" if compiled.available() else "python")
    np.testing.assert_allclose(mine.q, builtin.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mine.x_d, builtin.x_d, rtol=0, atol=1e-12)


def test_a_disturbance_written_again_is_the_papers(tmp_path):
    """The paper's tau_d through the Disturbance contract gives the built-in run; its gain and
    plant.disturbance_scale scale it alike."""
    body = '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:PaperDisturbance"\n'
    mine = run_experiment(load_config(_experiment(tmp_path, body)))
    assert mine.backend == "python"  # the compiled plant has sinusoids only
    builtin = _builtin(backend="python")
    np.testing.assert_allclose(mine.q, builtin.q, rtol=0, atol=1e-12)
    doubled = run_experiment(load_config(_experiment(tmp_path, body + "disturbance_params = {gain = 2.0}\n")))
    scaled = run_experiment(load_config(_experiment(tmp_path, body + "disturbance_scale = 2.0\n")))
    np.testing.assert_allclose(doubled.q, scaled.q, rtol=0, atol=1e-12)
    assert np.abs(doubled.q - mine.q).max() > 1e-5


def test_a_criterion_written_again_is_joint_centering(tmp_path):
    """Joint centering through the Criterion contract steers the Panda's self-motion as the
    built-in one (and h is recorded alike)."""
    body = '[subtasks]\ncriteria = ["custom"]\nweights = [1.0]\ncriterion_class = "parts.py:Centering"\n'
    mine = run_experiment(load_config(_experiment(tmp_path, body, "panda-ellipse", 0.3)))
    builtin = _builtin(
        "panda-ellipse",
        0.3,
        "python",
        subtasks={"criteria": ["joint_centering"], "weights": [1.0]},
    )
    np.testing.assert_allclose(mine.q, builtin.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mine.signals["h"], builtin.signals["h"], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "body, base, message",
    [
        (
            ELLIPSE.replace("Ellipse", "LateNaNEllipse"),
            "paper-ellipse",
            "trajectory.class: LateNaNEllipse(0.05",
        ),
        (
            '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:LateNaNDisturbance"\n',
            "paper-ellipse",
            "plant.disturbance_class: LateNaNDisturbance(0.05",
        ),
        (
            '[subtasks]\ncriteria = ["custom"]\nweights = [1.0]\n'
            'criterion_class = "parts.py:LateNaNCentering"\n',
            "panda-ellipse",
            "subtasks.criterion_class: LateNaNCentering.gradient(model, q) returned a non-finite value",
        ),
    ],
    ids=["trajectory", "disturbance", "criterion"],
)
def test_a_part_that_breaks_its_contract_later_is_named_not_blamed_on_the_gains(
    tmp_path, body, base, message
):
    """A NaN from a user's part after its first call is a one-line error naming its key, its
    class and (for a function of time) when; the run is not reported diverged with the gains
    blamed."""
    with pytest.raises(ConfigError) as err:
        run_experiment(load_config(_experiment(tmp_path, body, base, 0.2)))
    assert message in str(err.value), str(err.value)


def test_user_parts_are_recorded_and_rerun_from_another_folder(tmp_path, monkeypatch):
    """config.toml records each part's file and SHA-256; run again from elsewhere, the same run."""
    body = ELLIPSE + '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:PaperDisturbance"\n'
    path = _experiment(tmp_path, body)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--no-plots"]) == 0
    text = (out / "config.toml").read_text()
    assert "# trajectory sha256: " in text and "# disturbance sha256: " in text
    assert f'class = "{(tmp_path / "parts.py").resolve()}:Ellipse"' in text
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["run", str(out / "config.toml"), "--out", "again", "--no-plots"]) == 0
    np.testing.assert_array_equal(load_run(elsewhere / "again").q, load_run(out).q)
    (tmp_path / "parts.py").write_text(PARTS.read_text() + "\n# edited\n")
    with pytest.warns(UserWarning) as caught:
        load_config(out / "config.toml")
    said = " ".join(str(w.message) for w in caught)
    assert "the trajectory file" in said and "the disturbance file" in said and "has changed since" in said


@pytest.mark.parametrize(
    ("body", "key", "message"),
    [
        (
            '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:WrongSize"\n',
            "plant.disturbance_class",
            "WrongSize(0.0) returned shape (2,); expected (3,)",
        ),
        (
            '[trajectory]\nkind = "custom"\nclass = "parts.py:NotATrajectory"\n',
            "trajectory.class",
            "is not a subclass of nnrobust.Trajectory",
        ),
        (
            ELLIPSE.replace("b = [0.0, 0.10]}", "b = [0.0, 0.10], speed = 2.0}"),
            "trajectory.params.speed",
            "Ellipse takes no such parameter",
        ),
        ('[trajectory]\nkind = "custom"\n', "trajectory.class", "kind = 'custom' needs the class"),
        (
            '[trajectory]\nclass = "parts.py:Ellipse"\n',
            "trajectory.class",
            "is read only with kind = 'custom'",
        ),
        (
            '[subtasks]\ncriteria = ["custom"]\ncriterion_class = "parts.py:Elipse"\n',
            "subtasks.criterion_class",
            "no 'Elipse'",
        ),
        (
            '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:PaperDisturbance"\n'
            "disturbance_omega_scale = 2.0\n",
            "plant.disturbance_omega_scale",
            "acts on sinusoids",
        ),
    ],
)
def test_bad_user_parts_are_refused_by_key(tmp_path, body, key, message):
    with pytest.raises(ConfigError) as err:
        build(load_config(_experiment(tmp_path, body)))
    assert err.value.key.endswith(key) and message in str(err.value), str(err.value)


def test_a_custom_trajectory_is_refused_on_a_pose_task(tmp_path):
    with pytest.raises(ConfigError, match="a custom trajectory is for planar and position tasks"):
        load_config(_experiment(tmp_path, ELLIPSE, "panda-pose"))
