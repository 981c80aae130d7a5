"""The whole book as one PDF (`make pdf`): built once per session from the committed notebooks
with XeLaTeX, then read with poppler-utils. It has a title page naming the thesis, the
licences and the software's version; a bookmark for every page and every finding; every
figure as an image and every thesis table; and no glyph missing from its fonts. It prints
no HTML-only output as its repr, no papermill parameters cell and no setup code (a line names
the notebook instead); at most 5 lines run more than 10 pt past the margin; and the build
prints a short summary instead of LaTeX's log."""

import io
import json
import re
import shutil
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

from asoc_companion.notebooks import notebooks
from asoc_companion.paths import BOOK
from asoc_companion.printing import OVERFULL_LIMIT, build_pdf, is_setup_cell, overfull_boxes

TOOLS = ("xelatex", "latexmk", "pdfinfo", "pdftotext", "pdfimages", "pdftohtml")


@pytest.fixture(scope="session")
def pdf(tmp_path_factory):
    """The PDF built once per session; its path (the LaTeX log lies beside it)."""
    missing = [t for t in TOOLS if shutil.which(t) is None]
    if missing:
        pytest.fail(
            f"{', '.join(missing)} missing: `make tex` installs Debian's TeX Live and poppler-utils"
        )
    out = tmp_path_factory.mktemp("pdf")
    subprocess.run([sys.executable, "-m", "asoc_companion.book"], check=True, capture_output=True)
    summary = io.StringIO()
    status = build_pdf(BOOK, output_folder=out, out=summary)
    path = out / "_build" / "latex" / "asoc-companion.pdf"
    assert status == 0 and path.exists(), summary.getvalue()
    (out / "summary.txt").write_text(summary.getvalue())
    return path


def _text(pdf_path, *pages) -> str:
    first_last = ["-f", str(pages[0]), "-l", str(pages[-1])] if pages else []
    return subprocess.run(
        ["pdftotext", "-layout", *first_last, str(pdf_path), "-"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout


def bookmarks(pdf_path) -> list:
    """The titles of the PDF's outline (bookmarks), read by pdftohtml's XML output."""
    xml = subprocess.run(
        ["pdftohtml", "-xml", "-i", "-stdout", "-q", str(pdf_path)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    outline = xml[xml.find("<outline>") :]
    return [
        re.sub(r"<[^>]+>", "", t).strip()
        for t in re.findall(r"<item[^>]*>(.*?)</item>", outline, re.S)
    ]


def _words(text: str) -> str:
    """Letters and digits only, lower case: headings compared across Markdown, TeX and PDF."""
    return re.sub(r"[^a-z0-9]+", "", text.lower())


def _headings(path: Path, level: str) -> list:
    cells = json.loads(path.read_text())["cells"]
    return [
        line[len(level) + 1 :]
        for c in cells
        if c["cell_type"] == "markdown"
        for line in "".join(c["source"]).splitlines()
        if line.startswith(level + " ")
    ]


@pytest.mark.book
def test_title_page_names_the_thesis_licences_and_version(pdf):
    first = " ".join(_text(pdf, 1).split())
    title = re.search(r'^title: "(.+)"', (BOOK / "_config.yml").read_text(), re.M)[1]
    assert title in first, f"the title page lacks the book's title {title!r}: {first[:200]!r}"
    thesis = (
        "Approximate Stochastic Optimal Control of Smooth Nonlinear Systems and "
        "Piecewise Linear Systems"
    )
    assert thesis in first
    assert "Maxim Dolgov" in first and "CC BY-NC 4.0" in first and "MIT" in first
    assert f"asoc version {version('asoc')}" in first


@pytest.mark.book
def test_bookmarks_for_every_page_and_finding(pdf):
    marks = {_words(b) for b in bookmarks(pdf)}
    titles = [_headings(info.path, "#")[0] for info in notebooks().values()]
    titles += [
        re.search(r"^# (.+)$", (BOOK / f"{page}.md").read_text(), re.M)[1]
        for page in ("ledger", "architecture", "api", "api_mjls")
    ]
    markdown = "\n".join(
        "".join(c["source"])
        for c in json.loads((BOOK / "findings.ipynb").read_text())["cells"]
        if c["cell_type"] == "markdown"
    )
    findings = re.findall(r"\(finding-[\w-]+\)=\s*\n##\s+(.+)", markdown)
    assert len(findings) >= 11
    # a bookmark drops TeX and formatting: compare the first words of each heading
    missing = [t for t in titles + findings if not any(m.startswith(_words(t)[:24]) for m in marks)]
    assert not missing, f"no bookmark for {missing}"


@pytest.mark.book
def test_every_figure_and_table_is_in_the_pdf(pdf):
    n_figures = sum(len(info.figures) for info in notebooks().values())
    images = subprocess.run(
        ["pdfimages", "-list", str(pdf)], capture_output=True, text=True, check=True
    ).stdout
    n_images = len(images.splitlines()) - 2  # two header lines
    assert n_images >= n_figures, f"{n_images} images for {n_figures} figures"
    text = _text(pdf)
    tables = [t for info in notebooks().values() for t in info.tables]
    missing = [t for t in tables if f"Table {t}" not in text]
    assert tables and not missing, f"tables not in the PDF: {missing}"
    pages = int(
        re.search(
            r"Pages:\s+(\d+)",
            subprocess.run(
                ["pdfinfo", str(pdf)], capture_output=True, text=True, check=True
            ).stdout,
        )[1]
    )
    assert pages > 100, f"only {pages} pages"


@pytest.mark.book
def test_no_missing_glyphs(pdf):
    log = pdf.with_suffix(".log").read_text(errors="replace")
    missing = sorted(set(re.findall(r"Missing character: There is no (.+?) in font", log)))
    assert not missing, f"characters the PDF's fonts lack: {missing}"


# ---- a PDF a reader can read from cover to cover (issue 31, item 1) ---------------------------

MAX_OVERFULL = 5
"""Lines allowed to run more than OVERFULL_LIMIT past the margin."""


@pytest.mark.book
def test_no_html_repr_in_the_latex(pdf):
    # "<" is \PYGZlt{} in a listing, \textless{} in text
    tex = pdf.with_suffix(".tex").read_text()
    found = re.findall(r"IPython\.core\.display\.\w+ object|[\w.]+ object at 0x[0-9a-f]+", tex)
    reprs = sorted(set(found))
    assert not reprs, f"outputs printed as their repr (an HTML-only display?): {reprs}"


@pytest.mark.book
def test_no_injected_parameters_and_no_setup_code(pdf):
    text = _text(pdf)
    assert "# Parameters" not in text, "papermill's injected-parameters cell is printed"
    for info in notebooks().values():
        cells = json.loads(info.path.read_text())["cells"]
        setup = [
            c
            for c in cells
            if c["cell_type"] == "code"
            and is_setup_cell("".join(c["source"]))
            and not {"remove-cell", "remove-input"} & set(c["metadata"].get("tags", []))
        ]
        if setup:
            assert f"open book/{info.path.name}" in text, f"no line names {info.path.name}"
    tex = pdf.with_suffix(".tex").read_text()
    # repro.setup(...) and import asoc_companion as repro, as Pygments marks them up
    setup_code = (
        r"\PYG{n}{repro}\PYG{o}{.}\PYG{n}{setup}",
        r"\PYG{n+nn}{asoc\PYGZus{}companion}\PYG{+w}{ }\PYG{k}{as}"
        r"\PYG{+w}{ }\PYG{n+nn}{repro}",
    )
    assert not any(code in tex for code in setup_code), "setup code is printed"
    # the method's code stays: a cell the text discusses, after the setup cell
    assert "sigma_point_linearizations()" in text


@pytest.mark.book
def test_theorems_table_is_in_the_pdf(pdf):
    text = " ".join(_text(pdf).split())
    assert "Theorem 3.19" in text and "One instance checks:" in text
    assert "Corrected statement:" in text


@pytest.mark.book
def test_few_lines_run_past_the_margin(pdf):
    boxes = overfull_boxes(pdf.with_suffix(".log").read_text(errors="replace"))
    assert len(boxes) <= MAX_OVERFULL, f"{len(boxes)} lines {OVERFULL_LIMIT} pt too wide: {boxes}"


@pytest.mark.book
def test_the_build_prints_a_summary_not_the_log(pdf):
    summary = (pdf.parents[2] / "summary.txt").read_text()
    assert len(summary.splitlines()) <= 3, summary
    assert re.search(r"\d+ pages, built in \d+ s", summary)
    assert str(pdf.with_suffix(".log")) in summary
