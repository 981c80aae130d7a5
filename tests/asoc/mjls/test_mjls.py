"""Unit tests of asoc.mjls: model validation, stability, moments, Alg. 3.1, LMIs, baselines,
Monte Carlo."""

import warnings

import numpy as np
import pytest
import scipy.linalg as sla

from asoc.mjls import (
    MJLS,
    ModeDependentGain,
    StaticGain,
    TimeVariantGain,
    closed_loop,
    dynamic_output_feedback,
    h2_cost,
    ms_spectral_radius,
    second_moments,
    simulate,
    static_output_feedback,
    steady_state_second_moment,
)
from asoc.mjls.baselines import do_val_h2_state_feedback, time_variant_feedback
from asoc.mjls.examples import sec354_system
from asoc.mjls.intractability import expected_cost_two_steps_before_horizon
from asoc.mjls.lmi import static_output_lmi
from asoc.mjls.observed_mode_feedback import observed_mode_state_feedback


def random_mjls(rng, M=3, nx=3, nu=2, ny=2, scale=0.6):
    A = rng.normal(size=(M, nx, nx))
    A *= scale / np.max(np.abs(np.linalg.eigvals(A)), axis=1)[:, None, None]
    T = rng.random((M, M)) + 0.2
    T /= T.sum(axis=1, keepdims=True)
    return MJLS(
        A=A,
        B=rng.normal(size=(M, nx, nu)),
        C=rng.normal(size=(M, ny, nx)),
        H=0.3 * rng.normal(size=(M, nx, nx)),
        Q=np.eye(nx),
        R=np.eye(nu),
        T=T,
    )


# --- validation ------------------------------------------------------------------------------


def test_bad_transition_matrix_names_the_row():
    with pytest.raises(ValueError, match=r"T: expected rows summing to 1, found sum 1.1 in row 1"):
        sec354_system(1).replace(T=[[0.7, 0.3], [0.5, 0.6]])


def test_wrong_shape_names_matrix_and_shapes():
    sys = sec354_system(1)
    with pytest.raises(ValueError, match=r"B: expected shape .*found \(2, 3, 1\)"):
        sys.replace(B=np.zeros((2, 3, 1)))
    with pytest.raises(ValueError, match=r"A: expected 2 modes, found 3"):
        sys.replace(A=np.zeros((3, 2, 2)))


def test_weights_and_finiteness_are_checked():
    sys = sec354_system(1)
    with pytest.raises(ValueError, match="Q: expected a symmetric matrix"):
        sys.replace(Q=np.array([[1.0, 1.0], [0.0, 1.0]]))
    with pytest.raises(ValueError, match="Q: .*positive semi-definite"):
        sys.replace(Q=-np.eye(2))
    with pytest.raises(ValueError, match="R: .*positive definite"):
        sys.replace(R=np.zeros((1, 1)))
    with pytest.raises(ValueError, match="A: expected finite entries"):
        sys.replace(A=np.full((2, 2, 2), np.nan))


# --- stability and moments ---------------------------------------------------------------------


def test_spectral_radius_single_mode_is_square_of_eigenvalue_radius():
    A = np.array([[[0.5, 1.0], [0.0, -0.8]]])
    assert ms_spectral_radius(A, [[1.0]]) == pytest.approx(0.8**2)


def test_second_moments_match_monte_carlo():
    rng = np.random.default_rng(0)
    sys = random_mjls(rng)
    L = 0.1 * rng.normal(size=(sys.nu, sys.ny))
    Acl = closed_loop(sys, L)
    x0 = np.array([1.0, -2.0, 0.5])
    mu0 = np.array([1.0, 0.0, 0.0])
    K = 8
    X, mu = second_moments(
        Acl, sys.H @ np.swapaxes(sys.H, 1, 2), sys.T, mu0[:, None, None] * np.outer(x0, x0), mu0, K
    )
    run = simulate(
        sys, StaticGain(L), x0, K, 200_000, np.random.default_rng(1), mode0=0, trajectories=True
    )
    xK, thK = run.x[:, K], run.theta[:, K]
    for i in range(sys.M):
        emp = np.einsum("na,nb->ab", xK * (thK == i)[:, None], xK) / len(xK)
        assert np.allclose(emp, X[K, i], atol=0.04 * np.abs(X[K]).max())


def test_steady_state_moment_is_the_fixed_point_and_h2_is_the_mean_cost():
    sys = sec354_system(1)
    L = np.array([[-0.6350]])
    Acl = closed_loop(sys, L)
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    X = steady_state_second_moment(Acl, HHt, sys.T, sys.mu_inf)
    X_iter, _ = second_moments(Acl, HHt, sys.T, np.zeros_like(X), sys.mu_inf, 3000)
    assert np.allclose(X, X_iter[-1], rtol=1e-8)
    run = simulate(sys, StaticGain(L), np.zeros(2), 400, 20_000, np.random.default_rng(2))
    assert run.average_cost.mean() == pytest.approx(h2_cost(sys, L, X), rel=0.03)


# --- Algorithm 3.1 -------------------------------------------------------------------------------


def test_alg31_reduces_to_lqr_for_one_mode_with_state_feedback():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    B = rng.normal(size=(3, 2))
    sys = MJLS(A=[A], B=[B], C=[np.eye(3)], H=[np.eye(3)], Q=np.eye(3), R=np.eye(2), T=[[1.0]])
    res = static_output_feedback(sys)
    P = sla.solve_discrete_are(A, B, np.eye(3), np.eye(2))
    L_lqr = -np.linalg.solve(np.eye(2) + B.T @ P @ B, B.T @ P @ A)
    assert res.converged and res.stabilizing
    assert np.allclose(res.L, L_lqr, atol=1e-7)


def test_alg31_gain_is_a_local_minimum_of_the_h2_cost():
    sys = sec354_system(1)
    res = static_output_feedback(sys)
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)

    def cost(L):
        return h2_cost(
            sys, L, steady_state_second_moment(closed_loop(sys, L), HHt, sys.T, sys.mu_inf)
        )

    assert res.cost == pytest.approx(cost(res.L))
    for d in (1e-3, -1e-3):
        assert cost(res.L + d) > res.cost


def _cycling_system():
    """A one-mode SISO plant on which Alg. 3.1's rounded iterates enter an exact cycle (period 4)
    that never converges (the theorems study's instance 724 of Thm. 3.19)."""
    return MJLS(
        A=[
            [[-0.4010618596277141, 0.15882195728302725], [-0.04761625360329824, 0.9673182700358467]]
        ],
        B=[[[0.8873383401418364], [-2.2116975975090343]]],
        C=[[[0.48262978539405166, -0.1189634013936829]]],
        H=[
            [
                [-0.012479499244516093, 0.02867173577466553],
                [-0.16041686665335952, -0.06703692602438936],
            ]
        ],
        Q=[[[3.468697134485018, -1.7170386980821353], [-1.7170386980821353, 2.285042014736245]]],
        R=[[[1.2638465871897315]]],
        T=[[1.0]],
    )


def test_alg31_stops_on_the_cycle_of_the_study_instance_and_says_why():
    """Theorem study instance 724 of Thm. 3.19: the iterates settle into a 2-cycle; the rule stops
    at once (it ran to max_iter before) with the member of smallest exact cost."""
    with pytest.warns(RuntimeWarning, match="cycle of period 2.*exact_static_output_feedback"):
        res = static_output_feedback(_cycling_system())
    assert (res.status, res.period, res.converged) == ("cycle", 2, False) and res.iterations < 200


def test_alg31_sdp_solve_of_331_agrees_with_vec():
    sys = sec354_system(1, "state")
    a, b = static_output_feedback(sys), static_output_feedback(sys, method="sdp", max_iter=2000)
    assert np.allclose(a.L, b.L, atol=1e-5)


def test_alg31_reports_non_convergence_and_instability():
    with pytest.warns(RuntimeWarning, match="did not converge"):
        res = static_output_feedback(sec354_system(1), max_iter=3)
    assert not res.converged and res.iterations == 3
    with pytest.warns(RuntimeWarning, match="does not stabilise"):
        res = static_output_feedback(sec354_system(1, "C=[1 0]"))
    assert res.converged and not res.stabilizing and res.cost == np.inf
    with pytest.raises(ValueError, match="tol"):
        static_output_feedback(sec354_system(1), tol=-1)


# --- LMIs and baselines --------------------------------------------------------------------------


def test_lmi_infeasible_is_a_result_not_an_exception():
    res = static_output_lmi(sec354_system(1, "C=[1 0]"))
    assert not res.feasible and res.L is None and res.status == "infeasible"


def test_lmi_state_feedback_gain_stabilises_and_bounds_the_h2_cost():
    sys = sec354_system(1, "state")
    res = static_output_lmi(sys)
    assert res.feasible
    Acl = closed_loop(sys, res.L)
    assert ms_spectral_radius(Acl, sys.T) < 1
    X = steady_state_second_moment(Acl, sys.H @ np.swapaxes(sys.H, 1, 2), sys.T, sys.mu_inf)
    assert h2_cost(sys, res.L, X) <= res.bound + 1e-6
    observed = static_output_lmi(sys, mode_observed=True)
    assert (
        observed.feasible and observed.L.shape == (2, 1, 2) and observed.bound <= res.bound + 1e-6
    )


def test_lmi_and_baseline_gains_carry_the_certified_bracket():
    """The stability verdict of an LMI gain follows the certified bracket of rho, as every
    design's."""
    from asoc.mjls import mean_square_stability
    from asoc.mjls.baselines import do_val_h2_state_feedback

    for sys, design in (
        (sec354_system(1, "state"), static_output_lmi),
        (sec354_system(2, "state"), do_val_h2_state_feedback),
    ):
        res = design(sys)
        truth = mean_square_stability(closed_loop(sys, res.L), sys.T)  # C = I: state feedback
        lower, upper = res.rho_bracket
        assert lower <= res.rho <= upper and upper - lower < 1e-6
        assert res.stabilizing is truth.stabilizing is True and abs(res.rho - truth.rho) < 1e-9


def test_do_val_gain_stabilises_and_bounds_its_cost():
    sys = sec354_system(2, "state")
    res = do_val_h2_state_feedback(sys)
    Acl = sys.A + sys.B @ res.L
    X = steady_state_second_moment(Acl, sys.H @ np.swapaxes(sys.H, 1, 2), sys.T, sys.mu_inf)
    assert ms_spectral_radius(Acl, sys.T) < 1
    assert h2_cost(sys, res.L, X) <= res.bound + 1e-6


def test_observed_mode_riccati_reduces_to_dare_and_beats_mode_independent_gain():
    rng = np.random.default_rng(4)
    A, B = rng.normal(size=(2, 2)), rng.normal(size=(2, 1))
    one = MJLS(A=[A], B=[B], C=[np.eye(2)], H=[np.eye(2)], Q=np.eye(2), R=np.eye(1), T=[[1.0]])
    res = observed_mode_state_feedback(one)
    assert np.allclose(res.P[0], sla.solve_discrete_are(A, B, np.eye(2), np.eye(1)), rtol=1e-8)
    sys = sec354_system(1, "state")
    obs = observed_mode_state_feedback(sys)
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    X = steady_state_second_moment(sys.A + sys.B @ obs.L, HHt, sys.T, sys.mu_inf)
    cost_obs = float(np.einsum("iab,iba->", sys.Q + np.swapaxes(obs.L, 1, 2) @ sys.R @ obs.L, X))
    assert cost_obs <= static_output_feedback(sys).cost


def test_observed_mode_riccati_reports_an_unstabilisable_system():
    """Mode 2 has no input and stays with probability 0.9: rho >= 0.9 * 1.5^2 > 1 for every gain."""
    A, B = np.diag([1.5, 0.5]), np.array([[1.0], [0.0]])
    sys = MJLS(
        A=[A, A],
        B=[B, 0 * B],
        C=[np.eye(2)] * 2,
        H=[np.eye(2)] * 2,
        Q=np.eye(2),
        R=np.eye(1),
        T=[[0.5, 0.5], [0.1, 0.9]],
    )
    with pytest.warns(RuntimeWarning, match="not mean-square stabilisable even with observed mode"):
        res = observed_mode_state_feedback(sys)
    assert not res.converged and not res.stabilizing and res.rho >= 0.9 * 1.5**2
    assert np.all(np.isfinite(res.P)) and np.all(np.isfinite(res.L))
    with pytest.raises(ValueError, match="max_iter"):
        observed_mode_state_feedback(sys, max_iter=0)


def test_variational_method_decreases_cost_and_predicts_monte_carlo():
    sys = sec354_system(1)
    x0 = np.array([3.0, 0.0])
    res = time_variant_feedback(sys, 30, x0)
    assert res.converged and np.all(np.diff(res.costs) <= 1e-9 * res.costs[0])
    mc = simulate(sys, TimeVariantGain(res.G), x0, 30, 40_000, np.random.default_rng(5)).cost
    se = mc.std() / np.sqrt(mc.size)
    assert abs(mc.mean() - res.costs[-1]) < 4 * se
    # with one mode and state feedback the optimum is the finite-horizon LQR
    one = MJLS(
        A=[sys.A[0]], B=[sys.B[0]], C=[np.eye(2)], H=[sys.H[0]], Q=np.eye(2), R=np.eye(1), T=[[1.0]]
    )
    G = time_variant_feedback(one, 5, x0).G
    P = np.eye(2)
    for k in range(4, -1, -1):
        A_, B_ = one.A[0], one.B[0]
        Lk = -np.linalg.solve(np.eye(1) + B_.T @ P @ B_, B_.T @ P @ A_)
        P = np.eye(2) + A_.T @ P @ A_ + A_.T @ P @ B_ @ Lk
        if k > 0:
            assert np.allclose(G[k], Lk, atol=1e-8)
        else:  # X(0) = x0 x0^T: only G_0 x0 is determined
            assert np.allclose(G[0] @ x0, Lk @ x0, atol=1e-8)


# --- Monte Carlo ------------------------------------------------------------------------------


def test_simulation_is_deterministic_and_validates_input():
    sys = sec354_system(1)
    a = simulate(sys, StaticGain([[-0.6]]), np.array([3.0, 0.0]), 20, 500, np.random.default_rng(7))
    b = simulate(sys, StaticGain([[-0.6]]), np.array([3.0, 0.0]), 20, 500, np.random.default_rng(7))
    assert np.array_equal(a.cost, b.cost)
    with pytest.raises(ValueError, match="horizon"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(2), 0, 10, np.random.default_rng(0))
    with pytest.raises(ValueError, match="mode0"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(2), 5, 10, np.random.default_rng(0), mode0=2)
    with pytest.raises(TypeError, match="rng"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(2), 5, 10, 0)
    with pytest.raises(ValueError, match="x0"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(3), 5, 10, np.random.default_rng(0))


def test_mode_chain_has_the_transition_frequencies_of_T():
    sys = sec354_system(1)
    run = simulate(
        sys,
        ModeDependentGain(np.zeros((2, 1, 1))),
        np.zeros(2),
        50,
        4000,
        np.random.default_rng(8),
        trajectories=True,
    )
    th = run.theta
    for i in range(2):
        frm = th[:, :-1] == i
        freq = (th[:, 1:][frm] == 1).mean()
        assert freq == pytest.approx(sys.T[i, 1], abs=0.01)


# --- Sec. 3.4 --------------------------------------------------------------------------------


def test_expected_cost_two_steps_before_horizon_matches_monte_carlo():
    a, b, g = np.array([1.0, 0.3]), np.array([1.0, 0.8]), 0.2
    T, pi = np.array([[0.7, 0.3], [0.2, 0.8]]), np.array([0.4, 0.6])
    x, u = 1.5, -0.7
    J = expected_cost_two_steps_before_horizon(x, u, a, b, g, T, pi)
    rng = np.random.default_rng(9)
    q = rng.choice(2, size=400_000, p=pi)
    xn = a[q] * x + b[q] * u + g * rng.standard_normal(q.size)
    from asoc.mjls.intractability import psi

    samples = (
        x**2 + u**2 + xn**2 * psi(xn, np.full_like(xn, x), np.full_like(xn, u), a, b, g, T, pi)
    )
    assert J == pytest.approx(samples.mean(), abs=4 * samples.std() / np.sqrt(q.size))


# --- issue 15: named errors, zero optimum, reducible chains, why an iteration stopped --------


def _plant(**changes):
    A = [np.array([[0.5, 0.1], [0.0, 0.3]]), np.array([[0.2, 0.0], [0.1, 0.4]])]
    fields = dict(
        A=A,
        B=np.zeros((2, 1)),
        C=np.array([[1.0, 0.0]]),
        H=np.eye(2),
        Q=np.eye(2),
        R=np.eye(1),
        T=[[0.9, 0.1], [0.2, 0.8]],
    )
    fields.update(changes)
    return MJLS(**fields)


def test_zero_optimal_gain_converges():
    res = static_output_feedback(_plant())
    assert res.status == "converged" and res.iterations < 100 and np.all(res.L == 0)
    res = dynamic_output_feedback(_plant(J=0.1 * np.ones((1, 1))))
    assert res.status == "converged" and np.all(res.L == 0)


def test_reducible_chain_warns_and_takes_mu_inf():
    with pytest.warns(RuntimeWarning, match="T: the chain has 2 closed classes.*mu_inf"):
        _plant(T=np.eye(2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sys = _plant(T=np.eye(2), mu_inf=[0.25, 0.75])
    np.testing.assert_array_equal(sys.mu_inf, [0.25, 0.75])
    with pytest.raises(ValueError, match=r"mu_inf: expected a stationary distribution of T"):
        _plant(mu_inf=[0.5, 0.5])
    with pytest.raises(ValueError, match=r"mu_inf: expected probabilities summing to 1"):
        _plant(T=np.eye(2), mu_inf=[0.5, 0.6])


@pytest.mark.parametrize(
    "changes, error, match",
    [
        (dict(A=np.eye(2) * (1 + 1j)), TypeError, r"A: expected a real array, found complex"),
        (
            dict(T=np.array([[0.9, 0.1], [0.2, 0.8]]) + 0j),
            TypeError,
            r"T: expected a real array, found "
            r"complex",
        ),
        (
            dict(T=np.zeros((0, 0))),
            ValueError,
            r"T: expected a square \(M, M\) matrix with M >= 1, "
            r"found shape \(0, 0\)",
        ),
        (dict(T=[[np.nan, 1.0], [0.5, 0.5]]), ValueError, r"T: expected finite entries"),
        (dict(B=np.zeros((3, 1))), ValueError, r"B: expected shape \(2, 2, \*\) \(nx = 2 from A\)"),
        (dict(Q=[["a", "b"], ["c", "d"]]), TypeError, r"Q: expected a real array"),
    ],
)
def test_bad_system_matrices_are_named(changes, error, match):
    with pytest.raises(error, match=match):
        _plant(**changes)


def test_a_non_system_is_a_type_error():
    with pytest.raises(TypeError, match=r"sys: expected an MJLS \(asoc.mjls.MJLS\), found dict"):
        static_output_feedback({"A": 1})
    with pytest.raises(TypeError, match=r"sys: expected an MJLS"):
        closed_loop("plant", [[0.0]])


def test_lmi_margin_must_be_positive():
    with pytest.raises(ValueError, match=r"eps: expected a finite real number > 0, found -1"):
        static_output_lmi(sec354_system(1), eps=-1)


@pytest.mark.parametrize(
    "value, error",
    [
        (2.5, TypeError),
        (True, TypeError),
        ("10", TypeError),
        (float("nan"), TypeError),
        (0, ValueError),
    ],
)
def test_integer_counts_are_checked(value, error):
    with pytest.raises(error, match="max_iter: expected an integer"):
        static_output_feedback(sec354_system(1), max_iter=value)


def test_simulate_checks_the_controller_and_the_initial_state():
    sys, rng = sec354_system(1), np.random.default_rng(0)
    with pytest.raises(ValueError, match=r"x0: expected finite entries"):
        simulate(sys, StaticGain([[0.0]]), [np.nan, 0.0], 5, 10, rng)
    with pytest.raises(ValueError, match=r"L: expected finite entries"):
        simulate(sys, StaticGain([[np.nan]]), np.zeros(2), 5, 10, rng)
    with pytest.raises(ValueError, match=r"L: expected shape \(1, 1\) for the system"):
        simulate(sys, StaticGain([[0.0, 1.0]]), np.zeros(2), 5, 10, rng)
    with pytest.raises(TypeError, match=r"mode0: expected an integer, found 1.5"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(2), 5, 10, rng, mode0=1.5)
    with pytest.raises(ValueError, match=r"x0_cov: expected a symmetric matrix"):
        simulate(sys, StaticGain([[0.0]]), np.zeros(2), 5, 10, rng, x0_cov=[[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(TypeError, match=r"controller: expected an asoc.mjls.Controller"):
        simulate(sys, [[0.0]], np.zeros(2), 5, 10, rng)


def test_results_say_why_they_stopped():
    sys = sec354_system(1)
    with pytest.warns(RuntimeWarning, match=r"Algorithm 3.1 did not converge within 3 iterations"):
        res = static_output_feedback(sys, max_iter=3)
    assert (res.converged, res.status) == (
        False,
        "max_iterations",
    ) and "relative change" in res.message
    assert static_output_feedback(sys).status == "converged"
    unstabilisable = _plant(A=2 * np.eye(2))  # B = 0, unstable
    with pytest.warns(RuntimeWarning, match="diverges"):
        obs = observed_mode_state_feedback(unstabilisable)
    assert obs.status == "diverged" and not obs.converged
    with pytest.warns(
        RuntimeWarning, match="Algorithm 3.2 stopped at iteration .* the bounds diverged"
    ):
        dyn = dynamic_output_feedback(_plant(A=3 * np.eye(2), J=0.1 * np.ones((1, 1))))
    assert dyn.status == "diverged"
    lmi = static_output_lmi(sec354_system(1, "C=[1 0]"))
    assert (lmi.feasible, lmi.status, lmi.solver_status) == (False, "infeasible", "infeasible")


def test_table_3_2_designs_subset_equals_the_whole_table_and_names_unknown_rows():
    from asoc.mjls.monte_carlo_comparison import TABLE_3_2_ROWS, table_3_2_designs

    whole = table_3_2_designs(2, [3.0, 0.0], 20)
    part = table_3_2_designs(2, [3.0, 0.0], 20, rows=[TABLE_3_2_ROWS[4], TABLE_3_2_ROWS[3]])
    assert list(part) == [TABLE_3_2_ROWS[3], TABLE_3_2_ROWS[4]]  # in table order
    assert np.array_equal(
        part[TABLE_3_2_ROWS[3]].controller.L, whole[TABLE_3_2_ROWS[3]].controller.L
    )
    assert np.array_equal(
        part[TABLE_3_2_ROWS[4]].controller.L, whole[TABLE_3_2_ROWS[4]].controller.L
    )
    with pytest.raises(ValueError, match="^rows: expected"):
        table_3_2_designs(2, [3.0, 0.0], 20, rows=[("state feedback", "LQR")])
    with pytest.raises(TypeError, match="^rows: expected a sequence"):
        table_3_2_designs(2, [3.0, 0.0], 20, rows=None)


# --- Alg. 3.1 with measurement noise J (issue 24) --------------------------------------------


def _noisy_system(seed=5):
    rng = np.random.default_rng(seed)
    base = random_mjls(rng, M=2, nx=3, nu=1, ny=2)
    return base.replace(J=0.8 * rng.normal(size=(2, 2, 2)))


def _dense_static_cost(sys, L):
    """The average cost of u = L (C x + J v) from one dense linear solve, written out here:
    vec X_j = sum_i p_ij [(Acl_i (x) Acl_i) vec X_i + mu_i vec(H_i H_i^T + B_i L J_i J_i^T L^T
    B_i^T)]."""
    M, n = sys.M, sys.nx
    Acl = [sys.A[i] + sys.B[i] @ L @ sys.C[i] for i in range(M)]
    W = [
        sys.mu_inf[i]
        * (sys.H[i] @ sys.H[i].T + sys.B[i] @ L @ sys.J[i] @ sys.J[i].T @ L.T @ sys.B[i].T)
        for i in range(M)
    ]
    big = np.zeros((M * n * n, M * n * n))
    rhs = np.zeros(M * n * n)
    for j in range(M):
        for i in range(M):
            big[j * n * n : (j + 1) * n * n, i * n * n : (i + 1) * n * n] = sys.T[i, j] * np.kron(
                Acl[i], Acl[i]
            )
            rhs[j * n * n : (j + 1) * n * n] += sys.T[i, j] * W[i].ravel()
    X = np.linalg.solve(np.eye(M * n * n) - big, rhs).reshape(M, n, n)
    return sum(
        np.trace((sys.Q[i] + sys.C[i].T @ L.T @ sys.R[i] @ L @ sys.C[i]) @ X[i])
        + sys.mu_inf[i] * np.trace(sys.R[i] @ L @ sys.J[i] @ sys.J[i].T @ L.T)
        for i in range(M)
    )


@pytest.mark.parametrize("moments", ["step", "exact"])
def test_alg31_includes_the_measurement_noise(moments):
    """The cost Alg. 3.1 reports for a system with J != 0 is the true one (dense), and its gain is
    stationary for it: the finite-difference gradient of the true cost vanishes there."""
    sys = _noisy_system()
    res = static_output_feedback(sys, moments=moments)
    assert res.converged and res.stabilizing
    assert res.cost == pytest.approx(_dense_static_cost(sys, res.L), rel=1e-9)
    h = 1e-5
    for index in np.ndindex(res.L.shape):
        step = np.zeros_like(res.L)
        step[index] = h
        slope = (_dense_static_cost(sys, res.L + step) - _dense_static_cost(sys, res.L - step)) / (
            2 * h
        )
        # measured 9e-10; the gain ignoring J: 1.1
        assert abs(slope) < 1e-7 * res.cost
    # the gain that ignores J
    ignored = static_output_feedback(sys.replace(J=None), moments=moments)
    assert _dense_static_cost(sys, ignored.L) > res.cost * (1 + 1e-2)  # 1.645 against 1.596


def test_alg31_cost_with_measurement_noise_agrees_with_monte_carlo():
    sys = _noisy_system()
    res = static_output_feedback(sys)
    horizon, runs = 400, 4000
    mc = simulate(sys, StaticGain(res.L), np.zeros(sys.nx), horizon, runs, np.random.default_rng(2))
    # the average over a long horizon from x0 = 0: the transient costs a bias of O(1 / horizon)
    estimate = mc.average_cost.mean()
    error = mc.average_cost.std(ddof=1) / np.sqrt(runs)
    assert abs(estimate - res.cost) < 4 * error + 0.02 * res.cost
    # J matters here
    assert abs(estimate - static_output_feedback(sys.replace(J=None)).cost) > 4 * error


def test_alg31_without_measurement_noise_is_unchanged():
    sys = sec354_system(1)
    res = static_output_feedback(sys)
    assert res.cost == pytest.approx(0.5672987307882352, rel=1e-10)  # main's value before J
    zero = static_output_feedback(sys.replace(J=np.zeros((1, 1))))
    assert zero.L == pytest.approx(res.L, rel=1e-12) and zero.cost == pytest.approx(
        res.cost, rel=1e-12
    )
