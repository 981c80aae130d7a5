"""Counterexamples of the theorems study: saved as data, the one to show chosen, printed rounded."""

import json
import re
from pathlib import Path

from ..atomic_files import atomic_write_json
from ..plan import values_folder
from .chapter3 import MARGIN, SHOW
from .engine import verdict_text
from .statement import Outcome
from .typeset import CHECKS_TEX, CORRECTIONS_TEX, MUTANTS_TEX

__all__ = ["COUNTEREXAMPLES", "SYSTEMS_KEPT", "save_counterexamples", "load_counterexamples",
           "margin", "shown_counterexample", "describe", "mutant_text", "typeset",
           "statements_markdown", "StatementsPage"]


COUNTEREXAMPLES = "theorems_counterexamples.json"
# system matrices saved for the 20 smallest counterexamples per statement
SYSTEMS_KEPT = 20


def save_counterexamples(results, seed, folder) -> Path:
    """Every failing instance (statement, index, deciding numbers, system) as JSON, atomically."""
    statements = {key: [{"index": int(i), "numbers": res.failures[i]} for i in sorted(res.failures)]
                  for key, res in results.items() if res.failures}
    data = {"seed": int(seed), "statements": {key: _trim_systems(key, entries) for key,
                                              entries in statements.items()}}
    # shaped like a notebook's values file, which every reader of figures/values expects
    return atomic_write_json(values_folder(folder) / COUNTEREXAMPLES,
                             {"notebook": COUNTEREXAMPLES.removesuffix(".json"), "values": data})


def _trim_systems(key, entries, keep=SYSTEMS_KEPT):
    """Keep the system matrices of the ``keep`` smallest counterexamples (the order of
    :func:`shown_counterexample`); the others keep their numbers and re-run from (seed, key, index).
    """
    order = sorted(entries, key=lambda e: _order(key, e))
    kept = {e["index"] for e in order[:keep]}
    return [e if e["index"] in kept else {"index": e["index"],
                                          "numbers": {k: v for k,
                                                      v in e["numbers"].items() if k != "system"}}
            for e in entries]


def load_counterexamples(folder):
    """The saved counterexamples, or None when there is no file."""
    path = values_folder(folder) / COUNTEREXAMPLES
    return json.loads(path.read_text())["values"] if path.exists() else None


def margin(key, numbers) -> float:
    """How clearly the instance fails (0 when the statement has no measure)."""
    return float(MARGIN[key](numbers)) if key in MARGIN else 0.0


def shown_counterexample(key, entries):
    """Among the failing instances with the fewest states, then modes, the one that fails most
    clearly (largest margin: its verdict survives rounding and other BLAS kernels); ties by index.
    """
    if not entries:
        return None
    return min(entries, key=lambda e: _order(key, e))


def _order(key, entry):
    n = entry["numbers"]
    return (n.get("n_states", 0), n.get("n_modes", 0), -margin(key, n), entry["index"])


def describe(key, outcome: Outcome) -> str:
    """One line per deciding number, rounded to what is meant (same text, other BLAS kernels)."""
    n = outcome.numbers
    lines = [f"{key}: {outcome.verdict}; {n.get('n_states')} states, {n.get('n_modes')} modes, "
             f"{n.get('n_inputs')} input(s), {n.get('n_outputs')} output(s)"]
    for label, name, spec in SHOW.get(key, []):
        value = n.get(name)
        if spec == "<1":
            text = "yes" if value is not None and value < 1 else "no"
        elif isinstance(value, bool) or value is None:
            text = {True: "yes", False: "no", None: "-"}[value]
        else:
            text = format(value, spec)
        lines.append(f"  {label}: {text}")
    return "\n".join(lines)


def mutant_text(record) -> str:
    """"caught in 37 of 100" (or "NOT caught in 0 of 100", "-" when the mutant was not run)."""
    mutant = record.get("mutant")
    if not mutant:
        return "-"
    caught = "caught" if mutant["fails"] else "NOT caught"
    return f"{caught} in {mutant['fails']} of {mutant['instances']}"


# The Theorems page as MyST Markdown: rendered by the HTML and the LaTeX builders alike (math
# typeset by MathJax and by LaTeX), a compact table first, then one section per statement.

_MARKDOWN_SPECIAL = re.compile(r"([\\`*_\[\]<>#|])")


def _markdown_text(text: str) -> str:
    """``text`` for MyST Markdown: Markdown's special characters escaped outside ``$...$`` math.

    Examples
    --------
    >>> _markdown_text(r"x_k [a] and $\\mathbf x_k$")
    'x\\\\_k \\\\[a\\\\] and $\\\\mathbf x_k$'
    """
    parts = text.split("$")
    if len(parts) % 2 == 0:
        raise ValueError(f"text: expected paired $ signs, found {text!r}")
    return "$".join(part if k % 2 else _MARKDOWN_SPECIAL.sub(r"\\\1", part)
                    for k, part in enumerate(parts))


def typeset(table: dict, text: str) -> str:
    """``text`` as Markdown: its typeset form from ``table`` (theorems.typeset), else escaped."""
    return table.get(text) or _markdown_text(text)


def _mutant_markdown(mutant) -> str:
    """A mutant's description with its math typeset (``MUTANTS_TEX``), as Markdown."""
    return typeset(MUTANTS_TEX, mutant["description"])


def _anchor(key: str) -> str:
    return "check-" + key.removeprefix("statement_").replace("_", "-")


def _links(st, record, findings) -> str:
    links = []
    if record.get("fails"):
        links.append(f"{{ref}}`counterexample <{st.key.replace('_', '-')}>`")
    if st.key in findings:
        links.append(f"{{ref}}`finding <{findings[st.key]}>`")
    return ", ".join(links)


def statements_markdown(statements, records, findings) -> str:
    """The theorems page's statements as MyST Markdown: one compact table (statement, verdict,
    whether the check caught its mutant, a link to the statement's section), then per statement a
    section with the claim, what one instance checks, the verdict, the mutant, and (when the record
    has them) the diagnosis and the corrected statement with its verdict. ``records`` maps a key to
    its recorded value (``StatementResult.recorded_value()``); ``findings`` maps a key to a label of
    the findings page.

    Examples
    --------
    >>> from asoc_companion.theorems.statement import Statement
    >>> lemma = Statement("statement_3_0", "Lemma 3.0", "$|x| >= 0$", "nothing",
    ...                   not_checkable="a definition")
    >>> page = statements_markdown([lemma], {}, {})
    >>> "| {ref}`Lemma 3.0 <check-3-0>` | not checkable | - |" in page
    True
    >>> "**Lemma 3.0.** $|x| >= 0$" in page
    True
    """
    rows = ["| Statement | Verdict | Mutant |", "| :-- | :-- | :-- |"]
    sections = []
    for st in statements:
        record = records.get(st.key, {})
        title = f"{{ref}}`{st.label} <{_anchor(st.key)}>`"
        lines = [f"({_anchor(st.key)})=", f"**{st.label}.** {st.summary}", "",
                 f"- *One instance checks:* {typeset(CHECKS_TEX, st.checked)}"]
        if st.check is None:
            rows.append(f"| {title} | not checkable | - |")
            lines.append(f"- *Not checkable:* {_markdown_text(st.not_checkable)}")
        else:
            verdict = verdict_text(record)
            rows.append(f"| {title} | {'**' + verdict + '**' if record['fails'] else verdict} "
                        f"| {mutant_text(record)} |")
            links = _links(st, record, findings)
            lines.append(f"- *Verdict:* {verdict}" + (f" ({links})" if links else ""))
            if record.get("mutant"):
                mutant = _mutant_markdown(record["mutant"])
                lines.append(f"- *Mutant:* {mutant}; {mutant_text(record)}")
        lines += _correction_lines(record)
        sections.append("\n".join(lines))
    return "\n".join(rows) + "\n\n" + "\n\n".join(sections) + "\n"


def _correction_lines(record) -> list:
    lines = []
    if record.get("diagnosis"):
        lines.append(f"- *Diagnosis:* {_markdown_text(record['diagnosis'])}")
    if record.get("corrected"):
        corrected = record["corrected"]
        statement = typeset(CORRECTIONS_TEX, corrected["statement"])
        text = (f"- *Corrected statement:* {statement} "
                f"(*{verdict_text({**corrected, 'not_applicable': 0})}*")
        if corrected.get("mutant"):
            text += f"; mutant {_mutant_markdown(corrected['mutant'])}: {mutant_text(corrected)}"
        lines.append(text + ")")
    elif record.get("no_correction"):
        lines.append(f"- *No correction found:* {_markdown_text(record['no_correction'])}")
    return lines


class StatementsPage:
    """The statements of the theorems page for display in a notebook: Markdown (MyST) only, so
    that the HTML and the PDF render the same table and sections (:func:`statements_markdown`).
    """

    def __init__(self, statements, records, findings):
        self.markdown = statements_markdown(statements, records, findings)

    def _repr_markdown_(self):
        return self.markdown
