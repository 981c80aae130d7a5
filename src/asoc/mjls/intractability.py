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

from ..validation import (
    choice,
    integer,
    probability_vector,
    real_array,
    real_scalar,
    stochastic_matrix,
)

__all__ = ["psi", "expected_cost_two_steps_before_horizon", "hessian", "hessian_min_eigenvalue",
           "min_curvature_in_u", "nonconvex_radius", "symmetric_representative",
           "quadratic_fit_residual"]


def _scalar_model(a, b, g, T, pi, Q, R):
    """Validated scalar modes a, b (M,), noise gain g > 0, T (M, M), pi (M,), Q >= 0, R > 0."""
    a = real_array(a, "a", ndim=1)
    if a.size == 0:
        raise ValueError("a: expected at least one mode, found none")
    b = real_array(b, "b")
    if b.shape != a.shape:
        raise ValueError(f"b: expected the shape of a, {a.shape}, found shape {b.shape}")
    g = real_scalar(g, "g", low=0, low_open=True)
    T = stochastic_matrix(T, "T", a.size)
    pi = probability_vector(pi, "pi", a.size)
    Q = real_scalar(Q, "Q", low=0)
    R = real_scalar(R, "R", low=0, low_open=True)
    return a, b, g, T, pi, Q, R


def psi(x_next, x, u, a, b, g, T, pi, Q=1.0, R=1.0):
    """Psi(I_{K-1}) of Prop. 3.5 for scalar modes, evaluated at x_{K-1} = x_next.

    The filtered distribution of theta_{K-2} given x_{K-1} is the Wonham update
    pi_t N(x_next; a_t x + b_t u, g^2) / sum_r (...); that of theta_{K-1} follows by T.

    Examples
    --------
    >>> from asoc.mjls.examples import SEC34_A, SEC34_B, SEC34_G, SEC34_T, SEC34_PI
    >>> z = np.array([0.0])
    >>> psi(z, z, z, SEC34_A, SEC34_B, SEC34_G, SEC34_T, SEC34_PI).round(4)
    array([1.2881])
    """
    a, b, g, T, pi, Q, R = _scalar_model(a, b, g, T, pi, Q, R)
    x_next, x, u = (real_array(v, n) for v, n in ((x_next, "x_next"), (x, "x"), (u, "u")))
    return _psi(x_next, x, u, a, b, g, T, pi, Q, R)


def _psi(x_next, x, u, a, b, g, T, pi, Q, R):
    """:func:`psi` on checked arguments. The modes run along a new first axis: reductions over
    them are then elementwise operations between whole arrays, not over a short last axis.
    """
    modes = (slice(None),) + (None,) * np.broadcast(x_next, x, u).ndim
    resid = (x_next - a[modes] * x - b[modes] * u) / g
    logw = -0.5 * resid ** 2 + np.log(pi)[modes]
    logw -= logw.max(axis=0)
    post = np.exp(logw)
    post /= post.sum(axis=0)
    rho = np.tensordot(T, post, axes=(0, 0))                     # P(theta_{K-1} = j | I_{K-1})
    e_qa = np.tensordot(Q + a * Q * a, rho, axes=1)               # E{Q + A^T Q A}
    e_ab = np.tensordot(a * Q * b, rho, axes=1)                   # E{A^T Q B}
    e_rb = np.tensordot(R + b * Q * b, rho, axes=1)               # E{R + B^T Q B}
    return e_qa - e_ab ** 2 / e_rb


def expected_cost_two_steps_before_horizon(x, u, a, b, g, T, pi, Q=1.0, R=1.0, n_nodes=80,
                                           terms="full"):
    """J_{K-2}(x, u) - Delta of (3.5) (K the horizon) on arrays x, u, by Gauss-Hermite quadrature.

    ``terms="last"`` gives only its last term, E{x_{K-1}^2 Psi(I_{K-1}) | I_{K-2}} of (3.6).

    Parameters
    ----------
    x, u : array_like
        State and input at step K-2 (broadcast against each other).
    a, b : array_like, shape (M,)
        Scalar mode dynamics x_{k+1} = a_i x + b_i u + g w.
    g : float
        Noise gain (w ~ N(0, 1)), > 0.
    T : array_like, shape (M, M)
        Transition matrix.
    pi : array_like, shape (M,)
        Filtered distribution of theta_{K-2}.
    Q, R : float
        Weights, Q >= 0, R > 0.
    n_nodes : int
        Gauss-Hermite nodes, >= 1.
    terms : {"full", "last"}

    Returns
    -------
    numpy.ndarray
        J_{K-2} - Delta on the broadcast grid.

    Raises
    ------
    TypeError, ValueError
        Naming the argument, for invalid shapes, values or types.

    Examples
    --------
    >>> from asoc.mjls.examples import SEC34_A, SEC34_B, SEC34_G, SEC34_T, SEC34_PI
    >>> J = expected_cost_two_steps_before_horizon(1.0, [-0.5, 0.0], SEC34_A, SEC34_B, SEC34_G,
    ...                                            SEC34_T, SEC34_PI)
    >>> J.round(3)
    array([1.449, 1.68 ])
    """
    a, b, g, T, pi, Q, R = _scalar_model(a, b, g, T, pi, Q, R)
    n_nodes = integer(n_nodes, "n_nodes", minimum=1)
    choice(terms, "terms", ("full", "last"))
    x, u = real_array(x, "x"), real_array(u, "u")
    try:
        x, u = np.broadcast_arrays(x, u)
    except ValueError as err:
        raise ValueError(f"u: expected a shape that broadcasts with x {x.shape}, "
                         f"found {u.shape}") from err
    nodes, weights = np.polynomial.hermite_e.hermegauss(n_nodes)
    weights = weights / weights.sum()
    total = Q * x ** 2 + R * u ** 2 if terms == "full" else np.zeros_like(x)
    for q in range(len(a)):
        mean = a[q] * x + b[q] * u
        x_next = mean[..., None] + g * nodes                      # (..., n_nodes)
        val = x_next ** 2 * _psi(x_next, x[..., None], u[..., None], a, b, g, T, pi, Q, R)
        total = total + pi[q] * (val @ weights)
    return total


def _grid(J, X, U, h):
    """Validated callable J, grids X, U of one shape and step h > 0."""
    if not callable(J):
        raise TypeError(f"J: expected a function J(x, u), found {type(J).__name__}")
    return (J, *_grid_arrays(X=X, U=U), real_scalar(h, "h", low=0, low_open=True))


def _grid_arrays(**arrays):
    """Non-empty real arrays of one shape, the first one's (named in the message)."""
    (first, value), *rest = arrays.items()
    ref = real_array(value, first)
    if ref.size == 0:
        raise ValueError(f"{first}: expected a non-empty grid, found shape {ref.shape}")
    out = [ref]
    for name, value in rest:
        out.append(real_array(value, name))
        if out[-1].shape != ref.shape:
            raise ValueError(f"{name}: expected the shape of {first}, {ref.shape}, "
                             f"found shape {out[-1].shape}")
    return out


def hessian(J, X, U, h=1e-3):
    """Second derivatives (J_xx, J_uu, J_xu) of J(x, u) on a grid (central differences, step h).

    Examples
    --------
    >>> fxx, fuu, fxu = hessian(lambda x, u: x ** 2 + x * u, np.zeros(1), np.zeros(1))
    >>> fxx.round(6), fuu.round(6), fxu.round(6)
    (array([2.]), array([0.]), array([1.]))
    """
    J, X, U, h = _grid(J, X, U, h)
    centre = J(X, U)
    fxx = (J(X + h, U) - 2 * centre + J(X - h, U)) / h ** 2
    fuu = (J(X, U + h) - 2 * centre + J(X, U - h)) / h ** 2
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

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-1, 1, 3), np.linspace(-1, 1, 3))
    >>> round(hessian_min_eigenvalue(lambda x, u: x ** 2 - u ** 2, X, U)[0], 6)
    -2.0
    """
    J, X, U, h = _grid(J, X, U, h)
    return _argmin(_smallest_eigenvalue(*hessian(J, X, U, h)), X, U)


def min_curvature_in_u(J, X, U, h=1e-3):
    """Smallest d^2 J / du^2 over a grid: >= 0 means J is convex in u for every fixed x there.

    Returns (J_uu_min, (x, u)) where it is attained.

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-1, 1, 3), np.linspace(-1, 1, 3))
    >>> round(min_curvature_in_u(lambda x, u: x ** 2 + 3 * u ** 2, X, U)[0], 6)
    6.0
    """
    J, X, U, h = _grid(J, X, U, h)
    return _argmin((J(X, U + h) - 2 * J(X, U) + J(X, U - h)) / h ** 2, X, U)


def nonconvex_radius(J, X, U, h=1e-3):
    """Smallest max(|x|, |u|) on the grid at which the Hessian of J has a negative eigenvalue.

    The square [-r, r]^2 with r below this radius is convex on the grid; returns
    (radius, (x, u)) of that grid point, or (inf, None) if the Hessian is PSD everywhere.

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-2, 2, 5), np.linspace(-2, 2, 5))
    >>> nonconvex_radius(lambda x, u: x ** 4 - 6 * x ** 2 + u ** 2, X, U)[0]
    0.0
    """
    J, X, U, h = _grid(J, X, U, h)
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

    Examples
    --------
    >>> symmetric_representative((1.0, -2.0))
    (-1.0, 2.0)
    """
    x, u = (float(v) for v in real_array(point, "point", shape=(2,)))
    return (x, u) if u > 0 or (u == 0 and x >= 0) else (-x + 0.0, -u + 0.0)


def quadratic_fit_residual(X, U, J):
    """Relative RMS residual of the least-squares fit of J by a full quadratic in (x, u).

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 5))
    >>> quadratic_fit_residual(X, U, 1 + X * U + U ** 2) < 1e-12
    True
    """
    X, U, J = _grid_arrays(X=X, U=U, J=J)
    x, u, j = X.ravel(), U.ravel(), J.ravel()
    basis = np.stack([np.ones_like(x), x, u, x * x, x * u, u * u], axis=1)
    coef, *_ = np.linalg.lstsq(basis, j, rcond=None)
    return float(np.sqrt(np.mean((basis @ coef - j) ** 2)) / np.sqrt(np.mean(j ** 2)))
