"""Command line: ``python -m asoc_companion list | figure N | table N | reproduce | ledger``.

Each command takes ``--fidelity full|ci``. ``full`` runs the thesis's settings and
updates ``figures/`` and the executed notebooks in ``book/``; ``ci`` runs small
Monte Carlo sizes and writes to ``book/_build/ci/`` only. ``reproduce`` re-executes a
notebook only when its inputs changed (``figures/values/manifest.json``; ``--force``
runs all). ``figure N -p name value`` runs with other parameters into
``book/_build/runs/<notebook>-<hash>/`` and never touches tracked files.
"""

import argparse
import sys
import time

from . import manifest
from . import notebooks as nbs
from .io import atomic_write_text
from .ledger import intro_markdown, ledger_markdown, ledger_rows
from .paths import BOOK, CI_OUTPUT, ROOT
from .values import load_all_values, load_values


def _run(info, fidelity, output_dir=None, overrides=None):
    start = time.perf_counter()
    print(f"running {info.path.name} ({info.title}) at fidelity={fidelity} ...", flush=True)
    executed = nbs.run(info, fidelity, output_dir=output_dir, overrides=overrides)
    print(f"  done in {time.perf_counter() - start:.1f} s -> {_rel(executed)}", flush=True)


def _rel(path) -> str:
    try:
        return str(path.resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def _run_tracked(info, fidelity, force):
    """Run ``info`` into its default folder unless its manifest entry is up to date."""
    out = nbs.default_output_dir(fidelity)
    params = nbs.harness_parameters(info, fidelity, out)
    changed = ["--force"] if force else manifest.changed_inputs(info, params, out)
    if not changed:
        print(f"{info.path.name}: up to date, skipped", flush=True)
        return
    print(f"{info.path.name}: changed: {', '.join(changed)}", flush=True)
    _run(info, fidelity)
    manifest.update_manifest(info, params, out)


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
    path, values = (BOOK / "ledger.md", load_all_values()) if fidelity == "full" \
        else (CI_OUTPUT / "ledger.md", load_all_values(CI_OUTPUT))
    _write_if_changed(path, ledger_markdown(values=values),
                      "" if fidelity == "full" else " (ci fidelity: Monte Carlo cells use small samples)")
    if fidelity == "full":
        intro = BOOK / "intro.md"
        _write_if_changed(intro, intro_markdown(intro.read_text(), ledger_rows(values=values)), " (summary)")


def _write_if_changed(path, text, remark=""):
    if path.exists() and path.read_text() == text:
        print(f"{_rel(path)}: up to date")
        return
    atomic_write_text(path, text)
    print(f"wrote {_rel(path)}{remark}")


def _overrides(pairs, info) -> dict:
    return nbs.check_overrides(info, {name: nbs.parse_value(value) for name, value in pairs or ()})


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m asoc_companion", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_ in [("list", "list notebooks, figures and tables"),
                        ("reproduce", "run every notebook whose inputs changed, then write the ledger"),
                        ("ledger", "write the ledger page from the recorded values")]:
        p = sub.add_parser(name, help=help_)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
        if name == "reproduce":
            p.add_argument("--force", action="store_true", help="re-execute every notebook")
    for name in ("figure", "table"):
        p = sub.add_parser(name, help=f"regenerate one {name} by its thesis number, e.g. 3.4")
        p.add_argument("number")
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
        p.add_argument("-p", "--parameter", nargs=2, action="append", metavar=("NAME", "VALUE"),
                       help="override a parameter of the notebook (papermill's -p); "
                            "the run goes to book/_build/runs/, tracked files stay unchanged")
    args = parser.parse_args(argv)

    if args.command == "list":
        for info in nbs.notebooks().values():
            figs = ", ".join(f"Fig. {f}" for f in info.figures)
            tabs = ", ".join(f"Table {t}" for t in info.tables)
            params = ", ".join(n for n in nbs.default_parameters(info) if n not in nbs.HARNESS_PARAMETERS)
            print(f"{info.name:10s} {info.title}\n{'':10s} {'; '.join(x for x in (figs, tabs) if x)}\n"
                  f"{'':10s} parameters (-p): {params}")
        return 0
    if args.command in ("figure", "table"):
        try:
            info = nbs.find(args.command, args.number)
            overrides = _overrides(args.parameter, info)
        except ValueError as err:
            print(err, file=sys.stderr)
            return 2
        if not overrides:
            _run(info, args.fidelity)
            if args.fidelity == "full":
                out = nbs.default_output_dir("full")
                manifest.update_manifest(info, nbs.harness_parameters(info, "full", out), out)
            return 0
        out = nbs.run_folder(info, args.fidelity, overrides)
        _run(info, args.fidelity, output_dir=out, overrides=overrides)
        print(f"this run (figures, values, executed notebook): {_rel(out)}/")
        print(compare_with_committed(info.name, out))
        return 0
    if args.command == "reproduce":
        for info in nbs.build_order(nbs.notebooks().values()):
            _run_tracked(info, args.fidelity, args.force)
    _ledger(args.fidelity)
    return 0


if __name__ == "__main__":
    sys.exit(main())
