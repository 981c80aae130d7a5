"""The API reference page (book/api.md) is generated from the docstrings and builds offline;
in headless Chromium it lists the public controller designs with their full signatures."""

import inspect
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import asoc.belief
import asoc.gp
import asoc.mjls
import asoc.repro
from asoc.repro.paths import BOOK

PACKAGES = (asoc.mjls, asoc.belief, asoc.gp, asoc.repro)
REQUIRED = ("static_output_feedback", "exact_dynamic_output_feedback")


@pytest.fixture(scope="module")
def api_html(tmp_path_factory):
    out = tmp_path_factory.mktemp("book")
    subprocess.run([sys.executable, "-m", "asoc.repro.book"], check=True)
    jb = Path(sys.executable).parent / "jupyter-book"
    proc = subprocess.run([str(jb), "build", str(BOOK), "--path-output", str(out), "--quiet"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    page = out / "_build" / "html" / "api.html"
    assert page.exists(), "api.html was not built"
    return page


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


def _signature_text(browser, obj_id):
    return browser.execute_script(
        "const e = document.getElementById(arguments[0]); return e ? e.textContent : null;", obj_id)


@pytest.mark.book
@pytest.mark.parametrize("name", REQUIRED)
def test_api_page_lists_function_with_signature(api_html, browser, name):
    func = getattr(asoc.mjls, name)
    browser.get(api_html.as_uri())
    text = _signature_text(browser, f"asoc.mjls.{name}")
    assert text is not None, f"api.html has no entry asoc.mjls.{name}"
    text = " ".join(text.replace("\u00b6", "").split())
    assert f"{name}(" in text, text
    for param in inspect.signature(func).parameters.values():
        shown = param.name if param.default is inspect.Parameter.empty else f"{param.name}={param.default!r}"
        assert shown.replace(" ", "") in text.replace(" ", ""), f"{name}: {shown} missing from {text!r}"


@pytest.mark.book
def test_api_page_covers_every_public_function(api_html, browser):
    browser.get(api_html.as_uri())
    ids = set(browser.execute_script(
        "return Array.from(document.querySelectorAll('dt.sig[id]')).map(e => e.id)"))
    missing = [f"{pkg.__name__}.{name}" for pkg in PACKAGES for name in pkg.__all__
               if inspect.isfunction(getattr(pkg, name)) and f"{pkg.__name__}.{name}" not in ids]
    assert not missing, f"not on the API page: {missing}"
