"""Covariance functions of a distance between distributions (Table 2.1) and the mean kernel.

Every function of Table 2.1 takes the distance :math:`\\Delta = D(d_i, d_j)` (any array
shape) and the length scale :math:`l`, and returns the unit-variance covariance; the GP
multiplies by :math:`\\alpha^2`. :func:`mean_kernel_dirac` and :func:`mean_kernel_gaussian`
are the mean covariance function (2.22) of Dallaire et al. [42], the thesis's baseline.
"""

import numpy as np
from scipy.special import gamma as gamma_fn
from scipy.special import kv

from .. import validation
from . import mixture_checks as v

__all__ = ["squared_exponential", "matern", "exponential", "gamma_exponential",
           "rational_quadratic", "TABLE_2_1", "COVARIANCES", "bilinear_product",
           "mean_kernel_dirac", "mean_kernel_gaussian"]


def squared_exponential(delta, l: float, check: bool = True):
    r"""Squared exponential covariance function, Table 2.1: :math:`\exp(-\tfrac12 \Delta^2 / l^2)`.

    Parameters
    ----------
    delta : array_like
        Distances between distributions (finite, non-negative).
    l : float
        Length scale, > 0.
    check : bool
        False skips the checks (float distances >= 0 and positive parameters, e.g. a
        library loop that evaluates the covariance on its own checked matrix many times).

    Returns
    -------
    numpy.ndarray
        Covariances, shape of ``delta``.

    Raises
    ------
    ValueError, TypeError
        If ``delta`` has negative or non-finite entries, or ``l`` is not positive.

    Examples
    --------
    >>> squared_exponential([0.0, 1.0], 1.0).round(4).tolist()
    [1.0, 0.6065]
    """
    if check:
        delta, l = v.distances(delta), v.positive(l, "l")
    return _squared_exponential(delta, l)


def matern(delta, l: float, nu: float = 2.5, check: bool = True):
    r"""Matern, Table 2.1: :math:`\frac{2^{1-\nu}}{\Gamma(\nu)} (\tfrac{\sqrt{2\nu}}{l}\Delta)^\nu
    K_\nu(\tfrac{\sqrt{2\nu}}{l}\Delta)`, with value 1 at :math:`\Delta = 0`.

    Parameters
    ----------
    delta : array_like
        Distances (finite, non-negative).
    l : float
        Length scale, > 0.
    nu : float
        Smoothness, > 0.
    check : bool
        False skips the checks (float distances >= 0 and positive parameters, e.g. a
        library loop that evaluates the covariance on its own checked matrix many times).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``delta`` is invalid, or ``l`` or ``nu`` is not positive.

    Examples
    --------
    >>> matern([0.0, 1.0], 1.0, nu=2.5).round(4).tolist()
    [1.0, 0.524]
    """
    if check:
        delta, l, nu = v.distances(delta), v.positive(l, "l"), v.positive(nu, "nu")
    return _matern(delta, l, nu)


def exponential(delta, l: float, check: bool = True):
    r"""Exponential, Table 2.1: :math:`\exp(-\Delta / l)` (Matern with :math:`\nu = 1/2`).

    Parameters
    ----------
    delta : array_like
        Distances (finite, non-negative).
    l : float
        Length scale, > 0.
    check : bool
        False skips the checks (float distances >= 0 and positive parameters, e.g. a
        library loop that evaluates the covariance on its own checked matrix many times).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``delta`` is invalid or ``l`` is not positive.

    Examples
    --------
    >>> exponential([0.0, 1.0], 2.0).round(4).tolist()
    [1.0, 0.6065]
    """
    if check:
        delta, l = v.distances(delta), v.positive(l, "l")
    return _exponential(delta, l)


def gamma_exponential(delta, l: float, gamma: float = 1.5, check: bool = True):
    r""":math:`\gamma`-exponential, Table 2.1: :math:`\exp(-(\Delta / l)^\gamma)`,
    :math:`0 < \gamma \le 2`.

    Parameters
    ----------
    delta : array_like
        Distances (finite, non-negative).
    l : float
        Length scale, > 0.
    gamma : float
        Exponent in (0, 2].
    check : bool
        False skips the checks (float distances >= 0 and positive parameters, e.g. a
        library loop that evaluates the covariance on its own checked matrix many times).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``delta`` is invalid, ``l`` is not positive or ``gamma`` is outside (0, 2].

    Examples
    --------
    >>> gamma_exponential([0.0, 1.0], 1.0, gamma=1.5).round(4).tolist()
    [1.0, 0.3679]
    """
    if check:
        delta, l = v.distances(delta), v.positive(l, "l")
        gamma = validation.real_scalar(gamma, "gamma", low=0, high=2, low_open=True)
    return _gamma_exponential(delta, l, gamma)


def rational_quadratic(delta, l: float, alpha: float = 1.0, check: bool = True):
    r"""Rational quadratic, Table 2.1: :math:`(1 + \Delta^2 / (2 \alpha l^2))^{-\alpha}`.

    Parameters
    ----------
    delta : array_like
        Distances (finite, non-negative).
    l : float
        Length scale, > 0.
    alpha : float
        Scale mixture parameter, > 0.
    check : bool
        False skips the checks (float distances >= 0 and positive parameters, e.g. a
        library loop that evaluates the covariance on its own checked matrix many times).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``delta`` is invalid, or ``l`` or ``alpha`` is not positive.

    Examples
    --------
    >>> rational_quadratic([0.0, 1.0], 1.0, alpha=1.0).round(4).tolist()
    [1.0, 0.6667]
    """
    if check:
        delta, l, alpha = v.distances(delta), v.positive(l, "l"), v.positive(alpha, "alpha")
    return _rational_quadratic(delta, l, alpha)


def _squared_exponential(delta, l):
    return np.exp(-0.5 * (delta / l) ** 2)


def _matern(delta, l, nu=2.5):
    r = np.sqrt(2 * nu) * delta / l
    with np.errstate(invalid="ignore", over="ignore"):
        out = 2 ** (1 - nu) / gamma_fn(nu) * r**nu * kv(nu, r)
    return np.where(r == 0, 1.0, np.nan_to_num(out, nan=0.0))


def _exponential(delta, l):
    return np.exp(-delta / l)


def _gamma_exponential(delta, l, gamma=1.5):
    return np.exp(-(delta / l) ** gamma)


def _rational_quadratic(delta, l, alpha=1.0):
    return (1 + delta ** 2 / (2 * alpha * l**2)) ** (-alpha)


#: Table 2.1: name -> (function, LaTeX expression, extra shape parameter or None).
TABLE_2_1 = {
    "squared exponential": (squared_exponential,
                            r"$\exp\left(-\frac{1}{2}\frac{\Delta^2}{l^2}\right)$", None),
    "Matérn": (matern, r"$\frac{2^{1-\nu}}{\Gamma(\nu)}\left(\frac{\sqrt{2\nu}}{l}\Delta\right)^\nu"
                       r" K_\nu\left(\frac{\sqrt{2\nu}}{l}\Delta\right)$", "nu"),
    "exponential": (exponential, r"$\exp\left(-\frac{\Delta}{l}\right)$", None),
    "γ-exponential": (gamma_exponential,
                      r"$\exp\left(-\left(\frac{\Delta}{l}\right)^\gamma\right)$",
                      "gamma"),
    "rational quadratic": (rational_quadratic,
                           r"$\left(1+\frac{\Delta^2}{2\alpha l^2}\right)^{-\alpha}$", "alpha"),
}

#: Short names used by :class:`asoc.gp.DistributionGP`.
COVARIANCES = {"se": squared_exponential, "matern": matern, "exponential": exponential,
               "gamma_exponential": gamma_exponential, "rational_quadratic": rational_quadratic}


def bilinear_product(K_distance, means_i, means_j, Sigma):
    r"""Product of a distance covariance with a bilinear kernel of the means (Sec. 2.6.3).

    :math:`k(d_i, d_j) = \hat{\underline x}_i^\top \mathbf\Sigma \hat{\underline x}_j\,
    k_D(d_i, d_j)`, with ``K_distance`` (N, M) the distance covariance (e.g.
    :func:`squared_exponential` of a distance matrix), ``means_i`` (N, n), ``means_j`` (M, n)
    and :math:`\mathbf\Sigma \succeq 0` (n, n).

    Parameters
    ----------
    K_distance : array_like, (N, M)
        Distance covariance.
    means_i, means_j : array_like, (N, n) and (M, n)
        Means of the distributions.
    Sigma : array_like, (n, n)
        Symmetric positive semidefinite weight.

    Returns
    -------
    numpy.ndarray, (N, M)

    Raises
    ------
    ValueError, TypeError
        If ``Sigma`` is not symmetric PSD or the shapes do not match.

    Examples
    --------
    >>> bilinear_product(np.ones((1, 2)), [[1.0]], [[2.0], [3.0]], [[1.0]]).tolist()
    [[2.0, 3.0]]
    """
    Sigma = v.covariance(Sigma, "Sigma")
    mi = validation.real_array(means_i, "means_i", shape=(None, Sigma.shape[0]))
    mj = validation.real_array(means_j, "means_j", shape=(None, Sigma.shape[0]))
    K = validation.real_array(K_distance, "K_distance")
    if K.shape != (len(mi), len(mj)):
        raise ValueError(f"K_distance: expected shape {(len(mi), len(mj))}, found {K.shape}")
    return (mi @ Sigma @ mj.T) * K


def mean_kernel_dirac(X, Y=None, WX=None, WY=None, *, alpha: float, Lambda, chunk: int = 16):
    r"""Mean covariance function (2.22) of Dallaire et al. [42] between Dirac mixtures.

    :math:`k(d_i, d_j) = \sum_a \sum_b w_{i,a} w_{j,b}\, \alpha^2
    \exp(-\tfrac12 (\underline x_{i,a} - \underline x_{j,b})^\top \mathbf\Lambda^{-1}
    (\underline x_{i,a} - \underline x_{j,b}))`, the SE kernel averaged over both inputs.
    ``X`` (N, L, d), ``Y`` (M, K, d) (``None``: ``X``), weights (N, L)/(M, K) or ``None``;
    ``Lambda`` a positive scalar (:math:`l^2`) or (d, d) positive definite matrix; ``chunk``
    mixtures of ``X`` per vectorised block. Returns (N, M).

    Parameters
    ----------
    X, Y : array_like, (N, L, d) and (M, K, d)
        Dirac mixtures (``Y=None``: ``X``).
    WX, WY : array_like (N, L) / (M, K) or None
        Weights (None: equal).
    alpha : float
        Signal standard deviation, > 0.
    Lambda : float or array_like (d, d)
        Squared length scale or positive definite matrix.
    chunk : int
        Mixtures of ``X`` per vectorised block.

    Returns
    -------
    numpy.ndarray, (N, M)

    Raises
    ------
    ValueError, TypeError
        If the mixtures, weights, ``alpha`` or ``Lambda`` are invalid or the dimensions differ.

    Examples
    --------
    >>> X = np.array([[[0.0], [1.0]], [[0.0], [0.0]]])
    >>> mean_kernel_dirac(X, alpha=1.0, Lambda=1.0).round(4).tolist()
    [[0.8033, 0.8033], [0.8033, 1.0]]
    """
    X = v.mixture_set(X, "X")
    WX = v.set_weights(WX, X.shape, "WX")
    if Y is None:
        Y, WY = X, WX
    else:
        Y = v.mixture_set(Y, "Y")
        WY = v.set_weights(WY, Y.shape, "WY")
    v.same_dimension(X, Y, "X, Y")
    Linv = _lambda_inverse(Lambda, X.shape[2])
    alpha = v.positive(alpha, "alpha")
    chunk = validation.integer(chunk, "chunk", minimum=1)
    out = np.empty((len(X), len(Y)))
    for start in range(0, len(X), chunk):
        sl = slice(start, start + chunk)
        diff = X[sl, None, :, None, :] - Y[None, :, None, :, :]
        quad = np.einsum("...i,ij,...j->...", diff, Linv, diff)
        out[sl] = np.einsum("na,nmab,mb->nm", WX[sl], np.exp(-0.5 * quad), WY)
    return alpha**2 * out


def mean_kernel_gaussian(means_i, covs_i, means_j, covs_j, *, alpha: float, Lambda):
    r"""Mean covariance function (2.22) between Gaussians, closed form ([42], SE kernel).

    :math:`k = \alpha^2 |\mathbf I + \mathbf\Lambda^{-1}(\mathbf C_i + \mathbf C_j)|^{-1/2}
    \exp(-\tfrac12 \Delta\underline\mu^\top (\mathbf\Lambda + \mathbf C_i + \mathbf C_j)^{-1}
    \Delta\underline\mu)`. ``means_*`` (N, d), ``covs_*`` (N, d, d). Returns (N, M).

    Parameters
    ----------
    means_i, covs_i : array_like, (N, d) and (N, d, d)
    means_j, covs_j : array_like, (M, d) and (M, d, d)
    alpha : float
        Signal standard deviation, > 0.
    Lambda : float or array_like (d, d)
        Squared length scale or positive definite matrix.

    Returns
    -------
    numpy.ndarray, (N, M)

    Raises
    ------
    ValueError, TypeError
        If shapes do not match, a covariance is not symmetric PSD, or ``alpha``/``Lambda``
        is invalid.

    Examples
    --------
    >>> k = mean_kernel_gaussian([[0.0]], [[[1.0]]], [[0.0]], [[[1.0]]], alpha=1.0, Lambda=1.0)
    >>> k.round(4).tolist()     # 1 / sqrt(1 + 2)
    [[0.5774]]
    """
    mi = validation.real_array(means_i, "means_i", ndim=2)
    d = mi.shape[1]
    mj = validation.real_array(means_j, "means_j", shape=(None, d))
    Ci = validation.real_array(covs_i, "covs_i", shape=(len(mi), d, d))
    Ci = validation.semidefinite(Ci, "covs_i")
    Cj = validation.real_array(covs_j, "covs_j", shape=(len(mj), d, d))
    Cj = validation.semidefinite(Cj, "covs_j")
    if 0 in mi.shape + mj.shape:
        raise ValueError("means_i, means_j: expected non-empty (N, d) arrays, "
                         f"found {mi.shape} and {mj.shape}")
    Lam = np.linalg.inv(_lambda_inverse(Lambda, d))
    alpha = v.positive(alpha, "alpha")
    S = Lam + Ci[:, None] + Cj[None]                                   # (N, M, d, d)
    dm = mi[:, None] - mj[None]
    quad = np.einsum("nmi,nmi->nm", dm, np.linalg.solve(S, dm[..., None])[..., 0])
    ratio = np.linalg.det(S) / np.linalg.det(Lam)
    return alpha**2 / np.sqrt(ratio) * np.exp(-0.5 * quad)


def _lambda_inverse(Lambda, d):
    Lam = validation.real_array(Lambda, "Lambda")
    if Lam.ndim == 0:
        return np.eye(d) / v.positive(Lam, "Lambda")
    return np.linalg.inv(validation.covariance(Lam, "Lambda", d, definite=True))
