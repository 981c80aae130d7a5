"""The optimality conditions (3.49)-(3.51) / (3.70)-(3.71) of Algs. 3.2 and 3.3, and their solvers.

The gains z = [vec F; vec K; vec L] (column-stacking vec, :func:`asoc.linalg.pack`) of the
bounded cost's stationary point solve H z + rho = 0 with H and rho built from (3.50).
:func:`optimality_system` forms H; :class:`OptimalityOperator` applies it matrix-free, and
:func:`solve_optimality_cg` solves it by conjugate gradients preconditioned with
:class:`KroneckerPreconditioner`. H is (numerically) singular at the fixed point of Alg. 3.2
when the controller state does not excite every direction, so (3.51) is solved in the
minimum-norm (regularised) sense: :func:`solve_gains`.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg

from .. import config
from ..linalg import kronecker_sum, pack, transpose, unpack
from ..threads import single_threaded
from ..validation import choice

__all__ = ["METHODS", "optimality_vector", "optimality_system", "OptimalityOperator",
           "KroneckerPreconditioner", "GainSolve", "solve_optimality_cg", "gains_from_bounds",
           "solve_gains"]


METHODS = ("lstsq", "sdp")


def _gain_shapes(sys):
    """Shapes of F, K, L in the unknown z = [vec F; vec K; vec L] of (3.49) (as asoc.linalg.pack).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> _gain_shapes(sec373_system(1))
    ((2, 2), (2, 1), (1, 2))
    """
    return (sys.nx, sys.nx), (sys.nx, sys.ny), (sys.nu, sys.nx)


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
        -(EPunder @ A @ S @ transpose(C)).sum(axis=0).reshape(-1, order="F"),
        (transpose(B) @ EP @ A @ Xunder).sum(axis=0).reshape(-1, order="F")])


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
    >>> H, rho = optimality_system(sys, I, I, I, I, sys.mu_inf, np.full((2, 1, 1), 0.01))
    >>> H.shape, rho.shape, np.allclose(H, H.T)
    ((8, 8), (8,), True)
    """
    B, C, R = sys.B, sys.C, sys.R
    S = Xbar + Xunder
    EP = EPbar + EPunder
    m = mu[:, None, None]
    EPuB = EPunder @ B
    XuCt = Xunder @ transpose(C)
    nF, nK = sys.nx * sys.nx, sys.nx * sys.ny
    blocks = ((slice(0, nF), slice(0, nF), kronecker_sum(Xunder, EPunder)),                  # Phi_F
              (slice(nF, nF + nK), slice(nF, nF + nK),
               kronecker_sum(m * JJt + C @ S @ transpose(C), EPunder)),
              (slice(nF + nK, None), slice(nF + nK, None),
               kronecker_sum(Xunder, R + transpose(B) @ EP @ B)),
              (slice(0, nF), slice(nF, nF + nK), kronecker_sum(XuCt, EPunder)),           # Gamma_FK
              (slice(0, nF), slice(nF + nK, None), -kronecker_sum(Xunder, EPuB)),         # Gamma_FL
              (slice(nF, nF + nK), slice(nF + nK, None),
               -kronecker_sum(transpose(XuCt), EPuB)))                                    # Gamma_KL
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
        Shapes of F, K, L (``_gain_shapes``).
    size : int
        Number of unknowns n^2 + n ny + nu n.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> JJt = np.full((2, 1, 1), 0.01)
    >>> op = OptimalityOperator(sys, I, 2 * I, I, 3 * I, sys.mu_inf, JJt)
    >>> H, _ = optimality_system(sys, I, 2 * I, I, 3 * I, sys.mu_inf, JJt)
    >>> z = np.arange(8.0)
    >>> bool(np.allclose(op.matvec(z), H @ z))
    True
    """

    def __init__(self, sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
        self.B, self.C, self.Xunder, self.EPunder = sys.B, sys.C, Xunder, EPunder
        # output weight (M, ny, ny) and input weight (M, nu, nu)
        self.output_weight = sys.C @ Xbar @ transpose(sys.C) + mu[:, None, None] * JJt
        self.input_weight = sys.R + transpose(sys.B) @ EPbar @ sys.B
        self.shapes = _gain_shapes(sys)
        self.size = sum(a * b for a, b in self.shapes)

    def apply(self, F, K, L):
        """The F, K and L rows of H [vec F; vec K; vec L] as matrices of the shapes of F, K, L."""
        D = F + K @ self.C - self.B @ L
        E = self.EPunder @ D @ self.Xunder
        return (E.sum(axis=0),
                (E @ transpose(self.C) + self.EPunder @ (K @ self.output_weight)).sum(axis=0),
                (self.input_weight @ L @ self.Xunder - transpose(self.B) @ E).sum(axis=0))

    def matvec(self, z):
        """H z for z = [vec F; vec K; vec L]."""
        return pack(*self.apply(*unpack(z, self.shapes)))


def _nearest_kronecker(X, Y, steps=50):
    """X0 (x) Y0 nearest in the Frobenius norm to sum_i X_i (x) Y_i (Van Loan and Pitsianis 1993).

    X0 = sum_i a_i X_i and Y0 = sum_i b_i Y_i, the leading singular pair of
    sum_i vec(X_i) vec(Y_i)^T, by power iteration on the M x M Gram matrices (for the
    preconditioner of (3.51); for positive semidefinite X_i, Y_i both are positive
    semidefinite).

    Examples
    --------
    >>> X = np.array([np.eye(2), 2 * np.eye(2)]); Y = np.array([np.eye(3), 2 * np.eye(3)])
    >>> X0, Y0 = _nearest_kronecker(X, Y)
    >>> bool(np.allclose(np.kron(X0, Y0), np.kron(X[0], Y[0]) + np.kron(X[1], Y[1])))
    True
    """
    Gx, Gy = (np.einsum("iab,jab->ij", Z, Z) for Z in (X, Y))
    b = np.ones(len(Y))
    for _ in range(steps):
        b = Gx @ (Gy @ b)
        b /= max(np.linalg.norm(b), np.finfo(float).tiny)
    Y0_norm2 = b @ Gy @ b
    a = Gy @ b / Y0_norm2 if Y0_norm2 > 0 else np.zeros(len(X))
    return np.tensordot(a, X, 1), np.tensordot(b, Y, 1)


class KroneckerPreconditioner:
    """Block-diagonal approximate inverse of H + delta I of (3.51), one Kronecker product a block.

    Each diagonal block of :func:`optimality_system` (F, K, L) is replaced by its
    ``_nearest_kronecker`` X0 (x) Y0; with X0 = U diag(a) U^T, Y0 = W diag(b) W^T,
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
    >>> P = KroneckerPreconditioner(sys, I, I, I, I, sys.mu_inf, np.full((2, 1, 1), 0.01))
    >>> P.solve(np.ones(8), 0.0).shape, P.scale > 0
    ((8,), True)
    """

    def __init__(self, sys, Xbar, Xunder, EPbar, EPunder, mu, JJt):
        B, C = sys.B, sys.C
        pairs = (_nearest_kronecker(Xunder, EPunder),
                 _nearest_kronecker(C @ (Xbar + Xunder) @ transpose(C)
                                    + mu[:, None, None] * JJt, EPunder),
                 _nearest_kronecker(Xunder, sys.R + transpose(B) @ (EPbar + EPunder) @ B))
        self.factors = [(*np.linalg.eigh(X0), *np.linalg.eigh(Y0)) for X0, Y0 in pairs]
        self.shapes = _gain_shapes(sys)
        self.scale = max(float(np.abs(a).max() * np.abs(b).max()) for a, _, b, _ in self.factors)

    def solve(self, z, delta):
        """(P + delta I)^-1 z, P the block-diagonal Kronecker approximation of H."""
        out = []
        for (a, U, b, W), Z in zip(self.factors, unpack(z, self.shapes)):
            scaled = (transpose(W) @ Z @ U) / (np.maximum(np.outer(b, a), 0.0) + delta)
            out.append(W @ scaled @ transpose(U))
        return pack(*out)


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
    """||H z + rho|| / ||rho||, scaled against overflow (0 for rho = 0, nan if not finite)."""
    scale = float(np.max(np.abs(rho), initial=0.0))
    if scale == 0.0:
        return 0.0
    with np.errstate(invalid="ignore", over="ignore"):
        return float(np.linalg.norm((Hz + rho) / scale) / np.linalg.norm(rho / scale))


def solve_optimality_cg(op, rho, preconditioner, rcond=None, tol=None, max_iter=None):
    """(3.51) matrix-free: z ~ -H^+ rho by iterated Tikhonov, each step by preconditioned CG.

    The counterpart of the minimum-norm np.linalg.lstsq(H, -rho, rcond) for large systems.
    H is singular at the fixed point of Alg. 3.2 (see ``config.defaults["mjls.rank_rtol"]``): lstsq
    drops the singular values below rcond ||H||, here ``mjls.tikhonov_steps`` steps of
    z <- z + (H + delta I)^-1 (-rho - H z) from z = 0, delta = rcond ||H|| (||H|| estimated by
    ``preconditioner.scale``; rcond None: machine epsilon times the number of unknowns, as
    LAPACK's), damp them. Each shifted system is positive definite and solved by conjugate gradients
    preconditioned with :class:`KroneckerPreconditioner`. A direction of H with eigenvalue lambda
    keeps the fraction 1 - (delta / (lambda + delta))^steps of its least-squares component (lstsq: 1
    above delta, 0 below), so the two agree to about (rcond cond(H))^steps when H is well
    conditioned; when it is not, both are regularised solutions of an ill-posed system and may
    differ.

    Parameters
    ----------
    op : OptimalityOperator
    rho : numpy.ndarray
        The vector of (3.49) (:func:`optimality_vector`).
    preconditioner : KroneckerPreconditioner
    rcond : float, optional
    tol : float, optional
        Each step stops when its shifted residual falls below tol ||rho|| (default
        ``config.defaults["mjls.cg_tolerance"]``).
    max_iter : int, optional
        Iteration cap of each step (default ``mjls.cg_max_iter_factor`` times the number of
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
    >>> args = (sys, I, 2 * I, I, 3 * I, sys.mu_inf, np.full((2, 1, 1), 0.01))
    >>> H, rho = optimality_system(*args)
    >>> z, info = solve_optimality_cg(OptimalityOperator(*args), rho,
    ...                               KroneckerPreconditioner(*args))
    >>> bool(np.allclose(z, np.linalg.lstsq(H, -rho)[0], rtol=1e-12)), info.residual < 1e-12
    (True, True)
    """
    size = len(rho)
    if not np.any(rho):
        return np.zeros(size), GainSolve("cg", 0.0)
    delta = (np.finfo(float).eps * size if rcond is None else rcond) * preconditioner.scale
    if max_iter is None:
        max_iter = max(1, int(config.defaults["mjls.cg_max_iter_factor"] * size))
    tol = config.defaults["mjls.cg_tolerance"] if tol is None else tol
    norm_rho = float(np.linalg.norm(rho))
    shifted = scipy.sparse.linalg.LinearOperator((size, size),
                                                 matvec=lambda z: op.matvec(z) + delta * z,
                                                 dtype=float)
    inverse = scipy.sparse.linalg.LinearOperator((size, size),
                                                 matvec=lambda z: preconditioner.solve(z, delta),
                                                 dtype=float)
    z, iterations = np.zeros(size), 0
    with single_threaded():
        for _ in range(config.defaults["mjls.tikhonov_steps"]):
            target = -rho - op.matvec(z)
            step, count = _conjugate_gradients(shifted, target, inverse, tol * norm_rho, max_iter)
            iterations += count
            reached = float(np.linalg.norm(shifted.matvec(step) - target)) / norm_rho
            if not reached <= 10 * tol:
                raise np.linalg.LinAlgError("conjugate gradients on (3.51) reached the relative "
                                            f"residual {reached:.2g} > {tol:.2g} in {count} "
                                            f"iterations ({size} unknowns)")
            z = z + step
        Hz = op.matvec(z)
    return z, GainSolve("cg", _relative_residual(Hz, rho), iterations, delta)


def _conjugate_gradients(A, b, inverse, atol, max_iter):
    """X with ||A x - b|| <= atol by scipy's preconditioned CG from 0, and the iteration count."""
    count = [0]

    def callback(_):
        count[0] += 1

    x, _ = scipy.sparse.linalg.cg(A, b, rtol=0.0, atol=atol, maxiter=max_iter, M=inverse,
                                  callback=callback)
    return x, count[0]


def gains_from_bounds(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method="lstsq", rcond=None):
    """F, K, L solving (3.51)/(3.71).

    ``"lstsq"``: the minimum-norm least-squares solution, i.e. the quadratic program (3.73) (it also
    covers singular systems, e.g. Punder = 0 at the end of a finite horizon, where F and K do not
    enter the cost), by np.linalg.lstsq below ``config.defaults["mjls.matrix_free_min_unknowns"]``
    unknowns, else by :func:`solve_optimality_cg`; ``"sdp"``: the SDP after Alg. 3.2 (min lambda
    with [[lambda I, G], [G^T, I]] >= 0, G = [F K L^T]) solved with cvxpy/Clarabel. ``rcond``:
    relative singular-value threshold of ``"lstsq"`` (None: LAPACK's eps * size).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> F, K, L = gains_from_bounds(sys, I, I, I, I, sys.mu_inf, np.full((2, 1, 1), 0.01))
    >>> F.shape, K.shape, L.shape
    ((2, 2), (2, 1), (1, 2))
    """
    return solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method, rcond)[:3]


def solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method="lstsq", rcond=None):
    """F, K, L solving (3.51)/(3.71) and a :class:`GainSolve` saying how (see gains_from_bounds).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> *gains, info = solve_gains(sys, I, I, I, I, sys.mu_inf, np.full((2, 1, 1), 0.01))
    >>> info.method, info.residual < 1e-12
    ('dense', True)
    """
    choice(method, "method", METHODS)
    args = (sys, Xbar, Xunder, EPbar, EPunder, mu, JJt)
    shapes = _gain_shapes(sys)
    n_unknowns = sum(a * b for a, b in shapes)
    if method == "lstsq" and n_unknowns >= config.defaults["mjls.matrix_free_min_unknowns"]:
        z, info = solve_optimality_cg(OptimalityOperator(*args), optimality_vector(*args[:5]),
                                      KroneckerPreconditioner(*args), rcond)
        return (*unpack(z, shapes), info)
    H, rho = optimality_system(*args)
    if method == "lstsq":
        z = np.linalg.lstsq(H, -rho, rcond=rcond)[0]
    elif method == "sdp":
        z = _gains_sdp(H, rho, *shapes[1], shapes[2][0])
    else:
        raise ValueError(f"method must be one of {METHODS}, found {method!r}")
    return (*unpack(z, shapes), GainSolve("dense" if method == "lstsq" else method,
                                               _relative_residual(H @ z, rho)))


def _gains_sdp(H, rho, n, ny, nu):
    """The SDP recommended after Alg. 3.2: min lambda, [[lambda I, G], [G^T, I]] >= 0, (3.49)."""
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
    return pack(F.value, K.value, L.value)
