"""Input checks of asoc.gp on top of :mod:`asoc.validation`: Dirac mixtures, sets of mixtures,
distances and integration limits (ValueError/TypeError naming the argument).
"""

import numpy as np

from .. import validation as check

__all__ = ["weights", "locations", "same_dimension", "mixture_set", "set_weights", "covariance",
           "positive", "order", "distances", "widths", "limits", "gaussian_set",
           "piecewise_constant"]


def weights(w, m: int, name: str) -> np.ndarray:
    """Mixture weights of ``m`` components: ``None`` means equal weights.

    Examples
    --------
    >>> weights(None, 4, "w")
    array([0.25, 0.25, 0.25, 0.25])
    >>> weights([0.5, 0.6], 2, "w")
    Traceback (most recent call last):
    ...
    ValueError: w: expected probabilities summing to 1, found sum 1.1
    """
    return check.weights_or_equal(w, name, m)


def locations(x, name: str) -> np.ndarray:
    """Dirac locations as an ``(M, d)`` float array; a number or 1-D array is read as M scalars.

    Examples
    --------
    >>> locations([1.0, 2.0, 3.0], "x")
    array([[1.],
           [2.],
           [3.]])
    >>> locations(np.zeros((0, 2)), "x")
    Traceback (most recent call last):
    ...
    ValueError: x: expected non-empty locations of shape (M, d), found shape (0, 2)
    """
    x = check.real_array(x, name)
    if x.ndim < 2:
        x = x.reshape(-1, 1)
    if x.ndim != 2 or 0 in x.shape:
        raise ValueError(f"{name}: expected non-empty locations of shape (M, d), "
                         f"found shape {x.shape}")
    return x


def same_dimension(x, y, names: str):
    """Raise unless the mixtures have the same dimension (last axis).

    Examples
    --------
    >>> same_dimension(np.zeros((3, 2)), np.zeros((4, 2)), "x, y")
    >>> same_dimension(np.zeros((3, 2)), np.zeros((4, 1)), "x, y")
    Traceback (most recent call last):
    ...
    ValueError: x, y: expected mixtures of the same dimension, found 2 and 1
    """
    if x.shape[-1] != y.shape[-1]:
        raise ValueError(f"{names}: expected mixtures of the same dimension, "
                         f"found {x.shape[-1]} and {y.shape[-1]}")


def mixture_set(X, name: str) -> np.ndarray:
    """A set of equally sized mixtures as ``(N, L, d)``; ``(N, L)`` is read as scalar locations.

    Examples
    --------
    >>> mixture_set([[0.0, 1.0], [2.0, 3.0]], "X").shape
    (2, 2, 1)
    >>> mixture_set(np.zeros(3), "X")
    Traceback (most recent call last):
    ...
    ValueError: X: expected a non-empty array of shape (N, L, d), found shape (3,)
    """
    X = check.real_array(X, name)
    if X.ndim == 2:
        X = X[:, :, None]
    if X.ndim != 3 or 0 in X.shape:
        raise ValueError(f"{name}: expected a non-empty array of shape (N, L, d), "
                         f"found shape {X.shape}")
    return X


def set_weights(W, shape, name: str) -> np.ndarray:
    """Weights of a mixture set, ``(N, L)`` rows of probabilities; ``None`` means equal weights.

    Examples
    --------
    >>> set_weights(None, (2, 4), "W")
    array([[0.25, 0.25, 0.25, 0.25],
           [0.25, 0.25, 0.25, 0.25]])
    >>> set_weights([[0.5, 0.5], [1.0, 0.5]], (2, 2), "W")
    Traceback (most recent call last):
    ...
    ValueError: W: expected each row to sum to 1, found a sum 1.5
    """
    n, m = shape[:2]
    if W is None:
        return np.full((n, m), 1.0 / m)
    return check.probability_rows(W, name, (n, m))


def covariance(C, name: str, definite=False) -> np.ndarray:
    """A symmetric positive semi-definite covariance as an ``(n, n)`` array (scalars allowed).

    Examples
    --------
    >>> covariance(2.0, "C")
    array([[2.]])
    >>> covariance([[1.0, 2.0], [2.0, 1.0]], "C")
    Traceback (most recent call last):
    ...
    ValueError: C: expected a positive semi-definite matrix, found smallest eigenvalue -1
    """
    return check.covariance(C, name, definite=definite, scalar=True)


def positive(value, name: str) -> float:
    """A finite number > 0.

    Examples
    --------
    >>> positive(0.5, "sigma")
    0.5
    >>> positive(0, "sigma")
    Traceback (most recent call last):
    ...
    ValueError: sigma: expected a finite real number > 0, found 0
    """
    return check.real_scalar(value, name, low=0, low_open=True)


def order(value, name: str) -> float:
    """The order of a distance: a number in [1, 100] (higher powers of distances overflow).

    Examples
    --------
    >>> order(2, "p")
    2.0
    >>> order(0.5, "p")
    Traceback (most recent call last):
    ...
    ValueError: p: expected a finite real number >= 1 and <= 100, found 0.5
    """
    return check.real_scalar(value, name, low=1, high=100)


def distances(delta, name: str = "delta") -> np.ndarray:
    """Finite non-negative distances of any shape.

    Examples
    --------
    >>> distances([0.0, 1.5])
    array([0. , 1.5])
    >>> distances([-1.0, 1.5])
    Traceback (most recent call last):
    ...
    ValueError: delta: expected non-negative distances, found minimum -1
    """
    delta = check.real_array(delta, name)
    if np.any(delta < 0):
        raise ValueError(f"{name}: expected non-negative distances, "
                         f"found minimum {delta.min():.3g}")
    return delta


def widths(b, size: int, name: str = "b") -> np.ndarray:
    """Kernel widths b > 0: a number or one per evaluation point.

    Examples
    --------
    >>> widths(0.5, 3)
    array([0.5, 0.5, 0.5])
    >>> widths([0.5, 1.0], 3)
    Traceback (most recent call last):
    ...
    ValueError: b: expected a number or shape (3,), found shape (2,)
    """
    b = check.real_array(b, name)
    if b.ndim > 1 or (b.ndim == 1 and b.size != size):
        raise ValueError(f"{name}: expected a number or shape ({size},), found shape {b.shape}")
    if np.any(b <= 0):
        raise ValueError(f"{name}: expected positive kernel widths, found minimum {b.min():.3g}")
    return np.broadcast_to(b, (size,))


def limits(lower, upper):
    """Integration limits: real numbers or infinities with lower < upper.

    Examples
    --------
    >>> limits(0, np.inf)
    [0.0, inf]
    >>> limits(1, 0)
    Traceback (most recent call last):
    ...
    ValueError: lower, upper: expected lower < upper, found 1.0 and 0.0
    >>> limits("a", 0)
    Traceback (most recent call last):
    ...
    TypeError: lower: expected a real number or an infinity, found 'a'
    """
    out = []
    for name, value in (("lower", lower), ("upper", upper)):
        if (isinstance(value, (bool, np.bool_, str, bytes)) or not np.isscalar(value)
                or np.iscomplexobj(value)):
            raise TypeError(f"{name}: expected a real number or an infinity, found {value!r}")
        value = float(value)
        if np.isnan(value):
            raise ValueError(f"{name}: expected a real number or an infinity, found nan")
        out.append(value)
    if not out[0] < out[1]:
        raise ValueError(f"lower, upper: expected lower < upper, found {out[0]} and {out[1]}")
    return out


def gaussian_set(means, covs, means_name: str, covs_name: str, definite=False):
    """Gaussians: means (N, d), symmetric PSD covariances (N, d, d) (definite if ``definite``).

    Examples
    --------
    >>> means, covs = gaussian_set([0.0, 1.0], [1.0, 2.0], "means", "covs")
    >>> means.shape, covs.shape, covs[:, 0, 0]
    ((2, 1), (2, 1, 1), array([1., 2.]))
    >>> gaussian_set([0.0, 1.0], [1.0], "means", "covs")
    Traceback (most recent call last):
    ...
    ValueError: covs: expected shape (2, 1, 1) (one covariance per mean), found shape (1, 1, 1)
    """
    means = check.real_array(means, means_name)
    if means.ndim == 1:
        means = means[:, None]
    if means.ndim != 2 or 0 in means.shape:
        raise ValueError(f"{means_name}: expected a non-empty array of shape (N, d), "
                         f"found shape {means.shape}")
    N, d = means.shape
    covs = check.real_array(covs, covs_name)
    if covs.ndim == 1 and d == 1:
        covs = covs[:, None, None]
    if covs.shape != (N, d, d):
        raise ValueError(f"{covs_name}: expected shape ({N}, {d}, {d}) (one covariance per mean), "
                         f"found shape {covs.shape}")
    return means, check.semidefinite(covs, covs_name, definite=definite)


def piecewise_constant(heights, edges, heights_name: str = "heights"):
    """Densities constant on the cells of ``edges``: heights (N, B) >= 0, increasing edges (B + 1,).

    Examples
    --------
    >>> piecewise_constant([[0.5, 0.5]], [0.0, 1.0, 2.0])
    (array([[0.5, 0.5]]), array([1., 1.]))
    >>> piecewise_constant([[0.5, 0.5]], [0.0, 2.0, 1.0])
    Traceback (most recent call last):
    ...
    ValueError: edges: expected at least two increasing cell edges, found [0.0, 2.0, 1.0]
    """
    edges = check.real_array(edges, "edges", ndim=1)
    if edges.size < 2 or not np.all(np.diff(edges) > 0):
        raise ValueError("edges: expected at least two increasing cell edges, "
                         f"found {edges.tolist()}")
    heights = check.real_array(heights, heights_name, shape=(None, edges.size - 1))
    if heights.shape[0] == 0 or np.any(heights < 0):
        minimum = heights.min() if heights.size else "none"
        raise ValueError(f"{heights_name}: expected non-empty non-negative heights of shape "
                         f"(N, {edges.size - 1}), found shape {heights.shape} and "
                         f"minimum {minimum}")
    return heights, np.diff(edges)
