"""Expected cost J_{K-2}(x, u) of the scalar example in Sec. 3.4 (Prop. 3.5, eq. (3.6), Fig. 3.3).

With state feedback and unobserved mode, the optimal cost-to-go at K-1 is
x_{K-1}^2 Psi(I_{K-1}) (Prop. 3.5), where Psi depends on the Wonham-filtered mode
distribution and therefore on x_{K-1} itself. One step earlier,

    J_{K-2}(x, u) = E{ x^2 Q + u^2 R + x_{K-1}^2 Psi(I_{K-1}) | I_{K-2} }   (+ Delta),

an expectation over the Gaussian mixture of x_{K-1} = a_q x + b_q u + g w given the mode
q at K-2 with filtered probabilities pi. It is evaluated here by Gauss-Hermite
quadrature in w (exact up to quadrature error for the smooth integrand).
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


def expected_cost_K2(x, u, a, b, g, T, pi, Q=1.0, R=1.0, n_nodes=80):
    """J_{K-2}(x, u) - Delta of (3.5) on arrays x, u (broadcast), by Gauss-Hermite quadrature.

    Parameters
    ----------
    a, b : (M,) scalar mode dynamics x_{k+1} = a_i x + b_i u + g w.
    g : noise gain (w ~ N(0, 1)).
    T : (M, M) transition matrix; pi : filtered distribution of theta_{K-2}.
    """
    a, b, pi = (np.asarray(v, dtype=float) for v in (a, b, pi))
    if g <= 0:
        raise ValueError(f"g must be > 0, found {g}")
    x, u = np.broadcast_arrays(np.asarray(x, float), np.asarray(u, float))
    nodes, weights = np.polynomial.hermite_e.hermegauss(n_nodes)
    weights = weights / weights.sum()
    total = Q * x ** 2 + R * u ** 2
    for q in range(len(a)):
        mean = a[q] * x + b[q] * u
        x_next = mean[..., None] + g * nodes                      # (..., n_nodes)
        val = x_next ** 2 * psi(x_next, x[..., None], u[..., None], a, b, g, T, pi, Q, R)
        total = total + pi[q] * (val @ weights)
    return total


def convexity_violation(J, xs, us):
    """Largest violation of midpoint convexity on a grid: max over grid pairs of
    J((p+q)/2) - (J(p)+J(q))/2 along rows, columns and diagonals (> 0 means not convex)."""
    worst = -np.inf
    arg = None
    for step in range(1, min(J.shape) // 2):
        for (di, dj) in ((step, 0), (0, step), (step, step), (step, -step)):
            i0, i1 = max(0, -2 * di), J.shape[0] - max(0, 2 * di)
            j0, j1 = max(0, -2 * dj), J.shape[1] - max(0, 2 * dj)
            p = J[i0:i1, j0:j1]
            mid = J[i0 + di:i1 + di, j0 + dj:j1 + dj]
            q = J[i0 + 2 * di:i1 + 2 * di, j0 + 2 * dj:j1 + 2 * dj]
            gap = mid - 0.5 * (p + q)
            k = np.unravel_index(np.argmax(gap), gap.shape)
            if gap[k] > worst:
                worst = float(gap[k])
                i, j = k[0] + i0, k[1] + j0
                arg = ((xs[i], us[j]), (xs[i + 2 * di], us[j + 2 * dj]))
    return worst, arg
