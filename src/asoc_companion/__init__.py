"""Reproduction harness: record values, save figures and tables, build the ledger.

Typical notebook use::

    import asoc_companion as repro
    repro.setup("sec3_5", fidelity=fidelity, output_dir=output_dir)
    repro.record("rho_open_T1", rho)          # a number the thesis prints
    repro.save_figure(fig, "3.4")             # figures/fig3_4.png and .pdf
    md = repro.save_table("3.2", header, rows)
"""

from .captions import figure_caption
from .figures import STYLE, apply_style, markdown_table, save_figure, save_table
from .ledger import ledger_markdown, write_ledger
from .prose import fill, prose
from .reference import Entry, load_reference, status
from asoc.stats import bootstrap_ci, bootstrap_median_ci, settling_iteration
from .values import load_all_values, load_values, record, setup

__all__ = ["figure_caption", "STYLE", "apply_style", "markdown_table", "save_figure", "save_table",
           "ledger_markdown", "write_ledger", "fill", "prose", "Entry", "load_reference", "status",
           "bootstrap_ci", "bootstrap_median_ci", "settling_iteration", "load_all_values", "load_values", "record", "setup"]
