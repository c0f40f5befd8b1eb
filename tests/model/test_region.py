"""An identified robot's box (nnrobust.model.region) against what is known: its half-width holds
independent standard normal coordinates at exactly its level (Monte Carlo), a point of it is a
plant whose torque is the base regressor times that point's parameters (Pinocchio's regressor,
an independent reference), and what is no plant, or a key that would change the box's plant, is
refused in one line naming the key."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.stats

pytest.importorskip("cvxpy")

from nnrobust.config import apply_overrides  # noqa: E402
from nnrobust.config.presets import load_preset  # noqa: E402
from nnrobust.core.exceptions import ConfigError  # noqa: E402
from nnrobust.model.loading import load_robot  # noqa: E402
from nnrobust.model.perturbation import perturb_inertias  # noqa: E402
from nnrobust.model.region import box_half_width, read_region  # noqa: E402
from nnrobust.model.regressor import base_parameters, torque_regressor  # noqa: E402
from nnrobust.plant.friction import Friction  # noqa: E402
from nnrobust.run.experiment import build  # noqa: E402
from nnrobust.studies.identify import identify  # noqa: E402
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log  # noqa: E402


@pytest.mark.parametrize("p", [1, 13, 57])
def test_the_box_holds_independent_standard_normal_coordinates_at_its_level(p):
    c = box_half_width(0.95, p)
    assert (2 * scipy.stats.norm.cdf(c) - 1) ** p == pytest.approx(0.95, abs=1e-12)
    z = np.random.default_rng(p).standard_normal((40_000, p))
    inside = np.mean(np.max(np.abs(z), axis=1) <= c)
    assert inside == pytest.approx(0.95, abs=0.005)  # 4.6 standard errors of a 40 000-draw share
    if p == 1:
        assert c == pytest.approx(1.959964, abs=1e-6)


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    """An identification of a paper arm 20 % off its URDF, with the URDF's friction."""
    folder = tmp_path_factory.mktemp("identified")
    arm = load_robot("three_link_planar")
    true = perturb_inertias(arm.model, relative_error=0.2, seed=5)
    friction = Friction(arm.viscous_friction, arm.coulomb_friction)
    faults = SensorFaults(torque_noise=0.05, torque_quantum=0.01, jitter=1e-4, stale=0.02)
    log = synthetic_log(
        true, FourierTrajectory.random(arm.model, seed=5, speed=1.5), 25.0, friction=friction, faults=faults
    )
    identify(log, "three_link_planar", folder / "id")
    return folder / "id"


def _plant(region_file, z=None, **more):
    config = load_preset("paper-ellipse")
    changes = {"plant.region": str(region_file), "simulation.duration": 0.1, **more}
    if z is not None:
        changes["plant.region_coordinates"] = [float(x) for x in z]
    return build(apply_overrides(config, changes)).plant


def test_a_point_of_the_box_is_a_plant_whose_torque_is_the_regressor_times_its_parameters(identified):
    region = read_region(identified / "region.json")
    assert region.dimension == 13 and region.half_width == pytest.approx(box_half_width(0.95, 13))
    model = load_robot("three_link_planar").model
    base = base_parameters(model, [f"p{i}" for i in range(30)])
    rng = np.random.default_rng(0)
    for z in (np.zeros(13), rng.uniform(-region.half_width, region.half_width, 13)):
        plant = _plant(identified / "region.json", z)
        beta = region.beta(z)
        q, v, a = rng.uniform(-1, 1, (3, 6, 3))
        Y = torque_regressor(model, q, v, a)  # the URDF's kinematics: N x 3 x 30
        expected = Y[:, :, base.base] @ beta[:7] + v * beta[7:10] + np.sign(v) * beta[10:13]
        data = plant.model.model.createData()
        import pinocchio as pin

        got = np.array([pin.rnea(plant.model.model, data, *s) for s in zip(q, v, a)])
        got += plant.friction.torque(v)
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    # the centre is the estimate: its plant's friction is the least-squares one
    summary = json.loads((identified / "identification.json").read_text())
    least = np.array([p["least_squares"] for p in summary["parameters"]])
    np.testing.assert_allclose(region.center, least)
    np.testing.assert_allclose(_plant(identified / "region.json").friction.viscous, least[7:10], rtol=1e-9)


def test_box_toml_is_a_sweep_table_over_every_coordinate(identified):
    from nnrobust.config import parse_toml

    box = parse_toml((identified / "box.toml").read_text(), "box.toml")
    region = read_region(identified / "region.json")
    assert box["claim"]["level"] == 0.95 and box["set"]["plant.region"] == str(identified / "region.json")
    assert box["vary"] == {
        f"plant.region_coordinates[{i}]": {"uniform": [-region.half_width, region.half_width]}
        for i in range(13)
    }


def test_what_is_no_plant_or_would_change_the_boxs_plant_is_refused(identified, tmp_path):
    region_file = identified / "region.json"
    region = read_region(region_file)
    negative = region.center.copy()
    negative[7] = -1.0  # viscous friction of joint 1 below zero
    cases = [
        ({"z": region.coordinates(negative)}, "plant.region_coordinates", "no plant: viscous friction"),
        ({"z": np.zeros(14)}, "plant.region_coordinates", "has 14 entries; the box has 13"),
        ({"plant.friction": "scaled"}, "plant.friction", "the identified box's"),
        ({"plant.viscous_friction": [1.0, 1.0, 1.0]}, "plant.viscous_friction", "would replace"),
        ({"plant.engine": "mujoco"}, "plant.engine", "runs on 'pinocchio' only"),
    ]
    for more, key, said in cases:
        z = more.pop("z", None)
        with pytest.raises(ConfigError) as err:
            _plant(region_file, z, **more)
        assert err.value.key == key and said in str(err.value), str(err.value)
    with pytest.raises(ConfigError, match="give plant.region too"):
        apply_overrides(load_preset("paper-ellipse"), {"plant.region_coordinates": [0.0]})
    data = json.loads(region_file.read_text())
    for change, said in (
        ({"format": "x"}, "is not an identified region"),
        ({"axes": [[1.0]]}, "axes has shape (1, 1); expected (13, 13)"),
        ({"joints": ["a", "b", "c"]}, "the box's joints ['a', 'b', 'c'] are not the robot's"),
    ):
        bad = tmp_path / f"bad{len(said)}.json"
        bad.write_text(json.dumps({**data, **change}))
        with pytest.raises(ConfigError) as err:
            _plant(bad)
        assert err.value.key.startswith("plant.region") and said in str(err.value), str(err.value)
