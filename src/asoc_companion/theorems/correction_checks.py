"""The random-instance checks of the corrected statements (Sec. 2.6.3, Thm. 3.19 - 3.33).

Each ``check_*`` draws one instance from the theorems study's families with the ``rng`` it is
given and returns the verdict of the corrected statement, that of its mutant (a deliberately
wrong variant), and, where the diagnosis needs it, a third entry.
:mod:`asoc_companion.theorems.corrections` runs them and writes the records.
"""

import warnings

import numpy as np
import scipy.linalg

from asoc import gp
from asoc.mjls import (
    augmented_closed_loop,
    dynamic_output_feedback,
    finite_horizon_cost,
    finite_horizon_dynamic_output_feedback,
    ms_spectral_radius,
    static_output_feedback,
    steady_state_cost,
    successor_average,
)

from . import bounds
from .counterexamples import mcvmd_integral, printed_closed_form
from .instances import draw_system, random_spd_stack, rescaled

__all__ = ["EIG_TOL", "COST_RTOL", "SPREAD", "check_kernels", "SINGULAR_NOISE_SHARE",
           "check_3_19", "check_3_26", "check_3_27", "check_3_31", "check_3_32", "check_3_33"]

# smallest eigenvalue of a gap, relative to the matrix scale
EIG_TOL = 1e-9
# two exact costs agree (both from coupled Lyapunov solves)
COST_RTOL = 1e-6


def _min_eig(S):
    return float(np.min(np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))))


# ------------------------------------------------------------------ Sec. 2.6.3: kernels

def _bhattacharyya(m, s):
    """BC = int sqrt(p_i p_j) of 1-D Gaussians N(m_i, s_i^2), as a matrix."""
    v = s[:, None] ** 2 + s[None, :] ** 2
    return np.minimum(np.sqrt(2 * s[:, None] * s[None, :] / v)
                      * np.exp(-(m[:, None] - m[None, :]) ** 2 / (4 * v)), 1.0)


def _l2_gaussians(m, s):
    """||p_i - p_j||_2 of 1-D Gaussian densities (closed form)."""
    v = s[:, None] ** 2 + s[None, :] ** 2
    cross = np.exp(-(m[:, None] - m[None, :]) ** 2 / (2 * v)) / np.sqrt(2 * np.pi * v)
    own = 1 / (2 * np.sqrt(np.pi) * s)
    return np.sqrt(np.maximum(own[:, None] + own[None, :] - 2 * cross, 0.0))


SPREAD = 100.0          # spread-out Dirac sets: means on [0, 4 SPREAD], beyond 2 b_max of gp.mcvmd


def _gram_verdict(D, name, relative_scale, reference=None):
    """(verdict, lowest eigenvalue) of the Gram matrix at relative_scale times the median of the
    positive distances of ``reference`` (default ``D``).
    """
    reference = D if reference is None else reference
    gram = gp.COVARIANCES[name](D, relative_scale * np.median(reference[reference > 0]))
    lowest = _min_eig(gram)
    return ("holds" if lowest >= -EIG_TOL * len(D) else "fails"), lowest


def check_kernels(rng):
    """Corrected Sec. 2.6.3 on 3-7 random 1-D Gaussians: a Hilbert-embeddable distance (usual
    Hellinger, L2, mCvMd of 3-point Dirac approximations: the closed form within 2 b_max, or the
    definition on sets spread over about 4 SPREAD) under a random covariance of Table 2.1 gives a
    PSD Gram matrix; the mutant uses the printed Hellinger (1 - BC)^2 at the same length-scale rule.
    Third entry, on the spread sets only: (verdict, lowest eigenvalue) of the closed form with b_max
    = 100 (``gp.mcvmd``), which the corrected statement excludes.
    """
    n = int(rng.integers(3, 8))
    m, s = np.sort(rng.uniform(0.0, 4.0, n)), rng.uniform(0.5, 1.5, n)
    kind = ("hellinger", "l2", "mcvmd", "mcvmd_spread")[rng.integers(4)]
    name = sorted(gp.COVARIANCES)[rng.integers(len(gp.COVARIANCES))]
    relative_scale = np.exp(rng.uniform(np.log(0.1), np.log(3.0)))   # below 0.1 the Gram is ~ I
    bc = _bhattacharyya(m, s)
    closed_form = None
    if kind == "hellinger":
        D = np.sqrt(1 - bc)
    elif kind == "l2":
        D = _l2_gaussians(m, s)
    else:
        scale = SPREAD if kind == "mcvmd_spread" else 1.0
        points = [scale * (mi + si * np.array([-1.0, 0.0, 1.0])) for mi, si in zip(m, s)]
        pairwise = lambda distance: np.array([[distance(a, b) for b in points] for a in points])
        if kind == "mcvmd_spread":
            D, closed = pairwise(mcvmd_integral), pairwise(printed_closed_form)
            closed_form = _gram_verdict(closed, name, relative_scale, reference=D)
        else:
            D = pairwise(lambda a, b: gp.mcvmd(a, None, b, None))
    verdicts = [_gram_verdict(distance, name, relative_scale)[0] for distance in (D, (1 - bc) ** 2)]
    return (*verdicts, closed_form)


# ------------------------------------------------------------------ Thm. 3.19: Alg. 3.1

SINGULAR_NOISE_SHARE = 0.25    # share of the corrected Thm. 3.19's draws with H = 0 (not covered)


def check_3_19(rng):
    """Corrected Thm. 3.19 (M = 1, C = I, H H^T > 0): Alg. 3.1 converges to the LQ gain of the
    Riccati equation. Premise: the DARE has a stabilising solution (Q > 0). Mutant: the limit is the
    LQ gain for 2 R. A quarter of the draws have H = 0: the hypothesis excludes them
    (``not_applicable``), and the third entry says whether Alg. 3.1 still reached the LQ gain there
    (None on the others).
    """
    singular = rng.random() < SINGULAR_NOISE_SHARE
    sys = draw_system(rng, max_modes=1)
    sys = sys.replace(C=np.eye(sys.nx)[None], J=None, H=0 * sys.H if singular else sys.H)
    A, B, Q, R = sys.A[0], sys.B[0], sys.Q[0], sys.R[0]

    def lq_gain(weight):
        P = scipy.linalg.solve_discrete_are(A, B, Q, weight)
        return -np.linalg.solve(weight + B.T @ P @ B, B.T @ P @ A)

    try:
        gains = lq_gain(R), lq_gain(2 * R)
    except (np.linalg.LinAlgError, ValueError):
        return "not_applicable", "not_applicable", None
    with warnings.catch_warnings():                  # H = 0 drives the moments' scales to overflow
        warnings.simplefilter("ignore", RuntimeWarning)
        run = static_output_feedback(sys, warn=False, moments="step")
    L = np.asarray(run.L).reshape(gains[0].shape)
    agree = lambda G: (run.converged and run.stabilizing
                       and np.abs(L - G).max() <= 1e-6 * (1 + np.abs(G).max()))
    verdicts = ("holds" if agree(gains[0]) else "fails"), ("holds" if agree(gains[1]) else "fails")
    if singular:
        return "not_applicable", "not_applicable", verdicts[0]
    return (*verdicts, None)


# ------------------------------------------------------------------ Prop. 3.26

def _stabilised_loop(rng, sys):
    """Random (F, K, L) and the system rescaled: the augmented loop's rho uniform in [0.2, 0.85]."""
    F = 0.5 * rng.standard_normal((sys.nx, sys.nx))
    K = 0.5 * rng.standard_normal((sys.nx, sys.ny))
    L = 0.5 * rng.standard_normal((sys.nu, sys.nx))
    rho = ms_spectral_radius(augmented_closed_loop(sys, F, K, L)[0], sys.T)
    c = float(np.sqrt(rng.uniform(0.2, 0.85) / rho))
    return rescaled(sys, c), c * F, c * K, L


def check_3_26(rng, with_sign=False):
    """Corrected Prop. 3.26: X~ <= 2 [[Xbar + X2, X2], [X2, X2]] and P~ <= 2 [[Pbar + P2, -P2],
    [-P2, P2]] (Pbar = P1 + P12 + P12^T + P2) for the exact X~_inf, P~_inf of a random stabilising
    (F, K, L). Mutant: factor 1 (the printed bound). ``with_sign`` adds the P-bound with the printed
    sign and factor 2.
    """
    sys, F, K, L = _stabilised_loop(rng, draw_system(rng))
    _, X, _ = steady_state_cost(sys, F, K, L)
    At, _, Qt = augmented_closed_loop(sys, F, K, L)
    P = bounds.costate(At, Qt, sys.T)
    gap = lambda bound, Z: _min_eig(bound - Z) / np.abs(Z).max()
    ok = lambda factor, sign=1.0: min(gap(bounds.moment_bound(X, factor), X),
                                      gap(bounds.costate_bound(P, factor, sign), P)) >= -EIG_TOL
    verdicts = ("holds" if ok(2.0) else "fails"), ("holds" if ok(1.0) else "fails")
    if with_sign:
        sign_gap = gap(bounds.costate_bound(P, 2.0, -1.0), P)
        return verdicts + ("holds" if sign_gap >= -EIG_TOL else "fails",)
    return verdicts


# ------------------------------------------------------------------ Thm. 3.27: M = 1

def _lqg(sys, r_factor=1.0):
    """The LQG controller (3.37) of a one-mode system: F = A + B L - K C, K the Kalman predictor
    gain, L the LQ gain (for r_factor R).
    """
    A, B, C, H, Q, R = sys.A[0], sys.B[0], sys.C[0], sys.H[0], sys.Q[0], r_factor * sys.R[0]
    JJt = sys.J[0] @ sys.J[0].T
    Xf = scipy.linalg.solve_discrete_are(A.T, C.T, H @ H.T, JJt)
    K = A @ Xf @ C.T @ np.linalg.inv(C @ Xf @ C.T + JJt)
    P = scipy.linalg.solve_discrete_are(A, B, Q, R)
    L = -np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    return A + B @ L - K @ C, K, L


def check_3_27(rng):
    """Corrected Thm. 3.27 (M = 1): the converged, stabilising solution of Alg. 3.2 has the exact
    cost of the LQG controller. Mutant: compared with the LQG controller for 2 R.
    """
    sys = draw_system(rng, max_states=2, max_modes=1)
    run = dynamic_output_feedback(sys, max_iter=3000, warn=False)
    if not (run.converged and run.stabilizing):
        return "not_applicable", "not_applicable"
    try:
        costs = [steady_state_cost(sys, *_lqg(sys, f))[0] for f in (1.0, 2.0)]
    except (np.linalg.LinAlgError, ValueError):
        return "not_applicable", "not_applicable"
    return tuple("holds" if abs(run.cost - c) <= COST_RTOL * c else "fails" for c in costs)


# ------------------------------------------------------------------ Thm. 3.31

def _finite_instance(rng):
    sys = draw_system(rng)
    horizon = int(rng.integers(2, 9))
    F = 0.5 * rng.standard_normal((horizon, sys.nx, sys.nx))
    K = 0.5 * rng.standard_normal((horizon, sys.nx, sys.ny))
    L = 0.5 * rng.standard_normal((horizon, sys.nu, sys.nx))
    mu0 = rng.dirichlet(np.ones(sys.M))
    mean0, cov0 = rng.standard_normal((sys.M, sys.nx)), random_spd_stack(rng, sys.M, sys.nx, 0.2)
    return sys, horizon, F, K, L, mu0, mean0, cov0


def check_3_31(rng):
    """Corrected Thm. 3.31: J_0 <= the doubled forward bound (random gains or Alg. 3.3's, horizons
    2-8). Mutant: factor 1 (the printed recursions (3.66)-(3.67) summed forward). Third entry: bound
    / J_0.
    """
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    if rng.random() < 0.5:
        run = finite_horizon_dynamic_output_feedback(sys, horizon=horizon, mean0=mean0, cov0=cov0,
                                                     mu0=mu0, init=(F, K, L), max_iter=100,
                                                     warn=False)
        F, K, L = run.F, run.K, run.L
    xhat0 = mu0 @ mean0
    exact = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0)
    bound = lambda factor: bounds.forward_bound(sys, F, K, L, mean0, cov0, mu0, xhat0, factor)
    doubled = bound(2.0)
    verdict = lambda b: "holds" if exact <= b * (1 + 1e-9) else "fails"
    return verdict(doubled), verdict(bound(1.0)), doubled / exact


# ------------------------------------------------------------------ Thm. 3.32

def check_3_32(rng):
    """Corrected Thm. 3.32: the solution of (3.70) minimises (B.4) (symmetric differences vanish and
    random perturbations do not lower it). Mutant: (B.4) with the factor 2 of 2 E(Pbar + Pu) B L Xu
    A^T dropped. Third entry: relative error of (3.65) - (B.4) = sum_i tr[(Z12 + Z21 + 2 Z22)
    Xbar_i].
    """
    sys = draw_system(rng)
    M, n = sys.M, sys.nx
    Xbar, Xunder = random_spd_stack(rng, M, n), random_spd_stack(rng, M, n)
    EPbar = successor_average(sys.T, random_spd_stack(rng, M, n))
    EPunder = successor_average(sys.T, random_spd_stack(rng, M, n))
    mu = rng.dirichlet(np.ones(M))
    H, rho = bounds.optimality_conditions(sys, Xbar, Xunder, EPbar, EPunder, mu)
    z = np.linalg.lstsq(H, -rho, rcond=None)[0]
    data = (Xbar, Xunder, EPbar, EPunder, mu)
    steps = [scale * rng.standard_normal(z.size) for scale in (1e-3, 1e-1, 1.0) for _ in range(3)]

    def verdict(cross):
        f = lambda v: bounds.functional_b4(sys, *bounds.split(v, sys), *data, cross=cross)
        base = f(z)
        ok = all(abs(f(z + d) - f(z - d)) <= 1e-9 * (abs(base) + abs(f(z + d) - base))
                 and f(z + d) >= base - 1e-9 * abs(base) for d in steps)
        return "holds" if ok else "fails"

    F, K, L = bounds.split(z, sys)
    printed = bounds.bound_3_65(sys, F, K, L, *data)
    expanded = bounds.functional_b4(sys, F, K, L, *data)
    difference = bounds.difference_3_65_b4(sys, F, K, L, Xbar, EPbar, EPunder)
    identity = abs(printed - expanded - difference) / abs(printed)
    return verdict(2.0), verdict(1.0), identity


# ------------------------------------------------------------------ Thm. 3.33

def check_3_33(rng):
    """Alg. 3.3 from random gains, with the Step 5 safeguard and with the literal Step 5
    (safeguard=False): whether Jbar_0 increases (beyond 1e-8 relative) anywhere, and the largest
    relative increase.
    """
    sys = draw_system(rng, max_states=2, max_modes=2)
    horizon = int(rng.integers(2, 9))
    mu0 = rng.dirichlet(np.ones(sys.M))
    mean0, cov0 = rng.standard_normal((sys.M, sys.nx)), random_spd_stack(rng, sys.M, sys.nx, 0.2)
    seed = int(rng.integers(2**32))
    out = []
    for safeguard in (True, False):
        try:
            run = finite_horizon_dynamic_output_feedback(sys, horizon=horizon, mean0=mean0,
                                                         cov0=cov0, mu0=mu0,
                                                         init=np.random.default_rng(seed),
                                                         max_iter=300, safeguard=safeguard,
                                                         warn=False)
        except (ValueError, np.linalg.LinAlgError):        # the iterates blew up (literal Step 5)
            out.append(np.inf)
            continue
        b = np.asarray(run.cost_bounds)
        rise = np.diff(b) / np.maximum(1.0, np.abs(b[1:]))
        out.append(float(rise.max()) if rise.size else 0.0)
    return out
