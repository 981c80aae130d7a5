"""Checks of Sec. 3.6 (dynamic output feedback, Alg. 3.2): the augmented cost (Prop. 3.20), second
moments (Prop. 3.23), average cost (Prop. 3.24), Hamiltonian (Prop. 3.25), the bound (Prop. 3.26)
and the optimality of Alg. 3.2's solution (Thm. 3.27).

Prop. 3.25's Lagrangian is built densely and on its own: the augmented closed loop
[[A_i, B_i L], [K C_i, F]] with noise blockdiag(H_i, K J_i) is assembled here, not taken from
``asoc.mjls.dynamic.augmented_closed_loop``, and the constraint of (3.42) is multiplied by P~ as
a vector product.
"""

import numpy as np
from scipy.linalg import block_diag

from asoc.linalg import sym, transpose
from asoc.mjls import (
    average_cost_and_gradient,
    dynamic_output_feedback,
    ms_spectral_radius,
    predecessor_sum,
    steady_state_cost,
    successor_average,
)
from asoc.mjls.closed_loops import augmented_closed_loop, noise_covariances
from asoc.mjls.finite_horizon import augmented_initial_moment
from asoc.mjls.moment_operator import ms_operator

from .instances import (
    Z_SCORE,
    ModeChain,
    ModeOperator,
    RunModes,
    draw_system,
    gaussian_mixture,
    initial_modes,
    min_eig,
    norm_scale,
    outcome,
    random_spd_stack,
    rescaled,
    sample_mixture,
    stationary_average,
    trace_sum,
    verdict,
    z_scores,
)
from .mean_square import moment_map_matrix

__all__ = ["check_3_20", "loop_step", "quadratic_form", "check_3_23", "check_3_24", "check_3_25",
           "check_3_26", "check_3_27"]


def check_3_20(rng, mutant=False):
    """Prop. 3.20: x~^T Q~ x~ = x^T Q x + u^T R u, u = L x^. Mutant: Q~ = diag(Q, R) (L dropped)."""
    sys = draw_system(rng)
    L = rng.standard_normal((sys.nu, sys.nx))
    i = rng.integers(sys.M)
    x, xhat = rng.standard_normal(sys.nx), rng.standard_normal(sys.nx)
    _, _, Qt = augmented_closed_loop(sys, np.zeros((sys.nx, sys.nx)), np.zeros((sys.nx, sys.ny)),
                                     np.eye(sys.nu, sys.nx) if mutant else L)
    xt = np.concatenate([x, xhat])
    u = L @ xhat
    direct = x @ sys.Q[i] @ x + u @ sys.R[i] @ u
    rel = abs(xt @ Qt[i] @ xt - direct) / max(direct, 1e-300)
    return outcome(verdict(rel < 1e-12), sys, relative_difference=rel)


def _dynamic_gains(rng, sys, scale=0.5):
    """Random controller matrices F (nx, nx), K (nx, ny), L (nu, nx), entries N(0, scale^2)."""
    F = scale * rng.standard_normal((sys.nx, sys.nx))
    K = scale * rng.standard_normal((sys.nx, sys.ny))
    L = scale * rng.standard_normal((sys.nu, sys.nx))
    return F, K, L


def _stabilised_dynamic(rng, sys, low=0.2, high=0.85):
    """Random (F, K, L) and the system rescaled (with F, K) to an augmented rho in [low, high]."""
    F, K, L = _dynamic_gains(rng, sys)
    At = augmented_closed_loop(sys, F, K, L)[0]
    target = rng.uniform(low, high)
    c = float(np.sqrt(target / ms_spectral_radius(At, sys.T)))
    return rescaled(sys, c), c * F, c * K, L, target


def loop_step(sys):
    """One step of plant (3.36) and controller (3.37) for all runs:
    ``step((x, x^), modes, r, F, K, L)`` with x, x^ of shape (runs, nx) and ``modes`` the runs'
    RunModes; the new (x, x^).
    """
    J = np.zeros((sys.M, sys.ny, 1)) if sys.J is None else sys.J
    C, meas, A, B, H = (ModeOperator(S) for S in (sys.C, J, sys.A, sys.B, sys.H))

    def step(state, modes, r, F, K, L):
        x, xh = state
        y = C(x, modes) + meas(r.standard_normal((len(x), J.shape[2])), modes)
        x_new = A(x, modes) + B(xh @ L.T, modes) + H(r.standard_normal((len(x), sys.nw)), modes)
        return x_new, xh @ F.T + y @ K.T

    return step


def quadratic_form(S, theta, x):
    """x_r^T S_{theta_r} x_r for every run r."""
    return np.einsum("ra,rab,rb->r", x, S[theta], x)


def check_3_23(rng, mutant=False):
    """Prop. 3.23: the printed block recursion of X~ against Monte Carlo, k = 1..3.
    Mutant: the recursion without the process noise mu_k^i H_i H_i^T.
    """
    sys = draw_system(rng)
    F, K, L = _dynamic_gains(rng, sys)
    c = norm_scale(rng, augmented_closed_loop(sys, F, K, L)[0])
    sys, F, K = rescaled(sys, c), c * F, c * K
    HHt, JJt = noise_covariances(sys)
    if mutant:
        HHt = 0 * HHt
    mu0, mean0, cov0 = gaussian_mixture(rng, sys)
    xhat0 = rng.standard_normal(sys.nx)
    Xt = augmented_initial_moment(mean0, cov0, mu0, xhat0)
    n, A, B, C, m = sys.nx, sys.A, sys.B, sys.C, mu0
    n_runs = 10000
    x, theta = sample_mixture(rng, mu0, mean0, cov0, n_runs)
    state = x, np.broadcast_to(xhat0, x.shape).copy()
    step, chain = loop_step(sys), ModeChain(sys.T)
    worst = 0.0
    BL, KC, T_ = B @ L, K @ C, transpose
    for _ in range(3):
        X1, X12, X2 = Xt[:, :n, :n], Xt[:, :n, n:], Xt[:, n:, n:]
        mm = m[:, None, None]
        new1 = predecessor_sum(sys.T, A @ X1 @ T_(A) + A @ X12 @ T_(BL) + BL @ T_(X12) @ T_(A)
                               + BL @ X2 @ T_(BL) + mm * HHt)
        new12 = predecessor_sum(sys.T, A @ X1 @ T_(KC) + A @ X12 @ F.T + BL @ T_(X12) @ T_(KC)
                                + BL @ X2 @ F.T)
        new2 = predecessor_sum(sys.T, KC @ X1 @ T_(KC) + KC @ X12 @ F.T + F @ T_(X12) @ T_(KC)
                               + F @ X2 @ F.T + mm * (K @ JJt @ K.T))
        Xt = np.block([[new1, new12], [T_(new12), new2]])
        m = m @ sys.T
        state, theta = step(state, RunModes(theta, sys.M), rng, F, K, L), chain.next(rng, theta)
        worst = max(worst, z_scores(np.hstack(state), theta, Xt, m))
    return outcome(verdict(worst < Z_SCORE), sys, max_z=worst, runs=n_runs)


def check_3_24(rng, mutant=False):
    """Prop. 3.24: sum_i tr[Q~_i X~_inf^i] against the Monte Carlo stationary average cost of the
    loop. Mutant: Q~ without the input's block L^T R_i L.
    """
    sys = draw_system(rng)
    sys, F, K, L, target = _stabilised_dynamic(rng, sys)
    exact, Xt, rho = steady_state_cost(sys, F, K, L)
    if mutant:
        exact = trace_sum(sys.Q, Xt[:, :sys.nx, :sys.nx])
    n_runs = 1000
    cost = lambda state, modes: (quadratic_form(sys.Q, modes.theta, state[0])
                                 + quadratic_form(sys.R, modes.theta, state[1] @ L.T))
    loop = loop_step(sys)
    step = lambda state, modes, r: loop(state, modes, r, F, K, L)
    start = np.zeros((n_runs, sys.nx)), np.zeros((n_runs, sys.nx))
    modes0 = initial_modes(rng, sys.mu_inf, n_runs)
    mc, se, burn = stationary_average(rng, step, cost, start, modes0, sys.T, rho, n_runs)
    z = abs(mc - exact) / np.hypot(se, 1e-3 * exact)
    return outcome(verdict(z < Z_SCORE), sys, cost_3_42=exact, monte_carlo=mc, standard_error=se,
                   z=z, rho=rho,
                   burn_in=burn)


def _augmented_dense(sys, F, K, L):
    """(A~_i, H~_i, Q~_i) of (3.39) assembled block by block: [[A_i, B_i L], [K C_i, F]],
    blockdiag(H_i, K J_i) and blockdiag(Q_i, L^T R_i L).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> At, Ht, Qt = _augmented_dense(sys, np.eye(2), np.ones((2, 1)), np.ones((1, 2)))
    >>> At.shape, Ht.shape, Qt.shape
    ((2, 4, 4), (2, 4, 2), (2, 4, 4))
    """
    J = np.zeros((sys.M, sys.ny, 0)) if sys.J is None else sys.J
    At = np.stack([np.block([[sys.A[i], sys.B[i] @ L], [K @ sys.C[i], F]]) for i in range(sys.M)])
    Ht = np.stack([block_diag(sys.H[i], K @ J[i]) for i in range(sys.M)])
    Qt = np.stack([block_diag(sys.Q[i], L.T @ sys.R[i] @ L) for i in range(sys.M)])
    return At, Ht, Qt


def check_3_25(rng, mutant=False):
    """Prop. 3.25: the stated Hamiltonian of (3.42) (with E_i(P~)) against its Lagrangian built
    densely. Mutant: the stated form without the noise term mu_i H~_i H~_i^T.
    """
    sys = draw_system(rng)
    F, K, L = _dynamic_gains(rng, sys)
    At, HHt_cl, Qt = augmented_closed_loop(sys, F, K, L)
    n2 = 2 * sys.nx
    X, P = random_spd_stack(rng, sys.M, n2), random_spd_stack(rng, sys.M, n2)
    mu = sys.mu_inf
    inner = At @ X @ transpose(At) + (0 if mutant else mu[:, None, None] * HHt_cl)
    stated = trace_sum(Qt, X) + trace_sum(successor_average(sys.T, P), inner) - trace_sum(P, X)
    Ad, Hd, Qd = _augmented_dense(sys, F, K, L)
    noise = np.einsum("ij,iab->jab", sys.T, mu[:, None, None] * (Hd @ transpose(Hd)))
    constraint = moment_map_matrix(Ad, sys.T) @ X.ravel() + noise.ravel() - X.ravel()
    dense = trace_sum(Qd, X) + float(P.ravel() @ constraint)
    scale = (abs(trace_sum(Qt, X)) + trace_sum(P, X)
             + abs(trace_sum(successor_average(sys.T, P), inner)))
    rel = abs(stated - dense) / scale
    return outcome(verdict(rel < 1e-12), sys, stated=stated, lagrangian=dense,
                   relative_difference=rel)


def check_3_26(rng, mutant=False):
    """Prop. 3.26 as printed: X~ <= [[Xbar + Xu, Xu], [Xu, Xu]] and P~ <= [[Pbar + Pu, -Pu], [-Pu,
    Pu]] with Xbar = X1 - X12 - X12^T + X2, Xu = X2 (3.43) of the exact X~_inf, P~_inf of a
    stabilising (F, K, L). Mutant: the inequalities flipped (the bounds read as lower bounds).
    """
    sys = draw_system(rng)
    sys, F, K, L, _ = _stabilised_dynamic(rng, sys)
    _, Xt, rho = steady_state_cost(sys, F, K, L)
    At, _, Qt = augmented_closed_loop(sys, F, K, L)
    Pt = np.linalg.solve(np.eye(Qt.size) - ms_operator(At, sys.T, check=False).T, Qt.ravel())
    Pt = sym(Pt.reshape(Qt.shape))
    n = sys.nx
    sign = -1.0 if mutant else 1.0

    def gaps(Z, off):
        Z1, Z12, Z2 = Z[:, :n, :n], Z[:, :n, n:], Z[:, n:, n:]
        bar = Z1 - Z12 - transpose(Z12) + Z2
        bound = np.block([[bar + Z2, off * Z2], [off * Z2, Z2]])
        return min_eig(sign * (bound - Z)) / max(np.abs(Z).max(), 1e-300)

    gap_X, gap_P = gaps(Xt, 1.0), gaps(Pt, -1.0)
    return outcome(verdict(min(gap_X, gap_P) > -1e-9), sys, min_eig_bound_minus_X=gap_X,
                   min_eig_bound_minus_P=gap_P, rho=rho)


def check_3_27(rng, mutant=False):
    """Thm. 3.27: a stabilising solution of (3.45)-(3.49) (Alg. 3.2 converged) is the optimal
    (3.37): the gradient of the exact cost (3.42) vanishes there. Mutant: the solution's L scaled by
    1.2.
    """
    sys = draw_system(rng, max_states=2, max_modes=2)
    run = dynamic_output_feedback(sys, max_iter=3000, warn=False)
    numbers = dict(alg_converged=run.converged, alg_stabilizing=run.stabilizing,
                   alg_iterations=run.iterations)
    if not (run.converged and run.stabilizing):
        return outcome("not_applicable", sys, **numbers)
    F, K, L = run.F, run.K, 1.2 * run.L if mutant else run.L
    cost, grad = average_cost_and_gradient(sys, F, K, L)
    if not np.isfinite(cost):
        return outcome("fails", sys, cost=cost, **numbers)
    theta = np.concatenate([F.ravel(), K.ravel(), L.ravel()])
    g = np.concatenate([np.ravel(x) for x in grad])
    stationarity = float(np.linalg.norm(g) * max(np.linalg.norm(theta), 1e-12) / cost)
    step = 1e-3 * max(np.linalg.norm(theta), 1e-6) / max(np.linalg.norm(g), 1e-300)
    nF, nK = F.size, K.size
    moved = theta - step * g
    lower, _ = average_cost_and_gradient(sys, moved[:nF].reshape(F.shape),
                                         moved[nF:nF + nK].reshape(K.shape),
                                         moved[nF + nK:].reshape(L.shape))
    improvement = (cost - lower) / cost
    not_optimal = stationarity > 1e-4 and improvement > 1e-7
    return outcome(verdict(not not_optimal), sys, cost=cost, relative_gradient=stationarity,
                   improvement_by_gradient_step=improvement, **numbers)
