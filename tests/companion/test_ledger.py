"""The committed full-fidelity values give every reference entry its expected status, and
the committed ledger page is the one the generator writes from them."""

import pytest

from asoc_companion import load_all_values, load_reference, status
from asoc_companion.ledger import ledger_markdown
from asoc_companion.paths import BOOK

REFERENCE = load_reference()
VALUES = load_all_values()


@pytest.mark.parametrize("key", sorted(REFERENCE))
def test_full_fidelity_status_is_the_expected_one(key):
    entry = REFERENCE[key]
    assert key in VALUES, f"{key} has no full-fidelity value in figures/values"
    assert status(entry, VALUES[key]) == entry.expect, (
        f"{key}: ours {VALUES[key]!r}, thesis {entry.thesis!r}: status changed"
    )


def test_every_recorded_value_is_in_the_reference():
    """Every value of a page that has a reference file (the thesis's sections, the findings and
    the own-system pages) has an entry. The theorems study records verdicts of its own checks,
    not numbers to compare (tests/companion/test_theorems*.py test them), and has no reference
    file."""
    from asoc_companion.paths import project

    pages = {p.stem for p in (project().reference).glob("*.yaml")}
    missing = sorted(k for k in set(VALUES) - set(REFERENCE) if k.split(".")[0] in pages)
    assert not missing, (
        f"recorded but not in tests/reference/thesis_values/<notebook>.yaml: {missing}"
    )


def test_committed_ledger_is_current():
    assert (BOOK / "ledger.md").read_text() == ledger_markdown(REFERENCE, VALUES), (
        "book/ledger.md is stale: run `python -m asoc_companion ledger`"
    )


def test_notebooks_have_figures_in_figures_folder():
    from asoc_companion.figures import file_stem
    from asoc_companion.notebooks import notebooks
    from asoc_companion.paths import FIGURES

    for info in notebooks().values():
        for number in info.figures:
            assert (FIGURES / f"{file_stem('fig', number)}.png").exists(), number
        for number in info.tables:
            assert (FIGURES / f"{file_stem('table', number)}.md").exists(), number


# --- the page layout (issue 9): intro summary, shared notes, precision, links, captions ---------

import json
import re

from asoc_companion.anchors import heading_anchor
from asoc_companion.captions import caption_markdown, load_claims
from asoc_companion.ledger import decimals, intro_markdown, ledger_rows, note_groups, section_links
from asoc_companion.notebooks import notebooks
from asoc_companion.reference import Entry


def test_committed_intro_summary_is_current():
    text = (BOOK / "intro.md").read_text()
    assert intro_markdown(text) == text, (
        "book/intro.md summary is stale: run `python -m asoc_companion ledger`"
    )


@pytest.mark.parametrize(
    "tol, thesis, expected",
    [
        (6e-5, 1.297, 4),
        (5e-7, 0.001343, 6),
        (5e-8, 0.0019924, 7),
        (None, 0.025, 3),
        (None, [0.5, 0.9], 1),
        (None, "text", None),
    ],
)
def test_decimals_from_tolerance_or_printed_number(tol, thesis, expected):
    assert decimals(Entry(key="x.y", where="", kind="measured", thesis=thesis, tol=tol)) == expected


def test_ours_is_rounded_to_the_thesis_decimals_plus_two():
    rows = {r["key"]: r for r in ledger_rows(REFERENCE, VALUES)}
    for key, entry in REFERENCE.items():
        if entry.kind == "deterministic" and isinstance(VALUES.get(key), float):
            assert rows[key]["ours"] == f"{VALUES[key]:.{decimals(entry) + 2}f}", key


def test_a_note_shared_by_rows_is_printed_once():
    rows = [
        dict(
            key=f"n.k{i}",
            name=f"k{i}",
            note=f"Row {i} is own. " + "A long shared explanation. " * 12,
            claim="",
            ours_long="",
            where="w",
        )
        for i in range(5)
    ]
    groups = note_groups(rows)
    assert len(groups) == 1
    head, tail, parts = groups[0]
    assert head == "" and tail.count("A long shared explanation.") == 12
    assert [own for own, _ in parts] == [f"Row {i} is own." for i in range(5)]
    page = ledger_markdown(REFERENCE, VALUES)
    shared = "none gives the printed values."  # in every Table 3.2 note of sec3_5
    assert sum(1 for r in REFERENCE.values() if shared in r.note) > 1 and page.count(shared) == 1


def test_every_row_links_to_the_heading_of_the_cell_that_computes_it():
    for name, info in notebooks().items():
        keys = [e.name for e in REFERENCE.values() if e.notebook == name]
        headings = {
            heading_anchor(line)
            for cell in json.loads(info.path.read_text())["cells"]
            if cell["cell_type"] == "markdown"
            for line in "".join(cell["source"]).splitlines()
            if re.match(r"#{2,6}\s", line)
        }
        for key, link in section_links(info.path, keys).items():
            page, _, anchor = link.partition("#")
            assert page == f"{name}.html" and anchor in headings, f"{name}.{key}: {link}"


def test_every_figure_has_a_claim_and_a_caption_cell():
    """Every thesis figure (the section notebooks; the own-system chapter is not the thesis's)."""
    claims = load_claims()
    for info in (i for i in notebooks().values() if i.name.startswith("sec")):
        sources = [
            c["source"] if isinstance(c["source"], str) else "".join(c["source"])
            for c in json.loads(info.path.read_text())["cells"]
        ]
        for number in info.figures:
            assert number in claims, (
                f"Fig. {number} has no entry in tests/reference/figure_claims.yaml"
            )
            assert all(k in REFERENCE for k in claims[number]["keys"]), number
            assert sum(f'figure_caption("{number}")' in s for s in sources) == 1, (
                f"{info.name}: Fig. {number}"
            )


def test_caption_follows_the_ledger_status():
    reference = {
        "s.a": Entry(key="s.a", where="", kind="deterministic", thesis=1.0, tol=0.01),
        "s.b": Entry(key="s.b", where="", kind="claim", thesis="c"),
    }
    claims = {"9.9": {"where": "Sec. 9", "claim": "it converges", "keys": ["s.a", "s.b"]}}
    ok = caption_markdown(
        "9.9", claims, reference, {"s.a": 1.001, "s.b": {"holds": True, "value": 1}}
    )
    part = caption_markdown(
        "9.9", claims, reference, {"s.a": 1.5, "s.b": {"holds": True, "value": 1}}
    )
    assert "“it converges”" in ok and "{bdg-success}`shows it`" in ok and "2 of 2" in ok
    assert "{bdg-warning}`shows it in part`" in part and "1 of 2" in part
    with pytest.raises(ValueError, match="number"):
        caption_markdown("1.1", claims, reference, {})


# --- evidence on every deviating row, statistical claims (issue 30) ------------------------------

from asoc_companion.evidence import EVIDENCE_NEEDS, evidence_problems


@pytest.mark.parametrize("key", sorted(k for k, e in REFERENCE.items() if e.expect == "deviates"))
def test_every_deviating_row_has_complete_evidence(key):
    """Every `expect: deviates` row of every reference file (Secs. 2.5/2.6 included) names whose
    fault the deviation is, with the entries its kind needs."""
    assert not evidence_problems(REFERENCE[key]), evidence_problems(REFERENCE[key])


def test_the_evidence_check_catches_each_missing_entry():
    base = dict(key="demo.x", where="p. 1", kind="measured", expect="deviates")
    assert evidence_problems(Entry(**base)) == [
        "demo.x: a deviating row needs evidence (a mapping with kind)"
    ]
    assert "kind must be one of" in evidence_problems(Entry(**base, evidence={"kind": "typo"}))[0]
    for kind, needs in EVIDENCE_NEEDS.items():
        complete = {"kind": kind, **{field: ["a reading"] for field in needs}}
        assert evidence_problems(Entry(**base, evidence=complete)) == []
        for field in needs:
            partial = {k: v for k, v in complete.items() if k != field}
            assert evidence_problems(Entry(**base, evidence=partial)) == [
                f"demo.x: evidence of kind {kind} needs {field}"
            ]


def test_thesis_error_sections_link_to_a_page_of_the_book():
    pages = set(notebooks())
    for key, entry in REFERENCE.items():
        if entry.evidence and entry.evidence.get("kind") == "thesis-error":
            assert entry.evidence["section"].partition("#")[0] in pages, key


def test_the_ledger_shows_the_evidence_kind_beside_deviates_and_totals_by_kind():
    evidence = {
        "kind": "thesis-error",
        "certificate": "bound {{s.bound:.1f}} above the printed value",
        "section": "findings#finding-demo",
    }
    reference = {
        "s.a": Entry(
            key="s.a",
            where="p. 1",
            kind="deterministic",
            thesis=1.0,
            tol=0.01,
            expect="deviates",
            evidence=evidence,
        ),
        "s.b": Entry(
            key="s.b",
            where="p. 2",
            kind="deterministic",
            thesis=1.0,
            tol=0.01,
            expect="deviates",
            evidence={"kind": "open", "tried": "two readings"},
        ),
    }
    values = {"s.a": 2.0, "s.b": 3.0, "s.bound": 41.25}
    page = ledger_markdown(reference, values)
    assert "{bdg-warning}`deviates` {bdg-danger-line}`thesis error`" in page
    assert "{bdg-warning}`deviates` {bdg-secondary-line}`open`" in page
    assert (
        "bound 41.2 above the printed value" in page and 'href="findings.html#finding-demo"' in page
    )
    assert "{bdg-danger-line}`1 thesis error` {bdg-secondary-line}`1 open`" in page


def test_a_statistical_claim_shows_n_interval_and_test_and_counts_apart_from_deviates():
    record = {
        "verdict": "not resolved",
        "n": 30,
        "estimate": 0.012,
        "ci_low": -0.02,
        "ci_high": 0.04,
        "test": "paired sign test",
    }
    entry = Entry(
        key="s.claim", where="p. 3", kind="claim", thesis="A is better", expect="not-resolved"
    )
    assert status(entry, record) == "not-resolved"
    assert status(entry, {**record, "verdict": "holds"}) == "reproduced"
    assert status(entry, {**record, "verdict": "fails"}) == "deviates"
    [row] = ledger_rows({entry.key: entry}, {entry.key: record})
    assert row["status"] == "not-resolved" and row["tolerance"] == "[-0.02, 0.04]"
    assert "n = 30" in row["note"] and "paired sign test" in row["note"]
    page = ledger_markdown({entry.key: entry}, {entry.key: record})
    assert "{bdg-info}`1 not resolved`" in page and "deviates`" not in page
    with pytest.raises(ValueError, match="verdict"):
        status(entry, {**record, "verdict": "maybe"})
    from asoc_companion.captions import verdict

    assert verdict([entry.key], {entry.key: entry}, {entry.key: record}) == "not-resolved"


# --- every ledger check can fail (issue 30, item 2) -----------------------------------------------

from asoc_companion.mutants import NOT_PLANTED, ledger_mutants, mutants_path

MUTANTS = ledger_mutants(REFERENCE)


def test_ledger_mutants_cover_every_claim_and_the_committed_file_is_current():
    claims = {k for k, e in REFERENCE.items() if e.kind == "claim"}
    assert set(MUTANTS) == claims
    assert json.loads(mutants_path().read_text())["values"] == MUTANTS, (
        "figures/values/ledger_mutants.json is stale: run `python -m asoc_companion ledger`"
    )


@pytest.mark.parametrize(
    "key", sorted(k for k, m in MUTANTS.items() if m["description"] != NOT_PLANTED)
)
def test_each_planted_variant_is_caught(key):
    assert MUTANTS[key]["caught"], f"{key}: the check does not catch {MUTANTS[key]['description']}"


def test_every_claim_has_a_planted_variant():
    # the statistical claims of Secs. 2.5-2.6 get theirs from their recorded decisions
    assert MUTANTS and [k for k, m in MUTANTS.items() if m["description"] == NOT_PLANTED] == []


def test_a_statistical_claim_without_its_recorded_decision_has_no_variant():
    claim = REFERENCE["sec2_5.claim_min_trace_smaller"]
    assert ledger_mutants({claim.key: claim}, values={})[claim.key]["description"] == NOT_PLANTED


def test_every_tolerance_is_a_number():
    # YAML 1.1 reads 1e-09 as text (write 1.0e-9); a text ci_rtol broke the ci comparison
    bad = [
        (key, field, getattr(e, field))
        for key, e in REFERENCE.items()
        for field in ("tol", "ci_rtol")
        if getattr(e, field) is not None
        and (isinstance(getattr(e, field), bool) or not isinstance(getattr(e, field), (int, float)))
    ]
    assert bad == []
