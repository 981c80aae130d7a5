"""Statistical second-order Taylor expansion at a Dirac mixture (Definition 2.2) and the
linearisation example of Fig. 2.2.
"""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from .filters import DiracMixture, sigma_points

__all__ = ["QuadraticExpansion", "derivatives", "statistical_taylor_expansion",
           "sigma_point_linearizations", "statistical_taylor_linearization_error"]


@dataclass(frozen=True)
class QuadraticExpansion:
    """E{s + v^T x + 1/2 x^T V x}: the expansion (2.8) written as a quadratic in x.

    Attributes ``s`` (scalar), ``v`` (n,), ``V`` (n, n).

    Examples
    --------
    >>> q = QuadraticExpansion(1.0, np.array([0.0, 2.0]), 2 * np.eye(2))
    >>> float(q(np.array([1.0, 1.0]))), q.expectation([0.0, 0.0], np.eye(2))
    (5.0, 3.0)
    """

    s: float
    v: np.ndarray
    V: np.ndarray

    def __call__(self, x):
        """The quadratic s + v^T x + 1/2 x^T V x at points x of shape (..., n)."""
        x = np.asarray(x, dtype=float)
        return self.s + x @ self.v + 0.5 * np.einsum("...i,ij,...j->...", x, self.V, x)

    def expectation(self, mean, cov):
        """E{.} for x with the given mean and covariance: s + v^T m + 1/2 (m^T V m + tr(V C))."""
        mean = np.asarray(mean, dtype=float)
        return float(self(mean) + 0.5 * np.trace(self.V @ np.asarray(cov, dtype=float)))


def derivatives(g, x, grad=None, hess=None):
    """Gradient and Hessian of scalar ``g`` at ``x``: analytic if given, else numdifftools [46].

    Examples
    --------
    g(x) = x_0^2 + 3 x_0 x_1 has gradient (2 x_0 + 3 x_1, 3 x_0) and Hessian [[2, 3], [3, 0]];
    numdifftools finds them to rounding, analytic derivatives are used as given:

    >>> g = lambda x: x[0] ** 2 + 3 * x[0] * x[1]
    >>> G, H = derivatives(g, [1.0, 2.0])
    >>> G.round(6) + 0.0, H.round(6) + 0.0                   # + 0.0: a rounded -0.0 prints as 0.
    (array([8., 3.]), array([[2., 3.],
           [3., 0.]]))
    >>> derivatives(g, [1.0, 2.0], grad=lambda x: [2 * x[0] + 3 * x[1], 3 * x[0]],
    ...             hess=lambda x: [[2.0, 3.0], [3.0, 0.0]])[0]
    array([8., 3.])
    """
    import numdifftools as nd
    x = np.atleast_1d(np.asarray(x, dtype=float))
    G = np.atleast_1d(grad(x)) if grad is not None else np.atleast_1d(nd.Gradient(g)(x))
    H = np.atleast_2d(hess(x)) if hess is not None else np.atleast_2d(nd.Hessian(g)(x))
    return G.reshape(x.size), H.reshape(x.size, x.size)


def statistical_taylor_expansion(g, mixture: DiracMixture, grad=None, hess=None
                                 ) -> QuadraticExpansion:
    """Second-order expansion of a(p) = E{g(x)} at a Dirac mixture (Definition 2.2, eq. 2.8).

    sum_i alpha_i [g(x_i) + grad g(x_i)^T (x - x_i) + 1/2 (x - x_i)^T hess g(x_i) (x - x_i)],
    collected as s + v^T x + 1/2 x^T V x with (the form of Theorem 2.4)

    s = sum_i alpha_i [g(x_i) - grad g(x_i)^T x_i + 1/2 x_i^T hess g(x_i) x_i],
    v = sum_i alpha_i [grad g(x_i) - hess g(x_i) x_i],   V = sum_i alpha_i hess g(x_i).

    Parameters
    ----------
    g : callable
        R^n -> R.
    mixture : DiracMixture
        The expansion point.
    grad, hess : callable, optional
        Analytic derivatives of g; numdifftools otherwise.

    Returns
    -------
    QuadraticExpansion
        s, v, V of the expansion.

    Raises
    ------
    TypeError
        If ``g``, ``grad`` or ``hess`` is not callable or ``mixture`` not a DiracMixture.

    Examples
    --------
    >>> q = statistical_taylor_expansion(lambda x: float(x @ x), DiracMixture([[1.0], [-1.0]]))
    >>> round(q.s, 6), q.v.round(6).tolist(), q.V.round(6).tolist()
    (0.0, [0.0], [[2.0]])
    """
    check.function(g, "g")
    check.instance(mixture, DiracMixture, "mixture")
    for name, f in (("grad", grad), ("hess", hess)):
        if f is not None:
            check.function(f, name)
    s, v, V = 0.0, 0.0, 0.0
    for alpha, x in zip(mixture.weights, mixture.points):
        G, H = derivatives(g, x, grad, hess)
        s += alpha * (float(g(x)) - G @ x + 0.5 * x @ H @ x)
        v = v + alpha * (G - H @ x)
        V = V + alpha * H
    return QuadraticExpansion(float(s), np.atleast_1d(v), np.atleast_2d(V))


# --- Fig. 2.2 -------------------------------------------------------------------------

def _fig22_function(x):
    return np.sin(x) + x


def _fig22_derivative(x):
    return np.cos(x) + 1.0


def sigma_point_linearizations(a=_fig22_function, da=_fig22_derivative, mean=4.0, var=1.5):
    """The linear approximations compared in Fig. 2.2 as ``{name: (slope, intercept)}``.

    The Dirac mixture is the UKF's sigma points of N(mean, var) (kappa = 0.5: the points
    4, 2.5, 5.5 with weights 1/3 each). Readings of "linearisation at the three sigma points":

    * ``ekf``: first-order Taylor expansion at the mean (Fig. 2.2 a);
    * ``mean_gradient``: the weighted mean of the derivatives at the sigma points as slope,
      through (mean, a(mean)) - the reading that gives the printed 0.6289 (Fig. 2.2 b);
    * ``def_2_2_first_order``: first-order part of Definition 2.2 (average of the
      tangents at the sigma points);
    * ``regression``: statistical linear regression through the sigma points [109];
    * ``mean_gradient_through_mean_value``: the mean derivative through (mean, E{a}).

    Parameters
    ----------
    a, da : callable
        The function and its derivative (default: a(x) = sin(x) + x of Fig. 2.2).
    mean, var : float
        The Gaussian N(mean, var).

    Returns
    -------
    dict
        ``{name: (slope, intercept)}``.

    Raises
    ------
    ValueError, TypeError
        If ``a`` or ``da`` is not callable, ``mean`` not finite or ``var`` not positive.

    Examples
    --------
    >>> slope, intercept = sigma_point_linearizations()["mean_gradient"]
    >>> round(float(slope), 4), round(float(intercept), 4)
    (0.7513, 0.238)
    """
    check.function(a, "a"), check.function(da, "da")
    mean = check.real_scalar(mean, "mean")
    var = check.real_scalar(var, "var", low=0, low_open=True)
    pts, w = sigma_points(np.array([mean]), np.array([[var]]))
    x = pts[:, 0]
    ya, slopes = a(x), da(x)
    mean_slope = w @ slopes
    y_mean = w @ ya
    reg_slope = (w * (x - mean)) @ (ya - y_mean) / ((w * (x - mean)) @ (x - mean))
    return {
        "ekf": (da(mean), a(mean) - da(mean) * mean),
        "mean_gradient": (mean_slope, a(mean) - mean_slope * mean),
        "def_2_2_first_order": (mean_slope, w @ (ya - slopes * x)),
        "regression": (reg_slope, y_mean - reg_slope * mean),
        "mean_gradient_through_mean_value": (mean_slope, y_mean - mean_slope * mean),
    }


def statistical_taylor_linearization_error(x_true=5.7, mean=4.0, var=1.5, reading="mean_gradient"):
    """Absolute linearisation errors of Fig. 2.2 at the true input ``x_true``.

    a(x) = sin(x) + x, the Gaussian N(4, 1.5) (variance 1.5: the toolbox UKF's sigma points
    are then 4 and 4 +- 1.5, the points the thesis prints).

    Parameters
    ----------
    x_true : float
        The input at which the errors are evaluated.
    mean, var : float
        The Gaussian N(mean, var).
    reading : str
        A key of :func:`sigma_point_linearizations`.

    Returns
    -------
    ekf_error : float
        The error of the linearisation at the mean (the thesis prints it for Fig. 2.2; see the
        ledger).
    statistical_error : float
        The error of the statistical linearisation ``reading``.

    Raises
    ------
    ValueError, TypeError
        If ``x_true`` or ``mean`` is not finite, ``var`` is not positive or ``reading`` is unknown.

    Examples
    --------
    >>> ekf, statistical = statistical_taylor_linearization_error()
    >>> round(ekf, 4), round(statistical, 4)
    (1.3173, 0.6289)
    """
    x_true = check.real_scalar(x_true, "x_true")
    lines = sigma_point_linearizations(mean=mean, var=var)
    check.choice(reading, "reading", lines)
    truth = _fig22_function(x_true)
    err = {name: abs(truth - (k * x_true + d)) for name, (k, d) in lines.items()}
    return float(err["ekf"]), float(err[reading])
