"""Run the theorems study: statements x instances, in parallel, independent of the executor.

Instance ``i`` of statement ``key`` draws everything from
``numpy.random.default_rng(instance_seed(key, seed, i))``, which equals the ``i``-th child of
``SeedSequence((seed, crc32(key))).spawn(n)``: any instance re-runs alone from its index, and
the results do not depend on how the work is scheduled. By default the instances run through
joblib on all local cores; with a Dask scheduler address, through joblib's dask backend on
the cluster (``distributed.Client(address)`` + ``joblib.parallel_config(backend="dask")``).
"""

import time
import warnings
import zlib
from dataclasses import dataclass, field

import joblib
import numpy as np

from asoc.progress import progress_bar

from . import STATEMENTS
from .chapter2 import SUMMARIES as CHAPTER_2_SUMMARIES
from .chapter3 import SUMMARIES as CHAPTER_3_SUMMARIES

SUMMARIES = {**CHAPTER_2_SUMMARIES, **CHAPTER_3_SUMMARIES}
BATCH = 25                                 # instances per task: amortises the executor's overhead


def instance_seed(key: str, seed: int, index: int) -> np.random.SeedSequence:
    """The seed of instance ``index``: child ``index`` of ``SeedSequence((seed, crc32(key))).spawn(n)``.

    Examples
    --------
    >>> import numpy as np
    >>> direct = instance_seed("statement_3_19", 2017, 5)
    >>> spawned = np.random.SeedSequence((2017, zlib.crc32(b"statement_3_19"))).spawn(10)[5]
    >>> bool(np.array_equal(direct.generate_state(4), spawned.generate_state(4)))
    True
    """
    return np.random.SeedSequence((int(seed), zlib.crc32(key.encode())), spawn_key=(int(index),))


def statement(key: str):
    """The Statement with record key ``key``."""
    for st in STATEMENTS:
        if st.key == key:
            return st
    raise ValueError(f"key: expected one of the statement keys ({STATEMENTS[0].key}, ...), found {key!r}")


def run_instance(key: str, seed: int, index: int):
    """One instance of one statement: the Outcome, or ("error", message) when the check raised."""
    rng = np.random.default_rng(instance_seed(key, seed, index))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return statement(key).check(rng)
        except Exception as err:                                      # a checker bug: reported, not hidden
            return ("error", f"{type(err).__name__}: {err}")


def _run_batch(key, seed, indices):
    return [(i, run_instance(key, seed, i)) for i in indices]


@dataclass
class StatementResult:
    """Counts and failing instances of one statement (what is recorded as ``statement_<c>_<n>``)."""

    key: str
    instances: int
    holds: int = 0
    fails: int = 0
    not_applicable: int = 0
    errors: int = 0
    failing: list = field(default_factory=list)
    failures: dict = field(default_factory=dict)
    error_messages: dict = field(default_factory=dict)
    summary: dict = field(default_factory=dict)
    seconds: float = 0.0

    def record(self) -> dict:
        """The recorded value: counts, failing indices, the statement's summary and timing."""
        counts = {"holds": self.holds, "fails": self.fails, "not_applicable": self.not_applicable, "errors": self.errors}
        return {"verdict": verdict_text(counts), "instances": self.instances, "holds": self.holds, "fails": self.fails,
                "not_applicable": self.not_applicable, "errors": self.errors, "failing": self.failing,
                "errored": sorted(self.error_messages), "summary": self.summary, "seconds": round(self.seconds, 2)}


def _tally(key, n, results, seconds):
    res = StatementResult(key, n, seconds=seconds)
    outcomes = []
    for index, out in sorted(results, key=lambda r: r[0]):
        if isinstance(out, tuple):
            res.errors += 1
            res.error_messages[index] = out[1]
            continue
        outcomes.append(out)
        setattr(res, out.verdict, getattr(res, out.verdict) + 1)
        if out.verdict == "fails":
            res.failing.append(index)
            res.failures[index] = out.numbers
    if key in SUMMARIES:
        res.summary = SUMMARIES[key](outcomes)
    return res


def run_study(instances, seed=2017, only=None, n_jobs=-1, scheduler=None, progress=True):
    """Check every statement (or those in ``only``) on its instances; returns {key: StatementResult}.

    Parameters
    ----------
    instances : int or callable
        Instances per statement, or ``instances(statement) -> int`` (e.g. fewer for expensive ones).
    seed : int
        Study seed; instance ``i`` of ``key`` uses :func:`instance_seed`.
    only : iterable of str, optional
        Statement keys to run (default all with a check).
    n_jobs : int
        joblib workers (-1: all local cores; ignored with a scheduler).
    scheduler : str, optional
        Dask scheduler address, e.g. ``"tcp://host:8786"``, or a ``distributed.Client``.
    progress : bool
        tqdm bar over instances (shown on a terminal only).
    """
    chosen = [st for st in STATEMENTS if st.check is not None and (only is None or st.key in set(only))]
    if only is not None:
        unknown = set(only) - {st.key for st in STATEMENTS}
        if unknown:
            raise ValueError(f"only: expected statement keys such as 'statement_3_19', found {sorted(unknown)}")
    counts = {st.key: int(instances(st) if callable(instances) else instances) for st in chosen}
    tasks = [(st.key, list(range(start, min(start + BATCH, counts[st.key]))))
             for st in chosen for start in range(0, counts[st.key], BATCH)]
    jobs = (joblib.delayed(_run_batch)(key, seed, indices) for key, indices in tasks)
    collected = {st.key: [] for st in chosen}
    elapsed = {st.key: 0.0 for st in chosen}
    bar = progress_bar(total=sum(counts.values()), enabled=progress, desc="theorems", unit="instance")
    start = time.perf_counter()
    with _backend(scheduler, n_jobs) as parallel:
        last = start
        for (key, _), batch in zip(tasks, parallel(jobs)):
            now = time.perf_counter()
            elapsed[key] += now - last
            last = now
            collected[key].extend(batch)
            bar.update(len(batch))
    bar.close()
    return {key: _tally(key, counts[key], collected[key], elapsed[key]) for key in collected}


class _backend:
    """joblib.Parallel on local processes, or on a Dask cluster through joblib's dask backend."""

    def __init__(self, scheduler, n_jobs):
        self.scheduler, self.n_jobs = scheduler, n_jobs
        self.client = self.config = None

    def __enter__(self):
        if self.scheduler is None:
            return joblib.Parallel(n_jobs=self.n_jobs, return_as="generator")
        from distributed import Client

        self.client = self.scheduler if isinstance(self.scheduler, Client) else Client(self.scheduler)
        self.config = joblib.parallel_config(backend="dask")
        self.config.__enter__()
        return joblib.Parallel(return_as="generator")

    def __exit__(self, *exc):
        if self.config is not None:
            self.config.__exit__(*exc)
        if self.client is not None and self.client is not self.scheduler:
            self.client.close()
        return False


def verdict_text(result) -> str:
    """"holds in 1000 of 1000", "fails in 7 of 1000" (not-applicable instances said separately)."""
    applicable = result["holds"] + result["fails"]
    text = (f"fails in {result['fails']} of {applicable}" if result["fails"]
            else f"holds in {result['holds']} of {applicable}")
    if result["not_applicable"]:
        text += f" (premise false in {result['not_applicable']})"
    if result.get("errors"):
        text += f"; {result['errors']} checker errors"
    return text
