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

__all__ = ["BATCH", "MUTANT_SUFFIX", "instance_seed", "statement", "run_instance",
           "StatementResult", "run_study", "verdict_text"]


BATCH = 25                                 # instances per task: amortises the executor's overhead
# a mutant's instances draw from the seeds of key + suffix
MUTANT_SUFFIX = ":mutant"


def instance_seed(key: str, seed: int, index: int) -> np.random.SeedSequence:
    """The seed of instance ``index``: child ``index`` of
    ``SeedSequence((seed, crc32(key))).spawn(n)``.

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
    raise ValueError(f"key: expected one of the statement keys ({STATEMENTS[0].key}, ...), found "
                     f"{key!r}")


def run_instance(key: str, seed: int, index: int, mutant: bool = False):
    """One instance of one statement (or of its mutant, drawn from the seeds of
    ``key + ":mutant"``): the Outcome, or ("error", message) when the check raised.

    Examples
    --------
    >>> run_instance("statement_3_30", 2017, 0).verdict, run_instance("statement_3_30", 2017, 0,
    ...     mutant=True).verdict
    ('holds', 'fails')
    """
    seed_key = key + MUTANT_SUFFIX if mutant else key
    rng = np.random.default_rng(instance_seed(seed_key, seed, index))
    check = statement(key).check
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return check(rng, mutant=True) if mutant else check(rng)
        # a checker bug: reported, not hidden
        except Exception as err:
            return ("error", f"{type(err).__name__}: {err}")


def _run_batch(key, seed, indices, mutant):
    return [(i, run_instance(key, seed, i, mutant)) for i in indices]


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
    mutant: dict | None = None
    corrected: dict | None = None
    diagnosis: str | None = None

    def recorded_value(self) -> dict:
        """The recorded value: counts, failing indices, the summary, the mutant and the timing."""
        counts = {"holds": self.holds, "fails": self.fails, "not_applicable": self.not_applicable,
                  "errors": self.errors}
        record = {"verdict": verdict_text(counts), "instances": self.instances, "holds": self.holds,
                  "fails": self.fails, "not_applicable": self.not_applicable, "errors": self.errors,
                  "failing": self.failing, "errored": sorted(self.error_messages),
                  "summary": self.summary,
                  "seconds": round(self.seconds, 2)}
        if self.mutant is not None:
            record["mutant"] = self.mutant
        if self.corrected is not None:
            record["corrected"] = self.corrected
        if self.diagnosis is not None:
            record["diagnosis"] = self.diagnosis
        return record


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
    summarise = statement(key).summarise
    if summarise is not None:
        res.summary = summarise(outcomes)
        # a corrected reading checked beside the claim
        res.corrected = res.summary.pop("corrected", None)
        res.diagnosis = res.summary.pop("diagnosis", None)        # why a failing claim fails
    return res


def _mutant_record(key, results):
    """What the mutant's instances gave: ``{"description", "fails", "instances"}`` (+ premise-false
    and errors when there were any, and the statement's ``why_not``). The mutant is caught when
    ``fails > 0``; it has power when it is caught in at least half of its draws.
    """
    verdicts = [out if isinstance(out, tuple) else out.verdict for _, out in results]
    record = {"description": statement(key).mutant, "fails": verdicts.count("fails"),
              "instances": len(verdicts)}
    if statement(key).why_not:
        record["why_not"] = statement(key).why_not
    for name, count in (("not_applicable", verdicts.count("not_applicable")),
                        ("errors", sum(isinstance(v, tuple) for v in verdicts))):
        if count:
            record[name] = count
    return record


def run_study(instances, seed=2017, only=None, n_jobs=-1, scheduler=None, progress=True,
              mutants=None):
    """Check every statement (or those in ``only``) on its instances: {key: StatementResult}.

    Parameters
    ----------
    instances : int or callable
        Instances per statement, or ``instances(statement) -> int`` (e.g. fewer for expensive ones).
    mutants : int or callable, optional
        Instances of each statement's mutant (the same check against a planted false variant;
        default none); recorded as the result's ``mutant``.
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
    chosen = [st for st in STATEMENTS
              if st.check is not None and (only is None or st.key in set(only))]
    if only is not None:
        unknown = set(only) - {st.key for st in STATEMENTS}
        if unknown:
            raise ValueError("only: expected statement keys such as 'statement_3_19', found "
                             f"{sorted(unknown)}")
    count = lambda n, st: 0 if n is None else int(n(st) if callable(n) else n)
    counts = {(st.key, mutant): count(n, st)
              for st in chosen for mutant, n in ((False, instances), (True, mutants))}
    tasks = [(key, mutant, list(range(start, min(start + BATCH, n))))
             for (key, mutant), n in counts.items() for start in range(0, n, BATCH)]
    jobs = (joblib.delayed(_run_batch)(key, seed, indices, mutant) for key, mutant,
            indices in tasks)
    collected = {task: [] for task in counts}
    elapsed = {st.key: 0.0 for st in chosen}
    bar = progress_bar(total=sum(counts.values()), enabled=progress, desc="theorems",
                       unit="instance")
    with _backend(scheduler, n_jobs) as parallel:
        last = time.perf_counter()
        for (key, mutant, _), batch in zip(tasks, parallel(jobs)):
            now = time.perf_counter()
            elapsed[key] += now - last
            last = now
            collected[key, mutant].extend(batch)
            bar.update(len(batch))
    bar.close()
    results = {st.key: _tally(st.key, counts[st.key, False], collected[st.key, False],
                              elapsed[st.key])
               for st in chosen}
    if mutants is not None:
        for key, res in results.items():
            res.mutant = _mutant_record(key, collected[key, True])
            # the check's mutant is the corrected reading's
            if res.corrected is not None:
                res.corrected["mutant"] = res.mutant
    return results


class _backend:
    """joblib.Parallel on local processes, or on a Dask cluster through joblib's dask backend."""

    def __init__(self, scheduler, n_jobs):
        self.scheduler, self.n_jobs = scheduler, n_jobs
        self.client = self.config = None

    def __enter__(self):
        if self.scheduler is None:
            return joblib.Parallel(n_jobs=self.n_jobs, return_as="generator")
        from distributed import Client

        self.client = self.scheduler if isinstance(self.scheduler,
                                                   Client) else Client(self.scheduler)
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
