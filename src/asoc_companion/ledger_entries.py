"""The ledger's rows: each reference entry beside its recorded value, formatted, with a status.

:func:`ledger_rows` compares ``tests/reference/thesis_values`` with ``figures/values``; the
ledger page (:mod:`asoc_companion.ledger`) and the landing page's summary
(:mod:`asoc_companion.intro_summary`) lay the rows out, counted by status with
:func:`counts` and shown as badges with :func:`badge`.
"""

import math

from .evidence import evidence_text, is_statistic, statistic_text
from .notebooks import notebooks
from .prose import fill
from .reference import load_reference, status
from .values import load_all_values

__all__ = ["STATUS_TEXT", "BADGE", "SHORT", "badge", "decimals", "ledger_rows", "counts",
           "counts_badges", "notebook_order", "ledger_label"]


STATUS_TEXT = {"reproduced": "reproduced", "deviates": "deviates", "not-resolved": "not resolved",
               "new": "not printed", "missing": "missing"}
BADGE = {"reproduced": "success", "deviates": "warning", "not-resolved": "info", "new": "muted",
         "missing": "danger"}
SHORT = 24                   # longer values of a row go to its note


def badge(st: str, text: str | None = None) -> str:
    """A sphinx-design badge for status ``st`` (``reproduced``, ``deviates``, ``new``, ``missing``).

    Examples
    --------
    >>> badge("deviates"), badge("reproduced", "shows it")
    ('{bdg-warning}`deviates`', '{bdg-success}`shows it`')
    """
    return f"{{bdg-{BADGE[st]}}}`{text or STATUS_TEXT[st]}`"


def decimals(entry) -> int | None:
    """Decimals of ``entry`` as printed: from its rounding tolerance, else from the printed number.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> decimals(Entry("demo.rho", where="an example", kind="deterministic", thesis=0.2503,
    ...     tol=5e-5))
    4
    >>> decimals(Entry("demo.costs", where="an example", kind="measured", thesis=[1.25, 3.5]))
    2
    """
    if entry.tol:
        return max(0, math.ceil(-math.log10(2 * entry.tol) - 1e-9))
    numbers = [v for v in _flat(entry.thesis)
               if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if not numbers:
        return None
    places = lambda text: len(text.split(".")[1].rstrip("0")) if "e" not in text else 4
    return max(places(repr(float(v))) for v in numbers)


def _flat(value):
    if isinstance(value, (list, tuple)):
        for v in value:
            yield from _flat(v)
    else:
        yield value


def _fmt(value, places=None) -> str:
    """``value`` for the table: ``places`` decimals if the precision is known, else 4 digits."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.{places}f}" if places is not None and abs(value) < 1e6 else f"{value:.4g}"
    if isinstance(value, list):
        return "[" + ", ".join(_fmt(v, places) for v in value) + "]"
    if isinstance(value, dict):
        if is_statistic(value):
            return _fmt(value["estimate"], places)
        if "ci" in value:
            return _fmt(value.get("median", value.get("value")), places)
        return _fmt(value.get("value"), places)
    return str(value).replace("|", "\\|").replace("\n", " ")


def _tolerance(entry, ours, places) -> str:
    if entry.kind == "deterministic":
        return f"± {entry.tol:g}"
    if entry.kind == "monte_carlo" and isinstance(ours, dict):
        lo, hi = ours["ci"]
        return f"[{_fmt(lo, places)}, {_fmt(hi, places)}]"
    if is_statistic(ours):
        return f"[{_fmt(ours['ci_low'], places)}, {_fmt(ours['ci_high'], places)}]"
    return "check" if entry.kind == "claim" else "–"


def ledger_rows(reference=None, values=None):
    """One dict per reference entry: key, notebook, where, claim, thesis, ours, ours_long,
    tolerance, status, note.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> reference = {"demo.rho": Entry("demo.rho", where="p. 1", kind="deterministic", thesis=0.25,
    ...     tol=5e-5,
    ...                                note="Spectral radius {{demo.rho:.3f}}.")}
    >>> [row] = ledger_rows(reference, {"demo.rho": 0.2500001})
    >>> row["thesis"], row["ours"], row["tolerance"], row["status"], row["note"]
    ('0.2500', '0.250000', '± 5e-05', 'reproduced', 'Spectral radius 0.250.')
    """
    reference = reference if reference is not None else load_reference()
    values = values if values is not None else load_all_values()
    rows = []
    for key, entry in reference.items():
        ours_value = values.get(key)
        st = status(entry, ours_value)
        places = None if decimals(entry) is None else decimals(entry) + 2
        note = " ".join(t for t in (statistic_text(ours_value) if is_statistic(ours_value) else "",
                                    fill(" ".join(entry.note.split()), values),
                                    fill(evidence_text(entry.evidence), values)) if t)
        if st != entry.expect and st != "missing":
            note = f"(status changed from expected '{entry.expect}') " + note
        ours = _fmt(ours_value, places)
        claim = entry.kind == "claim"
        rows.append(dict(key=key, name=entry.name, notebook=entry.notebook, where=entry.where,
                         claim=str(entry.thesis) if claim else "",
                         thesis="claim" if claim else _fmt(entry.thesis,
                                                           None if places is None else places - 2),
                         ours=ours if len(ours) <= SHORT else "see note",
                         ours_long=ours if len(ours) > SHORT else "",
                         tolerance=_tolerance(entry, ours_value, places), status=st, note=note,
                         evidence=(entry.evidence or {}).get("kind", "")))
    return rows


def counts(rows) -> dict:
    """``{status: number of rows}``.

    Examples
    --------
    >>> counts([{"status": "reproduced"}, {"status": "deviates"}, {"status": "reproduced"}])
    {'reproduced': 2, 'deviates': 1}
    """
    out = {}
    for row in rows:
        out[row["status"]] = out.get(row["status"], 0) + 1
    return out


def counts_badges(c) -> str:
    """The badges of the counts ``c`` (``{status: number}``), in the order of :data:`STATUS_TEXT`.

    Parameters
    ----------
    c : dict
        ``{status: number of rows}``, as :func:`counts` returns it.

    Returns
    -------
    str

    Examples
    --------
    >>> counts_badges({"deviates": 1, "reproduced": 2})
    '{bdg-success}`2 reproduced` {bdg-warning}`1 deviates`'
    """
    return " ".join(badge(s, f"{c[s]} {STATUS_TEXT[s]}") for s in STATUS_TEXT if c.get(s))


def notebook_order(rows):
    """The notebooks of ``rows`` with their information, in the book's order (unknown ones last).

    Parameters
    ----------
    rows : list of dict
        Ledger rows (:func:`ledger_rows`); only their ``"notebook"`` is read.

    Returns
    -------
    list of tuple
        ``(notebook name, NotebookInfo or None)`` for each notebook that has a row.
    """
    infos = notebooks()
    names = list(infos) + [n for n in dict.fromkeys(r["notebook"] for r in rows) if n not in infos]
    return [(n, infos.get(n)) for n in names if any(r["notebook"] == n for r in rows)]


def ledger_label(notebook: str) -> str:
    """The MyST label of a notebook's section on the ledger page.

    Examples
    --------
    >>> ledger_label("sec3_5")
    'ledger-sec3_5'
    """
    return f"ledger-{notebook}"
