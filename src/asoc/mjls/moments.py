"""Second moments X_k^i = E{x_k x_k^T 1(theta_k = i)} (3.28) and the H2 cost (Prop. 3.7)."""

import numpy as np

from .system import D


def second_moment_step(Acl, HHt, T, X, mu):
    """One step of (3.29): X_{k+1}^j = sum_i p_ij [Acl_i X^i Acl_i^T + mu^i H_i H_i^T]."""
    inner = Acl @ X @ np.swapaxes(Acl, 1, 2) + mu[:, None, None] * HHt
    return D(T, inner)


def second_moments(Acl, HHt, T, X0, mu0, horizon):
    """X_k^i for k = 0..horizon by (3.29), with mode distributions mu_k = mu_0 T^k.

    Returns (X, mu) of shapes (horizon+1, M, n, n) and (horizon+1, M).
    """
    X = np.empty((horizon + 1,) + np.shape(X0))
    mu = np.empty((horizon + 1, len(mu0)))
    X[0], mu[0] = X0, mu0
    for k in range(horizon):
        X[k + 1] = second_moment_step(Acl, HHt, T, X[k], mu[k])
        mu[k + 1] = mu[k] @ T
    return X, mu


def moment_operator(Acl, T):
    """The matrix of X -> D_j(Acl X Acl^T) on row-major vecs (3.29): block (j, i) = p_ij Acl_i (x) Acl_i.

    Its spectral radius is that of Cor. 3.2; its transpose maps vec P to vec(Acl_i^T E_i(P) Acl_i).
    """
    M, n, _ = Acl.shape
    kron = np.einsum("iab,icd->iacbd", Acl, Acl).reshape(M, n * n, n * n)    # Acl_i (x) Acl_i
    return np.einsum("ij,ixy->jxiy", T, kron).reshape(M * n * n, M * n * n)


def steady_state_second_moment(Acl, HHt, T, mu_inf):
    """X_inf^i solving the coupled Lyapunov equations of Prop. 3.7 / (3.32) directly.

    Vectorised: vec X^j = sum_i p_ij [(Acl_i (x) Acl_i) vec X^i + mu_i vec(H_i H_i^T)].
    Only meaningful when the closed loop is mean-square stable (Cor. 3.2).
    """
    M, n, _ = Acl.shape
    rhs = D(T, mu_inf[:, None, None] * HHt).reshape(M * n * n)
    X = np.linalg.solve(np.eye(M * n * n) - moment_operator(Acl, T), rhs).reshape(M, n, n)
    return 0.5 * (X + np.swapaxes(X, 1, 2))


def h2_cost(sys, L, X_inf):
    """sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_inf^i] (Prop. 3.7 and Prop. 3.15)."""
    L = np.asarray(L, dtype=float).reshape(sys.nu, sys.ny)
    LC = L @ sys.C
    weight = sys.Q + np.swapaxes(LC, 1, 2) @ sys.R @ LC
    return float(np.einsum("iab,iba->", weight, X_inf))
