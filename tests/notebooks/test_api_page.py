"""The API reference page (book/api.md) is generated from the docstrings and builds offline;
in headless Chromium it lists the public controller designs with their full signatures."""

import inspect

import pytest

import asoc.belief
import asoc.gp
import asoc.mjls
import asoc_companion

PACKAGES = (asoc.mjls, asoc.belief, asoc.gp, asoc_companion)
REQUIRED = ("static_output_feedback", "exact_dynamic_output_feedback")


@pytest.fixture(scope="module")
def api_html(html):
    page = html / "api.html"
    assert page.exists(), "api.html was not built"
    return page


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


def test_docstrings_render_without_sphinx_errors(html):
    """A docstring that Sphinx misreads (e.g. |P| taken for a substitution) is reported in the build log."""
    log = (html.parent.parent / "build.log").read_text()
    problems = [line for line in log.splitlines() if "docstring of" in line]
    assert not problems, "\n".join(problems)
