"""Second-moment operators of an MJLS on (M, n, n) stacks, matrix-free (Cor. 3.2, Props. 3.7, 3.23).

The mean-square behaviour of x_{k+1} = A_{theta_k} x_k (+ noise) is governed by the linear map

    L(X)_j = sum_i p_ij A_i X_i A_i^T          (the second-moment recursion (3.29)),

and by its adjoint (the costate or multiplier recursion of Prop. 3.16)

    L*(P)_i = A_i^T E_i(P) A_i,  E_i(P) = sum_j p_ij P_j.

Applying either costs O(M n^3 + M^2 n^2); their Kronecker matrix (Cor. 3.2) costs
O((M n^2)^2) memory and O((M n^2)^3) time to factorise. This module holds everything the
Chapter 3 algorithms need of them, in one place:

- :func:`second_moment_map`, :func:`costate_map`: the maps on stacks;
- :func:`kronecker_matrix`: the dense matrix (row-major vec), used below :data:`DENSE_MAX_RADIUS` and :data:`DENSE_MAX_SOLVE`;
- :func:`spectral_radius`: rho(L) by Arnoldi (``scipy.sparse.linalg.eigs``) on a
  LinearOperator, with a cone power method as fallback; :func:`mean_square_stability` adds a
  verdict that is "undecided" within a stated tolerance of 1;
- :func:`solve_coupled_lyapunov`: X = L(X) + W (stationary moments, Prop. 3.7/3.23) or
  P = L*(P) + Q (multipliers, costates), by GMRES on the operator or a dense LU, with the
  residual reported;
- :func:`radius_and_moments_unchecked`, :func:`radii_and_moments_unchecked`: rho and the
  moments from one Kronecker matrix per closed loop, without checks, for searches over a gain;
- :func:`closed_loop`, :func:`augmented_closed_loop`, :func:`noise_covariances`: the
  closed-loop stacks of (3.10) and (3.39)-(3.40).

L is a positive map (it keeps the cone of positive semidefinite stacks), so rho(L) is an
eigenvalue with a positive semidefinite eigenvector (Krein-Rutman; Costa, Fragoso and
Marques 2005, Ch. 3), and the spectral radius of L on all matrices equals that on symmetric
ones. The iterative methods therefore work on symmetrised stacks.
"""

import contextlib
import enum
import sys
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg
from threadpoolctl import ThreadpoolController

from ..validation import real_array
from .system import check_system

#: Up to this size M n^2 the spectral radius comes from the eigenvalues of the dense Kronecker
#: matrix, above it from Arnoldi: the measured crossover (2 cores, random systems with rho
#: 0.95: 0.6 ms each at 64, dense 2.4 ms against 1.5 ms at 100; the Scaling page).
DENSE_MAX_RADIUS = 64
#: Up to this size the coupled Lyapunov equations are solved by a dense LU factorisation,
#: above it by BiCGSTAB (measured crossover: 0.9 ms against 1.5 ms at 256, 1.9 ms against
#: 1.1 ms at 288).
DENSE_MAX_SOLVE = 256
#: Krylov-space sizes ARPACK tries in turn for rho. 20 vectors stall on a dominant eigenvalue of
#: multiplicity 4 (the larger-plant page's chain, M n^2 = 512: no convergence after 0.9 s,
#: 40 vectors 0.7 s), 60 converge there in 10 ms; on the Scaling page's systems 60 vectors
#: cost 4 ms (n = 16, M = 4) to 49 ms (n = 64, M = 8), against 6 to 35 ms with 20.
ARNOLDI_SUBSPACES = (60, 150)
#: When ARPACK does not converge: dense eigenvalues up to this M n^2 (measured: 0.2 s at 512,
#: 0.85 s at 1024), the cone power method above it.
DENSE_FALLBACK_RADIUS = 1024
#: rho within this distance of 1 is reported as undecided (rounding of the eigenvalue solver,
#: about 1e-13 on well-conditioned operators, is far below it).
RHO_TOLERANCE = 1e-9
#: Relative residual ||X - L(X) - W|| / ||W|| the iterative solver stops at.
SOLVE_TOLERANCE = 1e-12

_THREADS = ThreadpoolController()
#: LAPACK's LU factorisation and solve, as scipy.linalg.lu_factor and lu_solve call them.
_GETRF, _GETRS = scipy.linalg.get_lapack_funcs(("getrf", "getrs"), dtype=np.float64)


def single_threaded():
    """A context in which BLAS runs on one thread: the iterative methods work on n x n products
    and vectors of length M n^2, where threads cost more than they gain (10x slower at n = 64,
    M = 8 on a loaded 2-core machine)."""
    return _THREADS.limit(limits=1, user_api="blas")


def _T(X):
    return np.swapaxes(X, -1, -2)


def _sym(X):
    return 0.5 * (X + _T(X))


@contextlib.contextmanager
def switch_points(radius=None, solve=None):
    """Temporarily set :data:`DENSE_MAX_RADIUS` and :data:`DENSE_MAX_SOLVE` (None: unchanged).

    ``switch_points(radius=10**9, solve=10**9)`` forces the dense Kronecker path, ``(0, 0)`` the
    matrix-free one, e.g. to time both (the Scaling page).

    Examples
    --------
    >>> from asoc.mjls import operators
    >>> with switch_points(radius=0):
    ...     operators.DENSE_MAX_RADIUS
    0
    >>> operators.DENSE_MAX_RADIUS == 64
    True
    """
    module = sys.modules[__name__]
    saved = module.DENSE_MAX_RADIUS, module.DENSE_MAX_SOLVE
    try:
        if radius is not None:
            module.DENSE_MAX_RADIUS = radius
        if solve is not None:
            module.DENSE_MAX_SOLVE = solve
        yield
    finally:
        module.DENSE_MAX_RADIUS, module.DENSE_MAX_SOLVE = saved


def second_moment_map(A, T, X):
    """L(X)_j = sum_i p_ij A_i X_i A_i^T, the homogeneous part of (3.29) / Prop. 3.23.

    Parameters
    ----------
    A : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    T : numpy.ndarray, shape (M, M)
        Transition matrix, p_ij = P(theta_{k+1} = j | theta_k = i).
    X : numpy.ndarray, shape (M, n, n)
        A stack, e.g. second moments E{x x^T 1(theta = i)}.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)

    Examples
    --------
    >>> A = np.array([[[0.5]], [[2.0]]]); T = np.array([[0.9, 0.1], [0.5, 0.5]])
    >>> second_moment_map(A, T, np.ones((2, 1, 1))).ravel()
    array([2.225, 2.025])
    """
    Y = A @ X @ _T(A)
    return (T.T @ Y.reshape(len(Y), -1)).reshape(Y.shape)


def costate_map(A, T, P):
    """L*(P)_i = A_i^T E_i(P) A_i, the adjoint of :func:`second_moment_map` (Prop. 3.16).

    <L(X), P> = <X, L*(P)> with <X, P> = sum_i tr(X_i^T P_i).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[2.0]]]); T = np.array([[0.9, 0.1], [0.5, 0.5]])
    >>> costate_map(A, T, np.ones((2, 1, 1))).ravel()
    array([0.25, 4.  ])
    """
    EP = (T @ P.reshape(len(P), -1)).reshape(P.shape)
    return _T(A) @ EP @ A


def kronecker_matrix(A, T):
    """The matrix of :func:`second_moment_map` on row-major vecs: block (j, i) = p_ij A_i (x) A_i.

    Its transpose is the matrix of :func:`costate_map`; its spectrum is that of the matrix of
    Cor. 3.2 (:func:`asoc.mjls.ms_operator`), diag(A_i (x) A_i) (T^T (x) I) (products BC and
    CB). Size (M n^2)^2: use only for small systems.
    """
    return _kronecker_stack(A[None], T)[0]


def _kronecker_stack(A, T):
    """:func:`kronecker_matrix` of each closed loop of a stack A, shape (G, M, n, n) (every entry one product)."""
    G, M, n, _ = A.shape
    kron = np.einsum("giab,gicd->giacbd", A, A).reshape(G, M, n * n, n * n)
    return np.einsum("ij,gixy->gjxiy", T, kron).reshape(G, M * n * n, M * n * n)


def _linear_operator(A, T, adjoint=False, shift=False):
    """L (or L*) as a LinearOperator on flat symmetrised stacks; with ``shift``, I - L."""
    M, n, _ = A.shape
    apply = costate_map if adjoint else second_moment_map

    def matvec(x):
        X = _sym(np.asarray(x).reshape(M, n, n).real)
        Y = apply(A, T, X)
        return (X - Y if shift else Y).ravel()

    return scipy.sparse.linalg.LinearOperator((M * n * n, M * n * n), matvec=matvec, dtype=float)


def _cone_power_bracket(A, T, tol, max_iter):
    """rho(L) by the power method on the cone of positive definite stacks.

    For X > 0 the Collatz-Wielandt bounds min_j lambda_min(X_j^-1 L(X)_j) <= rho <=
    max_j lambda_max(X_j^-1 L(X)_j) hold; they tighten as X approaches the Perron vector.
    Returns (estimate, lower, upper, iterations).
    """
    M, n, _ = A.shape
    X = np.broadcast_to(np.eye(n), (M, n, n)).copy()
    lo, hi = 0.0, np.inf
    it = 0
    for it in range(1, max_iter + 1):
        Y = _sym(second_moment_map(A, T, X)) + 1e-300 * np.eye(n)
        try:
            lam = np.concatenate([scipy.linalg.eigh(Y[j], X[j], eigvals_only=True) for j in range(M)])
        except np.linalg.LinAlgError:
            lam = None
        if lam is not None:
            lo, hi = max(lo, float(lam.min())), min(hi, float(lam.max()))
        if hi - lo <= tol * max(hi, 1e-300):
            break
        X = Y / np.abs(Y).max()
        X += 1e-14 * np.trace(X, axis1=1, axis2=2).max() * np.eye(n)     # keep it definite
    return 0.5 * (lo + hi) if np.isfinite(hi) else np.nan, lo, hi, it


def _arnoldi_radius(A, T):
    """rho by ARPACK on the matrix-free operator, or None when it does not converge.

    A dominant eigenvalue of multiplicity > 1 (e.g. two complex pairs of equal modulus, as in
    the chain of masses of the larger-plant page) can stall a small Krylov space: the search
    space grows through :data:`ARNOLDI_SUBSPACES` before giving up.
    """
    M, n, _ = A.shape
    dim = M * n * n
    op = _linear_operator(A, T)
    for ncv in ARNOLDI_SUBSPACES:
        try:
            with single_threaded():
                lam = scipy.sparse.linalg.eigs(op, k=1, which="LM", tol=1e-14, ncv=min(dim - 1, ncv),
                                               maxiter=max(1000, dim),
                                               v0=np.broadcast_to(np.eye(n), (M, n, n)).ravel(),
                                               return_eigenvectors=False)
            return float(np.max(np.abs(lam)))
        except scipy.sparse.linalg.ArpackNoConvergence:
            if ncv >= dim - 1:
                break
    return None


def spectral_radius(A, T, method="auto"):
    """rho of the second-moment operator (Cor. 3.2): mean-square stable iff rho < 1.

    Parameters
    ----------
    A : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    method : {"auto", "dense", "arnoldi", "power"}
        ``"dense"``: eigenvalues of :func:`kronecker_matrix`; ``"arnoldi"``: ARPACK on the
        matrix-free operator (largest modulus; Krylov spaces of :data:`ARNOLDI_SUBSPACES`
        vectors in turn; when none converges, ``"dense"`` up to M n^2 =
        :data:`DENSE_FALLBACK_RADIUS`, else ``"power"``); ``"power"``: the cone power method with Collatz-Wielandt bounds
        (relative width 1e-10). ``"auto"``: dense up to M n^2 = :data:`DENSE_MAX_RADIUS`,
        else Arnoldi.

    Returns
    -------
    float

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> round(spectral_radius(A, T), 12), round(spectral_radius(A, T, "power"), 9)
    (0.845, 0.845)
    """
    M, n, _ = A.shape
    dim = M * n * n
    if method == "auto":
        method = "dense" if dim <= DENSE_MAX_RADIUS else "arnoldi"
    if method == "dense" or (method == "arnoldi" and dim <= 3):
        return float(np.max(np.abs(np.linalg.eigvals(kronecker_matrix(A, T)))))
    if method == "arnoldi":
        rho = _arnoldi_radius(A, T)
        if rho is not None:
            return rho
        method = "dense" if dim <= DENSE_FALLBACK_RADIUS else "power"
        if method == "dense":
            return float(np.max(np.abs(np.linalg.eigvals(kronecker_matrix(A, T)))))
    if method == "power":
        with single_threaded():
            return float(_cone_power_bracket(A, T, 1e-10, 100000)[0])
    raise ValueError(f"method: expected one of 'auto', 'dense', 'arnoldi', 'power', found {method!r}")


class Verdict(enum.Enum):
    """Mean-square stability verdict of Cor. 3.2 with a rounding band around rho = 1."""

    STABLE = "stable"
    UNSTABLE = "unstable"
    UNDECIDED = "undecided"


@dataclass(frozen=True)
class MeanSquareStability:
    """rho of Cor. 3.2, its margin 1 - rho and the verdict; ``undecided`` within ``tolerance`` of 1.

    Attributes
    ----------
    rho : float
    margin : float
        1 - rho (positive: stable).
    tolerance : float
        Half-width of the undecided band around rho = 1.
    verdict : Verdict
    """

    rho: float
    margin: float
    tolerance: float
    verdict: Verdict

    @property
    def stable(self) -> bool:
        """True only when rho < 1 - tolerance."""
        return self.verdict is Verdict.STABLE


def mean_square_stability(A, T, tolerance=RHO_TOLERANCE, method="auto"):
    """Cor. 3.2 as a verdict: stable (rho < 1 - tol), unstable (rho > 1 + tol) or undecided.

    Examples
    --------
    >>> T = np.array([[1.0]])
    >>> mean_square_stability(np.array([[[0.5]]]), T).verdict
    <Verdict.STABLE: 'stable'>
    >>> mean_square_stability(np.array([[[1.0]]]), T).verdict
    <Verdict.UNDECIDED: 'undecided'>
    """
    rho = spectral_radius(A, T, method)
    margin = 1.0 - rho
    if margin > tolerance:
        verdict = Verdict.STABLE
    elif margin < -tolerance:
        verdict = Verdict.UNSTABLE
    else:
        verdict = Verdict.UNDECIDED
    return MeanSquareStability(rho=rho, margin=margin, tolerance=tolerance, verdict=verdict)


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
        "dense" or "gmres".
    iterations : int
        Krylov iterations (0 for dense).
    """

    X: np.ndarray
    residual: float
    method: str
    iterations: int


class _Dense:
    """An LU factorisation of I - kronecker_matrix, reused for moments and costates.

    LAPACK getrf and getrs called directly, as :func:`scipy.linalg.lu_factor` (unchecked) and
    :func:`scipy.linalg.lu_solve` (right-hand side checked) call them, without their wrappers'
    per-call cost; ``kron`` passes a Kronecker matrix already formed.
    """

    def __init__(self, A, T, kron=None):
        M, n, _ = A.shape
        kron = kronecker_matrix(A, T) if kron is None else kron
        self.lu, self.piv, info = _GETRF(np.eye(M * n * n) - kron)
        if info > 0:
            warnings.warn(f"Diagonal number {info} is exactly zero. Singular matrix.", scipy.linalg.LinAlgWarning,
                          stacklevel=3)

    def solve(self, W, adjoint=False):
        rhs = W.ravel()
        if not np.isfinite(rhs).all():
            raise ValueError("array must not contain infs or NaNs")
        solution, _ = _GETRS(self.lu, self.piv, rhs, trans=1 if adjoint else 0)
        return solution.reshape(W.shape)


def residual(A, T, X, W, adjoint=False):
    """||X - L(X) - W||_F / ||W||_F (L* for ``adjoint``)."""
    apply = costate_map if adjoint else second_moment_map
    return float(np.linalg.norm(X - apply(A, T, X) - W) / max(np.linalg.norm(W), 1e-300))


def solve_coupled_lyapunov(A, T, W, adjoint=False, method="auto", tol=SOLVE_TOLERANCE):
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
        ``"dense"``: LU of I - :func:`kronecker_matrix`; ``"bicgstab"``, ``"gmres"``
        (restarted after 60): Krylov methods on the matrix-free I - L; ``"fixed_point"``:
        X <- L(X) + W (converges like rho^k). ``"auto"``: dense up to M n^2 =
        :data:`DENSE_MAX_SOLVE`, else BiCGSTAB (measured fastest: about half the
        matrix-vector products of GMRES and none of its orthogonalisation; the fixed point
        needs 500 iterations at rho = 0.95, 2700 at 0.99), continued by GMRES when it
        stalls above ``tol``.
    tol : float
        Relative residual the iterative methods stop at.

    Returns
    -------
    LyapunovSolution
        X, its residual, the method and the number of iterations. GMRES that does not reach
        ``tol`` returns its last iterate; the residual says how far it got.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.8]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> sol = solve_coupled_lyapunov(A, T, np.ones((2, 1, 1)), method="gmres")
    >>> np.round(sol.X.ravel(), 6), sol.residual < 1e-12
    (array([1.801802, 1.801802]), True)
    """
    return coupled_lyapunov_solver(A, T, method, tol)(W, adjoint)


def radius_and_moments_unchecked(A, T, W):
    """rho of Cor. 3.2 and, when rho < 1, the solution X of X = L(X) + W, from one Kronecker matrix.

    An internal fast path for loops over many closed loops (a search over a gain): the same
    numbers as ``spectral_radius(A, T)`` and ``solve_coupled_lyapunov(A, T, W).X`` on their dense
    paths, without checks and without the residual. Above :data:`DENSE_MAX_RADIUS` or
    :data:`DENSE_MAX_SOLVE` it calls those two functions. :func:`radii_and_moments_unchecked`
    does the same for a stack of closed loops.

    Parameters
    ----------
    A : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices (not validated).
    T : numpy.ndarray, shape (M, M)
        Transition matrix (not validated).
    W : numpy.ndarray, shape (M, n, n)
        Finite symmetric right-hand side, e.g. sum_i p_ij mu_i H_i H_i^T.

    Returns
    -------
    rho : float
    X : numpy.ndarray, shape (M, n, n), or None
        The symmetrised solution; None when rho >= 1 (or rho is NaN).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.8]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> rho, X = radius_and_moments_unchecked(A, T, np.ones((2, 1, 1)))
    >>> round(rho, 6), np.round(X.ravel(), 6)
    (0.445, array([1.801802, 1.801802]))
    """
    rho, X = radii_and_moments_unchecked(A[None], T, W)
    return float(rho[0]), X[0]


def radii_and_moments_unchecked(A, T, W):
    """:func:`radius_and_moments_unchecked` for a stack of closed loops A, shape (G, M, n, n).

    The Kronecker matrices of all G loops are formed at once and their eigenvalues computed
    in one call (each matrix as alone). Returns rho, shape (G,), and a list of G solutions
    (None where rho >= 1).

    Examples
    --------
    >>> A = np.array([[[[0.5]], [[0.8]]], [[[1.5]], [[0.8]]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> rho, X = radii_and_moments_unchecked(A, T, np.ones((2, 1, 1)))
    >>> rho.round(6), X[1] is None
    (array([0.445, 1.445]), True)
    """
    G, M, n, _ = A.shape
    dim = M * n * n
    if dim > DENSE_MAX_RADIUS or dim > DENSE_MAX_SOLVE:
        rho = np.array([spectral_radius(loop, T) for loop in A])
        return rho, [solve_coupled_lyapunov(loop, T, W).X if r < 1 else None for loop, r in zip(A, rho)]
    kron = _kronecker_stack(A, T)
    rho = np.max(np.abs(np.linalg.eigvals(kron)), axis=1)
    return rho, [_sym(_Dense(loop, T, K).solve(W)) if r < 1 else None for loop, K, r in zip(A, kron, rho)]


def coupled_lyapunov_solver(A, T, method="auto", tol=SOLVE_TOLERANCE):
    """A function (W, adjoint=False) -> :class:`LyapunovSolution` for one closed loop A.

    The dense method factorises I - L once for all right-hand sides and both directions.
    Arguments as :func:`solve_coupled_lyapunov`.
    """
    M, n, _ = A.shape
    auto = method == "auto"
    if auto:
        method = "dense" if M * n * n <= DENSE_MAX_SOLVE else "bicgstab"
    if method == "dense":
        dense = _Dense(A, T)

        def solve(W, adjoint=False):
            X = _sym(dense.solve(W, adjoint))
            return LyapunovSolution(X=X, residual=residual(A, T, X, W, adjoint), method="dense", iterations=0)
        return solve
    if method not in ITERATIVE:
        raise ValueError(f"method: expected 'auto', 'dense' or one of {ITERATIVE}, found {method!r}")

    def solve(W, adjoint=False):
        with single_threaded():
            return _solve(W, adjoint)

    def _solve(W, adjoint):
        X, it = _iterative_solve(A, T, W, adjoint, method, tol)
        X, used = _sym(X), method
        res = residual(A, T, X, W, adjoint)
        if auto and not res <= 10 * tol:                  # BiCGSTAB stalled or broke down
            X2, it2 = _iterative_solve(A, T, W, adjoint, "gmres", tol, x0=X if np.all(np.isfinite(X)) else None)
            X2 = _sym(X2)
            res2 = residual(A, T, X2, W, adjoint)
            if not res <= res2:
                X, res, it, used = X2, res2, it + it2, "bicgstab+gmres"
        return LyapunovSolution(X=X, residual=res, method=used, iterations=it)
    return solve


ITERATIVE = ("bicgstab", "gmres", "fixed_point")


def _iterative_solve(A, T, W, adjoint, method, tol, max_iter=5000, x0=None):
    """X and the iteration count for X = L(X) + W by GMRES, BiCGSTAB or the fixed point."""
    M, n, _ = A.shape
    if method == "fixed_point":
        apply = costate_map if adjoint else second_moment_map
        X = W.copy()
        norm_W = max(np.linalg.norm(W), 1e-300)
        for it in range(1, max_iter + 1):
            X_new = apply(A, T, X) + W
            if np.linalg.norm(X_new - X) <= tol * norm_W or not np.all(np.isfinite(X_new)):
                return X_new, it
            X = X_new
        return X, max_iter
    count = [0]

    def callback(_):
        count[0] += 1

    op = _linear_operator(A, T, adjoint, shift=True)
    b = _sym(W).ravel()
    x0 = b if x0 is None else x0.ravel()
    if method == "gmres":
        x, _ = scipy.sparse.linalg.gmres(op, b, x0=x0, rtol=tol, atol=0.0, restart=60, maxiter=max_iter // 60 + 1,
                                         callback=callback, callback_type="pr_norm")
    else:
        x, _ = scipy.sparse.linalg.bicgstab(op, b, x0=x0, rtol=tol, atol=0.0, maxiter=max_iter, callback=callback)
    return x.reshape(M, n, n), count[0]


def closed_loop_unchecked(sys, L):
    """A_i + B_i L C_i of (3.10) for the inner loops of Alg. 3.1 (:func:`asoc.mjls.closed_loop` checks L)."""
    return sys.A + sys.B @ np.asarray(L, dtype=float).reshape(sys.nu, sys.ny) @ sys.C


def noise_covariances(sys):
    """H_i H_i^T (M, nx, nx) and J_i J_i^T (M, ny, ny) of (3.36); J = None means noise-free outputs.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> HHt, JJt = noise_covariances(sys)
    >>> HHt.shape, JJt.ravel().round(4)
    ((2, 2, 2), array([0.01, 0.01]))
    """
    check_system(sys)
    HHt = sys.H @ _T(sys.H)
    JJt = np.zeros((sys.M, sys.ny, sys.ny)) if sys.J is None else sys.J @ _T(sys.J)
    return HHt, JJt


def check_gains(sys, F, K, L):
    """Validate F (nc, nc), K (nc, ny), L (nu, nc) of (3.37); return them as arrays.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> check_gains(sec373_system(1), np.eye(2), np.ones((2, 1)), np.ones((1, 3)))
    Traceback (most recent call last):
    ...
    ValueError: L: expected shape (1, 2) (nc = 2 from F, nu = 1, ny = 1 from sys), found shape (1, 3)
    """
    check_system(sys)
    F = np.atleast_2d(real_array(F, "F"))
    nc = F.shape[0]
    F = real_array(F, "F", shape=(nc, nc))
    K, L = np.atleast_2d(real_array(K, "K")), np.atleast_2d(real_array(L, "L"))
    for name, g, shape in (("K", K, (nc, sys.ny)), ("L", L, (sys.nu, nc))):
        if g.shape != shape:
            raise ValueError(f"{name}: expected shape {shape} (nc = {nc} from F, nu = {sys.nu}, ny = {sys.ny} "
                             f"from sys), found shape {g.shape}")
    return F, K, L


def augmented_closed_loop(sys, F, K, L):
    """The augmented closed loop (3.39)-(3.40) and weight of Prop. 3.20 for x~ = [x; x^].

    A~_i = [[A_i, B_i L], [K C_i, F]], H~_i H~_i^T = diag(H_i H_i^T, K J_i J_i^T K^T),
    Q~_i = diag(Q_i, L^T R_i L).

    Parameters
    ----------
    sys : MJLS
    F, K, L : array_like, shapes (nc, nc), (nc, ny), (nu, nc)
        Gains of the controller (3.37).

    Returns
    -------
    At, HHt_cl, Qt : numpy.ndarray, each (M, nx + nc, nx + nc)

    Raises
    ------
    ValueError
        If a gain has the wrong shape or non-finite entries.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> At, Wt, Qt = augmented_closed_loop(sys, 0.5 * np.eye(2), np.ones((2, 1)), -np.ones((1, 2)))
    >>> At.shape, At[0, 2:, :2].tolist()
    ((2, 4, 4), [[1.0, 0.0], [1.0, 0.0]])
    """
    F, K, L = check_gains(sys, F, K, L)
    M, nx, nc = sys.M, sys.nx, F.shape[0]
    HHt, JJt = noise_covariances(sys)
    At = np.zeros((M, nx + nc, nx + nc))
    At[:, :nx, :nx] = sys.A
    At[:, :nx, nx:] = sys.B @ L
    At[:, nx:, :nx] = K @ sys.C
    At[:, nx:, nx:] = F
    HHt_cl = np.zeros_like(At)
    HHt_cl[:, :nx, :nx] = HHt
    HHt_cl[:, nx:, nx:] = K @ JJt @ K.T
    Qt = np.zeros_like(At)
    Qt[:, :nx, :nx] = sys.Q
    Qt[:, nx:, nx:] = L.T @ sys.R @ L
    return At, HHt_cl, Qt
