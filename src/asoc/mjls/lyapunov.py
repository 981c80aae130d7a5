"""Coupled Lyapunov equations X = L(X) + W of an MJLS (Prop. 3.7, Prop. 3.23) and their adjoint
P = L*(P) + Q (Prop. 3.16), with the residual of every solution checked.

Small systems (M n^2 up to ``config.defaults["mjls.dense_max_solve"]``) are solved by one LU
factorisation of I - :func:`asoc.mjls.ms_operator`, larger ones by BiCGSTAB (continued by GMRES
when it stalls) on the matrix-free operator. Every solution's relative residual
||X - L(X) - W||_F / ||W||_F is computed; an iterative solution that misses
``mjls.solve_residual_max`` is replaced by a dense solve where the Kronecker matrix fits
(M n^2 up to ``mjls.dense_fallback_solve``), and otherwise returned with a RuntimeWarning that
states the residual, never silently.
"""

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from .. import config
from ..linalg import bicgstab, sym
from ..threads import single_threaded
from ..validation import real_array, stochastic_matrix
from .certificate import certified_upper_bound
from .moment_operator import (
    costate_map,
    kronecker_stack,
    linear_operator,
    second_moment_map,
    shifted_map,
)
from .stability import mean_square_stability

__all__ = ["ITERATIVE", "LyapunovSolution", "residual", "solve_coupled_lyapunov",
           "coupled_lyapunov_solver", "radius_and_moments", "radii_and_moments"]


#: The iterative methods of :func:`solve_coupled_lyapunov`.
ITERATIVE = ("bicgstab", "gmres", "fixed_point")
#: LAPACK's LU factorisation and solve, as scipy.linalg.lu_factor and lu_solve call them.
_GETRF, _GETRS = scipy.linalg.get_lapack_funcs(("getrf", "getrs"), dtype=np.float64)


@dataclass(frozen=True)
class LyapunovSolution:
    """Solution of the coupled Lyapunov equations X = L(X) + W (or P = L*(P) + Q).

    Attributes
    ----------
    X : numpy.ndarray, shape (M, n, n)
        The (symmetrised) solution.
    residual : float
        ||X - L(X) - W||_F / ||W||_F of the returned X.
    method : str
        "dense", the iterative method, or e.g. "bicgstab+gmres+dense" for the fallbacks taken.
    iterations : int
        Krylov iterations (0 for dense).

    Examples
    --------
    >>> sol = solve_coupled_lyapunov(np.array([[[0.5]]]), np.eye(1), np.ones((1, 1, 1)))
    >>> round(float(sol.X[0, 0, 0]), 6), sol.method, sol.accepted        # x = 0.25 x + 1
    (1.333333, 'dense', True)
    """

    X: np.ndarray
    residual: float
    method: str
    iterations: int

    @property
    def accepted(self) -> bool:
        """The residual is at most ``config.defaults["mjls.solve_residual_max"]``."""
        return bool(self.residual <= config.defaults["mjls.solve_residual_max"])


class _Dense:
    """An LU factorisation of I - ms_operator, reused for moments and costates (getrf/getrs)."""

    def __init__(self, A, T, kron=None):
        M, n, _ = A.shape
        kron = kronecker_stack(A[None], T)[0] if kron is None else kron
        self.lu, self.piv, self.info = _GETRF(np.eye(M * n * n) - kron)

    def solve(self, W, adjoint=False):
        rhs = W.ravel()
        if not np.isfinite(rhs).all():
            raise ValueError("W: expected finite entries, found infs or NaNs")
        if self.info > 0:                                # exactly singular: 1 is an eigenvalue of L
            return np.full(W.shape, np.nan)
        solution, _ = _GETRS(self.lu, self.piv, rhs, trans=1 if adjoint else 0)
        return solution.reshape(W.shape)


def residual(A, T, X, W, adjoint=False):
    """||X - L(X) - W||_F / ||W||_F (L* for ``adjoint``) of a symmetric X (as every solution
    here is; of another X, that of its symmetric part); inf for a non-finite X.

    Examples
    --------
    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> residual(A, T, np.array([[[4 / 3]]]), np.ones((1, 1, 1))) < 1e-15
    True
    """
    if not np.all(np.isfinite(X)):
        return np.inf
    scale = max(np.linalg.norm(W), np.finfo(float).tiny)
    difference = shifted_map(A, T, X.ravel(), adjoint, identity=1.0)
    difference -= W.ravel()
    return float(np.linalg.norm(difference) / scale)


def solve_coupled_lyapunov(A, T, W, adjoint=False, method="auto", tol=None):
    """X_j = sum_i p_ij A_i X_i A_i^T + W_j (Prop. 3.7, Prop. 3.23), or the adjoint P = L*(P) + W.

    Has a unique solution iff 1 is not an eigenvalue of L; it is the stationary second moment
    (resp. multiplier) when rho(L) < 1 (Cor. 3.2) and W >= 0.

    Parameters
    ----------
    A : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    W : numpy.ndarray, shape (M, n, n)
        Symmetric right-hand side, e.g. sum_i p_ij mu_i H_i H_i^T, or Q~_i.
    adjoint : bool
        Solve P = L*(P) + W (multipliers, Prop. 3.16) instead.
    method : {"auto", "dense", "bicgstab", "gmres", "fixed_point"}
        ``"dense"``: LU of I - :func:`asoc.mjls.ms_operator`; ``"bicgstab"``, ``"gmres"``
        (restarted after 60): Krylov methods on the matrix-free I - L; ``"fixed_point"``:
        X <- L(X) + W (converges like rho^k). ``"auto"``: dense up to M n^2 =
        ``config.defaults["mjls.dense_max_solve"]``, else BiCGSTAB (about half the
        matrix-vector products of GMRES and none of its orthogonalisation), continued by
        GMRES when it stalls above ``tol``.
    tol : float, optional
        Relative residual the iterative methods stop at (default
        ``config.defaults["mjls.solve_tolerance"]``).

    Returns
    -------
    LyapunovSolution
        X, its residual, the method and the number of iterations. An iterative solution whose
        residual exceeds ``mjls.solve_residual_max`` is replaced by the dense solution up to
        M n^2 = ``mjls.dense_fallback_solve``; above, it is returned with a RuntimeWarning.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.8]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> sol = solve_coupled_lyapunov(A, T, np.ones((2, 1, 1)), method="gmres")
    >>> np.round(sol.X.ravel(), 6), sol.residual < 1e-12
    (array([1.801802, 1.801802]), True)
    """
    return coupled_lyapunov_solver(A, T, method, tol)(W, adjoint)


def coupled_lyapunov_solver(A, T, method="auto", tol=None):
    """A function (W, adjoint=False, on_miss="fallback", x0=None) -> :class:`LyapunovSolution`
    for one closed loop A.

    The dense method factorises I - L once for all right-hand sides and both directions.
    Arguments as :func:`solve_coupled_lyapunov`. ``on_miss="report"`` returns an iterative
    solution that misses ``mjls.solve_residual_max`` as it is (``accepted`` False), without the
    dense fallback or the warning: for callers that test stability by the solve and check
    ``accepted`` themselves (e.g. an exact design's line search through unstable gains).
    ``x0`` starts an iterative solve (e.g. from the solution for a nearby closed loop; the
    dense method ignores it).

    Examples
    --------
    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> solve = coupled_lyapunov_solver(A, T)
    >>> solve(np.ones((1, 1, 1))).X.ravel().round(4), solve(np.ones((1, 1, 1)), adjoint=True).method
    (array([1.3333]), 'dense')
    """
    M, n, _ = A.shape
    tol = config.defaults["mjls.solve_tolerance"] if tol is None else tol
    auto = method == "auto"
    if auto:
        method = "dense" if M * n * n <= config.defaults["mjls.dense_max_solve"] else "bicgstab"
    if method != "dense" and method not in ITERATIVE:
        raise ValueError(f"method: expected 'auto', 'dense' or one of {ITERATIVE}, "
                         f"found {method!r}")
    # the LU factorisation, made when first needed
    dense = []

    def dense_solve(W, adjoint):
        if not dense:
            dense.append(_Dense(A, T))
        X = sym(dense[0].solve(W, adjoint))
        return X, residual(A, T, X, W, adjoint)

    def solve(W, adjoint=False, on_miss="fallback", x0=None):
        if method == "dense":
            X, res = dense_solve(W, adjoint)
            return LyapunovSolution(X=X, residual=res, method="dense", iterations=0)
        with single_threaded():
            X, res, used, it = _iterative(A, T, W, adjoint, method, tol, auto, x0)
        if on_miss == "fallback" and not res <= config.defaults["mjls.solve_residual_max"]:
            if M * n * n <= config.defaults["mjls.dense_fallback_solve"]:
                X2, res2 = dense_solve(W, adjoint)
                if not res <= res2:
                    X, res, used = X2, res2, used + "+dense"
            if not res <= config.defaults["mjls.solve_residual_max"]:
                limit = config.defaults["mjls.solve_residual_max"]
                warnings.warn(f"the coupled Lyapunov solve ({used}) reached a relative residual of "
                              f"{res:.3g} only, above mjls.solve_residual_max = {limit:.3g}: "
                              "the returned X is not a solution (rho(L) near 1?)", RuntimeWarning,
                              stacklevel=2)
        return LyapunovSolution(X=X, residual=res, method=used, iterations=it)
    return solve


def _iterative(A, T, W, adjoint, method, tol, auto, x0=None):
    """X, its residual, the method(s) used and the iterations; BiCGSTAB continued by GMRES for
    ``auto`` (from ``x0``, e.g. the solution for a nearby closed loop, when given).
    """
    X, it = _iterative_solve(A, T, W, adjoint, method, tol, x0=x0)
    X, used = sym(X), method
    res = residual(A, T, X, W, adjoint)
    if auto and not res <= 10 * tol:                  # BiCGSTAB stalled or broke down
        X2, it2 = _iterative_solve(A, T, W, adjoint, "gmres", tol,
                                   x0=X if np.all(np.isfinite(X)) else None)
        X2 = sym(X2)
        res2 = residual(A, T, X2, W, adjoint)
        if not res <= res2:
            X, res, it, used = X2, res2, it + it2, "bicgstab+gmres"
    return X, res, used, it


def _iterative_solve(A, T, W, adjoint, method, tol, max_iter=5000, x0=None):
    """X and the iteration count for X = L(X) + W by GMRES, BiCGSTAB or the fixed point."""
    M, n, _ = A.shape
    if method == "fixed_point":
        apply = costate_map if adjoint else second_moment_map
        X = W.copy()
        norm_W = max(np.linalg.norm(W), np.finfo(float).tiny)
        for it in range(1, max_iter + 1):
            X_new = apply(A, T, X) + W
            if np.linalg.norm(X_new - X) <= tol * norm_W or not np.all(np.isfinite(X_new)):
                return X_new, it
            X = X_new
        return X, max_iter
    b = sym(W).ravel()
    x0 = b if x0 is None else x0.ravel()
    if method == "gmres":
        count = [0]

        def callback(_):
            count[0] += 1

        x, _ = scipy.sparse.linalg.gmres(linear_operator(A, T, adjoint, identity=1.0), b, x0=x0,
                                         rtol=tol, atol=0.0, restart=60,
                                         maxiter=max_iter // 60 + 1, callback=callback,
                                         callback_type="pr_norm")
        return x.reshape(M, n, n), count[0]
    x, iterations = bicgstab(lambda v, out: shifted_map(A, T, v, adjoint, identity=1.0, out=out),
                             b, x0, tol, max_iter)
    return x.reshape(M, n, n), iterations


def radius_and_moments(A, T, W, check=True):
    """Rho of Cor. 3.2 and, when stability is certified, the solution X of X = L(X) + W (Prop. 3.7).

    For searches over a gain: from one Kronecker matrix at small sizes (its eigenvalues give
    rho, its LU factorisation X and the certificate Y = L(Y) + I, whose positive definiteness
    with a Collatz-Wielandt bound below 1 proves rho < 1); above ``mjls.dense_max_radius`` or
    ``mjls.dense_max_solve`` from :func:`asoc.mjls.mean_square_stability` and
    :func:`solve_coupled_lyapunov`. :func:`radii_and_moments` does the same for a stack of
    closed loops.

    Parameters
    ----------
    A : array_like, shape (M, n, n)
        Closed-loop matrices.
    T : array_like, shape (M, M)
        Transition matrix.
    W : array_like, shape (M, n, n)
        Finite symmetric right-hand side, e.g. sum_i p_ij mu_i H_i H_i^T.
    check : bool
        Validate the arguments (False: float arrays of consistent shapes, for inner loops).

    Returns
    -------
    rho : float
        The estimate of rho (inside the certified bracket where stability is certified).
    X : numpy.ndarray, shape (M, n, n), or None
        The symmetrised solution; None unless mean-square stability is certified.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.8]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> rho, X = radius_and_moments(A, T, np.ones((2, 1, 1)))
    >>> round(rho, 6), np.round(X.ravel(), 6)
    (0.445, array([1.801802, 1.801802]))
    """
    if check:
        A, T, W = _checked(real_array(A, "A", ndim=3)[None], T, W)
        A = A[0]
    rho, X = radii_and_moments(A[None], T, W, check=False)
    return float(rho[0]), X[0]


def radii_and_moments(A, T, W, check=True):
    """:func:`radius_and_moments` for a stack of closed loops A, shape (G, M, n, n).

    The Kronecker matrices of all G loops are formed at once and their eigenvalues computed
    in one call. Returns rho, shape (G,), and a list of G solutions (None where stability is
    not certified).

    Examples
    --------
    >>> A = np.array([[[[0.5]], [[0.8]]], [[[1.5]], [[0.8]]]])
    >>> T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> rho, X = radii_and_moments(A, T, np.ones((2, 1, 1)))
    >>> rho.round(6), X[1] is None
    (array([0.445, 1.445]), True)
    """
    if check:
        A, T, W = _checked(real_array(A, "A", ndim=4), T, W)
    G, M, n, _ = A.shape
    dim = M * n * n
    if (dim > config.defaults["mjls.dense_max_radius"]
            or dim > config.defaults["mjls.dense_max_solve"]):
        stability = [mean_square_stability(loop, T, check=False) for loop in A]
        return (np.array([s.rho for s in stability]),
                [solve_coupled_lyapunov(loop, T, W).X if s.stable else None
                 for loop, s in zip(A, stability)])
    kron = kronecker_stack(A, T)
    rho = np.max(np.abs(np.linalg.eigvals(kron)), axis=1)
    eye = np.broadcast_to(np.eye(n), (M, n, n))
    X = [None] * G
    for g in np.flatnonzero(rho < 1):
        dense = _Dense(A[g], T, kron[g])
        upper = certified_upper_bound(A[g], T, sym(dense.solve(eye)))
        if upper < 1:
            rho[g] = min(rho[g], upper)
            X[g] = sym(dense.solve(W))
    return rho, X


def _checked(A, T, W):
    """Validated (G, M, n, n) loops, (M, M) T and (M, n, n) W."""
    G, M, n, n2 = A.shape
    if n != n2:
        raise ValueError(f"A: expected square closed-loop matrices, found shape {A.shape}")
    T = stochastic_matrix(T, "T", M)
    W = real_array(W, "W", shape=(M, n, n))
    return A, T, W
