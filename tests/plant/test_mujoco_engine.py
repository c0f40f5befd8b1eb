"""MuJoCo as the true plant (plant.engine = "mujoco"): the load-time audit against Pinocchio, the
engine's dynamics against this package's plant, and closed-loop runs on both loops."""

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError, ModelMismatch
from nnrobust.model.loading import load_robot
from nnrobust.outputs.run_folder import load_run, write_run
from nnrobust.plant import Friction, Plant, SinusoidalDisturbance
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.simulation import _rk4_step

mujoco = pytest.importorskip("mujoco")

from nnrobust.plant.mujoco_engine import (  # noqa: E402 (after the skip)
    AUDIT_TOLERANCE,
    audit,
    build_mujoco_plant,
)

DATA = Path(__file__).parents[1] / "data"
ROTATED = DATA / "engines" / "rotated_inertia.urdf"


def bare_plant(robot, coulomb=0.0, disturbance=None):
    n = robot.nq
    return Plant(
        robot, Friction(np.zeros(n), np.full(n, coulomb)), disturbance or SinusoidalDisturbance.none(n)
    )


def engine_of(source, integrator="rk4", period=1e-3, **plant):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_robot(source, task="position")
    return robot, build_mujoco_plant(robot, bare_plant(robot, **plant), period, 1, integrator)


@pytest.mark.parametrize(
    "source",
    ["three_link_planar", "panda", "ur5", str(ROTATED), str(DATA / "pybullet" / "kuka_iiwa" / "model.urdf")],
)
def test_audit_passes_where_the_importer_reads_the_urdf_as_pinocchio_does(source):
    """M, bias and gravity of MuJoCo's compiled model agree with Pinocchio's to 1e-8 (measured:
    about 1e-14) at 16 random states; the rotated-inertia URDF has rotated <inertial> frames
    with full tensors and massive bodies behind fixed joints (which MuJoCo fuses)."""
    _, engine = engine_of(source)
    assert set(engine.audit) == {"mass_matrix", "bias", "gravity"}
    assert max(engine.audit.values()) <= AUDIT_TOLERANCE


def test_the_rotated_inertia_urdf_has_what_it_claims():
    """Fixed joints between massive bodies are fused by MuJoCo (fewer bodies than links), and
    the inertial frames are rotated: the case of mujoco #3559."""
    robot, engine = engine_of(str(ROTATED))
    text = ROTATED.read_text()
    assert text.count('type="fixed"') == 3 and text.count("rpy=") >= 6
    assert engine.model.nbody < 1 + text.count("<link ")  # static bodies fused into their parents
    assert robot.nq == 3


@pytest.mark.parametrize(
    ("field", "body_of_joint", "term"),
    [
        ("body_inertia", "wrist", "mass matrix"),
        ("body_mass", "elbow", "mass matrix"),
        ("body_ipos", "shoulder", "mass matrix"),
    ],
)
def test_a_corrupted_compiled_model_is_refused_with_the_joint_named(field, body_of_joint, term):
    robot, engine = engine_of(str(ROTATED))
    body = engine.model.jnt_bodyid[engine.model.joint(body_of_joint).id]
    values = getattr(engine.model, field)
    values[body] = values[body] * (1 + 1e-6) + (1e-6 if field == "body_ipos" else 0.0)
    with pytest.raises(ModelMismatch, match=rf"{term} by .*at joint '{body_of_joint}'"):
        audit(engine, robot)


def test_gravity_of_the_wrong_sign_is_refused_in_the_gravity_term():
    robot, engine = engine_of(str(ROTATED))
    engine.model.opt.gravity[:] = -engine.model.opt.gravity
    with pytest.raises(ModelMismatch, match="differs from Pinocchio's in the bias"):
        audit(engine, robot)


def test_an_importer_that_drops_the_inertial_rotation_is_refused():
    """The bug of mujoco #3559 reproduced by hand: MuJoCo given the URDF without the <inertial>
    rotations, Pinocchio the URDF with them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_robot(str(ROTATED), task="position")
    text = robot.urdf_text
    robot.urdf_text = text.replace('rpy="0.6 -1.0 0.3"', 'rpy="0 0 0"')  # the hand's inertial frame
    with pytest.raises(ModelMismatch, match="at joint 'wrist' \\(link 'hand'\\)"):
        build_mujoco_plant(robot, bare_plant(robot), 1e-3, 1)


@pytest.mark.parametrize("disturbance", [False, True])
def test_mujoco_rk4_reproduces_the_pinocchio_plant_open_loop(disturbance):
    """Frictionless spatial arm under a constant torque for 1 s, both by RK4 at 1 ms: without a
    disturbance MuJoCo's dynamics are Pinocchio's to 1e-11 rad; with one, MuJoCo holds tau_d at
    the middle of the step (measured 8e-6 rad after 1 s)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_robot(str(ROTATED), task="position")
    n = robot.nq
    dist = (
        SinusoidalDisturbance(np.array([[1.0], [0.5], [0.2]]), np.array([3.0]), np.zeros((3, 1)))
        if disturbance
        else SinusoidalDisturbance.none(n)
    )
    plant = bare_plant(robot, disturbance=dist)
    engine = build_mujoco_plant(robot, plant, 1e-3, 1, "rk4")
    q0, v0, tau = np.array([0.3, -0.4, 0.5]), np.array([0.5, -0.2, 1.0]), np.array([2.0, -1.0, 0.3])
    engine.reset(q0, v0)
    X = np.concatenate([q0, v0])

    def f(t, X):
        return np.concatenate([X[n:], plant.acceleration(t, X[:n], X[n:], tau)])

    for k in range(1000):
        X = _rk4_step(f, k * 1e-3, X, 1e-3)
        q, _ = engine.advance(k * 1e-3, tau, 1e-3)
    assert np.abs(q - X[:n]).max() < (1e-4 if disturbance else 1e-10)


def test_frictionloss_holds_below_the_coulomb_level_only_softly():
    """MuJoCo's dry friction is a soft constraint: the paper's wrist pushed at half its Coulomb
    level creeps (0.026 rad/s at the 2-step time constant; MuJoCo's default creeps 10x faster),
    and above the level it slides as the Coulomb law says."""
    robot = load_robot("three_link_planar")
    n, h = robot.nq, 1e-3
    plant = bare_plant(robot, coulomb=1.0)
    engine = build_mujoco_plant(robot, plant, h, 1, "implicitfast")
    speeds = {}
    for push in (0.5, 1.5):
        engine.reset(np.zeros(n), np.zeros(n))
        for k in range(1000):
            _, v = engine.advance(k * h, np.array([0.0, 0.0, push]), h)
        speeds[push] = v[2]
    assert 0.005 < speeds[0.5] < 0.05  # held softly: a creep, not rest, not sliding
    assert speeds[1.5] > 10.0  # slides: 0.5 N m net on the wrist for 1 s


def test_paper_ellipse_on_mujoco_same_on_both_loops_and_within_3x_of_pinocchio(tmp_path):
    """Acceptance: audit <= 1e-8, RMS error within 3x of the Pinocchio plant's (measured 6.66 mm
    against 6.64 mm), metrics.json names the engine; the compiled loop (which calls MuJoCo's
    mj_step itself) and the Python loop give the same run."""
    runs = {}
    for engine, backend in (("pinocchio", "compiled"), ("mujoco", "compiled"), ("mujoco", "python")):
        config = load_preset("paper-ellipse")
        config.simulation.duration = 4.0
        config.plant.engine, config.simulation.backend = engine, backend
        runs[engine, backend] = run_experiment(config)
    mj = runs["mujoco", "compiled"]
    assert mj.backend == "compiled" and mj.plant_engine == "mujoco"
    np.testing.assert_allclose(mj.q, runs["mujoco", "python"].q, rtol=0, atol=1e-9)
    reference = runs["pinocchio", "compiled"].metrics()["rms_error_after_2s"]
    metrics = mj.metrics()
    assert reference / 3 < metrics["rms_error_after_2s"] < 3 * reference
    assert metrics["plant_engine"] == "mujoco" and metrics["engine_audit"]["version"] == mujoco.__version__
    assert max(metrics["engine_audit"][t] for t in ("mass_matrix", "bias", "gravity")) <= AUDIT_TOLERANCE
    write_run(tmp_path / "run", mj, plots=False)
    loaded = load_run(tmp_path / "run")
    assert loaded.plant_engine == "mujoco" and loaded.engine_audit == metrics["engine_audit"]
    assert runs["pinocchio", "compiled"].metrics()["engine_audit"] is None


@pytest.mark.parametrize("backend", ["compiled", "python"])
@pytest.mark.parametrize(
    "case, rows, words",
    [
        (
            {"plant": {"loads": [{"kind": "impulse", "time": 0.5, "impulse": [1e9, 0.0, 0.0]}]}},
            501,
            "MuJoCo's bad acceleration (mjWARN_BADQACC: non-finite or above 1e10 at joint 'joint1') at "
            "t = 0.5000 s; MuJoCo resets the state to q = 0, so the run ends here",
        ),
        (
            {
                "controller": {"kind": "no-u0", "Kp": [1e12, 1e12], "Kv": [1.1e6, 1.1e6]},
                "plant": {"torque_limits": "none"},
            },
            76,
            "MuJoCo's bad control (mjWARN_BADCTRL: non-finite or above 1e10 at joint 'joint1') at "
            "t = 0.0750 s; MuJoCo applies zero torque instead, so the run ends here",
        ),
    ],
    ids=["impulse-1e9", "Kp-1e12-unlimited"],
)
def test_a_state_or_torque_mujoco_discards_ends_the_run_as_diverged(
    backend, case, rows, words, tmp_path, monkeypatch
):
    """MuJoCo answers a huge acceleration by resetting q to 0, and a huge torque by applying none,
    each with a warning only; both loops read the warning after every step and end the run there
    as diverged, naming it (these runs were reported completed, 390 mm RMS)."""
    monkeypatch.chdir(tmp_path)  # MuJoCo appends its warnings to MUJOCO_LOG.TXT in the working folder
    sections = {key: dict(value) for key, value in case.items()}
    sections["plant"]["engine"] = "mujoco"
    config = load_preset("paper-ellipse").replace(
        **sections, simulation={"duration": 1.0, "backend": backend}
    )
    result = run_experiment(config)
    assert (result.status, result.backend, result.t.size) == ("diverged", backend, rows)
    assert words in result.message, result.message
    assert np.all(np.isfinite(result.q))  # the state MuJoCo reset to never reaches the record


def test_panda_on_mujoco_tracks_as_on_pinocchio():
    config = load_preset("panda-ellipse")
    config.simulation.duration = 3.0
    results = {}
    for engine in ("pinocchio", "mujoco"):
        config.plant.engine = engine
        results[engine] = run_experiment(config).metrics()
    ratio = results["mujoco"]["rms_error_after_2s"] / results["pinocchio"]["rms_error_after_2s"]
    assert results["mujoco"]["status"] == "completed" and 1 / 3 < ratio < 3


def test_armature_enters_both_engines_alike():
    """plant.armature adds to the diagonal of the true M on both engines: the audit still passes,
    and M grows by exactly the armature."""
    config = load_preset("paper-ellipse")
    config.plant.engine, config.plant.armature = "mujoco", [0.01, 0.02, 0.03]
    setup = build(config)
    q = setup.q0
    plain = setup.robot.mass(q)
    np.testing.assert_allclose(setup.plant.model.mass(q) - plain, np.diag([0.01, 0.02, 0.03]), atol=1e-14)
    assert max(setup.plant.engine.audit.values()) <= AUDIT_TOLERANCE
    assert np.all(setup.nominal.mass(q) != setup.plant.model.mass(q))  # the controller does not know it


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
def test_a_payload_enters_both_engines_alike(preset):
    """plant.payload: MuJoCo's model carries the same sphere (the audit of M, the bias and gravity
    against Pinocchio's loaded true model still passes, and its total mass grows by the payload);
    a run with it is the same on both loops."""
    from nnrobust.run import compiled

    config = load_preset(preset).replace(
        plant={"engine": "mujoco", "payload": 2.5}, simulation={"duration": 0.5}
    )
    setup = build(config)
    assert max(setup.plant.engine.audit.values()) <= AUDIT_TOLERANCE
    plain = build(config.replace(plant={"payload": 0.0})).plant.engine
    assert setup.plant.engine.model.body_mass.sum() == pytest.approx(plain.model.body_mass.sum() + 2.5)
    if compiled.available():
        runs = [run_experiment(config.replace(simulation={"backend": b})) for b in ("compiled", "python")]
        np.testing.assert_allclose(runs[0].q, runs[1].q, atol=1e-8)


def test_options_mujoco_cannot_honour_are_refused():
    config = load_preset("paper-ellipse")
    config.plant.engine, config.plant.stiction = "mujoco", 1.5
    with pytest.raises(ConfigError, match="plant.stiction: MuJoCo's frictionloss has one level"):
        build(config)
    config = load_preset("paper-ellipse")
    config.plant.engine, config.simulation.integrator = "mujoco", "solve_ivp"
    with pytest.raises(ConfigError, match="simulation.integrator"):
        build(config)
    config = load_preset("paper-ellipse")
    config.plant.mujoco_integrator = "verlet"
    with pytest.raises(ConfigError, match="plant.mujoco_integrator: 'verlet' is not one of"):
        build(config)


def test_without_mujoco_one_line_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    config = load_preset("paper-ellipse")
    config.plant.engine = "mujoco"
    with pytest.raises(ConfigError) as err:
        build(config)
    assert "pip install 'nnrobust[mujoco]'" in str(err.value) and "\n" not in str(err.value)


def test_compare_shows_the_sim_to_sim_gap_and_the_verdicts_that_flip(tmp_path, capsys):
    """nnrobust compare of one experiment on both engines: the engine column, every metric's
    change from the first run, and a --require property that holds on one engine only."""
    from nnrobust.cli import main

    folders = []
    for engine in ("pinocchio", "mujoco"):
        config = load_preset("paper-ellipse")
        config.simulation.duration, config.plant.engine = 4.0, engine
        write_run(tmp_path / engine, run_experiment(config), plots=False)
        folders.append(str(tmp_path / engine))
    metrics = [load_run(f).metrics() for f in folders]
    low, high = sorted(m["rms_error_after_2s"] for m in metrics)
    bound = (low + high) / 2  # between the two: holds on one engine, fails on the other
    assert main(["compare", *folders, "--require", f"rms_error_after_2s<={bound!r}"]) == 0
    out = capsys.readouterr().out
    assert "engine" in out.splitlines()[0] and "mujoco" in out
    gap = metrics[1]["rms_error_after_2s"] - metrics[0]["rms_error_after_2s"]
    line = next(line for line in out.splitlines() if line.startswith("RMS error t>=2s"))
    assert f"{1e3 * gap:+.3g}" in line
    holds = {
        e: "holds" if m["rms_error_after_2s"] <= bound else "fails"
        for e, m in zip(("pinocchio", "mujoco"), metrics)
    }
    assert f"rms_error_after_2s<={bound:g}: pinocchio: {holds['pinocchio']}; mujoco: {holds['mujoco']}" in out
    assert holds["pinocchio"] != holds["mujoco"]


def test_a_custom_controller_on_mujoco_same_on_the_hybrid_and_python_loops():
    """The hybrid loop (compiled plant stepping, Python law) steps MuJoCo too: the same run."""
    custom = Path(__file__).resolve().parents[2] / "examples" / "custom_controller.py"
    runs = {}
    for backend in ("hybrid", "python"):
        config = load_preset("paper-ellipse").replace(
            controller={"kind": "custom", "class": f"{custom}:TaskPD"},
            plant={"engine": "mujoco"},
            simulation={"duration": 1.0, "backend": backend},
        )
        runs[backend] = run_experiment(config)
    assert runs["hybrid"].backend == "hybrid" and runs["hybrid"].plant_engine == "mujoco"
    np.testing.assert_allclose(runs["hybrid"].q, runs["python"].q, rtol=0, atol=1e-9)


def test_a_sweep_varies_the_engine(scheduler, tmp_path):
    """plant.engine in [vary]: each sample runs on its engine (the same draw: different, close)."""
    pytest.importorskip("distributed")
    from nnrobust.studies.sweep import load_sweep, read_results, run_sweep

    path = tmp_path / "gap.toml"
    path.write_text(
        'name = "gap"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\nsamples = 1\nseed = 3\n'
        '[set]\n"simulation.duration" = 2.5\n"nominal.seed" = 5\n"sensing.seed" = 5\n'
        '[vary]\n"plant.engine" = ["pinocchio", "mujoco"]\n'
    )
    run_sweep(load_sweep(path), tmp_path / "out", scheduler=scheduler)
    frame = read_results(tmp_path / "out").set_index("plant.engine")
    assert set(frame.index) == {"pinocchio", "mujoco"} and set(frame["status"]) == {"completed"}
    errors = frame["rms_error_after_2s"]
    assert errors["mujoco"] != errors["pinocchio"] and 1 / 3 < errors["mujoco"] / errors["pinocchio"] < 3
