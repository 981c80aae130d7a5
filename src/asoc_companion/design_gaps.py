"""What Algs. 3.2 and 3.3 cost a user: the gap to the exact-cost designs (the findings page).

Alg. 3.2 returns a fixed point of (3.45)-(3.49), the stationarity conditions of the approximate
Hamiltonian (A.7); Alg. 3.3 minimises the expansion (B.4) step by step with the safeguard on
(3.65). Neither minimises the exact cost. On seeded random small systems this module measures
the relative gap (J_alg - J_exact) / J_exact between the exact cost of the algorithm's controller
and that of the library's exact-cost design started from it (BFGS on (3.42), L-BFGS on (3.56)),
which is never worse than its start, so the gap is >= 0 up to the optimiser's tolerance.
"""

import numpy as np

from asoc.mjls import (
    dynamic_output_feedback,
    exact_dynamic_output_feedback,
    exact_finite_horizon_dynamic_output_feedback,
    finite_horizon_dynamic_output_feedback,
)
from asoc.progress import progress_bar

from .theorems.instances import draw_system, random_spd_stack

__all__ = ["design_gaps", "quantiles"]


def _draw(rng):
    """A small system with two modes (M = 1 is plain LQG, where Alg. 3.2 is optimal)."""
    while True:
        sys = draw_system(rng, max_states=2, max_modes=2)
        if sys.M == 2:
            return sys


def _infinite_horizon_gap(rng):
    """Relative gap of Alg. 3.2's controller to the exact-cost design started from it (None if Alg.
    3.2 does not converge to a stabilising controller).

    Examples
    --------
    The exact-cost design improves on Alg. 3.2 by a small fraction; on the second system Alg. 3.2
    diverges (the closed loop's rho is about 5), so there is no gap to report:

    >>> gap = _infinite_horizon_gap(np.random.default_rng(0))
    >>> 0 <= gap < 0.01, _infinite_horizon_gap(np.random.default_rng(1))
    (True, None)
    """
    sys = _draw(rng)
    run = dynamic_output_feedback(sys, max_iter=3000, warn=False)
    if not (run.converged and run.stabilizing):
        return None
    best = exact_dynamic_output_feedback(sys, init=(run.F, run.K, run.L), max_iter=500, warn=False)
    return float((run.cost - best.cost) / best.cost)


def _finite_horizon_gap(rng, horizon=20):
    """Relative gap of Alg. 3.3's controller (random mixture x_0) to the exact-cost design from it.

    Examples
    --------
    >>> gap = _finite_horizon_gap(np.random.default_rng(0), horizon=5)
    >>> 0 <= gap < 0.01
    True
    """
    sys = _draw(rng)
    mu0 = rng.dirichlet(np.ones(sys.M))
    mean0, cov0 = rng.standard_normal((sys.M, sys.nx)), random_spd_stack(rng, sys.M, sys.nx, 0.2)
    kwargs = dict(horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0, warn=False)
    run = finite_horizon_dynamic_output_feedback(sys, max_iter=300, **kwargs)
    best = exact_finite_horizon_dynamic_output_feedback(sys, init=(run.F, run.K, run.L),
                                                        max_iter=1000, **kwargs)
    return float((run.cost - best.cost) / best.cost)


def design_gaps(seed_sequence, n_systems, horizon=20, progress=False):
    """Relative gaps of Alg. 3.2 and Alg. 3.3 on ``n_systems`` seeded systems (one child each).

    Returns ``{"alg_3_2": [...], "alg_3_3": [...], "alg_3_2_not_applicable": int}``.

    Examples
    --------
    >>> gaps = design_gaps(np.random.SeedSequence(3), 2, horizon=5)
    >>> len(gaps["alg_3_3"]), min(gaps["alg_3_3"]) > -1e-6
    (2, True)
    """
    if not isinstance(seed_sequence, np.random.SeedSequence):
        raise TypeError("seed_sequence: expected a numpy.random.SeedSequence, found "
                        f"{type(seed_sequence).__name__}")
    if isinstance(n_systems, bool) or not isinstance(n_systems, (int, np.integer)) or n_systems < 1:
        raise ValueError(f"n_systems: expected a positive integer, found {n_systems!r}")
    infinite, finite = seed_sequence.spawn(2)
    bar = progress_bar(total=2 * n_systems, enabled=progress, desc="design gaps", unit="system")
    gaps_32 = []
    for child in infinite.spawn(n_systems):
        gaps_32.append(_infinite_horizon_gap(np.random.default_rng(child)))
        bar.update()
    gaps_33 = []
    for child in finite.spawn(n_systems):
        gaps_33.append(_finite_horizon_gap(np.random.default_rng(child), horizon))
        bar.update()
    bar.close()
    return {"alg_3_2": [g for g in gaps_32 if g is not None], "alg_3_3": gaps_33,
            "alg_3_2_not_applicable": sum(g is None for g in gaps_32)}


def quantiles(gaps, probabilities=(0.0, 0.25, 0.5, 0.75, 0.9, 1.0)):
    """The gaps' quantiles (min, quartiles, 90 %, max).

    Examples
    --------
    >>> quantiles([0.0, 0.1, 0.2, 0.3, 0.4])
    [0.0, 0.1, 0.2, 0.3, 0.36, 0.4]
    """
    return [float(q) for q in np.quantile(np.asarray(gaps), probabilities)]
