"""Dynamic output feedback without mode observation: Alg. 3.2, Alg. 3.3 and the baseline [38]."""

import warnings

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are

from asoc import config
from asoc.linalg import pack, unpack
from asoc.mjls import MJLS, optimality, second_moments, simulate
from asoc.mjls.closed_loops import augmented_closed_loop, noise_covariances
from asoc.mjls.dynamic import dynamic_output_feedback, steady_state_cost
from asoc.mjls.finite_horizon import (
    finite_horizon_cost,
    finite_horizon_dynamic_output_feedback,
    initial_bounds,
)
from asoc.mjls.observed_mode_lqg import mode_observed_lqg
from asoc.mjls.optimality import gains_from_bounds
from asoc.mjls.system import successor_average


def random_system(seed, M=3, nx=3, nu=2, ny=2, radius=0.95, iid=False):
    """A random MJLS with mode matrices of spectral radius ``radius`` and noisy outputs."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((M, nx, nx))
    A *= radius / np.abs(np.linalg.eigvals(A)).max(axis=1)[:, None, None]
    B = rng.standard_normal((M, nx, nu))
    C = rng.standard_normal((M, ny, nx))
    H = 0.3 * rng.standard_normal((M, nx, nx))
    J = 0.2 * np.broadcast_to(np.eye(ny), (M, ny, ny))
    T = rng.random((M, M)) + 0.2
    if iid:
        T[:] = T[0]
    T /= T.sum(axis=1, keepdims=True)
    return MJLS(
        A,
        B,
        C,
        H,
        np.broadcast_to(np.eye(nx), (M, nx, nx)),
        np.broadcast_to(np.eye(nu), (M, nu, nu)),
        T,
        J=J,
    )


def initial_state(sys, seed=0):
    rng = np.random.default_rng(seed)
    mean0 = rng.standard_normal((sys.M, sys.nx))
    G = rng.standard_normal((sys.M, sys.nx, sys.nx))
    cov0 = 0.1 * G @ np.swapaxes(G, 1, 2)
    mu0 = np.full(sys.M, 1.0 / sys.M)
    return mean0, cov0, mu0


@pytest.fixture(scope="module")
def sys3():
    return random_system(11)


@pytest.fixture(scope="module")
def alg32(sys3):
    return dynamic_output_feedback(sys3)


def test_alg32_converges_and_stabilises_random_system(alg32):
    r = alg32
    assert r.converged and r.stabilizing and r.rho < 1
    assert r.F.shape == (3, 3) and r.K.shape == (3, 2) and r.L.shape == (2, 3)
    assert np.isfinite(r.cost) and np.isfinite(r.bound)
    assert r.history["trace_Xbar"].shape == (r.iterations + 1, 3)


def test_gains_satisfy_the_optimality_conditions(sys3, alg32):
    """At the fixed point, (F, K, L) solve (3.49) for the final bounds (Thm. 3.27)."""
    r = alg32
    _, JJt = noise_covariances(sys3)
    F, K, L = gains_from_bounds(
        sys3,
        r.Xbar,
        r.Xunder,
        successor_average(sys3.T, r.Pbar),
        successor_average(sys3.T, r.Punder),
        sys3.mu_inf,
        JJt,
    )
    for a, b in ((F, r.F), (K, r.K), (L, r.L)):
        np.testing.assert_allclose(a, b, atol=1e-7 * max(1, np.abs(b).max()))


def test_sdp_solve_agrees_with_least_squares(sys3, alg32):
    r = alg32
    _, JJt = noise_covariances(sys3)
    args = (
        sys3,
        r.Xbar,
        r.Xunder,
        successor_average(sys3.T, r.Pbar),
        successor_average(sys3.T, r.Punder),
        sys3.mu_inf,
        JJt,
    )
    for a, b in zip(gains_from_bounds(*args, method="sdp"), gains_from_bounds(*args)):
        np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-4)


def test_augmented_moments_agree_with_monte_carlo(sys3, alg32):
    """Exact cost of the augmented recursion (Prop. 3.23) vs Monte Carlo, within 4 std. errors."""
    r = alg32
    horizon = 15
    mean0, cov0, mu0 = initial_state(sys3)
    gains = [np.broadcast_to(g, (horizon,) + g.shape) for g in (r.F, r.K, r.L)]
    xhat0 = mu0 @ mean0
    exact = finite_horizon_cost(sys3, *gains, mean0, cov0, mu0)
    from asoc.mjls import DynamicOutputFeedback

    sim = simulate(
        sys3,
        DynamicOutputFeedback(r.F, r.K, r.L, xhat0=xhat0),
        mean0,
        horizon,
        40000,
        np.random.default_rng(5),
        mu0=mu0,
        x0_cov=cov0,
    )
    se = sim.cost.std() / np.sqrt(sim.cost.size)
    assert abs(sim.cost.mean() - exact) < 4 * se


def test_mode_observed_controller_cost_agrees_with_monte_carlo(sys3):
    horizon = 15
    mean0, cov0, mu0 = initial_state(sys3, 1)
    o = mode_observed_lqg(sys3, horizon, mean0, cov0, mu0)
    c = o.controller(sys3)
    assert c.observes_mode
    sim = simulate(sys3, c, mean0, horizon, 40000, np.random.default_rng(6), mu0=mu0, x0_cov=cov0)
    se = sim.cost.std() / np.sqrt(sim.cost.size)
    assert abs(sim.cost.mean() - o.cost) < 4 * se


def test_steady_state_cost_is_the_limit_of_the_moment_recursion(sys3, alg32):
    """Prop. 3.24: sum_i tr[Q~_i X~_k^i] of the recursion (Prop. 3.23) tends to the cost."""
    r = alg32
    At, HHt, Qt = augmented_closed_loop(sys3, r.F, r.K, r.L)
    horizon = int(np.ceil(np.log(1e-12) / np.log(r.rho)))
    X, _ = second_moments(At, HHt, sys3.T, np.zeros_like(At), sys3.mu_inf, horizon)
    stage_costs = np.einsum("kiab,iba->k", X, Qt)
    assert stage_costs[-1] == pytest.approx(r.cost, rel=1e-8)
    assert np.all(np.diff(stage_costs) >= -1e-9 * r.cost)  # from X~_0 = 0 the moments grow


def test_finite_horizon_bounds_decrease_monotonically(sys3):
    """Thm. 3.33: Jbar_0 is non-increasing over the iterations of Alg. 3.3."""
    mean0, cov0, mu0 = initial_state(sys3)
    f = finite_horizon_dynamic_output_feedback(sys3, horizon=30, mean0=mean0, cov0=cov0, mu0=mu0)
    assert f.converged
    assert f.F.shape == (30, 3, 3) and f.K.shape == (30, 3, 2) and f.L.shape == (30, 2, 3)
    b = f.cost_bounds
    assert b.ndim == 1 and b.size == f.iterations
    assert np.all(np.diff(b) <= 1e-8 * np.abs(b[1:]))


def test_finite_horizon_from_random_gains_also_decreases(sys3):
    mean0, cov0, mu0 = initial_state(sys3, 2)
    f = finite_horizon_dynamic_output_feedback(
        sys3,
        horizon=20,
        mean0=mean0,
        cov0=cov0,
        mu0=mu0,
        init=np.random.default_rng(0),
        max_iter=200,
    )
    b = f.cost_bounds
    assert np.all(np.diff(b) <= 1e-8 * np.abs(b[1:]))


def lqg(sys):
    """Classical LQG compensator x^+ = F x^ + K y, u = L x^ (one-step predictor) from scipy
    DAREs."""
    A, B, C, H, J, Q, R = (m[0] for m in (sys.A, sys.B, sys.C, sys.H, sys.J, sys.Q, sys.R))
    P = solve_discrete_are(A, B, Q, R)
    L = -np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    S = solve_discrete_are(A.T, C.T, H @ H.T, J @ J.T)
    K = A @ S @ C.T @ np.linalg.inv(C @ S @ C.T + J @ J.T)
    return A + B @ L - K @ C, K, L


@pytest.mark.parametrize("seed", [1, 2])
def test_one_mode_reduces_to_classical_lqg(seed):
    sys = random_system(seed, M=1, radius=1.1)
    r = dynamic_output_feedback(sys)
    F, K, L = lqg(sys)
    assert r.converged and r.stabilizing
    for a, b in ((r.F, F), (r.K, K), (r.L, L)):
        np.testing.assert_allclose(a, b, atol=1e-8 * max(1, np.abs(b).max()))
    # For M = 1 the bound of Prop. 3.26 is attained: true cost = bound (= LQG cost).
    assert r.cost == pytest.approx(r.bound, rel=1e-8)
    assert r.cost == pytest.approx(steady_state_cost(sys, F, K, L)[0], rel=1e-10)


def test_one_mode_finite_horizon_is_the_optimal_lqg():
    """M = 1: Alg. 3.3 attains the cost of the time-varying LQG (Kalman predictor + LQ gains)."""
    sys = random_system(3, M=1, radius=1.1)
    mean0, cov0, mu0 = initial_state(sys)
    horizon = 25
    with warnings.catch_warnings():
        # Jbar_0 (3.72) also weighs gain directions at k = 0 that do not affect the cost
        # (Xunder_0 has rank 1; (3.73) picks their minimum norm), so it may rise slightly.
        warnings.simplefilter("ignore", RuntimeWarning)
        f = finite_horizon_dynamic_output_feedback(
            sys, horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0
        )
    o = mode_observed_lqg(sys, horizon, mean0, cov0, mu0)
    assert f.cost == pytest.approx(o.cost, rel=1e-9)
    # Gains agree wherever they influence the cost (min-norm elsewhere, Alg. 3.3 (3.73)).
    np.testing.assert_allclose(f.L[1:], o.F[1:, 0], atol=1e-8)
    np.testing.assert_allclose(f.K[:-3], o.Mf[:-3, 0], atol=1e-8)
    np.testing.assert_allclose(f.L[0] @ f.xhat0, o.F[0, 0] @ o.xhat0, atol=1e-8)


def test_bound_is_attained_for_independent_modes():
    """With identical rows of T (white parameters) the infinite-horizon bound is exact at the
    fixed point of Alg. 3.2 (X12 = X2, the case named after Prop. 3.26)."""
    sys = random_system(6, iid=True)
    r = dynamic_output_feedback(sys)
    assert r.converged and r.stabilizing
    assert r.cost == pytest.approx(r.bound, rel=1e-7)


def test_optimal_observed_controller_beats_mode_independent_ones(sys3, alg32):
    mean0, cov0, mu0 = initial_state(sys3, 3)
    horizon = 30
    o = mode_observed_lqg(sys3, horizon, mean0, cov0, mu0)
    f = finite_horizon_dynamic_output_feedback(
        sys3, horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0
    )
    ti = finite_horizon_cost(
        sys3,
        *[np.broadcast_to(g, (horizon,) + g.shape) for g in (alg32.F, alg32.K, alg32.L)],
        mean0,
        cov0,
        mu0,
    )
    assert o.cost < f.cost and o.cost < ti


def test_time_variant_system_matrices(sys3, alg32):
    """(3.54): a sequence of MJLS per step; equal steps give the time-invariant result."""
    mean0, cov0, mu0 = initial_state(sys3)
    args = dict(horizon=8, mean0=mean0, cov0=cov0, mu0=mu0, init=alg32)
    a = finite_horizon_dynamic_output_feedback(sys3, **args)
    b = finite_horizon_dynamic_output_feedback([sys3] * 8, **args)
    np.testing.assert_allclose(a.cost_bounds, b.cost_bounds)
    other = sys3.replace(A=0.5 * sys3.A)
    c = finite_horizon_dynamic_output_feedback([sys3] * 4 + [other] * 4, **args)
    assert c.converged and c.cost < a.cost  # damped dynamics in the second half cost less
    assert np.all(np.diff(c.cost_bounds) <= 1e-8 * np.abs(c.cost_bounds[1:]))


def test_augmented_closed_loop_blocks(sys3, alg32):
    r = alg32
    At, HHt, Qt = augmented_closed_loop(sys3, r.F, r.K, r.L)
    np.testing.assert_allclose(At[1, :3, 3:], sys3.B[1] @ r.L)
    np.testing.assert_allclose(At[2, 3:, :3], r.K @ sys3.C[2])
    np.testing.assert_allclose(HHt[0, 3:, 3:], r.K @ sys3.J[0] @ sys3.J[0].T @ r.K.T)
    np.testing.assert_allclose(Qt[0, 3:, 3:], r.L.T @ sys3.R[0] @ r.L)


def test_initial_bounds_follow_theorem_331():
    mean0 = np.array([[5.0, 0.0], [0.0, 0.0]])
    cov0 = np.stack([0.01 * np.eye(2), np.zeros((2, 2))])
    xhat0, Xbar0, Xunder0 = initial_bounds(mean0, cov0, np.array([1.0, 0.0]))
    np.testing.assert_allclose(xhat0, [5, 0])
    np.testing.assert_allclose(Xbar0[0], 0.01 * np.eye(2))
    np.testing.assert_allclose(Xunder0[0], [[25, 0], [0, 0]])
    assert not Xbar0[1].any() and not Xunder0[1].any()


# --- bad input and failure -------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(horizon=0), "horizon"),
        (dict(horizon=2.5), "horizon"),
        (dict(mean0=np.zeros((2, 3))), "mean0"),
        (dict(cov0=np.zeros((3, 3))), "cov0"),
        (dict(cov0=-np.broadcast_to(np.eye(3), (3, 3, 3))), "cov0"),
        (dict(mu0=[0.5, 0.5, 0.5]), "mu0"),
        (dict(mu0=[0.5, 0.5]), "mu0"),
        (dict(method="newton"), "method"),
        (dict(tol=0), "tol"),
    ],
)
def test_finite_horizon_bad_input(sys3, kwargs, match):
    mean0, cov0, mu0 = initial_state(sys3)
    args = dict(horizon=5, mean0=mean0, cov0=cov0, mu0=mu0)
    args.update(kwargs)
    with pytest.raises((ValueError, TypeError), match=match):
        finite_horizon_dynamic_output_feedback(sys3, **args)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(tol=-1), "tol"),
        (dict(max_iter=0), "max_iter"),
        (dict(init=0), "init"),
        (dict(method="qp"), "method"),
        (dict(rng=1), "rng"),
    ],
)
def test_infinite_horizon_bad_input(sys3, kwargs, match):
    with pytest.raises((ValueError, TypeError), match=match):
        dynamic_output_feedback(sys3, **kwargs)


def test_bad_gain_shapes(sys3):
    with pytest.raises(ValueError, match="K"):
        steady_state_cost(sys3, np.eye(3), np.zeros((3, 3)), np.zeros((2, 3)))


def test_bad_initial_gains(sys3):
    mean0, cov0, mu0 = initial_state(sys3)
    with pytest.raises(ValueError, match="init"):
        finite_horizon_dynamic_output_feedback(
            sys3,
            horizon=5,
            mean0=mean0,
            cov0=cov0,
            mu0=mu0,
            init=(np.eye(2), np.zeros((3, 2)), np.zeros((2, 3))),
        )


def test_non_convergence_is_flagged(sys3):
    with pytest.warns(RuntimeWarning, match="did not converge"):
        r = dynamic_output_feedback(sys3, max_iter=3)
    assert not r.converged and r.iterations == 3
    mean0, cov0, mu0 = initial_state(sys3)
    with pytest.warns(RuntimeWarning, match="did not converge"):
        f = finite_horizon_dynamic_output_feedback(
            sys3, horizon=5, mean0=mean0, cov0=cov0, mu0=mu0, max_iter=1
        )
    assert not f.converged


def test_unstabilisable_system_is_flagged():
    """No input (B = 0) and an unstable mode: no controller stabilises; never silent."""
    sys = random_system(6, radius=1.3)
    sys = sys.replace(B=np.zeros_like(sys.B))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = dynamic_output_feedback(sys, max_iter=2000)
    assert not r.stabilizing and np.isinf(r.cost)
    assert any(issubclass(w.category, RuntimeWarning) for w in caught)


# --- (3.51) matrix-free: operator, conjugate gradients, switch ---------------------------------


def random_bounds(sys, seed, spread=1.0):
    """Symmetric positive definite Xbar, Xunder, E(Pbar), E(Punder) (G G^T / n + I, G scaled by
    spread)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(4):
        G = spread * rng.standard_normal((sys.M, sys.nx, sys.nx))
        out.append(G @ np.swapaxes(G, 1, 2) / sys.nx + np.eye(sys.nx))
    return out


def optimality_args(sys, seed, spread=1.0):
    return (sys, *random_bounds(sys, seed, spread), sys.mu_inf, noise_covariances(sys)[1])


@pytest.mark.parametrize("seed, M, nx, nu, ny", [(1, 3, 5, 3, 2), (2, 1, 4, 1, 1), (3, 4, 7, 2, 3)])
def test_matrix_free_operator_equals_dense_matrix(seed, M, nx, nu, ny):
    args = optimality_args(random_system(seed, M=M, nx=nx, nu=nu, ny=ny), seed, spread=3.0)
    H, rho = optimality.optimality_system(*args)
    op = optimality.OptimalityOperator(*args)
    assert op.size == len(rho) == nx * nx + nx * ny + nu * nx
    np.testing.assert_array_equal(optimality.optimality_vector(*args[:5]), rho)
    for z in np.random.default_rng(seed).standard_normal((3, op.size)):
        Hz = H @ z
        assert np.linalg.norm(op.matvec(z) - Hz) <= 1e-12 * np.linalg.norm(Hz)
    F, K, L = unpack(z, op.shapes)
    assert [g.shape for g in op.apply(F, K, L)] == [(nx, nx), (nx, ny), (nu, nx)]
    np.testing.assert_array_equal(pack(F, K, L), z)


@pytest.mark.parametrize("seed, nx", [(4, 6), (5, 8), (6, 10)])
def test_matrix_free_solve_agrees_with_lstsq(monkeypatch, seed, nx):
    args = optimality_args(random_system(seed, M=3, nx=nx, nu=2, ny=2), seed)
    dense = optimality.solve_gains(*args)
    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 0)
    *gains, info = optimality.solve_gains(*args)
    assert dense[3].method == "dense" and info.method == "cg" and 0 < info.iterations < 200
    assert info.residual < 1e-11 and info.shift > 0
    for a, b in zip(gains, dense[:3]):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-8 * np.abs(b).max())


def test_switch_point_selects_the_solver(monkeypatch):
    args = optimality_args(random_system(7, M=2, nx=4, nu=1, ny=1), 7)  # 24 unknowns
    assert optimality.solve_gains(*args)[3].method == "dense"
    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 24)
    assert optimality.solve_gains(*args)[3].method == "cg"
    # the SDP stays dense
    assert optimality.solve_gains(*args, method="sdp")[3].method == "sdp"


def test_conjugate_gradients_that_stop_short_raise_with_the_residual():
    args = optimality_args(random_system(8, M=3, nx=6, nu=2, ny=2), 8, spread=3.0)
    op, P = optimality.OptimalityOperator(*args), optimality.KroneckerPreconditioner(*args)
    with pytest.raises(
        np.linalg.LinAlgError, match=r"relative residual .* > 1e-15 in 2 iterations"
    ):
        optimality.solve_optimality_cg(
            op, optimality.optimality_vector(*args[:5]), P, tol=1e-15, max_iter=2
        )


def test_matrix_free_failure_stops_alg32_with_a_message(monkeypatch):
    from asoc.mjls.examples import sec373_system

    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 0)
    # one iteration for 8 unknowns
    monkeypatch.setitem(config.defaults, "mjls.cg_max_iter_factor", 1 / 8)
    with pytest.raises(FloatingPointError, match="first iteration: conjugate gradients"):
        dynamic_output_feedback(sec373_system(1))


def test_matrix_free_alg32_matches_dense_on_the_thesis_example(monkeypatch):
    """Sec. 3.7.3 with T[1]: the forced matrix-free path gives the dense gains, cost and bound."""
    from asoc.mjls.examples import sec373_system

    sys = sec373_system(1)
    dense = dynamic_output_feedback(sys)
    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 0)
    free = dynamic_output_feedback(sys)
    assert dense.solve.method == "dense" and free.solve.method == "cg"
    assert (free.status, free.iterations) == (dense.status, dense.iterations)
    for a, b in zip((free.F, free.K, free.L), (dense.F, dense.K, dense.L)):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
    assert free.cost == pytest.approx(dense.cost, rel=1e-10)
    assert free.bound == pytest.approx(dense.bound, rel=1e-10)
    assert free.worst_residual < 1e-9 and "conjugate gradients" in free.message
    again = dynamic_output_feedback(sys)  # deterministic
    for a, b in zip((free.F, free.K, free.L), (again.F, again.K, again.L)):
        np.testing.assert_array_equal(a, b)


def test_matrix_free_alg33_matches_dense(monkeypatch, sys3, alg32):
    mean0, cov0, mu0 = initial_state(sys3)
    args = dict(horizon=10, mean0=mean0, cov0=cov0, mu0=mu0, init=alg32)
    dense = finite_horizon_dynamic_output_feedback(sys3, **args)
    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 0)
    free = finite_horizon_dynamic_output_feedback(sys3, **args)
    assert free.converged and free.iterations == dense.iterations
    assert free.cost == pytest.approx(dense.cost, rel=1e-9)


@pytest.mark.parametrize(
    "kwargs, match", [(dict(method="cg"), "method"), (dict(tol=np.nan), "tol")]
)
def test_bad_input_is_named_on_the_matrix_free_path(monkeypatch, sys3, kwargs, match):
    monkeypatch.setitem(config.defaults, "mjls.matrix_free_min_unknowns", 0)
    with pytest.raises((ValueError, TypeError), match=match):
        dynamic_output_feedback(sys3, **kwargs)
    with pytest.raises(ValueError, match="method"):
        gains_from_bounds(*optimality_args(sys3, 0), method="cg")


def _verdicts(sequence, tol=1e-10, max_iter=10_000):
    """The verdicts of Alg. 3.2's stopping rule on a sequence of (scalar) bound iterates."""
    from asoc.mjls.stopping import StoppingRule

    rule = StoppingRule(tol, max_iter)
    for it, value in enumerate(sequence):
        verdict = rule.status(it, tuple(np.full((1, 1, 1), v) for v in value))
        if verdict is not None:
            return verdict, it, rule
    return None, len(sequence), rule


def test_stopping_rule_tells_a_cycle_from_an_oscillating_convergence():
    """A 2-cycle is a cycle; a sequence converging like (-0.99)^k (small lag-2 change) is not."""
    k = np.arange(5000)[:, None]
    cycle = 1.0 + 0.1 * (-1.0) ** k + 1e-3 * 0.5**k * np.ones(4)
    verdict, it, rule = _verdicts(cycle)
    assert (verdict, rule.period) == ("cycle", 2) and it < 60
    oscillating = 1.0 + 0.1 * (-0.99) ** k * np.ones(4)
    assert _verdicts(oscillating)[0] == "converged"


def test_stopping_rule_stops_wandering_and_diverging_sequences_within_a_few_windows():
    w = config.defaults["mjls.alg32_patience"]
    wandering = 1.0 + np.random.default_rng(0).random((5000, 4))
    verdict, it, _ = _verdicts(wandering)
    assert verdict == "no_progress" and it <= 2 * w + 5
    growing = 9.0 ** np.arange(200)[:, None] * np.ones(4)
    verdict, it, _ = _verdicts(growing)
    assert verdict == "diverged" and it <= 2 * w + 5
    # converges, slowly: not stopped early
    slow = 1.0 + 0.995 ** np.arange(8000)[:, None] * np.ones(4)
    assert _verdicts(slow)[0] == "converged"
    assert _verdicts(slow, max_iter=1000)[0] == "no_progress"  # ... unless tol is out of reach


def test_alg32_stops_on_the_cycle_of_the_networked_loop_and_names_the_exact_design():
    from asoc.mjls import exact_dynamic_output_feedback
    from asoc.mjls.examples import networked_loop

    sys = networked_loop()
    with pytest.warns(RuntimeWarning, match="cycle of period 2.*exact_dynamic_output_feedback"):
        r = dynamic_output_feedback(sys)
    assert (r.status, r.period, r.converged) == ("cycle", 2, False) and r.iterations < 200
    other = dynamic_output_feedback(sys, max_iter=r.iterations - 1, warn=False)  # the other member
    assert r.bound <= other.bound
    assert r.cost == pytest.approx(steady_state_cost(sys, r.F, r.K, r.L)[0], rel=1e-12)
    exact = exact_dynamic_output_feedback(sys)
    assert exact.converged and exact.cost < min(r.cost, other.cost)


def test_alg32_on_an_unstabilisable_plant_stops_as_diverged_within_a_few_windows():
    A = 3.0 * np.eye(2)
    sys = MJLS(
        [A, A],
        np.zeros((2, 1)),
        [[1.0, 0.0]],
        np.eye(2),
        np.eye(2),
        np.eye(1),
        [[0.5, 0.5], [0.5, 0.5]],
        J=0.1 * np.ones((1, 1)),
    )
    r = dynamic_output_feedback(sys, warn=False)
    assert r.status == "diverged" and r.iterations <= 2 * config.defaults["mjls.alg32_patience"] + 5
    assert "exact_dynamic_output_feedback" in r.message
