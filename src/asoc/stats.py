"""Statistics for Monte Carlo results: medians with bootstrap confidence intervals."""

import numpy as np

__all__ = ["bootstrap_ci", "bootstrap_median_ci", "settling_iteration", "VERDICTS", "decide_claim"]


def _check_samples(samples, level):
    """The samples as a flat float array; ValueError on empty/non-finite samples or a bad level."""
    x = np.asarray(samples, dtype=float).ravel()
    if x.size == 0:
        raise ValueError("samples: need at least one sample, found none")
    if not np.all(np.isfinite(x)):
        raise ValueError("samples: found non-finite entries")
    if not 0 < level < 1:
        raise ValueError(f"level must lie in (0, 1), found {level}")
    return x


def bootstrap_ci(samples, rng: np.random.Generator, statistic=np.median, n_boot: int = 1000,
                 level: float = 0.95, chunk: int = 50):
    """Percentile bootstrap interval of ``statistic`` (Efron & Tibshirani, 1993, ch. 13).

    Parameters
    ----------
    samples : array_like, shape (N,)
    rng : numpy.random.Generator
        Source of the resampling indices (seeded by the caller).
    statistic : callable
        Taking ``axis=``; default ``np.median``.
    n_boot : int
        Number of bootstrap resamples.
    level : float
        Confidence level in (0, 1).
    chunk : int
        Resamples drawn at once (bounds the memory, not the result).

    Returns
    -------
    dict
        ``value`` (statistic of the samples), ``ci`` ([low, high]) and ``n``.

    Raises
    ------
    ValueError
        If the samples are empty or non-finite, ``level`` is outside (0, 1) or ``rng`` is not
        a Generator.

    Examples
    --------
    >>> ci = bootstrap_ci(np.arange(1.0, 10.0), np.random.default_rng(0), n_boot=200, level=0.9)
    >>> ci["value"], ci["n"], [round(c, 9) for c in ci["ci"]]
    (5.0, 9, [3.0, 7.0])
    """
    x = _check_samples(samples, level)
    if not isinstance(rng, np.random.Generator):
        raise ValueError("rng: pass a seeded numpy.random.Generator")
    stats = []
    for start in range(0, n_boot, chunk):
        size = min(chunk, n_boot - start)
        idx = rng.integers(0, x.size, size=(size, x.size))
        stats.append(statistic(x[idx], axis=1))
    stats = np.concatenate(stats)
    alpha = (1 - level) / 2
    lo, hi = np.quantile(stats, [alpha, 1 - alpha])
    return {"value": float(statistic(x)), "ci": [float(lo), float(hi)], "n": int(x.size)}


def bootstrap_median_ci(samples, level: float = 0.95):
    """Exact percentile-bootstrap interval of the median, without resampling.

    The bootstrap median (lower median X*_(m), m = ceil(n/2), of a resample of size n) is
    an order statistic X_(j) of the sorted sample with P(X*_(m) <= X_(j)) = P(Bin(n, j/n)
    >= m) (Efron, "The Jackknife, the Bootstrap and Other Resampling Plans", 1982, Sec.
    10.7; Maritz & Jarrett, JASA 1978). The interval is read off this distribution exactly,
    so it needs no random numbers and is what infinitely many resamples would give.

    Parameters
    ----------
    samples : array_like, (N,)
    level : float
        Confidence level in (0, 1).

    Returns
    -------
    dict
        ``value`` (the sample median), ``ci`` ([low, high]) and ``n``.

    Raises
    ------
    ValueError
        If the samples are empty or non-finite, or ``level`` is outside (0, 1).

    Examples
    --------
    >>> bootstrap_median_ci([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    {'value': 5.0, 'ci': [2.0, 8.0], 'n': 9}
    """
    from scipy.stats import binom

    x = np.sort(_check_samples(samples, level))
    n = x.size
    m = (n + 1) // 2
    half = int(12 * np.sqrt(n)) + 2                   # the distribution lives within m +- 6 sd
    j = np.arange(max(1, m - half), min(n, m + half) + 1)
    cdf = binom.sf(m - 1, n, j / n)
    alpha = (1 - level) / 2
    lo = x[j[min(np.searchsorted(cdf, alpha), j.size - 1)] - 1]
    hi = x[j[min(np.searchsorted(cdf, 1 - alpha), j.size - 1)] - 1]
    return {"value": float(np.median(x)), "ci": [float(lo), float(hi)], "n": int(n)}


def settling_iteration(series, band: float = 0.02) -> int:
    """First index after which every series stays within ``band`` of its total change.

    The classical settling time (e.g. 2% band) applied to iteration histories: for each
    series s_0..s_N with final value s_N, the band is ``band * max|s_eta - s_N|``. This
    turns "converges after about N iterations", read off a plot, into a number that does
    not depend on the series' scale.

    Parameters
    ----------
    series : array_like, (N+1,) or (n_series, N+1)
    band : float
        Relative band in (0, 1).

    Returns
    -------
    int

    Raises
    ------
    ValueError
        If ``series`` is empty or non-finite, or ``band`` is outside (0, 1).

    Examples
    --------
    The series falls from 10 towards 1; the 2% band is 0.02 * 9 = 0.18 around the final value,
    entered for good at index 3:

    >>> settling_iteration([10.0, 5.0, 2.0, 1.01, 1.0, 1.0])
    3
    """
    s = np.atleast_2d(np.asarray(series, dtype=float))
    if s.shape[1] < 1 or not np.all(np.isfinite(s)):
        raise ValueError("series: need finite values, at least one per series")
    if not 0 < band < 1:
        raise ValueError(f"band must lie in (0, 1), found {band}")
    dev = np.abs(s - s[:, -1:])
    ok = np.all(dev <= band * dev.max(axis=1, keepdims=True), axis=0)
    bad = np.flatnonzero(~ok)
    return int(bad[-1] + 1) if bad.size else 0


#: Verdicts of :func:`decide_claim`, the vocabulary the ledger reads (asoc_companion.evidence).
VERDICTS = ("holds", "fails", "not resolved")


def decide_claim(samples, above=None, below=None, level: float = 0.95,
                 what: str = "samples") -> dict:
    """Decide a claim "above < median < below" from paired samples by a bootstrap interval.

    The claim is about the median of ``samples`` (e.g. paired differences of two methods over
    seeds, one per seed). Its exact percentile-bootstrap interval (:func:`bootstrap_median_ci`)
    decides: ``"holds"`` if the interval lies inside (``above``, ``below``), ``"fails"`` if
    it lies entirely outside, and ``"not resolved"`` if it straddles a bound: the data cannot
    tell the two apart at this confidence, which is a status of its own, not a deviation.

    Parameters
    ----------
    samples : array_like, (n,)
        One finite value per seed (n >= 1).
    above, below : float, optional
        The claimed bounds of the median (at least one).
    level : float
        Confidence level in (0, 1).
    what : str
        What the samples are, for the ``test`` sentence.

    Returns
    -------
    dict
        ``verdict``, ``n``, ``estimate`` (the median), ``ci_low``, ``ci_high``, ``test``, and
        the evidence it was decided on: ``above``, ``below``, ``level`` and ``samples`` (a
        list), so the decision can be repeated on the record alone.

    Raises
    ------
    ValueError
        If no bound is given, ``above >= below``, the samples are empty or non-finite, or
        ``level`` is outside (0, 1).

    Examples
    --------
    A clearly negative difference holds "below 0"; a zero-mean one is not resolved:

    >>> rng = np.random.default_rng(0)
    >>> decide_claim(-1.0 + 0.1 * rng.standard_normal(30), below=0.0)["verdict"]
    'holds'
    >>> decide_claim(rng.standard_normal(30), below=0.0)["verdict"]
    'not resolved'
    >>> decide_claim([1.2, 1.5, 1.1, 1.4, 1.3, 1.6, 1.2, 1.3, 1.5], above=0.0, below=1.0)["verdict"]
    'fails'
    """
    if above is None and below is None:
        raise ValueError("above, below: give at least one bound of the claimed median")
    lo_bound = -np.inf if above is None else float(above)
    hi_bound = np.inf if below is None else float(below)
    if not lo_bound < hi_bound:
        raise ValueError(f"above must be smaller than below, found above={above}, below={below}")
    ci = bootstrap_median_ci(samples, level)
    low, high = ci["ci"]
    if lo_bound < low and high < hi_bound:
        verdict = "holds"
    elif high < lo_bound or low > hi_bound:
        verdict = "fails"
    else:
        verdict = "not resolved"
    bounds = " and ".join(text for text in (None if above is None else f"> {above:g}",
                                             None if below is None else f"< {below:g}") if text)
    test = (f"claim: median of the {what} {bounds}; exact percentile-bootstrap {level:.0%} "
            f"interval of the median over n = {ci['n']}: inside holds, outside fails, "
            "straddling not resolved")
    if low == high and np.ptp(np.asarray(samples, dtype=float)) == 0:
        test += (f"; all {ci['n']} samples are equal, so the quantity does not vary between them "
                 f"and the verdict is exact, not statistical")
    return {"verdict": verdict, "n": ci["n"], "estimate": ci["value"], "ci_low": float(low),
            "ci_high": float(high), "test": test, "above": None if above is None else lo_bound,
            "below": None if below is None else hi_bound, "level": float(level),
            "samples": np.asarray(samples, dtype=float).ravel().tolist()}
