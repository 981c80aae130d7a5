"""``make bench``: time the project's performance targets and print them.

Each subpackage may provide ``bench.py`` with ``BENCHMARKS``: a list of
``(name, target_seconds, callable, repeat)``, and ``RATIOS``: a list of ``(name,
target_speedup, callable, repeat)`` whose callable returns (reference seconds, seconds) of
two computations timed alternately in the same process. The callable runs the timed work once and
returns the measured seconds (it may time a part of what it does, e.g. excluding
set-up). The median of ``repeat`` runs is printed next to the target; a missed target is
reported, not an error (timings depend on the machine's load).
"""

import importlib
import os
import platform
import statistics
import sys
import time

SUBPACKAGES = ("mjls", "belief", "gp")


def median_seconds(fn, repeat: int = 15) -> float:
    """Median wall time of ``repeat`` calls of ``fn()``."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(statistics.median(times))


def main(argv=None) -> int:
    import numpy as np

    only = (argv or sys.argv[1:]) or SUBPACKAGES
    print(f"machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}, NumPy {np.__version__}")
    failed = 0
    for sub in only:
        try:
            module = importlib.import_module(f"asoc.{sub}.bench")
        except ModuleNotFoundError:
            continue
        for name, target, fn, repeat in module.BENCHMARKS:
            times = [fn() for _ in range(repeat)]
            t = statistics.median(times)
            ok = t <= target
            failed += not ok
            print(f"[{sub}] {name:60s} {t:9.4f} s  (target {target:g} s, median of {repeat})"
                  f"  {'ok' if ok else 'SLOWER THAN TARGET'}", flush=True)
        for name, target, fn, repeat in getattr(module, "RATIOS", []):
            ref, fast = (statistics.median(ts) for ts in zip(*(fn() for _ in range(repeat))))
            ok = ref >= target * fast
            failed += not ok
            print(f"[{sub}] {name:60s} {ref / fast:9.1f} x  ({ref:.4f} s / {fast:.4f} s, target "
                  f">= {target:g} x, median of {repeat})  {'ok' if ok else 'BELOW TARGET'}", flush=True)
    print(f"{failed} target(s) missed" if failed else "all targets met")
    return 0


if __name__ == "__main__":
    sys.exit(main())
