"""The numerical evaluation of Sec. 2.6.4: test functions, inputs and error metrics."""

import numpy as np

from .. import validation as check

__all__ = ["MU_RANGE", "VAR_RANGE", "GRID_STEP_RANGE", "quadratic_function", "modified_rosenbrock",
           "training_gaussians", "evaluation_grid", "error_metrics"]


MU_RANGE = (-5.0, 5.0)           #: range of the means, Sec. 2.6.4
VAR_RANGE = (0.1**2, 2.0**2)     #: range of the variances, Sec. 2.6.4
GRID_STEP_RANGE = (1e-3, 10.0)   #: the steps of the test grid one can ask for (Sec. 2.6.4 uses 0.1)


def quadratic_function(mu, var):
    r"""Quadratic test function (Sec. 2.6.4) :math:`v_1(\mu, \sigma) = \mu^2 + \sigma^2`.

    :math:`v_1 = \mathrm E\{x^2\}` for :math:`x \sim \mathcal N(\mu, \sigma^2)`.

    Parameters
    ----------
    mu, var : array_like
        Mean and variance of the Gaussian input.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``mu`` or ``var`` is not finite and real, their shapes do not broadcast, or a
        variance is negative.

    Examples
    --------
    >>> quadratic_function([0.0, 2.0], [1.0, 0.5]).tolist()
    [1.0, 4.5]
    """
    mu, var = _inputs(mu, var)
    return mu ** 2 + var


def _inputs(mu, var):
    mu, var = check.real_array(mu, "mu"), check.real_array(var, "var")
    if np.any(var < 0):
        raise ValueError(f"var: expected non-negative variances, found minimum {var.min():.3g}")
    try:
        np.broadcast_shapes(mu.shape, var.shape)
    except ValueError:
        raise ValueError(f"mu, var: expected broadcastable shapes, found {mu.shape} and "
                         f"{var.shape}") from None
    return mu, var


def modified_rosenbrock(mu, var, a=0.1, b=4.0, c=0.1, d=-4.0):
    r"""Modified Rosenbrock test function :math:`v_2` (Sec. 2.6.4), x_1 = mu, x_2 = sigma^2.

    :math:`v_2(\mu, \sigma) = a(\mu + b)^2 + c(\mu^2 - \sigma^2 + d)^2 = 0.1(\mu + 4)^2 +
    0.1(\mu^2 - \sigma^2 - 4)^2`. The thesis lists :math:`b = 0.4` but its final formula
    uses :math:`\mu + 4`; we follow the final formula (the one that is evaluated).

    Parameters
    ----------
    mu, var : array_like
        Mean and variance of the Gaussian input.
    a, b, c, d : float
        Coefficients.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError, TypeError
        If ``mu`` or ``var`` is not finite and real, their shapes do not broadcast, a variance
        is negative, or a coefficient is not a finite number.

    Examples
    --------
    >>> modified_rosenbrock([-4.0, 0.0], [0.0, 1.0]).round(4).tolist()
    [14.4, 4.1]
    """
    mu, var = _inputs(mu, var)
    named = ((a, "a"), (b, "b"), (c, "c"), (d, "d"))
    a, b, c, d = (check.real_scalar(value, name) for value, name in named)
    return a * (mu + b) ** 2 + c * (mu**2 - var + d) ** 2


def training_gaussians(n: int, rng: np.random.Generator):
    """``n`` means uniform in [-5, 5] and variances uniform in [0.1^2, 2^2] (Fig. 2.8).

    Parameters
    ----------
    n : int
        Number of Gaussians, >= 2.
    rng : numpy.random.Generator

    Returns
    -------
    mu : numpy.ndarray, (n,)
        The means.
    var : numpy.ndarray, (n,)
        The variances.

    Raises
    ------
    ValueError, TypeError
        If ``rng`` is not a Generator or ``n`` is not an integer >= 2.

    Examples
    --------
    >>> mu, var = training_gaussians(3, np.random.default_rng(0))
    >>> mu.round(3).tolist(), var.round(3).tolist()
    ([1.37, -2.302, -4.59], [0.076, 3.255, 3.652])
    """
    rng = check.generator(rng)
    n = check.integer(n, "n", minimum=2)
    return rng.uniform(*MU_RANGE, size=n), rng.uniform(*VAR_RANGE, size=n)


def evaluation_grid(step: float = 0.1):
    """Uniform grid of the test Gaussians of Sec. 2.6.4, increment ``step`` in mean and variance.

    Returns ``(mu_axis, var_axis)``: the means from -5 to 5 and the variances from 0.1^2
    upwards while <= 2^2 (with step 0.1: 101 x 40 = 4040 test Gaussians).

    Parameters
    ----------
    step : float
        Increment, > 0.

    Returns
    -------
    mu_axis : numpy.ndarray
        The means.
    var_axis : numpy.ndarray
        The variances.

    Raises
    ------
    ValueError, TypeError
        If ``step`` is not a finite number in [1e-3, 10].

    Examples
    --------
    >>> mu, var = evaluation_grid(0.5)
    >>> len(mu), len(var), mu[:3].tolist(), var[:2].tolist()
    (21, 8, [-5.0, -4.5, -4.0], [0.01, 0.51])
    """
    step = check.real_scalar(step, "step", low=GRID_STEP_RANGE[0], high=GRID_STEP_RANGE[1])
    mu = np.round(np.arange(MU_RANGE[0], MU_RANGE[1] + 1e-9, step), 10)
    var = np.round(np.arange(VAR_RANGE[0], VAR_RANGE[1] + 1e-9, step), 10)
    return mu, var


def error_metrics(prediction, truth) -> dict:
    """Error metrics of Sec. 2.6.4: RMSE, max quadratic error, range-normalised RMSE, R^2.

    Parameters
    ----------
    prediction, truth : array_like
        Same shape.

    Returns
    -------
    dict
        ``rmse``, ``max_sq_error``, ``nrmse`` and ``r2``.

    Raises
    ------
    ValueError, TypeError
        If the arrays are not finite and real, their shapes differ, or ``truth`` is constant
        (no range to normalise by).

    Examples
    --------
    >>> m = error_metrics([1.0, 2.0, 2.0], [1.0, 2.0, 3.0])
    >>> round(m["rmse"], 4), m["max_sq_error"], round(m["nrmse"], 4), m["r2"]
    (0.5774, 1.0, 0.2887, 0.5)
    """
    t = check.real_array(truth, "truth").ravel()
    p = check.real_array(prediction, "prediction").ravel()
    if p.shape != t.shape:
        raise ValueError(f"prediction: expected {t.size} values (as truth), found {p.size}")
    if t.size == 0 or not np.ptp(t) > 0:
        raise ValueError(f"truth: expected values with a positive range, found range "
                         f"{np.ptp(t) if t.size else 'of no values'}")
    e2 = (p - t) ** 2
    rmse = float(np.sqrt(e2.mean()))
    return {"rmse": rmse, "max_sq_error": float(e2.max()), "nrmse": rmse / float(np.ptp(t)),
            "r2": float(1 - e2.sum() / np.sum((t - t.mean()) ** 2))}
