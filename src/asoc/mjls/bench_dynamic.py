"""Performance targets of Secs. 3.6-3.7 (merged into ``make bench`` by asoc.mjls.bench).

Each entry is (name, target seconds, callable returning the measured seconds, repeats).
"""

import time

import numpy as np

from .dynamic import dynamic_output_feedback
from .finite_horizon import finite_horizon_dynamic_output_feedback
from .simulate import DynamicOutputFeedback, simulate
from .examples import SEC373_COV0, SEC373_MEAN0, SEC373_MU0, sec373_system


def example_system():
    """The MJLS of Sec. 3.7.3 with T[1]."""
    return sec373_system(1)


MEAN0, COV0, MU0 = SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0


def _timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def bench_alg32():
    sys = example_system()
    return _timed(lambda: dynamic_output_feedback(sys))


def bench_alg33():
    sys = example_system()
    init = dynamic_output_feedback(sys)          # set-up, not timed
    return _timed(lambda: finite_horizon_dynamic_output_feedback(sys, 100, MEAN0, COV0, MU0, init=init))


def bench_monte_carlo():
    sys = example_system()
    r = dynamic_output_feedback(sys)
    controller = DynamicOutputFeedback(r.F, r.K, r.L, xhat0=MEAN0[0])
    rng = np.random.default_rng(0)
    return _timed(lambda: simulate(sys, controller, MEAN0, 100, 100_000, rng, mu0=MU0, x0_cov=COV0))


BENCHMARKS_DYNAMIC = [
    ("Alg. 3.2 on the Sec. 3.7.3 example (T[1])", 0.05, bench_alg32, 5),
    ("Alg. 3.3, horizon 100 (T[1], xi_0[1])", 2.0, bench_alg33, 3),
    ("Monte Carlo of a dynamic controller, 1e5 runs x 100 steps", 2.0, bench_monte_carlo, 3),
]
