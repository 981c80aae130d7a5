"""The companion's tooling: record values, save figures and tables, build the ledger and the book.

It is a package of its own: the library ``asoc`` never imports it (a test checks the
import graph). Typical notebook use::

    import asoc_companion as repro
    repro.setup("sec3_5", fidelity=fidelity, output_dir=output_dir)   # starts the active Recorder
    repro.record("rho_open_T1", rho)          # a number the thesis prints
    repro.save_figure(fig, "3.4")             # fig3_4.png and .pdf ("own.1": fig_own_1.*)
    md = repro.save_table("3.2", header, rows)

The project (book, figures, reference data) is found by :mod:`asoc_companion.paths`:
``$ASOC_COMPANION_ROOT`` or the nearest checkout above the current directory.
"""

from asoc.stats import bootstrap_ci, bootstrap_median_ci, settling_iteration

from .requirements import INSTALL_HINT, missing_requirements

if missing_requirements():
    # a library-only install (`pip install asoc`): the command line says what to install in one
    # line (asoc_companion.__main__), and so does every use of the package
    def __getattr__(name):
        if name not in __all__:
            raise AttributeError(f"module 'asoc_companion' has no attribute {name!r}")
        raise ModuleNotFoundError(f"asoc_companion.{name} needs "
                                  f"{', '.join(missing_requirements())}: {INSTALL_HINT}")
else:
    from .captions import figure_caption
    from .figures import STYLE, apply_style, markdown_table
    from .ledger import ledger_markdown, write_ledger
    from .prose import fill, prose
    from .recorder import Recorder, active, record, save_figure, save_table, setup
    from .reference import Entry, load_reference, status
    from .values import CorruptValuesError, load_all_values, load_values

__all__ = ["figure_caption", "STYLE", "apply_style", "markdown_table", "save_figure", "save_table",
           "ledger_markdown", "write_ledger", "fill", "prose", "Entry", "load_reference", "status",
           "bootstrap_ci", "bootstrap_median_ci", "settling_iteration", "load_all_values",
           "load_values",
           "CorruptValuesError", "Recorder", "active", "record", "setup"]
