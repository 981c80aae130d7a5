"""Expected cost J_{K-2}(x, u) of the scalar example in Sec. 3.4 (Prop. 3.5, eq. (3.6), Fig. 3.3).

With state feedback and unobserved mode, the optimal cost-to-go at K-1 is
x_{K-1}^2 Psi(I_{K-1}) (Prop. 3.5), where Psi depends on the Wonham-filtered mode
distribution and therefore on x_{K-1} itself. One step earlier,

    J_{K-2}(x, u) = E{ x^2 Q + u^2 R + x_{K-1}^2 Psi(I_{K-1}) | I_{K-2} }   (+ Delta),

an expectation over the Gaussian mixture of x_{K-1} = a_q x + b_q u + g w given the mode
q at K-2 with filtered probabilities pi. It is evaluated here by Gauss-Hermite
quadrature in w (exact up to quadrature error for the smooth integrand).

The thesis reads Fig. 3.3 two ways: the text evaluates "the last term in (3.5)", i.e.
(3.6) alone (``terms="last"``), the caption plots J_{K-2} (``terms="full"``). Both are
computed here, as are their curvatures (:func:`hessian_min_eigenvalue`,
:func:`min_curvature_in_u`, :func:`nonconvex_radius`).
"""

import numpy as np


def psi(x_next, x, u, a, b, g, T, pi, Q=1.0, R=1.0):
    """Psi(I_{K-1}) of Prop. 3.5 for scalar modes, evaluated at x_{K-1} = x_next.

    The filtered distribution of theta_{K-2} given x_{K-1} is the Wonham update
    pi_t N(x_next; a_t x + b_t u, g^2) / sum_r (...); that of theta_{K-1} follows by T.
    """
    resid = (x_next[..., None] - a * x[..., None] - b * u[..., None]) / g
    logw = -0.5 * resid ** 2 + np.log(pi)
    logw -= logw.max(axis=-1, keepdims=True)
    post = np.exp(logw)
    post /= post.sum(axis=-1, keepdims=True)
    rho = post @ T                                                # P(theta_{K-1} = j | I_{K-1})
    e_qa = rho @ (Q + a * Q * a)                                  # E{Q + A^T Q A}
    e_ab = rho @ (a * Q * b)                                      # E{A^T Q B}
    e_rb = rho @ (R + b * Q * b)                                  # E{R + B^T Q B}
    return e_qa - e_ab ** 2 / e_rb


def expected_cost_K2(x, u, a, b, g, T, pi, Q=1.0, R=1.0, n_nodes=80, terms="full"):
    """J_{K-2}(x, u) - Delta of (3.5) on arrays x, u (broadcast), by Gauss-Hermite quadrature.

    ``terms="last"`` gives only its last term, E{x_{K-1}^2 Psi(I_{K-1}) | I_{K-2}} of (3.6).

    Parameters
    ----------
    a, b : (M,) scalar mode dynamics x_{k+1} = a_i x + b_i u + g w.
    g : noise gain (w ~ N(0, 1)).
    T : (M, M) transition matrix; pi : filtered distribution of theta_{K-2}.
    """
    a, b, pi = (np.asarray(v, dtype=float) for v in (a, b, pi))
    if g <= 0:
        raise ValueError(f"g must be > 0, found {g}")
    if terms not in ("full", "last"):
        raise ValueError(f"terms: expected 'full' or 'last', found {terms!r}")
    x, u = np.broadcast_arrays(np.asarray(x, float), np.asarray(u, float))
    nodes, weights = np.polynomial.hermite_e.hermegauss(n_nodes)
    weights = weights / weights.sum()
    total = Q * x ** 2 + R * u ** 2 if terms == "full" else np.zeros_like(x)
    for q in range(len(a)):
        mean = a[q] * x + b[q] * u
        x_next = mean[..., None] + g * nodes                      # (..., n_nodes)
        val = x_next ** 2 * psi(x_next, x[..., None], u[..., None], a, b, g, T, pi, Q, R)
        total = total + pi[q] * (val @ weights)
    return total


def hessian(J, X, U, h=1e-3):
    """Second derivatives (J_xx, J_uu, J_xu) of J(x, u) on a grid (central differences, step h)."""
    fxx = (J(X + h, U) - 2 * J(X, U) + J(X - h, U)) / h ** 2
    fuu = (J(X, U + h) - 2 * J(X, U) + J(X, U - h)) / h ** 2
    fxu = (J(X + h, U + h) - J(X + h, U - h) - J(X - h, U + h) + J(X - h, U - h)) / (4 * h * h)
    return fxx, fuu, fxu


def _smallest_eigenvalue(fxx, fuu, fxu):
    return 0.5 * (fxx + fuu) - np.sqrt(0.25 * (fxx - fuu) ** 2 + fxu ** 2)


def _argmin(field, X, U):
    k = np.unravel_index(np.argmin(field), field.shape)
    return float(field[k]), (float(X[k]), float(U[k]))


def hessian_min_eigenvalue(J, X, U, h=1e-3):
    """Smallest eigenvalue of the Hessian of J(x, u) over a grid (central differences).

    Returns (lambda_min, (x, u)) where it is attained.
    """
    return _argmin(_smallest_eigenvalue(*hessian(J, X, U, h)), X, U)


def min_curvature_in_u(J, X, U, h=1e-3):
    """Smallest d^2 J / du^2 over a grid: >= 0 means J is convex in u for every fixed x there.

    Returns (J_uu_min, (x, u)) where it is attained.
    """
    return _argmin(hessian(J, X, U, h)[1], X, U)


def nonconvex_radius(J, X, U, h=1e-3):
    """Smallest max(|x|, |u|) on the grid at which the Hessian of J has a negative eigenvalue.

    The square [-r, r]^2 with r below this radius is convex on the grid; returns
    (radius, (x, u)) of that grid point, or (inf, None) if the Hessian is PSD everywhere.
    """
    negative = _smallest_eigenvalue(*hessian(J, X, U, h)) < 0
    if not negative.any():
        return float("inf"), None
    radius = np.where(negative, np.maximum(np.abs(X), np.abs(U)), np.inf)
    return _argmin(radius, X, U)


def symmetric_representative(point):
    """(x, u) or (-x, -u), whichever has u > 0 (or u = 0, x >= 0).

    J_{K-2}(x, u) = J_{K-2}(-x, -u) exactly (the dynamics (3.2) are linear and w is
    symmetric), so a grid minimum is attained at a symmetric pair and rounding decides
    which of the two an argmin returns; this picks one independent of rounding.
    """
    x, u = point
    return (x, u) if u > 0 or (u == 0 and x >= 0) else (-x + 0.0, -u + 0.0)


def quadratic_fit_residual(X, U, J):
    """Relative RMS residual of the least-squares fit of J by a full quadratic in (x, u)."""
    x, u, j = X.ravel(), U.ravel(), J.ravel()
    basis = np.stack([np.ones_like(x), x, u, x * x, x * u, u * u], axis=1)
    coef, *_ = np.linalg.lstsq(basis, j, rcond=None)
    return float(np.sqrt(np.mean((basis @ coef - j) ** 2)) / np.sqrt(np.mean(j ** 2)))
