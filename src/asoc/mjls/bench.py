"""Performance targets of Chapter 3 (``make bench``): Alg. 3.1, Monte Carlo, Table 3.2, [163].

Each entry is (name, target seconds, callable returning the measured seconds, repeats);
the targets of Secs. 3.6-3.7 come from :mod:`asoc.mjls.bench_dynamic`.
"""

import time

import numpy as np

from .baselines import time_variant_feedback
from .bench_dynamic import BENCHMARKS_DYNAMIC
from .comparison import median_costs, table_3_2_designs
from .examples import SEC354_X0, sec354_system
from .simulate import StaticGain, simulate
from .static import static_output_feedback


def _timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def bench_alg31(T):
    sys = sec354_system(T)
    return lambda: _timed(lambda: static_output_feedback(sys))


def bench_monte_carlo():
    sys = sec354_system(1)
    controller = StaticGain(static_output_feedback(sys).L)
    return _timed(lambda: simulate(sys, controller, SEC354_X0[2], 100, 100_000, np.random.default_rng(0)))


def bench_163(T):
    sys = sec354_system(T)
    return lambda: _timed(lambda: time_variant_feedback(sys, 100, SEC354_X0[2]))


def bench_table_3_2():
    """All 24 cells of Table 3.2 at full fidelity: designs (incl. baselines) and 1e5 runs each."""
    def run():
        for t in (1, 2):
            for xi in (1, 2):
                designs = table_3_2_designs(t, SEC354_X0[xi], 100)
                median_costs(designs, SEC354_X0[xi], 100, 100_000, 0)
    return _timed(run)


BENCHMARKS = [
    ("Alg. 3.1, Sec. 3.5.4 output feedback, T[1] (per gain)", 0.005, bench_alg31(1), 21),
    ("Alg. 3.1, Sec. 3.5.4 output feedback, T[2] (per gain)", 0.005, bench_alg31(2), 21),
    ("Monte Carlo, 1e5 runs x 100 steps, one static controller", 1.0, bench_monte_carlo, 3),
    ("[163] variational method, T[1], x0 = [3 0], K = 100", 10.0, bench_163(1), 3),
    ("[163] variational method, T[2], x0 = [3 0], K = 100", 10.0, bench_163(2), 3),
    ("Table 3.2 at full fidelity (24 cells x 1e5 runs, all baselines)", 120.0, bench_table_3_2, 1),
] + BENCHMARKS_DYNAMIC
