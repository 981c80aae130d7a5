"""``python -m asoc_companion.theorems``: run the theorems study from the command line.

Examples::

    python -m asoc_companion.theorems --instances 50 --mutants 20
    python -m asoc_companion.theorems --only statement_3_19 statement_3_26 --seed 2017
    python -m asoc_companion.theorems --scheduler tcp://host:8786 --output results.json
"""

import argparse
import sys
import time

from ..atomic_files import atomic_write_json
from .engine import run_study, verdict_text
from .report import mutant_text


def main(argv=None) -> int:
    """Run the theorems study with the arguments ``argv``; return the exit status.

    Parameters
    ----------
    argv : list of str, optional
        The command line after the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
    """
    parser = argparse.ArgumentParser(prog="python -m asoc_companion.theorems",
                                     description="Check the thesis's numbered statements on random "
                                                 "instances.")
    parser.add_argument("--instances", type=int, default=1000,
                        help="instances per statement (default 1000)")
    parser.add_argument("--expensive-instances", type=int, default=None,
                        help="instances for statements marked expensive (default: --instances / "
                             "10, at least 100)")
    parser.add_argument("--mutants", type=int, default=100,
                        help="instances of each statement's mutant (default 100; 0: none)")
    parser.add_argument("--seed", type=int, default=2017, help="study seed (default 2017)")
    parser.add_argument("--only", nargs="+", metavar="KEY",
                        help="statement keys, e.g. statement_3_19")
    parser.add_argument("--scheduler",
                        help="Dask scheduler address, e.g. tcp://host:8786 (default: local cores)")
    parser.add_argument("--jobs", type=int, default=-1,
                        help="local joblib workers (default: all cores)")
    parser.add_argument("--output", help="write the recorded results as JSON to this file")
    args = parser.parse_args(argv)
    if args.instances < 1:
        parser.error(f"--instances: expected an integer >= 1, found {args.instances}")
    expensive = args.expensive_instances or max(100, args.instances // 10)
    count = lambda st: min(expensive, args.instances) if st.expensive else args.instances
    start = time.perf_counter()
    if args.mutants < 0:
        parser.error(f"--mutants: expected an integer >= 0, found {args.mutants}")
    results = run_study(count, seed=args.seed, only=args.only, n_jobs=args.jobs,
                        scheduler=args.scheduler, mutants=args.mutants or None)
    recorded = {key: res.recorded_value() for key, res in results.items()}
    for key, value in recorded.items():
        print(f"{key:24s} {verdict_text(value):42s} mutant: {mutant_text(value):22s} failing: "
              f"{value['failing'][:8]}")
    print(f"{len(recorded)} statements in {time.perf_counter() - start:.1f} s")
    if args.output:
        atomic_write_json(args.output, recorded)
    return 0


if __name__ == "__main__":
    sys.exit(main())
