"""The book's Sphinx extension: a light offline site and a layout that stays current.

Jupyter Book injects every ``.js`` file under ``book/_static`` into every page, and its
theme adds a few scripts that this book does not use. This extension (listed under
``sphinx: extra_extensions`` in ``book/_config.yml``) keeps each page to what it uses:

- MathJax 3 is served from the book itself, as one bundle (:data:`MATHJAX_BUNDLE`, from the
  ``django-static-mathjax`` package) and its web fonts, copied into ``_static/mathjax``
  when the HTML build finishes; it is loaded once, on pages with math only (Sphinx also
  asks for it on the landing page, whose table of contents leads to math);
- scripts a page does not use are left out (``_unused_script``): the Thebe launcher
  (the book has no launch buttons), sphinx-design's tabs and the toggle button where the
  page has none, and any script listed twice;
- the architecture page's picture of the layout (``_layout_tree``) is generated from
  ``src/`` when the page is read, so it follows the modules as they are split;
- the API pages' ``<!-- api MODULE ... -->`` blocks become an autosummary table of the
  module's public names and their entries grouped by task (:func:`api_markdown`).

``python -m asoc_companion.book`` prepares a checkout for a build: it removes the MathJax
folder that earlier versions copied into ``book/_static`` (Jupyter Book would inject its
70 scripts into every page) and checks that MathJax is installed.
"""

import ast
import importlib
import inspect
import re
import shutil
import sys
from importlib.metadata import version
from importlib.util import find_spec
from pathlib import Path

from . import paths, printing

__all__ = ["MATHJAX_BUNDLE", "MATHJAX_FONTS", "API_BLOCK", "LAYOUT_MARKER", "THEBE_BODY", "THESIS",
           "LATEX_ELEMENTS", "SUMMARY_WIDTH", "public_names", "documented", "api_markdown",
           "THESIS_ABBREVIATIONS", "use_abbreviations", "setup"]


MATHJAX_BUNDLE = "tex-chtml-full.js"
"""The MathJax 3 combined component served: TeX input with every extension (nothing is
loaded on demand, e.g. ``\\boldsymbol``), CommonHTML output, the menu."""
MATHJAX_FONTS = Path("output") / "chtml" / "fonts" / "woff-v2"
"""The web fonts of the CommonHTML output, relative to MathJax's folder (not scripts)."""
API_BLOCK = re.compile(r"<!-- api (?P<module>[\w.]+)(?P<groups>.*?)-->", re.DOTALL)
"""An API block of a page: ``<!-- api MODULE`` then lines ``Title: name name ...`` then ``-->``."""
LAYOUT_MARKER = "<!-- layout: generated from src/ by asoc_companion.book -->"
"""Where the architecture page receives ``_layout_tree`` (replaced when the page is read)."""


def _mathjax_source() -> Path:
    """The folder of MathJax 3's ``es5`` build installed by ``django-static-mathjax``.

    Raises
    ------
    RuntimeError
        If the package is not installed.
    """
    spec = find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("MathJax not installed: pip install 'asoc[companion]' "
                           "(django-static-mathjax)")
    return Path(list(spec.submodule_search_locations)[0]) / "static" / "mathjax" / "es5"


def _install_mathjax(static) -> Path:
    """Copy :data:`MATHJAX_BUNDLE` and its fonts into ``static/mathjax``; return that folder."""
    source, target = _mathjax_source(), Path(static) / "mathjax"
    (target / MATHJAX_FONTS).mkdir(parents=True, exist_ok=True)
    shutil.copy2(source / MATHJAX_BUNDLE, target / MATHJAX_BUNDLE)
    shutil.copytree(source / MATHJAX_FONTS, target / MATHJAX_FONTS, dirs_exist_ok=True)
    return target


def _unused_script(script, body: str, seen: set) -> bool:
    """Whether a page with HTML ``body`` can do without ``script`` (a Sphinx ``_JavaScript``).

    ``seen`` collects the scripts already kept on the page; a repeated one is unused.

    Examples
    --------
    >>> from sphinx.builders.html._assets import _JavaScript
    >>> seen = set()
    >>> _unused_script(_JavaScript("_static/doctools.js"), "<p>text</p>", seen)
    False
    >>> _unused_script(_JavaScript("_static/doctools.js"), "<p>text</p>", seen)
    True
    >>> _unused_script(_JavaScript("_static/design-tabs.js"), "<p>text</p>", set())
    True
    >>> _unused_script(_JavaScript("_static/mathjax/a11y/sre.js"), "", set())
    True
    >>> _unused_script(_JavaScript(f"_static/mathjax/{MATHJAX_BUNDLE}"),
    ...     '<span class="math">x</span>', set())
    False
    """
    name = str(script.filename)
    key = (name, script.attributes.get("body", ""))
    if key in seen:
        return True
    seen.add(key)
    if name.startswith("_static/mathjax/"):
        # the bundle, where the page has math (Sphinx asks for it on the landing page too: its
        # table of contents leads to pages with math)
        return name != f"_static/mathjax/{MATHJAX_BUNDLE}" or 'class="math' not in body
    if "thebe" in name or "THEBE" in script.attributes.get("body", "") or "kernelName" in key[1]:
        return True
    if name.endswith("design-tabs.js"):
        return "sd-tab-set" not in body
    if name.endswith("togglebutton.js") or "togglebutton" in key[1] or "toggleHint" in key[1] \
            or "toggleOpenOnPrint" in key[1]:
        return "toggle" not in body and "dropdown" not in body
    return False


def _prune_page_assets(app, pagename, templatename, context, doctree):
    if app.builder.format != "html" or "script_files" not in context:
        return
    seen, body = set(), context.get("body", "")
    context["script_files"][:] = [s for s in context["script_files"]
                                  if not _unused_script(s, body, seen)]
    css_seen = set()
    context["css_files"][:] = [c for c in context["css_files"]
                               if not (c.filename in css_seen or css_seen.add(c.filename))]


THEBE_BODY = re.compile(r"\s*<script "
                        r"type=\"text/x-thebe-config\">.*?</script>\s*<script>kernelName = "
                        r"[^<]*</script>",
                        re.DOTALL)
"""What sphinx-thebe (loaded by Jupyter Book on every book) appends to each page's body."""


def _drop_thebe_config(app, pagename, templatename, context, doctree):
    if "body" in context:
        context["body"] = THEBE_BODY.sub("", context["body"])


THESIS = ("Maxim Dolgov, \\emph{Approximate Stochastic Optimal Control of Smooth Nonlinear Systems "
          "and Piecewise Linear Systems}, PhD thesis, Karlsruhe Institute of Technology, 2017")
"""The thesis, as the PDF's title page names it (LaTeX)."""


LATEX_ELEMENTS = {
    "papersize": "a4paper",
    # math keeps TeX's own fonts: fontspec's default moves \mathbf onto the text font, where
    # \mathbf\Sigma has no glyph (a missing character in the PDF)
    "fontenc": r"\usepackage[no-math]{fontspec}",
    # long API names fit the index's columns in a smaller size, set ragged (Sphinx's advice)
    "printindex": r"\footnotesize\raggedright\printindex",
    "preamble": printing.LATEX_PREAMBLE,
}
"""Sphinx's LaTeX settings for the PDF, besides the title page."""


def _title_page(title: str, version: str) -> str:
    """The PDF's title page (LaTeX): the book's title, the thesis, the licences, the version.

    Examples
    --------
    >>> page = _title_page("A companion", "0.1.0")
    >>> "A companion" in page and "CC BY-NC 4.0" in page and "version 0.1.0" in page
    True
    """
    return rf"""\begin{{titlepage}}
\centering\vspace*{{3cm}}
{{\Huge\bfseries {title}\par}}
\vspace{{1.5cm}}
{{\large The reproducible companion to\par\vspace{{0.5em}}{THESIS}\par}}
\vspace{{1.5cm}}
{{\large \texttt{{asoc}} version {version}\par}}
\vfill
{{\small The thesis text is licensed CC BY-NC 4.0; its equations, parameters and numbers are
cited by their numbers in the thesis. The software \texttt{{asoc}} and this book's code are
licensed MIT.\par}}
\end{{titlepage}}"""


def _configure(app, config):
    config.mathjax_path = f"mathjax/{MATHJAX_BUNDLE}"
    config.release = config.version = version("asoc")
    config.latex_elements = {**config.latex_elements, **LATEX_ELEMENTS,
                             "maketitle": _title_page(config.html_title or config.project,
                                                      config.release)}
    config.latex_use_xindy = False          # makeindex comes with TeX Live; xindy is a package more
    # Jupyter Book listed every .js under _static (a MathJax folder left there by an old
    # build would add 70 scripts): keep the book's own scripts only
    script = lambda js: str(js[0] if isinstance(js, tuple) else js)
    config.html_js_files = [js for js in config.html_js_files
                            if not script(js).startswith("mathjax/")]


def _copy_mathjax(app, exception):
    if exception is None and app.builder.format == "html":
        _install_mathjax(Path(app.outdir) / "_static")


SUMMARY_WIDTH = 42
"""Characters of a module's summary in the layout tree (the page's code block stays narrow)."""


def _module_summary(path: Path, width: int = SUMMARY_WIDTH) -> str:
    """The first line of a module's docstring, without reST markup, cut at ``width`` characters.

    Examples
    --------
    >>> import asoc_companion.book as me
    >>> _module_summary(Path(me.__file__))
    "The book's Sphinx extension: a light…"
    """
    doc = ast.get_docstring(ast.parse(path.read_text()))
    line = doc.strip().splitlines()[0].strip() if doc else ""
    line = re.sub(r":\w+:`~?([^`]+)`|``([^`]+)``", lambda m: m[1] or m[2], line).rstrip(".")
    return line if len(line) <= width else line[:width].rsplit(" ", 1)[0] + "…"


def _layout_tree(src) -> str:
    """A tree of the packages under ``src``, one line per module with its docstring's first line.

    Examples
    --------
    >>> tree = _layout_tree(paths.project().src)
    >>> tree.splitlines()[0]
    'src/'
    >>> any(line.lstrip(' │├└─').startswith('book.py') for line in tree.splitlines())
    True
    """
    lines = ["src/"]

    def walk(folder: Path, indent: str):
        entries = sorted(p for p in folder.iterdir() if p.name != "__init__.py"
                         and (p.suffix == ".py" or (p.is_dir() and (p / "__init__.py").exists())))
        names = [e.name + "/" * e.is_dir() for e in entries]
        width = max(map(len, names), default=0)
        for i, (entry, name) in enumerate(zip(entries, names)):
            last = i == len(entries) - 1
            summary = _module_summary(entry / "__init__.py" if entry.is_dir() else entry)
            lines.append(f"{indent}{'└── ' if last else '├── '}{name:<{width}}  {summary}".rstrip())
            if entry.is_dir():
                walk(entry, indent + ("    " if last else "│   "))

    walk(Path(src), "")
    return "\n".join(lines)


def public_names(module) -> list:
    """``module.__all__``, else the public names the module defines: its functions and classes,
    and its data that is not imported (lower-case objects of its own, e.g. a ``defaults`` dict).

    Examples
    --------
    >>> import asoc.config
    >>> names = public_names(asoc.config)
    >>> "option_context" in names and "Iterator" not in names
    True
    """
    if hasattr(module, "__all__"):
        return list(module.__all__)
    source = inspect.getsource(module)

    def defined_here(name, obj):
        if inspect.ismodule(obj) or name.startswith("_"):
            return False
        if getattr(obj, "__module__", None) == module.__name__:
            return True
        return (not (inspect.isclass(obj) or callable(obj))
                and re.search(rf"^{name}\b.*=", source, re.M))

    return [name for name, obj in vars(module).items() if defined_here(name, obj)]


def _attribute_docs(module) -> dict:
    """``{name: docstring}`` of the module's data documented in its source (``#:`` comments or
    a string right after the assignment); data without one would show its type's docstring.
    """
    from sphinx.pycode import ModuleAnalyzer

    try:
        docs = ModuleAnalyzer.for_module(module.__name__).find_attr_docs()
    except Exception:          # no source to read (a compiled or generated module)
        return {}
    return {name: lines for (scope, name), lines in docs.items() if scope == ""}


def documented(module, names) -> list:
    """``names`` without the module's data that has no documentation of its own."""
    docs = _attribute_docs(module)
    return [n for n in names
            if inspect.isclass(getattr(module, n)) or callable(getattr(module, n)) or n in docs]


def _directive(module, name) -> str:
    obj = getattr(module, name)
    if inspect.isclass(obj):
        return f".. autoclass:: {module.__name__}.{name}\n   :members:\n"
    if callable(obj):
        return f".. autofunction:: {module.__name__}.{name}\n"
    return f".. autodata:: {module.__name__}.{name}\n   :annotation:\n"


def api_markdown(module_name: str, groups: str) -> str:
    """The MyST text of an API block: an autosummary table of every public name of the module,
    then each group under a heading (``Title: name name ...``, one group a line) and the
    names no group lists under "More".

    Names a group lists that the module does not have are left out, so a renamed function
    moves to "More" instead of breaking the build. Without groups, the entries follow the
    table with no headings.

    Examples
    --------
    >>> text = api_markdown("asoc.config", "")
    >>> ".. autosummary::" in text and ".. autofunction:: asoc.config.option_context" in text
    True
    >>> "## Tunables" in api_markdown("asoc.config", "Tunables: defaults")
    True
    """
    module = importlib.import_module(module_name)
    names = documented(module, public_names(module))
    sections, listed = [], set()
    for line in groups.strip().splitlines():
        if ":" not in line:
            continue
        title, members = line.split(":", 1)
        members = [n for n in members.split() if n in names and n not in listed]
        listed.update(members)
        if members:
            sections.append((title.strip(), members))
    rest = [n for n in names if n not in listed]
    if rest:
        sections.append(("More" if sections else "", rest))
    order = [n for _, members in sections for n in members]
    table = "\n".join(f"   {n}" for n in order)
    parts = [f"```{{eval-rst}}\n.. currentmodule:: {module_name}\n\n.. autosummary::\n   "
             f":nosignatures:\n\n{table}\n```"]
    for title, members in sections:
        body = "\n".join(_directive(module, n) for n in members)
        parts.append((f"## {title}\n\n" if title else "") + f"```{{eval-rst}}\n{body}```")
    return "\n\n".join(parts)


def _expand_blocks(app, docname, source):
    text = source[0]
    if LAYOUT_MARKER in text:
        text = text.replace(LAYOUT_MARKER,
                            f"```text\n{_layout_tree(Path(app.srcdir).parent / 'src')}\n```")
    source[0] = API_BLOCK.sub(lambda m: api_markdown(m["module"], m["groups"]), text)


def _generated_pages(app, env, added, changed, removed):
    """Pages with generated blocks are read again on every build: the modules they list change
    without the page's own text changing.
    """
    return [doc for doc in env.found_docs
            if (Path(app.srcdir) / f"{doc}.md").exists()
            and re.search(r"<!-- (api |layout:)", (Path(app.srcdir) / f"{doc}.md").read_text())]


THESIS_ABBREVIATIONS = ("Alg.", "App.", "Assm.", "Cor.", "Def.", "Eq.", "Eqs.", "Fig.", "Figs.",
                        "Lem.", "Prop.", "Props.", "Ref.", "Sec.", "Secs.", "Thm.", "Thms.", "Vol.",
                        "cf.", "ch.", "resp.", "vs.")
"""Abbreviations the docstrings use before a number ("Cor. 3.2"): no sentence ends there."""


def use_abbreviations():
    """Teach autosummary's summary-line extraction :data:`THESIS_ABBREVIATIONS`.

    autosummary cuts a docstring's first sentence at the first period followed by a space,
    except after the abbreviations of its module-level ``WELL_KNOWN_ABBREVIATIONS`` (Sphinx has
    no setting for them), so a summary such as "The matrix of Cor. 3.2" would stop at "Cor.".
    """
    from sphinx.ext import autosummary

    known = autosummary.WELL_KNOWN_ABBREVIATIONS
    added = tuple(a for a in THESIS_ABBREVIATIONS if a not in known)
    autosummary.WELL_KNOWN_ABBREVIATIONS = known + added


def setup(app):
    """Sphinx entry point."""
    use_abbreviations()
    app.connect("config-inited", _configure, priority=900)
    app.connect("source-read", _expand_blocks)
    app.connect("env-get-outdated", _generated_pages)
    app.connect("html-page-context", _prune_page_assets, priority=900)
    app.connect("html-page-context", _drop_thebe_config, priority=901)
    app.connect("build-finished", _copy_mathjax)
    app.connect("doctree-resolved", printing.prune_doctree)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


def _prepare(book=None) -> Path:
    """Ready ``book`` (default the checkout's) for a build; return its folder.

    Removes ``book/_static/mathjax`` left by earlier versions and checks that MathJax is
    installed (``_mathjax_source``).
    """
    book = Path(book or paths.project().book)
    shutil.rmtree(book / "_static" / "mathjax", ignore_errors=True)
    _mathjax_source()
    return book


if __name__ == "__main__":
    print(f"{_prepare()} is ready to build (MathJax: {_mathjax_source() / MATHJAX_BUNDLE})")
    sys.exit(0)
