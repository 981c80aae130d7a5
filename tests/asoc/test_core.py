"""The core modules shared by the subpackages: asoc.optimize, asoc.result, asoc.threads,
asoc.progress, asoc.stats, asoc.linalg and asoc.setting_checks (beside their doctests)."""

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from asoc import config
from asoc.linalg import bicgstab, pack, relative_change, unpack
from asoc.optimize import bfgs
from asoc.progress import progress_bar
from asoc.result import STATUS_CODES, IterativeResult
from asoc.setting_checks import INT, REAL, SIZES
from asoc.stats import bootstrap_ci, bootstrap_median_ci
from asoc.threads import (
    concurrently,
    in_parts,
    parts,
    single_threaded,
    stacked_in_parts,
    worker_count,
)


def rosenbrock(z):
    x, y = z
    f = (1 - x) ** 2 + 100 * (y - x**2) ** 2
    return float(f), np.array([-2 * (1 - x) - 400 * x * (y - x**2), 200 * (y - x**2)])


@pytest.mark.parametrize("memory", [None, 5])
def test_bfgs_finds_the_rosenbrock_minimum(memory):
    result = bfgs(rosenbrock, [-1.2, 1.0], tol=1e-14, max_iter=500, memory=memory)
    assert result.status == "converged"
    np.testing.assert_allclose(result.z, [1.0, 1.0], atol=1e-5)
    assert np.all(np.diff(result.history) <= 1e-12 * np.abs(result.history[:-1]))  # descent


def test_bfgs_stops_at_the_domain_and_names_bad_input():
    def outside_unit_disc(z):  # f = inf outside the domain
        return (np.inf, z) if z @ z >= 1 else (float(-z[0]), np.array([-1.0, 0.0]))

    result = bfgs(outside_unit_disc, [0.0, 0.0], max_iter=200)
    assert result.z @ result.z < 1 and result.f < -0.9
    with pytest.raises((ValueError, TypeError), match="z0"):
        bfgs(rosenbrock, "start")
    with pytest.raises((ValueError, TypeError), match="tol"):
        bfgs(rosenbrock, [0.0, 0.0], tol=-1.0)


def test_a_result_status_must_agree_with_converged():
    assert set(STATUS_CODES) >= {"converged", "max_iterations", "cycle", "no_progress"}
    with pytest.raises(ValueError, match="contradicts"):
        IterativeResult(converged=True, status="max_iterations", message="")
    with pytest.raises(ValueError, match="status"):
        IterativeResult(converged=False, status="tired", message="")


def test_single_threaded_limits_blas_and_restores_it():
    before = {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    with single_threaded():
        assert {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"} == {1}
    assert {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"} == before


def test_progress_bar_passes_its_items_through():
    assert list(progress_bar(range(5), enabled=False)) == [0, 1, 2, 3, 4]


def test_bootstrap_intervals_cover_the_median_and_are_reproducible():
    samples = np.random.default_rng(0).standard_normal(400)
    low, high = bootstrap_ci(samples, np.random.default_rng(1))["ci"]
    assert [low, high] == list(bootstrap_ci(samples, np.random.default_rng(1))["ci"])
    assert low < np.median(samples) < high and high - low < 0.5
    exact_low, exact_high = bootstrap_median_ci(samples)["ci"]
    assert exact_low < np.median(samples) < exact_high
    assert abs(exact_low - low) < 0.05 and abs(exact_high - high) < 0.05


def test_relative_change_uses_the_configured_floor():
    assert relative_change(np.zeros(2), np.zeros(2)) == 0.0
    assert relative_change(np.zeros(2), np.full(2, 1e-13), floor=1.0) == pytest.approx(
        np.sqrt(2) * 1e-13
    )
    with config.option_context(**{"linalg.norm_floor": 1e-3}):
        assert relative_change(np.zeros(1), np.full(1, 1e-4)) == pytest.approx(0.1)
    parts = [np.arange(6.0).reshape(2, 3), np.ones((1, 2))]
    for a, b in zip(unpack(pack(*parts), [p.shape for p in parts]), parts):
        np.testing.assert_array_equal(a, b)


def test_setting_checks_state_what_they_accept():
    assert str(REAL(0, 1)) == "a real number in (0, 1)"
    assert str(INT(1)) == "an integer >= 1" and "tuple" in str(SIZES(2))
    with pytest.raises(ValueError, match="k: expected a real number in"):
        REAL(0, 1).check("k", 1.0)
    with pytest.raises(TypeError, match="k: expected an integer"):
        INT(0).check("k", 1.5)


def _blas_threads():
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


@pytest.mark.skipif(worker_count() < 2, reason="needs two cores for two BLAS threads")
def test_single_threaded_contexts_overlapping_on_threads_restore_blas_once_all_closed():
    with threadpool_limits(limits=2, user_api="blas"):  # else a restore to one thread is unseen
        _overlapping_contexts()


def _overlapping_contexts():
    before = _threads_by_library()
    assert 2 in before.values()  # a library whose restore to two threads would show
    inner_open, outer_closed = threading.Event(), threading.Event()

    def inner():
        with single_threaded():
            inner_open.set()
            outer_closed.wait(5)
            return _blas_threads()

    worker = ThreadPoolExecutor(1).submit(inner)
    inner_open.wait(5)
    with single_threaded():
        pass  # closes first: the other thread's context is still open
    still_limited = _blas_threads()
    outer_closed.set()
    assert still_limited == {1} and worker.result() == {1}
    assert _threads_by_library() == before


def _threads_by_library():
    return {lib["filepath"]: lib["num_threads"] for lib in threadpool_info()
            if lib["user_api"] == "blas"}


def test_concurrently_keeps_order_per_call_settings_and_raises_a_calls_error():
    @config.accepts_settings("mjls.rank_rtol")
    def both():
        return concurrently(lambda: config.defaults["mjls.rank_rtol"],
                            lambda: config.defaults["mjls.rank_rtol"],
                            lambda: threading.current_thread().name)

    first, second, _ = both(rank_rtol=1e-3)
    assert (first, second) == (1e-3, 1e-3)   # the caller's per-call value, on every thread
    before = _blas_threads()

    def fails():
        raise ValueError("from a worker")

    with pytest.raises(ValueError, match="from a worker"):
        concurrently(lambda: 1, fails)
    assert _blas_threads() == before


def test_nested_concurrently_takes_a_free_worker_or_runs_in_line_and_never_deadlocks():
    """Nested calls at every depth, many times over: the results in order, and no wait on a
    queued call (a deadlock would hang the test). A nested call made once the other call has
    finished runs on its worker."""
    def nested(k, depth):
        if depth == 0:
            return k
        return concurrently(lambda: nested(k, depth - 1), lambda: nested(-k, depth - 1))

    for _ in range(50):
        assert concurrently(lambda: nested(1, 2), lambda: nested(2, 2), lambda: nested(3, 1)) == [
            [[1, -1], [-1, 1]], [[2, -2], [-2, 2]], [3, -3]]
    if worker_count() > 1:
        finished = threading.Event()

        def after_the_other():
            finished.wait(5)
            for _ in range(200):                 # until the worker is released after its call
                names = concurrently(*[lambda: threading.current_thread().name] * 2)
                if len(set(names)) == 2:
                    return names
                time.sleep(0.01)
            return names

        names, _ = concurrently(after_the_other, finished.set)
        assert len(set(names)) == 2
    x = np.zeros(7)
    in_parts(lambda part: x.__setitem__(part, np.arange(7)[part]), 7)
    assert x.tolist() == list(range(7)) and sum(len(range(7)[p]) for p in parts(7)) == 7


def test_bicgstab_solves_a_nonsymmetric_system_to_its_tolerance_in_kept_vectors():
    """A well-conditioned non-symmetric K of size 400: the true residual meets rtol (to a factor
    10 for the drift of the recursively updated one), the right-hand side 0 gives x = 0 at once,
    and a limit of one iteration stops after one."""
    rng = np.random.default_rng(5)
    K = np.eye(400) + 0.3 * rng.standard_normal((400, 400)) / np.sqrt(400)
    b = rng.standard_normal(400)
    calls = []

    def apply(x, out):
        calls.append(out)
        np.matmul(K, x, out=out)

    x, iterations = bicgstab(apply, b, np.zeros(400), 1e-10, 100)
    assert np.linalg.norm(K @ x - b) <= 10 * 1e-10 * np.linalg.norm(b)
    assert 1 <= iterations < 100 and len({id(out) for out in calls}) <= 3
    zero, none = bicgstab(apply, np.zeros(400), np.ones(400), 1e-10, 100)
    assert none == 0 and not zero.any()
    _, one = bicgstab(apply, b, np.zeros(400), 1e-14, 1)
    assert one == 1
    for bad, name in (((1.0, b, b, 1e-10, 5), "apply"), ((apply, b, b, 0.0, 5), "rtol"),
                      ((apply, b, b[:3], 1e-10, 5), "x0"), ((apply, b, b, 1e-10, -1), "max_iter")):
        with pytest.raises((TypeError, ValueError), match=f"^{name}: expected"):
            bicgstab(*bad)


def test_stacked_in_parts_joins_the_parts_and_names_stacks_of_different_lengths():
    X = np.arange(24.0).reshape(6, 2, 2)
    np.testing.assert_array_equal(stacked_in_parts(lambda S: S.sum(axis=(1, 2)), X),
                                  X.sum(axis=(1, 2)))
    with pytest.raises(ValueError, match="^stacks: expected"):
        stacked_in_parts(lambda S, P: S, X, X[:2])
