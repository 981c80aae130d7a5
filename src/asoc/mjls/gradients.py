"""Gradients of the exact costs and of the mean-square spectral radius over the gains of (3.37)
and (3.55).

The exact designs of :mod:`asoc.mjls.exact_cost_design` minimise these functions. With the augmented
closed loop A~_i, W_i = H~_i H~_i^T and Q~_i of (3.39)-(3.40) and Prop. 3.20,

    X_j = sum_i p_ij [A~_i X_i A~_i^T + mu_i W_i]   (Prop. 3.23),
    P_i = Q~_i + A~_i^T E_i(P) A~_i                  (its adjoint, the costate),

the cost J = sum_i tr[Q~_i X_i] has dJ/dA~_i = 2 E_i(P) A~_i X_i, dJ/dW_i = mu_i E_i(P) and
dJ/dQ~_i = X_i; the finite-horizon cost J_0 (3.56) of the recursion (3.58) uses the same
relations step by step, and rho has d rho / dA~_i = 2 E_i(V) A~_i X_i / <V, X> with its
right and left Perron eigenvectors X, V.
"""

import numpy as np

from .. import config
from ..linalg import transpose
from .closed_loops import augmented_closed_loop, noise_covariances
from .lyapunov import coupled_lyapunov_solver
from .stability import mean_square_stability, perron_pair
from .system import predecessor_sum, successor_average

__all__ = ["average_cost_and_gradient", "positive_definite", "closed_loop_radius",
           "radius_and_gradient", "finite_horizon_cost_and_gradient"]


def _closed_loop_gradient(sys, G):
    """The gradient over (F, K, L) of a function of A~ (3.39) alone, from G_i = d/dA~_i.

    A~_i has F in its lower right block, K C_i in its lower left and B_i L in its upper right,
    so the chain rule sums those blocks of G_i over the modes.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> gF, gK, gL = _closed_loop_gradient(sys, np.ones((sys.M, 2 * sys.nx, 2 * sys.nx)))
    >>> gF.shape, gK.shape, gL.shape
    ((2, 2), (2, 1), (1, 2))
    """
    nx = sys.nx
    gF = G[:, nx:, nx:].sum(axis=0)
    gK = (G[:, nx:, :nx] @ transpose(sys.C)).sum(axis=0)
    gL = (transpose(sys.B) @ G[:, :nx, nx:]).sum(axis=0)
    return gF, gK, gL


def _gain_gradient(sys, K, L, At, X, EP, JJt, mu):
    """dJ/dF, dJ/dK, dJ/dL from the moments X and costates E_i(P) (adjoint of Prop. 3.23).

    Parameters
    ----------
    sys : MJLS
        One step of (3.36)/(3.54).
    K, L : numpy.ndarray
        The gains of (3.37); F enters only through ``At``.
    At : numpy.ndarray, shape (M, n, n)
        Augmented closed loop (3.39).
    X : numpy.ndarray, shape (M, n, n)
        Augmented second moments at this step.
    EP : numpy.ndarray, shape (M, n, n)
        E_i(P) of the costates at the next step.
    JJt : numpy.ndarray, shape (M, ny, ny)
        Measurement-noise covariances.
    mu : numpy.ndarray, shape (M,)
        Mode distribution.

    Returns
    -------
    tuple of numpy.ndarray
        (gF, gK, gL), of the shapes of F, K, L.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> At, Wt, Qt = augmented_closed_loop(sys, F, K, L)
    >>> I = np.broadcast_to(np.eye(4), (2, 4, 4))
    >>> gF, gK, gL = _gain_gradient(sys, K, L, At, I, I, noise_covariances(sys)[1], sys.mu_inf)
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
    sys : MJLS
        With measurement noise J (Sec. 3.6).
    F, K, L : numpy.ndarray
        Gains of (3.37), shapes (nc, nc), (nc, ny), (nu, nc).

    Returns
    -------
    cost : float
        The exact average cost (3.42); inf when A~ is not mean-square stable (Cor. 3.2).
    gradient : tuple of numpy.ndarray or None
        (gF, gK, gL), of the shapes of F, K, L; None when the cost is inf.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = 0.5 * np.eye(2), np.array([[0.1], [0.2]]), np.array([[-0.3, -0.2]])
    >>> cost, gradient = average_cost_and_gradient(sys, F, K, L)
    >>> cost, gradient
    (inf, None)
    >>> from asoc.mjls import dynamic_output_feedback
    >>> r = dynamic_output_feedback(sys)
    >>> cost, (gF, gK, gL) = average_cost_and_gradient(sys, r.F, r.K, r.L)
    >>> round(cost, 3), gL.shape
    (23.313, (1, 2))
    """
    At, Wt, Qt = augmented_closed_loop(sys, F, K, L)
    M, n, _ = At.shape
    solve = coupled_lyapunov_solver(At, sys.T)
    # an unstable loop is expected here
    Y = solve(np.broadcast_to(np.eye(n), (M, n, n)), on_miss="report")
    if not (np.all(np.isfinite(Y.X)) and Y.residual < config.defaults["mjls.solve_residual_max"]
            and positive_definite(Y.X)):
        return np.inf, None
    mu = sys.mu_inf
    X = solve(predecessor_sum(sys.T, mu[:, None, None] * Wt, check=False)).X
    P = solve(Qt, adjoint=True).X
    cost = float(np.einsum("iab,iba->", Qt, X))
    return cost, _gain_gradient(sys, K, L, At, X, successor_average(sys.T, P, check=False),
                                noise_covariances(sys)[1], mu)


def positive_definite(Y):
    """True when every matrix of the stack ``Y`` has a Cholesky factor (is positive definite).

    Examples
    --------
    >>> positive_definite(np.eye(2)[None]), positive_definite(-np.eye(2)[None])
    (True, False)
    """
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
    return mean_square_stability(augmented_closed_loop(sys, F, K, L)[0], sys.T, check=False).rho


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
    sys : MJLS
        The system.
    F, K, L : numpy.ndarray
        Gains of (3.37).

    Returns
    -------
    rho : float
        The mean-square spectral radius of the closed loop.
    gradient : tuple of numpy.ndarray
        (gF, gK, gL), of the shapes of F, K, L; zero where <V, X> vanishes (rho not
        differentiable).

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
    rho, X, V = perron_pair(At, sys.T)
    inner = float(np.einsum("iab,iab->", V, X))
    scale = np.linalg.norm(V) * np.linalg.norm(X)
    if not abs(inner) > config.defaults["mjls.perron_inner_rtol"] * scale:
        return rho, _closed_loop_gradient(sys, np.zeros_like(At))
    EV = successor_average(sys.T, V, check=False)
    return rho, _closed_loop_gradient(sys, 2.0 * EV @ At @ X / inner)


def finite_horizon_cost_and_gradient(st, F, K, L, X0, mu):
    """Exact J_0 (3.56) by the augmented recursion (3.58) and its gradient over F_k, K_k, L_k.

    Parameters
    ----------
    st : Stages
        The stages of the horizon (``asoc.mjls.finite_horizon_model.Stages``).
    F, K, L : numpy.ndarray
        Gains of (3.55), shapes (horizon, nc, nc), (horizon, nc, ny), (horizon, nu, nc).
    X0 : numpy.ndarray, shape (M, n, n)
        E{x~_0 x~_0^T 1(theta_0 = i)}.
    mu : numpy.ndarray, shape (horizon + 1, M)
        Mode distributions.

    Returns
    -------
    cost : float
        The exact finite-horizon cost J_0.
    gradient : tuple of numpy.ndarray
        (gF, gK, gL), of the shapes of F, K, L (backward adjoint recursion).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> from asoc.mjls.finite_horizon import augmented_initial_moment, finite_horizon_cost
    >>> from asoc.mjls.finite_horizon_model import mode_distributions, stages
    >>> st = stages(sys, 3)
    >>> gains = [np.broadcast_to(g, (3,) + g.shape)
    ...          for g in (0.5 * np.eye(2), np.ones((2, 1)), -np.ones((1, 2)))]
    >>> mean0, cov0, mu0 = SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0
    >>> X0 = augmented_initial_moment(mean0, cov0, mu0, mu0 @ mean0)
    >>> cost, (gF, gK, gL) = finite_horizon_cost_and_gradient(st, *gains, X0,
    ...                                                       mode_distributions(st, mu0))
    >>> bool(np.isclose(cost, finite_horizon_cost(sys, *gains, mean0, cov0, mu0))), gL.shape
    (True, (3, 1, 2))
    """
    m = st.stacked
    HHt, JJt = m.HHt, m.JJt
    nx, nc, M = st.systems[0].nx, F.shape[1], X0.shape[0]
    n = nx + nc
    horizon = st.horizon
    A = np.zeros((horizon, M, n, n))                                  # A~_{i,k} of (3.59)
    A[:, :, :nx, :nx], A[:, :, :nx, nx:] = m.A, m.B @ L[:, None]
    A[:, :, nx:, :nx], A[:, :, nx:, nx:] = K[:, None] @ m.C, F[:, None]
    W = np.zeros_like(A)                                              # mu_k,i H~ H~^T (3.60)
    W[:, :, :nx, :nx], W[:, :, nx:, nx:] = HHt, K[:, None] @ JJt @ np.swapaxes(K, 1, 2)[:, None]
    W *= mu[:-1, :, None, None]
    LRL = np.swapaxes(L, 1, 2)[:, None] @ m.R @ L[:, None]
    At = np.swapaxes(A, 2, 3)
    X = np.empty((horizon + 1, M, n, n))
    X[0] = X0
    for k in range(horizon):
        X[k + 1] = predecessor_sum(m.T[k], A[k] @ X[k] @ At[k] + W[k], check=False)
    P = np.zeros((M, n, n))
    P[:, :nx, :nx] = st.Q_final
    cost = float(np.einsum("iab,iba->", P, X[-1]))
    EP = np.empty_like(A)
    for k in range(horizon - 1, -1, -1):
        EP[k] = successor_average(m.T[k], P, check=False)
        P = At[k] @ EP[k] @ A[k]
        P[:, :nx, :nx] += m.Q[k]
        P[:, nx:, nx:] += LRL[k]
    cost += float(np.einsum("kiab,kiba->", m.Q, X[:-1, :, :nx, :nx])
                  + np.einsum("kiab,kiba->", LRL, X[:-1, :, nx:, nx:]))
    G = 2.0 * EP @ A @ X[:-1]                                         # dJ/dA~_{i,k}
    gF = G[:, :, nx:, nx:].sum(axis=1)
    gK = (G[:, :, nx:, :nx] @ np.swapaxes(m.C, 2, 3)).sum(axis=1)
    gK += 2.0 * (mu[:-1, :, None, None] * EP[:, :, nx:, nx:] @ K[:, None] @ JJt).sum(axis=1)
    gL = (np.swapaxes(m.B, 2, 3) @ G[:, :, :nx, nx:]).sum(axis=1)
    gL += 2.0 * (m.R @ L[:, None] @ X[:-1, :, nx:, nx:]).sum(axis=1)
    return cost, (gF, gK, gL)
