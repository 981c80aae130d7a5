"""Statistics for Monte Carlo results: medians with bootstrap confidence intervals."""

import numpy as np


def bootstrap_ci(samples, rng: np.random.Generator, statistic=np.median, n_boot: int = 1000,
                 level: float = 0.95, chunk: int = 50):
    """Percentile bootstrap interval of ``statistic`` (Efron & Tibshirani, 1993, ch. 13).

    Parameters
    ----------
    samples : array_like, shape (N,)
    rng : numpy.random.Generator
        Source of the resampling indices (seeded by the caller).
    statistic : callable taking ``axis=``; default ``np.median``.
    n_boot : number of bootstrap resamples.
    level : confidence level in (0, 1).

    Returns
    -------
    dict with ``value`` (statistic of the samples), ``ci`` ([low, high]) and ``n``.
    """
    x = np.asarray(samples, dtype=float).ravel()
    if x.size == 0:
        raise ValueError("samples: need at least one sample, found none")
    if not np.all(np.isfinite(x)):
        raise ValueError("samples: found non-finite entries")
    if not 0 < level < 1:
        raise ValueError(f"level must lie in (0, 1), found {level}")
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
