"""Any example-robot-data robot: continuous joints as revolute joints, floating bases fixed, the
default chain rule, robot.chain, implausible effort limits, and the NN controller on robots the
paper never saw (docs/robots.md)."""

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from nnrobust import load_robot
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import NNRobustError, RobotLoadError
from nnrobust.model.continuous_joints import (
    angles_from_configuration,
    configuration_from_angles,
    continuous_joint_names,
    with_revolute_continuous_joints,
)
from nnrobust.model.example_robots import example_robot, robot_names
from nnrobust.plant.scaling import implausible_efforts, torque_scale
from nnrobust.run.experiment import run_experiment


def _quiet(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return call(*args, **kwargs)


@pytest.mark.parametrize("name", ["kinova", "tiago", "double_pendulum_continuous"])
def test_continuous_joints_keep_the_dynamics_of_the_unbounded_joints(name):
    """M, the bias forces and every frame's Jacobian and placement of the rebuilt model equal
    Pinocchio's own (cos, sin) model at the same angles, on random states."""
    original = example_robot(name).model
    assert continuous_joint_names(original)
    rebuilt = with_revolute_continuous_joints(original)
    assert rebuilt.nq == rebuilt.nv == original.nv and rebuilt.nframes == original.nframes
    d, e = original.createData(), rebuilt.createData()
    rng = np.random.default_rng(1)
    for _ in range(5):
        angles = rng.uniform(-4, 4, rebuilt.nv)
        v, a = rng.normal(size=rebuilt.nv), rng.normal(size=rebuilt.nv)
        q = configuration_from_angles(original, angles)
        np.testing.assert_allclose(
            np.triu(pin.crba(rebuilt, e, angles)), np.triu(pin.crba(original, d, q)), atol=1e-12
        )
        np.testing.assert_allclose(
            pin.rnea(rebuilt, e, angles, v, a), pin.rnea(original, d, q, v, a), atol=1e-10
        )
        pin.computeJointJacobians(original, d, q)
        pin.computeJointJacobians(rebuilt, e, angles)
        pin.updateFramePlacements(original, d)
        pin.updateFramePlacements(rebuilt, e)
        for fid in range(0, original.nframes, 7):
            np.testing.assert_allclose(e.oMf[fid].homogeneous, d.oMf[fid].homogeneous, atol=1e-12)
            lwa = pin.LOCAL_WORLD_ALIGNED
            np.testing.assert_allclose(
                pin.getFrameJacobian(rebuilt, e, fid, lwa),
                pin.getFrameJacobian(original, d, fid, lwa),
                atol=1e-12,
            )
        continuous = [original.joints[original.getJointId(j)].idx_v for j in continuous_joint_names(original)]
        expected = angles.copy()
        expected[continuous] = np.arctan2(np.sin(angles[continuous]), np.cos(angles[continuous]))
        np.testing.assert_allclose(angles_from_configuration(original, q), expected, atol=1e-12)
    for i in range(1, rebuilt.njoints):  # unlimited exactly where the joint is continuous
        j = rebuilt.joints[i]
        unbounded = rebuilt.names[i] in continuous_joint_names(original)
        assert (rebuilt.lowerPositionLimit[j.idx_q] == -np.inf) == unbounded


def test_a_continuous_joint_in_a_urdf_file_is_one_unlimited_angle():
    from tests.bad_inputs.common import arm

    robot = load_robot(arm().replace('name="j1" type="revolute"', 'name="j1" type="continuous"'))
    assert robot.nq == 2 and robot.lower_limits[0] == -np.inf and robot.upper_limits[0] == np.inf
    assert np.isfinite(robot.lower_limits[1])


def test_every_shipped_robot_loads_or_is_refused_with_its_reason():
    loaded, refused = [], {}
    for name in robot_names():
        try:
            robot = _quiet(load_robot, name, task="position")
        except NNRobustError as err:
            refused[name] = str(err)
            continue
        assert robot.nq == robot.model.nv >= 1
        loaded.append(name)
    assert len(robot_names()) == 72 and len(loaded) >= 69, refused
    # the three that cannot be arms here: two drones without a joint, and an SDF this Pinocchio cannot read
    assert set(refused) <= {"hector", "iris", "cassie"}, refused
    assert "no movable joint" in refused.get("hector", "no movable joint")
    assert "SDF" in refused.get("cassie", "SDF")


def test_a_floating_base_is_fixed_to_the_world_and_said_once():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        leg = load_robot("solo12", task="position")
    assert [str(w.message) for w in caught] == [
        "solo12: a floating-base robot, simulated with its base fixed to the world"
    ]
    assert leg.nq == 3 and leg.task_frame == "HR_FOOT"
    assert all(name.startswith("HR_") for name in leg.joint_names)


@pytest.mark.parametrize(
    "name, n, frame, first",
    [
        ("panda", 7, "panda_hand_tcp", "panda_joint1"),  # fingers locked
        ("talos_arm", 6, "wrist_left_ft_tool_link", "arm_left_2_joint"),  # gripper locked, not a finger link
        ("baxter", 7, "right_hand_range_link", "right_s0"),  # one arm, not the whole robot
        ("tiago", 8, "hand_tool_link", "torso_lift_joint"),  # wheels, head and hand locked
        ("finger_edu", 3, "finger_tip_link", "finger_base_to_upper_joint"),  # a robot that is a finger
    ],
)
def test_the_default_chain_rule(name, n, frame, first):
    robot = _quiet(load_robot, name, task="position")
    assert (robot.nq, robot.task_frame, robot.joint_names[0]) == (n, frame, first)
    if name != "finger_edu":
        assert not any(w in j for j in robot.joint_names for w in ("finger", "gripper", "hand"))


def test_robot_chain_picks_a_sub_chain():
    left = load_robot("baxter", task="position", chain=("torso", "left_gripper"))
    assert left.nq == 7 and left.task_frame == "left_gripper"
    assert all(j.startswith("left_") for j in left.joint_names)
    head = load_robot("baxter", task="planar", chain=("torso", "head"))
    assert head.joint_names == ["head_pan"]
    with pytest.raises(RobotLoadError, match="is not between the root and"):
        load_robot("baxter", chain=("left_gripper", "right_gripper"))
    with pytest.raises(RobotLoadError, match="tip frame 'nowhere' is not in the model"):
        load_robot("baxter", chain=("torso", "nowhere"))
    with pytest.raises(RobotLoadError, match=r"cannot lock unknown joints \['nope'\]"):
        load_robot("baxter", chain=("torso", "left_gripper"), locked_joints=["nope"])


def test_frames_that_share_a_joint_name_are_told_apart():
    robot = _quiet(load_robot, "anymal_c", task="position")  # link RF_KFE and joint RF_KFE
    assert robot.model.existFrame("RH_KFE_link") and robot.task_frame == "RH_FOOT"


def test_implausible_effort_limits_are_named_and_not_used():
    """Baxter's head claims 50,000 N m; the Panda's limits are real (none is flagged)."""
    head = load_robot("baxter", task="planar", chain=("torso", "head"))
    assert implausible_efforts(head).tolist() == [True]
    with pytest.warns(UserWarning, match=r"joints 'head_pan' \(50000\).*over 100x"):
        scale = torque_scale(head)
    assert scale[0] < 10.0
    panda = load_robot("panda", task="position")
    assert not implausible_efforts(panda).any()
    np.testing.assert_array_equal(torque_scale(panda), panda.effort_limits)


def _well_conditioned(robot, samples=64):
    """The most manipulable of seeded configurations inside the working range."""
    rng = np.random.default_rng(0)
    low, high = robot.working_range
    candidates = [low + (high - low) * rng.uniform(0.2, 0.8, robot.nq) for _ in range(samples)]
    return max(candidates, key=lambda q: np.linalg.det(robot.task_jacobian(q) @ robot.task_jacobian(q).T))


def _late_rms(name: str, kind: str) -> float:
    """RMS position error over 1 s <= t < 2 s of the Panda preset's controller ``kind`` (scaled
    friction and disturbance, 20 % model error) on a 3-5 cm ellipse around a well-conditioned
    configuration of ``name``'s default chain, position task."""
    robot = _quiet(load_robot, name, task="position")
    q = _well_conditioned(robot)
    x = robot.task_position(q)
    config = load_preset("panda-ellipse").replace(
        name=f"{name}-ellipse",
        robot={"source": name, "task": "position"},
        controller={"kind": kind},
        trajectory={"center": [float(v) for v in x], "axis_a": [0.0, 0.03, 0.0], "axis_b": [0.02, 0.0, 0.02]},
        simulation={"duration": 2.0, "q_seed": [float(v) for v in q], "substeps": 4},
    )
    result = _quiet(run_experiment, config)
    assert result.status == "completed" and np.all(np.isfinite(result.q)), result.message
    return float(np.sqrt(np.mean(result.position_error()[result.t >= 1.0] ** 2)))


@pytest.mark.parametrize("name", ["kinova", "so101", "tiago", "solo12"])
def test_nn_controller_tracks_on_robots_the_paper_never_saw(name):
    """2 s of the NN controller: bounded, at least 3x better than the same law without u_0, and the
    errors docs/robots.md prints (to their 3 digits)."""
    import re
    from pathlib import Path

    nn, baseline = _late_rms(name, "nn"), _late_rms(name, "no-u0")
    assert nn < 0.02 and 3 * nn < baseline, (nn, baseline)
    docs = (Path(__file__).resolve().parents[2] / "docs" / "robots.md").read_text()
    row = re.search(rf"\| {name}( leg)? \| \d+ \| ([\d.]+) mm \| ([\d.]+) mm \|", docs)
    assert row, f"docs/robots.md has no row for {name}: run python -m tests.test_any_robot"
    assert (row.group(2), row.group(3)) == (f"{nn * 1e3:.3g}", f"{baseline * 1e3:.3g}"), (
        "run python -m tests.test_any_robot and paste its table into docs/robots.md"
    )


def test_compiled_loop_equals_python_with_unlimited_joints_in_the_joint_criteria():
    """Kinova's continuous joints take no part in joint_limits and joint_centering, in both loops."""
    robot = load_robot("kinova", task="position")
    q = _well_conditioned(robot)
    x = robot.task_position(q)
    config = load_preset("panda-ellipse").replace(
        name="kinova-ellipse",
        robot={"source": "kinova", "task": "position"},
        trajectory={"center": [float(v) for v in x], "axis_a": [0.0, 0.03, 0.0], "axis_b": [0.02, 0.0, 0.02]},
        simulation={"duration": 0.5, "q_seed": [float(v) for v in q], "substeps": 4},
        subtasks={"criteria": ["joint_centering", "joint_limits"], "weights": [0.5, 0.5]},
    )
    from tests.run.test_compiled import needs_extension

    if needs_extension.args[0]:
        pytest.skip(needs_extension.kwargs["reason"])
    fast = _quiet(run_experiment, config.replace(simulation={"backend": "compiled"}))
    slow = _quiet(run_experiment, config.replace(simulation={"backend": "python"}))
    assert (fast.backend, slow.backend) == ("compiled", "python")
    np.testing.assert_allclose(fast.q, slow.q, atol=1e-8)
    np.testing.assert_allclose(fast.tau, slow.tau, atol=1e-8)
    np.testing.assert_allclose(fast.signals["h"], slow.signals["h"], atol=1e-8)
    assert np.all(np.isfinite(slow.signals["h"]))


def test_docs_list_every_robot_as_the_command_prints_it(capsys):
    """docs/robots.md holds the output of `nnrobust robots --all`."""
    import re
    from pathlib import Path

    from nnrobust.cli import main

    assert main(["robots", "--all"]) == 0
    printed = capsys.readouterr().out
    docs = (Path(__file__).resolve().parents[2] / "docs" / "robots.md").read_text()
    block = re.search(r"<!-- robots-all -->\n```text\n(.*?)```\n<!-- /robots-all -->", docs, re.S)
    assert block and block.group(1) == printed, "run: nnrobust robots --all, and paste it into docs/robots.md"


if __name__ == "__main__":  # the table of docs/robots.md: python -m tests.test_any_robot
    print("| robot | n | NN | no-u0 |\n|---|---:|---:|---:|")
    for robot_name in ("kinova", "so101", "tiago", "solo12"):
        n = _quiet(load_robot, robot_name, task="position").nq
        print(
            f"| {robot_name} | {n} | {_late_rms(robot_name, 'nn') * 1e3:.3g} mm | "
            f"{_late_rms(robot_name, 'no-u0') * 1e3:.3g} mm |"
        )


@pytest.mark.parametrize("controller", ["nn", "pd"])
def test_a_minimal_experiment_file_runs_on_any_arm(tmp_path, controller):
    """Robot, task and trajectory only: the defaults adapt (the paper's criterion and disturbance
    only on the paper's arm), and the run completes bounded."""
    from nnrobust.config import load_config
    from nnrobust.run.experiment import build, run_experiment

    path = tmp_path / "minimal.toml"
    path.write_text(
        '[robot]\nsource = "panda"\ntask = "position"\n[trajectory]\ncenter = [0.45, 0.0, 0.45]\n'
        "axis_a = [0.1, 0.0, 0.0]\naxis_b = [0.0, 0.1, 0.0]\n[simulation]\nduration = 2.5\n"
        f'[controller]\nkind = "{controller}"\n'
    )
    config = load_config(path)
    setup = build(config)
    assert [type(c).__name__ for c in setup.criterion.criteria] == ["Manipulability", "JointLimitAvoidance"]
    peak = setup.plant.disturbance.amplitude.sum(axis=1)
    assert peak.shape == (7,) and np.all(peak > 0)  # scaled to the arm, not the paper's 3 joints
    result = run_experiment(config, setup=setup)
    assert result.status == "completed" and result.metrics()["rms_error_after_2s"] < 0.05


def test_the_paper_arm_keeps_the_papers_defaults():
    from nnrobust.config import ExperimentConfig
    from nnrobust.plant import SinusoidalDisturbance
    from nnrobust.run.experiment import build

    setup = build(ExperimentConfig().replace(simulation={"duration": 1.0}))
    assert [type(c).__name__ for c in setup.criterion.criteria] == ["PaperCriterion"]
    np.testing.assert_array_equal(setup.plant.disturbance.amplitude, SinusoidalDisturbance.paper().amplitude)


def _mass_matrix(text: str, q) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_robot(text).mass(np.asarray(q, float))


def test_exports_conventions_are_read_as_such_and_the_dynamics_follow():
    """A massless frame link's inertia is dropped, and a file whose products of inertia are in the
    CAD sign convention is read with that sign: M(q) equals that of the URDF written so by hand
    (the independent reference), and the assumption is said in one warning."""
    from nnrobust.model.urdf_check import InertiaAssumptionWarning
    from tests.bad_inputs.common import CAD_PRODUCTS, FLANGE, _l2_inertia, arm

    q = [0.3, -0.7]
    with pytest.warns(InertiaAssumptionWarning, match="massless link flange read with no inertia") as said:
        robot = load_robot(arm(extra=FLANGE))
    assert len(said) == 1
    by_hand = arm(
        extra=FLANGE.replace(
            'ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"',
            'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"',
        )
    )
    np.testing.assert_allclose(robot.mass(np.array(q)), _mass_matrix(by_hand, q), rtol=0, atol=1e-15)
    as_written = _pinocchio_mass(arm(extra=FLANGE), q)  # Pinocchio alone adds the flange's 0.1 kg m^2
    assert as_written[1, 1] > robot.mass(np.array(q))[1, 1] + 0.09

    with pytest.warns(InertiaAssumptionWarning, match="opposite sign"):
        robot = load_robot(_l2_inertia(CAD_PRODUCTS))
    flipped = (
        CAD_PRODUCTS.replace('ixy="0.0014185"', 'ixy="-0.0014185"')
        .replace('ixz="-0.00092094"', 'ixz="0.00092094"')
        .replace('iyz="-0.00169178"', 'iyz="0.00169178"')
    )
    np.testing.assert_allclose(
        robot.mass(np.array(q)), _mass_matrix(_l2_inertia(flipped), q), rtol=0, atol=1e-15
    )


def _pinocchio_mass(text: str, q) -> np.ndarray:
    model = pin.buildModelFromXML(text)
    data = model.createData()
    M = pin.crba(model, data, np.asarray(q, float))
    return np.triu(M) + np.triu(M, 1).T


def test_the_pybullet_arms_load_unmodified(tmp_path):
    """The URDFs of pybullet_data 3.2.7 (kept in tests/data/pybullet without their meshes) load
    with one warning each where they follow an exporter's convention."""
    from nnrobust.model.urdf_check import InertiaAssumptionWarning

    data = Path(__file__).parents[1] / "data" / "pybullet"
    expected = {
        "kuka_iiwa/model.urdf": None,
        "franka_panda/panda.urdf": "massless links panda_link8, panda_grasptarget",
        "xarm/xarm6_robot.urdf": "opposite sign",
    }
    for name, said in expected.items():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            robot = load_robot(str(data / name), task="position")
        assumptions = [str(w.message) for w in caught if issubclass(w.category, InertiaAssumptionWarning)]
        assert (said in assumptions[0]) if said else not assumptions, (name, assumptions)
        assert robot.nq in (6, 7) and np.all(np.linalg.eigvalsh(robot.mass(robot.mid_configuration)) > 0)


@pytest.mark.parametrize("arm", ["kuka_iiwa/model.urdf", "franka_panda/panda.urdf", "xarm/xarm6_robot.urdf"])
@pytest.mark.parametrize("controller", ["nn", "pd"])
def test_the_pybullet_arms_track_a_circle_with_the_defaults(arm, controller, tmp_path):
    """Issue 22's acceptance: each arm, unmodified, runs a position-task circle with nn and pd at
    the default settings, bounded (the substeps, where its light wrist needs them, chosen and said)."""
    from nnrobust.config import load_config
    from nnrobust.run.experiment import run_experiment

    path = tmp_path / "circle.toml"
    source = Path(__file__).parents[1] / "data" / "pybullet" / arm
    path.write_text(
        f'[robot]\nsource = "{source}"\ntask = "position"\n[trajectory]\n'
        "center = [0.45, 0.0, 0.5]\naxis_a = [0.1, 0.0, 0.0]\naxis_b = [0.0, 0.1, 0.0]\n"
        "[simulation]\nduration = 3.0\n"
        f'[controller]\nkind = "{controller}"\n'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = run_experiment(load_config(path))
    metrics = result.metrics()
    assert metrics["status"] == "completed" and not metrics["runaway"], metrics["warnings"]
    assert metrics["max_error"] < 0.1 and np.all(np.isfinite(result.q))
