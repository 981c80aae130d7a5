"""Build the HTML book from the committed notebooks and open pages in headless Chromium:
math must be typeset by MathJax, every image must load (natural width > 0), no table is wider
than its container in a 1280-px window, every internal link of the intro, findings and ledger
pages resolves to an existing anchor, and the intro reaches every finding in one click."""

import json
import re
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from asoc_companion.notebooks import notebooks
from asoc_companion.paths import BOOK

NOTEBOOK_PAGES = [f"{name}.html" for name in notebooks()]
PAGES = NOTEBOOK_PAGES + ["intro.html", "ledger.html"]


def _wait_for_math(driver, timeout=30):
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, timeout).until(
        lambda d: d.execute_script(
            "return window.MathJax && MathJax.startup && MathJax.startup.promise"
            " ? (MathJax.startup.promise.then(() => window.__mjdone = true),"
            " window.__mjdone === true)"
            " : false"
        )
    )


@pytest.mark.book
@pytest.mark.parametrize("page", PAGES)
def test_page_renders_math_and_images(html, browser, page):
    path = html / page
    assert path.exists(), f"{page} was not built"
    browser.get(path.as_uri())
    n_math_src = browser.execute_script(
        "return document.querySelectorAll('.math, mjx-container').length"
    )
    if page in NOTEBOOK_PAGES:
        assert n_math_src > 0, f"{page}: no math on the page"
        _wait_for_math(browser)
        rendered = browser.execute_script(
            "return document.querySelectorAll('mjx-container').length"
        )
        raw = browser.execute_script(
            "return Array.from(document.querySelectorAll('.math')).filter("
            "e => !e.querySelector('mjx-container') && e.textContent.includes('\\\\')).length"
        )
        assert rendered > 0 and raw == 0, f"{page}: {rendered} typeset, {raw} left as raw TeX"
    browser.execute_script("window.scrollTo(0, document.body.scrollHeight)")
    images = browser.execute_script(
        "return Array.from(document.images).map(i => [i.src, i.complete, i.naturalWidth])"
    )
    info = notebooks().get(page.removesuffix(".html"))
    if info is not None:
        assert len(images) >= len(info.figures), (
            f"{page}: expected its {len(info.figures)} figures, found {len(images)} images"
        )
    broken = [src for src, complete, width in images if not (complete and width > 0)]
    assert not broken, f"{page}: images that did not load: {broken}"


@pytest.mark.book
@pytest.mark.parametrize("page", PAGES)
def test_no_table_wider_than_its_container_at_1280px(html, browser, page):
    browser.get((html / page).as_uri())
    assert browser.execute_script("return window.innerWidth") <= 1280
    wide = browser.execute_script("""
        return Array.from(document.querySelectorAll('article table')).map(t => {
            const box = t.closest('.pst-scrollable-table-container') || t.parentElement;
            return [t.id || t.className, t.scrollWidth, box.clientWidth, box.scrollWidth];
        }).filter(([_, tw, cw, sw]) => tw > cw || sw > cw);""")
    assert not wide, (
        f"{page}: tables wider than their container "
        f"[table, scrollWidth, clientWidth, box scrollWidth]: {wide}"
    )


def _ids(path: Path) -> set:
    return set(re.findall(r'\sid="([^"]+)"', path.read_text()))


@pytest.mark.book
@pytest.mark.parametrize("page", ["intro.html", "findings.html", "theorems.html", "ledger.html"])
def test_internal_links_resolve(html, browser, page):
    browser.get((html / page).as_uri())
    hrefs = browser.execute_script(
        "return Array.from(document.querySelectorAll('article a[href]')).map(a => a.href)"
    )
    broken, checked = [], 0
    for href in hrefs:
        url = urlparse(href)
        if url.scheme != "file" or not unquote(url.path).startswith(str(html)):
            continue
        target = Path(unquote(url.path))
        checked += 1
        if not target.exists():
            broken.append(href)
        elif url.fragment and url.fragment not in _ids(target):
            broken.append(href)
    assert checked > 10, f"{page}: only {checked} internal links found"
    assert not broken, f"{page}: links to missing pages or anchors: {broken}"


@pytest.mark.book
def test_intro_summarises_and_reaches_every_finding(html, browser):
    browser.get((html / "intro.html").as_uri())
    n_badges = browser.execute_script(
        "return document.querySelectorAll('article .sd-badge').length"
    )
    assert n_badges >= 3 * len([n for n in notebooks() if n.startswith("sec")]), (
        "status badges missing"
    )
    links = set(
        browser.execute_script(
            "return Array.from(document.querySelectorAll(`article a[href*='findings.html#']`))"
            ".map(a => a.href.split('#')[1])"
        )
    )
    anchors = _ids(html / "findings.html")
    labels = re.findall(r"\((finding-[\w-]+)\)=", (BOOK / "findings.ipynb").read_text())
    assert len(labels) >= 11 and set(labels) <= anchors, "findings sections lack their anchors"
    assert links == set(labels), f"intro does not link every finding: missing {set(labels) - links}"


@pytest.mark.book
@pytest.mark.parametrize("name", [n for n, i in notebooks().items() if i.figures])
def test_every_rendered_figure_caption_states_the_claim(html, browser, name):
    cells = json.loads(notebooks()[name].path.read_text())["cells"]
    rendered = sum(
        1 for c in cells if "figure_caption(" in "".join(c["source"]) and c.get("outputs")
    )
    browser.get((html / f"{name}.html").as_uri())
    captions = browser.execute_script(
        "return Array.from(document.querySelectorAll('.asoc-caption')).map(e => e.textContent)"
    )
    assert len(captions) == rendered, (
        f"{name}: {len(captions)} captions shown, {rendered} caption cells executed"
    )
    assert all("the thesis" in c and "Ours:" in c for c in captions)


# ---- a light site with a clean console (issue 25, item 1) -------------------------------------

JS_BUDGET = 3_000_000  # bytes of JavaScript a page may load (3 MB)


def _all_pages(html):
    return sorted(p.name for p in html.glob("*.html"))


def _load_and_log(browser, path):
    """Open ``path``; return (requests [(url, type)], console errors) of this page load alone."""
    from selenium.webdriver.support.ui import WebDriverWait

    browser.get_log("performance"), browser.get_log("browser")  # drop what earlier pages left
    browser.get(path.as_uri())  # returns after the load event: deferred and async scripts ran
    WebDriverWait(browser, 10).until(
        lambda d: d.execute_script("return document.readyState") == "complete"
    )
    if browser.execute_script(
        "return !!(window.MathJax && MathJax.startup && MathJax.startup.promise)"
    ):
        _wait_for_math(browser)
    requests = []
    for entry in browser.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        if message["method"] == "Network.requestWillBeSent":
            requests.append((message["params"]["request"]["url"], message["params"].get("type")))
    errors = [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    return requests, errors


def javascript_bytes(requests) -> int:
    """Bytes of the distinct script files among ``requests`` (file: URLs, read from disk; a
    missing file is a console error, counted there)."""
    files = {Path(unquote(urlparse(url).path)) for url, kind in requests if kind == "Script"}
    return sum(f.stat().st_size for f in files if f.is_file())


@pytest.mark.book
def test_every_page_is_light_offline_and_has_a_clean_console(html, browser):
    """Every page: at most 3 MB of JavaScript, no console error, no request to a non-file: URL
    (the site works offline, no CDN), and no horizontal scroll at 400 px."""
    faults = []
    for name in _all_pages(html):
        browser.set_window_size(1280, 900)
        requests, errors = _load_and_log(browser, html / name)
        n_js = javascript_bytes(requests)
        remote = [url for url, _ in requests if not url.startswith(("file:", "data:", "blob:"))]
        if n_js > JS_BUDGET:
            faults.append(f"{name}: {n_js / 1e6:.2f} MB of JavaScript")
        if errors:
            faults.append(f"{name}: console errors {errors[:3]}")
        if remote:
            faults.append(f"{name}: requests outside the book {remote[:3]}")
        browser.set_window_size(400, 900)
        width, client = browser.execute_script(
            "return [document.documentElement.scrollWidth, document.documentElement.clientWidth]"
        )
        if width > client:
            faults.append(f"{name}: scrolls sideways at 400 px ({width} > {client} px)")
    browser.set_window_size(1280, 900)
    assert not faults, "\n".join(faults)


@pytest.mark.book
def test_mathjax_is_one_script_loaded_once(html, browser):
    requests, _ = _load_and_log(browser, html / "sec3_6.html")
    mathjax = [url for url, kind in requests if kind == "Script" and "/mathjax/" in url]
    assert len(mathjax) == 1, f"MathJax scripts loaded: {mathjax}"


# ---- pages that show the computation (item 2) ----------------------------------------------------

WARNING_TEXT = re.compile(
    r"\b\w*(Warning|Error):|warnings\.warn\(|Traceback \(most recent call "
    r"last\)"
)


def warning_blocks(page_html: str) -> list:
    """The stderr outputs, tracebacks and ``...Warning:`` lines of a built page (text, shortened).

    >>> warning_blocks('<div class="output stderr"><pre>x.py:3: RuntimeWarning: bad</pre></div>')
    ['<div class="output stderr">', 'RuntimeWarning:']
    >>> warning_blocks('<p>The fit did not converge.</p>')
    []
    """
    blocks = re.findall(r'<div class="output (?:stderr|traceback)[^"]*">', page_html)
    text = re.sub(r"<[^>]+>", "", page_html)
    return blocks + [m.group(0) for m in WARNING_TEXT.finditer(text)]


@pytest.mark.book
@pytest.mark.parametrize("page", NOTEBOOK_PAGES)
def test_no_warning_text_or_stray_output(html, page):
    text = (html / page).read_text()
    assert not warning_blocks(text), f"{page}: {warning_blocks(text)[:5]}"
    # a cell's displayed value is a bare repr (Scaling's `256`, `PosixPath('../figures')`): the book
    # prints numbers rounded, in sentences or tables, and hides the bookkeeping
    stray = re.findall(
        r'<div class="output text_plain[^"]*"><div '
        r'class="highlight"><pre><span></span>'
        r"([^<]{0,60})",
        text,
    )
    assert not stray, f"{page}: stray outputs {stray}"


# ---- one set of totals (item 4) ------------------------------------------------------------------


def test_landing_page_and_ledger_give_the_same_totals():
    """Both pages carry the same paragraph saying what is counted, and the landing page opens
    with the verdict formatted from the same statuses; no page cites an issue number."""
    from asoc_companion.ledger import totals_markdown, verdict_markdown

    intro, ledger = (BOOK / "intro.md").read_text(), (BOOK / "ledger.md").read_text()
    totals = totals_markdown()
    assert totals in intro and totals in ledger
    assert intro.index(verdict_markdown()) < intro.index("## What reproduces")
    cited = [
        (p.name, m)
        for p in [*BOOK.glob("*.md"), *BOOK.glob("*.ipynb")]
        for m in re.findall(r"\bissues? \d+\b", p.read_text())
    ]
    assert not cited, f"references to issue numbers a reader cannot follow: {cited}"


# ---- the Theorems page on a phone and on a desktop (issue 31, item 3) ---------------------------

FORMULAS_CUT = """
const cut = [];
for (const m of document.querySelectorAll('article mjx-container')) {
  const r = m.getBoundingClientRect();
  for (let e = m.parentElement; e && e !== document.body; e = e.parentElement) {
    if (getComputedStyle(e).overflowX !== 'visible') {
      const p = e.getBoundingClientRect();
      if (r.right > p.right + 1 || r.left < p.left - 1) cut.push(m.textContent.slice(0, 60));
      break;
    }
  }
}
return cut;"""
"""The formulas of a page that run past the box that clips or scrolls them."""


@pytest.mark.book
def test_theorems_page_reads_on_a_phone_and_shows_whole_formulas(html, browser):
    browser.set_window_size(1280, 900)
    browser.get((html / "theorems.html").as_uri())
    _wait_for_math(browser)
    header = browser.execute_script(
        "return Array.from(document.querySelectorAll('article table')[0].querySelectorAll('th'))"
        ".map(th => th.textContent.trim())"
    )
    assert header == ["Statement", "Verdict", "Mutant"], header
    sections = browser.execute_script("return document.querySelectorAll('[id^=check-]').length")
    assert sections >= 30, f"{sections} statement sections"
    assert not browser.execute_script(FORMULAS_CUT), "formulas cut at 1280 px"
    browser.set_window_size(400, 900)
    width, client = browser.execute_script(
        "return [document.documentElement.scrollWidth, document.documentElement.clientWidth]"
    )
    browser.set_window_size(1280, 900)
    assert width <= client, f"the Theorems page scrolls sideways at 400 px ({width} > {client} px)"
