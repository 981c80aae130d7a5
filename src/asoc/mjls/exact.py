"""Controllers (3.37) and (3.55) that minimise the exact cost instead of its bound (not in the thesis).

Algorithms 3.2 and 3.3 minimise the costs of the bounded second moments of Prop. 3.26 and
Thm. 3.31, which are not upper bounds of the true costs (Secs. 3.6-3.7 page). Here the exact
average cost (3.42) (Prop. 3.24), resp. the exact expected cost J_0 (3.56) from the augmented
recursion (3.58), is minimised over the gains by BFGS. The gradient is analytic: with the
augmented closed loop A~_i, W_i = H~_i H~_i^T and Q~_i of (3.39)-(3.40) and Prop. 3.20,

    X_j = sum_i p_ij [A~_i X_i A~_i^T + mu_i W_i]   (Prop. 3.23),
    P_i = Q~_i + A~_i^T E_i(P) A~_i                  (its adjoint, the costate),

the cost J = sum_i tr[Q~_i X_i] has dJ/dA~_i = 2 E_i(P) A~_i X_i, dJ/dW_i = mu_i E_i(P) and
dJ/dQ~_i = X_i; the finite-horizon case uses the same relations step by step.
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from ..progress import progress_bar
from ..result import IterativeResult
from ..validation import boolean, integer, real_scalar
from .dynamic import dynamic_output_feedback
from .finite_horizon import (_initial_gains, augmented_initial_moment, check_initial_state, finite_horizon_cost,
                             finite_horizon_dynamic_output_feedback, mode_distributions, stages,
                             time_variant_controller)
from .. import config
from .lyapunov import coupled_lyapunov_solver
from .operators import (augmented_closed_loop, costate_map, ms_operator, noise_covariances, second_moment_map,
                        single_threaded)
from .spectral import spectral_radius
from .system import check_system, predecessor_sum, successor_average

ARMIJO = 1e-4                 # sufficient-decrease constant of the backtracking line search
MIN_STEP = 2.0 ** -40         # the line search gives up below this step length
RHO_START = 0.999             # the stabilising search stops once rho is below this
RADIUS_MAX_ITER = 1000        # BFGS iterations of a search that minimises rho
LBFGS_MEMORY = 200            # pairs kept by L-BFGS for the K (nc^2 + nc ny + nu nc) time-variant gains


BFGS_STATUS = {"converged": "the decrease the quasi-Newton model predicts fell below tol * |f|",
               "max_iterations": "the iteration limit was reached",
               "no_progress": "the line search found no decrease even along the gradient"}


@dataclass(kw_only=True)
class ExactDynamicOutputFeedbackResult(IterativeResult):
    """Result of :func:`exact_dynamic_output_feedback` (BFGS on the exact cost (3.42)).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (nc, nc), (nc, ny), (nu, nc)
        The controller (3.37).
    converged, status, message
        Why BFGS stopped: ``"converged"`` (the decrease its model predicts is below
        tol * cost), ``"max_iterations"`` or ``"no_progress"`` (no descent step, or no
        mean-square stabilising start was found).
    iterations : int
    rho : float
        Mean-square spectral radius of the closed loop (Cor. 3.2).
    stabilizing : bool
    cost : float
        Exact average cost (3.42) (Prop. 3.24); inf if not stabilizing.
    history : dict
        ``"cost"``: the exact cost after each iteration.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> res = exact_dynamic_output_feedback(sys, max_iter=3, warn=False)
    >>> res.status, res.iterations, sorted(res.history)
    ('max_iterations', 3, ['cost'])
    """

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    iterations: int
    rho: float
    stabilizing: bool
    cost: float
    history: dict = field(repr=False)
    seconds: float = 0.0


@dataclass(kw_only=True)
class MinRadiusResult(IterativeResult):
    """Result of :func:`min_radius_dynamic_output_feedback` (BFGS on rho, Cor. 3.2).

    Attributes
    ----------
    F, K, L : numpy.ndarray
        The controller (3.37) of smallest rho found.
    converged, status, message
        Why BFGS stopped (as :class:`ExactDynamicOutputFeedbackResult`).
    iterations : int
    rho : float
    stabilizing : bool
    cost : float
        Exact average cost (3.42) if stabilizing, else inf.
    history : dict
        ``"rho"``: rho after each iteration.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> res = min_radius_dynamic_output_feedback(sys, max_iter=3)
    >>> res.status, res.iterations, sorted(res.history)
    ('max_iterations', 3, ['rho'])
    """

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    iterations: int
    rho: float
    stabilizing: bool
    cost: float
    history: dict = field(repr=False)
    seconds: float = 0.0


@dataclass(kw_only=True)
class ExactFiniteHorizonResult(IterativeResult):
    """Result of :func:`exact_finite_horizon_dynamic_output_feedback` (L-BFGS on J_0 (3.56)).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (horizon, nc, nc), (horizon, nc, ny), (horizon, nu, nc)
        The gains of (3.55) per step.
    xhat0 : numpy.ndarray, shape (nc,)
        The controller's initial state E{x_0}.
    converged, status, message
        Why L-BFGS stopped (as :class:`ExactDynamicOutputFeedbackResult`).
    iterations : int
    cost : float
        The exact expected cost J_0 (3.56) of the final gains.
    costs : numpy.ndarray
        The exact J_0 after each iteration.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = exact_finite_horizon_dynamic_output_feedback(sys, 5, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0,
    ...                                                    max_iter=3, warn=False)
    >>> res.status, res.F.shape, res.costs.size
    ('max_iterations', (5, 2, 2), 4)
    """

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    xhat0: np.ndarray
    iterations: int
    cost: float
    costs: np.ndarray = field(repr=False)
    seconds: float = 0.0

    def controller(self):
        """The controller (3.55) for :func:`asoc.mjls.simulate`."""
        return time_variant_controller(self)


def _pack(F, K, L):
    return np.concatenate([np.ravel(F), np.ravel(K), np.ravel(L)])


def _unpack(z, shapes):
    out, start = [], 0
    for shape in shapes:
        size = int(np.prod(shape))
        out.append(z[start:start + size].reshape(shape))
        start += size
    return out


def _closed_loop_gradient(sys, G):
    """The gradient over (F, K, L) of a function of A~ (3.39) alone, from G_i = d/dA~_i."""
    nx = sys.nx
    gF = G[:, nx:, nx:].sum(axis=0)
    gK = (G[:, nx:, :nx] @ np.swapaxes(sys.C, 1, 2)).sum(axis=0)
    gL = (np.swapaxes(sys.B, 1, 2) @ G[:, :nx, nx:]).sum(axis=0)
    return gF, gK, gL


def gain_gradient(sys, K, L, At, X, EP, JJt, mu):
    """dJ/dF, dJ/dK, dJ/dL from the moments X and costates E_i(P) (adjoint of Prop. 3.23).

    Parameters
    ----------
    sys : MJLS (one step of (3.36)/(3.54)).
    K, L : the gains of (3.37); F enters only through ``At``.
    At : (M, n, n) augmented closed loop (3.39).
    X : (M, n, n) augmented second moments at this step.
    EP : (M, n, n) E_i(P) of the costates at the next step.
    JJt : (M, ny, ny) measurement-noise covariances; mu : (M,) mode distribution.

    Returns
    -------
    (gF, gK, gL) : arrays of the shapes of F, K, L.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> At, Wt, Qt = augmented_closed_loop(sys, F, K, L)
    >>> I = np.broadcast_to(np.eye(4), (2, 4, 4))
    >>> gF, gK, gL = gain_gradient(sys, K, L, At, I, I, noise_covariances(sys)[1], sys.mu_inf)
    >>> gF.shape, gK.shape, gL.shape
    ((2, 2), (2, 1), (1, 2))
    """
    nx = sys.nx
    gF, gK, gL = _closed_loop_gradient(sys, 2.0 * EP @ At @ X)        # dJ/dA~_i
    gK += 2.0 * (mu[:, None, None] * EP[:, nx:, nx:] @ K @ JJt).sum(axis=0)
    gL += 2.0 * (sys.R @ L @ X[:, nx:, nx:]).sum(axis=0)
    return gF, gK, gL


def average_cost_and_gradient(sys, F, K, L):
    """Exact average cost (3.42) (Prop. 3.24) of (3.37) and its gradient over (F, K, L).

    Mean-square stability is tested without eigenvalues: the closed loop is stable iff the
    solution Y of Y_j = sum_i p_ij A~_i Y_i A~_i^T + I is positive definite (the coupled
    Lyapunov test, cf. Thm. 3.9); Y, X and P come from one solver
    (:func:`asoc.mjls.lyapunov.coupled_lyapunov_solver`: one LU factorisation when M n^2 is
    small, else BiCGSTAB on the operator; a Y whose relative residual exceeds 1e-8 counts
    as not stable).

    Parameters
    ----------
    sys : MJLS with measurement noise J (Sec. 3.6).
    F, K, L : gains of (3.37), shapes (nc, nc), (nc, ny), (nu, nc).

    Returns
    -------
    (cost, (gF, gK, gL)) : cost is inf and the gradient None when A~ is not mean-square
        stable (Cor. 3.2).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> cost, gradient = average_cost_and_gradient(sys, F, K, L)
    >>> cost, gradient
    (inf, None)
    >>> r = dynamic_output_feedback(sys)
    >>> cost, (gF, gK, gL) = average_cost_and_gradient(sys, r.F, r.K, r.L)
    >>> round(cost, 3), gL.shape
    (23.313, (1, 2))
    """
    At, Wt, Qt = augmented_closed_loop(sys, F, K, L)
    M, n, _ = At.shape
    solve = coupled_lyapunov_solver(At, sys.T)
    Y = solve(np.broadcast_to(np.eye(n), (M, n, n)), on_miss="report")
    if not (np.all(np.isfinite(Y.X)) and Y.residual < 1e-8 and _positive_definite(Y.X)):
        return np.inf, None
    mu = sys.mu_inf
    X = solve(predecessor_sum(sys.T, mu[:, None, None] * Wt)).X
    P = solve(Qt, adjoint=True).X
    cost = float(np.einsum("iab,iba->", Qt, X))
    return cost, gain_gradient(sys, K, L, At, X, successor_average(sys.T, P), noise_covariances(sys)[1], mu)


def _positive_definite(Y):
    try:
        np.linalg.cholesky(Y)
    except np.linalg.LinAlgError:
        return False
    return True


def closed_loop_radius(sys, F, K, L):
    """Mean-square spectral radius (Cor. 3.2) of the augmented closed loop (3.39).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> round(closed_loop_radius(sys, F, K, L), 4)
    1.3449
    """
    return spectral_radius(augmented_closed_loop(sys, F, K, L)[0], sys.T)


def radius_and_gradient(sys, F, K, L):
    """Mean-square spectral radius rho (Cor. 3.2) of (3.37) and its gradient over (F, K, L).

    rho is an eigenvalue of the positive operator X -> D_j(A~ X A~^T) (Prop. 3.23 without
    noise), with positive semidefinite right and left eigenvectors X and V (Krein-Rutman;
    Costa, Fragoso and Marques 2005, Ch. 3). Where it is simple, first-order eigenvalue
    perturbation gives d rho = <V, predecessor_sum(dA~ X A~^T + A~ X dA~^T)> / <V, X>, i.e.
    d rho / dA~_i = 2 E_i(V) A~_i X_i / <V, X>. rho is only piecewise smooth (eigenvalues may
    coalesce); BFGS is used on it regardless (Lewis and Overton, Math. Program. 141, 2013).

    Parameters
    ----------
    sys : MJLS; F, K, L : gains of (3.37).

    Returns
    -------
    (rho, (gF, gK, gL)) : the gradient is zero where <V, X> vanishes (rho not differentiable).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> rho, (gF, gK, gL) = radius_and_gradient(sys, F, K, L)
    >>> round(rho, 4), gF.shape
    (1.3449, (2, 2))
    """
    At = augmented_closed_loop(sys, F, K, L)[0]
    rho, X, V = _perron_pair(At, sys.T)
    inner = float(np.einsum("iab,iab->", V, X))
    if not abs(inner) > 1e-12 * np.linalg.norm(V) * np.linalg.norm(X):
        return rho, _closed_loop_gradient(sys, np.zeros_like(At))
    return rho, _closed_loop_gradient(sys, 2.0 * successor_average(sys.T, V) @ At @ X / inner)


def _perron_pair(At, T):
    """rho and the right and left Perron eigenvectors X, V (real symmetric stacks) of the
    second-moment operator: dense eigenvectors for small M n^2, else Arnoldi on L and L*."""
    M, n, _ = At.shape
    if M * n * n <= config.defaults["mjls.dense_max_radius"]:
        lam, left, right = scipy.linalg.eig(ms_operator(At, T, check=False), left=True, right=True)
        rho = float(np.max(np.abs(lam)))
        top = np.flatnonzero(np.abs(lam) >= rho * (1 - 1e-9))
        k = top[np.argmax(lam[top].real)]                             # the real Perron eigenvalue
        return rho, *(_real_symmetric(v[:, k].reshape(M, n, n)) for v in (right, left))
    vectors = []
    for apply in (second_moment_map, costate_map):
        op = scipy.sparse.linalg.LinearOperator(
            (M * n * n,) * 2, dtype=float,
            matvec=lambda x, f=apply: f(At, T, _symmetric(x.real.reshape(M, n, n))).ravel())
        with single_threaded():
            lam, v = scipy.sparse.linalg.eigs(op, k=1, which="LM", tol=1e-14, ncv=min(M * n * n - 1, 20),
                                              maxiter=max(1000, M * n * n),
                                              v0=np.broadcast_to(np.eye(n), (M, n, n)).ravel())
        vectors.append(_real_symmetric(v[:, 0].reshape(M, n, n)))
    return float(abs(lam[0])), *vectors


def _symmetric(Z):
    return 0.5 * (Z + np.swapaxes(Z, 1, 2))


def _real_symmetric(Z):
    """The real symmetric part of a complex eigenvector Z after removing its phase."""
    z = Z.ravel()
    Z = (Z * np.conj(z[np.argmax(np.abs(z))])).real
    return 0.5 * (Z + np.swapaxes(Z, 1, 2))


class _InverseHessian:
    """The BFGS inverse-Hessian approximation: dense, or limited-memory (the last ``memory``
    pairs, two-loop recursion) for many variables; empty means a scaled identity."""

    def __init__(self, n, memory):
        self.n, self.memory = n, memory
        self.reset()

    def reset(self):
        self.pairs, self.dense, self.scale = [], None, None

    @property
    def empty(self):
        return self.scale is None

    def apply(self, g):
        if self.empty:
            return g / max(1.0, float(np.linalg.norm(g)))
        if self.memory is None:
            return self.dense @ g
        q, alphas = g.copy(), []
        for s, y, r in reversed(self.pairs):
            alphas.append(r * float(s @ q))
            q -= alphas[-1] * y
        q *= self.scale
        for (s, y, r), a in zip(self.pairs, reversed(alphas)):
            q += (a - r * float(y @ q)) * s
        return q

    def update(self, s, y):
        sy = float(s @ y)
        if not sy > 1e-12 * np.linalg.norm(s) * np.linalg.norm(y):
            return                                     # curvature condition fails: skip
        if self.memory is not None:
            self.scale = sy / float(y @ y)
            self.pairs = (self.pairs + [(s, y, 1.0 / sy)])[-self.memory:]
            return
        if self.empty:
            self.scale = sy / float(y @ y)
            self.dense = self.scale * np.eye(self.n)
        Hy = self.dense @ y                            # rank-2 update as one product
        a = (1.0 + float(y @ Hy) / sy) / sy
        self.dense += np.column_stack([s, Hy]) @ np.column_stack([a * s - Hy / sy, -s / sy]).T


def bfgs(fun, z0, tol, max_iter, progress=False, desc="BFGS", memory=None, target=-np.inf):
    """Minimise ``fun`` (z -> (f, grad); f = inf outside the domain) by BFGS.

    The line search backtracks from the full quasi-Newton step until the Armijo condition
    holds (up to rounding of f); a step out of the domain (f = inf) is rejected like any
    other. The iteration stops (converged) when the decrease the quasi-Newton model predicts,
    g^T H^-1 g / 2, is below ``tol * |f|``, or once f <= ``target``. ``memory``: None for
    dense BFGS, else L-BFGS with that many pairs.

    Returns
    -------
    (z, f, status, iterations, history) : status a key of :data:`BFGS_STATUS`; history holds
        f after each iteration.

    Examples
    --------
    >>> fun = lambda z: ((z[0] - 1) ** 2 + 10 * (z[1] - z[0] ** 2) ** 2,
    ...                  np.array([2 * (z[0] - 1) - 40 * z[0] * (z[1] - z[0] ** 2), 20 * (z[1] - z[0] ** 2)]))
    >>> z, f, status, iterations, history = bfgs(fun, np.array([-1.0, 1.0]), 1e-14, 200)
    >>> status, z.round(4)
    ('converged', array([1., 1.]))
    """
    z = np.asarray(z0, dtype=float)
    f, g = fun(z)
    if not np.isfinite(f):
        raise ValueError("z0: the start is outside the domain (cost is inf)")
    Hinv = _InverseHessian(z.size, memory)
    history = [f]
    status = "max_iterations"
    it = 0
    for it in progress_bar(range(1, int(max_iter) + 1), progress, desc=desc, leave=False):
        fresh = Hinv.empty
        d = -Hinv.apply(g)
        slope = float(g @ d)
        if -0.5 * slope <= tol * abs(f) or f <= target:
            status = "converged"
            break
        t = 1.0
        while t >= MIN_STEP:
            z_new = z + t * d
            f_new, g_new = fun(z_new)
            if f_new <= f + ARMIJO * t * slope + 4 * np.finfo(float).eps * abs(f):
                break
            t *= 0.5
        else:
            if fresh:                                  # no descent even along -g: stop
                status = "no_progress"
                break
            Hinv.reset()                               # restart from a scaled gradient step
            continue
        Hinv.update(z_new - z, g_new - g)
        z, f, g = z_new, f_new, g_new
        history.append(f)
    return z, f, status, it, np.array(history)


def _start_gains(sys, init, nc):
    """(F, K, L) from ``init`` (result or tuple), else Alg. 3.2's result padded/cut to nc states
    (zeros when Alg. 3.2 diverges at once)."""
    if init is None:
        nc = sys.nx if nc is None else nc
        F0, K0, L0 = np.zeros((nc, nc)), np.zeros((nc, sys.ny)), np.zeros((sys.nu, nc))
        try:
            r = dynamic_output_feedback(sys, warn=False)
        except FloatingPointError:
            return F0, K0, L0
        m = min(nc, sys.nx)
        F0[:m, :m], K0[:m], L0[:, :m] = r.F[:m, :m], r.K[:m], r.L[:, :m]
        return F0, K0, L0
    gains = (init.F, init.K, init.L) if all(hasattr(init, g) for g in "FKL") else init
    if not (isinstance(gains, (tuple, list)) and len(gains) == 3):
        raise TypeError(f"init: expected a result with F, K, L (e.g. of dynamic_output_feedback) or a "
                        f"tuple (F, K, L), found {type(init).__name__}"
                        f"{f' of length {len(init)}' if isinstance(init, (tuple, list)) else ''}")
    F = np.atleast_2d(np.asarray(gains[0], dtype=float))
    if nc is not None and F.shape[0] != nc:
        raise ValueError(f"nc: expected the controller order of init, {F.shape[0]}, found {nc}")
    augmented_closed_loop(sys, *gains)                  # validates the shapes
    return tuple(np.atleast_2d(np.asarray(g, dtype=float)) for g in gains)


def averaged_lqg(sys, nc):
    """The LQG compensator of the mode-averaged system (sum_i mu_inf,i A_i, ...) in the form (3.37).

    A start for the stabilising phase when Alg. 3.2 gives none (predictor-form Kalman gain
    and LQ gain from the two discrete algebraic Riccati equations). Returns (F, K, L), or
    None when nc != nx or a Riccati equation has no stabilising solution.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = averaged_lqg(sys, 2)
    >>> F.shape, K.shape, L.shape
    ((2, 2), (2, 1), (1, 2))
    """
    if nc != sys.nx:
        return None
    mu = sys.mu_inf
    avg = lambda S: np.einsum("i,iab->ab", mu, S)
    A, B, C, Q, R = (avg(S) for S in (sys.A, sys.B, sys.C, sys.Q, sys.R))
    W = avg(sys.H @ np.swapaxes(sys.H, 1, 2))
    V = np.zeros((sys.ny, sys.ny)) if sys.J is None else avg(sys.J @ np.swapaxes(sys.J, 1, 2))
    V = V + 1e-6 * max(1.0, np.abs(V).max()) * np.eye(sys.ny)       # y = C x: a regular filter DARE
    Q = Q + 1e-6 * max(1.0, np.abs(Q).max()) * np.eye(sys.nx)
    W = W + 1e-6 * max(1.0, np.abs(W).max()) * np.eye(sys.nx)
    try:
        X = scipy.linalg.solve_discrete_are(A, B, Q, R)
        S = scipy.linalg.solve_discrete_are(A.T, C.T, W, V)
    except (np.linalg.LinAlgError, ValueError):
        return None
    L = -np.linalg.solve(R + B.T @ X @ B, B.T @ X @ A)
    K = A @ S @ C.T @ np.linalg.inv(C @ S @ C.T + V)
    return A + B @ L - K @ C, K, L


def _min_radius(sys, z, shapes, max_iter, target=-np.inf, progress=False):
    """BFGS on rho (Cor. 3.2) over (F, K, L) from z, stopping early once rho <= target.

    Returns (z, rho, status, iterations, history of rho)."""
    fun = lambda v: _flat(radius_and_gradient(sys, *_unpack(v, shapes)))
    return bfgs(fun, z, 1e-12, max_iter, progress, "min rho", target=target)


def _stabilising_start(sys, z, shapes):
    """z if it stabilises, else the first of z and the averaged LQG compensator (in order of
    rho) from which minimising rho reaches RHO_START. Returns (z, rho), the smallest rho
    reached when none stabilises."""
    rho = closed_loop_radius(sys, *_unpack(z, shapes))
    if rho < 1:
        return z, rho
    candidates = [z]
    lqg = averaged_lqg(sys, shapes[0][0])
    if lqg is not None:
        candidates.append(_pack(*lqg))
    radii = [rho] + [closed_loop_radius(sys, *_unpack(c, shapes)) for c in candidates[1:]]
    best = (candidates[int(np.argmin(radii))], min(radii))
    for i in np.argsort(radii):
        if not np.isfinite(radii[i]):
            continue
        zi, rho = _min_radius(sys, candidates[i], shapes, RADIUS_MAX_ITER, target=RHO_START)[:2]
        if rho < 1:
            return zi, rho
        best = min(best, (zi, rho), key=lambda b: b[1])
    return best


def _flat(out):
    cost, grads = out
    return cost, (None if grads is None else _pack(*grads))


def min_radius_dynamic_output_feedback(sys, init=None, nc=None, max_iter=RADIUS_MAX_ITER, progress=False):
    """The controller (3.37) of locally smallest mean-square spectral radius (Cor. 3.2); not in the thesis.

    BFGS on rho over (F, K, L) with the gradient of :func:`radius_and_gradient`. A rho that
    stays >= 1 from several starts is evidence, not proof, that no controller (3.37) of
    this order stabilises the system without observing the mode.

    Parameters
    ----------
    sys : MJLS (Sec. 3.6).
    init : start: a result with F, K, L (e.g. :class:`DynamicOutputFeedbackResult`), a
        tuple (F, K, L), or None for Algorithm 3.2's controller (as in
        :func:`exact_dynamic_output_feedback`).
    nc : controller order (default: that of ``init``, else nx).
    max_iter : BFGS iteration limit.
    progress : show a tqdm bar over iterations.

    Returns
    -------
    MinRadiusResult
        F, K, L; rho, stabilizing; cost: exact average cost (3.42) if stabilising, else inf;
        status (why BFGS stopped), iterations, seconds; history["rho"]: rho after each iteration.

    Raises
    ------
    TypeError
        if sys is not an MJLS, max_iter or nc not an integer, or init of the wrong type.
    ValueError
        if max_iter or nc is not positive, or init has the wrong shapes.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> res = min_radius_dynamic_output_feedback(sec373_system(1), max_iter=20)
    >>> res.stabilizing, bool(res.history["rho"][-1] <= res.history["rho"][0])
    (True, True)
    """
    check_system(sys)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    progress = boolean(progress, "progress")
    start = time.perf_counter()
    F, K, L = _start_gains(sys, init, _checked_order(nc))
    shapes = (F.shape, K.shape, L.shape)
    z, rho, status, it, history = _min_radius(sys, _pack(F, K, L), shapes, max_iter, progress=progress)
    F, K, L = _unpack(z, shapes)
    cost = average_cost_and_gradient(sys, F, K, L)[0]
    return MinRadiusResult(F=F, K=K, L=L, converged=status == "converged", status=status,
                           message=_bfgs_message(status, it, rho, "rho"), iterations=it, rho=rho,
                           stabilizing=bool(rho < 1), cost=cost, history={"rho": history},
                           seconds=time.perf_counter() - start)


def _checked_order(nc):
    return None if nc is None else integer(nc, "nc", minimum=1)


def _bfgs_message(status, it, value, name):
    return f"{BFGS_STATUS[status]} after {it} iterations ({name} {value:.6g})"


def exact_dynamic_output_feedback(sys, init=None, nc=None, tol=1e-10, max_iter=2000, warn=True,
                                  progress=False):
    """The controller (3.37) minimising the exact average cost (3.42) (Prop. 3.24); not in the thesis.

    BFGS over (F, K, L) with the analytic gradient (adjoint of the augmented second-moment
    equations, Prop. 3.23), inside the mean-square stabilising set (steps that leave it,
    where the cost is inf, are rejected by the line search).

    Parameters
    ----------
    sys : MJLS with measurement noise J (Sec. 3.6; J = None means y = C x).
    init : start: a result with F, K, L (e.g. :class:`DynamicOutputFeedbackResult`), a tuple
        (F, K, L), or None for Algorithm 3.2's controller. A non-stabilising start (and, failing it, the LQG
        compensator of the mode-averaged system) is first moved into the stabilising set by
        minimising the mean-square spectral radius (:func:`min_radius_dynamic_output_feedback`).
    nc : controller order (default: that of ``init``, else nx; Alg. 3.2's controller is
        padded with zeros or cut to nc states).
    tol : stop when the decrease the quasi-Newton model predicts is below tol * cost.
    max_iter : BFGS iteration limit.
    warn : warn when no stabilising start is found or the iteration does not converge.
    progress : show a tqdm bar over iterations.

    Returns
    -------
    ExactDynamicOutputFeedbackResult
        F, K, L; cost (exact, Prop. 3.24), rho, stabilizing, status (why BFGS stopped),
        iterations, seconds; history["cost"]: exact cost after each iteration.

    Raises
    ------
    TypeError
        if sys is not an MJLS, max_iter or nc is not an integer, a flag not a bool, or init
        has the wrong type.
    ValueError
        if tol or max_iter are not positive, nc < 1, or init has the wrong shapes.

    Examples
    --------
    On the example of Sec. 3.7.3 the exact optimum is below Alg. 3.2's cost (23.313):

    >>> from asoc.mjls.examples import sec373_system
    >>> res = exact_dynamic_output_feedback(sec373_system(1))
    >>> res.status, round(res.cost, 3)
    ('converged', 22.892)
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn, progress = boolean(warn, "warn"), boolean(progress, "progress")
    start = time.perf_counter()
    F, K, L = _start_gains(sys, init, _checked_order(nc))
    shapes = (F.shape, K.shape, L.shape)
    z, rho = _stabilising_start(sys, _pack(F, K, L), shapes)
    if not rho < 1:
        if warn:
            warnings.warn(f"exact_dynamic_output_feedback: found no mean-square stabilising start "
                          f"(smallest rho reached {rho:.4f}); pass a stabilising init", RuntimeWarning,
                          stacklevel=2)
        F, K, L = _unpack(z, shapes)
        return ExactDynamicOutputFeedbackResult(
            F=F, K=K, L=L, converged=False, status="no_progress",
            message=f"found no mean-square stabilising start (smallest rho reached {rho:.4f})",
            iterations=0, rho=rho, stabilizing=False, cost=np.inf, history={"cost": np.array([np.inf])},
            seconds=time.perf_counter() - start)
    fun = lambda v: _flat(average_cost_and_gradient(sys, *_unpack(v, shapes)))
    z, cost, status, it, history = bfgs(fun, z, tol, max_iter, progress, "exact (3.42)")
    F, K, L = _unpack(z, shapes)
    rho = closed_loop_radius(sys, F, K, L)
    message = _bfgs_message(status, it, cost, "cost")
    if warn and status != "converged":
        warnings.warn(f"exact_dynamic_output_feedback: {message}", RuntimeWarning, stacklevel=2)
    return ExactDynamicOutputFeedbackResult(F=F, K=K, L=L, converged=status == "converged", status=status,
                                            message=message, iterations=it, rho=rho, stabilizing=bool(rho < 1),
                                            cost=cost, history={"cost": history},
                                            seconds=time.perf_counter() - start)


def finite_horizon_cost_and_gradient(st, F, K, L, X0, mu):
    """Exact J_0 (3.56) by the augmented recursion (3.58) and its gradient over F_k, K_k, L_k.

    Parameters
    ----------
    st : :class:`asoc.mjls.finite_horizon.Stages` of the horizon.
    F, K, L : (horizon, nc, nc), (horizon, nc, ny), (horizon, nu, nc) gains of (3.55).
    X0 : (M, n, n) E{x~_0 x~_0^T 1(theta_0 = i)}; mu : (horizon + 1, M) mode distributions.

    Returns
    -------
    (cost, (gF, gK, gL)) : gradients of the shapes of F, K, L (backward adjoint recursion).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> from asoc.mjls.finite_horizon import augmented_initial_moment, mode_distributions, stages
    >>> st = stages(sys, 3)
    >>> gains = [np.broadcast_to(g, (3,) + g.shape) for g in (0.5 * np.eye(2), np.ones((2, 1)), -np.ones((1, 2)))]
    >>> X0 = augmented_initial_moment(SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0, SEC373_MU0 @ SEC373_MEAN0[1])
    >>> cost, (gF, gK, gL) = finite_horizon_cost_and_gradient(st, *gains, X0, mode_distributions(st, SEC373_MU0))
    >>> bool(np.isclose(cost, finite_horizon_cost(sys, *gains, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0))), gL.shape
    (True, (3, 1, 2))
    """
    m = st.stacked
    HHt, JJt = m["HHt"], m["JJt"]
    nx, nc, M = st.systems[0].nx, F.shape[1], X0.shape[0]
    n = nx + nc
    horizon = st.horizon
    A = np.zeros((horizon, M, n, n))                                  # A~_{i,k} of (3.59)
    A[:, :, :nx, :nx], A[:, :, :nx, nx:] = m["A"], m["B"] @ L[:, None]
    A[:, :, nx:, :nx], A[:, :, nx:, nx:] = K[:, None] @ m["C"], F[:, None]
    W = np.zeros_like(A)                                              # mu_k,i H~ H~^T (3.60)
    W[:, :, :nx, :nx], W[:, :, nx:, nx:] = HHt, K[:, None] @ JJt @ np.swapaxes(K, 1, 2)[:, None]
    W *= mu[:-1, :, None, None]
    LRL = np.swapaxes(L, 1, 2)[:, None] @ m["R"] @ L[:, None]
    At = np.swapaxes(A, 2, 3)
    X = np.empty((horizon + 1, M, n, n))
    X[0] = X0
    for k in range(horizon):
        X[k + 1] = predecessor_sum(m["T"][k], A[k] @ X[k] @ At[k] + W[k])
    P = np.zeros((M, n, n))
    P[:, :nx, :nx] = st.Q_final
    cost = float(np.einsum("iab,iba->", P, X[-1]))
    EP = np.empty_like(A)
    for k in range(horizon - 1, -1, -1):
        EP[k] = successor_average(m["T"][k], P)
        P = At[k] @ EP[k] @ A[k]
        P[:, :nx, :nx] += m["Q"][k]
        P[:, nx:, nx:] += LRL[k]
    cost += float(np.einsum("kiab,kiba->", m["Q"], X[:-1, :, :nx, :nx])
                  + np.einsum("kiab,kiba->", LRL, X[:-1, :, nx:, nx:]))
    G = 2.0 * EP @ A @ X[:-1]                                         # dJ/dA~_{i,k}
    gF = G[:, :, nx:, nx:].sum(axis=1)
    gK = (G[:, :, nx:, :nx] @ np.swapaxes(m["C"], 2, 3)).sum(axis=1)
    gK += 2.0 * (mu[:-1, :, None, None] * EP[:, :, nx:, nx:] @ K[:, None] @ JJt).sum(axis=1)
    gL = (np.swapaxes(m["B"], 2, 3) @ G[:, :, :nx, nx:]).sum(axis=1)
    gL += 2.0 * (m["R"] @ L[:, None] @ X[:-1, :, nx:, nx:]).sum(axis=1)
    return cost, (gF, gK, gL)


def exact_finite_horizon_dynamic_output_feedback(sys, horizon, mean0, cov0, mu0, init=None, tol=1e-12,
                                                 max_iter=5000, warn=True, progress=False):
    """The time-variant controller (3.55) minimising the exact J_0 (3.56)/(3.58); not in the thesis.

    L-BFGS over all gains F_k, K_k, L_k (k = 0..horizon-1) with the analytic gradient (the adjoint
    of the augmented forward recursion (3.58)); the controller starts at x^_0 = E{x_0} as in
    :func:`finite_horizon_dynamic_output_feedback`.

    Parameters
    ----------
    sys : MJLS, or a sequence of ``horizon`` (or ``horizon + 1``) MJLS (3.54).
    horizon : int >= 1.
    mean0, cov0, mu0 : the Gaussian-mixture initial state, as for Alg. 3.3.
    init : start: None for Algorithm 3.3's result (itself started from Alg. 3.2), a result
        with F, K, L (e.g. FiniteHorizonResult, DynamicOutputFeedbackResult) or a tuple
        (F, K, L), constant or per step.
    tol : stop when the decrease the quasi-Newton model predicts is below tol * J_0. The
        problem is ill-conditioned (the time-variant state transformations of x^_k leave
        J_0 unchanged), so the model underestimates the remaining decrease: on Sec. 3.7.3,
        tol = 1e-12 stops within about 1e-8 (relative) of the limit, tol = 1e-10 within 1e-7.
    max_iter : L-BFGS iteration limit.
    warn : warn when the iteration does not converge.
    progress : show a tqdm bar over iterations.

    Returns
    -------
    ExactFiniteHorizonResult
        F, K, L (per step), xhat0, cost (exact J_0), status (why L-BFGS stopped), iterations,
        seconds; costs: exact J_0 after each iteration.

    Raises
    ------
    TypeError
        for a sys that is not an MJLS (sequence), a non-integer horizon or max_iter, a flag
        that is not a bool or an init of the wrong type.
    ValueError
        for an invalid horizon, initial state, init, tol or max_iter.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = exact_finite_horizon_dynamic_output_feedback(sec373_system(1), 10, SEC373_MEAN0[1],
    ...                                                    SEC373_COV0, SEC373_MU0)
    >>> res.status, bool(res.cost <= res.costs[0])
    ('converged', True)
    """
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn, progress = boolean(warn, "warn"), boolean(progress, "progress")
    start = time.perf_counter()
    st = stages(sys, horizon)
    s0 = st.systems[0]
    mean0, cov0, mu0 = check_initial_state(s0.M, s0.nx, mean0, cov0, mu0)
    if init is None:
        init = finite_horizon_dynamic_output_feedback(sys, horizon, mean0, cov0, mu0, warn=False)
    F, K, L = _initial_gains(init, st, s0.nx, s0.ny, s0.nu)
    xhat0 = mu0 @ mean0
    X0 = augmented_initial_moment(mean0, cov0, mu0, xhat0)
    mu = mode_distributions(st, mu0)
    shapes = (F.shape, K.shape, L.shape)
    fun = lambda v: _flat(finite_horizon_cost_and_gradient(st, *_unpack(v, shapes), X0, mu))
    z, cost, status, it, history = bfgs(fun, _pack(F, K, L), tol, max_iter, progress, "exact (3.56)",
                                        memory=LBFGS_MEMORY)
    F, K, L = _unpack(z, shapes)
    message = _bfgs_message(status, it, cost, "J_0")
    if warn and status != "converged":
        warnings.warn(f"exact_finite_horizon_dynamic_output_feedback: {message}", RuntimeWarning,
                      stacklevel=2)
    return ExactFiniteHorizonResult(F=F, K=K, L=L, xhat0=xhat0, converged=status == "converged",
                                    status=status, message=message, iterations=it,
                                    cost=finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0),
                                    costs=history, seconds=time.perf_counter() - start)
