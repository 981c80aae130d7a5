"""The qualitative claims of Secs. 2.6 and 3.2-3.7 as predicates with planted false variants.

The notebooks decide a claim by calling the predicate here; :func:`ledger_mutants` feeds each
predicate its planted false variant (a controller that does not settle, a quadratic cost, a
feasible LMI, a reversed ordering, ...) and records whether the check catches it, i.e. returns
``holds = False``. A check that cannot fail separates nothing.

Thresholds:

* "approximately N iterations" read off a figure: the author's counts are round numbers (15, five),
  so the window is N +- 2.5 (the multiples of five that round to N); a trace counts as settled
  when it stays inside a band of 1, 2, 5 or 10 % of its total change (what looks flat in a plot),
  and the claim holds if one of these bands gives a settling iteration inside the window;
* "not quadratic": the residual of the best quadratic fit must exceed ten times the larger of the
  rounding floor (the residual of the fitted quadratic itself, fitted again) and the quadrature
  error (the relative RMS difference of the costs at two node counts): a quadratic cost computed
  with that quadrature error cannot pass;
* "almost equal to [163] in steady state and only slightly worse in the transient" (Sec. 3.5.4): the
  words are calibrated by the thesis's own Table 3.2: "almost equal" is a relative difference no
  larger than the largest printed one at x_0 = 0, "slightly worse" a positive relative excess no
  larger than the largest printed one at x_0 = [3 0]; our ratios are taken with the ends of the
  two bootstrap intervals, so the verdict does not rest on the medians alone.
"""

import numpy as np

from asoc.mjls import ms_spectral_radius
from asoc.mjls.intractability import hessian_min_eigenvalue, quadratic_fit_residual
from asoc.stats import settling_iteration
from asoc.validation import real_array, real_scalar

__all__ = ["BANDS", "ROUNDING", "settles_about", "relative_rms_difference", "not_quadratic",
           "not_convex", "converged_not_stabilizing", "non_increasing", "bounded", "lmi_separates",
           "ordered", "almost_equal_then_slightly_worse", "mean_square_unstable", "diverges",
           "matches", "resembles"]


BANDS = (0.01, 0.02, 0.05, 0.1)
ROUNDING = 2.5  # half the spacing of the round counts (multiples of five)


def settles_about(traces, about):
    """Whether the traces settle after "approximately ``about``" iterations (module docstring).

    Returns
    -------
    dict
        ``holds``, ``value`` (the settling iteration of the 2 % band), ``by_band`` and ``window``.

    Examples
    --------
    >>> fast = 1 + 0.7 ** np.arange(80)            # within 1-10 % after 6-13 iterations
    >>> settles_about(fast, 15)["holds"], settles_about(1 + 0.97 ** np.arange(400), 15)["holds"]
    (True, False)
    """
    by_band = {band: settling_iteration(traces, band) for band in BANDS}
    low, high = about - ROUNDING, about + ROUNDING
    return {
        "holds": any(low <= n <= high for n in by_band.values()),
        "value": by_band[0.02],
        "by_band": [by_band[b] for b in BANDS],
        "window": [low, high],
    }


def relative_rms_difference(a, b) -> float:
    """sqrt(mean((a - b)^2) / mean(a^2)): e.g. the quadrature error of costs at two node counts.

    Examples
    --------
    >>> round(relative_rms_difference(np.array([1.0, -1.0]), np.array([1.1, -1.1])), 12)
    0.1
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.sqrt(np.mean((a - b) ** 2) / np.mean(a**2)))


def not_quadratic(X, U, costs, quadrature_error):
    """Whether the costs on the grid are not quadratic: the fit residual exceeds ten times the
    rounding and quadrature floor (module docstring).

    Parameters
    ----------
    X, U, costs : numpy.ndarray
        The grid and the costs on it.
    quadrature_error : float
        Relative RMS error of the costs (:func:`relative_rms_difference` of two node counts).

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-5, 5, 21), np.linspace(-5, 5, 21), indexing="ij")
    >>> quadratic = 1 + X**2 + X * U + 2 * U**2
    >>> not_quadratic(X, U, quadratic * (1 + 1e-9 * np.cos(X)), 1e-9)["holds"]
    False
    >>> not_quadratic(X, U, quadratic + np.cos(X), 1e-9)["holds"]
    True
    """
    residual = quadratic_fit_residual(X, U, costs)
    x, u = X.ravel(), U.ravel()
    basis = np.stack([np.ones_like(x), x, u, x * x, x * u, u * u], axis=1)
    fitted = (basis @ np.linalg.lstsq(basis, costs.ravel(), rcond=None)[0]).reshape(X.shape)
    rounding = quadratic_fit_residual(X, U, fitted)
    threshold = 10 * max(rounding, quadrature_error, np.finfo(float).eps)
    return {"holds": bool(residual > threshold), "value": residual, "threshold": threshold}


def not_convex(J, X, U):
    """Whether J(x, u) is not convex on the grid: a Hessian eigenvalue (central differences) is < 0.

    Examples
    --------
    >>> X, U = np.meshgrid(np.linspace(-1, 1, 11), np.linspace(-1, 1, 11), indexing="ij")
    >>> saddle, bowl = (lambda x, u: x**2 - u**2), (lambda x, u: x**2 + u**2)
    >>> not_convex(saddle, X, U)["holds"], not_convex(bowl, X, U)["holds"]
    (True, False)
    """
    lam, where = hessian_min_eigenvalue(J, X, U)
    return {"holds": bool(lam < 0), "value": lam, "where": where}


def converged_not_stabilizing(result):
    """Whether Alg. 3.1 converged to a gain that does not stabilise (its result object)."""
    return {"holds": bool(result.converged and not result.stabilizing), "value": result.rho}


def non_increasing(values, rtol=1e-8):
    """Whether no value exceeds its predecessor by more than ``rtol`` (relative, rounding).

    Examples
    --------
    >>> non_increasing([3.0, 2.0, 2.0, 1.0])["holds"], non_increasing([3.0, 2.0, 2.1])["holds"]
    (True, False)
    """
    values = np.asarray(values, dtype=float)
    rises = np.diff(values) / np.abs(values[:-1])
    return {"holds": bool(np.all(rises <= rtol)), "value": float(rises.max(initial=0.0))}


def bounded(costs, bounds, rtol=1e-7):
    """Whether every exact cost is at most its bound (relative rounding ``rtol``).

    Examples
    --------
    >>> bounded([1.0, 2.0], [1.0, 2.5])["holds"], bounded([2.0], [1.75])["holds"]
    (True, False)
    """
    verdicts = [bool(c <= b * (1 + rtol)) for c, b in zip(costs, bounds)]
    return {"holds": all(verdicts), "value": verdicts}


def lmi_separates(infeasible_case, feasible_case):
    """Whether the LMI check separates: infeasible for the printed outputs and feasible for a
    case where it must be (state feedback, C = I). Arguments: ``LMIResult`` objects.
    """
    return {
        "holds": bool(not infeasible_case.feasible and feasible_case.feasible),
        "value": f"{infeasible_case.solver_status}; state feedback: {feasible_case.solver_status}",
    }


def ordered(lower, upper):
    """Whether ``lower[i] <= upper[i]`` for every scenario i (medians of two controllers).

    Examples
    --------
    >>> ordered([1.0, 2.0], [1.5, 2.0])["holds"], ordered([1.0, 2.5], [1.5, 2.0])["holds"]
    (True, False)
    """
    verdicts = [bool(a <= b) for a, b in zip(lower, upper)]
    return {"holds": all(verdicts), "value": verdicts}


def _ratio_interval(proposed, reference):
    """The ratio proposed / reference with the ends of the two 95 % intervals."""
    return proposed["ci"][0] / reference["ci"][1], proposed["ci"][1] / reference["ci"][0]


def almost_equal_then_slightly_worse(steady, transient, printed_steady, printed_transient):
    """Sec. 3.5.4's claim against [163], calibrated by the printed table (module docstring).

    Parameters
    ----------
    steady, transient : list of (proposed, reference) pairs of Monte Carlo records
        ``{"value", "ci"}``, one pair per transition matrix, at x_0 = 0 and x_0 = [3 0].
    printed_steady, printed_transient : list of (proposed, reference) printed medians.

    Examples
    --------
    The printed Table 3.2 satisfies its own claim; swapping the two controllers does not:

    >>> rec = lambda v: {"value": v, "ci": [v, v]}
    >>> steady = [(1.5623, 1.5611), (1.0539, 1.0351)]
    >>> transient = [(28.3532, 26.5108), (30.7562, 30.606)]
    >>> as_records = lambda pairs: [(rec(a), rec(b)) for a, b in pairs]
    >>> records = as_records(steady), as_records(transient)
    >>> almost_equal_then_slightly_worse(*records, steady, transient)["holds"]
    True
    >>> swapped = lambda pairs: [(b, a) for a, b in pairs]
    >>> almost_equal_then_slightly_worse(as_records(steady), as_records(swapped(transient)), steady,
    ...                                  transient)["holds"]
    False
    """
    almost = max(abs(a / b - 1) for a, b in printed_steady)
    slightly = max(a / b - 1 for a, b in printed_transient)
    steady_ratios = [_ratio_interval(p, r) for p, r in steady]
    transient_ratios = [_ratio_interval(p, r) for p, r in transient]
    holds = all(1 - almost <= lo and hi <= 1 + almost for lo, hi in steady_ratios) and all(
        lo > 1 and hi <= 1 + slightly for lo, hi in transient_ratios
    )
    return {
        "holds": bool(holds),
        "value": [
            [float(p["value"] / r["value"]) for p, r in pairs] for pairs in (steady, transient)
        ],
        "almost_equal": almost,
        "slightly_worse": slightly,
    }


def mean_square_unstable(A, T):
    """Whether the autonomous MJLS (A, T) is mean-square unstable: rho of Cor. 3.2 above 1.

    Returns
    -------
    dict
        ``holds`` and ``value`` (the mean-square spectral radius).

    Examples
    --------
    >>> A = np.array([[[2.0]], [[0.5]]])
    >>> mean_square_unstable(A, np.full((2, 2), 0.5))["holds"]
    True
    >>> mean_square_unstable(A / 4, np.full((2, 2), 0.5))["holds"]
    False
    """
    rho = float(ms_spectral_radius(A, T))
    return {"holds": rho > 1, "value": rho}


def diverges(final_states, x0, factor=10.0):
    """Whether trajectories diverge: the mean of ||x_K||^2 over runs exceeds ``factor`` ||x_0||^2.

    Parameters
    ----------
    final_states : array_like, (runs, n)
        x_K of each run.
    x0 : array_like, (n,)
        The common initial state.
    factor : float
        The growth of the second moment that counts as divergence.

    Returns
    -------
    dict
        ``holds`` and ``value`` (the growth E||x_K||^2 / ||x_0||^2).

    Examples
    --------
    >>> diverges([[30.0, 0.0], [0.0, 40.0]], [1.0, 0.0])["holds"]
    True
    >>> diverges([[0.1, 0.0], [0.0, 0.2]], [1.0, 0.0])["holds"]
    False
    """
    final_states = real_array(final_states, "final_states", ndim=2)
    x0 = real_array(x0, "x0", shape=(final_states.shape[1],))
    factor = real_scalar(factor, "factor", low=0, low_open=True)
    if not np.any(x0):
        raise ValueError("x0: expected a non-zero initial state (the growth is relative to it)")
    growth = float(np.mean(np.sum(final_states**2, axis=1)) / np.sum(x0**2))
    return {"holds": growth > factor, "value": growth}


def matches(value, reference, rtol=1e-4):
    """Whether ``value`` equals ``reference`` (e.g. a closed form and the quadrature of its
    definition) to the relative tolerance ``rtol``.

    Returns
    -------
    dict
        ``holds`` and ``value`` (the relative difference ``|value / reference - 1|``).

    Examples
    --------
    >>> matches(1.00001, 1.0)["holds"], matches(1.001, 1.0)["holds"]
    (True, False)
    >>> matches(1.0, 0.0)
    Traceback (most recent call last):
    ...
    ValueError: reference: expected a non-zero reference (the difference is relative)
    """
    value, reference = real_scalar(value, "value"), real_scalar(reference, "reference")
    rtol = real_scalar(rtol, "rtol", low=0, low_open=True)
    if reference == 0:
        raise ValueError("reference: expected a non-zero reference (the difference is relative)")
    relative = abs(value / reference - 1.0)
    return {"holds": relative < rtol, "value": relative}


def resembles(samples, truth, threshold=0.5):
    """Whether function samples follow a true function: the median over samples of their RMS
    deviation from it is at most ``threshold``.

    Parameters
    ----------
    samples : array_like, (S, N)
        S function samples on N points.
    truth : array_like, (N,)
        The true function on the same points.
    threshold : float
        The largest median RMS deviation that counts as resembling.

    Returns
    -------
    dict
        ``holds`` and ``value`` (the median RMS deviation).

    Examples
    --------
    >>> x = np.linspace(-2, 2, 41)
    >>> resembles([np.sin(x) + 0.1, np.sin(x) - 0.2], np.sin(x))["holds"]
    True
    >>> resembles([np.sin(x) + 1.0], np.sin(x))["holds"]
    False
    """
    truth = real_array(truth, "truth", ndim=1)
    samples = real_array(np.atleast_2d(samples), "samples", shape=(None, len(truth)))
    threshold = real_scalar(threshold, "threshold", low=0, low_open=True)
    deviation = float(np.median(np.sqrt(np.mean((samples - truth) ** 2, axis=1))))
    return {"holds": deviation <= threshold, "value": deviation}
