"""The benchmark suite (``make bench``: ``pytest tests/benchmarks --benchmark-only``).

pytest-benchmark times each benchmark in this one process. A benchmark states its target
in ``benchmark.extra_info["target_s"]`` (seconds, compared with the median); an in-process
ratio (reference seconds / our seconds, both timed alternately by
:func:`asoc_companion.timing.alternating_medians`) goes to ``extra_info["ratio"]`` with
its target in ``extra_info["target_ratio"]``. At the end of the session a table lists each
benchmark's median against its target and each ratio against its target. A missed target
is reported, not an error: timings depend on the machine and its load.
"""

import os
import platform

import pytest

RESULTS = []


@pytest.fixture(autouse=True)
def _collect_result(request):
    if "benchmark" not in request.fixturenames:
        yield
        return
    bench = request.getfixturevalue("benchmark")
    yield
    stats = getattr(bench, "stats", None)
    median = stats.stats.median if stats is not None else None
    RESULTS.append((request.node.nodeid.split("::", 1)[-1], median, dict(bench.extra_info)))


def targets_table(results) -> list:
    """Lines of the summary: median vs ``target_s``, ratio vs ``target_ratio``; a missed target is
    marked."""
    lines, missed = [], 0
    width = max([len(name) for name, _, _ in results] + [20])
    for name, median, info in results:
        if "target_s" in info and median is not None:
            ok = median <= info["target_s"]
            missed += not ok
            lines.append(
                f"{name:{width}}  {median:10.4f} s   target <= {info['target_s']:g} s   "
                f"{'ok' if ok else 'SLOWER THAN TARGET'}"
            )
        if "ratio" in info and "target_ratio" in info:
            ok = info["ratio"] >= info["target_ratio"]
            missed += not ok
            lines.append(
                f"{name:{width}}  {info['ratio']:10.1f} x   target >= "
                f"{info['target_ratio']:g} x   "
                f"{'ok' if ok else 'BELOW TARGET'}"
            )
    lines.append(f"{missed} target(s) missed" if missed else "all targets met")
    return lines


def pytest_terminal_summary(terminalreporter):
    if not RESULTS:
        return
    import numpy as np

    terminalreporter.section(
        "targets (median of the rounds; ratios measured alternately in this process)"
    )
    terminalreporter.write_line(
        f"machine: {os.cpu_count()} cores, "
        f"{platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}, NumPy {np.__version__}"
    )
    for line in targets_table(RESULTS):
        terminalreporter.write_line(line)
