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

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from ..progress import progress_bar
from .dynamic import DynamicOutputFeedbackResult, dynamic_output_feedback
from .finite_horizon import (FiniteHorizonResult, _initial_gains, augmented_initial_moment,
                             check_initial_state, finite_horizon_cost,
                             finite_horizon_dynamic_output_feedback, mode_distributions, stages)
from . import operators
from .operators import (augmented_closed_loop, coupled_lyapunov_solver, costate_map,
                        kronecker_matrix, noise_covariances, second_moment_map, single_threaded,
                        spectral_radius)
from .system import predecessor_sum, successor_average

ARMIJO = 1e-4                 # sufficient-decrease constant of the backtracking line search
MIN_STEP = 2.0 ** -40         # the line search gives up below this step length
RHO_START = 0.999             # the stabilising search stops once rho is below this
RADIUS_MAX_ITER = 1000        # BFGS iterations of a search that minimises rho
LBFGS_MEMORY = 200            # pairs kept by L-BFGS for the K (nc^2 + nc ny + nu nc) time-variant gains


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
    (:func:`asoc.mjls.operators.coupled_lyapunov_solver`: one LU factorisation when M n^2 is
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
    """
    At, Wt, Qt = augmented_closed_loop(sys, F, K, L)
    M, n, _ = At.shape
    solve = coupled_lyapunov_solver(At, sys.T)
    Y = solve(np.broadcast_to(np.eye(n), (M, n, n)))
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
    """Mean-square spectral radius (Cor. 3.2) of the augmented closed loop (3.39)."""
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
    if M * n * n <= operators.DENSE_MAX_RADIUS:
        lam, left, right = scipy.linalg.eig(kronecker_matrix(At, T), left=True, right=True)
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
    (z, f, converged, iterations, history) : history holds f after each iteration.
    """
    z = np.asarray(z0, dtype=float)
    f, g = fun(z)
    if not np.isfinite(f):
        raise ValueError("z0: the start is outside the domain (cost is inf)")
    Hinv = _InverseHessian(z.size, memory)
    history = [f]
    converged = False
    it = 0
    for it in progress_bar(range(1, int(max_iter) + 1), progress, desc=desc, leave=False):
        fresh = Hinv.empty
        d = -Hinv.apply(g)
        slope = float(g @ d)
        if -0.5 * slope <= tol * abs(f) or f <= target:
            converged = True
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
                break
            Hinv.reset()                               # restart from a scaled gradient step
            continue
        Hinv.update(z_new - z, g_new - g)
        z, f, g = z_new, f_new, g_new
        history.append(f)
    return z, f, converged, it, np.array(history)


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
    gains = (init.F, init.K, init.L) if isinstance(init, DynamicOutputFeedbackResult) else init
    if not (isinstance(gains, (tuple, list)) and len(gains) == 3):
        raise ValueError(f"init: expected a DynamicOutputFeedbackResult or a tuple (F, K, L), "
                         f"found {type(init).__name__}")
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

    Returns (z, rho, converged, iterations, history of rho)."""
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
    init : start: a :class:`DynamicOutputFeedbackResult`, a tuple (F, K, L), or None for
        Algorithm 3.2's controller (as in :func:`exact_dynamic_output_feedback`).
    nc : controller order (default: that of ``init``, else nx).
    max_iter : BFGS iteration limit.
    progress : show a tqdm bar over iterations.

    Returns
    -------
    DynamicOutputFeedbackResult
        F, K, L; rho, stabilizing; cost: exact average cost (3.42) if stabilising, else inf;
        converged (BFGS stopped at a stationary point), iterations, seconds;
        history["rho"]: rho after each iteration.

    Raises
    ------
    ValueError
        if max_iter is not a positive integer, or nc or init are invalid.
    """
    if int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"max_iter: expected an integer >= 1, found {max_iter}")
    start = time.perf_counter()
    F, K, L = _start_gains(sys, init, _checked_order(nc))
    shapes = (F.shape, K.shape, L.shape)
    z, rho, converged, it, history = _min_radius(sys, _pack(F, K, L), shapes, max_iter, progress=progress)
    F, K, L = _unpack(z, shapes)
    cost = average_cost_and_gradient(sys, F, K, L)[0]
    return DynamicOutputFeedbackResult(F=F, K=K, L=L, converged=converged, iterations=it, rho=rho,
                                       stabilizing=bool(rho < 1), cost=cost, bound=np.nan, Xbar=None,
                                       Xunder=None, Pbar=None, Punder=None, history={"rho": history},
                                       seconds=time.perf_counter() - start)


def _checked_order(nc):
    if nc is not None and (int(nc) != nc or nc < 1):
        raise ValueError(f"nc must be an integer >= 1, found {nc}")
    return nc


def exact_dynamic_output_feedback(sys, init=None, nc=None, tol=1e-10, max_iter=2000, warn=True,
                                  progress=False):
    """The controller (3.37) minimising the exact average cost (3.42) (Prop. 3.24); not in the thesis.

    BFGS over (F, K, L) with the analytic gradient (adjoint of the augmented second-moment
    equations, Prop. 3.23), inside the mean-square stabilising set (steps that leave it,
    where the cost is inf, are rejected by the line search).

    Parameters
    ----------
    sys : MJLS with measurement noise J (Sec. 3.6; J = None means y = C x).
    init : start: a :class:`DynamicOutputFeedbackResult`, a tuple (F, K, L), or None for
        Algorithm 3.2's controller. A non-stabilising start (and, failing it, the LQG
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
    DynamicOutputFeedbackResult
        F, K, L; cost (exact, Prop. 3.24), rho, stabilizing, converged, iterations, seconds;
        bound = nan and Xbar, Xunder, Pbar, Punder = None (no bound is involved);
        history["cost"]: exact cost after each iteration.

    Raises
    ------
    ValueError
        if tol or max_iter are not positive, nc is not a positive integer, or init has
        the wrong type or shapes.
    """
    if not tol > 0 or int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"tol must be > 0 and max_iter an integer >= 1, found tol={tol}, "
                         f"max_iter={max_iter}")
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
        return DynamicOutputFeedbackResult(F=F, K=K, L=L, converged=False, iterations=0, rho=rho,
                                           stabilizing=False, cost=np.inf, bound=np.nan, Xbar=None,
                                           Xunder=None, Pbar=None, Punder=None,
                                           history={"cost": np.array([np.inf])},
                                           seconds=time.perf_counter() - start)
    fun = lambda v: _flat(average_cost_and_gradient(sys, *_unpack(v, shapes)))
    z, cost, converged, it, history = bfgs(fun, z, tol, max_iter, progress, "exact (3.42)")
    F, K, L = _unpack(z, shapes)
    rho = closed_loop_radius(sys, F, K, L)
    if warn and not converged:
        warnings.warn(f"exact_dynamic_output_feedback did not converge within {it} iterations "
                      f"(cost {cost:.6g})", RuntimeWarning, stacklevel=2)
    return DynamicOutputFeedbackResult(F=F, K=K, L=L, converged=converged, iterations=it, rho=rho,
                                       stabilizing=bool(rho < 1), cost=cost, bound=np.nan, Xbar=None,
                                       Xunder=None, Pbar=None, Punder=None, history={"cost": history},
                                       seconds=time.perf_counter() - start)


def _stacked(st):
    """The matrices of all steps stacked over k: A, B, C, Q, R (K, M, ., .), T (K, M, M)."""
    return {name: np.stack([getattr(s, name) for s in st.systems]) for name in "ABCQRT"}


def finite_horizon_cost_and_gradient(st, F, K, L, X0, mu):
    """Exact J_0 (3.56) by the augmented recursion (3.58) and its gradient over F_k, K_k, L_k.

    Parameters
    ----------
    st : :class:`asoc.mjls.finite_horizon.Stages` of the horizon.
    F, K, L : (K, nc, nc), (K, nc, ny), (K, nu, nc) gains of (3.55).
    X0 : (M, n, n) E{x~_0 x~_0^T 1(theta_0 = i)}; mu : (K + 1, M) mode distributions.

    Returns
    -------
    (cost, (gF, gK, gL)) : gradients of the shapes of F, K, L (backward adjoint recursion).
    """
    m = _stacked(st)
    HHt, JJt = np.stack(st.HHt), np.stack(st.JJt)
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

    L-BFGS over all gains F_k, K_k, L_k (k = 0..K-1) with the analytic gradient (the adjoint
    of the augmented forward recursion (3.58)); the controller starts at x^_0 = E{x_0} as in
    :func:`finite_horizon_dynamic_output_feedback`.

    Parameters
    ----------
    sys : MJLS, or a sequence of ``horizon`` (or ``horizon + 1``) MJLS (3.54).
    horizon : K >= 1.
    mean0, cov0, mu0 : the Gaussian-mixture initial state, as for Alg. 3.3.
    init : start: None for Algorithm 3.3's result (itself started from Alg. 3.2), a
        FiniteHorizonResult, a DynamicOutputFeedbackResult or a tuple (F, K, L), constant
        or per step.
    tol : stop when the decrease the quasi-Newton model predicts is below tol * J_0. The
        problem is ill-conditioned (the time-variant state transformations of x^_k leave
        J_0 unchanged), so the model underestimates the remaining decrease: on Sec. 3.7.3,
        tol = 1e-12 stops within about 1e-8 (relative) of the limit, tol = 1e-10 within 1e-7.
    max_iter : L-BFGS iteration limit.
    warn : warn when the iteration does not converge.
    progress : show a tqdm bar over iterations.

    Returns
    -------
    FiniteHorizonResult
        F, K, L (per step), xhat0, cost (exact J_0), converged, iterations, seconds;
        costs: exact J_0 after each iteration; cost_bounds empty and Xbar, Xunder, Pbar,
        Punder None (no bound is involved).

    Raises
    ------
    ValueError
        for an invalid horizon, initial state, init, tol or max_iter.
    """
    if not tol > 0 or int(max_iter) != max_iter or max_iter < 1:
        raise ValueError(f"tol must be > 0 and max_iter an integer >= 1, found tol={tol}, "
                         f"max_iter={max_iter}")
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
    z, cost, converged, it, history = bfgs(fun, _pack(F, K, L), tol, max_iter, progress, "exact (3.56)",
                                           memory=LBFGS_MEMORY)
    F, K, L = _unpack(z, shapes)
    if warn and not converged:
        warnings.warn(f"exact_finite_horizon_dynamic_output_feedback did not converge within {it} "
                      f"iterations (J_0 {cost:.6g})", RuntimeWarning, stacklevel=2)
    return FiniteHorizonResult(F=F, K=K, L=L, xhat0=xhat0, cost_bounds=np.array([]), converged=converged,
                               iterations=it, cost=finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0),
                               Xbar=None, Xunder=None, Pbar=None, Punder=None,
                               seconds=time.perf_counter() - start, costs=history)
