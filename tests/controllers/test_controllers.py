import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnrobust.config import ExperimentConfig
from nnrobust.controllers import (
    AdditiveRBFBasis,
    DampedPseudoInverse,
    NNCompensator,
    SlidingModeCompensator,
    error_dynamics,
    lyapunov_P,
    lyapunov_Q,
    project_null_space,
)
from nnrobust.run.experiment import build
from nnrobust.run.simulation import simulate
from tests.problems import paper_robot, random_states

KP, KV = np.diag([10.0, 10.0]), np.diag([4.0, 4.0])


def test_lyapunov_solution_is_the_closed_form():
    """P solves A^T P + P A + Q = 0 and equals [[2 Kp Kv, Kp], [Kp, Kv]]."""
    P = lyapunov_P(KP, KV)
    A, _ = error_dynamics(KP, KV)
    np.testing.assert_allclose(A.T @ P + P @ A + lyapunov_Q(KP, KV), 0, atol=1e-10)
    np.testing.assert_allclose(P, np.block([[2 * KP @ KV, KP], [KP, KV]]), atol=1e-10)
    assert np.all(np.linalg.eigvalsh(P) > 0)


def test_kronecker_lyapunov_solver_matches_scipy():
    """The Kronecker-form solver against scipy's Bartels-Stewart, on random Hurwitz A (non-diagonal
    gains, pose-sized)."""
    from scipy.linalg import solve_continuous_lyapunov

    from nnrobust.controllers.nn_compensator import solve_lyapunov

    rng = np.random.default_rng(3)
    for n in (2, 6, 12):
        A = rng.normal(size=(n, n))
        A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)  # shift the spectrum left
        B = rng.normal(size=(n, n))
        Q = B @ B.T + np.eye(n)
        np.testing.assert_allclose(
            solve_lyapunov(A, Q), solve_continuous_lyapunov(A.T, -Q), rtol=1e-9, atol=1e-11
        )


def test_omega_is_kp_e_plus_kv_edot():
    """omega = B^T P y = Kp e + Kv e'."""
    basis = AdditiveRBFBasis(-np.ones(6), np.ones(6))
    comp = NNCompensator(KP, KV, basis)
    e, de = np.array([0.1, -0.2]), np.array([0.3, 0.05])
    np.testing.assert_allclose(comp.omega(np.concatenate([e, de])), KP @ e + KV @ de)


def _compensator(law, rho):
    basis = AdditiveRBFBasis(-np.ones(6), np.ones(6), centers=3)
    comp = NNCompensator(KP, KV, basis, law=law)
    z = np.zeros(comp.state_size)
    z[0] = rho  # the bias unit: rho-hat = rho exactly
    z[-1] = 1e-6  # eps
    return comp, z


def test_printed_u0_is_bounded_by_one_and_corrected_reaches_rho():
    """Printed eq. (15) has |u_0| < 1 for any rho-hat; the corrected form has |u_0| -> rho-hat."""
    y = np.array([0.1, 0.2, 0.3, -0.1])
    q = v = np.zeros(3)
    for rho in (0.5, 5.0, 50.0):
        comp, z = _compensator("printed", rho)
        u0, r = comp.u0(q, v, y, z)
        assert r == pytest.approx(rho) and np.linalg.norm(u0) < 1.0
        comp, z = _compensator("corrected", rho)
        u0, _ = comp.u0(q, v, y, z)
        assert np.linalg.norm(u0) == pytest.approx(rho, rel=1e-4)
        # u_0 opposes omega
        assert u0 @ comp.omega(y) < 0


def test_adaptive_law_and_boundary_layer():
    """Z' = F |w| phi(s) - F sigma Z and eps' = -gamma (eps - eps_min)."""
    basis = AdditiveRBFBasis(-np.ones(6), np.ones(6), centers=3)
    comp = NNCompensator(KP, KV, basis, F=2.0, gamma=3.0, eps_min=0.1, sigma=0.5)
    y, q, v = np.array([0.1, 0.2, 0.3, -0.1]), np.full(3, 0.2), np.full(3, -0.1)
    z = np.concatenate([np.full(comp.L, 0.7), [0.4]])
    dz = comp.state_derivative(q, v, y, z)
    phi = basis(np.concatenate([q, v]))
    np.testing.assert_allclose(dz[:-1], 2.0 * (np.linalg.norm(comp.omega(y)) * phi - 0.5 * 0.7))
    assert dz[-1] == pytest.approx(-3.0 * (0.4 - 0.1))


def test_pseudoinverse_penrose_conditions_and_null_space():
    """Eqs. (5)-(6) away from singularities; J (I - J+ J) z = 0 computed without n x n matrices."""
    robot = paper_robot()
    pinv = DampedPseudoInverse()
    rng = np.random.default_rng(0)
    for q, _, _ in random_states(3, 20, seed=8):
        J = robot.task_jacobian(q)
        if np.linalg.svd(J, compute_uv=False)[-1] < 0.05:
            continue
        Jp = pinv.matrix(J)
        np.testing.assert_allclose(J @ Jp @ J, J, atol=1e-12)
        np.testing.assert_allclose(Jp @ J @ Jp, Jp, atol=1e-12)
        np.testing.assert_allclose((Jp @ J).T, Jp @ J, atol=1e-12)
        z = rng.normal(size=3)
        np.testing.assert_allclose(J @ project_null_space(J, Jp, z), 0, atol=1e-12)


def test_pseudoinverse_stays_bounded_at_a_singularity():
    """At a stretched arm J+ is damped and finite."""
    robot = paper_robot()
    J = robot.task_jacobian(np.zeros(3))
    Jp = DampedPseudoInverse().matrix(J)
    assert np.all(np.isfinite(Jp)) and np.abs(Jp).max() < 1e3


def test_perfect_model_gives_the_linear_error_dynamics():
    """With M-hat = M, N-hat = N and no disturbance, e obeys e'' + Kv e' + Kp e = 0 (eq. 13, eta = 0)."""
    config = ExperimentConfig().replace(
        nominal={"kind": "urdf"},
        plant={"viscous_friction": [0.0] * 3, "coulomb_friction": [0.0] * 3, "disturbance": "none"},
        controller={"kind": "no-u0"},
        simulation={"q_seed": [0.2, 1.0, 1.0], "initial_task_offset": [0.02, -0.01], "duration": 3.0},
    )
    setup = build(config)
    trace = simulate(setup.plant, setup.controller, setup.q0, setup.v0, 3.0)
    e = np.array([setup.robot.task_position(q) for q in trace.q]) - setup.trajectory.position(trace.t)
    # analytic solution for each axis: critically... roots of s^2 + 4 s + 10 (complex: -2 +- i sqrt 6)
    wd = np.sqrt(6.0)
    e0 = np.array([0.02, -0.01])
    # e'(0) = J q'(0) - x_d'(0) = 0 since q'(0) = J+ x_d'(0)
    analytic = (
        np.exp(-2 * trace.t)[:, None]
        * (np.cos(wd * trace.t)[:, None] + (2 / wd) * np.sin(wd * trace.t)[:, None])
        * e0
    )
    assert np.abs(e - analytic).max() < 2e-4 * np.abs(e0).max() * 10


def _held_rk4(comp, q, v, y, z, period, steps=2000):
    """Fine RK4 of z' = state_derivative with (q, q', y) held: the oracle for advance()."""
    h = period / steps
    for _ in range(steps):
        k1 = comp.state_derivative(q, v, y, z)
        k2 = comp.state_derivative(q, v, y, z + 0.5 * h * k1)
        k3 = comp.state_derivative(q, v, y, z + 0.5 * h * k2)
        k4 = comp.state_derivative(q, v, y, z + h * k3)
        z = z + (h / 6) * (k1 + 2 * k2 + 2 * k3 + k4)
    return z


@pytest.mark.parametrize("sigma", [0.0, 0.5])
def test_sampled_adaptive_law_is_the_exact_solution_with_held_inputs(sigma):
    """advance() over one period equals a fine integration of the continuous law, inputs held."""
    basis = AdditiveRBFBasis(-np.ones(6), np.ones(6), centers=3)
    comp = NNCompensator(KP, KV, basis, F=4.0, gamma=2.0, eps_min=0.1, sigma=sigma)
    y, q, v = np.array([0.1, 0.2, 0.3, -0.1]), np.full(3, 0.2), np.full(3, -0.1)
    z = np.concatenate([np.linspace(0.1, 2.0, comp.L), [0.6]])
    for period in (1e-3, 0.25):
        np.testing.assert_allclose(
            comp.advance(q, v, y, z, period), _held_rk4(comp, q, v, y, z, period), rtol=1e-10, atol=1e-12
        )


def test_sigma_modification_forgets_at_rate_F_sigma_and_settles_at_the_drive_over_sigma():
    """Analytic solutions of Z' = F (|w| phi - sigma Z): with w = 0 the weights decay as
    e^(-F sigma t); with a held drive they settle at |w| phi / sigma (not the law's own
    derivative: these fail if the leakage is dropped from advance())."""
    basis = AdditiveRBFBasis(-np.ones(6), np.ones(6), centers=3)
    comp = NNCompensator(KP, KV, basis, F=4.0, gamma=2.0, eps_min=0.1, sigma=0.5)
    q, v = np.full(3, 0.2), np.full(3, -0.1)
    z = np.concatenate([np.linspace(0.1, 2.0, comp.L), [0.6]])
    rest = comp.advance(q, v, np.zeros(4), z, 0.3)
    np.testing.assert_allclose(rest[: comp.L], z[: comp.L] * np.exp(-4.0 * 0.5 * 0.3), rtol=1e-13)
    y = np.array([0.1, 0.2, 0.3, -0.1])
    drive = np.linalg.norm(comp.omega(y)) * comp.basis(comp.network_input(q, v, y))
    settled = comp.advance(q, v, y, z, 50.0)
    np.testing.assert_allclose(settled[: comp.L], drive / 0.5, rtol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-10, 10), min_size=2, max_size=2),
    st.lists(st.floats(-10, 10), min_size=2, max_size=2),
    st.floats(0.0, 50.0),
    st.floats(1e-6, 5.0),
    st.floats(0.0, 1.0),
)
def test_lyapunov_inequality_of_the_corrected_law(w, eta_dir, rho, eps, shrink):
    """omega^T (u_0 + eta) <= eps whenever rho-hat >= |eta| (the step of the paper's Lyapunov
    argument that makes V' <= -y^T Q y / 2 + eps); the printed law has no such bound."""
    w = np.asarray(w)
    comp, z = _compensator("corrected", rho)
    z[-1] = eps
    eta = np.asarray(eta_dir)
    norm = np.linalg.norm(eta)
    eta = eta / norm * rho * shrink if norm > 0 else eta  # |eta| <= rho
    # choose y with omega(y) = w: e = 0, e' = Kv^-1 w
    y = np.concatenate([np.zeros(2), np.linalg.solve(KV, w)])
    np.testing.assert_allclose(comp.omega(y), w, atol=1e-12)
    u0, _ = comp.u0(np.zeros(3), np.zeros(3), y, z)
    assert w @ (u0 + eta) <= eps * (1 + 1e-9) + 1e-12


def test_sliding_mode_term_is_a_saturated_unit_vector_law():
    """|u_0| = K outside the boundary layer, K |w| / Phi inside, continuous, opposing w."""
    comp = SlidingModeCompensator(KP, KV, gain=20.0, boundary=0.5)
    for scale in (0.01, 0.2, 0.5, 3.0, 100.0):
        w = scale * np.array([0.6, -0.8])
        y = np.concatenate([np.zeros(2), np.linalg.solve(KV, w)])
        u0, z, _ = comp.output(None, None, y, np.zeros(0), 1e-3)
        assert np.linalg.norm(u0) == pytest.approx(20.0 * min(scale, 0.5) / 0.5)
        np.testing.assert_allclose(u0 / np.linalg.norm(u0), -w / np.linalg.norm(w))
        assert z.size == 0


def test_one_set_of_nn_defaults_for_the_class_and_the_configuration():
    """NNCompensator's constructor defaults are the [nn] defaults of an experiment file."""
    import dataclasses

    from nnrobust.config import NNConfig

    config = NNConfig()
    fields = {f.name: f.default for f in dataclasses.fields(NNCompensator)}
    for name in ("F", "gamma", "eps0", "eps_min", "sigma", "law", "basis_input"):
        assert fields[name] == getattr(config, name), name


def test_the_pd_null_damping_is_sized_from_the_arm():
    """D = r m_s on the paper's arm, computed by hand from its closed-form model: the self-motion
    n = J_1 x J_2 (the kernel of the 2 x 3 J) has inertia m_s = n^T M n / |n|^2, and the task
    damping's rate r is the geometric mean of eig(J M^-1 J^T K_d), sqrt(det) for two rows; at a
    long period, D stops at m_s / (2 T). The PD built at the defaults uses it; a value set is kept."""
    from nnrobust.config import apply_overrides
    from nnrobust.config.presets import load_preset
    from nnrobust.controllers.task_space import sized_null_damping
    from tests.problems import closed_form_of

    model = closed_form_of(paper_robot())
    q0, Kd = np.array([0.3, 1.1, -0.7]), np.diag([40.0, 25.0])
    M, J = model.mass(q0), model.task_jacobian(q0)
    n = np.cross(J[0], J[1])
    m_s = n @ M @ n / (n @ n)
    r = np.sqrt(np.linalg.det(J @ np.linalg.inv(M) @ J.T @ Kd))
    assert sized_null_damping(model, q0, Kd, 1e-3) == pytest.approx(r * m_s, rel=1e-10)
    assert sized_null_damping(model, q0, Kd, 0.5) == pytest.approx(m_s / (2 * 0.5), rel=1e-10)
    config = apply_overrides(load_preset("paper-ellipse"), {"controller.kind": "pd"})
    setup = build(config)
    expected = sized_null_damping(setup.nominal, setup.q0, np.diag(config.controller.pd_Kd), 1e-3)
    assert setup.controller.null_damping == pytest.approx(expected)
    panda = build(apply_overrides(load_preset("panda-ellipse"), {"controller.kind": "pd"}))
    assert (round(expected, 1), round(panda.controller.null_damping, 1)) == (2.2, 1.3)  # docs/controller.md
    config = apply_overrides(config, {"controller.pd_null_damping": 0.25})
    assert build(config).controller.null_damping == 0.25


def test_one_of_the_papers_kinds_is_one_declaration(monkeypatch):
    """A kind declared beside its code (PaperKind) is a valid controller.kind, built by its own
    builder, reads its keys while the other kinds' stay inert, and brings its robust term's search
    coordinates to the tuner: nothing else names it."""
    from nnrobust.config import controller_kinds, inert_keys
    from nnrobust.config.presets import load_preset
    from nnrobust.controllers.registry import PAPER_KINDS, PaperKind
    from nnrobust.controllers.sliding_mode import SlidingModeCompensator
    from nnrobust.controllers.task_space import eq9_law
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.tuned import tunable
    from nnrobust.studies.tune.space import Param, arm_scales, search_space

    built = []

    def builder(parts):
        c = parts.controller
        built.append(parts.controller.kind)
        return eq9_law(parts, SlidingModeCompensator(np.diag(c.Kp), np.diag(c.Kv), 2.0 * c.sliding_gain, 0.1))

    kind = PaperKind(
        "double-sliding",
        "the sliding-mode term at twice its gain",
        "the experiment's",
        builder,
        keys=("controller.sliding_gain",),
        search=lambda scales: [Param("controller.sliding_gain", 1.0, 10.0, "m/s^2", weak="low")],
    )
    monkeypatch.setitem(PAPER_KINDS, kind.name, kind)
    assert kind.name in controller_kinds() and kind.name in tunable()
    config = load_preset("paper-ellipse").replace(
        controller={"kind": "double-sliding"}, simulation={"duration": 0.05}
    )
    inert = inert_keys(config)
    assert "controller.sliding_gain" not in inert and "controller.sliding_boundary" in inert
    assert "nn." in inert and "controller.Kp" not in inert
    setup = build(config)
    assert built == ["double-sliding"]
    assert setup.controller.compensator.gain == 2.0 * config.controller.sliding_gain
    space = search_space("double-sliding", arm_scales(setup))
    assert [p.name for p in space.params] == [
        "bandwidth",
        "damping_ratio",
        "controller.k",
        "controller.sliding_gain",
    ]
    values = {"bandwidth": 3.0, "damping_ratio": 1.0, "controller.k": 1.0, "controller.sliding_gain": 2.0}
    assert space.overrides(values)["controller.Kp"] == [9.0]
    pd_copy = PaperKind("pd-copy", "like pd", "Ĝ only", PAPER_KINDS["pd"].build, eq9=False)
    monkeypatch.setitem(PAPER_KINDS, pd_copy.name, pd_copy)  # not eq. (9): the PD's gains are searched
    pd_space = search_space("pd-copy", arm_scales(setup))
    pd_values = {"bandwidth": 3.0, "damping_ratio": 1.0, "controller.pd_null_damping": 1.0}
    assert {"controller.pd_Kp", "controller.pd_Kd"} <= set(pd_space.overrides(pd_values))
    result = run_experiment(config)
    assert result.status == "completed" and result.backend == "compiled"  # its twin is eq. (9)'s
    sliding = run_experiment(config.replace(controller={"kind": "sliding-mode"}))
    assert not np.array_equal(result.tau, sliding.tau)  # the doubled gain acts


def test_the_papers_kinds_keys_are_defaulted_and_checked_by_their_declarations(monkeypatch):
    """Every key a kind declares is a field of the configuration with the declared default; its
    range is the declaration's (narrowing a declared range in a test refuses a value the
    shipped one accepts, with the key and the range named)."""
    import dataclasses

    from nnrobust.config import from_dict
    from nnrobust.controllers.registry import PAPER_KINDS, declared_default, declared_params
    from nnrobust.core.exceptions import ConfigError

    config = ExperimentConfig()
    declared = declared_params()
    names = {
        f"{s}.{f.name}"
        for s in ("controller", "nn")
        for f in dataclasses.fields(getattr(config, s))
        if f.name != "extra"  # the values of keys a kind declares beyond the fields
    }
    assert names - {p.name for p in declared} == {"controller.kind", "controller.class_", "controller.params"}
    for p in declared:
        section, field = p.name.split(".")
        assert getattr(getattr(config, section), field) == declared_default(p.name), p.name
    assert from_dict({"controller": {"sliding_gain": 50.0}}).controller.sliding_gain == 50.0
    kind = PAPER_KINDS["sliding-mode"]
    narrowed = tuple(dataclasses.replace(p, high=40.0) if p.name.endswith("gain") else p for p in kind.params)
    monkeypatch.setitem(PAPER_KINDS, "sliding-mode", dataclasses.replace(kind, params=narrowed))
    with pytest.raises(ConfigError, match=r"controller.sliding_gain: 50 is outside \(0, 40\] m/s\^2"):
        from_dict({"controller": {"sliding_gain": 50.0}})
