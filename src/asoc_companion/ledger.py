"""The reproduction ledger: every printed number next to ours, with tolerance and status.

The page is laid out to fit a 1280-px window: per notebook a compact table (the key,
linked to the notebook section that records it, a status badge, the numbers rounded to
the thesis's decimals plus two, a link to its note) and below it the notes, each shared
note printed once for its group of rows. :func:`write_ledger` also refreshes the
per-section summary on the intro page.
"""

import re

from . import paths
from .anchors import section_links
from .atomic_files import atomic_write_text
from .evidence import evidence_badge, evidence_badges
from .figures import markdown_table
from .intro_summary import (
    FINDINGS,
    SUMMARY,
    VERDICT,
    intro_markdown,
    totals_markdown,
    verdict_markdown,
    write_intro_summary,
)
from .ledger_entries import (
    BADGE,
    SHORT,
    STATUS_TEXT,
    badge,
    counts,
    counts_badges,
    decimals,
    ledger_label,
    ledger_rows,
    notebook_order,
)

__all__ = ["STATUS_TEXT", "BADGE", "SHORT", "SHARED_PREFIX", "SUMMARY", "FINDINGS", "VERDICT",
           "badge", "decimals", "ledger_rows", "note_groups", "FIELDS", "counts", "ledger_label",
           "ledger_markdown", "totals_markdown", "verdict_markdown", "intro_markdown",
           "write_ledger"]


# notes sharing this many leading characters (whole sentences) are grouped
SHARED_PREFIX = 200
_SENTENCE = re.compile(r"(?<=[.:;])\s+")


def _shared(notes):
    """The leading and trailing sentences that all ``notes`` (lists of sentences) have in common."""
    n = min(map(len, notes))
    pre = 0
    while pre < n and all(s[pre] == notes[0][pre] for s in notes):
        pre += 1
    suf = 0
    while suf < n - pre and all(s[-1 - suf] == notes[0][-1 - suf] for s in notes):
        suf += 1
    return notes[0][:pre], notes[0][len(notes[0]) - suf:]


def note_groups(rows):
    """Rows grouped by note: ``[(shared_head, shared_tail, [(own_text, [rows])])]``.

    Rows with the same note form one group; consecutive groups whose notes begin or end with
    the same sentences (together at least ``SHARED_PREFIX`` characters) share that text,
    printed once, and keep only the sentences in which they differ.

    Examples
    --------
    Rows with the same note form one group, printed once:

    >>> rows = [{"name": "a", "note": "Too few runs."}, {"name": "b", "note": "Too few runs."},
    ...         {"name": "c", "note": "Another reading."}]
    >>> [(head, [[r["name"] for r in members] for _, members in parts]) for head, _,
    ...     parts in note_groups(rows)]
    [('Too few runs.', [['a', 'b']]), ('Another reading.', [['c']])]
    """
    by_note = {}
    for row in rows:
        by_note.setdefault(row["note"], []).append(row)
    groups = []
    for note, members in by_note.items():
        candidate = groups[-1] + [(_SENTENCE.split(note), members)] if groups else []
        pre, suf = _shared([s for s, _ in candidate]) if candidate else ([], [])
        if len(" ".join(pre + suf)) >= SHARED_PREFIX:
            groups[-1] = candidate
        else:
            groups.append([(_SENTENCE.split(note), members)])
    out = []
    for group in groups:
        pre, suf = _shared([s for s, _ in group]) if len(group) > 1 else (group[0][0], [])
        out.append((" ".join(pre), " ".join(suf),
                    [(" ".join(s[len(pre):len(s) - len(suf)]), members) for s, members in group]))
    return out


def _key_list(members) -> str:
    names = [f"`{r['name']}`" for r in members]
    if len(names) > 4:
        return f"{names[0]} … {names[-1]} ({len(names)} rows)"
    return ", ".join(names)


FIELDS = (("where", "Where"), ("claim", "Thesis"), ("ours_long", "Ours"))


def _row_details(members, fields=FIELDS) -> str:
    """Where printed, the claim's text and long values of ``members`` (once if they agree)."""
    parts = []
    for field, label in fields:
        texts = [r[field] for r in members if r[field]]
        quote = (lambda t: f"“{t.rstrip('.')}”") if field == "claim" else (lambda t: t.rstrip("."))
        if len(set(texts)) == 1:
            parts.append(f"*{label}:* {quote(texts[0])}.")
        elif texts:
            each = "; ".join(f"`{r['name']}`: {quote(r[field])}" for r in members if r[field])
            parts.append(f"*{label}:* {each}.")
    return " ".join(parts)


def _common_fields(members):
    """The detail fields on which all ``members`` agree, and the others."""
    same = tuple(f for f in FIELDS if len({r[f[0]] for r in members}) == 1)
    return same, tuple(f for f in FIELDS if f not in same)


def _status_cell(row) -> str:
    """The status badge, and beside "deviates" the evidence kind's badge."""
    kind = row.get("evidence") if row["status"] == "deviates" else ""
    return badge(row["status"]) + (" " + evidence_badge(kind) if kind else "")


def _breakable(name: str) -> str:
    """``name`` with line-break opportunities after its underscores (HTML)."""
    return name.replace("_", "_<wbr>")


def _notebook_section(notebook, info, mine) -> str:
    links = section_links(info.path, [r["name"] for r in mine]) if info else {}
    ref, notes = {}, []
    noted = [r for r in mine if r["note"] or r["claim"] or r["ours_long"]]
    for n, (head, tail, parts) in enumerate(note_groups(noted), 1):
        label = f"ledger-{notebook}-n{n}"
        members = [r for _, rs in parts for r in rs]
        ref.update({r["key"]: f"{{ref}}`{n} <{label}>`" for r in members})
        lead = f"({label})=\n**[{n}]** {_key_list(members)}: "
        if len(parts) == 1:
            notes.append(lead + f"{_row_details(members)} {head}\n")
        else:
            same, differ = _common_fields(members)
            shared = " ".join(t for t in (_row_details(members, same), head, tail) if t)
            notes.append(lead + shared + "\n\n"
                         + "".join(f"- {_key_list(rs)}: {_row_details(rs, differ)} {own}\n"
                                   for own, rs in parts))
    # raw links: Sphinx does not resolve Markdown links to another page's heading ids
    key_cell = lambda name: (f'<a href="{links[name]}"><code>{_breakable(name)}</code></a>'
                             if name in links else f"`{name}`")
    table = [[key_cell(r["name"]), _status_cell(r), r["thesis"], r["ours"], r["tolerance"],
              ref.get(r["key"], "")] for r in mine]
    title = info.title if info else notebook
    where = f"[`{info.path.name}`]({info.path.stem}): " if info else ""
    return (f"\n({ledger_label(notebook)})=\n## {title}\n\n{where}{counts_badges(counts(mine))} "
            f"{evidence_badges(mine)}\n\n"
            + markdown_table(["key", "status", "thesis", "ours", "tolerance / CI", "note"], table)
            + "\n**Notes**\n\n" + "\n".join(notes))


def ledger_markdown(reference=None, values=None) -> str:
    """The ledger page (MyST Markdown): a summary, then per notebook a table and the notes.

    Parameters
    ----------
    reference : dict, optional
        ``{key: Entry}``; default: :func:`load_reference`.
    values : dict, optional
        ``{"<notebook>.<key>": value}``; default: the committed values.

    Returns
    -------
    str

    Raises
    ------
    KeyError
        If a note names a value that is not recorded (see :func:`fill`).

    Examples
    --------
    In a temporary checkout without notebooks (the section is titled by its name):

    >>> from asoc_companion.reference import Entry
    >>> rho = Entry("sec_demo.rho", where="p. 1", kind="deterministic", thesis=0.25, tol=5e-5,
    ...     note="Too coarse.")
    >>> with paths.scratch_project() as root:
    ...     text = ledger_markdown({rho.key: rho}, {rho.key: 0.2502})
    >>> for line in text.splitlines():
    ...     if line.startswith(("# ", "## ", "| `")):
    ...         print(line)
    # Reproduction ledger
    ## sec_demo
    | `rho` | {bdg-warning}`deviates` | 0.2500 | 0.250200 | ± 5e-05 |
    {ref}`1 <ledger-sec_demo-n1>` |
    """
    rows = ledger_rows(reference, values)
    parts = ["# Reproduction ledger\n\n"
             "Every number the thesis prints in its numerical sections, next to the value this\n"
             "project regenerates at full thesis fidelity. Generated by `python -m asoc_companion "
             "ledger`\n"
             "from `tests/reference/thesis_values/<notebook>.yaml` and `figures/values/*.json`; do "
             "not edit.\n"
             "Deterministic values must match to the printed decimals (*tolerance*); Monte Carlo "
             "medians\n"
             "are compared with the bootstrap 95% interval of our own runs (*CI*); qualitative "
             "claims are\n"
             "explicit checks with the threshold stated in the note. Numbers are rounded to the "
             "thesis's\n"
             "decimals plus two. *Not printed* marks numbers the thesis does not print (readings "
             "tried,\n"
             "timings, comparisons a reader wants). Each key links to the notebook section that "
             "computes\n"
             "it, each note number to the note below the table; the [findings](findings) explain "
             "the\n"
             "deviations that matter.\n\n"
             f"{totals_markdown(rows)}\n"]
    for notebook, info in notebook_order(rows):
        parts.append(_notebook_section(notebook, info,
                                       [r for r in rows if r["notebook"] == notebook]))
    return "".join(parts)


def write_ledger(path=None) -> str:
    """Write ``book/ledger.md`` and the intro's summary; return the ledger's text.

    Parameters
    ----------
    path : path, optional
        Default ``book/ledger.md``.

    Returns
    -------
    str

    Raises
    ------
    KeyError
        If a note names a value that is not recorded (see :func:`fill`).
    OSError
        If the file cannot be written (the previous file is kept: atomic write).

    Examples
    --------
    A temporary checkout whose reference expects ``sec_demo.rho`` = 0.25 and whose values hold
    0.2500001:

    >>> from asoc_companion.recorder import Recorder
    >>> with paths.scratch_project() as root:
    ...     _ = (paths.project().reference / "sec_demo.yaml").write_text(
    ...         "sec_demo.rho: {where: p. 1, kind: deterministic, thesis: 0.25, tol: 5.0e-5, "
    ...         "note: Fine.}")
    ...     _ = Recorder("sec_demo", "full", root / "figures").record("rho", 0.2500001)
    ...     text = write_ledger(root / "book" / "ledger.md")
    ...     written = text == (root / "book" / "ledger.md").read_text()
    >>> written, [line for line in text.splitlines() if line.startswith("| `")]
    (True, ['| `rho` | {bdg-success}`reproduced` | 0.2500 | 0.250000 | ± 5e-05 |
    {ref}`1 <ledger-sec_demo-n1>` |'])
    """
    text = ledger_markdown()
    atomic_write_text(path or paths.project().book / "ledger.md", text)
    if path is None:
        write_intro_summary()
    return text
