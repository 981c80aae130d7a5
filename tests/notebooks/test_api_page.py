"""The API reference (book/api.md and one page per subpackage, generated from the docstrings)
builds offline; in headless Chromium each page opens with an autosummary table, its contents
on the right list every public function and class, every docstring is rendered once (one
"Parameters" block per entry), and the controller designs show their full signatures."""

import inspect

import pytest

import asoc.belief
import asoc.config
import asoc.gp
import asoc.mjls
import asoc_companion
from asoc_companion.book import api_markdown, public_names

PAGES = {
    asoc.mjls: "api_mjls.html",
    asoc.belief: "api_belief.html",
    asoc.gp: "api_gp.html",
    asoc.config: "api_core.html",
    asoc_companion: "api_companion.html",
}
REQUIRED = ("static_output_feedback", "exact_dynamic_output_feedback")


def _signature_text(browser, obj_id):
    return browser.execute_script(
        "const e = document.getElementById(arguments[0]); return e ? e.textContent : null;", obj_id
    )


@pytest.mark.book
@pytest.mark.parametrize("name", REQUIRED)
def test_api_page_lists_function_with_signature(html, browser, name):
    func = getattr(asoc.mjls, name)
    browser.get((html / "api_mjls.html").as_uri())
    text = _signature_text(browser, f"asoc.mjls.{name}")
    assert text is not None, f"api_mjls.html has no entry asoc.mjls.{name}"
    text = " ".join(text.replace("\u00b6", "").split())
    assert f"{name}(" in text, text
    for param in inspect.signature(func).parameters.values():
        shown = (
            param.name
            if param.default is inspect.Parameter.empty
            else f"{param.name}={param.default!r}"
        )
        assert shown.replace(" ", "") in text.replace(" ", ""), (
            f"{name}: {shown} missing from {text!r}"
        )


@pytest.mark.book
@pytest.mark.parametrize("package", list(PAGES), ids=lambda p: p.__name__)
def test_each_page_tables_and_lists_every_public_name(html, browser, package):
    """The autosummary table comes first, and the page's contents (right-hand table of
    contents) link every public function and class of the package."""
    browser.get((html / PAGES[package]).as_uri())
    first_table = browser.execute_script(
        "const t = document.querySelector('article table'); const d = "
        "document.querySelector('article dl.py');"
        "return t && t.classList.contains('autosummary') && (!d ||"
        " (t.compareDocumentPosition(d) & Node.DOCUMENT_POSITION_FOLLOWING) > 0);"
    )
    assert first_table, f"{PAGES[package]}: no autosummary table before the first entry"
    toc = set(
        browser.execute_script(
            "return Array.from(document.querySelectorAll('#pst-page-toc-nav a')).map(a => "
            "a.hash.slice(1))"
        )
    )
    public = [
        n
        for n in public_names(package)
        if inspect.isfunction(getattr(package, n)) or inspect.isclass(getattr(package, n))
    ]
    missing = [n for n in public if f"{package.__name__}.{n}" not in toc]
    assert public and not missing, f"{PAGES[package]}: not in the page's contents: {missing}"


@pytest.mark.book
def test_every_docstring_is_rendered_once(html, browser):
    """One entry per object over all API pages, and no entry with two "Parameters" blocks (the
    signature's types were once added as a second block under MJLS)."""
    seen, twice, doubled = set(), [], []
    for page in sorted(html.glob("api*.html")):
        browser.get(page.as_uri())
        ids = browser.execute_script(
            "return Array.from(document.querySelectorAll('article dt.sig[id]')).map(e => e.id)"
        )
        twice += [i for i in ids if i in seen]
        seen.update(ids)
        doubled += browser.execute_script("""
            return Array.from(document.querySelectorAll('article dl.py > dd')).filter(dd =>
                Array.from(dd.querySelectorAll(':scope > dl.field-list > dt'))
                     .filter(dt => dt.textContent.trim().startsWith('Parameters')).length > 1)
              .map(dd => dd.previousElementSibling.id);""")
    assert seen and not twice, f"documented twice: {twice}"
    assert not doubled, f"entries with two Parameters blocks: {doubled}"


def test_api_block_lists_renamed_functions_under_more():
    """A group naming a function the module no longer has leaves it out; a public function no
    group names still appears, under "More"."""
    text = api_markdown("asoc.config", "Tunables: defaults no_such_function")
    assert "no_such_function" not in text and "## More" in text and "option_context" in text


def test_docstrings_render_without_sphinx_errors(html):
    """A docstring that Sphinx misreads (e.g. |P| taken for a substitution) is reported in the build
    log."""
    log = (html.parent.parent / "build.log").read_text()
    problems = [line for line in log.splitlines() if "docstring of" in line or "WARNING" in line]
    assert not problems, "\n".join(problems)
