"""The companion's command line: list, run, figure, table, reproduce and ledger.

``python -m asoc_companion list | run NAME | figure N | table N | reproduce | ledger``.

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
import re
import signal
import sys

from . import paths
from .requirements import INSTALL_HINT, missing_requirements


def plain(text: str) -> str:
    """``text`` without reStructuredText markup, for the terminal: ``x``, `x`, :role:`x` become x.

    Examples
    --------
    >>> plain("``python -m asoc_companion list`` (:func:`run`, `list` shows them)")
    'python -m asoc_companion list (run, list shows them)'
    """
    return re.sub(r"(?::[\w:]+:)?`{1,2}~?([^`]+?)`{1,2}", r"\1", text)


FIDELITY_HELP = ("full: the thesis's settings, updates figures/ and book/; "
                 "ci: small Monte Carlo sizes, writes to book/_build/ci/ only (default: full)")

def _short(value) -> str:
    """A recorded value in a few characters (a Monte Carlo record's estimate, a claim's verdict)."""
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


def compare_with_committed(name, output_dir, fidelity="ci") -> str:
    """Table of ``name``'s values in ``output_dir`` beside the committed ones (key, committed, run).

    The committed values come from the full-fidelity run; the column headers say so, and
    give this run's ``fidelity``.
    """
    from .values import load_values

    ours, committed = load_values(name, output_dir), load_values(name)
    rows = [(key, _short(committed[key]) if key in committed else "-", _short(value))
            for key, value in ours.items()]
    head = ("key", "committed (full)", f"this run ({fidelity})")
    width = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(head)]
    lines = [f"{head[0]:{width[0]}}  {head[1]:{width[1]}}  {head[2]}"]
    lines += [f"{k:{width[0]}}  {c:{width[1]}}  {t}" for k, c, t in rows]
    return "\n".join(lines)


def unused_parameters(info, kind, number, overrides) -> str:
    """A note naming the changed parameters that cannot change ``kind`` ``number`` ("" if none).

    Examples
    --------
    >>> from asoc_companion import notebooks as nbs
    >>> print(unused_parameters(nbs.find("figure", "3.4"), "figure", "3.4", {"seed": 7}))
    note: seed does not reach the cells that make Fig. 3.4; the figure is the same without it.
    >>> unused_parameters(nbs.find("figure", "3.2"), "figure", "3.2", {"seed": 7})
    ''
    """
    from .notebooks import parameters_reaching

    unused = sorted(set(overrides) - parameters_reaching(info, kind, number))
    if not unused:
        return ""
    what = f"Fig. {number}" if kind == "figure" else f"Table {number}"
    verb = "does" if len(unused) == 1 else "do"
    thing = "figure" if kind == "figure" else "table"
    return (f"note: {', '.join(unused)} {verb} not reach the cells that make {what}; "
            f"the {thing} is the same without {'it' if len(unused) == 1 else 'them'}.")


def notebook_list(infos) -> str:
    """``list``'s text: per notebook its name and title, its figures and tables, its parameters,
    the later lines indented to the title's column.

    Examples
    --------
    >>> from asoc_companion import notebooks as nbs
    >>> lines = notebook_list([nbs.by_name("sec3_2"), nbs.by_name("large_system")]).splitlines()
    >>> lines[0].index("Sec. 3.2") == lines[1].index("Fig. 3.2") == lines[3].index("A larger")
    True
    """
    from . import notebooks as nbs

    infos = list(infos)
    width = max(len(info.name) for info in infos)
    lines = []
    for info in infos:
        figs = ", ".join(f"Fig. {f}" for f in info.figures)
        tabs = ", ".join(f"Table {t}" for t in info.tables)
        params = ", ".join(n for n in nbs.default_parameters(info)
                           if n not in nbs.HARNESS_PARAMETERS)
        items = "; ".join(x for x in (figs, tabs) if x) or "no figure or table of the thesis"
        lines.append(f"{info.name:{width}}  {info.title}")
        lines.append(f"{'':{width}}  {items}")
        lines.append(f"{'':{width}}  parameters (-p): {params}")
    return "\n".join(lines)


def _ledger(fidelity):
    from .ledger import intro_markdown, ledger_markdown, ledger_rows
    from .values import load_all_values

    project = paths.project()
    path, values = (project.book / "ledger.md", load_all_values()) if fidelity == "full" \
        else (project.ci_output / "ledger.md", load_all_values(project.ci_output))
    small = " (ci fidelity: Monte Carlo cells use small samples)"
    _write_if_changed(path, ledger_markdown(values=values), "" if fidelity == "full" else small)
    intro = project.book / "intro.md"
    if fidelity == "full":
        from .mutants import write_ledger_mutants
        write_ledger_mutants()                      # which claim checks catch their planted variant
    if fidelity == "full" and intro.exists():
        _write_if_changed(intro, intro_markdown(intro.read_text(), ledger_rows(values=values)),
                          " (summary)")


def _write_if_changed(path, text, remark=""):
    from .atomic_files import atomic_write_text
    from .build import rel as _rel

    if path.exists() and path.read_text() == text:
        print(f"{_rel(path)}: up to date")
        return
    atomic_write_text(path, text)
    print(f"wrote {_rel(path)}{remark}")


def build_parser():
    """The command line's argument parser, with one subcommand per action (``--help`` text).

    Examples
    --------
    >>> build_parser().parse_args(["run", "sec3_5", "--fidelity", "ci"]).fidelity
    'ci'
    """
    parser = argparse.ArgumentParser(prog="python -m asoc_companion",
                                     description=plain(__doc__.splitlines()[0]),
                                     epilog=plain(" ".join(__doc__.split("\n\n", 1)[1].split())))
    parser.add_argument("--root", help=f"the checkout to work on (default: ${paths.ENV_VAR}, "
                                       "else the nearest one above the current directory)")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_ in [("list", "list notebooks, figures and tables"),
                        ("reproduce",
                         "run every notebook whose inputs changed, then write the ledger"),
                        ("ledger", "write the ledger page from the recorded values")]:
        p = sub.add_parser(name, help=help_, description=help_)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full", help=FIDELITY_HELP)
        if name == "reproduce":
            p.add_argument("--force", action="store_true", help="re-execute every notebook")
            p.add_argument("--jobs", "-j", type=int, default=None,
                           help="notebooks run at the same time (default: the number of cores)")
    for name, what, help_, what_help in [
            ("figure", "number", "regenerate one figure by its number, e.g. 3.4 or own.1",
             "the figure's number in the thesis (e.g. 3.4), or own.N for the companion's own "
             "figures"),
            ("table", "number", "regenerate one table by its number, e.g. 3.2",
             "the table's number in the thesis"),
            ("run", "name", "run one notebook by its name, e.g. sec3_5 or findings",
             "the notebook's file name without .ipynb (list shows them)")]:
        p = sub.add_parser(name, help=help_, description=help_)
        p.add_argument(what, help=what_help)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full", help=FIDELITY_HELP)
        p.add_argument("-p", "--parameter", nargs=2, action="append", metavar=("NAME", "VALUE"),
                       help="override a parameter of the notebook (papermill's -p); "
                            "the run goes to book/_build/runs/, tracked files stay unchanged")
    return parser


def main(argv=None) -> int:
    """Run ``python -m asoc_companion`` with the arguments ``argv``; return the exit status.

    Parameters
    ----------
    argv : list of str, optional
        The command line after the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success, 1 when the companion's requirements are missing.
    """
    missing = missing_requirements()
    if missing:                      # installed without the companion extra
        print(f"asoc-companion needs {', '.join(missing)}: {INSTALL_HINT}", file=sys.stderr)
        return 1
    from . import build

    args = build_parser().parse_args(argv)
    if args.root:
        os.environ[paths.ENV_VAR] = os.path.abspath(args.root)     # notebook kernels inherit it
    try:
        signal.signal(signal.SIGTERM, build.terminate)
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
    from . import build
    from . import notebooks as nbs
    from .build import rel as _rel
    from .plan import make_plan

    paths.project()              # fail early, with the message, outside a checkout
    if args.command == "list":
        print(notebook_list(nbs.notebooks().values()))
        return 0
    if args.command in ("figure", "table", "run"):
        info = (nbs.by_name(args.name) if args.command == "run"
                else nbs.find(args.command, args.number))
        overrides = nbs.parse_overrides(info, args.parameter)
        plan = make_plan(paths.project(), info, args.fidelity, overrides)
        if not overrides:
            if args.fidelity == "full":
                build.run_and_record(plan)
            else:
                build.run_one(plan)
            return 0
        out = plan.output_dir
        build.run_one(plan)
        print(f"this run (figures, values, executed notebook): {_rel(out)}/")
        if args.command != "run":
            note = unused_parameters(info, args.command, args.number, overrides)
            if note:
                print(note)
        print(compare_with_committed(info.name, out, args.fidelity))
        return 0
    status = 0
    if args.command == "reproduce":
        status = build.reproduce(args.fidelity, args.force, args.jobs)
    _ledger(args.fidelity)
    return status


if __name__ == "__main__":
    sys.exit(main())
