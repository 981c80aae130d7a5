"""Evidence on a deviating ledger row, and claims decided by statistics.

A reference entry with ``expect: deviates`` carries ``evidence:``, a mapping whose ``kind`` says
whose fault the deviation is and which further entries it needs:

``thesis-error``  proven; ``certificate`` (what proves it: an exact computation, a bound, a
                  contradiction between two printed numbers, a closed-form counterexample) and
                  ``section`` (the notebook page, ``page`` or ``page#anchor``, that computes it);
``unspecified``   the thesis does not fix a parameter or reading; ``readings`` (the readings
                  tried, a list) and ``closest`` (the one that comes closest);
``open``          neither; ``tried`` (what was tried and what would settle it).

A statistical claim (``expect: not-resolved`` or any claim decided over seeds) records the
mapping ``{verdict, n, estimate, ci_low, ci_high, test}``; its verdict ``holds``, ``fails`` or
``not resolved`` gives the ledger status ``reproduced``, ``deviates`` or ``not-resolved``.
"""

__all__ = ["EVIDENCE_NEEDS", "EVIDENCE_BADGE", "STATISTIC_FIELDS", "VERDICT_STATUS",
           "evidence_problems", "evidence_badge", "evidence_text", "statistic_status",
           "is_statistic", "statistic_text", "evidence_badges"]


EVIDENCE_NEEDS = {
    "thesis-error": ("certificate", "section"),
    "unspecified": ("readings", "closest"),
    "open": ("tried",),
}
EVIDENCE_BADGE = {
    "thesis-error": ("danger", "thesis error"),
    "unspecified": ("primary", "unspecified"),
    "open": ("secondary", "open"),
}
STATISTIC_FIELDS = ("verdict", "n", "estimate", "ci_low", "ci_high", "test")
VERDICT_STATUS = {"holds": "reproduced", "fails": "deviates", "not resolved": "not-resolved"}


def evidence_problems(entry) -> list:
    """What the ``evidence`` of a reference entry lacks (empty when complete or not needed).

    Parameters
    ----------
    entry : asoc_companion.reference.Entry

    Returns
    -------
    list of str
        One sentence per problem, naming the key.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> row = Entry("demo.cost", where="p. 1", kind="measured", expect="deviates",
    ...             evidence={"kind": "open"})
    >>> evidence_problems(row)
    ['demo.cost: evidence of kind open needs tried']
    >>> evidence_problems(Entry("demo.rho", where="p. 1", kind="measured", expect="reproduced"))
    []
    """
    if entry.expect != "deviates" and entry.evidence is None:
        return []
    evidence = entry.evidence
    if not isinstance(evidence, dict):
        return [f"{entry.key}: a deviating row needs evidence (a mapping with kind)"]
    kind = evidence.get("kind")
    if kind not in EVIDENCE_NEEDS:
        return [
            f"{entry.key}: evidence kind must be one of {tuple(EVIDENCE_NEEDS)}, found {kind!r}"
        ]
    problems = [
        f"{entry.key}: evidence of kind {kind} needs {field}"
        for field in EVIDENCE_NEEDS[kind]
        if not evidence.get(field)
    ]
    if (
        kind == "unspecified"
        and evidence.get("readings")
        and not isinstance(evidence["readings"], list)
    ):
        problems.append(f"{entry.key}: evidence readings must be a list")
    return problems


def evidence_badge(kind: str, text: str | None = None) -> str:
    """A sphinx-design outline badge for an evidence ``kind``.

    Examples
    --------
    >>> evidence_badge("thesis-error"), evidence_badge("open", "3 open")
    ('{bdg-danger-line}`thesis error`', '{bdg-secondary-line}`3 open`')
    """
    colour, label = EVIDENCE_BADGE[kind]
    return f"{{bdg-{colour}-line}}`{text or label}`"


def _section_link(section: str) -> str:
    """An HTML link to the page (and anchor) ``page`` or ``page#anchor`` of the book.

    Examples
    --------
    >>> _section_link("findings#finding-table32")
    '<a href="findings.html#finding-table32">findings, finding-table32</a>'
    """
    page, _, anchor = section.partition("#")
    if not anchor:
        return f'<a href="{page}.html">{page}</a>'
    return f'<a href="{page}.html#{anchor}">{page}, {anchor}</a>'


def evidence_text(evidence) -> str:
    """The evidence as a sentence for the row's note (its ``{{key}}`` placeholders left for
    :func:`asoc_companion.prose.fill`).

    Examples
    --------
    >>> evidence = {"kind": "thesis-error", "certificate": "bound {{demo.b:.1f}} > printed.",
    ...             "section": "findings#finding-demo"}
    >>> print(evidence_text(evidence))  # doctest: +NORMALIZE_WHITESPACE
    *Evidence, thesis error:* bound {{demo.b:.1f}} > printed.
    Computed in <a href="findings.html#finding-demo">findings, finding-demo</a>.
    >>> evidence_text({"kind": "unspecified", "readings": ["a", "b"], "closest": "b"})
    '*Evidence, unspecified:* readings tried: a; b. Closest: b.'
    """
    if not evidence:
        return ""
    kind = evidence["kind"]
    head = f"*Evidence, {EVIDENCE_BADGE[kind][1]}:*"
    if kind == "thesis-error":
        body = (
            f"{_sentence(evidence['certificate'])} Computed in "
            f"{_section_link(evidence['section'])}."
        )
    elif kind == "unspecified":
        readings = "; ".join(str(r).rstrip(".") for r in evidence["readings"])
        body = f"readings tried: {readings}. Closest: {_sentence(evidence['closest'])}"
    else:
        body = _sentence(evidence["tried"])
    return f"{head} {body}"


def _sentence(text) -> str:
    text = " ".join(str(text).split())
    return text if text.endswith((".", "!", "?")) else text + "."


def statistic_status(value) -> str:
    """The ledger status of a statistical record ``{verdict, n, estimate, ci_low, ci_high, test}``.

    Raises
    ------
    ValueError
        If a field is missing or the verdict is not ``holds``, ``fails`` or ``not resolved``.

    Examples
    --------
    >>> statistic_status({"verdict": "not resolved", "n": 30, "estimate": 0.01, "ci_low": -0.02,
    ...                   "ci_high": 0.04, "test": "paired sign test"})
    'not-resolved'
    """
    missing = [f for f in STATISTIC_FIELDS if f not in value]
    if missing:
        raise ValueError(f"a statistical record needs {STATISTIC_FIELDS}; missing {missing}")
    verdict = str(value["verdict"]).replace("-", " ").replace("_", " ")
    if verdict not in VERDICT_STATUS:
        raise ValueError(
            f"verdict must be one of {tuple(VERDICT_STATUS)}, found {value['verdict']!r}"
        )
    return VERDICT_STATUS[verdict]


def is_statistic(value) -> bool:
    """Whether ``value`` is a statistical claim record (it has a ``verdict``).

    Examples
    --------
    >>> is_statistic({"verdict": "holds"}), is_statistic({"holds": True})
    (True, False)
    """
    return isinstance(value, dict) and "verdict" in value


def statistic_text(value) -> str:
    """n, the interval and the test of a statistical record, for the row's note.

    Examples
    --------
    >>> statistic_text({"verdict": "not resolved", "n": 30, "estimate": 0.0123, "ci_low": -0.02,
    ...                 "ci_high": 0.041, "test": "paired sign test"})
    ... # doctest: +NORMALIZE_WHITESPACE
    '*Statistics:* n = 30, estimate 0.0123, 95 % interval [-0.02, 0.041], paired sign test:
    not resolved.'
    """
    return (
        f"*Statistics:* n = {value['n']}, estimate {value['estimate']:.3g}, 95 % interval "
        f"[{value['ci_low']:.3g}, {value['ci_high']:.3g}], {value['test']}: {value['verdict']}."
    )


def _evidence_counts(rows) -> dict:
    """``{kind: number of deviating rows}`` over ``rows`` (dicts with ``status`` and ``evidence``).

    Examples
    --------
    >>> _evidence_counts([{"status": "deviates", "evidence": "open"},
    ...                  {"status": "reproduced", "evidence": ""},
    ...                  {"status": "deviates", "evidence": "open"}])
    {'open': 2}
    """
    out = {}
    for row in rows:
        if row["status"] == "deviates" and row.get("evidence"):
            out[row["evidence"]] = out.get(row["evidence"], 0) + 1
    return out


def evidence_badges(rows) -> str:
    """The totals by evidence kind as badges (empty when no row deviates).

    Examples
    --------
    >>> evidence_badges([{"status": "deviates", "evidence": "thesis-error"}])
    '{bdg-danger-line}`1 thesis error`'
    """
    c = _evidence_counts(rows)
    return " ".join(
        evidence_badge(k, f"{c[k]} {EVIDENCE_BADGE[k][1]}") for k in EVIDENCE_NEEDS if c.get(k)
    )
