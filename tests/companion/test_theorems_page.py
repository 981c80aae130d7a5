"""The Theorems page (issue 31, item 3): one compact table (statement, verdict, mutant) with a link
to each statement's section, then per statement its claim, its check, its mutant, and where it
fails the diagnosis and the corrected statement, as MyST Markdown that the HTML and the PDF both
render; every check, mutant and corrected statement that has math is typeset (LaTeX), not ASCII
(the diagnoses are written in LaTeX where they are made: tests/companion/test_corrections.py)."""

import re

from asoc_companion.theorems import STATEMENTS
from asoc_companion.theorems.report import StatementsPage, statements_markdown
from asoc_companion.theorems.typeset import CHECKS_TEX, CORRECTIONS_TEX, MUTANTS_TEX
from asoc_companion.values import load_values

ASCII_MATH = re.compile(r"[_^~]|<=|>=|\bsqrt\(|\bexp\(|\btr\[")
"""Marks of math written in ASCII (x_k, x^T, X~, <=, sqrt(...))."""


def _records():
    values = load_values("theorems")
    return {st.key: values[st.key] for st in STATEMENTS}


def test_one_row_and_one_section_per_statement():
    page = statements_markdown(STATEMENTS, _records(), {"statement_3_19": "finding-thm319"})
    table, _, sections = page.partition("\n\n")
    rows = table.splitlines()
    assert rows[0] == "| Statement | Verdict | Mutant |" and len(rows) == 2 + len(STATEMENTS)
    for st in STATEMENTS:
        anchor = "check-" + st.key.removeprefix("statement_").replace("_", "-")
        assert f"<{anchor}>`" in table and f"({anchor})=" in sections, st.key
    assert "{ref}`finding <finding-thm319>`" in sections
    assert StatementsPage(STATEMENTS, _records(), {})._repr_markdown_().startswith("| Statement |")


def test_every_mutant_and_correction_with_math_is_typeset():
    untyped = []
    for key, record in _records().items():
        corrected = record.get("corrected") or {}
        for mutant in (record.get("mutant"), corrected.get("mutant")):
            text = mutant["description"] if mutant else ""
            if ASCII_MATH.search(text) and text not in MUTANTS_TEX:
                untyped.append(f"{key} mutant: {mutant['description']}")
        statement = corrected.get("statement", "")
        if (
            "$" not in statement
            and ASCII_MATH.search(statement)
            and statement not in CORRECTIONS_TEX
        ):
            untyped.append(f"{key} corrected: {statement[:80]}")
    untyped += [
        f"{st.key} check: {st.checked[:80]}"
        for st in STATEMENTS
        if ASCII_MATH.search(st.checked) and st.checked not in CHECKS_TEX
    ]
    assert not untyped, untyped


def test_typeset_texts_keep_no_ascii_math_outside_dollars():
    for text in [*MUTANTS_TEX.values(), *CORRECTIONS_TEX.values(), *CHECKS_TEX.values()]:
        prose = re.sub(r"`[^`]*`", "", text).split("$")[::2]  # outside math and code
        assert not [p for p in prose if re.search(r"\^|_\w|<=|>=", p)], text
