"""The smallest counterexamples of the failing statements, in closed form where one exists.

Each function recomputes its counterexample from the printed equations: exactly in
``fractions.Fraction`` where the data are rational (Prop. 3.26, Thm. 3.31), to rounding
otherwise (Thm. 3.19, the kernels of Sec. 2.6.3), or from the study's own instance (the two fixed
points of Alg. 3.2 behind Thm. 3.27). The notebook re-runs them.
"""

import warnings
from fractions import Fraction

import numpy as np
import scipy.linalg
import scipy.special

from asoc import gp
from asoc.gp.cramer_von_mises import DEFAULT_B_MAX
from asoc.mjls import MJLS, dynamic_output_feedback, static_output_feedback, successor_average
from asoc.mjls.closed_loops import noise_covariances
from asoc.mjls.moment_bounds import bound_costate_step, bound_moment_step
from asoc.mjls.optimality import optimality_system

from .instances import draw_system

__all__ = ["prop_3_26_example", "thm_3_31_example", "THM_3_19_SYSTEM", "thm_3_19_example",
           "THM_3_19_NOISELESS", "thm_3_19_noiseless_example", "kernel_example",
           "THM_3_27_INSTANCE", "thm_3_27_fixed_points", "mcvmd_integral", "printed_closed_form"]


# ------------------------------------------------------------------ exact 2 x 2 algebra


def _mul(X, Y):
    return [[sum(X[i][k] * Y[k][j] for k in range(len(Y))) for j in range(len(Y[0]))]
            for i in range(len(X))]


def _tr(X):
    return X[0][0] + X[1][1]


def _add(*Xs):
    return [[sum(X[i][j] for X in Xs) for j in range(2)] for i in range(2)]


def _transpose(X):
    return [list(row) for row in zip(*X)]


def _congruence(A, X):
    """A X A^T."""
    return _mul(_mul(A, X), _transpose(A))


def prop_3_26_example():
    """Prop. 3.26 on one state, x_{k+1} = w_k, x^_{k+1} = x_k
    (F = 0, K = 1, L = 0, A = 0, C = H = 1).

    The augmented loop A~ = [[0, 0], [1, 0]] is nilpotent, so X~ = A~ X~ A~^T + diag(1, 0) is
    reached exactly after two steps. Returns the stationary X~, the printed bound and the corrected
    bound (factor 2), each minus X~, with the determinant of the 2 x 2 gap (a PSD 2 x 2 matrix has
    non-negative determinant and diagonal).

    Examples
    --------
    >>> ex = prop_3_26_example()
    >>> ex["printed_gap"], ex["printed_gap_determinant"]
    ([[Fraction(2, 1), Fraction(1, 1)], [Fraction(1, 1), Fraction(0, 1)]], Fraction(-1, 1))
    >>> ex["corrected_gap_determinant"] > 0
    True
    """
    At = [[Fraction(0), Fraction(0)], [Fraction(1), Fraction(0)]]
    noise = [[Fraction(1), Fraction(0)], [Fraction(0), Fraction(0)]]
    X = [[Fraction(0)] * 2 for _ in range(2)]
    # a fixed point after two steps
    for _ in range(3):
        X = _add(_congruence(At, X), noise)
    assert X == _add(_congruence(At, X), noise)
    (x1, x12), (_, x2) = X
    xbar = x1 - 2 * x12 + x2
    bound = [[xbar + x2, x2], [x2, x2]]
    gap = lambda factor: [[factor * bound[i][j] - X[i][j] for j in range(2)] for i in range(2)]
    det = lambda G: G[0][0] * G[1][1] - G[0][1] * G[1][0]
    return {"X": X, "printed_gap": gap(1), "printed_gap_determinant": det(gap(1)),
            "corrected_gap": gap(2), "corrected_gap_determinant": det(gap(2))}


def thm_3_31_example(gain=Fraction(-1, 4)):
    """Thm. 3.31 on one mode, one state, no noise: a = b = c = q = r = 1, x_0 ~ N(0, 1), x^_0 = 0,
    F = K = 0, u = l x^, horizon 1. Returns the exact cost J_0 (Lemma 3.29 / (3.62)) and the bound
    Jbar_0 (3.65) with (3.68)-(3.69), in fractions, and the off-diagonal entry of the bound of (B.2)
    minus the exact P~_0, -l (2l + 1): the bound's lower-right block equals P~_0's, so a non-zero
    off-diagonal entry makes the difference indefinite.

    x^ stays 0, so J_0 = E{x_0^2} + E{x_1^2} = 2 for every l; Jbar_0 = 2 + 2l + 4l^2.

    Examples
    --------
    >>> ex = thm_3_31_example()
    >>> ex["exact"], ex["bound"], ex["costate_gap_offdiagonal"]
    (Fraction(2, 1), Fraction(7, 4), Fraction(1, 8))
    """
    a = b = c = q = r = Fraction(1)
    f = k = Fraction(0)
    l = Fraction(gain)
    At = [[a, b * l], [k * c, f]]
    X0 = [[Fraction(1), Fraction(0)], [Fraction(0), Fraction(0)]]      # x_0 ~ N(0, 1), x^_0 = 0
    Qt = [[q, Fraction(0)], [Fraction(0), l * r * l]]
    Q_final = [[q, Fraction(0)], [Fraction(0), Fraction(0)]]
    exact = _tr(_mul(Qt, X0)) + _tr(_mul(Q_final, _congruence(At, X0)))
    Pbar_next, Punder_next = q, Fraction(0)                           # Pbar_K = Q, Punder_K = 0
    g = a - f + b * l - k * c
    Pbar = q + l * r * l + (a + b * l) ** 2 * Pbar_next + g ** 2 * Punder_next          # (3.68)
    Punder = l * r * l + (b * l) ** 2 * Pbar_next + (f - b * l) ** 2 * Punder_next       # (3.69)
    xbar0, xunder0 = Fraction(1), Fraction(0)                         # E{(x_0 - x^_0)^2}, x^_0^2
    bound = Pbar * (xbar0 + xunder0) + Punder * xbar0                 # (3.65), no noise: omega = 0
    # P~_0 = Q~_0 + A~^T P~_1 A~ (3.64)
    P0 = _add(Qt, _mul(_mul(_transpose(At), Q_final), At))
    # off-diagonal of (B.2)'s bound - P~_0
    costate_gap = -Punder - P0[0][1]
    return {"exact": exact, "bound": bound, "gain": l, "costate_gap_offdiagonal": costate_gap}


# ------------------------------------------------------------------ Thm. 3.19: a period-2 cycle

# one mode, nx = 2: instance 79 of the study, rounded to one decimal
THM_3_19_SYSTEM = dict(
    A=[[1.3, 0.3], [-0.5, -0.4]], B=[[0.2], [1.1]], C=[[0.0, 1.9]], H=[[-0.1, -0.3], [0.1, 0.0]],
    Q=[[2.8, -1.2], [-1.2, 1.9]], R=[[1.4]])


def _alg_3_1_one_mode(A, B, C, H, Q, R, start, iterations=400):
    """The gains of Alg. 3.1 ((3.34)-(3.35), one mode, column-major vec) from X = P = start I."""
    A, B, C, H, Q, R = (np.asarray(v, dtype=float) for v in (A, B, C, H, Q, R))
    X = P = start * np.eye(len(A))
    gains = []
    for _ in range(iterations):
        lhs = np.kron(C @ X @ C.T, R + B.T @ P @ B)
        vec_L = -np.linalg.solve(lhs, (B.T @ P @ A @ X @ C.T).ravel(order="F"))
        L = vec_L.reshape(B.shape[1], C.shape[0], order="F")
        Acl = A + B @ L @ C
        X, P = Acl @ X @ Acl.T + H @ H.T, Acl.T @ P @ Acl + Q + C.T @ L.T @ R @ L @ C
        gains.append(L)
    return np.array(gains)


def thm_3_19_example(starts=(1e-4, 1.0, 10.0), grid=20001):
    """Alg. 3.1 on :data:`THM_3_19_SYSTEM` from X = P = s I: the last two gains (a period-2 cycle),
    the squared spectral radius rho(A + B L C)^2 (Cor. 3.2, one mode) at both, and the smallest
    rho^2 over a grid of scalar gains in [-5, 5] (a stabilising gain exists).

    Examples
    --------
    >>> ex = thm_3_19_example(starts=(1e-4,), grid=2001)
    >>> ex["cycles"][0]["period_2"], ex["best_rho"] < 1 < min(ex["cycles"][0]["rho"])
    (True, True)
    """
    s = THM_3_19_SYSTEM
    A, B, C = (np.asarray(s[k]) for k in "ABC")
    rho = lambda L: float(np.max(np.abs(np.linalg.eigvals(A + B @ np.atleast_2d(L) @ C))) ** 2)
    cycles = []
    for start in starts:
        gains = _alg_3_1_one_mode(**s, start=start)[:, 0, 0]
        period_2 = bool(np.isclose(gains[-1], gains[-3], rtol=1e-9)
                        and not np.isclose(gains[-1], gains[-2], rtol=1e-3))
        cycles.append({"start": start, "gains": sorted([float(gains[-1]), float(gains[-2])]),
                       "rho": sorted([rho(gains[-1]), rho(gains[-2])]), "period_2": period_2})
    candidates = np.linspace(-5.0, 5.0, grid)
    radii = [rho(L) for L in candidates]
    best = int(np.argmin(radii))
    return {"cycles": cycles, "best_gain": float(candidates[best]), "best_rho": float(radii[best])}


THM_3_19_NOISELESS = dict(A=[[0.3364, 0.1107], [-1.3845, -0.4556]],   # issue 30's example
                          B=[[0.8825], [0.5804]])


def thm_3_19_noiseless_example():
    """Alg. 3.1 with state feedback (C = I, one mode) on :data:`THM_3_19_NOISELESS`, Q = I, R = 1,
    without noise (H = 0) and with H = 0.1 I: the library's status and gain against the LQ gain, and
    the smallest eigenvalue of X_1 = A X_0 A^T from X_0 = I (the first gain is 0 when P_0 = 0).

    Examples
    --------
    >>> ex = thm_3_19_noiseless_example()
    >>> ex["reaches_lq_gain"], ex["reaches_lq_gain_with_noise"], ex["min_eig_X1"] < 1e-6
    (False, True, True)
    """
    A, B = (np.array(THM_3_19_NOISELESS[k]) for k in "AB")
    Q, R = np.eye(2), np.eye(1)
    P = scipy.linalg.solve_discrete_are(A, B, Q, R)
    lq = -np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    runs = []
    for H in (np.zeros((2, 2)), 0.1 * np.eye(2)):
        sys = MJLS(A=A[None], B=B[None], C=np.eye(2)[None], H=H[None], Q=Q[None], R=R[None],
                   T=np.eye(1), J=None)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            run = static_output_feedback(sys, warn=False, moments="step", init=1.0)
        gap = np.abs(np.asarray(run.L).reshape(lq.shape) - lq).max()
        reached = bool(run.converged and gap <= 1e-6)
        runs.append((run.status, reached))
    return {"A": THM_3_19_NOISELESS["A"], "B": THM_3_19_NOISELESS["B"],
            "lq_gain": np.round(lq, 4).tolist(),
            "min_eig_X1": float(np.linalg.eigvalsh(A @ A.T).min()),
            "status": runs[0][0], "reaches_lq_gain": runs[0][1],
            "status_with_noise": runs[1][0], "reaches_lq_gain_with_noise": runs[1][1]}


# ------------------------------------------------------------------ Sec. 2.6.3: kernels

def kernel_example(length_scale=0.03):
    """N(0,1), N(1,1), N(2,1) with the printed Hellinger expression (1 - BC)^2 and the SE kernel:
    the smallest Gram eigenvalue (negative), and with the usual Hellinger sqrt(1 - BC) (not).

    Examples
    --------
    >>> ex = kernel_example()
    >>> round(ex["printed"], 3), ex["usual"] > -1e-12
    (-0.272, True)
    """
    means = [0.0, 1.0, 2.0]
    usual = np.array([[gp.hellinger_gaussian([a], [[1.0]], [b],
                                             [[1.0]]) for b in means] for a in means])
    lowest = lambda D: float(np.linalg.eigvalsh(gp.squared_exponential(D, length_scale))[0])
    return {"printed": lowest(usual ** 4), "usual": lowest(usual), "length_scale": length_scale}


# ------------------------------------------------------------------ Thm. 3.27: two fixed points

THM_3_27_INSTANCE = 13     # the study's saved counterexample of Thm. 3.27 (seed 2017): M = 2


def _fixed_point_residuals(sys, run):
    """How well Alg. 3.2's last iterate solves (3.45)-(3.49): the largest relative change of Xbar,
    Xu, Pbar, Pu under one more step (3.45)-(3.48) with the iterate's gains, the relative residual
    ||H z + rho|| / ||rho|| of (3.49) (z = [vec F; vec K; vec L], column-stacking), and the smallest
    eigenvalues of Xu and Pu (both invertible where positive).
    """
    Xbar, Xunder, Pbar, Punder = run.Xbar, run.Xunder, run.Pbar, run.Punder
    HHt, JJt = noise_covariances(sys)
    EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
    step = (*bound_moment_step(sys, run.F, run.K, run.L, Xbar, Xunder, sys.mu_inf, HHt, JJt),
            *bound_costate_step(sys, run.F, run.K, run.L, EPbar, EPunder))
    change = max(np.abs(new - old).max() / np.abs(old).max()
                 for new, old in zip(step, (Xbar, Xunder, Pbar, Punder)))
    H, rho = optimality_system(sys, Xbar, Xunder, EPbar, EPunder, sys.mu_inf, JJt)
    z = np.concatenate([np.ravel(G, order="F") for G in (run.F, run.K, run.L)])
    return {"residual_3_45_3_48": float(change),
            "residual_3_49": float(np.linalg.norm(H @ z + rho) / np.linalg.norm(rho)),
            "min_eig_Xu": float(np.linalg.eigvalsh(Xunder).min()),
            "min_eig_Pu": float(np.linalg.eigvalsh(Punder).min())}


def thm_3_27_fixed_points(seed=2017, index=THM_3_27_INSTANCE, random_starts=10, tol=1e-14):
    """Alg. 3.2 on instance ``index`` of the study's Thm. 3.27 (drawn as the study draws it) from
    the author's start 1e-4 I and from ``random_starts`` random SPD starts of scale 1 (seeds 0, 1,
    ...): the distinct converged, stabilising fixed points (costs equal to 1e-9 relative merged),
    each with its exact cost (3.42), how many starts reach it, its gains and
    ``_fixed_point_residuals``.

    Examples
    --------
    >>> ex = thm_3_27_fixed_points(random_starts=2)
    >>> (ex["M"], ex["nx"], ex["nu"], ex["ny"]), len(ex["fixed_points"])
    ((2, 1, 2, 1), 2)
    >>> [round(p["cost"], 3) for p in ex["fixed_points"]]
    [1.952, 2.424]
    """
    from .engine import instance_seed  # engine imports the statements, which import this

    rng = np.random.default_rng(instance_seed("statement_3_27", seed, index))
    sys = draw_system(rng, max_states=2, max_modes=2)
    starts = [("1e-4 I", dict(init=1e-4))] + [
        (f"random SPD, seed {s}", dict(init=1.0, rng=np.random.default_rng(s)))
        for s in range(random_starts)]
    points = []
    for name, kwargs in starts:
        run = dynamic_output_feedback(sys, tol=tol, max_iter=20000, warn=False, **kwargs)
        if not (run.converged and run.stabilizing):
            continue
        same = [p for p in points if abs(p["cost"] - run.cost) <= 1e-9 * run.cost]
        if same:
            same[0]["starts"].append(name)
            continue
        points.append({"cost": float(run.cost), "starts": [name], "F": run.F.tolist(),
                       "K": run.K.tolist(), "L": run.L.tolist(), "rho": float(run.rho),
                       **_fixed_point_residuals(sys, run)})
    return {"seed": seed, "index": index, "M": sys.M, "nx": sys.nx, "nu": sys.nu, "ny": sys.ny,
            "random_starts": random_starts, "fixed_points": sorted(points, key=lambda p: p["cost"])}


def mcvmd_integral(x, y, b_max=DEFAULT_B_MAX):
    r"""The mCvMd of two equally weighted 1-D Dirac sets from its definition, exactly,
    for finite ``b_max``.

    With the LCD kernel, :math:`\int (P_1 - P_2)^2 dm = \sqrt\pi\, b \sum_{kl} c_k c_l
    e^{-\Delta_{kl}^2/(4b^2)}` (``c``: the weights, those of ``y`` negative), and
    :math:`\int_0^{b_{\max}} b e^{-a/b^2} db = \tfrac12 (S e^{-a/S} - a E_1(a/S))`, :math:`S =
    b_{\max}^2`. Unlike the closed form of the thesis (``gp.mcvmd``, its large-``b_max`` expansion),
    this is an L2 distance for every ``b_max``.

    Examples
    --------
    >>> round(mcvmd_integral([0.0], [0.3], 10.0), 3)         # gp.mcvmd_quadrature: 0.593
    0.593
    >>> x, y = [0.0, 1.0], [300.0]
    >>> round(mcvmd_integral(x, y, 100.0), 1)          # the closed form refuses this b_max
    131.3
    >>> gp.mcvmd(x, None, y, None)
    Traceback (most recent call last):
    ...
    ValueError: b_max: expected a width large against the distances between the Dirac locations
    (the closed form holds for large b_max; its square is -0.017 of its terms), found 100.0
    """
    points = np.concatenate([np.ravel(x), np.ravel(y)])
    c = np.concatenate([np.full(np.size(x), 1 / np.size(x)), np.full(np.size(y), -1 / np.size(y))])
    a = (points[:, None] - points[None]) ** 2 / 4
    S = float(b_max) ** 2
    g = S * np.exp(-a / S) - a * scipy.special.exp1(np.maximum(a, 1e-300) / S)
    g[a == 0] = S
    return float(np.sqrt(max(np.sqrt(np.pi) / 2 * (c @ g @ c), 0.0)))


def printed_closed_form(a, b, b_max=DEFAULT_B_MAX):
    """The large-b_max closed form of the mCvMd (Sec. 2.6.3, item 5) of two equally weighted 1-D
    Dirac sets, its square clipped at 0: the formula itself, also where ``gp.mcvmd`` refuses it
    (a negative square, here on sets spread far beyond b_max).

    Examples
    --------
    >>> x, y = np.array([0.0, 1.0, 2.5]), np.array([-1.0, 0.3, 4.0])
    >>> bool(abs(printed_closed_form(x, y) - gp.mcvmd(x, None, y, None)) < 1e-12)
    True
    >>> printed_closed_form(np.array([0.0, 1.0]), np.array([300.0]))      # square < 0: clipped
    0.0
    """
    def xlog_mean(u, v):
        sq = (u[:, None] - v[None]) ** 2
        return float(np.mean(scipy.special.xlogy(sq, sq)))

    square = (xlog_mean(a, a) - 2 * xlog_mean(a, b) + xlog_mean(b, b)
              + 2 * gp.mcvmd_constant(b_max) * (a.mean() - b.mean()) ** 2)
    return float(np.sqrt(max(square, 0.0) * np.sqrt(np.pi) / 8))
