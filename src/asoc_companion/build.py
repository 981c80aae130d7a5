"""Running notebooks for the command line: one run, and the incremental parallel build.

``reproduce`` runs every notebook whose inputs changed (:mod:`asoc_companion.manifest`),
independent notebooks side by side in worker processes (``jobs``), each after the notebooks
it depends on (``metadata.asoc.depends``), with one BLAS/OpenMP thread per worker so two
notebooks do not oversubscribe the cores. Each run is crash-safe
(:func:`asoc_companion.notebooks.run`); the parent writes a notebook's manifest entry after
its files are in place. Each notebook's :class:`asoc_companion.plan.RunPlan` is made once, in
the parent, and passed to the worker, the run and the manifest. The workers' functions live
here, in an importable module, so the spawned processes find them whatever the parent's
``__main__`` is.
"""

import os
import signal
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context
from pathlib import Path

from . import manifest, paths
from . import notebooks as nbs
from .plan import make_plan, output_folder

__all__ = ["rel", "terminate", "run_one", "run_and_record", "reproduce"]


def rel(path) -> str:
    """``path`` relative to the project root when inside it."""
    try:
        return str(path.resolve().relative_to(paths.project().root))
    except ValueError:
        return str(path)


def terminate(signum, frame):
    """SIGTERM ends the run like Ctrl-C: the staging folder is removed, tracked files stay."""
    raise KeyboardInterrupt(f"signal {signum}")


def run_one(plan, progress_bar=None):
    """Run ``plan``; return the executed notebook's path and the wall time in seconds."""
    info, folder = plan.notebook, plan.output_dir
    start, started = time.perf_counter(), time.time()
    print(f"running {info.path.name} ({info.title}) at fidelity={plan.fidelity} ...", flush=True)
    executed = nbs.run(plan, progress_bar=progress_bar)
    seconds = time.perf_counter() - start
    print(f"  {info.path.name} done in {seconds:.1f} s -> {rel(executed)}", flush=True)
    written = _written_since(folder, started)
    if written:
        print(f"  outputs in {rel(folder)}/: {', '.join(written)}", flush=True)
    return executed, seconds


def _written_since(folder, since: float) -> list:
    """The files under ``folder`` written at or after ``since`` (a ``time.time()``), relative to it,
    in natural order (fig2_2 before fig2_10).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     for name in ("fig2_10.png", "fig2_2.png"):
    ...         _ = (Path(tmp) / name).write_text("")
    ...     _written_since(tmp, 0)
    ['fig2_2.png', 'fig2_10.png']
    """
    folder = Path(folder)
    found = [p for p in folder.rglob("*") if p.is_file() and p.stat().st_mtime >= since - 1]
    return sorted((p.relative_to(folder).as_posix() for p in found), key=nbs.natural_key)


def run_and_record(plan, progress_bar=None):
    """Run ``plan``, then write its manifest entry (last)."""
    _, seconds = run_one(plan, progress_bar=progress_bar)
    manifest.update_manifest(plan, seconds=seconds)


def _worker_init(root):
    signal.signal(signal.SIGTERM, terminate)      # clean up the staging folder and the kernel
    os.environ[paths.ENV_VAR] = str(root)


def _worker_run(plan):
    """Run one notebook in a worker process (the parent writes the manifest)."""
    return run_one(plan, progress_bar=False)[1]


def _pending(plans, force) -> list:
    """The plans to run, each with why (in build order)."""
    todo = []
    for plan in plans:
        changed = ["--force"] if force else manifest.changed_inputs(plan)
        name = plan.notebook.path.name
        if changed:
            why = ", ".join(changed)
            shown = why if changed[0].startswith("outputs") else "changed: " + why
            print(f"{name}: {shown}", flush=True)
            todo.append(plan)
        else:
            print(f"{name}: up to date, skipped", flush=True)
    return todo


def reproduce(fidelity, force=False, jobs=None) -> int:
    """Run each notebook whose inputs changed (all if ``force``), ``jobs`` at a time; 0 on success.

    A notebook starts when the notebooks it depends on (``metadata.asoc.depends``) have
    finished; a failed notebook's dependants are skipped, the others still run.
    """
    project = paths.project()
    ordered = [make_plan(project, info, fidelity)
               for info in nbs.build_order(nbs.notebooks().values())]
    todo = {plan.name: plan for plan in _pending(ordered, force)}
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(todo) or 1))
    waits = {name: [d for d in manifest.dependencies(plan.notebook.path) if d in todo]
             for name, plan in todo.items()}
    failed = []
    if jobs == 1:
        for name, plan in todo.items():
            if any(d in failed for d in waits[name]):
                failed.append(name)
                print(f"{plan.notebook.path.name}: skipped, a notebook it depends on failed",
                      flush=True)
                continue
            try:
                run_and_record(plan)
            except Exception as err:           # noqa: BLE001 -- report, go on with the others
                failed.append(name)
                print(f"{plan.notebook.path.name}: FAILED: {type(err).__name__}: "
                      f"{str(err).splitlines()[0] if str(err) else ''}",
                      flush=True)
        return 1 if failed else 0
    print(f"running {len(todo)} notebook(s), {jobs} at a time", flush=True)
    done = set()
    context = get_context("spawn")
    with ProcessPoolExecutor(jobs, mp_context=context, initializer=_worker_init,
                             initargs=(paths.project().root,)) as pool:
        try:
            _schedule(pool, todo, waits, jobs, output_folder(project, fidelity), done, failed)
        except KeyboardInterrupt:
            # stop the workers too: each removes its staging folder, nothing moves into place
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
            pool.shutdown(wait=True, cancel_futures=True)
            raise
    return 1 if failed else 0


def _longest_first(names, seconds) -> list:
    """``names`` by their last run's wall time, longest first, never-timed ones before all
    (the longest-processing-time rule: on two cores the short notebooks fill the gaps at the end).

    Examples
    --------
    >>> _longest_first(["sec3_2", "theorems", "new", "sec2_5"], {"sec3_2": 6.0, "theorems": 300.0,
    ...     "sec2_5": 90.0})
    ['new', 'theorems', 'sec2_5', 'sec3_2']
    """
    return sorted(names, key=lambda name: -seconds.get(name, float("inf")))


def _schedule(pool, todo, waits, jobs, out, done, failed):
    """Submit each plan when its dependencies are done, longest first (by the manifest in
    ``out``); write its manifest entry when it finishes.
    """
    running = {}
    order = _longest_first(list(todo), manifest.last_seconds(out))
    while len(done) + len(failed) < len(todo):
        for name in order:
            if name in running.values() or name in done or name in failed:
                continue
            if any(d in failed for d in waits[name]):
                failed.append(name)
                print(f"{name}.ipynb: skipped, a notebook it depends on failed", flush=True)
            elif all(d in done for d in waits[name]) and len(running) < jobs:
                running[pool.submit(_worker_run, todo[name])] = name
        if not running:
            continue          # every remaining notebook was just marked failed or skipped
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in finished:
            name = running.pop(future)
            try:
                seconds = future.result()
            except Exception as err:       # noqa: BLE001
                failed.append(name)
                print(f"{name}.ipynb: FAILED: {type(err).__name__}: "
                      f"{str(err).splitlines()[0] if str(err) else ''}", flush=True)
                continue
            manifest.update_manifest(todo[name], seconds=seconds)
            done.add(name)
