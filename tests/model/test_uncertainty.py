"""Model uncertainty for any URDF: perturbed nominal models stay physical; friction and
disturbance scale with the robot."""

import re

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.config import ExperimentConfig
from nnrobust.core.exceptions import ConfigError
from nnrobust.model import PinocchioModel
from nnrobust.model.perturbation import is_physical, perturb_inertias
from nnrobust.plant import scaled_disturbance, scaled_friction, torque_scale
from nnrobust.run.experiment import build_nominal, build_plant
from tests.arms import arm, random_configurations


def _perturbed(robot, **kwargs):
    return PinocchioModel(perturb_inertias(robot.model, **kwargs), robot.task_frame, robot.task)


@pytest.mark.parametrize("name", ["panda", "ur5", "planar7"])
def test_random_perturbation_is_physical_bounded_and_seeded(name):
    robot = arm(name, "position" if name != "planar7" else "planar")
    nominal = _perturbed(robot, relative_error=0.3, com_error=0.02, seed=3)
    again = _perturbed(robot, relative_error=0.3, com_error=0.02, seed=3)
    other = _perturbed(robot, relative_error=0.3, com_error=0.02, seed=4)
    changed = 0
    for j in range(1, robot.model.njoints):
        true, wrong = robot.model.inertias[j], nominal.model.inertias[j]
        assert is_physical(wrong)
        assert 0.7 * true.mass - 1e-12 <= wrong.mass <= 1.3 * true.mass + 1e-12
        assert np.linalg.norm(np.asarray(wrong.lever) - true.lever) <= 0.02 + 1e-12
        assert wrong == again.model.inertias[j]
        changed += wrong.mass != true.mass
    assert changed == robot.model.njoints - 1
    assert any(nominal.model.inertias[j] != other.model.inertias[j] for j in range(1, robot.model.njoints))
    for q in random_configurations(robot, 10, seed=5):
        M = nominal.mass(q)
        assert np.all(np.linalg.eigvalsh(M) > 0)
        assert not np.allclose(M, robot.mass(q))
        np.testing.assert_allclose(nominal.task_position(q), robot.task_position(q), atol=1e-14)


def test_uniform_scale_scales_the_dynamics_exactly():
    """Mass and inertia about the centre of mass both x1.2: every spatial inertia, so M and G, x1.2."""
    robot = arm("panda", "position")
    heavier = _perturbed(robot, mass_scale=1.2, inertia_scale=1.2)
    for q in random_configurations(robot, 5, seed=6):
        np.testing.assert_allclose(heavier.mass(q), 1.2 * robot.mass(q), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(heavier.gravity(q), 1.2 * robot.gravity(q), rtol=1e-12, atol=1e-12)


def test_invalid_perturbations_are_refused():
    model = arm("planar7", "planar").model
    with pytest.raises(ValueError, match="relative_error"):
        perturb_inertias(model, relative_error=1.0)
    with pytest.raises(ValueError, match="must be positive"):
        perturb_inertias(model, mass_scale=0.0)
    assert not is_physical(pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 1.0, 3.0])))  # 1 + 1 < 3
    assert is_physical(pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 2.0, 3.0])))


def test_torque_scale_uses_effort_limits_or_the_arm_inertia():
    robot = arm("panda", "position")
    np.testing.assert_allclose(torque_scale(robot), [87, 87, 87, 87, 12, 12, 12])
    model = pin.Model(robot.model)
    model.effortLimit = np.zeros(robot.nq)
    bare = PinocchioModel(model, robot.task_frame, robot.task)
    mid = 0.5 * (np.maximum(robot.lower_limits, -np.pi) + np.minimum(robot.upper_limits, np.pi))
    expected = 10.0 * np.diag(robot.mass(mid)) + np.abs(robot.gravity(mid))
    np.testing.assert_allclose(torque_scale(bare), expected)


def test_scaled_friction_and_disturbance_levels():
    robot = arm("panda", "position")
    tau = torque_scale(robot)
    friction = scaled_friction(robot, viscous_level=0.02, coulomb_level=0.01)
    np.testing.assert_allclose(friction.coulomb, 0.01 * tau)
    np.testing.assert_allclose(friction.viscous * robot.velocity_limits, 0.02 * tau)
    disturbance = scaled_disturbance(robot, level=0.05)
    samples = np.array([disturbance(t) for t in np.linspace(0, 2 * np.pi, 2001)])
    peak = np.abs(samples).max(axis=0)
    assert np.all(peak <= 0.05 * tau + 1e-12) and np.all(peak > 0.6 * 0.05 * tau)
    assert np.linalg.matrix_rank(samples[:, :4]) == 4  # joints are not in phase


def test_configuration_builds_the_perturbed_nominal_and_scaled_plant():
    robot = arm("panda", "position")
    config = ExperimentConfig().replace(
        robot={"source": "panda", "task": "position"},
        nominal={"kind": "urdf", "relative_error": 0.2, "seed": 7},
        plant={"friction": "scaled", "disturbance": "scaled", "coulomb_level": 0.02},
        trajectory={"center": [0.4, 0.0, 0.5], "axis_a": [0.1, 0, 0], "axis_b": [0, 0.1, 0]},
        controller={"Kp": [10.0] * 3, "Kv": [4.0] * 3, "pd_Kp": [1.0] * 3, "pd_Kd": [1.0] * 3},
        subtasks={"criteria": ["joint_centering"]},
    )
    nominal = build_nominal(config, robot)
    expected = perturb_inertias(robot.model, relative_error=0.2, seed=7)
    assert all(nominal.model.inertias[j] == expected.inertias[j] for j in range(1, robot.model.njoints))
    plant = build_plant(
        config.plant, config.sensing, robot, disturbance_kind="scaled", period=1e-3, duration=1.0
    )
    np.testing.assert_allclose(plant.friction.coulomb, 0.02 * torque_scale(robot))


def test_stiff_viscous_friction_sets_the_substeps_or_is_refused_before_the_run():
    """On a 15-link chain 3 % viscous friction is a ~4e3 1/s mode: RK4 at 1 ms would diverge. With
    simulation.substeps unset, 2 are chosen and said; set to 1, the run is refused."""
    from nnrobust.config.presets import load_preset
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.run.experiment import build

    config = load_preset("planar7-ellipse").replace(
        robot={"source": "planar15"}, simulation={"q_seed": [0.9] + [-0.1] * 14}
    )
    with pytest.warns(UserWarning, match=r"substeps = 2 chosen \(plant step 0.0005 s\): .*viscous friction"):
        assert build(config).substeps == 2
    with pytest.raises(ConfigError, match=r"simulation.substeps: .* set substeps >= 2"):
        build(config.replace(simulation={"substeps": 1}))
    assert build(config.replace(simulation={"substeps": 3})).substeps == 3


def test_friction_scale_scales_the_plant_friction_only():
    """plant.friction_scale multiplies the true plant's viscous and Coulomb friction; the
    controller's nominal friction stays as configured."""
    from nnrobust.config import apply_overrides
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build as build_experiment

    base = load_preset("paper-ellipse")
    one = build_experiment(base)
    scaled = build_experiment(apply_overrides(base, {"plant.friction_scale": 2.5}))
    np.testing.assert_allclose(scaled.plant.friction.viscous, 2.5 * one.plant.friction.viscous, rtol=1e-15)
    np.testing.assert_allclose(scaled.plant.friction.coulomb, 2.5 * one.plant.friction.coulomb, rtol=1e-15)
    assert one.plant.friction.viscous.any()
    np.testing.assert_array_equal(
        scaled.controller.nominal_friction.viscous, one.controller.nominal_friction.viscous
    )


def test_relative_error_of_the_closed_form_model():
    """nominal.relative_error on the closed form: each of beta-hat, p-hat is off by its own seeded
    factor within [1 - r, 1 + r]; the same seed gives the same model, another seed another one."""
    from nnrobust.config import apply_overrides
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build as build_experiment

    base = load_preset("paper-ellipse")
    exact = build_experiment(base).nominal.params

    def params(seed, r=0.3):
        setup = build_experiment(apply_overrides(base, {"nominal.relative_error": r, "nominal.seed": seed}))
        return np.r_[setup.nominal.params.beta, setup.nominal.params.p]

    reference = np.r_[exact.beta, exact.p]
    ratio = params(4) / reference
    assert np.all(np.abs(ratio - 1) <= 0.3) and np.all(ratio != 1)
    np.testing.assert_array_equal(params(4), params(4))
    assert not np.allclose(params(4), params(5))
    with pytest.raises(ConfigError, match="nominal.kind.*mass_scale"):
        apply_overrides(base, {"nominal.mass_scale": 1.1})


def test_model_error_as_factors_a_search_can_move_along():
    """nominal.factors: one factor per inertial parameter, set entry by entry (the others 1):
    closed form on (beta, p), URDF on each body's mass then its rotational inertia."""
    from nnrobust.config import apply_overrides
    from nnrobust.config.presets import load_preset
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.run.experiment import build

    paper = load_preset("paper-ellipse")
    exact = build(paper).nominal.params
    scaled = build(apply_overrides(paper, {"nominal.factors[4]": 1.3, "nominal.factors[0]": 0.8}))
    scaled = scaled.nominal.params
    np.testing.assert_allclose(scaled.p, np.multiply(exact.p, [1.0, 1.3, 1.0]), rtol=1e-15)
    np.testing.assert_allclose(scaled.beta, np.multiply(exact.beta, [0.8, 1.0, 1.0]), rtol=1e-15)
    panda = load_preset("panda-ellipse")
    base = build(panda).nominal.model
    changed = build(apply_overrides(panda, {"nominal.factors[0]": 2.0, "nominal.factors[13]": 0.5}))
    changed = changed.nominal.model
    assert changed.inertias[1].mass == pytest.approx(2 * base.inertias[1].mass, rel=1e-15)
    np.testing.assert_allclose(changed.inertias[7].inertia, 0.5 * base.inertias[7].inertia, rtol=1e-15)
    assert changed.inertias[2].mass == base.inertias[2].mass
    for overrides, words in (
        ({"nominal.seed[0]": 1}, "not a list"),
        ({"controller.Kp[5]": 1.0}, "has 2 entries"),
        ({"nominal.factors[1]": -1.0}, "must be in (0, 100]"),
    ):
        with pytest.raises(ConfigError, match=re.escape(words)):
            apply_overrides(paper, overrides)
    with pytest.raises(ConfigError, match="the closed-form model has 6 parameters"):
        build(apply_overrides(paper, {"nominal.factors[6]": 1.1}))
