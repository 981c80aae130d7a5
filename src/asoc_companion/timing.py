"""The one timing helper of the companion: median wall time, two computations timed alternately, and
the smallest wall or CPU time of a call.

Used by the notebooks that print run times (Sec. 3.5) and by the benchmark suite
(``tests/benchmarks``, ``make bench``) for in-process ratios; single computations there are
timed by pytest-benchmark itself.
"""

import statistics
import time

import numpy as np

__all__ = ["median_seconds", "alternating_medians", "time_call", "fitted_exponent"]


def median_seconds(fn, repeat: int = 15) -> float:
    """Median wall time of ``repeat`` calls of ``fn()``.

    Parameters
    ----------
    fn : callable
        Called without arguments.
    repeat : int
        Number of calls, at least 1.

    Returns
    -------
    float
        Seconds.

    Raises
    ------
    ValueError
        If ``repeat`` is not a positive integer.

    Examples
    --------
    >>> median_seconds(lambda: sum(range(10)), repeat=3) >= 0
    True
    """
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ValueError(f"repeat must be a positive integer, found {repeat!r}")
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(statistics.median(times))


def alternating_medians(reference, candidate, repeat: int = 15) -> tuple[float, float]:
    """Median wall times of ``reference()`` and ``candidate()``, called alternately in this process.

    Alternating keeps a change of the machine's load from favouring one of the two, so
    their ratio is a fair speed-up.

    Returns
    -------
    (float, float)
        Seconds of the reference, seconds of the candidate.

    Examples
    --------
    >>> ref, cand = alternating_medians(lambda: sum(range(1000)), lambda: None, repeat=3)
    >>> ref >= 0 and cand >= 0
    True
    """
    pairs = [(median_seconds(reference, 1), median_seconds(candidate, 1)) for _ in range(repeat)]
    return (float(statistics.median(p[0] for p in pairs)),
            float(statistics.median(p[1] for p in pairs)))


def time_call(fn, repeat=1, clock=time.perf_counter):
    """The smallest time of ``repeat`` calls of ``fn()`` (seconds) and the last result.

    ``clock`` is wall time by default; ``time.process_time`` (this process's CPU time, over all
    its threads) is not inflated by other processes sharing the cores, e.g. the other notebook
    of a parallel build.

    Examples
    --------
    >>> seconds, result = time_call(lambda: sum(range(1000)), 2, clock=time.process_time)
    >>> seconds >= 0, result
    (True, 499500)
    >>> time_call(print, clock=1.0)
    Traceback (most recent call last):
    ...
    TypeError: clock: expected a function returning seconds, e.g. time.process_time, found 1.0
    """
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ValueError(f"repeat: expected a positive integer, found {repeat!r}")
    if not callable(clock):
        raise TypeError("clock: expected a function returning seconds, e.g. time.process_time, "
                        f"found {clock!r}")
    best, out = np.inf, None
    for _ in range(repeat):
        start = clock()
        out = fn()
        best = min(best, clock() - start)
    return best, out


def fitted_exponent(sizes, seconds):
    """Slope of log(seconds) against log(sizes) by least squares: time ~ size^exponent.

    Examples
    --------
    >>> round(fitted_exponent([2, 4, 8], [1.0, 8.0, 64.0]), 12)
    3.0
    """
    x, y = np.log(np.asarray(sizes, float)), np.log(np.asarray(seconds, float))
    return float(np.polyfit(x, y, 1)[0])
