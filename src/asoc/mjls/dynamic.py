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
import scipy.sparse.linalg

from ..result import IterativeResult
from ..validation import boolean, choice, generator, integer, real_scalar
from .moments import steady_state_second_moment
from .operators import augmented_closed_loop, check_gains, noise_covariances  # noqa: F401 (public here)
from .operators import single_threaded
from .spectral import spectral_radius
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
#: From this many unknowns n^2 + n ny + nu n on, ``method="lstsq"`` solves (3.51) matrix-free
#: by conjugate gradients (:func:`solve_optimality_cg`) instead of np.linalg.lstsq on the dense
#: matrix. Measured crossover (one solve on the bounds of the 5th iteration of Alg. 3.2 on the
#: scaling family, n = 2..32, M = 2, 4, 8; medians, single-threaded LAPACK, 2 loaded cores),
#: dense against CG: 0.2-0.5 ms against 3.5-4.5 ms up to 48 unknowns (n = 6); 3.0-7.3 ms
#: against 3.7-4.0 ms at 195 (n = 13); 8.9-15 ms against 3.9-6.7 ms at 224 (n = 14);
#: 30-40 ms against 4-9 ms at 480 (n = 20); 0.44-0.64 s against 7-11 ms at 1280 (n = 32, up to
#: 13 s per dense solve on the bounds of the dense run). Threaded LAPACK on the loaded machine
#: took 0.1-1 s from ~100 unknowns on. The thesis's systems and those of the pages (at most
#: 104 unknowns) stay on the dense path.
MATRIX_FREE_MIN_UNKNOWNS = 200
#: Relative residual ||(H + delta I) dz - r|| / ||rho|| at which each conjugate-gradient solve stops.
CG_TOLERANCE = 1e-12
#: Iteration cap of conjugate gradients, as a multiple of the number of unknowns.
CG_MAX_ITER_FACTOR = 10
#: Steps of iterated Tikhonov regularisation in :func:`solve_optimality_cg`: one step leaves a
#: relative bias rcond cond(H) (1e-6 in the first iteration of Alg. 3.2 on the Sec. 3.7.3
#: example), two leave its square.
TIKHONOV_STEPS = 2


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


def gain_shapes(sys):
    """Shapes of F, K, L in the unknown z = [vec F; vec K; vec L] of (3.49).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> gain_shapes(sec373_system(1))
    ((2, 2), (2, 1), (1, 2))
    """
    return (sys.nx, sys.nx), (sys.nx, sys.ny), (sys.nu, sys.nx)


def stack_gains(F, K, L):
    """z = [vec F; vec K; vec L] of (3.49), column-stacking vec.

    Examples
    --------
    >>> stack_gains(np.array([[1.0, 2.0], [3.0, 4.0]]), np.zeros((2, 1)), np.ones((1, 2)))
    array([1., 3., 2., 4., 0., 0., 1., 1.])
    """
    return np.concatenate([np.reshape(G, -1, order="F") for G in (F, K, L)])


def split_gains(z, shapes):
    """F, K, L from z = [vec F; vec K; vec L] of (3.49); the inverse of :func:`stack_gains`.

    Examples
    --------
    >>> F, K, L = split_gains(np.arange(8.0), ((2, 2), (2, 1), (1, 2)))
    >>> F.tolist(), K.ravel().tolist(), L.tolist()
    ([[0.0, 2.0], [1.0, 3.0]], [4.0, 5.0], [[6.0, 7.0]])
    """
    ends = np.cumsum([0] + [a * b for a, b in shapes])
    return tuple(z[lo:hi].reshape(shape, order="F") for lo, hi, shape in zip(ends[:-1], ends[1:], shapes))


def optimality_vector(sys, Xbar, Xunder, EPbar, EPunder):
    """The vector rho of (3.49)/(3.70), built from (3.50): the conditions read H z + rho = 0.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> optimality_vector(sys, I, I, I, I).shape
    (8,)
    """
    A, B, C = sys.A, sys.B, sys.C
    S = Xbar + Xunder
    EP = EPbar + EPunder
    return np.concatenate([
        -(EPunder @ A @ Xunder).sum(axis=0).reshape(-1, order="F"),
        -(EPunder @ A @ S @ _T(C)).sum(axis=0).reshape(-1, order="F"),
        (_T(B) @ EP @ A @ Xunder).sum(axis=0).reshape(-1, order="F")])


def optimality_system(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
    """The matrix and vector of (3.49)/(3.70), built from (3.50).

    Unknown z = [vec F; vec K; vec L] (column-stacking vec); the conditions read H z + rho = 0.
    H is (half) the Hessian of the bounded cost (A.7)/(B.5), hence symmetric PSD. An
    inner-loop helper of Algs. 3.2-3.3: its arguments are not validated. Its size is
    (n^2 + n ny + nu n)^2; :class:`OptimalityOperator` applies it without forming it.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> H, rho = optimality_system(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> H.shape, rho.shape, np.allclose(H, H.T)
    ((8, 8), (8,), True)
    """
    B, C, R = sys.B, sys.C, sys.R
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
    return H, optimality_vector(sys, Xbar, Xunder, EPbar, EPunder)


class OptimalityOperator:
    """H of (3.49)/(3.70) applied matrix-free to (F, K, L), in O(M n^3) instead of O(n^4) memory.

    Each block of :func:`optimality_system` is a sum of Kronecker products, and
    (X (x) Y) vec Z = vec(Y Z X^T). With D_i = F + K C_i - B_i L and
    E_i = E_i(Punder) D_i Xunder_i the blocks of (3.50) add up to

    - F rows: sum_i E_i,
    - K rows: sum_i E_i C_i^T + E_i(Punder) K (C_i Xbar_i C_i^T + mu_i J_i J_i^T),
    - L rows: sum_i (R_i + B_i^T E_i(Pbar) B_i) L Xunder_i - B_i^T E_i,

    which is H z when Xbar, Xunder, EPbar, EPunder and R are symmetric (as the algorithms
    produce them). Arguments as :func:`optimality_system`, not validated.

    Attributes
    ----------
    shapes : tuple
        Shapes of F, K, L (:func:`gain_shapes`).
    size : int
        Number of unknowns n^2 + n ny + nu n.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> JJt = noise_covariances(sys)[1]
    >>> op = OptimalityOperator(sys, I, 2 * I, I, 3 * I, sys.mu_inf, JJt)
    >>> H, _ = optimality_system(sys, I, 2 * I, I, 3 * I, sys.mu_inf, JJt)
    >>> z = np.arange(8.0)
    >>> bool(np.allclose(op.matvec(z), H @ z))
    True
    """

    def __init__(self, sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
        self.B, self.C, self.Xunder, self.EPunder = sys.B, sys.C, Xunder, EPunder
        self.output_weight = sys.C @ Xbar @ _T(sys.C) + mu[:, None, None] * JJt     # (M, ny, ny)
        self.input_weight = sys.R + _T(sys.B) @ EPbar @ sys.B                       # (M, nu, nu)
        self.shapes = gain_shapes(sys)
        self.size = sum(a * b for a, b in self.shapes)

    def apply(self, F, K, L):
        """The F, K and L rows of H [vec F; vec K; vec L] as matrices of the shapes of F, K, L."""
        D = F + K @ self.C - self.B @ L
        E = self.EPunder @ D @ self.Xunder
        return (E.sum(axis=0),
                (E @ _T(self.C) + self.EPunder @ (K @ self.output_weight)).sum(axis=0),
                (self.input_weight @ L @ self.Xunder - _T(self.B) @ E).sum(axis=0))

    def matvec(self, z):
        """H z for z = [vec F; vec K; vec L]."""
        return stack_gains(*self.apply(*split_gains(z, self.shapes)))


def nearest_kronecker(X, Y, steps=50):
    """X0 (x) Y0 nearest in the Frobenius norm to sum_i X_i (x) Y_i (Van Loan and Pitsianis 1993).

    X0 = sum_i a_i X_i and Y0 = sum_i b_i Y_i, the leading singular pair of
    sum_i vec(X_i) vec(Y_i)^T, by power iteration on the M x M Gram matrices (for the
    preconditioner of (3.51); for positive semidefinite X_i, Y_i both are positive
    semidefinite).

    Examples
    --------
    >>> X = np.array([np.eye(2), 2 * np.eye(2)]); Y = np.array([np.eye(3), 2 * np.eye(3)])
    >>> X0, Y0 = nearest_kronecker(X, Y)
    >>> bool(np.allclose(np.kron(X0, Y0), np.kron(X[0], Y[0]) + np.kron(X[1], Y[1])))
    True
    """
    Gx, Gy = (np.einsum("iab,jab->ij", Z, Z) for Z in (X, Y))
    b = np.ones(len(Y))
    for _ in range(steps):
        b = Gx @ (Gy @ b)
        b /= max(np.linalg.norm(b), 1e-300)
    Y0_norm2 = b @ Gy @ b
    a = Gy @ b / Y0_norm2 if Y0_norm2 > 0 else np.zeros(len(X))
    return np.tensordot(a, X, 1), np.tensordot(b, Y, 1)


class KroneckerPreconditioner:
    """Block-diagonal approximate inverse of H + delta I of (3.51), one Kronecker product a block.

    Each diagonal block of :func:`optimality_system` (F, K, L) is replaced by its
    :func:`nearest_kronecker` X0 (x) Y0; with X0 = U diag(a) U^T, Y0 = W diag(b) W^T,
    (X0 (x) Y0 + delta I)^-1 vec Z = vec(W [(W^T Z U) / (b a^T + delta)] U^T). The F-K-L
    coupling and the spread over the modes are left to the conjugate gradients.

    Attributes
    ----------
    scale : float
        max over the blocks of ||X0|| ||Y0||, an estimate of ||H||_2 (the largest diagonal
        block).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> P = KroneckerPreconditioner(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> P.solve(np.ones(8), 0.0).shape, P.scale > 0
    ((8,), True)
    """

    def __init__(self, sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
        B, C = sys.B, sys.C
        pairs = (nearest_kronecker(Xunder, EPunder),
                 nearest_kronecker(C @ (Xbar + Xunder) @ _T(C) + mu[:, None, None] * JJt, EPunder),
                 nearest_kronecker(Xunder, sys.R + _T(B) @ (EPbar + EPunder) @ B))
        self.factors = [(*np.linalg.eigh(X0), *np.linalg.eigh(Y0)) for X0, Y0 in pairs]
        self.shapes = gain_shapes(sys)
        self.scale = max(float(np.abs(a).max() * np.abs(b).max()) for a, _, b, _ in self.factors)

    def solve(self, z, delta):
        """(P + delta I)^-1 z, P the block-diagonal Kronecker approximation of H."""
        out = []
        for (a, U, b, W), Z in zip(self.factors, split_gains(z, self.shapes)):
            scaled = (_T(W) @ Z @ U) / (np.maximum(np.outer(b, a), 0.0) + delta)
            out.append(W @ scaled @ _T(U))
        return stack_gains(*out)


@dataclass(frozen=True)
class GainSolve:
    """How (3.51) was solved.

    Attributes
    ----------
    method : str
        ``"dense"`` (np.linalg.lstsq), ``"cg"`` (:func:`solve_optimality_cg`) or ``"sdp"``.
    residual : float
        ||H z + rho|| / ||rho|| of the returned z (0 when rho = 0).
    iterations : int
        Conjugate-gradient iterations (0 otherwise).
    shift : float
        delta of the regularised system (H + delta I) z = -rho solved by ``"cg"`` (0 otherwise).

    Examples
    --------
    >>> GainSolve("cg", 3e-11, iterations=41, shift=1e-12)
    GainSolve(method='cg', residual=3e-11, iterations=41, shift=1e-12)
    """

    method: str
    residual: float
    iterations: int = 0
    shift: float = 0.0


def _relative_residual(Hz, rho):
    """||H z + rho|| / ||rho||, scaled against overflow (0 for rho = 0, nan for non-finite values)."""
    scale = float(np.max(np.abs(rho), initial=0.0))
    if scale == 0.0:
        return 0.0
    with np.errstate(invalid="ignore", over="ignore"):
        return float(np.linalg.norm((Hz + rho) / scale) / np.linalg.norm(rho / scale))


def solve_optimality_cg(op, rho, preconditioner, rcond=None, tol=None, max_iter=None):
    """(3.51) matrix-free: z ~ -H^+ rho by iterated Tikhonov, each step by preconditioned CG.

    The counterpart of the minimum-norm np.linalg.lstsq(H, -rho, rcond) for large systems.
    H is singular at the fixed point of Alg. 3.2 (see :data:`RANK_RTOL`): lstsq drops the
    singular values below rcond ||H||, here :data:`TIKHONOV_STEPS` steps of
    z <- z + (H + delta I)^-1 (-rho - H z) from z = 0, delta = rcond ||H|| (||H|| estimated by
    ``preconditioner.scale``; rcond None: machine epsilon times the number of unknowns, as
    LAPACK's), damp them. Each shifted system is positive definite and solved by conjugate
    gradients preconditioned with :class:`KroneckerPreconditioner`. A direction of H with
    eigenvalue lambda keeps the fraction 1 - (delta / (lambda + delta))^steps of its
    least-squares component (lstsq: 1 above delta, 0 below), so the two agree to about
    (rcond cond(H))^steps when H is well conditioned; when it is not, both are regularised
    solutions of an ill-posed system and may differ.

    Parameters
    ----------
    op : OptimalityOperator
    rho : numpy.ndarray
        The vector of (3.49) (:func:`optimality_vector`).
    preconditioner : KroneckerPreconditioner
    rcond : float, optional
    tol : float, optional
        Each step stops when its shifted residual falls below tol ||rho|| (default
        :data:`CG_TOLERANCE`).
    max_iter : int, optional
        Iteration cap of each step (default :data:`CG_MAX_ITER_FACTOR` times the number of
        unknowns).

    Returns
    -------
    z : numpy.ndarray
    GainSolve
        With the residual ||H z + rho|| / ||rho|| of the unshifted system and the total
        number of CG iterations.

    Raises
    ------
    numpy.linalg.LinAlgError
        If a step does not reach ``tol`` (10 ``tol`` after rounding) within ``max_iter``
        iterations; the message gives the residual reached.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> args = (sys, I, 2 * I, I, 3 * I, sys.mu_inf, noise_covariances(sys)[1])
    >>> H, rho = optimality_system(*args)
    >>> z, info = solve_optimality_cg(OptimalityOperator(*args), rho, KroneckerPreconditioner(*args))
    >>> bool(np.allclose(z, np.linalg.lstsq(H, -rho)[0], rtol=1e-12)), info.residual < 1e-12
    (True, True)
    """
    size = len(rho)
    if not np.any(rho):
        return np.zeros(size), GainSolve("cg", 0.0)
    delta = (np.finfo(float).eps * size if rcond is None else rcond) * preconditioner.scale
    max_iter = max(1, int(CG_MAX_ITER_FACTOR * size)) if max_iter is None else max_iter
    tol = CG_TOLERANCE if tol is None else tol
    norm_rho = float(np.linalg.norm(rho))
    shifted = scipy.sparse.linalg.LinearOperator((size, size), matvec=lambda z: op.matvec(z) + delta * z,
                                                 dtype=float)
    inverse = scipy.sparse.linalg.LinearOperator((size, size), matvec=lambda z: preconditioner.solve(z, delta),
                                                 dtype=float)
    z, iterations = np.zeros(size), 0
    with single_threaded():
        for _ in range(TIKHONOV_STEPS):
            target = -rho - op.matvec(z)
            step, count = _conjugate_gradients(shifted, target, inverse, tol * norm_rho, max_iter)
            iterations += count
            reached = float(np.linalg.norm(shifted.matvec(step) - target)) / norm_rho
            if not reached <= 10 * tol:
                raise np.linalg.LinAlgError(f"conjugate gradients on (3.51) reached the relative residual "
                                            f"{reached:.2g} > {tol:.2g} in {count} iterations ({size} unknowns)")
            z = z + step
        Hz = op.matvec(z)
    return z, GainSolve("cg", _relative_residual(Hz, rho), iterations, delta)


def _conjugate_gradients(A, b, inverse, atol, max_iter):
    """x with ||A x - b|| <= atol by scipy's preconditioned CG from 0, and the iteration count."""
    count = [0]

    def callback(_):
        count[0] += 1

    x, _ = scipy.sparse.linalg.cg(A, b, rtol=0.0, atol=atol, maxiter=max_iter, M=inverse, callback=callback)
    return x, count[0]


def gains_from_bounds(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method="lstsq", rcond=None):
    """F, K, L solving (3.51)/(3.71).

    ``"lstsq"``: the minimum-norm least-squares solution, i.e. the quadratic program (3.73)
    (it also covers singular systems, e.g. Punder = 0 at the end of a finite horizon, where
    F and K do not enter the cost), by np.linalg.lstsq below
    :data:`MATRIX_FREE_MIN_UNKNOWNS` unknowns, else by :func:`solve_optimality_cg`;
    ``"sdp"``: the SDP after Alg. 3.2 (min lambda with [[lambda I, G], [G^T, I]] >= 0,
    G = [F K L^T]) solved with cvxpy/Clarabel. ``rcond``: relative singular-value threshold of
    ``"lstsq"`` (None: LAPACK's eps * size).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> F, K, L = gains_from_bounds(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> F.shape, K.shape, L.shape
    ((2, 2), (2, 1), (1, 2))
    """
    return solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method, rcond)[:3]


def solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method="lstsq", rcond=None):
    """F, K, L solving (3.51)/(3.71) and a :class:`GainSolve` saying how; see :func:`gains_from_bounds`.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> *gains, info = solve_gains(sys, I, I, I, I, sys.mu_inf, noise_covariances(sys)[1])
    >>> info.method, info.residual < 1e-12
    ('dense', True)
    """
    choice(method, "method", METHODS)
    args = (sys, Xbar, Xunder, EPbar, EPunder, mu, JJt)
    shapes = gain_shapes(sys)
    if method == "lstsq" and sum(a * b for a, b in shapes) >= MATRIX_FREE_MIN_UNKNOWNS:
        z, info = solve_optimality_cg(OptimalityOperator(*args), optimality_vector(*args[:5]),
                                      KroneckerPreconditioner(*args), rcond)
        return (*split_gains(z, shapes), info)
    H, rho = optimality_system(*args)
    if method == "lstsq":
        z = np.linalg.lstsq(H, -rho, rcond=rcond)[0]
    elif method == "sdp":
        z = _gains_sdp(H, rho, *shapes[1], shapes[2][0])
    else:
        raise ValueError(f"method must be one of {METHODS}, found {method!r}")
    return (*split_gains(z, shapes), GainSolve("dense" if method == "lstsq" else method,
                                               _relative_residual(H @ z, rho)))


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
    solve : GainSolve
        How (3.51) was solved in the last iteration whose gains are returned (dense
        np.linalg.lstsq or matrix-free conjugate gradients, :data:`MATRIX_FREE_MIN_UNKNOWNS`),
        with its relative residual.
    worst_residual : float
        Largest relative residual ||H z + rho|| / ||rho|| of (3.51) over the iterations.

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
    solve: GainSolve = None
    worst_residual: float = 0.0


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
        Minimum-norm solution of (3.51) (relative threshold :data:`RANK_RTOL`; matrix-free
        from :data:`MATRIX_FREE_MIN_UNKNOWNS` unknowns on, see :func:`gains_from_bounds`), or
        the SDP after Alg. 3.2.
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
    gains = solve = None
    worst_residual, failure = 0.0, ""
    status, change = "max_iterations", np.inf
    it = 0
    for it in range(1, int(max_iter) + 1):
        EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
        try:
            F, K, L, step_solve = solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method, RANK_RTOL)
        except np.linalg.LinAlgError as error:
            status, failure = "linalg_error", str(error)
            break
        worst_residual = max(worst_residual, step_solve.residual) if np.isfinite(step_solve.residual) else np.nan
        new_X = bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt)
        new_P = bound_costate_step(sys, F, K, L, EPbar, EPunder)
        if not all(np.abs(v).max() < DIVERGED for v in (*new_X, *new_P)):
            status = "diverged"                     # the bounds diverge: not stabilisable this way
            break
        changes = [_rel_change(o, n) for o, n in zip((Xbar, Xunder, Pbar, Punder), (*new_X, *new_P))]
        if gains is not None:
            changes += [_rel_change(o, n, GAIN_FLOOR) for o, n in zip(gains, (F, K, L))]
        iterates.append(np.stack([*new_X, *new_P]))
        gains, solve = (F, K, L), step_solve
        Xbar, Xunder = new_X
        Pbar, Punder = new_P
        change = max(changes)
        if it > 1 and change < tol:
            status = "converged"
            break
    seconds = time.perf_counter() - start
    if gains is None:
        raise FloatingPointError(f"Algorithm 3.2: {'(3.51) could not be solved' if status == 'linalg_error' else 'the bounds diverged'} "
                                 f"in the first iteration{': ' + failure if failure else ''}")
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
               "linalg_error": f"stopped at iteration {it}: solving (3.51) failed (rho = {rho:.4f}; {failure})"}[status]
    if solve is not None and solve.method == "cg":
        message += (f"; (3.51) solved by conjugate gradients, largest relative residual "
                    f"||H z + rho|| / ||rho|| = {worst_residual:.1e}")
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
                                       seconds=seconds, solve=solve, worst_residual=worst_residual)
