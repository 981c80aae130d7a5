"""Unit tests of asoc.belief (Sec. 2.5): Def. 2.2, Lemma 2.1, filters, Alg. 2.2 vs LQG, [159]."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asoc.belief import (
    UKF,
    AffinePolicy,
    DiracMixture,
    GaussianNoise,
    ParticleFilter,
    QuadraticCost,
    StageProblem,
    Value,
    affine_policy_value,
    backward_pass,
    belief_ilqg,
    draw_noise,
    ekf_step,
    improved_policy_value,
    landmark_example,
    linear_gaussian_model,
    next_estimate_covariance,
    optimize_belief_trajectory,
    reference_trajectory,
    sigma_points,
    statistical_taylor_expansion,
    statistical_taylor_linearization_error,
    terminal_value,
)

# a linear-Gaussian model (the LQG case of Sec. 2.3)
A = np.array([[1.0, 0.1], [0.0, 1.0]])
B = np.array([[0.0], [0.1]])
H = 0.3 * np.eye(2)
C = np.array([[1.0, 0.0]])
J = np.array([[0.5]])
LIN = linear_gaussian_model(A, B, H, C, J)


def lqg_gains(Q, R, QK, K):
    """Finite-horizon Riccati recursion: u_k = L_k x_k."""
    P, gains = QK, []
    for _ in range(K):
        L = -np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
        P = Q + A.T @ P @ (A + B @ L)
        gains.append(L)
    return gains[::-1]


def test_fig2_2_errors():
    ekf, stat = statistical_taylor_linearization_error()
    assert abs(ekf - 1.3173) < 6e-5
    assert abs(stat - 0.6289) < 6e-5


@settings(max_examples=20, deadline=None)
@given(
    st.lists(st.floats(-3, 3), min_size=3, max_size=3), st.integers(1, 6), st.integers(0, 10_000)
)
def test_definition_2_2_exact_for_quadratic(coef, m, seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(2, 2))
    Vq = M @ M.T + coef[0] * np.eye(2)
    vq = np.array(coef[1:])
    g = lambda x: 0.7 + vq @ x + 0.5 * x @ Vq @ x
    mix = DiracMixture(rng.normal(size=(m, 2)), rng.dirichlet(np.ones(m)))
    q = statistical_taylor_expansion(g, mix)
    x = rng.normal(size=(5, 2))
    assert np.allclose(q(x), [g(xi) for xi in x], atol=1e-6)


def test_definition_2_2_one_particle_is_taylor():
    g = lambda x: np.sin(x[0]) * np.exp(x[1])
    x0 = np.array([0.3, -0.2])
    q = statistical_taylor_expansion(g, DiracMixture(x0[None]))
    d = np.array([0.01, -0.02])
    grad = np.array([np.cos(x0[0]) * np.exp(x0[1]), np.sin(x0[0]) * np.exp(x0[1])])
    hess = np.array([[-np.sin(x0[0]), np.cos(x0[0])], [np.cos(x0[0]), np.sin(x0[0])]]) * np.exp(
        x0[1]
    )
    assert q(x0 + d) == pytest.approx(g(x0) + grad @ d + 0.5 * d @ hess @ d, abs=1e-8)


def test_lemma_2_1_matches_large_sample():
    ex = landmark_example()
    rng = np.random.default_rng(0)
    mean, cov = np.array([-2.0, 1.5]), np.diag([0.3, 0.2])
    u = np.array([0.4, -0.2])
    N = 400_000
    x = ex.model.a(GaussianNoise(mean, cov).sample(rng, N), u, ex.model.w.sample(rng, N))
    y = ex.model.h(x, ex.model.v.sample(rng, N))
    Z = np.concatenate([x, y], 1)
    Cz = np.cov(Z.T)
    big = Cz[:2, :2] - Cz[:2, 2:] @ np.linalg.solve(Cz[2:, 2:], Cz[2:, :2])
    vp, gamma = sigma_points(ex.model.v.mean, ex.model.v.cov)  # y is linear in v: exact moments
    parts = GaussianNoise(mean, cov).sample(rng, 1000)
    ours = next_estimate_covariance(
        DiracMixture(parts), u, ex.model, ex.model.w.sample(rng, 300), vp, gamma=gamma
    )
    assert np.allclose(ours, big, atol=0.03)


def test_ukf_matches_kalman_filter_on_linear_model():
    ukf = UKF(LIN)
    mean, cov = np.array([1.0, -0.5]), np.diag([0.2, 0.1])
    m_kf, P_kf = mean.copy(), cov.copy()
    est = (mean, cov)
    rng = np.random.default_rng(3)
    for k in range(10):
        u, y = rng.normal(size=1), rng.normal(size=1)
        est = ukf.step(est, u, y)
        m_kf, P_kf = A @ m_kf + B @ u, A @ P_kf @ A.T + H @ H.T
        S = C @ P_kf @ C.T + J @ J.T
        K = P_kf @ C.T @ np.linalg.inv(S)
        m_kf, P_kf = m_kf + K @ (y - C @ m_kf), P_kf - K @ S @ K.T
    assert np.allclose(est[0], m_kf, atol=1e-10) and np.allclose(est[1], P_kf, atol=1e-10)
    m_e, P_e = ekf_step(LIN, mean, cov, np.array([0.3]), np.array([0.2]))
    m_u, P_u = ukf.step((mean, cov), np.array([0.3]), np.array([0.2]))
    assert np.allclose(m_e, m_u) and np.allclose(P_e, P_u)


def test_particle_filter_tracks_kalman_filter():
    pf = ParticleFilter(LIN, 20_000, np.random.default_rng(5))
    mean, cov = np.array([1.0, -0.5]), np.diag([0.2, 0.1])
    est = pf.initial(mean, cov)
    kf = (mean, cov)
    for u, y in [(0.2, 0.9), (-0.1, 1.1), (0.0, 1.0)]:
        est = pf.step(est, np.array([u]), np.array([y]))
        kf = UKF(LIN).step(kf, np.array([u]), np.array([y]))
    assert np.allclose(est.mean, kf[0], atol=0.03) and np.allclose(est.cov, kf[1], atol=0.03)
    assert pf.next_covariance(est, np.array([0.0])).shape == (2, 2)


def test_algorithm_2_2_converges_to_lqg():
    Q, R, K = np.eye(2), np.array([[0.5]]), 8
    cost = QuadraticCost(Q, R, Q, np.zeros(2), K)
    res = optimize_belief_trajectory(
        LIN,
        cost,
        np.array([1.0, 0.5]),
        0.1 * np.eye(2),
        rng=np.random.default_rng(0),
        n_cost_runs=50,
        max_iterations=10,
    )
    assert res.converged
    for L_ours, L_lqg in zip(res.policy.L, lqg_gains(Q, R, Q, K)):
        assert np.allclose(L_ours, L_lqg, atol=1e-6)
    assert np.allclose(res.policy.d, 0.0, atol=1e-6)


def test_analytic_and_numdifftools_derivatives_agree():
    ex = landmark_example(K=3)
    filt = UKF(ex.model)
    policy = AffinePolicy(np.zeros((3, 2, 2)), np.tile([1.0, -0.3], (3, 1)))
    ref = reference_trajectory(ex.model, filt, policy, ex.mean0, ex.cov0)
    wp, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    value = terminal_value(ex.cost, filt.mixture(ref.estimates[3]))
    stage = StageProblem(ex.model, ex.cost, filt, ref.estimates[2], value, wp, beta)
    e1, e2 = (
        stage.expansion(ref.u_bar[2], "analytic"),
        stage.expansion(ref.u_bar[2], "numdifftools"),
    )
    for name in ("p", "r", "Q", "P", "R"):
        assert np.allclose(getattr(e1, name), getattr(e2, name), atol=1e-6), name


def _step1_setup():
    """Landmark example, K = 3: the reference under a fixed policy and the value at step 2."""
    ex = landmark_example(K=3)
    filt = UKF(ex.model)
    policy = AffinePolicy(np.zeros((3, 2, 2)), np.tile([1.0, -0.3], (3, 1)))
    ref = reference_trajectory(ex.model, filt, policy, ex.mean0, ex.cov0)
    wp, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    nxt = improved_policy_value(
        StageProblem(
            ex.model,
            ex.cost,
            filt,
            ref.estimates[2],
            terminal_value(ex.cost, filt.mixture(ref.estimates[3])),
            wp,
            beta,
        ).expansion(ref.u_bar[2]),
        1.0,
    )
    return ex, filt, policy, ref, wp, beta, nxt


def test_affine_policy_value_equals_theorem_2_5_for_its_policy():
    ex, filt, policy, ref, wp, beta, nxt = _step1_setup()
    exp = StageProblem(ex.model, ex.cost, filt, ref.estimates[1], nxt, wp, beta).expansion(
        ref.u_bar[1]
    )
    p_t, r_t, P_t, R_t = exp.tilde
    eps = 0.5
    L = -np.linalg.solve(R_t, P_t)
    d = np.linalg.solve(R_t, p_t - eps * r_t) + ref.u_bar[1]
    a, b = improved_policy_value(exp, eps), affine_policy_value(exp, L, d, ref.u_bar[1])
    assert a.s == pytest.approx(b.s) and np.allclose(a.v, b.v) and np.allclose(a.V, b.V)
    assert np.allclose(a.S, b.S)


def test_belief_ilqg_feedback_on_mean_is_lqg_for_linear_model():
    Q, R, K = np.eye(2), np.array([[0.5]]), 6
    cost = QuadraticCost(Q, R, Q, np.zeros(2), K)
    res = belief_ilqg(LIN, cost, np.array([1.0, 0.5]), 0.1 * np.eye(2), rtol=1e-10)
    for L_ours, L_lqg in zip(res.L, lqg_gains(Q, R, Q, K)):
        assert np.allclose(L_ours[:, :2], L_lqg, atol=1e-5)


def test_both_controllers_improve_on_the_example():
    ex = landmark_example(K=20)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = optimize_belief_trajectory(
            ex.model,
            ex.cost,
            ex.mean0,
            ex.cov0,
            rng=np.random.default_rng(1),
            n_cost_runs=30,
            max_iterations=3,
        )
    assert res.costs[-1] < 0.5 * res.costs[0]
    assert all(np.all(e[e > 0] <= 1.0) for e in res.eps)


# --- bad input ---------------------------------------------------------------------


def test_bad_covariance():
    with pytest.raises(ValueError, match="cov"):
        GaussianNoise(np.zeros(2), np.array([[1.0, 0.0], [0.0, -1.0]]))
    with pytest.raises(ValueError, match="symmetric"):
        GaussianNoise(np.zeros(2), np.array([[1.0, 0.5], [0.0, 1.0]]))


def test_bad_horizon():
    with pytest.raises(ValueError, match="horizon"):
        QuadraticCost(np.eye(2), np.eye(2), np.eye(2), np.zeros(2), 0)


def test_bad_mixture_weights():
    with pytest.raises(ValueError, match="summing to 1"):
        DiracMixture(np.zeros((3, 2)), np.array([0.5, 0.5, 0.5]))
    with pytest.raises(ValueError, match="non-negative"):
        DiracMixture(np.zeros((2, 2)), np.array([1.5, -0.5]))


def test_cost_violating_assumption_2_3():
    with pytest.raises(ValueError, match="Assumption 2.3"):
        QuadraticCost(np.eye(2), np.zeros((2, 2)), np.eye(2), np.zeros(2), 5)


def test_bad_rng_and_policy_shape():
    ex = landmark_example(K=3)
    with pytest.raises(TypeError, match="rng"):
        optimize_belief_trajectory(ex.model, ex.cost, ex.mean0, ex.cov0, rng=1)
    with pytest.raises(ValueError, match="policy"):
        optimize_belief_trajectory(
            ex.model,
            ex.cost,
            ex.mean0,
            ex.cov0,
            rng=np.random.default_rng(0),
            policy=AffinePolicy.zero(4, 2, 2),
        )
    with pytest.raises(ValueError, match="n_runs"):
        draw_noise(ex.model, ex.mean0, ex.cov0, 3, 0, np.random.default_rng(0))


def test_indefinite_covariance_hessian_warns_not_crashes():
    ex = landmark_example(K=20)
    with pytest.warns(RuntimeWarning, match="Assumption 2.3"):
        res = optimize_belief_trajectory(
            ex.model,
            ex.cost,
            ex.mean0,
            ex.cov0,
            rng=np.random.default_rng(1),
            n_cost_runs=20,
            max_iterations=2,
            covariance_hessian="exact",
        )
    assert res.iterations == 2 and sum(res.rejected) > 0


def test_line_search_that_cannot_decrease_stops_with_flag():
    from asoc.belief import Expansion, line_search

    class Flat(StageProblem):
        def __init__(self):
            pass

        def cost_to_go(self, u):
            return 0.0 if np.allclose(u, 0.0) else 1.0 + float(np.sum(np.abs(u)))

    exp = Expansion(
        phi=np.zeros(1),
        p=np.zeros((1, 1)),
        r=np.ones((1, 1)),
        Q=np.zeros((1, 1, 1)),
        P=np.zeros((1, 1, 1)),
        R=np.eye(1)[None],
        points=np.zeros((1, 1)),
        alpha=np.ones(1),
    )
    ls = line_search(Flat(), exp, np.zeros(1), np.zeros(1))
    assert not ls.accepted and ls.cost_after == ls.cost_before
    assert ls.status == "no_progress" and "alpha_min" in ls.message


# --- safeguards for the curvature of the covariance term ---------------------------


def _schur_ok(H, nx, mu):
    Q, P, R = H[:nx, :nx], H[nx:, :nx], H[nx:, nx:] + mu * np.eye(H.shape[0] - nx)
    return (
        np.linalg.eigvalsh(R).min() > 0
        and np.linalg.eigvalsh(Q - P.T @ np.linalg.solve(R, P)).min() >= -1e-7
    )


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_levenberg_marquardt_shift_is_the_smallest_that_satisfies_2_9(seed):
    rng = np.random.default_rng(seed)
    nx, nu = 2, 2
    M = rng.normal(size=(nx + nu, nx + nu))
    H = M @ M.T + 0.1 * np.eye(nx + nu)  # satisfies (2.9)
    H[nx:, nx:] -= rng.uniform(0, 5) * np.eye(nu)  # negative curvature in u
    H = np.stack([H, H])
    mu = StageProblem.levenberg_marquardt_shift(np.array([0.5, 0.5]), H, nx)
    assert mu >= 0 and _schur_ok(H[0], nx, mu * (1 + 1e-5))
    if mu > 0:
        assert not _schur_ok(H[0], nx, mu * (1 - 1e-3))


def test_shift_is_zero_when_the_exact_hessian_satisfies_2_9():
    H = np.stack([np.array([[2.0, 0.5], [0.5, 1.0]])])
    assert StageProblem.levenberg_marquardt_shift(np.ones(1), H, 1) == 0.0


def test_covariance_hessian_variants_on_the_example():
    ex, filt, policy, ref, wp, beta, nxt = _step1_setup()
    exps = {
        name: StageProblem(
            ex.model, ex.cost, filt, ref.estimates[1], nxt, wp, beta, name
        ).expansion(ref.u_bar[1])
        for name in ("psd", "exact", "shift")
    }
    # the three differ only in R; the gradient (first-order dual effect) is the same
    for name in ("p", "r", "Q", "P"):
        assert np.allclose(getattr(exps["psd"], name), getattr(exps["exact"], name))
        assert np.allclose(getattr(exps["shift"], name), getattr(exps["exact"], name))
    R = {name: e.tilde[3] for name, e in exps.items()}
    # projection only adds curvature
    assert np.linalg.eigvalsh(R["psd"] - R["exact"]).min() >= -1e-9
    assert np.linalg.eigvalsh(R["psd"]).min() >= 2 * 0.1 - 1e-9  # >= grad_uu C_k = 2 R
    d = R["shift"] - R["exact"]
    # a shift mu I, nothing else
    assert np.allclose(d, d[0, 0] * np.eye(2)) and d[0, 0] >= 0
    with pytest.raises(ValueError, match="covariance_hessian"):
        StageProblem(ex.model, ex.cost, filt, ref.estimates[1], nxt, wp, beta, "clip")


# --- the control run without the covariance term (audit of Sec. 2.5.3) --------------


def test_without_covariance_term_the_expansion_is_the_particle_part_only():
    ex, filt, policy, ref, wp, beta, nxt = _step1_setup()
    assert np.any(nxt.S), "the setup must have a covariance term to remove"
    stage = StageProblem(
        ex.model, ex.cost, filt, ref.estimates[1], nxt, wp, beta, covariance_term=False
    )
    assert stage.covariance_part(ref.u_bar[1] + 0.3) == 0.0
    # the same as a value function whose S_{k+1} is zero
    no_S = type(nxt)(nxt.s, nxt.v, nxt.V, np.zeros_like(nxt.S))
    exp = stage.expansion(ref.u_bar[1])
    ref_exp = StageProblem(ex.model, ex.cost, filt, ref.estimates[1], no_S, wp, beta).expansion(
        ref.u_bar[1]
    )
    for name in ("phi", "p", "r", "Q", "P", "R"):
        assert np.allclose(getattr(exp, name), getattr(ref_exp, name), rtol=1e-12, atol=1e-12), name
    with_term = StageProblem(ex.model, ex.cost, filt, ref.estimates[1], nxt, wp, beta).expansion(
        ref.u_bar[1]
    )
    assert not np.allclose(with_term.phi, exp.phi)


# --- distributions over perturbed runs of Alg. 2.2 ----------------------------------


def test_distribution_record():
    from asoc.belief.sweep import distribution

    d = distribution([3.0, 1.0, 2.0, 10.0])
    assert d == {"value": 2.5, "median": 2.5, "range": [1.0, 10.0], "n": 4}
    with pytest.raises(ValueError, match="samples"):
        distribution([])


def test_perturbation_sweep_members_differ_and_psd_is_not_chaotic():
    from asoc.belief.sweep import perturbation_sweep

    ex = landmark_example(K=4)
    noise = draw_noise(ex.model, ex.mean0, ex.cov0, 4, 50, np.random.default_rng(3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        s = perturbation_sweep(
            ex.model,
            ex.cost,
            ex.mean0,
            ex.cov0,
            noise,
            3,
            np.random.default_rng(4),
            n_cost_runs=20,
            max_iterations=6,
        )
    assert s.iterations.shape == s.costs.shape == s.converged.shape == (3,)
    assert np.all((s.iterations >= 1) & (s.iterations <= 6)) and np.all(np.isfinite(s.costs))
    # the zero policy on the same draws is the baseline; the converged policies are far cheaper
    from asoc.belief import MeanAffineController, simulate

    zero = simulate(
        ex.model,
        ex.cost,
        ex.mean0,
        ex.cov0,
        MeanAffineController(ex.model, AffinePolicy.zero(4, 2, 2)),
        noise,
    ).costs.mean()
    assert s.baseline == pytest.approx(zero, rel=1e-12) and not s.diverged.any()
    # the default is not chaotic: members differ only in where the stopping rule (|dJ| <= 1e-4 J on
    # the J draws) stops, so their costs on other draws differ by the same order (factor 10 slack)
    assert np.ptp(s.costs) <= 10 * 1e-4 * np.mean(s.costs), s.costs


def test_perturbation_sweep_in_worker_processes_equals_the_serial_sweep():
    """n_jobs=2 gives the serial rows (to rounding: another process may use other BLAS kernels), and
    the
    workers' warnings reach the caller."""
    from asoc.belief.sweep import perturbation_sweep

    ex = landmark_example(K=4)
    noise = draw_noise(ex.model, ex.mean0, ex.cov0, 4, 20, np.random.default_rng(3))
    runs = {}
    for n_jobs in (1, 2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s = perturbation_sweep(
                ex.model,
                ex.cost,
                ex.mean0,
                ex.cov0,
                noise,
                2,
                np.random.default_rng(4),
                n_cost_runs=10,
                max_iterations=2,
                rtol=1e-12,
                n_jobs=n_jobs,
            )
        runs[n_jobs] = (s, [str(w.message) for w in caught])
    (serial, said), (parallel, said_parallel) = runs[1], runs[2]
    for field in ("iterations", "converged"):
        assert np.array_equal(getattr(serial, field), getattr(parallel, field)), field
    for field in ("costs", "diverged_iterates"):
        np.testing.assert_allclose(
            getattr(serial, field), getattr(parallel, field), rtol=1e-10, err_msg=field
        )
    assert serial.baseline == pytest.approx(parallel.baseline, rel=1e-12)
    assert said == said_parallel and any("did not converge" in m for m in said)


def test_perturbation_sweep_rejects_bad_arguments():
    from asoc.belief.sweep import perturbation_sweep

    ex = landmark_example(K=3)
    noise = draw_noise(ex.model, ex.mean0, ex.cov0, 3, 5, np.random.default_rng(0))
    with pytest.raises(ValueError, match="n_members"):
        perturbation_sweep(ex.model, ex.cost, ex.mean0, ex.cov0, noise, 0, np.random.default_rng(0))
    with pytest.raises(ValueError, match="scale"):
        perturbation_sweep(
            ex.model, ex.cost, ex.mean0, ex.cov0, noise, 2, np.random.default_rng(0), scale=0.0
        )
    with pytest.raises(TypeError, match="rng"):
        perturbation_sweep(ex.model, ex.cost, ex.mean0, ex.cov0, noise, 2, 1)
    with pytest.raises(ValueError, match="n_jobs"):
        perturbation_sweep(
            ex.model, ex.cost, ex.mean0, ex.cov0, noise, 2, np.random.default_rng(0), n_jobs=0
        )


# --- issue 15: bad input named, results say why they stopped --------------------------


@pytest.mark.parametrize(
    "bad, error",
    [
        (0, ValueError),
        (-1, ValueError),
        (2.5, TypeError),
        (float("nan"), TypeError),
        (float("inf"), TypeError),
        ("3", TypeError),
        (True, TypeError),
    ],
)
def test_integer_arguments_reject_non_integers(bad, error):
    ex = landmark_example(K=2)
    with pytest.raises(error, match="max_iterations: expected an integer"):
        optimize_belief_trajectory(
            ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0), max_iterations=bad
        )
    with pytest.raises(error, match="max_iterations: expected an integer"):
        belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0, max_iterations=bad)
    with pytest.raises(error, match="n_runs: expected an integer"):
        draw_noise(ex.model, ex.mean0, ex.cov0, 2, bad, np.random.default_rng(0))


def test_belief_ilqg_rejects_negative_definite_covariance():
    ex = landmark_example(K=2)
    with pytest.raises(
        ValueError,
        match="cov0: expected a positive semi-definite matrix, found smallest eigenvalue -1",
    ):
        belief_ilqg(ex.model, ex.cost, ex.mean0, -np.eye(2))
    with pytest.raises(ValueError, match="cov0"):
        optimize_belief_trajectory(
            ex.model, ex.cost, ex.mean0, -np.eye(2), rng=np.random.default_rng(0)
        )


def test_sigma_points_reject_degenerate_arguments():
    with pytest.raises(ValueError, match="mean: expected shape"):
        sigma_points(1.0, 1.0)  # a scalar is not a (..., n) mean
    with pytest.raises(ValueError, match="cov: expected shape"):
        sigma_points([0.0, 0.0], [[1.0]])
    with pytest.raises(ValueError, match="kappa: expected a finite real number > -2"):
        sigma_points([0.0, 0.0], np.eye(2), kappa=-2)
    with pytest.raises(TypeError, match="cov: expected a real array, found complex"):
        sigma_points([0.0], [[1j]])
    points, _ = sigma_points([0.0, 0.0], np.eye(2), kappa=1)  # spread sqrt(n + kappa) = sqrt(3)
    assert np.allclose(np.abs(points).max(), np.sqrt(3))


def test_results_say_why_they_stopped():
    ex = landmark_example(K=3)
    with pytest.warns(RuntimeWarning, match="did not converge"):
        res = optimize_belief_trajectory(
            ex.model,
            ex.cost,
            ex.mean0,
            ex.cov0,
            rng=np.random.default_rng(0),
            n_cost_runs=10,
            max_iterations=1,
        )
    assert (res.converged, res.status, res.iterations) == (False, "max_iterations", 1)
    assert "max_iterations = 1" in res.message
    res = optimize_belief_trajectory(
        ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0), n_cost_runs=10
    )
    assert res.converged and res.status == "converged" and "rtol" in res.message
    ilqg = belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0)
    assert ilqg.converged and ilqg.status == "converged"
    with pytest.warns(RuntimeWarning, match="did not converge"):
        short = belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0, max_iterations=1, rtol=1e-12)
    assert short.status in ("max_iterations", "no_progress") and not short.converged


def test_simulate_checks_the_controller_against_the_draws():
    from asoc.belief import MeanAffineController, simulate

    ex = landmark_example(K=3)
    noise = draw_noise(ex.model, ex.mean0, ex.cov0, 3, 2, np.random.default_rng(0))
    short = MeanAffineController(ex.model, AffinePolicy.zero(2, 2, 2))
    with pytest.raises(ValueError, match="controller: expected a horizon >= 3"):
        simulate(ex.model, ex.cost, ex.mean0, ex.cov0, short, noise)
    with pytest.raises(ValueError, match="policy: expected gains of shape"):
        MeanAffineController(ex.model, AffinePolicy.zero(3, 1, 2))
    with pytest.raises(TypeError, match="model: expected a NonlinearModel"):
        simulate("model", ex.cost, ex.mean0, ex.cov0, short, noise)


def _textbook_next_covariance(model, mean, cov, u, kappa=0.5):
    """C_{k+1} of the UKF written out: sigma points of each joint Gaussian from the root of its
    whole block-diagonal covariance (:func:`sigma_points`), Lemma 2.1 with the pseudo-inverse."""

    def joint_points(m, P, noise):
        joint_cov = np.block(
            [[P, np.zeros((m.size, noise.dim))], [np.zeros((noise.dim, m.size)), noise.cov]]
        )
        points, weights = sigma_points(np.concatenate([m, noise.mean]), joint_cov, kappa)
        return points[:, : m.size], points[:, m.size :], weights

    x, w, weights = joint_points(mean, cov, model.w)
    x_next = model.a(x, u, w)
    e = x_next - weights @ x_next
    x, v, weights = joint_points(weights @ x_next, (weights[:, None] * e).T @ e, model.v)
    y = model.h(x, v)
    ex, ey = x - weights @ x, y - weights @ y
    Cxy = (weights[:, None] * ex).T @ ey
    return (weights[:, None] * ex).T @ ex - Cxy @ np.linalg.pinv(
        (weights[:, None] * ey).T @ ey
    ) @ Cxy.T


def _random_models(rng):
    n_x = int(rng.integers(1, 4))
    yield landmark_example().model
    for n_y in (1, 2):
        yield linear_gaussian_model(
            np.eye(n_x) + 0.3 * rng.normal(size=(n_x, n_x)),
            rng.normal(size=(n_x, 2)),
            rng.normal(size=(n_x, 2)),
            rng.normal(size=(n_y, n_x)),
            np.eye(n_y),
        )
    from asoc.belief import NonlinearModel  # a measurement that says nothing: C^{yy} = 0

    yield NonlinearModel(
        a=lambda x, u, w: np.sin(x) + u + w,
        h=lambda x, v: 0.0 * x[..., :1] + 0.0 * v,
        w=GaussianNoise(np.zeros(n_x), np.eye(n_x)),
        v=GaussianNoise([0.0], [[1.0]]),
        n_x=n_x,
        n_u=n_x,
    )


def _random_estimates(seed, singular):
    """(rng, model, mean, cov) for each of :func:`_random_models`; ``singular``: the covariance
    has no Cholesky factor (its last row and column are zero)."""
    rng = np.random.default_rng(seed)
    for model in _random_models(rng):
        M = rng.normal(size=(model.n_x, model.n_x))
        mean, cov = rng.normal(size=model.n_x), 0.5 * M @ M.T
        if singular:
            cov[-1], cov[:, -1] = 0.0, 0.0
        yield rng, model, mean, cov


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.booleans())
def test_covariance_map_equals_the_public_and_the_textbook_next_covariance(seed, singular):
    for rng, model, mean, cov in _random_estimates(seed, singular):  # singular: the eigen root
        u = rng.normal(size=model.n_u)
        ukf = UKF(model)
        public = ukf.next_covariance((mean, cov), u)
        mapped = ukf.covariance_map((mean, cov))(u)
        scale = max(1.0, np.abs(public).max())
        np.testing.assert_allclose(mapped, public, rtol=1e-12, atol=1e-12 * scale)
        np.testing.assert_allclose(
            mapped, _textbook_next_covariance(model, mean, cov, u), rtol=1e-10, atol=1e-12 * scale
        )


def test_stage_problem_inner_loop_equals_its_checked_covariance_part():
    ex = landmark_example(K=2)
    filt = UKF(ex.model)
    w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    rng = np.random.default_rng(3)
    S = rng.normal(size=(2, 2))  # tr[S C] also for an S that is not symmetric
    stage = StageProblem(
        ex.model, ex.cost, filt, (ex.mean0, ex.cov0), Value(0.0, np.zeros(2), np.eye(2), S), w, beta
    )
    for u in rng.normal(size=(5, 2)):
        C = filt.next_covariance((ex.mean0, ex.cov0), u)
        assert stage.covariance_part(list(u)) == pytest.approx(0.5 * np.trace(S @ C), rel=1e-13)
        assert stage.covariance_part(u) == stage.covariance_part(list(u))
    with pytest.raises(ValueError, match="u: expected shape"):
        stage.covariance_part([1.0])


class _ProtocolOnly:
    """A filter that offers Alg. 2.2 nothing but the methods of the BeliefFilter protocol (a UKF
    inside)."""

    def __init__(self, model):
        self._inner = UKF(model)

    def initial(self, mean, cov):
        return self._inner.initial(mean, cov)

    def step(self, estimate, u, y):
        return self._inner.step(estimate, u, y)

    def mean(self, estimate):
        return self._inner.mean(estimate)

    def mixture(self, estimate):
        return self._inner.mixture(estimate)

    def next_covariance(self, estimate, u):
        return self._inner.next_covariance(estimate, u)

    def covariance_map(self, estimate):
        return lambda u: self._inner.next_covariance(estimate, u)


def test_the_trajectory_optimiser_uses_a_filter_through_its_protocol_only():
    from asoc.belief import BeliefFilter

    ex = landmark_example(K=3)
    wrapped = _ProtocolOnly(ex.model)
    assert isinstance(wrapped, BeliefFilter) and isinstance(UKF(ex.model), BeliefFilter)
    assert isinstance(ParticleFilter(ex.model, 10, np.random.default_rng(0)), BeliefFilter)
    w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    policy = AffinePolicy(np.zeros((3, 2, 2)), np.ones((3, 2)))
    ref = reference_trajectory(ex.model, wrapped, policy, ex.mean0, ex.cov0)
    new, value, eps, _ = backward_pass(ex.model, ex.cost, wrapped, ref, policy, w, beta)
    new_ukf, value_ukf, eps_ukf, _ = backward_pass(
        ex.model, ex.cost, UKF(ex.model), ref, policy, w, beta
    )
    np.testing.assert_allclose(new.L, new_ukf.L, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(new.d, new_ukf.d, rtol=1e-9, atol=1e-9)
    assert value.s == pytest.approx(value_ukf.s, rel=1e-9) and np.array_equal(eps, eps_ukf)
    # the covariance term (through covariance_map) took part
    assert np.any(value.S != 0)
    del _ProtocolOnly.covariance_map
    try:
        with pytest.raises(TypeError, match="filt: expected a filter .* without covariance_map"):
            backward_pass(ex.model, ex.cost, _ProtocolOnly(ex.model), ref, policy, w, beta)
    finally:
        _ProtocolOnly.covariance_map = lambda self, estimate: (
            lambda u: self._inner.next_covariance(estimate, u)
        )
