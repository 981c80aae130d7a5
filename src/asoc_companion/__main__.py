"""Command line: ``python -m asoc_companion list | run NAME | figure N | table N | reproduce | ledger``.

Each command takes ``--fidelity full|ci``. ``full`` runs the thesis's settings and
updates ``figures/`` and the executed notebooks in ``book/``; ``ci`` runs small
Monte Carlo sizes and writes to ``book/_build/ci/`` only. ``reproduce`` re-executes a
notebook only when its inputs changed or its outputs are incomplete
(``figures/values/manifest.json``; ``--force`` runs all), independent notebooks in
parallel (``--jobs``). ``figure N -p name value`` runs with other parameters into
``book/_build/runs/<notebook>-<hash>/`` and never touches tracked files. Every run
executes into a staging folder and moves into place only when it succeeds.
``--root`` names the checkout (default: ``$ASOC_COMPANION_ROOT`` or the nearest one above
the current directory).
"""

import argparse
import os
import signal
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context

from . import manifest, paths
from . import notebooks as nbs
from .io import atomic_write_text
from .ledger import intro_markdown, ledger_markdown, ledger_rows
from .values import load_all_values, load_values

# one BLAS/OpenMP thread per notebook when notebooks run side by side (no oversubscription)
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS")


def _rel(path) -> str:
    try:
        return str(path.resolve().relative_to(paths.project().root))
    except ValueError:
        return str(path)


def _run(info, fidelity, output_dir=None, overrides=None, progress_bar=None):
    start = time.perf_counter()
    print(f"running {info.path.name} ({info.title}) at fidelity={fidelity} ...", flush=True)
    executed = nbs.run(info, fidelity, output_dir=output_dir, overrides=overrides, progress_bar=progress_bar)
    print(f"  {info.path.name} done in {time.perf_counter() - start:.1f} s -> {_rel(executed)}", flush=True)
    return executed


def _run_and_record(info, fidelity, progress_bar=None):
    """Run ``info`` into its default folder, then write its manifest entry (last)."""
    _run(info, fidelity, progress_bar=progress_bar)
    out = nbs.default_output_dir(fidelity)
    manifest.update_manifest(info, nbs.harness_parameters(info, fidelity, out), out)


def _worker_init(root, single_thread):
    signal.signal(signal.SIGTERM, _terminate)      # clean up the staging folder and the kernel
    os.environ[paths.ENV_VAR] = str(root)
    if single_thread:
        for name in THREAD_VARIABLES:
            os.environ[name] = "1"


def _worker_run(name, fidelity):
    """Run one notebook in a worker process (the parent writes the manifest)."""
    info = nbs.by_name(name)
    _run(info, fidelity, progress_bar=False)
    return name


def _pending(infos, fidelity, force) -> list:
    """The notebooks to run, each with why (in build order)."""
    out = nbs.default_output_dir(fidelity)
    todo = []
    for info in infos:
        params = nbs.harness_parameters(info, fidelity, out)
        changed = ["--force"] if force else manifest.changed_inputs(
            info, params, out, executed=nbs.executed_path(info, fidelity, out))
        if changed:
            print(f"{info.path.name}: {', '.join(changed) if changed[0].startswith('outputs') else 'changed: ' + ', '.join(changed)}", flush=True)
            todo.append(info)
        else:
            print(f"{info.path.name}: up to date, skipped", flush=True)
    return todo


def reproduce(fidelity, force=False, jobs=None) -> int:
    """Run every notebook whose inputs changed (all with ``force``), ``jobs`` at a time; 0 if all succeeded.

    A notebook starts when the notebooks it depends on (``metadata.asoc.depends``) have
    finished; a failed notebook's dependants are skipped, the others still run.
    """
    ordered = nbs.build_order(nbs.notebooks().values())
    todo = {info.name: info for info in _pending(ordered, fidelity, force)}
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(todo) or 1))
    waits = {name: [d for d in manifest.dependencies(info.path) if d in todo] for name, info in todo.items()}
    failed = []
    if jobs == 1:
        for name, info in todo.items():
            if any(d in failed for d in waits[name]):
                failed.append(name)
                print(f"{info.path.name}: skipped, a notebook it depends on failed", flush=True)
                continue
            try:
                _run_and_record(info, fidelity)
            except Exception as err:           # noqa: BLE001 -- report, go on with the others
                failed.append(name)
                print(f"{info.path.name}: FAILED: {type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}",
                      flush=True)
        return 1 if failed else 0
    print(f"running {len(todo)} notebook(s), {jobs} at a time (one BLAS thread each)", flush=True)
    done = set()
    context = get_context("spawn")
    with ProcessPoolExecutor(jobs, mp_context=context, initializer=_worker_init,
                             initargs=(paths.project().root, True)) as pool:
        try:
            _schedule(pool, todo, waits, jobs, fidelity, done, failed)
        except KeyboardInterrupt:
            # stop the workers too: each removes its staging folder, nothing moves into place
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
            pool.shutdown(wait=True, cancel_futures=True)
            raise
    return 1 if failed else 0


def _schedule(pool, todo, waits, jobs, fidelity, done, failed):
    """Submit each notebook when its dependencies are done; write its manifest entry when it finishes."""
    running = {}
    while len(done) + len(failed) < len(todo):
        for name in todo:
            if name in running.values() or name in done or name in failed:
                continue
            if any(d in failed for d in waits[name]):
                failed.append(name)
                print(f"{name}.ipynb: skipped, a notebook it depends on failed", flush=True)
            elif all(d in done for d in waits[name]) and len(running) < jobs:
                running[pool.submit(_worker_run, name, fidelity)] = name
        if not running:
            continue          # every remaining notebook was just marked failed or skipped
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in finished:
            name = running.pop(future)
            try:
                future.result()
            except Exception as err:       # noqa: BLE001
                failed.append(name)
                print(f"{name}.ipynb: FAILED: {type(err).__name__}: "
                      f"{str(err).splitlines()[0] if str(err) else ''}", flush=True)
                continue
            out = nbs.default_output_dir(fidelity)
            manifest.update_manifest(todo[name], nbs.harness_parameters(todo[name], fidelity, out), out)
            done.add(name)


def _short(value) -> str:
    """A recorded value in a few characters (Monte Carlo record -> its estimate, claim -> verdict)."""
    if isinstance(value, dict):
        if "holds" in value:
            return f"{'holds' if value['holds'] else 'fails'} ({_short(value.get('value'))})"
        return _short(value.get("value", value.get("median")))
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, (int, float)):
        return f"{value:.6g}"
    if isinstance(value, list):
        shown = ", ".join(_short(v) for v in value[:3])
        return f"[{shown}{', ...' if len(value) > 3 else ''}]"
    return str(value)[:40]


def compare_with_committed(name, output_dir) -> str:
    """Table of ``name``'s values in ``output_dir`` next to the committed ones (key, committed, this run)."""
    ours, committed = load_values(name, output_dir), load_values(name)
    rows = [(key, _short(committed[key]) if key in committed else "-", _short(value))
            for key, value in ours.items()]
    width = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(("key", "committed", "this run"))]
    lines = [f"{'key':{width[0]}}  {'committed':{width[1]}}  this run"]
    lines += [f"{k:{width[0]}}  {c:{width[1]}}  {t}" for k, c, t in rows]
    return "\n".join(lines)


def _ledger(fidelity):
    project = paths.project()
    path, values = (project.book / "ledger.md", load_all_values()) if fidelity == "full" \
        else (project.ci_output / "ledger.md", load_all_values(project.ci_output))
    _write_if_changed(path, ledger_markdown(values=values),
                      "" if fidelity == "full" else " (ci fidelity: Monte Carlo cells use small samples)")
    if fidelity == "full":
        intro = project.book / "intro.md"
        _write_if_changed(intro, intro_markdown(intro.read_text(), ledger_rows(values=values)), " (summary)")


def _write_if_changed(path, text, remark=""):
    if path.exists() and path.read_text() == text:
        print(f"{_rel(path)}: up to date")
        return
    atomic_write_text(path, text)
    print(f"wrote {_rel(path)}{remark}")


def _parser():
    parser = argparse.ArgumentParser(prog="python -m asoc_companion", description=__doc__.splitlines()[0])
    parser.add_argument("--root", help=f"the checkout to work on (default: ${paths.ENV_VAR}, "
                                       "else the nearest one above the current directory)")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_ in [("list", "list notebooks, figures and tables"),
                        ("reproduce", "run every notebook whose inputs changed, then write the ledger"),
                        ("ledger", "write the ledger page from the recorded values")]:
        p = sub.add_parser(name, help=help_)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
        if name == "reproduce":
            p.add_argument("--force", action="store_true", help="re-execute every notebook")
            p.add_argument("--jobs", "-j", type=int, default=None,
                           help="notebooks run at the same time (default: the number of cores)")
    for name, what, help_ in [("figure", "number", "regenerate one figure by its number, e.g. 3.4 or own.1"),
                              ("table", "number", "regenerate one table by its number, e.g. 3.2"),
                              ("run", "name", "run one notebook by its name, e.g. sec3_5 or findings")]:
        p = sub.add_parser(name, help=help_)
        p.add_argument(what)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
        p.add_argument("-p", "--parameter", nargs=2, action="append", metavar=("NAME", "VALUE"),
                       help="override a parameter of the notebook (papermill's -p); "
                            "the run goes to book/_build/runs/, tracked files stay unchanged")
    return parser


def _terminate(signum, frame):
    """SIGTERM ends the run like Ctrl-C: the staging folder is removed, tracked files stay."""
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.root:
        os.environ[paths.ENV_VAR] = os.path.abspath(args.root)     # notebook kernels inherit it
    try:
        signal.signal(signal.SIGTERM, _terminate)
    except ValueError:            # not the main thread (e.g. called from a test runner thread)
        pass
    try:
        return _command(args)
    except (ValueError, RuntimeError) as err:
        # bad input and a corrupt values file are one-line messages, not tracebacks
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: nothing was moved into place", file=sys.stderr)
        return 130


def _command(args) -> int:
    paths.project()              # fail early, with the message, outside a checkout
    if args.command == "list":
        for info in nbs.notebooks().values():
            figs = ", ".join(f"Fig. {f}" for f in info.figures)
            tabs = ", ".join(f"Table {t}" for t in info.tables)
            params = ", ".join(n for n in nbs.default_parameters(info) if n not in nbs.HARNESS_PARAMETERS)
            print(f"{info.name:10s} {info.title}\n{'':10s} {'; '.join(x for x in (figs, tabs) if x)}\n"
                  f"{'':10s} parameters (-p): {params}")
        return 0
    if args.command in ("figure", "table", "run"):
        info = nbs.by_name(args.name) if args.command == "run" else nbs.find(args.command, args.number)
        overrides = nbs.parse_overrides(info, args.parameter)
        if not overrides:
            if args.fidelity == "full":
                _run_and_record(info, "full")
            else:
                _run(info, args.fidelity)
            return 0
        out = nbs.run_folder(info, args.fidelity, overrides)
        _run(info, args.fidelity, output_dir=out, overrides=overrides)
        print(f"this run (figures, values, executed notebook): {_rel(out)}/")
        print(compare_with_committed(info.name, out))
        return 0
    status = 0
    if args.command == "reproduce":
        status = reproduce(args.fidelity, args.force, args.jobs)
    _ledger(args.fidelity)
    return status


if __name__ == "__main__":
    sys.exit(main())
