"""Infinite-horizon dynamic output feedback without mode observation (Sec. 3.6, Alg. 3.2).

The controller (3.37) is x^_{k+1} = F x^_k + K y_k, u_k = L x^_k with constant F, K, L.
With it the MJLS (3.36) forms the augmented closed loop (3.39)-(3.40) in x~ = [x; x^].
Alg. 3.2 does not minimise the true cost (3.42) but the bound of Prop. 3.26: the second
moment of x~ is replaced by the two blocks

    Xbar_i  ~ E{(x - x^)(x - x^)^T 1(theta = i)}   (estimation error, (3.44)),
    Xunder_i ~ E{x^ x^^T 1(theta = i)}              (controller state),

and the Lagrange multiplier by Pbar_i, Punder_i. The gains solve the linear system (3.49)
built from (3.50). The module also gives the augmented closed loop and its exact
second-moment recursion (Prop. 3.23), so the true cost of any controller can be set next
to the bound (Prop. 3.24).
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .moments import steady_state_second_moment
from .operators import augmented_closed_loop, check_gains, noise_covariances, spectral_radius  # noqa: F401 (public here)
from .system import predecessor_sum, successor_average

METHODS = ("lstsq", "sdp")
DIVERGED = 1e100          # bounds beyond this are treated as diverging (the iteration stops)
#: Relative singular-value threshold of the minimum-norm solution of (3.51) in Alg. 3.2. Its
#: matrix becomes singular at the fixed point when the controller state does not excite every
#: direction (Xunder of low numerical rank, e.g. ny << nx): the bound then leaves F undetermined
#: there. With LAPACK's default threshold (about 1e-13 at nx = 8) those directions receive
#: rounding noise divided by ~1e-17 and the iteration diverges (Scaling page, n = 8, 16);
#: a threshold of 1e-10 treats them as the null space they are.
RANK_RTOL = 1e-10


def _T(X):
    return np.swapaxes(X, -1, -2)


def steady_state_cost(sys, F, K, L):
    """True average cost (3.38) of (3.37): sum_i tr[Q~_i X~_inf^i] by Prop. 3.24.

    X~_inf solves the coupled Lyapunov equations of Prop. 3.23 with mu = mu_inf.

    Parameters
    ----------
    sys : MJLS
    F, K, L : array_like, shapes (nc, nc), (nc, ny), (nu, nc)
        Gains of the controller (3.37).

    Returns
    -------
    cost : float
        inf when the closed loop is not mean-square stable (Cor. 3.2).
    X : numpy.ndarray, shape (M, nx + nc, nx + nc), or None
        X~_inf (None when not stable).
    rho : float
        Mean-square spectral radius of the augmented closed loop.

    Raises
    ------
    ValueError
        If a gain has the wrong shape or non-finite entries.
    """
    At, HHt_cl, Qt = augmented_closed_loop(sys, F, K, L)
    rho = spectral_radius(At, sys.T)
    if not rho < 1:
        return np.inf, None, rho
    X = steady_state_second_moment(At, HHt_cl, sys.T, sys.mu_inf)
    return float(np.einsum("iab,iba->", Qt, X)), X, rho


def bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt):
    """One step of the second-moment bounds, (3.45)-(3.46) / (3.66)-(3.67).

    Returns (Xbar_next, Xunder_next), each (M, nx, nx).
    """
    KC = K @ sys.C
    AKC = sys.A - KC
    G = AKC - F + sys.B @ L                       # A_i - F + B_i L - K C_i
    FKC = F + KC
    KJJK = K @ JJt @ K.T
    m = mu[:, None, None]
    Xbar_in = m * (HHt + KJJK) + AKC @ Xbar @ _T(AKC) + G @ Xunder @ _T(G)
    Xunder_in = m * KJJK + KC @ Xbar @ _T(KC) + FKC @ Xunder @ _T(FKC)
    Xbar_new, Xunder_new = predecessor_sum(sys.T, Xbar_in), predecessor_sum(sys.T, Xunder_in)
    return 0.5 * (Xbar_new + _T(Xbar_new)), 0.5 * (Xunder_new + _T(Xunder_new))


def bound_costate_step(sys, F, K, L, EPbar, EPunder):
    """One step of the multiplier bounds, (3.47)-(3.48) / (3.68)-(3.69).

    ``EPbar``, ``EPunder`` are E_i(Pbar), E_i(Punder) of the next step. Returns (Pbar, Punder).
    """
    BL = sys.B @ L
    ABL = sys.A + BL
    G = ABL - F - K @ sys.C
    FBL = F - BL
    LRL = L.T @ sys.R @ L
    Pbar = sys.Q + LRL + _T(ABL) @ EPbar @ ABL + _T(G) @ EPunder @ G
    Punder = LRL + _T(BL) @ EPbar @ BL + _T(FBL) @ EPunder @ FBL
    return 0.5 * (Pbar + _T(Pbar)), 0.5 * (Punder + _T(Punder))


def _kron_sum(X, Y):
    """sum_i X_i (x) Y_i for stacks X (M, a, b), Y (M, c, d)."""
    M, a, b = X.shape
    _, c, d = Y.shape
    return np.einsum("iab,icd->acbd", X, Y).reshape(a * c, b * d)


def optimality_system(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
    """The matrix and vector of (3.49)/(3.70), built from (3.50).

    Unknown z = [vec F; vec K; vec L] (column-stacking vec); the conditions read H z + rho = 0.
    H is (half) the Hessian of the bounded cost (A.7)/(B.5), hence symmetric PSD.
    """
    A, B, C, R = sys.A, sys.B, sys.C, sys.R
    S = Xbar + Xunder
    EP = EPbar + EPunder
    m = mu[:, None, None]
    EPuB = EPunder @ B
    XuCt = Xunder @ _T(C)
    nF, nK = sys.nx * sys.nx, sys.nx * sys.ny
    blocks = ((slice(0, nF), slice(0, nF), _kron_sum(Xunder, EPunder)),                  # Phi_F
              (slice(nF, nF + nK), slice(nF, nF + nK), _kron_sum(m * JJt + C @ S @ _T(C), EPunder)),
              (slice(nF + nK, None), slice(nF + nK, None), _kron_sum(Xunder, R + _T(B) @ EP @ B)),
              (slice(0, nF), slice(nF, nF + nK), _kron_sum(XuCt, EPunder)),           # Gamma_FK
              (slice(0, nF), slice(nF + nK, None), -_kron_sum(Xunder, EPuB)),         # Gamma_FL
              (slice(nF, nF + nK), slice(nF + nK, None), -_kron_sum(_T(XuCt), EPuB)))  # Gamma_KL
    n_z = nF + nK + sys.nu * sys.nx
    H = np.empty((n_z, n_z))
    for rows, cols, block in blocks:
        H[rows, cols] = block
        H[cols, rows] = block.T
    rho = np.concatenate([
        -(EPunder @ A @ Xunder).sum(axis=0).reshape(-1, order="F"),
        -(EPunder @ A @ S @ _T(C)).sum(axis=0).reshape(-1, order="F"),
        (_T(B) @ EP @ A @ Xunder).sum(axis=0).reshape(-1, order="F")])
    return H, rho


def gains_from_bounds(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method="lstsq", rcond=None):
    """F, K, L solving (3.51)/(3.71).

    ``"lstsq"``: the minimum-norm least-squares solution, i.e. the quadratic program (3.73)
    (it also covers singular systems, e.g. Punder = 0 at the end of a finite horizon, where
    F and K do not enter the cost); ``"sdp"``: the SDP after Alg. 3.2 (min lambda with
    [[lambda I, G], [G^T, I]] >= 0, G = [F K L^T]) solved with cvxpy/Clarabel. ``rcond``:
    relative singular-value threshold of ``"lstsq"`` (None: LAPACK's eps * size).
    """
    n, ny, nu = sys.nx, sys.ny, sys.nu
    H, rho = optimality_system(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt)
    if method == "lstsq":
        z = np.linalg.lstsq(H, -rho, rcond=rcond)[0]
    elif method == "sdp":
        z = _gains_sdp(H, rho, n, ny, nu)
    else:
        raise ValueError(f"method must be one of {METHODS}, found {method!r}")
    F = z[:n * n].reshape(n, n, order="F")
    K = z[n * n:n * n + n * ny].reshape(n, ny, order="F")
    L = z[n * n + n * ny:].reshape(nu, n, order="F")
    return F, K, L


def _gains_sdp(H, rho, n, ny, nu):
    """The SDP recommended after Alg. 3.2: min lambda s.t. [[lambda I, G], [G^T, I]] >= 0, (3.49)."""
    import cvxpy as cp

    F, K, L = cp.Variable((n, n)), cp.Variable((n, ny)), cp.Variable((nu, n))
    lam = cp.Variable()
    z = cp.hstack([cp.vec(F, order="F"), cp.vec(K, order="F"), cp.vec(L, order="F")])
    G = cp.hstack([F, K, L.T])
    block = cp.bmat([[lam * np.eye(n), G], [G.T, np.eye(n + ny + nu)]])
    scale = max(1.0, float(np.abs(H).max()))
    prob = cp.Problem(cp.Minimize(lam), [0.5 * (block + block.T) >> 0, (H @ z + rho) / scale == 0])
    prob.solve(solver=cp.CLARABEL)
    if F.value is None:
        raise np.linalg.LinAlgError(f"SDP of Alg. 3.2 failed ((3.49) may be inconsistent when "
                                    f"singular; use method='lstsq'): {prob.status}")
    return np.concatenate([F.value.reshape(-1, order="F"), K.value.reshape(-1, order="F"),
                           L.value.reshape(-1, order="F")])


@dataclass
class DynamicOutputFeedbackResult:
    """Result of Algorithm 3.2 (:func:`dynamic_output_feedback`).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (nx, nx), (nx, ny), (nu, nx)
        The controller (3.37).
    converged : bool
    iterations : int
    rho : float
        Mean-square spectral radius of the augmented closed loop (3.39) (Cor. 3.2).
    stabilizing : bool
        rho < 1.
    cost : float
        True average cost (3.38) from Prop. 3.24 (inf if not stabilizing).
    bound : float
        sum_i tr[Q_i (Xbar_i + Xunder_i) + L^T R_i L Xunder_i], the cost of the bounded
        second moment of Prop. 3.26 that the algorithm minimises (not always an upper
        bound of ``cost``).
    Xbar, Xunder, Pbar, Punder : numpy.ndarray, shape (M, nx, nx)
        The last iterates.
    history : dict
        Traces of Xbar_i, Xunder_i, Pbar_i, Punder_i per iteration, each (iterations + 1, M).
    seconds : float
        Wall time.

    For :func:`asoc.mjls.exact_dynamic_output_feedback`: bound = nan, the four blocks None,
    and history["cost"] the exact cost per iteration.
    """

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    converged: bool
    iterations: int
    rho: float
    stabilizing: bool
    cost: float
    bound: float
    Xbar: np.ndarray
    Xunder: np.ndarray
    Pbar: np.ndarray
    Punder: np.ndarray
    history: dict = field(repr=False)
    seconds: float = 0.0


def _initial_bounds(sys, init, rng):
    M, n = sys.M, sys.nx
    if rng is None:
        return [np.broadcast_to(init * np.eye(n), (M, n, n)).copy() for _ in range(4)]
    if not isinstance(rng, np.random.Generator):
        raise ValueError("rng: pass a seeded numpy.random.Generator (or None for init * I)")
    out = []
    for _ in range(4):
        G = rng.standard_normal((M, n, n))
        out.append(init * (G @ _T(G) / n + np.eye(n)))
    return out


def _rel_change(old, new):
    d = new - old
    return float(np.sqrt(np.vdot(d, d) / max(np.vdot(new, new), 1e-300)))


def dynamic_output_feedback(sys, tol=1e-10, max_iter=10000, init=1e-4, rng=None, method="lstsq",
                            warn=True):
    """Algorithm 3.2: the time-invariant controller (3.37) for the MJLS (3.36), mode not observed.

    Iterates Step 2 (gains from (3.51)) and Step 4 (bounds (3.52)) with mu = mu_inf.

    Parameters
    ----------
    sys : MJLS
        With measurement noise J (Sec. 3.6; J = None means y = C x).
    tol : float
        Stop when the relative changes of F, K, L and of Xbar, Xunder, Pbar, Punder
        (Frobenius norms) all fall below ``tol`` (Step 3 asks for unchanged gains; the
        author's reference code stops on the change of the four bounds, Mxttak/MJLS,
        MJLS_ClassMeasurementFeedbackConstGains.m).
    max_iter : int
        Iteration limit; ``converged=False`` and a warning when reached or when the
        bounds diverge (beyond 1e100, e.g. for a system this controller cannot stabilise).
    init : float
        Scale of the initial bounds. With ``rng=None`` all four start at init * I, as in
        the author's reference code (1e-4 I); with a Generator they are random symmetric
        positive definite matrices of that scale (Step 1).
    rng : numpy.random.Generator, optional
        Source of random initial bounds.
    method : {"lstsq", "sdp"}
        Minimum-norm solution of (3.51), or the SDP after Alg. 3.2.
    warn : bool
        Warn (RuntimeWarning) when the iteration does not converge or the controller does
        not stabilise.

    Returns
    -------
    DynamicOutputFeedbackResult
        Gains, convergence, rho, the true cost (Prop. 3.24) and the bound (Prop. 3.26).

    Raises
    ------
    ValueError
        If ``tol`` or ``init`` is not positive, ``max_iter`` is not an integer >= 1,
        ``method`` is unknown or ``rng`` is not a Generator.
    FloatingPointError
        If the bounds diverge already in the first iteration.
    """
    if not tol > 0 or int(max_iter) != max_iter or max_iter < 1 or not init > 0:
        raise ValueError(f"tol and init must be > 0 and max_iter an integer >= 1, found tol={tol}, "
                         f"max_iter={max_iter}, init={init}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, found {method!r}")
    start = time.perf_counter()
    HHt, JJt = noise_covariances(sys)
    mu = sys.mu_inf
    Xbar, Xunder, Pbar, Punder = _initial_bounds(sys, init, rng)
    iterates = [np.stack([Xbar, Xunder, Pbar, Punder])]
    gains = None
    converged = False
    it = 0
    for it in range(1, int(max_iter) + 1):
        EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
        try:
            F, K, L = gains_from_bounds(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method, RANK_RTOL)
        except np.linalg.LinAlgError:
            break
        new_X = bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt)
        new_P = bound_costate_step(sys, F, K, L, EPbar, EPunder)
        if not all(np.abs(v).max() < DIVERGED for v in (*new_X, *new_P)):
            break                                   # the bounds diverge: not stabilisable this way
        changes = [_rel_change(o, n) for o, n in zip((Xbar, Xunder, Pbar, Punder), (*new_X, *new_P))]
        if gains is not None:
            changes += [_rel_change(o, n) for o, n in zip(gains, (F, K, L))]
        iterates.append(np.stack([*new_X, *new_P]))
        gains = (F, K, L)
        Xbar, Xunder = new_X
        Pbar, Punder = new_P
        if it > 1 and max(changes) < tol:
            converged = True
            break
    seconds = time.perf_counter() - start
    if gains is None:
        raise FloatingPointError("Algorithm 3.2: the bounds diverged in the first iteration")
    F, K, L = gains
    cost, _, rho = steady_state_cost(sys, F, K, L)
    stabilizing = bool(rho < 1)
    bound = float(np.einsum("iab,iba->", sys.Q, Xbar + Xunder)
                  + np.einsum("iab,iba->", L.T @ sys.R @ L, Xunder))
    if warn and not converged:
        warnings.warn(f"Algorithm 3.2 did not converge within {it} iterations (rho = {rho:.4f})",
                      RuntimeWarning, stacklevel=2)
    elif warn and not stabilizing:
        warnings.warn(f"Algorithm 3.2 converged, but the controller does not stabilise the MJLS in "
                      f"the mean-square sense (rho = {rho:.4f} >= 1, Cor. 3.2)", RuntimeWarning,
                      stacklevel=2)
    traces = np.trace(np.array(iterates), axis1=-2, axis2=-1)           # (iterations + 1, 4, M)
    history = {f"trace_{k}": traces[:, j] for j, k in enumerate(("Xbar", "Xunder", "Pbar", "Punder"))}
    return DynamicOutputFeedbackResult(F=F, K=K, L=L, converged=converged, iterations=it, rho=rho,
                                       stabilizing=stabilizing, cost=cost, bound=bound, Xbar=Xbar,
                                       Xunder=Xunder, Pbar=Pbar, Punder=Punder, history=history,
                                       seconds=seconds)
