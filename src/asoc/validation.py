"""Argument checks shared by ``asoc.mjls``, ``asoc.belief`` and ``asoc.gp``.

Every check takes the value and the argument's name *as the caller wrote it* and raises a
``TypeError`` (wrong kind of object) or ``ValueError`` (right kind, wrong value) whose
message reads ``"<name>: expected <what>, found <what>"``. Each returns the value converted
(a float array, an ``int``), so a caller writes ``x0 = real_array(x0, "x0", shape=(n,))``.
"""

import collections.abc
import numbers

import numpy as np

__all__ = ["SYMMETRY_RTOL", "WEIGHT_ATOL", "integer", "real_scalar", "real_array", "symmetric",
           "semidefinite", "probability_vector", "generator", "instance", "function",
           "stochastic_matrix", "choice", "boolean", "covariance", "vector", "weights_or_equal",
           "probability_rows", "process_count"]


SYMMETRY_RTOL = 1e-9
WEIGHT_ATOL = 1e-8


def _describe(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{type(value).__name__} {text[:57]}..."


def integer(value, name: str, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer count: ``int`` or a NumPy integer; bool, float, NaN and strings are rejected.

    Examples
    --------
    >>> integer(5, "horizon", minimum=1)
    5
    >>> integer(2.5, "horizon")
    Traceback (most recent call last):
    ...
    TypeError: horizon: expected an integer, found 2.5
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, found {_describe(value)}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, found {value}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name}: expected an integer <= {maximum}, found {value}")
    return value


def process_count(value, name: str) -> int:
    """A number of worker processes as joblib reads it: a positive count or -1 (all cores).

    Examples
    --------
    >>> process_count(-1, "n_jobs")
    -1
    >>> process_count(0, "n_jobs")
    Traceback (most recent call last):
    ...
    ValueError: n_jobs: expected a positive number of processes or -1 (all cores), found 0
    """
    value = integer(value, name)
    if value == 0 or value < -1:
        raise ValueError(f"{name}: expected a positive number of processes or -1 (all cores), "
                         f"found {value}")
    return value


def real_scalar(value, name: str, *, low=None, high=None, low_open=False, high_open=False) -> float:
    """A finite real number, optionally in ``[low, high]`` (``low_open``/``high_open``: open ends).

    Examples
    --------
    >>> real_scalar(0.5, "eps", low=0, low_open=True)
    0.5
    >>> real_scalar(-1, "eps", low=0, low_open=True)
    Traceback (most recent call last):
    ...
    ValueError: eps: expected a finite real number > 0, found -1
    """
    if (isinstance(value, (bool, np.bool_, str, bytes))
            or not isinstance(value, (numbers.Real, np.ndarray))):
        raise TypeError(f"{name}: expected a real number, found {_describe(value)}")
    if isinstance(value, np.ndarray):
        if value.shape != () or not np.issubdtype(value.dtype, np.number) or np.iscomplexobj(value):
            raise TypeError(f"{name}: expected a real number, "
                            f"found an array of shape {value.shape}")
        value = value.item()
    bounds = []
    if low is not None:
        bounds.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        bounds.append(f"{'<' if high_open else '<='} {high:g}")
    want = "a finite real number" + (" " + " and ".join(bounds) if bounds else "")
    ok = np.isfinite(value)
    ok = ok and (low is None or (value > low if low_open else value >= low))
    ok = ok and (high is None or (value < high if high_open else value <= high))
    if not ok:
        raise ValueError(f"{name}: expected {want}, found {value!r}")
    return float(value)


def real_array(value, name: str, *, shape=None, ndim=None, finite=True) -> np.ndarray:
    """A real float array; ``shape`` may hold ``None`` for a free axis.

    Complex input is rejected (not truncated), as are strings and objects.

    Examples
    --------
    >>> real_array([[1, 2]], "C", shape=(1, None)).shape
    (1, 2)
    >>> real_array([1j], "A")
    Traceback (most recent call last):
    ...
    TypeError: A: expected a real array, found complex dtype complex128
    """
    try:
        array = np.asarray(value)
    except (ValueError, TypeError) as err:
        raise TypeError(f"{name}: expected a real array, found {_describe(value)}") from err
    if np.iscomplexobj(array):
        raise TypeError(f"{name}: expected a real array, found complex dtype {array.dtype}")
    if array.dtype == bool or not (np.issubdtype(array.dtype, np.integer)
                                   or np.issubdtype(array.dtype, np.floating)):
        raise TypeError(f"{name}: expected a real array, found dtype {array.dtype}")
    array = array.astype(float)
    if ndim is not None and array.ndim != ndim:
        raise ValueError(f"{name}: expected a {ndim}-dimensional array, found shape {array.shape}")
    if shape is not None:
        want = tuple(shape)
        if array.ndim != len(want) or any(w is not None and w != s
                                          for w, s in zip(want, array.shape)):
            entries = ", ".join("any" if w is None else str(w) for w in want)
            text = "(" + entries + ("," if len(want) == 1 else "") + ")"
            raise ValueError(f"{name}: expected shape {text}, found shape {array.shape}")
    if finite and not np.all(np.isfinite(array)):
        n_bad = int(np.size(array) - np.isfinite(array).sum())
        raise ValueError(f"{name}: expected finite entries, found {n_bad} non-finite")
    return array


def symmetric(array, name: str) -> np.ndarray:
    """A stack of symmetric matrices (last two axes), within a relative rounding tolerance.

    Examples
    --------
    >>> symmetric(np.array([[2.0, 1.0], [1.0, 3.0]]), "Q")
    array([[2., 1.],
           [1., 3.]])
    >>> symmetric(np.array([[2.0, 1.0], [0.0, 3.0]]), "Q")
    Traceback (most recent call last):
    ...
    ValueError: Q: expected a symmetric matrix, found asymmetry 1
    """
    asym = np.abs(array - np.swapaxes(array, -1, -2)).max(initial=0.0)
    if asym > SYMMETRY_RTOL * max(1.0, np.abs(array).max(initial=0.0)):
        raise ValueError(f"{name}: expected a symmetric matrix, found asymmetry {asym:.3g}")
    return 0.5 * (array + np.swapaxes(array, -1, -2))


def semidefinite(array, name: str, *, definite=False) -> np.ndarray:
    """A (stack of) symmetric positive semi-definite (``definite=True``: definite) matrices.

    Examples
    --------
    >>> semidefinite(np.eye(2), "Q")
    array([[1., 0.],
           [0., 1.]])
    >>> semidefinite(-np.eye(2), "Q")
    Traceback (most recent call last):
    ...
    ValueError: Q: expected a positive semi-definite matrix, found smallest eigenvalue -1
    """
    array = symmetric(array, name)
    if array.size == 0:
        return array
    lam = np.linalg.eigvalsh(array).min()
    scale = max(1.0, np.abs(array).max())
    if definite and lam <= 0:
        raise ValueError(f"{name}: expected a positive definite matrix, "
                         f"found smallest eigenvalue {lam:.3g}")
    if lam < -SYMMETRY_RTOL * scale:
        raise ValueError(f"{name}: expected a positive semi-definite matrix, found smallest "
                         f"eigenvalue {lam:.3g}")
    return array


def probability_vector(value, name: str, size: int | None = None) -> np.ndarray:
    """Probability weights: finite, non-negative, summing to one.

    Examples
    --------
    >>> probability_vector([0.25, 0.75], "mu")
    array([0.25, 0.75])
    >>> probability_vector([0.5, float("nan")], "mu")
    Traceback (most recent call last):
    ...
    ValueError: mu: expected finite entries, found 1 non-finite
    """
    p = real_array(value, name, shape=(size,))
    if p.size == 0:
        raise ValueError(f"{name}: expected at least one probability, found none")
    if np.any(p < 0):
        raise ValueError(f"{name}: expected non-negative probabilities, "
                         f"found minimum {p.min():.3g}")
    if abs(p.sum() - 1.0) > WEIGHT_ATOL:
        raise ValueError(f"{name}: expected probabilities summing to 1, found sum {p.sum():.10g}")
    return p


def generator(rng, name: str = "rng") -> np.random.Generator:
    """A seeded ``numpy.random.Generator`` (every random draw in asoc comes from one).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> generator(rng) is rng
    True
    >>> generator(1)
    Traceback (most recent call last):
    ...
    TypeError: rng: expected a numpy.random.Generator (np.random.default_rng(seed)), found int
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"{name}: expected a numpy.random.Generator (np.random.default_rng(seed)), "
                        f"found {type(rng).__name__}")
    return rng


# --- added for asoc.belief and asoc.gp -------------------------------------------------

def instance(value, types, name: str, what: str | None = None):
    """An object of one of ``types`` (e.g. the model or system argument).

    Examples
    --------
    >>> instance(3, int, "n")
    3
    >>> instance("a", (int, float), "n", "a number")
    Traceback (most recent call last):
    ...
    TypeError: n: expected a number, found str 'a'
    """
    if not isinstance(value, types):
        names = " or ".join(t.__name__ for t in (types if isinstance(types, tuple) else (types,)))
        raise TypeError(f"{name}: expected {what or 'a ' + names}, "
                        f"found {type(value).__name__} {_describe(value)}")
    return value


def function(value, name: str):
    """A callable (a model function, a density, a test function).

    Examples
    --------
    >>> function(abs, "g")(-2)
    2
    >>> function(1.0, "g")
    Traceback (most recent call last):
    ...
    TypeError: g: expected a callable, found float 1.0
    """
    if not callable(value):
        raise TypeError(f"{name}: expected a callable, "
                        f"found {type(value).__name__} {_describe(value)}")
    return value


def stochastic_matrix(value, name: str, size: int | None = None) -> np.ndarray:
    """A row-stochastic (transition) matrix: square, at least 1 x 1, rows are probability weights.

    Rows must sum to 1 within ``WEIGHT_ATOL``; the matrix is returned as given, not renormalised,
    and the library uses it as given everywhere (e.g. rho = p_11 rho(A)^2 for one mode), so that
    every result is that of the matrix the caller passed.

    Examples
    --------
    >>> stochastic_matrix([[0.9, 0.1], [0.2, 0.8]], "T").shape
    (2, 2)
    >>> stochastic_matrix(np.zeros((0, 0)), "T")
    Traceback (most recent call last):
    ...
    ValueError: T: expected a square (M, M) matrix with M >= 1, found shape (0, 0)
    """
    matrix = real_array(value, name, ndim=2)
    if matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ValueError(f"{name}: expected a square (M, M) matrix with M >= 1, "
                         f"found shape {matrix.shape}")
    if size is not None and matrix.shape[0] != size:
        raise ValueError(f"{name}: expected shape ({size}, {size}), found shape {matrix.shape}")
    for i, row in enumerate(matrix):
        if np.any(row < 0):
            raise ValueError(f"{name}: expected non-negative probabilities, "
                             f"found {row.min():.3g} in row {i}")
        if abs(row.sum() - 1.0) > WEIGHT_ATOL:
            raise ValueError(f"{name}: expected rows summing to 1, "
                             f"found sum {row.sum():.10g} in row {i}")
    return matrix


def choice(value, name: str, options) -> object:
    """One of a fixed set of options (strings, or other hashable values).

    Examples
    --------
    >>> choice("vec", "method", ("vec", "sdp"))
    'vec'
    >>> choice("lu", "method", ("vec", "sdp"))
    Traceback (most recent call last):
    ...
    ValueError: method: expected one of ('vec', 'sdp'), found 'lu'
    """
    try:
        ok = isinstance(value, collections.abc.Hashable) and value in options
    except (TypeError, ValueError):
        ok = False
    if isinstance(value, (bool, np.bool_)) and not any(option is value for option in options):
        ok = False                                       # True == 1, but True is not the option 1
    if not ok:
        raise ValueError(f"{name}: expected one of {tuple(options)}, found {_describe(value)}")
    return value


def boolean(value, name: str) -> bool:
    """A flag: ``True``/``False`` (or a NumPy bool); integers and strings are rejected.

    Examples
    --------
    >>> boolean(True, "warn")
    True
    >>> boolean("no", "warn")
    Traceback (most recent call last):
    ...
    TypeError: warn: expected True or False, found 'no'
    """
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, found {_describe(value)}")
    return bool(value)


def covariance(value, name: str, size: int | None = None, *, definite=False,
               scalar=False) -> np.ndarray:
    """A symmetric positive semi-definite (``definite=True``: definite) ``(size, size)`` matrix.

    ``scalar=True`` also accepts a number or a 1-element vector as a ``(1, 1)`` matrix.

    Examples
    --------
    >>> covariance(2.0, "var", scalar=True)
    array([[2.]])
    >>> covariance([[1.0, 0.0], [0.0, -1.0]], "cov0")
    Traceback (most recent call last):
    ...
    ValueError: cov0: expected a positive semi-definite matrix, found smallest eigenvalue -1
    """
    array = real_array(value, name)
    if scalar and array.ndim < 2 and array.size == 1:
        array = array.reshape(1, 1)
    want = "(n, n)" if size is None else f"({size}, {size})"
    if array.ndim != 2 or array.shape[0] != array.shape[1] or array.shape[0] == 0 \
            or (size is not None and array.shape[0] != size):
        raise ValueError(f"{name}: expected a square matrix of shape {want}, "
                         f"found shape {array.shape}")
    return semidefinite(array, name, definite=definite)


def vector(value, name: str, size: int | None = None) -> np.ndarray:
    """A non-empty finite real vector; a number is read as a 1-vector.

    Examples
    --------
    >>> vector(3, "mean0")
    array([3.])
    >>> vector([1.0, 2.0], "mean0", size=3)
    Traceback (most recent call last):
    ...
    ValueError: mean0: expected shape (3,), found shape (2,)
    """
    array = real_array(value, name)
    if array.ndim == 0:
        array = array.reshape(1)
    array = real_array(array, name, shape=(size,))
    if array.size == 0:
        raise ValueError(f"{name}: expected a non-empty vector, found shape {array.shape}")
    return array


def weights_or_equal(value, name: str, size: int) -> np.ndarray:
    """Probability weights of ``size`` components; ``None`` means equal weights.

    Examples
    --------
    >>> weights_or_equal(None, "wx", 4)
    array([0.25, 0.25, 0.25, 0.25])
    >>> weights_or_equal([0.5, float("nan")], "wx", 2)
    Traceback (most recent call last):
    ...
    ValueError: wx: expected finite entries, found 1 non-finite
    """
    if value is None:
        return np.full(size, 1.0 / size)
    return probability_vector(value, name, size)


def probability_rows(value, name: str, shape) -> np.ndarray:
    """A matrix of the given shape whose rows are probability weights.

    Examples
    --------
    >>> probability_rows([[0.5, 0.5], [1.0, 0.0]], "W", (2, 2)).sum(axis=1)
    array([1., 1.])
    >>> probability_rows([[0.5, 0.6]], "W", (1, 2))
    Traceback (most recent call last):
    ...
    ValueError: W: expected each row to sum to 1, found a sum 1.1
    """
    rows = real_array(value, name, shape=tuple(shape))
    if np.any(rows < 0):
        raise ValueError(f"{name}: expected non-negative probabilities, "
                         f"found minimum {rows.min():.3g}")
    sums = rows.sum(axis=-1)
    worst = np.argmax(np.abs(sums - 1.0)) if sums.size else None
    if worst is not None and abs(sums.flat[worst] - 1.0) > WEIGHT_ATOL:
        raise ValueError(f"{name}: expected each row to sum to 1, "
                         f"found a sum {sums.flat[worst]:.10g}")
    return rows
