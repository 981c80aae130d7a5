"""Deterministic Dirac mixture approximation of Gaussians by LCD / mCvMd minimisation.

The thesis draws "10 samples from each Gaussian using the deterministic density
approximation method from [82]" (Sec. 2.6.4): Hanebeck, Huber and Klumpp, "Dirac Mixture
Approximation of Multivariate Gaussian Densities", CDC 2009, which places L equally
weighted Dirac components so that the modified Cramer-von Mises distance between the
localized cumulative distributions (LCDs, [83]) of the Gaussian and of the mixture is
minimal. We implement the one-dimensional case used in Sec. 2.6.4: the distance to the
standard normal is minimised numerically over the L locations, and a Gaussian
:math:`\\mathcal N(\\mu, \\sigma^2)` gets the locations :math:`\\mu + \\sigma x_i` (the
standard-normal approximation transformed by the square root of the covariance, as [82]
do for general Gaussians).
"""

import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.optimize import minimize
from scipy.stats import norm

from .. import config
from .. import validation as check
from ..result import IterativeResult
from . import mixture_checks as v
from .cramer_von_mises import DEFAULT_B_MAX

__all__ = ["gradient_tolerance", "DiracApproximation", "mcvmd_standard_normal_dirac",
           "standard_normal_dirac_approximation", "gaussian_dirac_mixtures"]


def gradient_tolerance(b_max: float) -> float:
    r"""The gradient norm :math:`\sqrt{\epsilon S}` below which the mCvMd minimisation converged.

    The squared distance is a difference of terms of size :math:`S = \sqrt\pi\, b_{\max}^2 / 2`
    (the integral of the growing parts of the integrand), so it is known to about
    :math:`\epsilon S` (machine epsilon). A step along a gradient of norm :math:`g` can lower it
    by about :math:`g^2` (the Hessian is of order one), so below :math:`g = \sqrt{\epsilon S}`
    no step can make measurable progress: ~1.4e-6 for ``b_max = 100``. BFGS stops within a
    tenth of it (1e-8 to 4e-7 on every BLAS kernel we tried).

    Examples
    --------
    >>> f"{gradient_tolerance(100.0):.2g}"
    '1.4e-06'
    """
    return float(np.sqrt(np.finfo(float).eps * np.sqrt(np.pi) * b_max**2 / 2))


@dataclass(kw_only=True)
class DiracApproximation(IterativeResult):
    """Result of :func:`standard_normal_dirac_approximation`: the locations, and why it stopped.

    ``converged`` when the gradient norm of the squared distance at the optimum is below
    ``gradient_tolerance`` (the library's criterion, not the optimiser's status).

    Examples
    --------
    >>> a = standard_normal_dirac_approximation(4)
    >>> a.status, a.x.round(3).tolist()
    ('converged', [-1.259, -0.317, 0.317, 1.259])
    """

    x: np.ndarray          #: (L,) sorted locations of the equally weighted components
    distance: float        #: mCvMd between N(0, 1) and the mixture at the optimum
    iterations: int        #: BFGS iterations
    gradient_norm: float   #: norm of the gradient of the squared distance at the optimum
    b_max: float


def _b_nodes(b_max, per_panel=24):
    """Gauss-Legendre nodes and weights on geometric panels of [0, b_max]."""
    edges = [0.0, 0.125]
    while edges[-1] < b_max:
        edges.append(min(2 * edges[-1], b_max))
    t, w = np.polynomial.legendre.leggauss(per_panel)
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        nodes.append(0.5 * (b - a) * t + 0.5 * (a + b))
        weights.append(0.5 * (b - a) * w)
    return np.concatenate(nodes), np.concatenate(weights)


def mcvmd_standard_normal_dirac(x, wx=None, b_max: float = DEFAULT_B_MAX, nodes=None) -> float:
    r"""MCvMd (Sec. 2.6.3, item 5) between :math:`\mathcal N(0, 1)` and a 1-D Dirac mixture.

    The inner integral over :math:`m` of :math:`(P_1 - P_2)^2` is done in closed form
    (products of Gaussians in :math:`m`); with :math:`w(b) = 1` in one dimension,
    :math:`d^2 = \int_0^{b_{\max}} [G(b) - 2C(b) + D(b)]\,db` where
    :math:`G = \sqrt\pi\, b^2 / \sqrt{1 + b^2}`,
    :math:`C = \sqrt{2\pi}\, b^2 (1 + 2b^2)^{-1/2} \sum_i w_i e^{-x_i^2 / (2(1 + 2b^2))}`,
    :math:`D = \sqrt\pi\, b \sum_{ij} w_i w_j e^{-(x_i - x_j)^2 / (4 b^2)}`; the outer
    integral uses composite Gauss-Legendre quadrature (the growing parts cancel, the
    integrand decays like :math:`\bar x^2 / b`).

    Parameters
    ----------
    x : array_like, (L,)
        Dirac locations.
    wx : array_like (L,) or None
        Weights (None: equal).
    b_max : float
        Upper limit of the kernel widths.
    nodes : tuple of arrays, optional
        Precomputed quadrature nodes and weights over b.

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If the mixture is empty or the weights are invalid.

    Examples
    --------
    >>> round(mcvmd_standard_normal_dirac([-1.0, 1.0]), 4)
    0.2928
    """
    x = check.real_array(x, "x").ravel()
    if x.size == 0:
        raise ValueError("x: expected a non-empty mixture, found 0 components")
    wx = v.weights(wx, x.size, "wx")
    b_max = v.positive(b_max, "b_max")
    b, wb = _b_nodes(b_max) if nodes is None else _nodes(nodes)
    G = np.sqrt(np.pi) * b**2 / np.sqrt(1 + b**2)
    s = 1 + 2 * b**2
    C = np.sqrt(2 * np.pi) * b**2 / np.sqrt(s) * (np.exp(-x[None] ** 2 / (2 * s[:, None])) @ wx)
    d2 = (x[:, None] - x[None]) ** 2
    kernel = np.exp(-d2[None] / (4 * b[:, None, None] ** 2))
    D = np.sqrt(np.pi) * b * np.einsum("i,bij,j->b", wx, kernel, wx)
    return float(np.sqrt(max(wb @ (G - 2 * C + D), 0.0)))


def _objective_and_gradient(x, nodes):
    """Squared distance of :func:`mcvmd_standard_normal_dirac` (equal weights) and its gradient."""
    b, wb = nodes
    L = x.size
    s = 1 + 2 * b**2
    eC = np.exp(-x[None] ** 2 / (2 * s[:, None])) / L                       # (B, L)
    fC = np.sqrt(2 * np.pi) * b**2 / np.sqrt(s)
    dx = x[:, None] - x[None]
    eD = np.exp(-dx[None] ** 2 / (4 * b[:, None, None] ** 2)) / L**2         # (B, L, L)
    G = np.sqrt(np.pi) * b**2 / np.sqrt(1 + b**2)
    f = wb @ (G - 2 * fC * eC.sum(1) + np.sqrt(np.pi) * b * eD.sum((1, 2)))
    dC = fC[:, None] * eC * (-x[None] / s[:, None])
    dD = np.sqrt(np.pi) * b[:, None] * 2 * np.einsum("bkj,kj->bk", eD, -dx) / (2 * b[:, None] ** 2)
    return f, wb @ (-2 * dC + dD)


def _nodes(nodes):
    if not isinstance(nodes, tuple) or len(nodes) != 2:
        raise TypeError("nodes: expected a tuple (nodes, weights) of quadrature over b, "
                        f"found {type(nodes).__name__}")
    b = check.real_array(nodes[0], "nodes", ndim=1)
    return b, check.real_array(nodes[1], "nodes", shape=b.shape)


@lru_cache(maxsize=16)
def _lcd_standard_normal(L: int, b_max: float, max_iterations: int):
    """The minimisation of :func:`standard_normal_dirac_approximation`, remembered per argument."""
    nodes = _b_nodes(b_max)
    x0 = norm.ppf((2 * np.arange(1, L + 1) - 1) / (2 * L))
    res = minimize(_objective_and_gradient, x0, args=(nodes,), jac=True, method="BFGS",
                   options={"gtol": 1e-9, "maxiter": max_iterations})
    x = np.sort(res.x)
    # the gradient norm decides, not BFGS's status: it often ends with "precision loss" at a
    # flat optimum, after a number of iterations that depends on the last bits of the arithmetic
    gradient = float(np.linalg.norm(_objective_and_gradient(res.x, nodes)[1]))
    return x, mcvmd_standard_normal_dirac(x, nodes=nodes), gradient, int(res.nit)


def standard_normal_dirac_approximation(L: int = 10, b_max: float = DEFAULT_B_MAX
                                        ) -> DiracApproximation:
    r"""L equally weighted Dirac components approximating N(0, 1) by mCvMd minimisation [82].

    Starts from the midpoint quantiles :math:`\Phi^{-1}((2i - 1) / (2L))` and minimises
    :func:`mcvmd_standard_normal_dirac` over the locations with BFGS (analytic gradient);
    converged when the gradient norm is below ``gradient_tolerance``. Cached per
    (L, b_max). Warns if the minimisation does not converge.

    Parameters
    ----------
    L : int
        Number of components, 1 to ``config.defaults["gp.max_dirac_components"]`` (400).
    b_max : float
        Upper limit of the mCvMd kernel widths.

    Returns
    -------
    DiracApproximation
        Locations, the reached distance, iterations and why the minimisation stopped.

    Raises
    ------
    ValueError, TypeError
        If ``L`` is not an integer >= 1 or ``b_max`` is not positive.

    Examples
    --------
    >>> a = standard_normal_dirac_approximation(4)
    >>> a.converged, a.x.round(3).tolist(), round(a.distance, 4)
    (True, [-1.259, -0.317, 0.317, 1.259], 0.1016)
    """
    L = check.integer(L, "L", minimum=1, maximum=config.defaults["gp.max_dirac_components"])
    b_max = v.positive(b_max, "b_max")
    max_iterations = config.defaults["gp.dirac_max_iterations"]
    x, dist, gradient, nit = _lcd_standard_normal(L, b_max, max_iterations)
    tol = gradient_tolerance(b_max)
    if gradient <= tol:
        status = "converged"
        message = f"gradient norm {gradient:.2g} <= {tol:.2g} after {nit} iterations"
    else:
        status = "max_iterations" if nit >= max_iterations else "no_progress"
        message = (f"BFGS stopped after {nit} iterations with gradient norm {gradient:.2g} "
                   f"> {tol:.2g}")
        warnings.warn("standard_normal_dirac_approximation: minimisation did not converge "
                      f"(L={L}): {message}", RuntimeWarning)
    return DiracApproximation(x=x.copy(), distance=dist, iterations=nit, gradient_norm=gradient,
                              b_max=b_max, converged=status == "converged", status=status,
                              message=message)


def gaussian_dirac_mixtures(means, variances, L: int = 10, b_max: float = DEFAULT_B_MAX):
    """Deterministic L-component Dirac approximations of 1-D Gaussians N(mean, variance).

    Parameters
    ----------
    means, variances : array_like, (N,)
    L : int
        Number of equally weighted components.
    b_max : float
        Upper limit of the mCvMd kernel widths.

    Returns
    -------
    ndarray, (N, L, 1)
        The locations ``mean + sqrt(variance) * x_i`` (:func:`standard_normal_dirac_approximation`).

    Raises
    ------
    ValueError, TypeError
        If ``means`` and ``variances`` differ in shape or a variance is negative.

    Examples
    --------
    >>> gaussian_dirac_mixtures([0.0, 10.0], [1.0, 4.0], L=2)[:, :, 0].round(3).tolist()
    [[-0.795, 0.795], [8.41, 11.59]]
    """
    mu = np.atleast_1d(check.real_array(means, "means"))
    var = np.atleast_1d(check.real_array(variances, "variances"))
    if mu.shape != var.shape or mu.ndim != 1 or mu.size == 0:
        raise ValueError("means, variances: expected equal 1-D shapes, "
                         f"found {mu.shape} and {var.shape}")
    if np.any(var < 0):
        raise ValueError(f"variances: expected non-negative values, found minimum {var.min():.3g}")
    x = standard_normal_dirac_approximation(L, b_max).x
    return (mu[:, None] + np.sqrt(var)[:, None] * x[None])[:, :, None]
