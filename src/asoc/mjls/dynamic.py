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

from ..result import IterativeResult
from ..validation import boolean, choice, generator, integer, real_scalar
from .moments import steady_state_second_moment
from .operators import augmented_closed_loop, check_gains, noise_covariances, spectral_radius  # noqa: F401 (public here)
from .system import check_system, predecessor_sum, successor_average

METHODS = ("lstsq", "sdp")
DIVERGED = 1e100          # bounds beyond this are treated as diverging (the iteration stops)
GAIN_FLOOR = 1e-12        # absolute floor of a gain's norm in its relative change (a zero gain converges)
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

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> r = dynamic_output_feedback(sys)
    >>> cost, X, rho = steady_state_cost(sys, r.F, r.K, r.L)
    >>> round(cost, 3) == round(r.cost, 3), bool(rho < 1)
    (True, True)
    """
    At, HHt_cl, Qt = augmented_closed_loop(sys, F, K, L)
    rho = spectral_radius(At, sys.T)
    if not rho < 1:
        return np.inf, None, rho
    X = steady_state_second_moment(At, HHt_cl, sys.T, sys.mu_inf)
    return float(np.einsum("iab,iba->", Qt, X)), X, rho


def bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt):
    """One step of the second-moment bounds, (3.45)-(3.46) / (3.66)-(3.67).

    An inner-loop helper of Algs. 3.2-3.3: its arguments are not validated.

    Returns (Xbar_next, Xunder_next), each (M, nx, nx).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> HHt, JJt = noise_covariances(sys)
    >>> Z = np.zeros((2, 2, 2))
    >>> Xbar, Xunder = bound_moment_step(sys, np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)), Z, Z,
    ...                                  sys.mu_inf, HHt, JJt)
    >>> np.allclose(Xbar, sys.predecessor_sum(sys.mu_inf[:, None, None] * HHt)), np.abs(Xunder).max()
    (True, np.float64(0.0))
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

    An inner-loop helper of Algs. 3.2-3.3: its arguments are not validated.

    ``EPbar``, ``EPunder`` are E_i(Pbar), E_i(Punder) of the next step. Returns (Pbar, Punder).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> Z = np.zeros((2, 2, 2))
    >>> Pbar, Punder = bound_costate_step(sys, np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)), Z, Z)
    >>> np.allclose(Pbar, sys.Q), np.abs(Punder).max()
    (True, np.float64(0.0))
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
    H is (half) the Hessian of the bounded cost (A.7)/(B.5), hence symmetric PSD. An
    inner-loop helper of Algs. 3.2-3.3: its arguments are not validated.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> H, rho = optimality_system(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> H.shape, rho.shape, np.allclose(H, H.T)
    ((8, 8), (8,), True)
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

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> F, K, L = gains_from_bounds(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> F.shape, K.shape, L.shape
    ((2, 2), (2, 1), (1, 2))
    """
    choice(method, "method", METHODS)
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


@dataclass(kw_only=True)
class DynamicOutputFeedbackResult(IterativeResult):
    """Result of Algorithm 3.2 (:func:`dynamic_output_feedback`).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (nx, nx), (nx, ny), (nu, nx)
        The controller (3.37).
    converged, status, message
        Whether and why the iteration stopped (:class:`asoc.result.IterativeResult`):
        ``"converged"``, ``"max_iterations"``, ``"diverged"`` (the bounds grew beyond
        1e100) or ``"linalg_error"`` (solving (3.51) failed).
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

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> res = dynamic_output_feedback(sys)
    >>> res.converged, res.status, res.Xbar.shape
    (True, 'converged', (2, 2, 2))
    """

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
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
    generator(rng, "rng")
    out = []
    for _ in range(4):
        G = rng.standard_normal((M, n, n))
        out.append(init * (G @ _T(G) / n + np.eye(n)))
    return out


def _rel_change(old, new, floor=1e-150):
    """||new - old|| / max(||new||, floor) (Frobenius); the absolute floor lets a zero iterate converge."""
    d = new - old
    return float(np.sqrt(np.vdot(d, d) / max(np.vdot(new, new), floor ** 2)))


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
    TypeError
        If ``sys`` is not an MJLS, ``max_iter`` is not an integer, ``rng`` is not a
        Generator or ``warn`` not a bool.
    ValueError
        If ``tol`` or ``init`` is not a finite positive number, ``max_iter`` < 1 or
        ``method`` is unknown.
    FloatingPointError
        If the bounds diverge (or (3.51) fails) already in the first iteration.

    Examples
    --------
    The example of Sec. 3.7.3 with T[1]:

    >>> from asoc.mjls.examples import sec373_system
    >>> res = dynamic_output_feedback(sec373_system(1))
    >>> res.status, res.stabilizing, round(res.cost, 3), round(res.bound, 3)
    ('converged', True, 23.313, 18.03)
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    init = real_scalar(init, "init", low=0, low_open=True)
    choice(method, "method", METHODS)
    warn = boolean(warn, "warn")
    start = time.perf_counter()
    HHt, JJt = noise_covariances(sys)
    mu = sys.mu_inf
    Xbar, Xunder, Pbar, Punder = _initial_bounds(sys, init, rng)
    iterates = [np.stack([Xbar, Xunder, Pbar, Punder])]
    gains = None
    status, change = "max_iterations", np.inf
    it = 0
    for it in range(1, int(max_iter) + 1):
        EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
        try:
            F, K, L = gains_from_bounds(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method, RANK_RTOL)
        except np.linalg.LinAlgError:
            status = "linalg_error"
            break
        new_X = bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt)
        new_P = bound_costate_step(sys, F, K, L, EPbar, EPunder)
        if not all(np.abs(v).max() < DIVERGED for v in (*new_X, *new_P)):
            status = "diverged"                     # the bounds diverge: not stabilisable this way
            break
        changes = [_rel_change(o, n) for o, n in zip((Xbar, Xunder, Pbar, Punder), (*new_X, *new_P))]
        if gains is not None:
            changes += [_rel_change(o, n, GAIN_FLOOR) for o, n in zip(gains, (F, K, L))]
        iterates.append(np.stack([*new_X, *new_P]))
        gains = (F, K, L)
        Xbar, Xunder = new_X
        Pbar, Punder = new_P
        change = max(changes)
        if it > 1 and change < tol:
            status = "converged"
            break
    seconds = time.perf_counter() - start
    if gains is None:
        raise FloatingPointError(f"Algorithm 3.2: {'(3.51) could not be solved' if status == 'linalg_error' else 'the bounds diverged'} "
                                 f"in the first iteration")
    F, K, L = gains
    cost, _, rho = steady_state_cost(sys, F, K, L)
    stabilizing = bool(rho < 1)
    bound = float(np.einsum("iab,iba->", sys.Q, Xbar + Xunder)
                  + np.einsum("iab,iba->", L.T @ sys.R @ L, Xunder))
    message = {"converged": f"converged after {it} iterations (relative change {change:.2g} < tol = {tol:.2g})",
               "max_iterations": f"did not converge within {it} iterations (relative change {change:.2g} "
                                 f">= tol = {tol:.2g}, rho = {rho:.4f})",
               "diverged": f"stopped at iteration {it}: the bounds diverged beyond {DIVERGED:.0e} "
                           f"(rho = {rho:.4f})",
               "linalg_error": f"stopped at iteration {it}: solving (3.51) failed (rho = {rho:.4f})"}[status]
    if warn and status != "converged":
        warnings.warn(f"Algorithm 3.2 {message}", RuntimeWarning, stacklevel=2)
    elif warn and not stabilizing:
        warnings.warn(f"Algorithm 3.2 converged, but the controller does not stabilise the MJLS in "
                      f"the mean-square sense (rho = {rho:.4f} >= 1, Cor. 3.2)", RuntimeWarning,
                      stacklevel=2)
    traces = np.trace(np.array(iterates), axis1=-2, axis2=-1)           # (iterations + 1, 4, M)
    history = {f"trace_{k}": traces[:, j] for j, k in enumerate(("Xbar", "Xunder", "Pbar", "Punder"))}
    return DynamicOutputFeedbackResult(F=F, K=K, L=L, converged=status == "converged", status=status,
                                       message=message, iterations=it, rho=rho,
                                       stabilizing=stabilizing, cost=cost, bound=bound, Xbar=Xbar,
                                       Xunder=Xunder, Pbar=Pbar, Punder=Punder, history=history,
                                       seconds=seconds)
