"""Command line: ``python -m asoc list | figure N | table N | reproduce | ledger``.

Each command takes ``--fidelity full|ci``. ``full`` runs the thesis's settings and
updates ``figures/`` and the executed notebooks in ``book/``; ``ci`` runs small
Monte Carlo sizes and writes to ``book/_build/ci/`` only.
"""

import argparse
import sys
import time

from .repro import notebooks as nbs
from .repro.ledger import write_ledger
from .repro.paths import CI_OUTPUT


def _run(infos, fidelity):
    for info in infos:
        start = time.perf_counter()
        print(f"running {info.path.name} ({info.title}) at fidelity={fidelity} ...", flush=True)
        executed = nbs.run(info, fidelity)
        print(f"  done in {time.perf_counter() - start:.1f} s -> {executed}", flush=True)


def _ledger(fidelity):
    if fidelity == "full":
        write_ledger()
        print("wrote book/ledger.md")
    else:
        from .repro.ledger import ledger_markdown
        from .repro.values import load_all_values
        from .repro.io import atomic_write_text
        path = CI_OUTPUT / "ledger.md"
        atomic_write_text(path, ledger_markdown(values=load_all_values(CI_OUTPUT)))
        print(f"wrote {path} (ci fidelity: Monte Carlo cells use small samples)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m asoc", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_ in [("list", "list notebooks, figures and tables"),
                        ("reproduce", "run every notebook, then write the ledger"),
                        ("ledger", "write the ledger page from the recorded values")]:
        p = sub.add_parser(name, help=help_)
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
    for name in ("figure", "table"):
        p = sub.add_parser(name, help=f"regenerate one {name} by its thesis number, e.g. 3.4")
        p.add_argument("number")
        p.add_argument("--fidelity", choices=("full", "ci"), default="full")
    args = parser.parse_args(argv)

    if args.command == "list":
        for info in nbs.notebooks().values():
            figs = ", ".join(f"Fig. {f}" for f in info.figures)
            tabs = ", ".join(f"Table {t}" for t in info.tables)
            print(f"{info.name:10s} {info.title}\n{'':10s} {'; '.join(x for x in (figs, tabs) if x)}")
        return 0
    if args.command in ("figure", "table"):
        try:
            info = nbs.find(args.command, args.number)
        except ValueError as err:
            print(err, file=sys.stderr)
            return 2
        _run([info], args.fidelity)
        return 0
    if args.command == "reproduce":
        _run(nbs.notebooks().values(), args.fidelity)
    _ledger(args.fidelity)
    return 0


if __name__ == "__main__":
    sys.exit(main())
