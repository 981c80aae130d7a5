"""Second moments X_k^i = E{x_k x_k^T 1(theta_k = i)} (3.28) and the H2 cost (Prop. 3.7)."""

import numpy as np

from .operators import second_moment_map, solve_coupled_lyapunov
from .system import predecessor_sum


def second_moment_step(Acl, HHt, T, X, mu):
    """One step of (3.29): X_{k+1}^j = sum_i p_ij [Acl_i X^i Acl_i^T + mu^i H_i H_i^T].

    Parameters
    ----------
    Acl : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    HHt : numpy.ndarray, shape (M, n, n)
        Noise covariances H_i H_i^T.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    X : numpy.ndarray, shape (M, n, n)
        Second moments X_k^i = E{x_k x_k^T 1(theta_k = i)} (3.28).
    mu : numpy.ndarray, shape (M,)
        Mode distribution at step k.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)
        X_{k+1}.

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    return second_moment_map(Acl, T, X) + predecessor_sum(T, mu[:, None, None] * HHt)


def second_moments(Acl, HHt, T, X0, mu0, horizon):
    """X_k^i for k = 0..horizon by (3.29), with mode distributions mu_k = mu_0 T^k.

    Parameters
    ----------
    Acl, HHt : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices and noise covariances H_i H_i^T.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    X0 : numpy.ndarray, shape (M, n, n)
        Initial second moments.
    mu0 : numpy.ndarray, shape (M,)
        Initial mode distribution.
    horizon : int
        Number of steps K.

    Returns
    -------
    X : numpy.ndarray, shape (horizon + 1, M, n, n)
    mu : numpy.ndarray, shape (horizon + 1, M)

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    X = np.empty((horizon + 1,) + np.shape(X0))
    mu = np.empty((horizon + 1, len(mu0)))
    X[0], mu[0] = X0, mu0
    for k in range(horizon):
        X[k + 1] = second_moment_step(Acl, HHt, T, X[k], mu[k])
        mu[k + 1] = mu[k] @ T
    return X, mu


def steady_state_second_moment(Acl, HHt, T, mu_inf):
    """X_inf^i solving the coupled Lyapunov equations of Prop. 3.7 / (3.32) directly.

    Vectorised: vec X^j = sum_i p_ij [(Acl_i (x) Acl_i) vec X^i + mu_i vec(H_i H_i^T)], solved
    by :func:`asoc.mjls.operators.solve_coupled_lyapunov` (dense LU for small M n^2, else
    BiCGSTAB on the operator to a relative residual of 1e-12). Only meaningful when the
    closed loop is mean-square stable (Cor. 3.2).

    Parameters
    ----------
    Acl, HHt : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices and noise covariances.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    mu_inf : numpy.ndarray, shape (M,)
        Stationary mode distribution.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)
        The stationary second moments (symmetrised).

    Raises
    ------
    numpy.linalg.LinAlgError
        If I - M is singular (rho(M) = 1).
    """
    return solve_coupled_lyapunov(Acl, T, predecessor_sum(T, mu_inf[:, None, None] * HHt)).X


def h2_cost(sys, L, X_inf):
    """sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_inf^i] (Prop. 3.7 and Prop. 3.15).

    Parameters
    ----------
    sys : MJLS
    L : array_like, shape (nu, ny)
        Static gain.
    X_inf : numpy.ndarray, shape (M, nx, nx)
        Stationary second moments of the closed loop (:func:`steady_state_second_moment`).

    Returns
    -------
    float
        The average (H2) cost (3.9) of u = L y.

    Raises
    ------
    ValueError
        If ``L`` does not have nu * ny entries.
    """
    L = np.asarray(L, dtype=float).reshape(sys.nu, sys.ny)
    LC = L @ sys.C
    weight = sys.Q + np.swapaxes(LC, 1, 2) @ sys.R @ LC
    return float(np.einsum("iab,iba->", weight, X_inf))
