"""The numerical evaluation of Sec. 2.6.4: test functions, inputs and error metrics."""

import numpy as np

MU_RANGE = (-5.0, 5.0)           #: range of the means, Sec. 2.6.4
VAR_RANGE = (0.1**2, 2.0**2)     #: range of the variances, Sec. 2.6.4


def v1(mu, var):
    r"""Quadratic function :math:`v_1(\mu, \sigma) = \mu^2 + \sigma^2 = \mathrm E\{x^2\}` (Sec. 2.6.4).

    Parameters
    ----------
    mu, var : array_like
        Mean and variance of the Gaussian input.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    return np.asarray(mu) ** 2 + np.asarray(var)


def v2(mu, var, a=0.1, b=4.0, c=0.1, d=-4.0):
    r"""Modified Rosenbrock function (Sec. 2.6.4) with :math:`x_1 = \mu`, :math:`x_2 = \sigma^2`.

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
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    mu, var = np.asarray(mu), np.asarray(var)
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
    mu, var : numpy.ndarray, (n,)

    Raises
    ------
    ValueError
        If ``rng`` is not a Generator or ``n`` < 2.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a seeded numpy.random.Generator, found {type(rng).__name__}")
    if int(n) < 2:
        raise ValueError(f"n: expected at least 2 training Gaussians, found {n}")
    return rng.uniform(*MU_RANGE, size=n), rng.uniform(*VAR_RANGE, size=n)


def test_grid(step: float = 0.1):
    """Uniform grid of test Gaussians with increment ``step`` in mean and variance (Sec. 2.6.4).

    Returns ``(mu_axis, var_axis)``: the means from -5 to 5 and the variances from 0.1^2
    upwards while <= 2^2 (with step 0.1: 101 x 40 = 4040 test Gaussians).

    Parameters
    ----------
    step : float
        Increment, > 0.

    Returns
    -------
    mu_axis, var_axis : numpy.ndarray

    Raises
    ------
    ValueError
        If ``step`` is not positive.
    """
    if not step > 0:
        raise ValueError(f"step: expected a positive increment, found {step!r}")
    mu = np.round(np.arange(MU_RANGE[0], MU_RANGE[1] + 1e-9, step), 10)
    var = np.round(np.arange(VAR_RANGE[0], VAR_RANGE[1] + 1e-9, step), 10)
    return mu, var


def error_metrics(prediction, truth) -> dict:
    """RMSE, maximum quadratic error, RMSE normalised by the range of ``truth``, and R^2.

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
    ValueError
        If the shapes differ.
    """
    p, t = np.asarray(prediction, float).ravel(), np.asarray(truth, float).ravel()
    if p.shape != t.shape:
        raise ValueError(f"prediction: expected shape {t.shape}, found {p.shape}")
    e2 = (p - t) ** 2
    rmse = float(np.sqrt(e2.mean()))
    return {"rmse": rmse, "max_sq_error": float(e2.max()), "nrmse": rmse / float(np.ptp(t)),
            "r2": float(1 - e2.sum() / np.sum((t - t.mean()) ** 2))}
