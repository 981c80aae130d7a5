"""Figures for reading (issue 31, item 4): every saved figure is at most the printed width and
its text at least 9 pt there, and a caption that names a colour names one of the figure style's
palette (the colours the figure is drawn in), never a colour typed from the thesis's figure."""

import json
import re
import struct

import matplotlib
import pytest
from matplotlib.figure import Figure

from asoc_companion import figures
from asoc_companion.notebooks import notebooks
from asoc_companion.paths import FIGURES

COLOUR_WORDS = re.compile(
    r"\((?P<colour>[a-z ]+?)(?:,[^)]*)?\)"
    r"|\b(?P<plain>red|green|blue|orange|yellow|purple|vermillion|grey|gray|magenta"
    r"|cyan) (?:crosses|line|curve|dots|markers)\b"
)
"""A colour named in a caption: "(red)", "(red, covariances ...)" or "red crosses"."""
COLOURS = {
    "red",
    "green",
    "blue",
    "orange",
    "yellow",
    "purple",
    "black",
    "grey",
    "gray",
    "magenta",
    "cyan",
    "violet",
    "brown",
    "pink",
    *figures.PALETTE,
}


def test_a_wide_figure_is_shrunk_to_the_printed_width_with_legible_text(tmp_path):
    with matplotlib.rc_context(figures.STYLE):
        fig = Figure(figsize=(9.6, 3.6))
        ax = fig.add_subplot()
        ax.plot([0, 1], [0, 1], label="a line")
        ax.legend(fontsize=6)
        ax.set_xlabel("x", fontsize=7)
        png = figures.save_figure(fig, "own.9", tmp_path)
    width_px = struct.unpack(">I", png.read_bytes()[16:20])[0]
    assert width_px / figures.STYLE["savefig.dpi"] <= figures.PRINT_WIDTH_INCHES + 0.05
    sizes = [t.get_fontsize() for t in fig.findobj(matplotlib.text.Text) if t.get_text()]
    assert min(sizes) >= figures.MIN_FONT_POINTS


@pytest.mark.parametrize("layout", [None, "constrained"])
def test_content_outside_the_axes_is_printed_within_the_width(tmp_path, layout):
    # a legend beside the axes makes the saved (tight) PNG wider than the figure itself
    with matplotlib.rc_context(figures.STYLE):
        fig = Figure(figsize=(figures.PRINT_WIDTH_INCHES, 3.0), layout=layout)
        ax = fig.add_subplot()
        ax.plot([0, 1], [0, 1], label="a long legend label beside the axes")
        ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5))
        png = figures.save_figure(fig, "own.9", tmp_path)
    inches = struct.unpack(">I", png.read_bytes()[16:20])[0] / figures.STYLE["savefig.dpi"]
    assert figures.PRINT_WIDTH_INCHES - 0.5 < inches <= figures.PRINT_WIDTH_INCHES


def test_a_legend_wider_than_the_page_is_refused_with_a_reason(tmp_path):
    with matplotlib.rc_context(figures.STYLE):
        fig = Figure(figsize=(6.4, 3.0))
        ax = fig.add_subplot()
        for k in range(4):
            ax.plot([0, 1], [k, k], label=f"a long description of controller number {k}")
        ax.legend(ncol=4, loc="lower center", bbox_to_anchor=(0.5, 1.02))
        with pytest.raises(RuntimeError, match="more rows"):
            figures.save_figure(fig, "own.9", tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("number", [n for info in notebooks().values() for n in info.figures])
def test_committed_figures_print_at_most_the_text_width(number):
    """The committed PNG (saved at savefig.dpi) is no wider than the printed width, so its text,
    at least MIN_FONT_POINTS in the figure, is not scaled below that on the page. (Regenerated
    by `make book`.)"""
    png = FIGURES / f"{figures.file_stem('fig', number)}.png"
    width_px = struct.unpack(">I", png.read_bytes()[16:20])[0]
    inches = width_px / figures.STYLE["savefig.dpi"]
    assert inches <= figures.PRINT_WIDTH_INCHES + 0.05, f"Fig. {number} is {inches:.2f} in wide"


def test_colour_names_come_from_the_style():
    assert figures.colour_name("C0") == "blue" and figures.colour_name("C1") == "vermillion"
    with pytest.raises(ValueError, match="colour"):
        figures.colour_name("#123456")


def _caption_texts():
    for info in notebooks().values():
        cells = json.loads(info.path.read_text())["cells"]
        for k, cell in enumerate(cells):
            texts = ["".join(cell["source"])] if cell["cell_type"] == "markdown" else []
            texts += [
                "".join(o["data"]["text/markdown"])
                for o in cell.get("outputs", [])
                if "text/markdown" in o.get("data", {})
            ]
            for text in texts:
                if re.search(r"\*\*(Figure|Fig\.) ", text):
                    yield f"{info.name} cell {k}", text


def test_captions_name_only_the_palettes_colours():
    wrong = []
    for where, text in _caption_texts():
        for match in COLOUR_WORDS.finditer(text):
            colour = (match["colour"] or match["plain"]).strip()
            if colour in COLOURS and colour not in figures.PALETTE:
                wrong.append(f"{where}: {match[0]!r}")
    assert not wrong, "captions naming a colour the figure is not drawn in: " + "; ".join(wrong)
