"""The API pages parse: every public function, class and method of the modules the API pages
list passes numpydoc's validation of its Parameters and Returns sections (a sentence where a
type belongs, an undocumented or misordered parameter, a Returns line that is not a type); its
summary line, as the pages' autosummary tables cut it, is a whole sentence; and every name its
See Also section or its ``:func:``/``:class:`` references name resolves."""

import importlib
import inspect
import re

import numpydoc.validate as numpydoc_validate
import pytest
from docutils.frontend import get_default_settings
from docutils.parsers.rst import Parser
from docutils.utils import new_document
from sphinx.ext.autosummary import extract_summary

from asoc_companion.book import (
    API_BLOCK,
    THESIS_ABBREVIATIONS,
    documented,
    public_names,
    use_abbreviations,
)
from asoc_companion.paths import BOOK

PARSE_ERRORS = {
    "PR02": "documents a parameter the signature lacks (often a sentence read as a name)",
    "PR03": "documents the parameters in another order than the signature",
    "PR04": "gives a parameter no type",
    "PR05": "has a type ending with a period (a sentence where the type belongs)",
    "PR06": "uses a type spelled otherwise than numpydoc's (str, bool, int)",
    "PR10": "has a parameter line without a space before the colon",
    "RT02": "has a Returns line with more than the type",
}
"""numpydoc's codes for a Parameters or Returns section that does not parse as its reader meant."""


def api_modules() -> list:
    """The modules of the API pages' ``<!-- api MODULE -->`` blocks."""
    return sorted(
        {m["module"] for page in BOOK.glob("api*.md") for m in API_BLOCK.finditer(page.read_text())}
    )


def api_objects():
    """``(qualified name, object, module)`` of each public function, class and method, once."""
    seen = {}
    for module_name in api_modules():
        module = importlib.import_module(module_name)
        for name in documented(module, public_names(module)):
            obj = getattr(module, name)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            qualified = f"{obj.__module__}.{obj.__qualname__}"
            seen.setdefault(qualified, (obj, module))
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(member):
                        seen.setdefault(f"{qualified}.{attr}", (member, module))
    return sorted((q, obj, module) for q, (obj, module) in seen.items())


OBJECTS = api_objects()


def test_the_api_has_names():
    assert len(OBJECTS) > 150


def _has_section(doc: str, title: str) -> bool:
    return re.search(rf"^\s*{title}\n\s*-{{3,}}", doc or "", re.M) is not None


def sentence_types(doc: str) -> list:
    """Entries of the Parameters, Returns and Attributes sections whose type reads as a sentence
    (a colon, a semicolon, an unbalanced parenthesis, a final period or a leading "the"): the
    description was written on the type's line."""
    from numpydoc.docscrape import NumpyDocString

    parsed = NumpyDocString(doc)
    return [
        f"{entry.name or section}: {entry.type!r}"
        for section in ("Parameters", "Returns", "Attributes")
        for entry in parsed[section]
        if re.search(r": |;|\.$|^the ", entry.type)
        or entry.type.count("(") != entry.type.count(")")
    ]


@pytest.mark.parametrize("qualified", [q for q, _, _ in OBJECTS])
def test_parameters_and_returns_parse(qualified):
    errors = numpydoc_validate.validate(qualified)["errors"]
    obj = next(o for q, o, _ in OBJECTS if q == qualified)
    bad = [
        f"{code} {msg}"
        for code, msg in errors
        if code in PARSE_ERRORS
        or (code == "PR01" and _has_section(inspect.getdoc(obj), "Parameters"))
    ]
    bad += [
        f"a sentence where the type belongs, {entry}"
        for entry in sentence_types(inspect.getdoc(obj) or "")
    ]
    assert not bad, f"{qualified}: " + "; ".join(bad)


def _summary(doc: str) -> str:
    document = new_document("", get_default_settings(Parser))
    return extract_summary(doc.splitlines(), document)


def test_summaries_are_whole_sentences():
    """The autosummary tables' summary never stops at a thesis abbreviation ("Cor.", "Prop.")."""
    use_abbreviations()
    cut = {}
    for qualified, obj, _ in OBJECTS:
        doc = inspect.getdoc(obj)
        if doc:
            summary = _summary(doc)
            if summary.endswith(tuple(c + a for a in THESIS_ABBREVIATIONS for c in " (")):
                cut[qualified] = summary
    assert not cut, cut


def test_summary_line_is_not_cut_at_an_abbreviation():
    use_abbreviations()
    summary = _summary("The matrix of Cor. 3.2 (dense). More text.")
    assert summary == "The matrix of Cor. 3.2 (dense)."


REFERENCE = re.compile(r":(?:func|class|meth|data|attr|obj):`~?(?P<name>[\w.]+)`")


def documented_targets() -> set:
    """Every name the API pages document: ``module.name`` and ``module.Class.member``."""
    targets = set()
    for module_name in api_modules():
        module = importlib.import_module(module_name)
        for name in documented(module, public_names(module)):
            targets.add(f"{module_name}.{name}")
            obj = getattr(module, name)
            if inspect.isclass(obj):
                targets.update(
                    f"{module_name}.{name}.{a}" for a in dir(obj) if not a.startswith("_")
                )
    return targets


TARGETS = documented_targets()


def _resolves(name: str, obj, module) -> bool:
    """Whether ``name`` leads to a documented entry as Sphinx looks it up from the entry of ``obj``
    on ``module``'s page: in its class, in the page's module, or as a full path."""
    entry = obj.__qualname__.split(".")
    owner = entry[:-1] if not inspect.isclass(obj) else entry
    candidates = [".".join([module.__name__, *owner, name]), f"{module.__name__}.{name}", name]
    return any(c in TARGETS for c in candidates)


def test_cross_references_resolve():
    from numpydoc.docscrape import NumpyDocString

    broken = []
    for qualified, obj, module in OBJECTS:
        doc = inspect.getdoc(obj) or ""
        names = [m["name"] for m in REFERENCE.finditer(doc)]
        try:
            names += [name for entries, _ in NumpyDocString(doc)["See Also"] for name, _ in entries]
        except Exception as error:  # a docstring numpydoc cannot read at all
            broken.append(f"{qualified}: {error}")
            continue
        broken += [f"{qualified}: {name}" for name in names if not _resolves(name, obj, module)]
    assert not broken, broken
