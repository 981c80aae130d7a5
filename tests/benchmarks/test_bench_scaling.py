"""Scaling targets of issues 17 and 26: the Chapter 3 algorithms at up to 100 states and 100 modes.

Run: ``PYTHONPATH=$PWD/src .venv/bin/python -m pytest tests/benchmarks/test_bench_scaling.py
--benchmark-only -p no:cacheprovider``. Each benchmark puts its target in
``extra_info["target_s"]`` (seconds) or, for a speed-up measured in one process,
``extra_info["ratio"]`` and ``extra_info["target_ratio"]``. A missed target is reported, not
asserted: timings depend on the machine and its load. The systems come from
:func:`asoc_companion.scaling.scaling_system` (mode matrices of spectral norm 0.95,
Dirichlet rows of T) with fixed seeds. Every benchmark runs its algorithm to the documented
stopping rule; a per-iteration figure says so in its name.
"""

import time
import tracemalloc

import numpy as np
import pytest

from asoc.mjls import (
    StaticGain,
    dynamic_output_feedback,
    exact_dynamic_output_feedback,
    exact_static_output_feedback,
    ms_spectral_radius,
    simulate,
    static_output_feedback,
)
from asoc.mjls.moment_operator import ms_operator
from asoc.mjls.stability import mean_square_stability
from asoc_companion.scaling import published_size_system, scaling_system
from asoc_companion.timing import fitted_exponent, time_call


def system(n, M):
    """The benchmark system with n states and M modes (seed n * 100 + M)."""
    return scaling_system(np.random.default_rng(n * 100 + M), n, M)


def test_ms_spectral_radius_ratio_n16_m4(benchmark):
    """n = 16, M = 4: matrix-free rho at least 20x faster than the dense operator (one process)."""
    s = system(16, 4)
    dense_s, rho_dense = time_call(
        lambda: float(np.max(np.abs(np.linalg.eigvals(ms_operator(s.A, s.T))))), 3
    )
    rho = benchmark.pedantic(lambda: ms_spectral_radius(s.A, s.T), rounds=10, iterations=1)
    free_s = benchmark.stats.stats.min
    assert rho == pytest.approx(rho_dense, rel=1e-10)
    benchmark.extra_info.update(ratio=dense_s / free_s, target_ratio=20.0, dense_s=dense_s)


def test_ms_spectral_radius_n64_m8(benchmark):
    """n = 64, M = 8: rho under 1 s (the dense matrix would need 8.6 GB)."""
    s = system(64, 8)
    rho = benchmark.pedantic(lambda: ms_spectral_radius(s.A, s.T), rounds=3, iterations=1)
    assert 0 < rho < 0.95**2
    assert rho == pytest.approx(
        mean_square_stability(s.A, s.T, method="power", check=False).rho, rel=1e-8
    )
    benchmark.extra_info.update(target_s=1.0, rho=rho)


def test_alg31_exact_n64_m8(benchmark):
    """n = 64, M = 8: Alg. 3.1 with moments="exact" under 10 s."""
    s = system(64, 8)
    r = benchmark.pedantic(
        lambda: static_output_feedback(s, moments="exact"), rounds=1, iterations=1
    )
    assert r.converged and r.stabilizing
    benchmark.extra_info.update(target_s=10.0, iterations=r.iterations)


def test_alg32_n32_m8(benchmark):
    """n = 32, M = 8: Alg. 3.2 to its stopping rule under 20 s.

    On this family Alg. 3.2 does not converge: its bounds wander (the ill-posed (3.51), see
    :mod:`asoc.mjls.dynamic`), and the run stops with status "no_progress". One iteration
    solves (3.51), n^2 + 2 n ny = 1280 unknowns, matrix-free by conjugate gradients."""
    s = system(32, 8)
    r = benchmark.pedantic(lambda: dynamic_output_feedback(s, warn=False), rounds=1, iterations=1)
    benchmark.extra_info.update(target_s=20.0, iterations=r.iterations, status=r.status)


@pytest.mark.parametrize("n, M, target", [(16, 4, 2.0), (32, 8, 20.0), (32, 16, 60.0)])
def test_exact_dynamic_output_feedback(benchmark, n, M, target):
    """exact_dynamic_output_feedback from its default start (a bounded Alg. 3.2 run or the
    averaged LQG compensator) to convergence: 2 s at n = 16, M = 4; 20 s at n = 32, M = 8;
    60 s at n = 32, M = 16 (64 augmented states, M n^2 = 65,536 at M = 16)."""
    s = system(n, M)
    r = benchmark.pedantic(lambda: exact_dynamic_output_feedback(s), rounds=1, iterations=1)
    assert r.converged and r.stabilizing
    benchmark.extra_info.update(target_s=target, iterations=r.iterations)


@pytest.fixture(scope="module")
def published():
    """n = 100, M = 100, nu = ny = 12, open-loop rho 0.99 (the largest MJLS in public code we
    found)."""
    return published_size_system(np.random.default_rng(26))


def test_alg31_n100_m100(benchmark, published):
    """n = 100, M = 100: Alg. 3.1 (moments="auto") to its stopping rule under 4 s (issue 33)."""
    r = benchmark.pedantic(
        lambda: static_output_feedback(published, warn=False), rounds=1, iterations=1
    )
    benchmark.extra_info.update(target_s=4.0, iterations=r.iterations, status=r.status)


def test_exact_static_design_n100_m100(benchmark, published):
    """n = 100, M = 100: exact_static_output_feedback from Alg. 3.1's converged gain (given, not
    timed) and the averaged LQ gain, to a stationary point."""
    alg31 = static_output_feedback(published, warn=False)
    r = benchmark.pedantic(
        lambda: exact_static_output_feedback(published, alg31=alg31, warn=False),
        rounds=1,
        iterations=1,
    )
    benchmark.extra_info.update(target_s=30.0, iterations=r.iterations, status=r.status)


def test_ms_spectral_radius_n100_m100(benchmark, published):
    """n = 100, M = 100: rho of the open loop under 10 s (M n^2 = 1e6)."""
    rho = benchmark.pedantic(
        lambda: ms_spectral_radius(published.A, published.T), rounds=1, iterations=1
    )
    assert rho == pytest.approx(0.99, rel=1e-8)
    benchmark.extra_info.update(target_s=10.0)


def _monte_carlo_within_30_s_and_4_gb(benchmark, s, runs):
    """``runs`` x 100 steps of ``s`` under the zero gain, timed once, its peak memory traced by
    tracemalloc."""
    gain = StaticGain(np.zeros((s.nu, s.ny)))

    def run():
        tracemalloc.start()
        out = simulate(s, gain, np.zeros(s.nx), 100, runs, np.random.default_rng(0))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return out, peak

    r, peak = benchmark.pedantic(run, rounds=1, iterations=1)
    assert r.cost.shape == (runs,) and np.all(np.isfinite(r.cost))
    assert peak < 4e9
    benchmark.extra_info.update(target_s=30.0, peak_gb=peak / 1e9, target_gb=4.0)


def test_monte_carlo_n100_m100(benchmark, published):
    """n = 100, M = 100: 1,000 runs x 100 steps under 30 s and 4 GB."""
    _monte_carlo_within_30_s_and_4_gb(benchmark, published, 1000)


def test_monte_carlo_n64_m8(benchmark):
    """n = 64, M = 8: 1e4 runs x 100 steps under 30 s and 4 GB."""
    _monte_carlo_within_30_s_and_4_gb(benchmark, system(64, 8), 10_000)


def test_exponent_ms_spectral_radius_m8(benchmark):
    """Fitted exponent of the matrix-free rho's time against n = 8..64 at M = 8 (target <= 3)."""
    sizes = (8, 16, 32, 64)
    systems = {n: system(n, 8) for n in sizes}

    def run():
        return [
            time_call(
                lambda s=systems[n]: (
                    mean_square_stability(s.A, s.T, method="arnoldi", check=False).rho
                ),
                3,
            )[0]
            for n in sizes
        ]

    seconds = benchmark.pedantic(run, rounds=1, iterations=1)
    benchmark.extra_info.update(
        exponent=fitted_exponent(sizes, seconds),
        target_exponent=3.0,
        seconds=dict(zip(map(str, sizes), seconds)),
    )


def test_exponent_alg31_exact_per_iteration_m4(benchmark):
    """Fitted exponent of Alg. 3.1's time per iteration (moments="exact") against n = 16..64 at M =
    4 (target <= 3).

    Per iteration: the number of iterations depends on the system, not on the method; from
    n = 16 on, both phases run matrix-free (at n = 8, M n^2 = 256 is on the dense side)."""
    sizes = (16, 32, 64)
    systems = {n: system(n, 4) for n in sizes}

    def run():
        out = []
        for n in sizes:
            start = time.perf_counter()
            r = static_output_feedback(systems[n], moments="exact")
            out.append((time.perf_counter() - start) / r.iterations)
        return out

    seconds = benchmark.pedantic(run, rounds=1, iterations=1)
    benchmark.extra_info.update(
        exponent=fitted_exponent(sizes, seconds),
        target_exponent=3.0,
        seconds=dict(zip(map(str, sizes), seconds)),
    )
