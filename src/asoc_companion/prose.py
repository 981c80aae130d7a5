"""Numbers in prose come from recorded values (book/architecture.md, "Portability").

Text (a ledger note, a notebook paragraph, the findings page) names a recorded value by a
placeholder ``{{path:spec}}`` and :func:`fill` replaces it by the value formatted with the
Python format ``spec``:

- ``path`` is ``<notebook>.<key>`` or, inside a notebook, just ``<key>`` (the current
  notebook's value, see :func:`prose`); it may go on into dicts and lists:
  ``{{sec2_5.mc_cost_proposed.ci[0]:.1f}}``, ``{{sec3_6.iters.T1}}``;
- inside a notebook, ``thesis_<notebook>.<key>`` is the value the thesis prints for a
  reference entry (``tests/reference/thesis_values``), so quotes of printed numbers are not
  typed either: ``{{thesis_sec3_5.rho_open_T1:.4f}}``;
- a Monte Carlo record (a dict with ``value`` or ``median`` and ``ci``) prints as ``m [lo, hi]``, a
  claim
  record (``holds``, ``value``) prints its value, a bool prints ``yes``/``no``.

An unknown path raises ``KeyError`` naming it: a number is never typed in its place.
"""

import re

__all__ = ["PLACEHOLDER", "fill", "thesis_values", "prose"]


PLACEHOLDER = re.compile(r"\{\{\s*([A-Za-z_][\w.\[\]-]*?)\s*(?::\s*([^{}]*?))?\s*\}\}")
_STEP = re.compile(r"\.?([A-Za-z0-9_-]+)|\[(-?\d+)\]")


def _lookup(path: str, values: dict, notebook: str | None = None):
    """The value at ``path`` in ``values`` (``{"<notebook>.<key>": value}``).

    Examples
    --------
    >>> values = {"sec3_5.rho": 0.25, "sec2_5.cost": {"median": 1.5, "ci": [1.25, 1.75]}}
    >>> _lookup("sec2_5.cost.ci[0]", values), _lookup("rho", values, notebook="sec3_5")
    (1.25, 0.25)
    >>> _lookup("sec3_5.gain", values)
    Traceback (most recent call last):
    ...
    KeyError: '{{sec3_5.gain}}: sec3_5.gain is not recorded'
    """
    steps = [name or int(index) for name, index in _STEP.findall(path)]
    if any(k.startswith(f"{steps[0]}.") for k in values) and len(steps) > 1:
        key, rest = f"{steps[0]}.{steps[1]}", steps[2:]
    elif notebook is not None:
        key, rest = f"{notebook}.{steps[0]}", steps[1:]
    else:
        raise KeyError(f"{{{{{path}}}}}: no notebook named {steps[0]!r} has recorded values")
    if key not in values:
        raise KeyError(f"{{{{{path}}}}}: {key} is not recorded")
    value = values[key]
    for step in rest:
        try:
            value = value[step]
        except (KeyError, IndexError, TypeError):
            raise KeyError(f"{{{{{path}}}}}: {key} has no part {step!r}") from None
    return value


def _format_value(value, spec: str = "") -> str:
    """``value`` formatted with ``spec`` (Monte Carlo records as ``m [lo, hi]``).

    Examples
    --------
    >>> _format_value({"median": 1.5, "ci": [1.25, 1.75]},
    ...     ".2f"), _format_value(True), _format_value([0.5, 1], ".1f")
    ('1.50 [1.25, 1.75]', 'yes', '[0.5, 1.0]')
    """
    if isinstance(value, dict):
        if "ci" in value and ("median" in value or "value" in value):
            lo, hi = value["ci"]
            centre = _format_value(value.get("median", value.get("value")), spec)
            return f"{centre} [{_format_value(lo, spec)}, {_format_value(hi, spec)}]"
        if "value" in value:
            return _format_value(value["value"], spec)
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, list):
        return "[" + ", ".join(_format_value(v, spec) for v in value) + "]"
    return format(value, spec) if spec else str(value)


def fill(text: str, values: dict, notebook: str | None = None) -> str:
    """``text`` with every ``{{path:spec}}`` replaced by the recorded value.

    Parameters
    ----------
    text : str
        Text with placeholders ``{{path:spec}}``.
    values : dict
        ``{"<notebook>.<key>": value}``, e.g. :func:`load_all_values`.
    notebook : str, optional
        Resolves unqualified paths ``{{key}}``.

    Returns
    -------
    str

    Raises
    ------
    KeyError
        If a placeholder names a value that is not recorded.

    Examples
    --------
    >>> fill("rho = {{sec3_5.rho:.3f}}, stable: {{stable}}", {"sec3_5.rho": 0.25,
    ...     "sec3_5.stable": True}, "sec3_5")
    'rho = 0.250, stable: yes'
    """
    formatted = lambda m: _format_value(_lookup(m.group(1), values, notebook), m.group(2) or "")
    return PLACEHOLDER.sub(formatted, text)


def thesis_values(reference=None) -> dict:
    """The printed values of the reference entries, keyed ``thesis_<notebook>.<key>``.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> entry = Entry("demo.rho", where="an example", kind="deterministic", thesis=0.25, tol=5e-5)
    >>> thesis_values({entry.key: entry})
    {'thesis_demo.rho': 0.25}
    """
    from .reference import load_reference

    reference = reference if reference is not None else load_reference()
    return {f"thesis_{e.notebook}.{e.name}": e.thesis for e in reference.values()
            if e.thesis is not None}


def prose(text: str):
    """Markdown for a notebook cell: ``text`` filled from this notebook's values, the committed ones
    and the thesis's printed values (``{{thesis_<notebook>.<key>}}``).

    Parameters
    ----------
    text : str
        Markdown with placeholders ``{{key:spec}}`` (this notebook) or
        ``{{notebook.key:spec}}``.

    Returns
    -------
    IPython.display.Markdown

    Raises
    ------
    KeyError
        If a placeholder names a value that is not recorded.

    Examples
    --------
    In a temporary checkout whose reference gives the thesis's ``demo.rho``, a run of ``demo``
    records its own ``rho`` and quotes both (the active recorder, the style and the variable are
    restored afterwards):

    >>> from asoc_companion import paths, recorder
    >>> with paths.scratch_project() as root, recorder.scratch_run(output_dir=root / "staging"):
    ...     _ = (paths.project().reference / "demo.yaml").write_text(
    ...         "demo.rho: {where: an example, kind: deterministic, thesis: 0.25, tol: 5.0e-5}")
    ...     _ = recorder.record("rho", 0.2500001)
    ...     print(prose("rho = {{rho:.4f}} (thesis: {{thesis_demo.rho}})").data)
    rho = 0.2500 (thesis: 0.25)
    """
    from IPython.display import Markdown

    from .recorder import active, current_values

    recorder = active(required=False)
    values = {**thesis_values(), **current_values()}
    return Markdown(fill(text, values, recorder.notebook if recorder else None))


