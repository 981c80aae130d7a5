"""Sec. 3.5.2's checks: H2 norm (Props. 3.7, 3.10), BMIs (Lemmas 3.8, 3.11), LMIs (Thms. 3.9, 3.12).

* The H2 formulas are compared with the Monte Carlo stationary E{z^T z} of the closed loop.
* The lemmas are implications: a point (L, G, Y) is drawn with no relation to the Lyapunov
  equation of L (Y_i and G random symmetric positive definite, at random scales), the BMI
  (3.15) decides the premise, and the conclusion is tested independently: P = D(Y) satisfies
  the constraint of (3.14) (so L stabilises), and the objective is >= the H2 norm of L.
* The theorems take feasibility from the LMI solver's verified certificate
  (``asoc.mjls.static_output_lmi``: the returned matrices satisfy the LMIs by eigenvalues),
  and test the recovered gain's mean-square stability on its own (:func:`moment_map_radius`).
"""

import cvxpy as cp
import numpy as np

from asoc.linalg import transpose
from asoc.mjls import closed_loop, static_output_lmi, steady_state_second_moment
from asoc.mjls.examples import sec354_system
from asoc.mjls.lmi import performance_output, solve_quietly

from .instances import (
    Z_SCORE,
    ModeOperator,
    best_scalar_gain,
    draw_system,
    initial_modes,
    min_eig,
    outcome,
    random_spd_stack,
    rescaled,
    stabilised,
    stationary_average,
    trace_sum,
    verdict,
)
from .mean_square import moment_map_radius

__all__ = ["check_3_7", "check_3_10", "BOUNDARY_SHARE", "check_3_8", "check_3_11", "check_3_9",
           "decide_3_9", "check_3_12", "summarise_lmi", "MARGIN_SOLVERS", "MARGIN_AGREEMENT",
           "lmi_margin", "certified_margins", "lmi_C12_margin"]


def _stationary_check(rng, mode_dependent, mutant):
    """Props. 3.7 / 3.10: sum_i tr[(D+ELC) X (D+ELC)^T] against the Monte Carlo stationary E{z^T z}.
    Mutant: the formula with D_i in place of D_i + E_i L C_i (the input's share of z dropped).
    """
    sys = draw_system(rng)
    shape = (sys.M, sys.nu, sys.ny) if mode_dependent else (sys.nu, sys.ny)
    L = 0.5 * rng.standard_normal(shape)
    acl = lambda s: s.A + s.B @ L @ s.C
    sys, target = stabilised(rng, sys, acl)
    Acl = acl(sys)
    X = steady_state_second_moment(Acl, sys.H @ transpose(sys.H), sys.T, sys.mu_inf)
    D, E = performance_output(sys)
    DE = D + E @ L @ sys.C
    formula_output = D if mutant else DE
    h2 = trace_sum(formula_output @ X, transpose(formula_output))
    n_runs = 1000
    closed, noise, output = ModeOperator(Acl), ModeOperator(sys.H), ModeOperator(DE)

    def step(x, modes, r):
        return closed(x, modes) + noise(r.standard_normal((len(x), sys.nw)), modes)

    cost = lambda x, modes: np.sum(output(x, modes) ** 2, axis=1)
    mc, se, burn = stationary_average(rng, step, cost, np.zeros((n_runs, sys.nx)),
                                      initial_modes(rng, sys.mu_inf, n_runs), sys.T, target, n_runs)
    z = abs(mc - h2) / np.hypot(se, 1e-3 * h2)
    return outcome(verdict(z < Z_SCORE), sys, h2_formula=h2, monte_carlo=mc, standard_error=se, z=z,
                   rho=target, burn_in=burn)


def check_3_7(rng, mutant=False):
    """Prop. 3.7: the H2 norm of (3.10) by its trace formula against Monte Carlo (one L)."""
    return _stationary_check(rng, False, mutant)


def check_3_10(rng, mutant=False):
    """Prop. 3.10: the H2 norm by its trace formula against Monte Carlo (mode-dependent L_i)."""
    return _stationary_check(rng, True, mutant)


def _random_scaled_spd(rng, count, n, scale):
    """``count`` random SPD n x n matrices scale exp(N(0, 0.15^2)) (I + u W_i), u uniform on [0,
    0.5] and W_i random SPD: spread around a multiple of I, with no relation to any equation of the
    system.
    """
    spread = np.eye(n) + rng.uniform(0.0, 0.5) * random_spd_stack(rng, count, n)
    return spread * (scale * np.exp(0.15 * rng.standard_normal(count)))[:, None, None]


BOUNDARY_SHARE = 0.5     # share of the lemmas' draws at the BMI's boundary (all of the mutants')


def _boundary_point(rng, sys, Acl, HHt, mode_dependent, rho):
    """(Y, G) near the boundary of the BMI (3.15): Y solves Y_i = s Acl_i D_i(Y) Acl_i^T + mu_i H_i
    H_i^T + delta I and G_i = D_i(Y) (Lemma 3.8, one G: the largest multiple of sum_i mu_i D_i(Y)
    below every D_i(Y)), so that with G_i = D_i(Y) the BMI's Schur
    complement is (1 - s) Acl_i D_i(Y) Acl_i^T + delta I: s uniform on [0.5, min(1.5, 0.999 / rho)]
    puts the draws on both sides of the boundary s = 1, delta = 1e-3 tr(mean H H^T) / n (a thin
    margin).
    """
    M, n, mu = sys.M, sys.nx, sys.mu_inf
    s = rng.uniform(0.5, min(1.5, 0.999 / rho))
    delta = 1e-3 * float(np.trace(HHt.mean(axis=0)) / n)
    basis = np.eye(M * n * n).reshape(M * n * n, M, n, n)
    images = s * np.einsum("ji,iab,Njbc,idc->Niad", sys.T, Acl, basis, Acl).reshape(M * n * n, -1).T
    noise = mu[:, None, None] * HHt + delta * np.eye(n)
    Y = np.linalg.solve(np.eye(M * n * n) - images, noise.ravel()).reshape(M, n, n)
    Y = 0.5 * (Y + transpose(Y))
    P = np.einsum("ji,jab->iab", sys.T, Y)
    if mode_dependent:
        return Y, P, s
    average = np.einsum("i,iab->ab", mu, P)
    root = np.linalg.cholesky(average)
    relative = lambda Pi: np.linalg.solve(root, np.linalg.solve(root, Pi).T)   # root^-1 Pi root^-T
    below = min(np.linalg.eigvalsh(relative(Pi)).min() for Pi in P)
    return Y, below * average[None], s


def _lemma_bmi(rng, mode_dependent, mutant):
    """Lemmas 3.8 / 3.11: a point (L, G, Y) satisfying the BMI (3.15) gives D(Y) feasible for
    (3.14), hence a stabilising L, and an objective >= ||G||_2^2 of L. Half the draws (all of the
    mutant's) lie near the BMI's boundary (``_boundary_point``), the others draw Y and G
    independently of L's Lyapunov equation; the BMI decides the premise.
    Mutant: the BMI with its corner block G + G^T in place of G + G^T - D_i(Y).
    """
    sys = draw_system(rng)
    shape = (sys.M, sys.nu, sys.ny) if mode_dependent else (sys.nu, sys.ny)
    L = 0.5 * rng.standard_normal(shape)
    acl = lambda s: s.A + s.B @ L @ s.C
    boundary = mutant or rng.random() < BOUNDARY_SHARE
    target = rng.uniform(*((0.3, 1.5) if boundary else (0.1, 1.6)))      # rho of the closed loop
    sys = rescaled(sys, float(np.sqrt(target / moment_map_radius(acl(sys), sys.T))))
    Acl, mu, M, n = acl(sys), sys.mu_inf, sys.M, sys.nx
    HHt = sys.H @ transpose(sys.H)
    if boundary:
        Y, G, s = _boundary_point(rng, sys, Acl, HHt, mode_dependent, target)
        P = np.einsum("ji,jab->iab", sys.T, Y)
    else:
        scale = float(np.trace(HHt.mean(axis=0)) / n) * np.exp(rng.uniform(1.0, 4.0))
        Y = _random_scaled_spd(rng, M, n, scale)
        P = np.einsum("ji,jab->iab", sys.T, Y)                     # D_i(Y) = sum_j p_ji Y_j
        G = _random_scaled_spd(rng, M if mode_dependent else 1, n,
                               float(np.trace(P.mean(axis=0)) / n))
    G = np.broadcast_to(G, P.shape)
    corner = G + transpose(G) - (0 if mutant else P)
    blocks = np.block([[Y - mu[:, None, None] * HHt, Acl @ G], [transpose(Acl @ G), corner]])
    bmi_margin = min_eig(blocks)
    D, E = performance_output(sys)
    DE = D + E @ L @ sys.C
    objective = trace_sum(DE @ P, transpose(DE))
    inner = Acl @ P @ transpose(Acl) + mu[:, None, None] * HHt
    constraint_margin = min_eig(P - np.einsum("ij,iab->jab", sys.T, inner))   # (3.14) with P = D(Y)
    rho = moment_map_radius(Acl, sys.T)
    h2 = (trace_sum(DE @ steady_state_second_moment(Acl, HHt, sys.T, mu),
                    transpose(DE)) if rho < 1 else np.inf)
    numbers = dict(bmi_margin=bmi_margin, constraint_3_14_margin=constraint_margin, rho=rho,
                   objective=objective, h2_norm_squared=h2)
    if not bmi_margin > 0:
        return outcome("not_applicable", sys, **numbers)
    holds = constraint_margin > 0 and rho < 1 and objective >= h2 * (1 - 1e-9)
    return outcome(verdict(holds), sys, **numbers)


def check_3_8(rng, mutant=False):
    """Lemma 3.8: a point satisfying the BMI (3.15) gives a stabilising L (one L)."""
    return _lemma_bmi(rng, False, mutant)


def check_3_11(rng, mutant=False):
    """Lemma 3.11: a point satisfying the BMI gives stabilising gains (mode-dependent L_i)."""
    return _lemma_bmi(rng, True, mutant)


def check_3_9(rng, mutant=False):
    """Thm. 3.9: LMIs feasible (verified certificate) -> L = F M^{-1} stabilises; also records SOF
    stabilisability (search). Mutant: the gain recovered with a sign error, L = -F M^{-1}.
    """
    return decide_3_9(draw_system(rng, siso=True, families=("thesis_like", "unstable", "stable")),
                      mutant=mutant)


def decide_3_9(sys, mu=None, mutant=False):
    """Thm. 3.9 on one SISO system. ``mu``: the mode weights of the noise term mu_i H_i H_i^T in the
    LMIs (default the stationary distribution, as printed); another ``mu`` is imposed through the
    equivalent noise H_i sqrt(mu_i / mu_inf_i), since ``static_output_lmi`` uses mu_inf.
    """
    if mu is not None:
        sys = sys.replace(H=sys.H * np.sqrt(np.asarray(mu) / sys.mu_inf)[:, None, None])
    lmi = static_output_lmi(sys)
    L_best, rho_best = best_scalar_gain(sys)
    numbers = dict(lmi_feasible=lmi.feasible, lmi_status=lmi.status, lmi_margin=lmi.margin,
                   sof_stabilisable=rho_best < 1, min_rho_over_L=rho_best, best_L=L_best)
    if not lmi.feasible:
        return outcome("not_applicable", sys, **numbers)
    gain = -lmi.L if mutant else lmi.L
    rho = moment_map_radius(closed_loop(sys, gain), sys.T)
    if not rho < 1:
        numbers["failure_kind"] = _failure_kind(sys, lmi, gain)
    return outcome(verdict(rho < 1), sys, lmi_L=np.ravel(gain), rho_of_lmi_gain=rho, **numbers)


def _failure_kind(sys, lmi, gain):
    """Why a certified-feasible LMI gives a non-stabilising gain: "counterexample" when the
    recovered gain with the solver's G, Y satisfies Lemma 3.8's BMI (the proof's chain holds, yet
    the gain does not stabilise), "numerical failure" when it does not (the recovery L = F M^{-1}
    broke the chain M C_i = C_i G).
    """
    G, Y = lmi.variables["G"], np.stack(lmi.variables["Y"])
    G = np.stack(G) if len(G) == sys.M else np.broadcast_to(G[0], Y.shape)
    Acl = sys.A + sys.B @ gain @ sys.C
    P = np.einsum("ji,jab->iab", sys.T, Y)
    HHt = sys.H @ transpose(sys.H)
    blocks = np.block([[Y - sys.mu_inf[:, None, None] * HHt, Acl @ G],
                       [transpose(Acl @ G), G + transpose(G) - P]])
    return "counterexample" if min_eig(blocks) > 0 else "numerical failure"


def check_3_12(rng, mutant=False):
    """Thm. 3.12: LMIs (mode observed) feasible -> L_i = F_i M_i^{-1} stabilise the mode-observed
    loop. Mutant: the gains recovered with a sign error, L_i = -F_i M_i^{-1}.
    """
    sys = draw_system(rng, max_states=2)
    lmi = static_output_lmi(sys, mode_observed=True)
    if not lmi.feasible:
        return outcome("not_applicable", sys, lmi_feasible=False, lmi_status=lmi.status,
                       lmi_margin=lmi.margin)
    gains = -lmi.L if mutant else lmi.L
    rho = moment_map_radius(sys.A + sys.B @ gains @ sys.C, sys.T)
    kind = {} if rho < 1 else {"failure_kind": _failure_kind(sys, lmi, gains)}
    return outcome(verdict(rho < 1), sys, lmi_feasible=True, lmi_margin=lmi.margin,
                   rho_of_lmi_gains=rho, **kind)


def summarise_lmi(outcomes):
    """Conservatism of Thm. 3.9: the share of SOF-stabilisable instances whose LMIs are feasible."""
    stabilisable = [o for o in outcomes if o.numbers.get("sof_stabilisable")]
    certified = [o for o in stabilisable if o.numbers.get("lmi_feasible")]
    return {"sof_stabilisable": len(stabilisable), "certified_by_lmi": len(certified),
            "lmi_feasible": sum(bool(o.numbers.get("lmi_feasible")) for o in outcomes)}


MARGIN_SOLVERS = ("CLARABEL", "SCS")
MARGIN_AGREEMENT = 1e-4       # two solvers' optimal margins agree to this (SCS is first order)


def lmi_margin(sys, solver="CLARABEL"):
    """The optimal margin of Thm. 3.9's LMIs without the noise term and the objective's LMI: the
    largest t with [[Y_i, A_i G + B_i F C_i], [., G + G^T - D_i(Y)]] >= t I, Y_i >= t I, G >= t I, M
    >= t I, M C_i = C_i G, normalised by tr G + sum_i tr Y_i = 1. These LMIs are homogeneous and
    implied by the printed ones (dropping mu_i H_i H_i^T >= 0 only enlarges the corner), so a
    negative optimal margin certifies that the printed LMIs are infeasible for every eps > 0.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> lmi_margin(sec354_system(1)) < 0                    # C1 = [1 2], C2 = [2 1]
    True
    >>> stable = sec354_system(1).replace(A=0.1 * sec354_system(1).A)
    >>> lmi_margin(stable) > 0
    True
    """
    nx, ny, nu = sys.nx, sys.ny, sys.nu
    t = cp.Variable()
    F = cp.Variable((nu, ny))
    G, Mv = cp.Variable((nx, nx), symmetric=True), cp.Variable((ny, ny), symmetric=True)
    Y = [cp.Variable((nx, nx), symmetric=True) for _ in range(sys.M)]
    cons = [G >> t * np.eye(nx), Mv >> t * np.eye(ny),
            cp.trace(G) + sum(cp.trace(Yi) for Yi in Y) == 1]
    for i in range(sys.M):
        DY = sum(sys.T[j, i] * Y[j] for j in range(sys.M))
        mid = sys.A[i] @ G + sys.B[i] @ F @ sys.C[i]
        block = cp.bmat([[Y[i], mid], [mid.T, 2 * G - DY]])
        cons += [0.5 * (block + block.T) >> t * np.eye(2 * nx), Y[i] >> t * np.eye(nx),
                 Mv @ sys.C[i] == sys.C[i] @ G]
    problem = cp.Problem(cp.Maximize(t), cons)
    status = solve_quietly(problem, solver)
    if status != cp.OPTIMAL:
        raise RuntimeError(f"lmi_margin: {solver} returned {status!r}, not an optimal margin")
    return float(t.value)


def certified_margins(sys):
    """:func:`lmi_margin` by each of :data:`MARGIN_SOLVERS` and the verdict: "infeasible" when all
    are negative beyond :data:`MARGIN_AGREEMENT` and agree to it, "feasible" when all are positive
    beyond it, else "undecided".
    """
    margins = {solver: lmi_margin(sys, solver) for solver in MARGIN_SOLVERS}
    values = np.array(list(margins.values()))
    agree = np.ptp(values) <= MARGIN_AGREEMENT
    verdict = ("infeasible" if agree and values.max() < -MARGIN_AGREEMENT else
               "feasible" if agree and values.min() > MARGIN_AGREEMENT else "undecided")
    return {"margins": margins, "verdict": verdict}


def lmi_C12_margin():
    """:func:`certified_margins` for the example of Sec. 3.5.4 with C1 = [1 2], C2 = [2 1], per T:
    the thesis says Thm. 3.9's LMIs are feasible there (``sec3_5.lmi_C12_T1``, ``_T2``).
    """
    return {f"T{t}": certified_margins(sec354_system(t, "C1=[1 2], C2=[2 1]")) for t in (1, 2)}
