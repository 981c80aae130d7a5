"""Checks of Sec. 3.5.3: the second moments (Prop. 3.14), the cost (Prop. 3.15), the Hamiltonian
(Prop. 3.16), the optimality conditions (Thm. 3.17, Prop. 3.18) and Alg. 3.1 (Thm. 3.19).

Prop. 3.15 is checked as printed, with the weight Q_i + L^T R_i L; the reading with
Q_i + C_i^T L^T R_i L C_i (the cost of u = L C x) is checked beside it and recorded as the
corrected statement. Prop. 3.16's Lagrangian is built densely, on its own: the closed loop
A_i + B_i L C_i and the matrix of the moment map (:func:`moment_map_matrix`) are assembled
here, and the constraint of (3.30) is multiplied by P as a vector product.
"""

import numpy as np
import scipy.optimize

from asoc.linalg import sym, transpose
from asoc.mjls import (
    closed_loop,
    gain_from_moments,
    h2_cost,
    predecessor_sum,
    second_moments,
    static_output_feedback,
    steady_state_second_moment,
    successor_average,
)
from asoc.mjls.lyapunov import radii_and_moments, radius_and_moments
from asoc.mjls.moment_operator import ms_operator

from .instances import (
    Z_SCORE,
    ModeChain,
    ModeOperator,
    RunModes,
    best_scalar_gain,
    draw_system,
    gaussian_mixture,
    norm_scale,
    outcome,
    random_spd_stack,
    rescaled,
    sample_mixture,
    scalar_gain_radii,
    stabilised,
    trace_sum,
    verdict,
    z_scores,
)
from .mean_square import moment_map_matrix

__all__ = ["check_3_14", "check_3_15", "summarise_3_15", "check_3_16", "check_3_17", "check_3_18",
           "check_3_19", "decide_3_19", "summarise_3_19"]


def check_3_14(rng, mutant=False):
    """Prop. 3.14: X_k^i of (3.29) against Monte Carlo E{x_k x_k^T 1(theta_k = i)}, k = 1..3.
    Mutant: the recursion without the noise term mu_k^i H_i H_i^T.
    """
    sys = draw_system(rng)
    L = 0.5 * rng.standard_normal((sys.nu, sys.ny))
    sys = rescaled(sys, norm_scale(rng, closed_loop(sys, L)))
    Acl = closed_loop(sys, L)
    HHt = sys.H @ transpose(sys.H)
    mu0, mean0, cov0 = gaussian_mixture(rng, sys)
    X0 = mu0[:, None, None] * (cov0 + np.einsum("ia,ib->iab", mean0, mean0))
    X, mus = second_moments(Acl, 0 * HHt if mutant else HHt, sys.T, X0, mu0, 3)
    n_runs = 10000
    x, theta = sample_mixture(rng, mu0, mean0, cov0, n_runs)
    worst = 0.0
    chain, closed, noise = ModeChain(sys.T), ModeOperator(Acl), ModeOperator(sys.H)
    for k in range(1, 4):
        modes = RunModes(theta, sys.M)
        x = closed(x, modes) + noise(rng.standard_normal((n_runs, sys.nw)), modes)
        theta = chain.next(rng, theta)
        worst = max(worst, z_scores(x, theta, X[k], mus[k]))
    return outcome(verdict(worst < Z_SCORE), sys, max_z=worst, runs=n_runs)


def check_3_15(rng, mutant=False):
    """Prop. 3.15 as printed: the average cost (3.11) from a random x_0 and theta_0 ~ mu_inf (the
    mean stage cost of the moment recursion over steps h..2h-1, rho^h <= 1e-13) equals (3.30)'s
    objective sum_i tr[(Q_i + L^T R_i L) X_inf^i] (defined when n_y = n_x); the corrected reading
    with C_i^T L^T R_i L C_i is checked beside it (``corrected_holds``). Mutant: the corrected
    reading with X_inf solved without the noise term (the instance's verdict is then the corrected
    reading's).
    """
    sys = draw_system(rng)
    L = 0.5 * rng.standard_normal((sys.nu, sys.ny))
    sys, target = stabilised(rng, sys, lambda s: closed_loop(s, L), 0.2, 0.95)
    Acl = closed_loop(sys, L)
    HHt = sys.H @ transpose(sys.H)
    X_inf = steady_state_second_moment(Acl, 0 * HHt if mutant else HHt, sys.T, sys.mu_inf)
    corrected = h2_cost(sys, L, X_inf)
    x0 = 3 * rng.standard_normal(sys.nx)
    # theta_0 stationary: the moments approach X_inf as rho^k
    mu0 = sys.mu_inf
    half = int(np.ceil(max(100.0, np.log(1e-13) / np.log(target))))
    X, _ = second_moments(Acl, HHt, sys.T, mu0[:, None, None] * np.outer(x0, x0), mu0, 2 * half)
    LC = L @ sys.C
    # E{x^T Q x + u^T R u}, u = L C x
    per_step = np.einsum("iab,kiba->k", sys.Q + transpose(LC) @ sys.R @ LC, X)
    # the average cost (3.11), the transient below 1e-13 |x_0|^2
    tail = per_step[half:2 * half].mean()
    agrees = lambda objective: abs(tail - objective) <= 1e-8 * abs(objective)
    c_is_identity = sys.ny == sys.nx and bool(np.allclose(sys.C, np.eye(sys.nx)))
    numbers = dict(objective_corrected=corrected, corrected_holds=agrees(corrected),
                   average_cost=tail, rho=target,
                   averaging_window=half, c_is_identity=c_is_identity)
    if mutant:
        return outcome(verdict(agrees(corrected)), sys, **numbers)
    if sys.ny != sys.nx:
        return outcome("not_applicable", sys, reason="L^T R_i L is n_y x n_y, Q_i is n_x x n_x",
                       **numbers)
    printed = trace_sum(sys.Q + transpose(L) @ sys.R @ L, X_inf)
    return outcome(verdict(agrees(printed)), sys, objective_printed=printed, **numbers)


def summarise_3_15(outcomes):
    """The corrected reading of Prop. 3.15 (weight Q_i + C_i^T L^T R_i L C_i) on every instance."""
    holds = sum(bool(o.numbers["corrected_holds"]) for o in outcomes)
    return {"diagnosis": (r"A typo that starts in (3.11), not in (3.30): with $\mathbf "
                          r"u_k=\mathbf L\mathbf y_k=\mathbf L\mathbf C_i\mathbf x_k$ (3.7) the "
                          r"stage cost $\mathbf x_k^\top\mathbf Q_i\mathbf x_k+\mathbf "
                          r"u_k^\top\mathbf R_i\mathbf u_k$ is $\mathbf x_k^\top(\mathbf "
                          r"Q_i+\mathbf C_i^\top\mathbf L^\top\mathbf R_i\mathbf L\mathbf "
                          r"C_i)\mathbf x_k$, but (3.11) already prints the weight $\mathbf "
                          r"Q_i+\mathbf L^\top\mathbf R_i\mathbf L$, which drops $\mathbf C_i$ "
                          r"(it is even undefined unless $n_y=n_x$), and (3.30) copies it; the "
                          r"substitution of $\mathbf u_k$ holds only for $\mathbf C_i=\mathbf I$. "
                          r"Prop. 3.16 and Thm. 3.17 use the weight with $\mathbf C_i$."),
            "corrected": {"statement": "Problem (3.11) equals (3.30) with the weight "
                                       "$\\mathbf Q_i+\\mathbf C_i^\\top\\mathbf L^\\top\\mathbf "
                                       "R_i\\mathbf L\\mathbf C_i$",
                          "holds": holds, "fails": len(outcomes) - holds,
                          "instances": len(outcomes)}}


def _lagrangian_dense(A, B, C, L, Q, R, H, T, mu, X, P):
    """The Lagrangian of (3.30): sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_i] + <P, map(X) + noise -
    X>, with the closed loop and the moment map's matrix assembled here (``L`` one gain or one per
    mode).

    Examples
    --------
    >>> one = np.ones((1, 1, 1))
    >>> _lagrangian_dense(0.5 * one, one, one, np.zeros((1, 1)), one, one, one, np.eye(1),
    ...     np.ones(1), 2 * one, one)
    1.5
    """
    Acl = A + B @ L @ C
    LC = L @ C
    weight = Q + transpose(LC) @ R @ LC
    noise = np.einsum("ij,iab->jab", T, mu[:, None, None] * (H @ transpose(H)))
    constraint = moment_map_matrix(Acl, T) @ X.ravel() + noise.ravel() - X.ravel()
    return float(np.sum(weight * transpose(X)) + P.ravel() @ constraint)


def check_3_16(rng, mutant=False):
    """Prop. 3.16: the stated Hamiltonian (with E_i(P)) against the Lagrangian of (3.30) built
    densely. Mutant: the stated form without the noise term mu_i H_i H_i^T.
    """
    sys = draw_system(rng)
    L = rng.standard_normal((sys.nu, sys.ny))
    X, P = random_spd_stack(rng, sys.M, sys.nx), random_spd_stack(rng, sys.M, sys.nx)
    mu = sys.mu_inf
    Acl = closed_loop(sys, L)
    inner = Acl @ X @ transpose(Acl) + (0 if mutant else mu[:, None,
                                                            None] * (sys.H @ transpose(sys.H)))
    LC = L @ sys.C
    weight = sys.Q + transpose(LC) @ sys.R @ LC
    stated = trace_sum(weight, X) - trace_sum(P, X) + trace_sum(successor_average(sys.T, P), inner)
    dense = _lagrangian_dense(sys.A, sys.B, sys.C, L, sys.Q, sys.R, sys.H, sys.T, mu, X, P)
    scale = (trace_sum(weight, X) + trace_sum(P, X)
             + abs(trace_sum(successor_average(sys.T, P), inner)))
    rel = abs(stated - dense) / scale
    return outcome(verdict(rel < 1e-12), sys, stated=stated, lagrangian=dense,
                   relative_difference=rel)


def _gain_residual(sys, L, X, P, weight_R=True):
    """(3.31): sum_i (R_i + B_i^T E_i(P) B_i) L C_i X_i C_i^T + B_i^T E_i(P) A_i X_i C_i^T, and its
    scale (``weight_R=False``: the residual without R_i, a mutant).
    """
    EP = successor_average(sys.T, P)
    weight = (sys.R if weight_R else 0) + transpose(sys.B) @ EP @ sys.B
    first = weight @ L @ sys.C @ X @ transpose(sys.C)
    second = transpose(sys.B) @ EP @ sys.A @ X @ transpose(sys.C)
    scale = np.linalg.norm(first.sum(0)) + np.linalg.norm(second.sum(0))
    return first.sum(axis=0) + second.sum(axis=0), scale


def _costate(sys, L):
    """P_inf of (3.33): P_i = Acl_i^T E_i(P) Acl_i + Q_i + C_i^T L^T R_i L C_i."""
    Acl = closed_loop(sys, L)
    LC = L @ sys.C
    rhs = (sys.Q + transpose(LC) @ sys.R @ LC).ravel()
    P = np.linalg.solve(np.eye(rhs.size) - ms_operator(Acl, sys.T, check=False).T, rhs)
    return sym(P.reshape(sys.Q.shape))


def check_3_17(rng, mutant=False):
    """Thm. 3.17: the minimiser of the cost (found by a grid and a scalar search over L) satisfies
    (3.31). Mutant: the residual of (3.31) without R_i.
    """
    sys = draw_system(rng, siso=True)
    s = np.linspace(-np.pi / 2, np.pi / 2, 403)[1:-1]
    radii = scalar_gain_radii(sys, np.tan(s))
    if not radii.min() < 1:
        return outcome("not_applicable", sys, min_rho_over_L=float(radii.min()))
    HHt = sys.H @ transpose(sys.H)
    noise = predecessor_sum(sys.T, sys.mu_inf[:, None, None] * HHt)

    def cost(t):
        """The H2 cost of L = tan(t) (inf when not stabilising), on the system validated once: the
        library's check=False paths of ms_spectral_radius with steady_state_second_moment, and of
        h2_cost.
        """
        L = np.array([[np.tan(t)]])
        _, X = radius_and_moments(closed_loop(sys, L, check=False), sys.T, noise, check=False)
        return np.inf if X is None else h2_cost(sys, L, X, check=False)

    # cost(t) at the grid points with rho < 1, at once
    costs = np.full(len(s), np.inf)
    grid = np.flatnonzero(radii < 1)
    gains = np.tan(s[grid])
    # closed_loop of each
    loops = sys.A + (sys.B @ gains[:, None, None, None]) @ sys.C
    for index, gain, X in zip(grid, gains, radii_and_moments(loops, sys.T, noise, check=False)[1]):
        if X is not None:
            costs[index] = h2_cost(sys, np.array([[gain]]), X, check=False)
    best = int(np.argmin(costs))
    bracket = (s[max(best - 1, 0)], s[min(best + 1, len(s) - 1)])
    res = scipy.optimize.minimize_scalar(cost, bounds=bracket, method="bounded",
                                         options={"xatol": 1e-12})
    t = res.x if res.fun <= costs[best] else s[best]
    L = np.array([[np.tan(t)]])
    X = steady_state_second_moment(closed_loop(sys, L), HHt, sys.T, sys.mu_inf)
    residual, scale = _gain_residual(sys, L, X, _costate(sys, L), weight_R=not mutant)
    rel = float(np.linalg.norm(residual) / scale)
    return outcome(verdict(rel < 1e-5), sys, optimal_L=float(L[0, 0]), cost=cost(t),
                   relative_residual_3_31=rel)


def check_3_18(rng, mutant=False):
    """Prop. 3.18: the printed vec formula (column-major vec, C X C^T (x) (R + B^T E(P) B)) solves
    (3.31). Mutant: the formula with 2 R_i in place of R_i (a factor changed).
    """
    sys = draw_system(rng)
    X, P = random_spd_stack(rng, sys.M, sys.nx), random_spd_stack(rng, sys.M, sys.nx)
    EP = successor_average(sys.T, P)
    R = 2 * sys.R if mutant else sys.R
    lhs = sum(np.kron(sys.C[i] @ X[i] @ sys.C[i].T,
                      R[i] + sys.B[i].T @ EP[i] @ sys.B[i]) for i in range(sys.M))
    rhs = sum(sys.B[i].T @ EP[i] @ sys.A[i] @ X[i] @ sys.C[i].T for i in range(sys.M))
    L = -np.linalg.solve(lhs, rhs.ravel(order="F")).reshape((sys.nu, sys.ny), order="F")
    residual, scale = _gain_residual(sys, L, X, P)
    rel = float(np.linalg.norm(residual) / scale)
    library = gain_from_moments(sys, X, P)
    tol = 1e-13 * np.linalg.cond(lhs)
    return outcome(verdict(rel < max(tol, 1e-10)), sys, relative_residual=rel,
                   library_difference=float(np.abs(library - L).max()),
                   condition=float(np.linalg.cond(lhs)))


def check_3_19(rng, mutant=False):
    """Thm. 3.19: SOF-stabilisable (grid over scalar L) -> Alg. 3.1 converges to a stabilising,
    unique solution (same limit from X = P = 1e-4 I and from X = P = I), on the thesis's model
    (3.7), which has no measurement noise (J = None; Alg. 3.1 with J is the library's
    generalisation). Mutant: Alg. 3.1 stopped after 3 iterations.
    """
    sys = draw_system(rng, siso=True, families=("thesis_like", "unstable", "stable",
                                                "sparse_T")).replace(J=None)
    return decide_3_19(sys, max_iter=3 if mutant else 20000)


def decide_3_19(sys, max_iter=20000):
    """Thm. 3.19 on one SISO system: premise by the gain grid, conclusion by Alg. 3.1 (2 starts)."""
    L_best, rho_best = best_scalar_gain(sys)
    if not rho_best < 1:
        return outcome("not_applicable", sys, min_rho_over_L=rho_best, best_L=L_best)
    run = static_output_feedback(sys, max_iter=max_iter, warn=False, moments="step")
    numbers = dict(min_rho_over_L=rho_best, best_L=L_best, margin=1 - rho_best,
                   alg_L=float(run.L[0, 0]),
                   alg_rho=run.rho, alg_converged=run.converged, alg_iterations=run.iterations)
    if not (run.converged and run.stabilizing):
        return outcome("fails", sys, **numbers)
    other = static_output_feedback(sys, init=1.0, max_iter=max_iter, warn=False, moments="step")
    same = other.converged and abs(other.L[0, 0] - run.L[0, 0]) <= 1e-6 * (1 + abs(run.L[0, 0]))
    return outcome(verdict(same), sys, alg_L_from_identity=float(other.L[0, 0]), **numbers)


def summarise_3_19(outcomes):
    """Thm. 3.19: how the failures fail (no convergence; a non-stabilising limit; another limit from
    I), and how many have one mode (plain linear systems).
    """
    fails = [o.numbers for o in outcomes if o.verdict == "fails"]
    return {"not_converged": sum(not n["alg_converged"] for n in fails),
            "converged_not_stabilising": sum(n["alg_converged"] and not n["alg_rho"] < 1
                                             for n in fails),
            "other_limit_from_identity": sum(n["alg_converged"] and n["alg_rho"] < 1
                                             for n in fails),
            "one_mode": sum(n["n_modes"] == 1 for n in fails),
            "smallest_margin": min((1 - n["min_rho_over_L"] for n in fails), default=float("nan"))}
