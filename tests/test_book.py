"""Build the HTML book from the committed notebooks and open pages in headless Chromium:
math must be typeset by MathJax and every image must load (natural width > 0)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from asoc.repro.notebooks import notebooks
from asoc.repro.paths import BOOK

NOTEBOOK_PAGES = [f"{name}.html" for name in notebooks()]
PAGES = NOTEBOOK_PAGES + ["intro.html", "ledger.html"]


@pytest.fixture(scope="module")
def html(tmp_path_factory):
    out = tmp_path_factory.mktemp("book")
    subprocess.run([sys.executable, "-m", "asoc.repro.book"], check=True)
    jb = Path(sys.executable).parent / "jupyter-book"
    proc = subprocess.run([str(jb), "build", str(BOOK), "--path-output", str(out), "--quiet"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    return out / "_build" / "html"


@pytest.fixture(scope="module")
def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    if not shutil.which("chromium") or not shutil.which("chromedriver"):
        pytest.fail("chromium and chromedriver are required (make test installs them)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--allow-file-access-from-files"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    yield driver
    driver.quit()


def _wait_for_math(driver, timeout=30):
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, timeout).until(lambda d: d.execute_script(
        "return window.MathJax && MathJax.startup && MathJax.startup.promise"
        " ? (MathJax.startup.promise.then(() => window.__mjdone = true), window.__mjdone === true)"
        " : false"))


@pytest.mark.book
@pytest.mark.parametrize("page", PAGES)
def test_page_renders_math_and_images(html, browser, page):
    path = html / page
    assert path.exists(), f"{page} was not built"
    browser.get(path.as_uri())
    n_math_src = browser.execute_script("return document.querySelectorAll('.math, mjx-container').length")
    if page in NOTEBOOK_PAGES:
        assert n_math_src > 0, f"{page}: no math on the page"
        _wait_for_math(browser)
        rendered = browser.execute_script("return document.querySelectorAll('mjx-container').length")
        raw = browser.execute_script(
            "return Array.from(document.querySelectorAll('.math')).filter("
            "e => !e.querySelector('mjx-container') && e.textContent.includes('\\\\')).length")
        assert rendered > 0 and raw == 0, f"{page}: {rendered} typeset, {raw} left as raw TeX"
    browser.execute_script("window.scrollTo(0, document.body.scrollHeight)")
    images = browser.execute_script(
        "return Array.from(document.images).map(i => [i.src, i.complete, i.naturalWidth])")
    info = notebooks().get(page.removesuffix(".html"))
    if info is not None:
        assert len(images) >= len(info.figures), \
            f"{page}: expected its {len(info.figures)} figures, found {len(images)} images"
    broken = [src for src, complete, width in images if not (complete and width > 0)]
    assert not broken, f"{page}: images that did not load: {broken}"
