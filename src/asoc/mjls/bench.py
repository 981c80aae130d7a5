"""Performance targets of Chapter 3 (``make bench``): Alg. 3.1, Monte Carlo, Table 3.2, [163].

Each entry of BENCHMARKS is (name, target seconds, callable returning the measured seconds,
repeats); the targets of Secs. 3.6-3.7 come from :mod:`asoc.mjls.bench_dynamic`. Each entry
of RATIOS is (name, target speed-up, callable returning (reference seconds, seconds), repeats):
the two are timed alternately in the same process.
"""

import time

import numpy as np

from .baselines import time_variant_feedback
from .bench_dynamic import BENCHMARKS_DYNAMIC
from .comparison import median_costs, table_3_2_designs
from .examples import SEC354_X0, sec354_system
from .simulate import StaticGain, simulate
from .stability import closed_loop
from .static import gain_from_moments, static_output_feedback
from .system import predecessor_sum, successor_average


def _timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def bench_alg31(T, moments="step"):
    sys = sec354_system(T)
    return lambda: _timed(lambda: static_output_feedback(sys, moments=moments))


def thesis_iteration(sys, tol=1e-10, max_iter=20000, init=1e-4):
    """Alg. 3.1 as printed, in plain NumPy: X^i = P^i = init I; L from (3.34); one step of
    each recursion (3.35); stop when L changes by less than tol (relative). Returns L."""
    X = np.broadcast_to(init * np.eye(sys.nx), (sys.M, sys.nx, sys.nx)).copy()
    P = X.copy()
    muHHt = sys.mu_inf[:, None, None] * (sys.H @ np.swapaxes(sys.H, 1, 2))
    L = np.zeros((sys.nu, sys.ny))
    for _ in range(max_iter):
        L_new = gain_from_moments(sys, X, P)
        Acl = closed_loop(sys, L_new)
        LC = L_new @ sys.C
        X, P = (predecessor_sum(sys.T, Acl @ X @ np.swapaxes(Acl, 1, 2) + muHHt),
                sys.Q + np.swapaxes(LC, 1, 2) @ sys.R @ LC + np.swapaxes(Acl, 1, 2) @ successor_average(sys.T, P) @ Acl)
        done = np.linalg.norm(L_new - L) <= tol * np.linalg.norm(L_new)
        L = L_new
        if done:
            break
    return L


def ratio_alg31(T, moments):
    """(seconds of the plain thesis iteration, seconds of static_output_feedback(moments=...))."""
    sys = sec354_system(T)
    return lambda: (_timed(lambda: thesis_iteration(sys)),
                    _timed(lambda: static_output_feedback(sys, moments=moments)))


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


RATIOS = [
    ("Alg. 3.1 T[1]: plain thesis iteration / moments='step'", 0.5, ratio_alg31(1, "step"), 21),
    ("Alg. 3.1 T[1]: plain thesis iteration / moments='exact'", 0.5, ratio_alg31(1, "exact"), 21),
    ("Alg. 3.1 T[2]: plain thesis iteration / moments='step'", 0.5, ratio_alg31(2, "step"), 21),
    ("Alg. 3.1 T[2]: plain thesis iteration / moments='exact'", 5.0, ratio_alg31(2, "exact"), 21),
]

BENCHMARKS = [
    ("Alg. 3.1, Sec. 3.5.4 output feedback, T[1] (per gain)", 0.005, bench_alg31(1), 21),
    ("Alg. 3.1, Sec. 3.5.4 output feedback, T[2] (per gain)", 0.005, bench_alg31(2), 21),
    ("Alg. 3.1, moments='exact', T[1] (per gain)", 0.005, bench_alg31(1, "exact"), 21),
    ("Alg. 3.1, moments='exact', T[2] (per gain)", 0.005, bench_alg31(2, "exact"), 21),
    ("Monte Carlo, 1e5 runs x 100 steps, one static controller", 1.0, bench_monte_carlo, 3),
    ("[163] variational method, T[1], x0 = [3 0], K = 100", 10.0, bench_163(1), 3),
    ("[163] variational method, T[2], x0 = [3 0], K = 100", 10.0, bench_163(2), 3),
    ("Table 3.2 at full fidelity (24 cells x 1e5 runs, all baselines)", 120.0, bench_table_3_2, 1),
] + BENCHMARKS_DYNAMIC
