"""One plotting style for every figure; atomic saving under the thesis's numbering.

A figure or table the thesis has is saved under its number ("3.4" -> ``fig3_4.png``); one
the thesis does not have (the own-system chapter) gets an id of its own, ``own.<n>``
("own.1" -> ``fig_own_1.png``), never a chapter number the thesis lacks.
"""

import csv
import io
import re
import struct
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt

from .atomic_files import atomic_write_bytes, atomic_write_text

__all__ = ["PALETTE", "PRINT_WIDTH_INCHES", "MIN_FONT_POINTS", "MIN_AXES_INCHES", "STYLE",
           "SAVE_METADATA",
           "apply_style", "colour_name", "fit_for_print", "NUMBER", "file_stem", "save_figure",
           "markdown_table", "save_table", "close"]


PALETTE = {"blue": "#0072B2", "vermillion": "#D55E00", "bluish green": "#009E73",
           "reddish purple": "#CC79A7", "orange": "#E69F00", "sky blue": "#56B4E9",
           "yellow": "#F0E442", "black": "#000000"}
"""The colour cycle (Okabe and Ito's colour-blind-safe palette) by the names captions use:
``C0`` is blue, ``C1`` vermillion, ... (:func:`colour_name`)."""

PRINT_WIDTH_INCHES = 6.2
"""The width a figure is printed at: the PDF's text width (A4 with 1 in margins is 6.27 in)."""
MIN_FONT_POINTS = 9
MIN_AXES_INCHES = 2.0
"""The narrowest figure :func:`save_figure` makes to fit content beside the axes in print."""
"""The smallest text size of a figure, in points at :data:`PRINT_WIDTH_INCHES`."""

STYLE = {
    "figure.figsize": (6.4, 4.0),
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "savefig.bbox": "tight",
    "font.size": 10,
    "axes.titlesize": 10,
    "axes.labelsize": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.fontsize": MIN_FONT_POINTS,
    "xtick.labelsize": MIN_FONT_POINTS,
    "ytick.labelsize": MIN_FONT_POINTS,
    "legend.frameon": False,
    "lines.linewidth": 1.5,
    "image.cmap": "viridis",
    "mathtext.fontset": "cm",
    "axes.prop_cycle": matplotlib.cycler(color=list(PALETTE.values())),
}


# No dates or producer strings in saved files: an unchanged figure gives identical bytes.
SAVE_METADATA = {"pdf": {"Creator": None, "Producer": None, "CreationDate": None, "ModDate": None},
                 "png": {"Software": None}}


def apply_style():
    """Apply the project's matplotlib style (called by :func:`asoc_companion.setup`).

    Returns
    -------
    None

    Examples
    --------
    >>> with matplotlib.rc_context():                 # leaves the global style as it was
    ...     apply_style()
    ...     print(matplotlib.rcParams["savefig.dpi"], matplotlib.rcParams["axes.grid"])
    150.0 True
    """
    matplotlib.rcParams.update(STYLE)


def colour_name(colour) -> str:
    """The palette's name of ``colour`` ("C1", a hex string or an RGB tuple), for a caption.

    Examples
    --------
    >>> colour_name("C1"), colour_name("#0072b2")
    ('vermillion', 'blue')
    """
    import matplotlib.colors as mcolors

    if isinstance(colour, str) and re.fullmatch(r"C\d+", colour):
        names = list(PALETTE)
        return names[int(colour[1:]) % len(names)]
    wanted = mcolors.to_hex(colour)
    for name, hex_ in PALETTE.items():
        if mcolors.to_hex(hex_) == wanted:
            return name
    raise ValueError(f"colour: {colour!r} is not a colour of the figure style's palette")


def fit_for_print(fig):
    """Make ``fig`` legible at the printed width: no wider than :data:`PRINT_WIDTH_INCHES`
    (a wider figure is shrunk, keeping its aspect ratio and re-laid out), and no text below
    :data:`MIN_FONT_POINTS`, so every text is printed at least that large.

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> fig = Figure(figsize=(9.6, 3.6))
    >>> ax = fig.add_subplot()
    >>> _ = ax.set_title("title", fontsize=7)
    >>> fit_for_print(fig)
    >>> float(fig.get_figwidth()), min(t.get_fontsize() for t in fig.findobj(matplotlib.text.Text))
    (6.2, 9.0)
    """
    import matplotlib.text

    width, height = fig.get_size_inches()
    if width > PRINT_WIDTH_INCHES:
        if fig.get_layout_engine() is None:
            fig.set_layout_engine("tight")
        fig.set_size_inches(PRINT_WIDTH_INCHES, height * PRINT_WIDTH_INCHES / width)
    for text in fig.findobj(matplotlib.text.Text):
        if text.get_text() and text.get_fontsize() < MIN_FONT_POINTS:
            text.set_fontsize(MIN_FONT_POINTS)


NUMBER = re.compile(r"(\d+)\.(\d+)|own\.(\d+)")


def file_stem(kind: str, number: str) -> str:
    """``fig3_4`` for ("fig", "3.4"), ``fig_own_1`` for ("fig", "own.1"); ValueError otherwise.

    Examples
    --------
    >>> file_stem("fig", "3.4"), file_stem("table", "own.1")
    ('fig3_4', 'table_own_1')
    >>> file_stem("fig", "A.1")
    Traceback (most recent call last):
    ...
    ValueError: number must look like '3.4' (thesis numbering) or 'own.1' (not in the thesis),
    found 'A.1'
    """
    match = NUMBER.fullmatch(str(number))
    if match is None:
        raise ValueError("number must look like '3.4' (thesis numbering) or 'own.1' (not in the "
                         f"thesis), found {number!r}")
    return f"{kind}{match[1]}_{match[2]}" if match[3] is None else f"{kind}_own_{match[3]}"


def save_figure(fig, number: str, output_dir):
    """Save ``fig`` as ``fig<chapter>_<n>.png`` and ``.pdf`` (atomically); return the PNG path.

    The figure is first made legible in print (:func:`fit_for_print`); the notebook then shows
    it at that size too.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    number : str
        Thesis number such as "3.4", or "own.1" for a figure the thesis does not have.
    output_dir : path
        The folder (a notebook run's: see :func:`asoc_companion.save_figure`).

    Returns
    -------
    pathlib.Path
        The PNG file.

    Raises
    ------
    ValueError
        If ``number`` does not look like "3.4" or "own.1".

    Examples
    --------
    >>> import tempfile
    >>> from matplotlib.figure import Figure
    >>> fig = Figure()
    >>> _ = fig.add_subplot().plot([0, 1], [1, 0])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     png = save_figure(fig, "own.1", folder)
    ...     print(png.name, sorted(p.name for p in Path(folder).iterdir()))
    fig_own_1.png ['fig_own_1.pdf', 'fig_own_1.png']
    """
    out = Path(output_dir)
    stem = file_stem("fig", number)
    fit_for_print(fig)
    png = _shrink_to_printed_width(fig)
    paths = [atomic_write_bytes(out / f"{stem}.png", png),
             atomic_write_bytes(out / f"{stem}.pdf", _render(fig, "pdf"))]
    return paths[0]


def _render(fig, ext) -> bytes:
    """The file ``fig`` saves to, cut to its drawn content (what the page prints)."""
    buf = io.BytesIO()
    fig.savefig(buf, format=ext, metadata=SAVE_METADATA[ext], bbox_inches="tight",
                dpi=STYLE["savefig.dpi"])
    return buf.getvalue()


def _shrink_to_printed_width(fig, attempts=6) -> bytes:
    """The PNG of ``fig``, made narrower until its drawn content (a legend or a label outside
    the axes included) is at most :data:`PRINT_WIDTH_INCHES` wide.

    Text keeps its size, so each attempt takes the measured excess off the figure's width.

    Raises
    ------
    RuntimeError
        If the content is still wider after ``attempts`` tries (text alone wider than a page).
    """
    for _ in range(attempts):
        png = _render(fig, "png")
        printed = struct.unpack(">I", png[16:20])[0] / STYLE["savefig.dpi"]
        if printed <= PRINT_WIDTH_INCHES:
            return png
        if fig.get_layout_engine() is None:       # first lay it out, then measure again
            fig.set_layout_engine("tight")
            continue
        width, height = fig.get_size_inches()
        narrower = width - (printed - PRINT_WIDTH_INCHES) - 0.02
        if narrower < MIN_AXES_INCHES:
            break
        fig.set_size_inches(narrower, height * narrower / width)
    raise RuntimeError(f"the figure's content stays {printed:.2f} in wide, more than the printed "
                       f"{PRINT_WIDTH_INCHES} in: text wider than the page (a legend in one row?) "
                       f"does not shrink with the figure; give it more rows")


def markdown_table(header, rows) -> str:
    """A GitHub-flavoured Markdown table from a header and rows of cells.

    Parameters
    ----------
    header : sequence
        Column titles.
    rows : sequence of sequences
        Cells, converted with ``str``.

    Returns
    -------
    str

    Raises
    ------
    TypeError
        If ``rows`` is not an iterable of iterables.

    Examples
    --------
    >>> print(markdown_table(["k", "rho"], [[0, 0.25], [1, 0.5]]), end="")
    | k | rho |
    |---|---|
    | 0 | 0.25 |
    | 1 | 0.5 |
    """
    lines = ["| " + " | ".join(map(str, header)) + " |",
             "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(map(str, row)) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def save_table(number: str, header, rows, output_dir) -> str:
    """Save a table as ``table<chapter>_<n>.csv`` and ``.md`` (atomically); return the Markdown.

    Parameters
    ----------
    number : str
        Thesis number such as "3.2", or "own.1" for a table the thesis does not have.
    header : sequence
        Column titles.
    rows : sequence of sequences
        One list of cells per row.
    output_dir : path
        The folder.

    Returns
    -------
    str
        The Markdown table.

    Raises
    ------
    ValueError
        If ``number`` does not look like "3.2" or "own.1", or a row has a different number of cells
        than
        ``header``.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     print(save_table("3.2", ["k", "rho"], [[0, 0.25]], folder), end="")
    ...     print((Path(folder) / "table3_2.csv").read_text(), end="")
    | k | rho |
    |---|---|
    | 0 | 0.25 |
    k,rho
    0,0.25
    """
    if any(len(row) != len(header) for row in rows):
        raise ValueError("rows: every row needs as many cells as header")
    out = Path(output_dir)
    stem = file_stem("table", number)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    atomic_write_text(out / f"{stem}.csv", buf.getvalue())
    md = markdown_table(header, rows)
    atomic_write_text(out / f"{stem}.md", md)
    return md


def close(fig):
    """Close ``fig`` after it has been shown and saved.

    Examples
    --------
    >>> fig = plt.figure()
    >>> close(fig)
    >>> plt.fignum_exists(fig.number)
    False
    """
    plt.close(fig)
