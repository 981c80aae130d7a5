"""Performance of the companion's tooling: the manifest check that `make book` runs on every
call (import analysis of every notebook), and the timing helper's own overhead."""

from asoc_companion import manifest, paths
from asoc_companion import notebooks as nbs
from asoc_companion.plan import make_plan
from asoc_companion.timing import median_seconds


def test_manifest_check_of_every_notebook(benchmark):
    """Hashes of every notebook's inputs (sources, import closures, values): what `make book` checks
    first."""
    infos = list(nbs.notebooks().values())
    plans = [make_plan(paths.project(), info, "full") for info in infos]

    def check():
        return [manifest.entry(plan) for plan in plans]

    benchmark.extra_info["target_s"] = 1.0
    benchmark.pedantic(check, rounds=5)


def test_median_seconds_overhead(benchmark):
    """median_seconds of an empty call, 1000 repeats: the helper adds microseconds, not
    milliseconds."""
    benchmark.extra_info["target_s"] = 0.01
    benchmark.pedantic(median_seconds, args=(lambda: None, 1000), rounds=5)
