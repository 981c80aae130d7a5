"""The book in print: which notebook cells the PDF leaves out, and `make pdf`'s short summary.

The notebooks are rendered from their committed cells, so the rules apply when the book is
built (a Sphinx ``doctree-resolved`` hook, ``_prune_cells``), never by editing a notebook:

- papermill's injected-parameters cell (tag ``injected-parameters``) repeats the parameters
  cell above it; it is left out of every builder's output;
- a *setup cell* (:func:`is_setup_cell`: it imports the companion or calls ``setup``) is
  printed as one line naming the notebook to open instead of its code; its output stays.
  The cells after it, the method's code that the text discusses, stay as they are.

Record cells are tagged ``remove-cell`` in the notebooks and never rendered.

``python -m asoc_companion.printing`` builds the PDF (:func:`build_pdf`) and prints a summary
instead of the LaTeX log: pages, time, the overfull boxes over 10 pt and where the log is.
"""

import ast
import re
import subprocess
import sys
import time
from pathlib import Path

from docutils import nodes

from . import paths

__all__ = ["INJECTED_TAG", "OVERFULL", "OVERFULL_LIMIT", "is_setup_cell", "TEXT_WIDTH_CHARACTERS",
           "COLUMN_CAP", "prune_doctree", "LATEX_PREAMBLE", "overfull_boxes", "build_pdf"]


INJECTED_TAG = "injected-parameters"
"""papermill's tag of the cell it inserts below the parameters cell."""
OVERFULL = re.compile(r"^Overfull \\hbox \((?P<points>[\d.]+)pt too wide\)", re.M)
"""An overfull line box in a LaTeX log, with its excess width."""
OVERFULL_LIMIT = 10.0
"""Excess width (pt) above which an overfull box is visible on the page."""


def is_setup_cell(source: str) -> bool:
    """Whether a code cell sets a notebook up: it imports ``asoc_companion`` or calls ``setup``.

    Examples
    --------
    >>> is_setup_cell("import numpy as np\\nimport asoc_companion as repro")
    True
    >>> is_setup_cell('out = repro.setup("theorems", fidelity=fidelity)')
    True
    >>> is_setup_cell("from asoc_companion.theorems.kernels import gram_certificate\\nx = 1")
    False
    >>> is_setup_cell("%matplotlib inline")
    False
    """
    try:
        tree = ast.parse(source)
    except SyntaxError:                 # IPython magics: no setup cell of this book has one
        return False
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name == "asoc_companion" for a in node.names):
            return True
        if isinstance(node, ast.Call):
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if name == "setup":
                return True
    return False


def _notebook_name(cell, docname: str) -> str:
    source = cell.source or cell.get("source") or docname
    return f"book/{Path(source).stem}.ipynb"


def _setup_note(notebook: str) -> nodes.paragraph:
    """The line printed in place of a setup cell's code."""
    note = nodes.paragraph(classes=["setup-note"])
    note += nodes.emphasis(text=f"Setup code (imports, parameters read, asoc_companion.setup) "
                                f"not printed: open {notebook} to read or run it.")
    return note


def _prune_cells(doctree, builder_format: str, docname: str = "") -> dict:
    """Apply the print rules to a resolved doctree; return how many cells each rule changed.

    ``builder_format`` is the Sphinx builder's format: injected-parameters cells are removed
    for every builder, setup cells' code for ``"latex"`` only.
    """
    changed = {"injected": 0, "setup": 0}
    for cell in list(doctree.findall(nodes.container)):
        if cell.get("nb_element") != "cell_code":
            continue
        tags = cell.get("cell_metadata", {}).get("tags", [])
        if INJECTED_TAG in tags:
            cell.parent.remove(cell)
            changed["injected"] += 1
            continue
        if builder_format != "latex":
            continue
        for source in [c for c in cell.children if c.get("nb_element") == "cell_code_source"]:
            code = "".join(block.astext() for block in source.findall(nodes.literal_block))
            if is_setup_cell(code):
                cell.replace(source, _setup_note(_notebook_name(cell, docname)))
                changed["setup"] += 1
    return changed


TEXT_WIDTH_CHARACTERS = 80
"""Characters of body text a printed line holds (A4, Sphinx's margins, 10 pt FreeSerif)."""
COLUMN_CAP = 40
"""A column wider than this many characters is wrapped rather than given its natural width."""


def _column_widths(longest, words, width: int = TEXT_WIDTH_CHARACTERS):
    """Relative widths of a table's columns (characters) from each column's longest cell and
    longest word, and whether the table needs the small font to fit ``width`` characters.

    Each column gets at least its longest word (up to the cap) and the cell padding (3
    characters); what the
    line has left goes to the columns with longer cells, up to :data:`COLUMN_CAP`. When the
    words alone do not fit, the table is set in the small font (a quarter more characters).

    Examples
    --------
    >>> _column_widths([60, 60], [10, 10])
    ([40.0, 40.0], False)
    >>> _column_widths([8] * 10, [8] * 10)
    ([11.0, 11.0, 11.0, 11.0, 11.0, 11.0, 11.0, 11.0, 11.0, 11.0], True)
    """
    least = [min(w, COLUMN_CAP) + 3 for w in words]
    wants = [max(m, min(n, COLUMN_CAP)) for m, n in zip(least, longest)]
    small = sum(least) > width
    room = width * 1.25 if small else width
    spare, extra = room - sum(least), [w - m for w, m in zip(wants, least)]
    if spare <= 0 or not sum(extra):
        return [float(m) for m in least], small
    share = min(1.0, spare / sum(extra))
    return [m + share * e for m, e in zip(least, extra)], small


def _fit_wide_tables(doctree, width: int = TEXT_WIDTH_CHARACTERS) -> int:
    """Give every table that would run past the margin column widths, so LaTeX wraps its cells.

    Sphinx sets a long table without declared widths in ``l`` columns, which never wrap; a
    table whose longest cells add up to more than ``width`` characters gets the widths of
    ``_column_widths``, and the small font when it needs it. Returns how many tables
    were changed.
    """
    changed = 0
    for table in list(doctree.findall(nodes.table)):
        if "colwidths-given" in table["classes"]:
            continue
        for group in table.findall(nodes.tgroup):
            specs = [c for c in group.children if isinstance(c, nodes.colspec)]
            longest, words = [0] * len(specs), [0] * len(specs)
            for row in group.findall(nodes.row):
                for k, entry in enumerate(row.children[:len(specs)]):
                    text = entry.astext()
                    longest[k] = max(longest[k], len(text))
                    words[k] = max([words[k]] + [len(w) for w in text.split()])
            if sum(longest) <= width:
                continue
            widths, small = _column_widths(longest, words, width)
            for spec, chars in zip(specs, widths):
                spec["colwidth"] = max(1, round(10 * chars))
            table["classes"].append("colwidths-given")
            if small:
                index = table.parent.index(table)
                table.parent.insert(index + 1, nodes.raw("", r"\endgroup", format="latex"))
                small_font = nodes.raw("", r"\begingroup\footnotesize", format="latex")
                table.parent.insert(index, small_font)
            changed += 1
    return changed


def prune_doctree(app, doctree, docname):
    """Sphinx's ``doctree-resolved`` hook: ``_prune_cells`` for the running builder, and
    ``_fit_wide_tables`` for the LaTeX builder.
    """
    _prune_cells(doctree, app.builder.format, docname)
    if app.builder.format == "latex":
        _fit_wide_tables(doctree)


LATEX_PREAMBLE = r"""
% identifiers break after an underscore (API names, record keys) instead of running past the margin
\DeclareRobustCommand{\_}{\textunderscore\hspace{0pt}}
"""
"""LaTeX for the preamble of the PDF (Sphinx's ``latex_elements["preamble"]``)."""


def overfull_boxes(log: str, limit: float = OVERFULL_LIMIT) -> list:
    """The excess widths (pt) of the overfull line boxes in a LaTeX log wider than ``limit``.

    Examples
    --------
    >>> log = "Overfull \\\\hbox (12.5pt too wide) in par\\nOverfull \\\\hbox (1.2pt too wide)"
    >>> overfull_boxes(log)
    [12.5]
    """
    return [p for p in map(float, OVERFULL.findall(log)) if p > limit]


def build_pdf(book=None, options=(), output_folder=None, out=sys.stdout) -> int:
    """Build the PDF with Jupyter Book's LaTeX builder; print a summary, not the log.

    ``options`` are passed to ``jupyter-book build`` (e.g. ``["--all"]``); the build goes to
    ``output_folder/_build`` (default: the book's folder). The builder's output is saved as
    ``_build/latex/build-output.txt`` beside LaTeX's own log; on failure its last lines are
    printed. Returns the builder's exit status.
    """
    book = Path(book or paths.project().book)
    folder = Path(output_folder or book)
    latex = folder / "_build" / "latex"
    jupyter_book = Path(sys.executable).parent / "jupyter-book"
    start = time.perf_counter()
    where = ["--path-output", str(folder)] if output_folder else []
    command = [str(jupyter_book), "build", str(book), "--builder", "pdflatex", *where, *options]
    proc = subprocess.run(command, capture_output=True, text=True, timeout=1800)
    seconds = time.perf_counter() - start
    latex.mkdir(parents=True, exist_ok=True)
    output = latex / "build-output.txt"
    output.write_text(proc.stdout + proc.stderr)
    pdf, log = latex / "asoc-companion.pdf", latex / "asoc-companion.log"
    if proc.returncode != 0 or not pdf.exists():
        tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-25:])
        print(f"{tail}\nThe PDF build failed after {seconds:.0f} s; the whole output: {output}",
              file=out)
        return proc.returncode or 1
    info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True).stdout
    pages = re.search(r"Pages:\s+(\d+)", info)
    boxes = overfull_boxes(log.read_text(errors="replace")) if log.exists() else []
    print(f"The PDF is at {pdf}: {pages[1] if pages else '?'} pages, built in "
          f"{seconds:.0f} s, {len(boxes)} overfull boxes over {OVERFULL_LIMIT:g} pt.\n"
          f"LaTeX's log: {log}; the builder's output: {output}", file=out)
    return 0


if __name__ == "__main__":
    sys.exit(build_pdf(options=sys.argv[1:]))
