"""Checks of the numbered statements of Chapter 3 (Thm. 3.1 to Thm. 3.33).

Every numbered item of Chapter 3 that is not a definition (3.3, 3.4, 3.13, 3.22) or a
problem statement (3.6, 3.21) has one ``Statement`` here, keyed ``statement_3_<n>``.
Each check draws one instance from its ``rng`` and decides it:

* an identity is compared with an independent computation (Monte Carlo with a tolerance of
  ``Z_SCORE`` standard errors, a numerical minimisation, an explicit expansion);
* an implication decides its premise independently (static output-feedback
  stabilisability by a search over the gain, ``instances.best_gain``) and then tests the
  conclusion; ``not_applicable`` when the premise is false for the instance.

The algorithms under test come from ``asoc.mjls``; this module only draws and compares.
"""

import itertools

import numpy as np
import scipy.optimize

from asoc.mjls import (average_cost_and_gradient, closed_loop, dynamic_output_feedback, finite_horizon_cost,
                       finite_horizon_dynamic_output_feedback, gain_from_moments, h2_cost, ms_spectral_radius,
                       predecessor_sum, second_moments, static_output_feedback, static_output_lmi,
                       steady_state_cost, steady_state_second_moment, successor_average)
from asoc.mjls.bound import bound_costate_step, bound_moment_step
from asoc.mjls.operators import augmented_closed_loop, noise_covariances
from asoc.mjls.optimality import optimality_system
from asoc.mjls.finite_horizon import augmented_initial_moment, initial_bounds
from asoc.mjls.lmi import performance_output
from asoc.mjls.moments import h2_cost_unchecked
from asoc.mjls.operators import (closed_loop_unchecked, kronecker_matrix, radii_and_moments_unchecked,
                                 radius_and_moments_unchecked)

from .core import Outcome, Statement
from .instances import (Z_SCORE, ModeChain, ModeOperator, ModeQuadratic, RunModes, best_scalar_gain, draw_system,
                        indicator_moment_estimate, initial_modes, min_eig, moment_estimate, radius_to, random_spd,
                        random_spd_stack, rescaled, row_sums, size, scalar_gain_radii, stationary_average,
                        system_data)

_T = lambda S: np.swapaxes(S, -1, -2)
_tr = lambda A, B: float(np.sum(A * np.swapaxes(B, -1, -2)))     # sum of tr[A_i B_i] over a stack


def _verdict(ok):
    return "holds" if ok else "fails"


def _outcome(verdict, sys=None, **numbers):
    """An Outcome with plain numbers; a failing instance also carries its system as data."""
    clean = {k: (v.tolist() if isinstance(v, np.ndarray) else (float(v) if isinstance(v, np.floating) else
                 (bool(v) if isinstance(v, np.bool_) else v))) for k, v in numbers.items()}
    if sys is not None:
        clean.update(size(sys))
        if verdict == "fails":
            clean["system"] = system_data(sys)
    return Outcome(verdict, clean)


def _stabilised(rng, sys, gain_fn, low=0.2, high=0.85):
    """Rescale A_i, B_i so that the closed loop of ``gain_fn(sys)`` has rho uniform in [low, high]."""
    target = rng.uniform(low, high)
    factor = radius_to(sys, gain_fn(sys), target)
    return rescaled(sys, factor), target


def _moment_growth(A, T, steps=600):
    """Growth rate of tr X_k under X_{k+1} = D_j(A_i X_i A_i^T) from X_0 = I (recursion (3.29),
    no noise), over the last half of ``steps``: the mean-square decay without eigenvalues."""
    M, n, _ = A.shape
    X = np.broadcast_to(np.eye(n) / M, (M, n, n)).copy()
    At = _T(A)
    scales = []
    for _ in range(steps):
        X = predecessor_sum(T, A @ X @ At)
        s = X.trace(axis1=1, axis2=2).sum()
        if not s > 0:
            return 0.0
        X = X / s
        scales.append(s)
    log_scales = list(itertools.accumulate(np.log(scales).tolist(), initial=0.0))
    return float(np.exp((log_scales[steps] - log_scales[steps // 2]) / (steps - steps // 2)))


# ------------------------------------------------------------------ Sec. 3.3

def check_3_1(rng):
    """Thm. 3.1: PD solutions Q of the coupled Lyapunov equations (either form) for PD S imply MSS."""
    sys = draw_system(rng)
    A, T, M, n = sys.A, sys.T, sys.M, sys.nx
    S = random_spd_stack(rng, M, n)
    op = kronecker_matrix(A, T)
    eye = np.eye(M * n * n)
    try:
        Q_first = np.linalg.solve(eye - op.T, S.ravel()).reshape(M, n, n)     # A_i^T E_i(Q) A_i - Q_i = -S_i
        Q_second = np.linalg.solve(eye - op, S.ravel()).reshape(M, n, n)      # D_j(A Q A^T) - Q_j = -S_j
    except np.linalg.LinAlgError:
        return _outcome("not_applicable", sys, reason="singular coupled Lyapunov operator")
    eig_first, eig_second = min_eig(Q_first), min_eig(Q_second)
    growth = _moment_growth(A, T)
    numbers = dict(min_eig_Q_first_form=eig_first, min_eig_Q_second_form=eig_second, moment_growth=growth)
    if eig_first <= 0 and eig_second <= 0:
        return _outcome("not_applicable", sys, **numbers)
    return _outcome(_verdict(growth < 1 + 1e-6), sys, **numbers)


def check_3_2(rng):
    """Cor. 3.2: rho(M) < 1 implies MSS, decided by the decay of the second moments (3.29)."""
    sys = draw_system(rng)
    rho = ms_spectral_radius(sys.A, sys.T)
    growth = _moment_growth(sys.A, sys.T)
    if not rho < 1:
        return _outcome("not_applicable", sys, rho=rho, moment_growth=growth)
    return _outcome(_verdict(growth < 1 + 1e-6), sys, rho=rho, moment_growth=growth)


# ------------------------------------------------------------------ Sec. 3.4

def check_3_5(rng):
    """Prop. 3.5 at step K-1: J*_{K-1} = x^T Psi x + Delta, against a numerical minimisation over u."""
    sys = draw_system(rng, max_states=2)
    A, B, Q, R, T, M = sys.A, sys.B, sys.Q, sys.R, sys.T, sys.M
    W = random_spd(rng, sys.nx, 0.1)                               # covariance of w_k (3.2)
    belief = rng.dirichlet(np.ones(M))                             # p(theta_{K-1} | I_{K-1})
    x = rng.standard_normal(sys.nx) * 2
    EQ = successor_average(T, Q)                                   # E{Q_{theta_K} | theta_{K-1} = i}

    def expected_cost(u):
        nxt = A @ x + B @ u
        return float(belief @ (np.einsum("a,iab,b->i", x, Q, x) + np.einsum("a,iab,b->i", u, R, u)
                               + np.einsum("ia,iab,ib->i", nxt, EQ, nxt) + np.einsum("iab,ba->i", EQ, W)))

    res = scipy.optimize.minimize(expected_cost, np.zeros(sys.nu), method="BFGS", options={"gtol": 1e-12})
    Ew = lambda S: np.einsum("i,i...->...", belief, S)
    psi = (Ew(Q + _T(A) @ EQ @ A)
           - Ew(_T(A) @ EQ @ B) @ np.linalg.solve(Ew(R + _T(B) @ EQ @ B), Ew(_T(B) @ EQ @ A)))
    delta = float(belief @ np.einsum("iab,ba->i", EQ, W))
    closed = float(x @ psi @ x + delta)
    rel = abs(closed - res.fun) / max(abs(res.fun), 1e-12)
    return _outcome(_verdict(rel < 1e-7 and delta > 0), sys, closed_form=closed, minimised=res.fun,
                    relative_difference=rel, delta=delta)


# ------------------------------------------------------------------ Sec. 3.5.2: H2 norm, LMIs

def _stationary_check(rng, mode_dependent):
    """Props. 3.7 / 3.10: sum_i tr[(D+ELC) X (D+ELC)^T] against the Monte Carlo stationary E{z^T z}."""
    sys = draw_system(rng)
    shape = (sys.M, sys.nu, sys.ny) if mode_dependent else (sys.nu, sys.ny)
    L = 0.5 * rng.standard_normal(shape)
    acl = lambda s: s.A + s.B @ L @ s.C
    sys, target = _stabilised(rng, sys, acl)
    Acl = acl(sys)
    HHt = sys.H @ _T(sys.H)
    X = steady_state_second_moment(Acl, HHt, sys.T, sys.mu_inf)
    D, E = performance_output(sys)
    DE = D + E @ L @ sys.C
    h2 = _tr(DE @ X, _T(DE))
    n_runs = 1000
    closed, noise, output = ModeOperator(Acl), ModeOperator(sys.H), ModeOperator(DE)

    def step(x, modes, r):
        w = r.standard_normal((len(x), sys.nw))
        return closed(x, modes) + noise(w, modes)

    cost = lambda x, modes: row_sums(output(x, modes) ** 2)
    mc, se, burn = stationary_average(rng, step, cost, np.zeros((n_runs, sys.nx)),
                                      initial_modes(rng, sys.mu_inf, n_runs), sys.T, target, n_runs)
    z = abs(mc - h2) / np.hypot(se, 1e-3 * h2)
    return _outcome(_verdict(z < Z_SCORE), sys, h2_formula=h2, monte_carlo=mc, standard_error=se,
                    z=z, rho=target, burn_in=burn)


def check_3_7(rng):
    return _stationary_check(rng, mode_dependent=False)


def check_3_10(rng):
    return _stationary_check(rng, mode_dependent=True)


def _lemma_bmi(rng, mode_dependent):
    """Lemmas 3.8 / 3.11: a point (L, G, Y) satisfying the BMI constraint has objective >= ||G||_2^2.

    Y is built from a slack S > 0 (Y_i = Acl_i D_i(Y) Acl_i^T + mu_i H_i H_i^T + S_i) and G
    is drawn around D(Y); the constraint is then checked numerically (the premise)."""
    sys = draw_system(rng)
    shape = (sys.M, sys.nu, sys.ny) if mode_dependent else (sys.nu, sys.ny)
    L = 0.5 * rng.standard_normal(shape)
    acl = lambda s: s.A + s.B @ L @ s.C
    sys, _ = _stabilised(rng, sys, acl, 0.2, 0.95)
    Acl, mu, M, n = acl(sys), sys.mu_inf, sys.M, sys.nx
    HHt = sys.H @ _T(sys.H)
    S = random_spd_stack(rng, M, n, scale=rng.uniform(0.01, 1.0))
    P = steady_state_second_moment(Acl, HHt + S / mu[:, None, None], sys.T, mu)     # P = D(Y)
    Y = Acl @ P @ _T(Acl) + mu[:, None, None] * HHt + S
    spread = np.exp(rng.normal(0, 0.3, M if mode_dependent else 1))
    G = P * spread[:, None, None] if mode_dependent else np.broadcast_to(P.mean(axis=0) * spread[0], P.shape)
    G = G + 0.05 * np.mean(np.abs(P)) * _sym_noise(rng, M if mode_dependent else 1, n)
    blocks = np.block([[Y - mu[:, None, None] * HHt, Acl @ G], [_T(Acl @ G), G + _T(G) - P]])
    margin = min_eig(blocks)
    D, E = performance_output(sys)
    DE = D + E @ L @ sys.C
    objective = _tr(DE @ P, _T(DE))
    h2 = _tr(DE @ steady_state_second_moment(Acl, HHt, sys.T, mu), _T(DE))
    numbers = dict(constraint_margin=margin, objective=objective, h2_norm_squared=h2)
    if not margin > 0:
        return _outcome("not_applicable", sys, **numbers)
    return _outcome(_verdict(objective >= h2 * (1 - 1e-9)), sys, **numbers)


def _sym_noise(rng, m, n):
    G = rng.standard_normal((m, n, n))
    return 0.5 * (G + _T(G))


def check_3_8(rng):
    return _lemma_bmi(rng, mode_dependent=False)


def check_3_11(rng):
    return _lemma_bmi(rng, mode_dependent=True)


def check_3_9(rng):
    """Thm. 3.9: feasible LMIs -> L = F M^{-1} stabilises; also records SOF stabilisability (search)."""
    return decide_3_9(draw_system(rng, siso=True, families=("thesis_like", "unstable", "stable")))


def decide_3_9(sys, mu=None):
    """Thm. 3.9 on one SISO system. ``mu``: the mode weights of the noise term mu_i H_i H_i^T in the
    LMIs (default the stationary distribution, as printed); another ``mu`` is imposed through the
    equivalent noise H_i sqrt(mu_i / mu_inf_i), since ``static_output_lmi`` uses mu_inf."""
    if mu is not None:
        sys = sys.replace(H=sys.H * np.sqrt(np.asarray(mu) / sys.mu_inf)[:, None, None])
    lmi = static_output_lmi(sys)
    L_best, rho_best = best_scalar_gain(sys)
    numbers = dict(lmi_feasible=lmi.feasible, lmi_status=lmi.status, sof_stabilisable=rho_best < 1,
                   min_rho_over_L=rho_best, best_L=L_best)
    if not lmi.feasible:
        return _outcome("not_applicable", sys, **numbers)
    rho = ms_spectral_radius(closed_loop(sys, lmi.L), sys.T)
    return _outcome(_verdict(rho < 1), sys, lmi_L=np.ravel(lmi.L), rho_of_lmi_gain=rho, **numbers)


def check_3_12(rng):
    """Thm. 3.12: feasible LMIs (mode observed) -> L_i = F_i M_i^{-1} stabilise the mode-observed loop."""
    sys = draw_system(rng, max_states=2)
    lmi = static_output_lmi(sys, mode_observed=True)
    if not lmi.feasible:
        return _outcome("not_applicable", sys, lmi_feasible=False, lmi_status=lmi.status)
    rho = ms_spectral_radius(sys.A + sys.B @ lmi.L @ sys.C, sys.T)
    return _outcome(_verdict(rho < 1), sys, lmi_feasible=True, rho_of_lmi_gains=rho)


def _lmi_summary(outcomes):
    """Conservatism of Thm. 3.9: the share of SOF-stabilisable instances whose LMIs are feasible."""
    stabilisable = [o for o in outcomes if o.numbers.get("sof_stabilisable")]
    certified = [o for o in stabilisable if o.numbers.get("lmi_feasible")]
    return {"sof_stabilisable": len(stabilisable), "certified_by_lmi": len(certified),
            "lmi_feasible": sum(bool(o.numbers.get("lmi_feasible")) for o in outcomes)}


# ------------------------------------------------------------------ Sec. 3.5.3: Alg. 3.1

def _gaussian_mixture(rng, sys):
    mu0 = rng.dirichlet(np.ones(sys.M))
    mean0 = rng.standard_normal((sys.M, sys.nx))
    cov0 = random_spd_stack(rng, sys.M, sys.nx, 0.2)
    return mu0, mean0, cov0


def _sample_mixture(rng, mu0, mean0, cov0, n_runs):
    theta = initial_modes(rng, mu0, n_runs)
    chol = ModeOperator(np.linalg.cholesky(cov0))
    x = mean0[theta] + chol(rng.standard_normal((n_runs, mean0.shape[1])), RunModes(theta, len(mu0)))
    return x, theta


def _z_scores(x, theta, exact, mu, min_hits=100):
    """Largest |Monte Carlo - exact| / standard error, the Monte Carlo of E{x x^T 1(theta = i)} over the
    runs (x, theta), over the entries of the modes with at least ``min_hits`` expected visits (rarer
    modes have too few samples for a normal standard error)."""
    mean, se = indicator_moment_estimate(x, theta, len(mu))
    seen = mu * len(x) >= min_hits
    if not seen.any():
        return 0.0
    scale = 1e-12 * (1 + np.abs(exact).max())
    return float(np.max(np.abs(mean - exact)[seen] / np.maximum(se, scale)[seen]))


def _norm_scale(rng, Acl):
    """Factor making max_i ||Acl_i||_2 uniform on [0.5, 1.5]. A Monte Carlo estimate of a moment is only
    trustworthy when no rare mode path carries it: with ||Acl_i|| = 3, a path staying in mode i multiplies
    x x^T by 9 per step, and a few samples decide the mean (the standard error then misleads)."""
    return float(rng.uniform(0.5, 1.5) / np.max(np.linalg.norm(Acl, ord=2, axis=(1, 2))))


def check_3_14(rng):
    """Prop. 3.14: X_k^i of (3.29) against Monte Carlo E{x_k x_k^T 1(theta_k = i)}, k = 1..3."""
    sys = draw_system(rng)
    L = 0.5 * rng.standard_normal((sys.nu, sys.ny))
    sys = rescaled(sys, _norm_scale(rng, closed_loop(sys, L)))
    Acl = closed_loop(sys, L)
    HHt = sys.H @ _T(sys.H)
    mu0, mean0, cov0 = _gaussian_mixture(rng, sys)
    X0 = mu0[:, None, None] * (cov0 + np.einsum("ia,ib->iab", mean0, mean0))
    X, mus = second_moments(Acl, HHt, sys.T, X0, mu0, 3)
    n_runs = 10000
    x, theta = _sample_mixture(rng, mu0, mean0, cov0, n_runs)
    worst = 0.0
    chain, closed, noise = ModeChain(sys.T), ModeOperator(Acl), ModeOperator(sys.H)
    for k in range(1, 4):
        modes = RunModes(theta, sys.M)
        x = closed(x, modes) + noise(rng.standard_normal((n_runs, sys.nw)), modes)
        theta = chain.next(rng, theta)
        worst = max(worst, _z_scores(x, theta, X[k], mus[k]))
    return _outcome(_verdict(worst < Z_SCORE), sys, max_z=worst, runs=n_runs)


def check_3_15(rng):
    """Prop. 3.15: the average cost (3.11) from a given x_0, theta_0 equals (3.30)'s objective
    (with C_i^T L^T R_i L C_i; the printed L^T R_i L only fits C_i = I)."""
    sys = draw_system(rng)
    L = 0.5 * rng.standard_normal((sys.nu, sys.ny))
    sys, target = _stabilised(rng, sys, lambda s: closed_loop(s, L), 0.2, 0.95)
    Acl = closed_loop(sys, L)
    HHt = sys.H @ _T(sys.H)
    objective = h2_cost(sys, L, steady_state_second_moment(Acl, HHt, sys.T, sys.mu_inf))
    x0 = 3 * rng.standard_normal(sys.nx)
    mu0 = np.eye(sys.M)[rng.integers(sys.M)]
    K = 1000
    X, _ = second_moments(Acl, HHt, sys.T, mu0[:, None, None] * np.outer(x0, x0), mu0, K)
    LC = L @ sys.C
    per_step = np.einsum("iab,kiba->k", sys.Q + _T(LC) @ sys.R @ LC, X)
    avg, avg_half = per_step.mean(), per_step[:K // 2 + 1].mean()
    error = abs(avg - objective)
    return _outcome(_verdict(error <= 1.5 * abs(avg - avg_half) + 1e-8 * objective), sys,
                    objective_3_30=objective, average_cost_K1000=avg, average_cost_K500=avg_half, rho=target)


def check_3_16(rng):
    """Prop. 3.16: the stated Hamiltonian equals the Lagrangian of (3.30) (constraint times P)."""
    sys = draw_system(rng)
    L = rng.standard_normal((sys.nu, sys.ny))
    X, P = random_spd_stack(rng, sys.M, sys.nx), random_spd_stack(rng, sys.M, sys.nx)
    mu = sys.mu_inf
    Acl = closed_loop(sys, L)
    inner = Acl @ X @ _T(Acl) + mu[:, None, None] * (sys.H @ _T(sys.H))
    LC = L @ sys.C
    weight = sys.Q + _T(LC) @ sys.R @ LC
    stated = _tr(weight, X) - _tr(P, X) + _tr(successor_average(sys.T, P), inner)
    lagrangian = _tr(weight, X) - _tr(P, X) + sum(_tr(P[j], sys.T[i, j] * inner[i])
                                                 for i in range(sys.M) for j in range(sys.M))
    scale = _tr(weight, X) + _tr(P, X) + abs(_tr(successor_average(sys.T, P), inner))
    rel = abs(stated - lagrangian) / scale
    return _outcome(_verdict(rel < 1e-12), sys, relative_difference=rel)


def _gain_residual(sys, L, X, P):
    """(3.31): sum_i (R_i + B_i^T E_i(P) B_i) L C_i X_i C_i^T + B_i^T E_i(P) A_i X_i C_i^T, and its scale."""
    EP = successor_average(sys.T, P)
    first = (sys.R + _T(sys.B) @ EP @ sys.B) @ L @ sys.C @ X @ _T(sys.C)
    second = _T(sys.B) @ EP @ sys.A @ X @ _T(sys.C)
    return first.sum(axis=0) + second.sum(axis=0), np.linalg.norm(first.sum(0)) + np.linalg.norm(second.sum(0))


def _costate(sys, L):
    """P_inf of (3.33): P_i = Acl_i^T E_i(P) Acl_i + Q_i + C_i^T L^T R_i L C_i."""
    Acl = closed_loop(sys, L)
    LC = L @ sys.C
    rhs = (sys.Q + _T(LC) @ sys.R @ LC).ravel()
    P = np.linalg.solve(np.eye(rhs.size) - kronecker_matrix(Acl, sys.T).T, rhs).reshape(sys.Q.shape)
    return 0.5 * (P + _T(P))


def check_3_17(rng):
    """Thm. 3.17: the minimiser of the cost (found by a grid and a scalar search over L) satisfies (3.31)."""
    sys = draw_system(rng, siso=True)
    s = np.linspace(-np.pi / 2, np.pi / 2, 403)[1:-1]
    radii = scalar_gain_radii(sys, np.tan(s))
    if not radii.min() < 1:
        return _outcome("not_applicable", sys, min_rho_over_L=float(radii.min()))
    HHt = sys.H @ _T(sys.H)
    noise = predecessor_sum(sys.T, sys.mu_inf[:, None, None] * HHt)

    def cost(t):
        """The H2 cost of L = tan(t) (inf when not stabilising), on the system validated once: the
        library's unchecked paths of ms_spectral_radius with steady_state_second_moment, and of h2_cost."""
        L = np.array([[np.tan(t)]])
        _, X = radius_and_moments_unchecked(closed_loop_unchecked(sys, L), sys.T, noise)
        return np.inf if X is None else h2_cost_unchecked(sys, L, X)

    costs = np.full(len(s), np.inf)                         # cost(t) at the grid points with rho < 1, at once
    grid = np.flatnonzero(radii < 1)
    gains = np.tan(s[grid])
    loops = sys.A + (sys.B @ gains[:, None, None, None]) @ sys.C                # closed_loop_unchecked of each
    for index, gain, X in zip(grid, gains, radii_and_moments_unchecked(loops, sys.T, noise)[1]):
        if X is not None:
            costs[index] = h2_cost_unchecked(sys, np.array([[gain]]), X)
    best = int(np.argmin(costs))
    res = scipy.optimize.minimize_scalar(cost, bounds=(s[max(best - 1, 0)], s[min(best + 1, len(s) - 1)]),
                                         method="bounded", options={"xatol": 1e-12})
    t = res.x if res.fun <= costs[best] else s[best]
    L = np.array([[np.tan(t)]])
    Acl = closed_loop(sys, L)
    X = steady_state_second_moment(Acl, HHt, sys.T, sys.mu_inf)
    residual, scale = _gain_residual(sys, L, X, _costate(sys, L))
    rel = float(np.linalg.norm(residual) / scale)
    return _outcome(_verdict(rel < 1e-5), sys, optimal_L=float(L[0, 0]), cost=cost(t),
                    relative_residual_3_31=rel)


def check_3_18(rng):
    """Prop. 3.18: the printed vec formula (column-major vec, C X C^T (x) (R + B^T E(P) B)) solves (3.31)."""
    sys = draw_system(rng)
    X, P = random_spd_stack(rng, sys.M, sys.nx), random_spd_stack(rng, sys.M, sys.nx)
    EP = successor_average(sys.T, P)
    lhs = sum(np.kron(sys.C[i] @ X[i] @ sys.C[i].T, sys.R[i] + sys.B[i].T @ EP[i] @ sys.B[i])
              for i in range(sys.M))
    rhs = sum(sys.B[i].T @ EP[i] @ sys.A[i] @ X[i] @ sys.C[i].T for i in range(sys.M))
    L = -np.linalg.solve(lhs, rhs.ravel(order="F")).reshape((sys.nu, sys.ny), order="F")
    residual, scale = _gain_residual(sys, L, X, P)
    rel = float(np.linalg.norm(residual) / scale)
    library = gain_from_moments(sys, X, P)
    tol = 1e-13 * np.linalg.cond(lhs)
    return _outcome(_verdict(rel < max(tol, 1e-10)), sys, relative_residual=rel,
                    library_difference=float(np.abs(library - L).max()), condition=float(np.linalg.cond(lhs)))


def check_3_19(rng):
    """Thm. 3.19: SOF-stabilisable (grid over scalar L) -> Alg. 3.1 converges to a stabilising,
    unique solution (same limit from X = P = 1e-4 I and from X = P = I)."""
    return decide_3_19(draw_system(rng, siso=True, families=("thesis_like", "unstable", "stable", "sparse_T")))


def decide_3_19(sys):
    """Thm. 3.19 on one SISO system: premise by the gain grid, conclusion by Alg. 3.1 (two starts)."""
    L_best, rho_best = best_scalar_gain(sys)
    if not rho_best < 1:
        return _outcome("not_applicable", sys, min_rho_over_L=rho_best, best_L=L_best)
    run = static_output_feedback(sys, warn=False, moments="step")
    numbers = dict(min_rho_over_L=rho_best, best_L=L_best, margin=1 - rho_best, alg_L=float(run.L[0, 0]),
                   alg_rho=run.rho, alg_converged=run.converged, alg_iterations=run.iterations)
    if not (run.converged and run.stabilizing):
        return _outcome("fails", sys, **numbers)
    other = static_output_feedback(sys, init=1.0, warn=False, moments="step")
    same = other.converged and abs(other.L[0, 0] - run.L[0, 0]) <= 1e-6 * (1 + abs(run.L[0, 0]))
    return _outcome(_verdict(same), sys, alg_L_from_identity=float(other.L[0, 0]), **numbers)


# ------------------------------------------------------------------ Sec. 3.6: Alg. 3.2

def check_3_20(rng):
    """Prop. 3.20: x~^T Q~ x~ = x^T Q x + u^T R u with u = L x^."""
    sys = draw_system(rng)
    L = rng.standard_normal((sys.nu, sys.nx))
    i = rng.integers(sys.M)
    x, xhat = rng.standard_normal(sys.nx), rng.standard_normal(sys.nx)
    _, _, Qt = augmented_closed_loop(sys, np.zeros((sys.nx, sys.nx)), np.zeros((sys.nx, sys.ny)), L)
    xt = np.concatenate([x, xhat])
    u = L @ xhat
    direct = x @ sys.Q[i] @ x + u @ sys.R[i] @ u
    rel = abs(xt @ Qt[i] @ xt - direct) / max(direct, 1e-300)
    return _outcome(_verdict(rel < 1e-12), sys, relative_difference=rel)


def _dynamic_gains(rng, sys, scale=0.5):
    F = scale * rng.standard_normal((sys.nx, sys.nx))
    K = scale * rng.standard_normal((sys.nx, sys.ny))
    L = scale * rng.standard_normal((sys.nu, sys.nx))
    return F, K, L


def _stabilised_dynamic(rng, sys, low=0.2, high=0.85):
    """Random (F, K, L) and the system rescaled (with F, K) so the augmented loop has rho in [low, high]."""
    F, K, L = _dynamic_gains(rng, sys)
    At = augmented_closed_loop(sys, F, K, L)[0]
    target = rng.uniform(low, high)
    c = float(np.sqrt(target / ms_spectral_radius(At, sys.T)))
    return rescaled(sys, c), c * F, c * K, L, target


def _loop_step(sys):
    """One step of plant (3.36) and controller (3.37) for all runs: ``step((x, x^), modes, r, F, K, L)``
    with x, x^ of shape (runs, nx) and ``modes`` the runs' RunModes; the new (x, x^)."""
    J = np.zeros((sys.M, sys.ny, 1)) if sys.J is None else sys.J
    C, meas, A, B, H = (ModeOperator(S) for S in (sys.C, J, sys.A, sys.B, sys.H))

    def step(state, modes, r, F, K, L):
        x, xh = state
        y = C(x, modes) + meas(r.standard_normal((len(x), J.shape[2])), modes)
        x_new = A(x, modes) + B(xh @ L.T, modes) + H(r.standard_normal((len(x), sys.nw)), modes)
        return x_new, xh @ F.T + y @ K.T

    return step


def _quadratic_costs(sys):
    """x^T Q_theta x and u^T R_theta u for all runs: ``(state_cost(x, theta), input_cost(u, theta))``."""
    return ModeQuadratic(sys.Q), ModeQuadratic(sys.R)


def check_3_23(rng):
    """Prop. 3.23: the printed block recursion of X~ against Monte Carlo, k = 1..3."""
    sys = draw_system(rng)
    F, K, L = _dynamic_gains(rng, sys)
    c = _norm_scale(rng, augmented_closed_loop(sys, F, K, L)[0])
    sys, F, K = rescaled(sys, c), c * F, c * K
    HHt, JJt = noise_covariances(sys)
    mu0, mean0, cov0 = _gaussian_mixture(rng, sys)
    xhat0 = rng.standard_normal(sys.nx)
    Xt = augmented_initial_moment(mean0, cov0, mu0, xhat0)
    n, A, B, C, m = sys.nx, sys.A, sys.B, sys.C, mu0
    n_runs = 10000
    x, theta = _sample_mixture(rng, mu0, mean0, cov0, n_runs)
    state = x, np.broadcast_to(xhat0, x.shape).copy()
    step, chain = _loop_step(sys), ModeChain(sys.T)
    worst, compact_diff = 0.0, 0.0
    for _ in range(3):
        X1, X12, X2 = Xt[:, :n, :n], Xt[:, :n, n:], Xt[:, n:, n:]
        BL, KC = B @ L, K @ C
        mm = m[:, None, None]
        new1 = predecessor_sum(sys.T, A @ X1 @ _T(A) + A @ X12 @ _T(BL) + BL @ _T(X12) @ _T(A)
                               + BL @ X2 @ _T(BL) + mm * HHt)
        new12 = predecessor_sum(sys.T, A @ X1 @ _T(KC) + A @ X12 @ F.T + BL @ _T(X12) @ _T(KC) + BL @ X2 @ F.T)
        new2 = predecessor_sum(sys.T, KC @ X1 @ _T(KC) + KC @ X12 @ F.T + F @ _T(X12) @ _T(KC) + F @ X2 @ F.T
                               + mm * (K @ JJt @ K.T))
        At, HHt_cl, _ = augmented_closed_loop(sys, F, K, L)
        compact = predecessor_sum(sys.T, At @ Xt @ _T(At) + mm * HHt_cl)
        Xt = np.block([[new1, new12], [_T(new12), new2]])
        compact_diff = max(compact_diff, float(np.abs(compact - Xt).max() / np.abs(Xt).max()))
        m = m @ sys.T
        state, theta = step(state, RunModes(theta, sys.M), rng, F, K, L), chain.next(rng, theta)
        worst = max(worst, _z_scores(np.hstack(state), theta, Xt, m))
    return _outcome(_verdict(worst < Z_SCORE), sys, max_z=worst, compact_form_difference=compact_diff,
                    runs=n_runs)


def check_3_24(rng):
    """Prop. 3.24: sum_i tr[Q~_i X~_inf^i] against the Monte Carlo stationary average cost of the loop."""
    sys = draw_system(rng)
    sys, F, K, L, target = _stabilised_dynamic(rng, sys)
    exact, _, rho = steady_state_cost(sys, F, K, L)
    n_runs = 1000
    state_cost, input_cost = _quadratic_costs(sys)
    cost = lambda state, modes: state_cost(state[0], modes.theta) + input_cost(state[1] @ L.T, modes.theta)
    loop = _loop_step(sys)
    step = lambda state, modes, r: loop(state, modes, r, F, K, L)
    start = np.zeros((n_runs, sys.nx)), np.zeros((n_runs, sys.nx))
    mc, se, burn = stationary_average(rng, step, cost, start, initial_modes(rng, sys.mu_inf, n_runs), sys.T, rho,
                                      n_runs)
    z = abs(mc - exact) / np.hypot(se, 1e-3 * exact)
    return _outcome(_verdict(z < Z_SCORE), sys, cost_3_42=exact, monte_carlo=mc, standard_error=se, z=z,
                    rho=rho, burn_in=burn)


def check_3_25(rng):
    """Prop. 3.25: the stated Hamiltonian of (3.42) equals its Lagrangian (constraint times P~)."""
    sys = draw_system(rng)
    F, K, L = _dynamic_gains(rng, sys)
    At, HHt_cl, Qt = augmented_closed_loop(sys, F, K, L)
    n2 = 2 * sys.nx
    X, P = random_spd_stack(rng, sys.M, n2), random_spd_stack(rng, sys.M, n2)
    inner = At @ X @ _T(At) + sys.mu_inf[:, None, None] * HHt_cl
    stated = _tr(Qt, X) + _tr(successor_average(sys.T, P), inner) - _tr(P, X)
    lagrangian = _tr(Qt, X) - _tr(P, X) + _tr(P, predecessor_sum(sys.T, inner))
    rel = abs(stated - lagrangian) / (abs(_tr(Qt, X)) + _tr(P, X) + abs(_tr(P, predecessor_sum(sys.T, inner))))
    return _outcome(_verdict(rel < 1e-12), sys, relative_difference=rel)


def check_3_26(rng):
    """Prop. 3.26 as printed: X~ <= [[Xbar + Xu, Xu], [Xu, Xu]] and P~ <= [[Pbar + Pu, -Pu], [-Pu, Pu]]
    with Xbar = X1 - X12 - X12^T + X2, Xu = X2 (3.43) of the exact X~_inf, P~_inf of a stabilising (F, K, L)."""
    sys = draw_system(rng)
    sys, F, K, L, _ = _stabilised_dynamic(rng, sys)
    _, Xt, rho = steady_state_cost(sys, F, K, L)
    At, _, Qt = augmented_closed_loop(sys, F, K, L)
    Pt = np.linalg.solve(np.eye(Qt.size) - kronecker_matrix(At, sys.T).T, Qt.ravel()).reshape(Qt.shape)
    Pt = 0.5 * (Pt + _T(Pt))
    n = sys.nx

    def gaps(Z, sign):
        Z1, Z12, Z2 = Z[:, :n, :n], Z[:, :n, n:], Z[:, n:, n:]
        bar = Z1 - Z12 - _T(Z12) + Z2
        bound = np.block([[bar + Z2, sign * Z2], [sign * Z2, Z2]])
        return min_eig(bound - Z) / max(np.abs(Z).max(), 1e-300)

    gap_X, gap_P = gaps(Xt, 1.0), gaps(Pt, -1.0)
    return _outcome(_verdict(min(gap_X, gap_P) > -1e-9), sys, min_eig_bound_minus_X=gap_X,
                    min_eig_bound_minus_P=gap_P, rho=rho)


def check_3_27(rng):
    """Thm. 3.27: a stabilising solution of (3.45)-(3.49) (Alg. 3.2 converged) is the optimal (3.37):
    the gradient of the exact cost (3.42) vanishes there."""
    sys = draw_system(rng, max_states=2, max_modes=2)
    run = dynamic_output_feedback(sys, max_iter=3000, warn=False)
    numbers = dict(alg_converged=run.converged, alg_stabilizing=run.stabilizing, alg_iterations=run.iterations)
    if not (run.converged and run.stabilizing):
        return _outcome("not_applicable", sys, **numbers)
    cost, grad = average_cost_and_gradient(sys, run.F, run.K, run.L)
    theta = np.concatenate([run.F.ravel(), run.K.ravel(), run.L.ravel()])
    g = np.concatenate([np.ravel(x) for x in grad])
    stationarity = float(np.linalg.norm(g) * max(np.linalg.norm(theta), 1e-12) / cost)
    step = 1e-3 * max(np.linalg.norm(theta), 1e-6) / max(np.linalg.norm(g), 1e-300)
    nF, nK = run.F.size, run.K.size
    moved = theta - step * g
    lower, _ = average_cost_and_gradient(sys, moved[:nF].reshape(run.F.shape), moved[nF:nF + nK].reshape(run.K.shape),
                                         moved[nF + nK:].reshape(run.L.shape))
    improvement = (cost - lower) / cost
    not_optimal = stationarity > 1e-4 and improvement > 1e-7
    return _outcome(_verdict(not not_optimal), sys, cost=cost, relative_gradient=stationarity,
                    improvement_by_gradient_step=improvement, **numbers)


# ------------------------------------------------------------------ Sec. 3.7: Alg. 3.3

def _finite_instance(rng, max_states=3, max_modes=3):
    sys = draw_system(rng, max_states=max_states, max_modes=max_modes)
    horizon = int(rng.integers(2, 9))
    F = 0.5 * rng.standard_normal((horizon, sys.nx, sys.nx))
    K = 0.5 * rng.standard_normal((horizon, sys.nx, sys.ny))
    L = 0.5 * rng.standard_normal((horizon, sys.nu, sys.nx))
    mu0, mean0, cov0 = _gaussian_mixture(rng, sys)
    return sys, horizon, F, K, L, mu0, mean0, cov0


def check_3_28(rng):
    """Prop. 3.28: the expected cost (3.56) by the moment recursion (3.57)-(3.58) against Monte Carlo."""
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    xhat0 = mu0 @ mean0
    exact = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0)
    n_runs = 10000
    x, theta = _sample_mixture(rng, mu0, mean0, cov0, n_runs)
    state, total = (x, np.broadcast_to(xhat0, x.shape).copy()), np.zeros(n_runs)
    step, chain = _loop_step(sys), ModeChain(sys.T)
    state_cost, input_cost = _quadratic_costs(sys)
    for k in range(horizon):
        total += state_cost(state[0], theta) + input_cost(state[1] @ L[k].T, theta)
        state, theta = step(state, RunModes(theta, sys.M), rng, F[k], K[k], L[k]), chain.next(rng, theta)
    total += state_cost(state[0], theta)
    mc, se = moment_estimate(total)
    z = abs(mc - exact) / max(se, 1e-12 * exact)
    return _outcome(_verdict(z < Z_SCORE), sys, cost_3_57=exact, monte_carlo=float(mc), standard_error=float(se),
                    z=z, horizon=horizon)


def check_3_29(rng):
    """Lemma 3.29: sum_i tr[P~_0^i X~_0^i] + mu_0^i omega_{i,0} by the backward recursion (3.64)
    against the forward sum (3.62)."""
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    xhat0 = mu0 @ mean0
    forward = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0)
    n = sys.nx
    P = np.zeros((sys.M, 2 * n, 2 * n))
    P[:, :n, :n] = sys.Q                                               # P~_K = Q~_K
    omega = np.zeros(sys.M)
    for k in range(horizon - 1, -1, -1):
        At, HHt_cl, Qt = augmented_closed_loop(sys, F[k], K[k], L[k])
        EP = successor_average(sys.T, P)
        omega = np.einsum("iab,iba->i", EP, HHt_cl) + sys.T @ omega     # tr[H~^T E(P) H~] + E_i(omega)
        P = Qt + _T(At) @ EP @ At
    backward = _tr(P, augmented_initial_moment(mean0, cov0, mu0, xhat0)) + float(mu0 @ omega)
    rel = abs(backward - forward) / forward
    return _outcome(_verdict(rel < 1e-10), sys, backward=backward, forward=forward, relative_difference=rel)


def check_3_30(rng):
    """Lemma 3.30: X >= A >= 0 and Y >= B >= 0 imply tr[AB] <= tr[XY] (rank-deficient draws included)."""
    n = int(rng.integers(1, 5))

    def psd():
        G = rng.standard_normal((n, int(rng.integers(1, n + 1))))
        return G @ G.T

    A, B = psd(), psd()
    X, Y = A + psd(), B + psd()
    small, large = np.trace(A @ B), np.trace(X @ Y)
    return _outcome(_verdict(small <= large * (1 + 1e-12) + 1e-12), None, tr_AB=small, tr_XY=large,
                    n_states=n, n_modes=1)


def _bound_cost(sys, F, K, L, mean0, cov0, mu0):
    """Jbar_0 (3.65) for fixed gains by (3.66)-(3.69) (the library's step functions) and omega."""
    horizon = len(F)
    HHt, JJt = noise_covariances(sys)
    _, Xbar, Xunder = initial_bounds(mean0, cov0, mu0)
    mus, X_seq = [mu0], [(Xbar, Xunder)]
    for k in range(horizon):
        X_seq.append(bound_moment_step(sys, F[k], K[k], L[k], *X_seq[-1], mus[-1], HHt, JJt))
        mus.append(mus[-1] @ sys.T)
    Pbar, Punder, omega = sys.Q.copy(), np.zeros_like(sys.Q), np.zeros(sys.M)
    for k in range(horizon - 1, -1, -1):
        EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
        omega = (np.einsum("iab,iba->i", EPbar + EPunder, HHt) + np.einsum("iab,iba->i", EPunder, K[k] @ JJt @ K[k].T)
                 + sys.T @ omega)
        Pbar, Punder = bound_costate_step(sys, F[k], K[k], L[k], EPbar, EPunder)
    Xbar, Xunder = X_seq[0]
    return _tr(Pbar, Xbar + Xunder) + _tr(Punder, Xbar) + float(mu0 @ omega)


def check_3_31(rng):
    """Thm. 3.31: J_0 <= Jbar_0 for fixed gains (the exact cost from (3.57)-(3.58))."""
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    optimised = bool(rng.random() < 0.5)
    if optimised:                                                     # the gains Alg. 3.3 returns
        run = finite_horizon_dynamic_output_feedback(sys, horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0,
                                                     init=(F, K, L), max_iter=100, warn=False)
        F, K, L = run.F, run.K, run.L
    exact = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0)
    bound = _bound_cost(sys, F, K, L, mean0, cov0, mu0)
    return _outcome(_verdict(exact <= bound * (1 + 1e-9)), sys, exact_cost=exact, bound=bound,
                    relative_excess=(exact - bound) / bound, horizon=horizon, gains_from_alg_3_3=optimised)


def check_3_32(rng):
    """Thm. 3.32 at k = 0: with X_0 given and P_1 > 0 (the later gains fixed), Jbar_0 (3.65) with
    (3.68)-(3.69) is a quadratic in (F_0, K_0, L_0); at its minimiser (3.70) must hold, so the
    solution of (3.70) must not be improved by random perturbations."""
    sys = draw_system(rng)
    M, n = sys.M, sys.nx
    Xbar, Xunder = random_spd_stack(rng, M, n), random_spd_stack(rng, M, n)         # X_0 of a horizon >= 2
    EPbar = successor_average(sys.T, random_spd_stack(rng, M, n))                   # E_i(P_1), P_1 > 0
    EPunder = successor_average(sys.T, random_spd_stack(rng, M, n))
    Eomega, mu = sys.T @ rng.random(M), rng.dirichlet(np.ones(M))
    HHt, JJt = noise_covariances(sys)
    shapes = [(n, n), (n, sys.ny), (sys.nu, n)]
    sizes = np.cumsum([0] + [a * b for a, b in shapes])

    def unpack(z):
        return [z[sizes[j]:sizes[j + 1]].reshape(shapes[j], order="F") for j in range(3)]

    def bound(z):
        F, K, L = unpack(z)
        Pbar, Punder = bound_costate_step(sys, F, K, L, EPbar, EPunder)
        omega = np.einsum("iab,iba->i", EPbar + EPunder, HHt) + np.einsum("iab,iba->i", EPunder, K @ JJt @ K.T) + Eomega
        return _tr(Pbar, Xbar + Xunder) + _tr(Punder, Xbar) + float(mu @ omega)

    H, rho = optimality_system(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt)
    z = np.linalg.lstsq(H, -rho, rcond=None)[0]
    best = bound(z)
    drops = [best - bound(z + scale * rng.standard_normal(z.size)) for scale in (1e-3, 1e-1, 1.0) for _ in range(5)]
    worst = max(drops) / abs(best)
    return _outcome(_verdict(worst <= 1e-9), sys, bound_at_solution=best, largest_relative_drop=worst)


def check_3_33(rng):
    """Thm. 3.33: Alg. 3.3 gives non-increasing Jbar_0 and its parameters converge
    (20 further iterations after the stop change them by < 1e-4 relative)."""
    sys, horizon, _, _, _, mu0, mean0, cov0 = _finite_instance(rng, max_states=2, max_modes=2)
    seed = int(rng.integers(2**32))
    kwargs = dict(horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0, warn=False)
    run = finite_horizon_dynamic_output_feedback(sys, init=np.random.default_rng(seed), max_iter=300, **kwargs)
    bounds = run.cost_bounds
    increases = np.diff(bounds) / np.maximum(1.0, np.abs(bounds[1:]))
    largest_increase = float(increases.max()) if increases.size else 0.0
    numbers = dict(iterations=run.iterations, converged=run.converged, largest_relative_increase=largest_increase,
                   first_bound=float(bounds[0]), last_bound=float(bounds[-1]), horizon=horizon)
    if not run.converged:
        return _outcome("fails", sys, **numbers)
    more = finite_horizon_dynamic_output_feedback(sys, init=np.random.default_rng(seed), max_iter=run.iterations + 20,
                                                  tol=1e-300, **kwargs)
    theta = lambda r: np.concatenate([r.F.ravel(), r.K.ravel(), r.L.ravel()])
    change = float(np.linalg.norm(theta(more) - theta(run)) / max(np.linalg.norm(theta(run)), 1e-12))
    return _outcome(_verdict(largest_increase <= 1e-8 and change < 1e-4), sys, parameter_change_after_20=change,
                    **numbers)


STATEMENTS = [
    Statement("statement_3_1", "Theorem 3.1", "Positive definite solutions of either coupled Lyapunov equation imply mean-square stability.",
              "Random A_i, T and S_i > 0; Q solved from each form; if Q > 0, mean-square stability is decided by the decay of the second moments (3.29).",
              check_3_1),
    Statement("statement_3_2", "Corollary 3.2", "rho(M) < 1 (Kronecker form) implies mean-square stability.",
              "rho from the eigenvalues of M; stability decided independently by the decay of the second-moment recursion (3.29).",
              check_3_2),
    Statement("statement_3_5", "Proposition 3.5", "The optimal cost-to-go at K-1 is x^T Psi x + Delta (the step that makes K-2 intractable).",
              "Closed form x^T Psi x + Delta against the minimum over u (BFGS) of the exact expectation over modes and noise, for a random belief.",
              check_3_5),
    Statement("statement_3_7", "Proposition 3.7", "The H2 norm of the closed loop (3.10) is sum_i tr[(D_i+E_i L C_i) X_i (.)^T] with X from the coupled Gramian equations.",
              "Formula against the Monte Carlo stationary E{z^T z} (1000 runs), within 6 standard errors.",
              check_3_7),
    Statement("statement_3_8", "Lemma 3.8", "Any (L, G, Y) satisfying the BMI (3.15) gives an objective that bounds (3.14) from above.",
              "Feasible points built from a slack S > 0 and G near D(Y), feasibility checked numerically; objective >= ||G||_2^2 of L.",
              check_3_8),
    Statement("statement_3_9", "Theorem 3.9", "If the LMIs are feasible, L = F M^{-1} stabilises the MJLS in the mean-square sense.",
              "LMIs solved (Clarabel); rho of the recovered gain by Cor. 3.2. Conservatism: SOF stabilisability decided by a 2001-point grid over scalar L plus a bounded search.",
              check_3_9, expensive=True),
    Statement("statement_3_10", "Proposition 3.10", "The H2 norm with mode feedback L_i is the Gramian formula of Prop. 3.7 with L_i.",
              "Formula against the Monte Carlo stationary E{z^T z}, within 6 standard errors.",
              check_3_10),
    Statement("statement_3_11", "Lemma 3.11", "The mode-observed BMI with G_i bounds (3.25) from above.",
              "As Lemma 3.8 with mode-dependent G_i and L_i.",
              check_3_11),
    Statement("statement_3_12", "Theorem 3.12", "If the mode-observed LMIs are feasible, L_i = F_i M_i^{-1} stabilise the MJLS with mode feedback.",
              "LMIs solved (Clarabel); rho of A_i + B_i L_i C_i by Cor. 3.2.",
              check_3_12, expensive=True),
    Statement("statement_3_14", "Proposition 3.14", "The second moments X_k^i follow the recursion (3.29).",
              "Recursion against Monte Carlo E{x_k x_k^T 1(theta_k=i)} (10000 runs, k = 1..3, Gaussian-mixture x_0, closed loop scaled to max ||A_i + B_i L C_i|| in [0.5, 1.5]), every entry within 6 standard errors.",
              check_3_14),
    Statement("statement_3_15", "Proposition 3.15", "Problem (3.11) equals (3.30): the average cost is sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_inf^i] (printed with L^T R_i L).",
              "(3.30)'s objective against the average cost over 1000 steps from a random x_0 (moment recursion), within its 1/K convergence error.",
              check_3_15),
    Statement("statement_3_16", "Proposition 3.16", "The Hamiltonian of (3.30) in terms of E_i(P).",
              "Stated form against the Lagrangian written with the constraint, at random L, X, P.",
              check_3_16),
    Statement("statement_3_17", "Theorem 3.17", "The optimal static gain satisfies the coupled equations (3.31)-(3.33).",
              "Global minimiser of the exact cost over scalar L (grid + bounded search); residual of (3.31) there with X, P from (3.32)-(3.33).",
              check_3_17),
    Statement("statement_3_18", "Proposition 3.18", "vec L = -(sum C X C^T (x) (R + B^T E(P) B))^{-1} vec(sum B^T E(P) A X C^T) solves (3.31).",
              "Printed formula (column-major vec) at random X, P; residual of (3.31); also compared with asoc.mjls.gain_from_moments.",
              check_3_18),
    Statement("statement_3_19", "Theorem 3.19", "If the MJLS is SOF-stabilisable, Alg. 3.1 converges to its unique (stabilising) solution.",
              "Premise by a 2001-point grid over scalar L plus a bounded search (rho < 1); Alg. 3.1 (asoc.mjls.static_output_feedback) must converge to a stabilising gain, the same from 1e-4 I and from I.",
              check_3_19),
    Statement("statement_3_20", "Proposition 3.20", "The cost (3.38) in the augmented state with Q~ = diag(Q, L^T R L).",
              "x~^T Q~ x~ against x^T Q x + u^T R u at random points.",
              check_3_20),
    Statement("statement_3_23", "Proposition 3.23", "The second moments of the augmented closed loop (3.39) follow the printed block recursion.",
              "Printed blocks against Monte Carlo of plant and controller (10000 runs, k = 1..3, max ||A~_i|| in [0.5, 1.5]), within 6 standard errors.",
              check_3_23),
    Statement("statement_3_24", "Proposition 3.24", "Problem (3.41) equals (3.42): the average cost is sum_i tr[Q~_i X~_inf^i].",
              "(3.42) against the Monte Carlo stationary cost of plant and controller (1000 runs), within 6 standard errors.",
              check_3_24),
    Statement("statement_3_25", "Proposition 3.25", "The Hamiltonian of (3.42) in terms of E_i(P~).",
              "Stated form against the Lagrangian at random gains, X~, P~.",
              check_3_25),
    Statement("statement_3_26", "Proposition 3.26", "X~_inf and P~_inf are bounded above by the block matrices built from (3.43).",
              "Exact X~_inf, P~_inf of a random stabilising (F, K, L); smallest eigenvalue of bound minus matrix.",
              check_3_26),
    Statement("statement_3_27", "Theorem 3.27", "The dynamic output-feedback law (3.37) is determined by the coupled equations (3.45)-(3.49).",
              "Reading: the solution is the optimal (3.37). At a converged, stabilising Alg. 3.2 solution, the exact cost's gradient must vanish (a gradient step must not lower the cost).",
              check_3_27, expensive=True),
    Statement("statement_3_28", "Proposition 3.28", "The finite-horizon cost (3.56) equals the moment form (3.57)-(3.58).",
              "Moment form (asoc.mjls.finite_horizon_cost) against Monte Carlo of plant and time-variant controller (10000 runs), within 6 standard errors.",
              check_3_28),
    Statement("statement_3_29", "Lemma 3.29", "The cost-to-go is sum_i tr[P~_t X~_t] + mu_t omega_t with the backward recursion (3.64).",
              "Backward recursion against the forward sum of stage costs, random gains and horizons 2-8.",
              check_3_29),
    Statement("statement_3_30", "Lemma 3.30", "X >= A >= 0 and Y >= B >= 0 imply tr[AB] <= tr[XY].",
              "Random positive semidefinite A, B and increments (rank-deficient included).",
              check_3_30),
    Statement("statement_3_31", "Theorem 3.31", "For fixed gains, the exact cost J_k is bounded above by Jbar_k (3.65).",
              "Exact J_0 (moment recursion) against Jbar_0 from (3.66)-(3.69), random gains, horizons 2-8.",
              check_3_31),
    Statement("statement_3_32", "Theorem 3.32", "A minimiser of the bound (3.65) satisfies the linear conditions (3.70).",
              "At one step, the solution of (3.70) against random perturbations of (F_k, K_k, L_k) in Jbar_k (3.65)/(3.68)-(3.69).",
              check_3_32),
    Statement("statement_3_33", "Theorem 3.33", "Alg. 3.3's costs Jbar_0 are non-increasing and its parameters converge.",
              "Alg. 3.3 (asoc.mjls.finite_horizon_dynamic_output_feedback, Step 5 safeguard on) from random gains: increases of Jbar_0, convergence within 300 iterations, change of the gains over 20 more iterations.",
              check_3_33, expensive=True),
]

def _bound_summary(outcomes):
    """Thm. 3.31: failures among the instances with Alg. 3.3's gains and with random gains."""
    by = {True: [0, 0], False: [0, 0]}
    for o in outcomes:
        if o.verdict != "not_applicable":
            by[bool(o.numbers.get("gains_from_alg_3_3"))][o.verdict == "fails"] += 1
    return {"alg_3_3_gains": {"instances": sum(by[True]), "fails": by[True][1]},
            "random_gains": {"instances": sum(by[False]), "fails": by[False][1]}}


def _alg31_summary(outcomes):
    """Thm. 3.19: how the failures fail (no convergence; a non-stabilising limit; another limit from I),
    and how many have one mode (plain linear systems)."""
    fails = [o.numbers for o in outcomes if o.verdict == "fails"]
    return {"not_converged": sum(not n["alg_converged"] for n in fails),
            "converged_not_stabilising": sum(n["alg_converged"] and not n["alg_rho"] < 1 for n in fails),
            "other_limit_from_identity": sum(n["alg_converged"] and n["alg_rho"] < 1 for n in fails),
            "one_mode": sum(n["n_modes"] == 1 for n in fails),
            "smallest_margin": min((1 - n["min_rho_over_L"] for n in fails), default=float("nan"))}


SUMMARIES = {"statement_3_9": _lmi_summary, "statement_3_19": _alg31_summary, "statement_3_31": _bound_summary}

# How a counterexample is printed (label, number, format) and which number measures how clearly it
# fails (the page shows, among the smallest systems, the clearest failure).
SHOW = {
    "statement_3_19": [("min over L of rho (premise: < 1)", "min_rho_over_L", ".3f"),
                       ("Alg. 3.1 converged", "alg_converged", ""), ("Alg. 3.1 gain stabilises", "alg_rho", "<1")],
    "statement_3_26": [("min eig(bound - X~)", "min_eig_bound_minus_X", ".3f"),
                       ("min eig(bound - P~)", "min_eig_bound_minus_P", ".3f")],
    "statement_3_27": [("relative gradient of the exact cost", "relative_gradient", ".1e"),
                       ("a gradient step lowers the cost by (relative)", "improvement_by_gradient_step", ".1e")],
    "statement_3_31": [("exact J_0", "exact_cost", ".4f"), ("bound Jbar_0", "bound", ".4f")],
    "statement_3_32": [("largest relative drop of Jbar_0 below the solution of (3.70)", "largest_relative_drop", ".1e")],
    "statement_3_33": [("Alg. 3.3 converged", "converged", ""),
                       ("largest relative increase of Jbar_0", "largest_relative_increase", ".1e")],
}
MARGIN = {"statement_3_19": lambda n: 1 - n["min_rho_over_L"],
          "statement_3_26": lambda n: -min(n["min_eig_bound_minus_X"], n["min_eig_bound_minus_P"]),
          "statement_3_27": lambda n: n["improvement_by_gradient_step"],
          "statement_3_31": lambda n: n["relative_excess"],
          "statement_3_32": lambda n: n["largest_relative_drop"]}
