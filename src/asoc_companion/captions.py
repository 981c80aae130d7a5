"""Figure captions that say what the thesis claims about a figure and whether ours shows it.

The registry ``tests/reference/figure_claims.yaml`` holds, per figure number, the thesis's
statement (``claim``, quoted, with ``where``) and the reference keys that check it; the
caption's verdict is the ledger status of those keys, so it can never disagree with the
ledger. In a notebook, a code cell ``repro.figure_caption("3.4")`` right after the figure
renders the caption.
"""

import yaml

from . import paths
from .ledger import badge, ledger_label
from .reference import SAFE_LOADER, load_reference, status

__all__ = ["CLAIMS_NAME", "load_claims", "verdict", "caption_markdown", "STATUS_WORDS",
           "figure_caption"]


CLAIMS_NAME = "figure_claims.yaml"


def _claims_path():
    """``tests/reference/figure_claims.yaml`` of the project.

    Examples
    --------
    >>> with paths.scratch_project() as root:
    ...     print(_claims_path().relative_to(root).as_posix())
    tests/reference/figure_claims.yaml
    """
    return paths.project().reference.parent / CLAIMS_NAME


def load_claims(path=None) -> dict:
    """``{figure number: {"where", "claim", "keys"}}`` from the registry, validated.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "figure_claims.yaml"
    ...     _ = path.write_text("own.1: {where: p. 1, claim: The loop is stable., "
    ...                         "keys: [sec_demo.rho]}")
    ...     print(load_claims(path))
    {'own.1': {'where': 'p. 1', 'claim': 'The loop is stable.', 'keys': ['sec_demo.rho']}}
    """
    with open(path or _claims_path()) as handle:
        raw = yaml.load(handle, Loader=SAFE_LOADER) or {}
    for number, spec in raw.items():
        missing = {"where", "claim", "keys"} - set(spec)
        if missing:
            raise ValueError(f"figure_claims: figure {number} lacks {sorted(missing)}")
    return {str(number): spec for number, spec in raw.items()}


def verdict(keys, reference, values) -> str:
    """``reproduced`` if every key is, ``deviates`` if any deviates, ``missing`` if any value is
    absent, else ``not-resolved`` if a statistical claim among them is not resolved.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> reference = {"sec_demo.rho": Entry("sec_demo.rho", where="p. 1", kind="deterministic",
    ...     thesis=0.25, tol=5e-5)}
    >>> verdict(["sec_demo.rho"], reference, {"sec_demo.rho": 0.25}), verdict(["sec_demo.rho"],
    ...     reference, {})
    ('reproduced', 'missing')
    """
    statuses = [status(reference[k], values.get(k)) for k in keys]
    for st in ("missing", "deviates", "not-resolved"):
        if st in statuses:
            return st
    return "reproduced"


def caption_markdown(number: str, claims=None, reference=None, values=None) -> str:
    """The caption of figure ``number``: the thesis's claim and, in one line, whether ours shows it.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> rho = Entry("sec_demo.rho", where="p. 1", kind="deterministic", thesis=0.25, tol=5e-5)
    >>> claims = {"own.1": {"where": "p. 1", "claim": "The loop is stable.", "keys": [rho.key]}}
    >>> print(caption_markdown("own.1", claims, {rho.key: rho}, {rho.key: 0.2500001}), end="")
    :::{container} asoc-caption
    **Fig. own.1, the thesis** (p. 1): “The loop is stable.”
    <BLANKLINE>
    **Ours:** {bdg-success}`shows it` checks reproduced: 1 of 1 (`rho`;
    {ref}`ledger <ledger-sec_demo>`).
    :::
    """
    claims = claims if claims is not None else load_claims()
    reference = reference if reference is not None else load_reference()
    if number not in claims:
        raise ValueError(f"number: figure {number!r} has no entry in {CLAIMS_NAME}; known: "
                         f"{', '.join(claims)}")
    spec = claims[number]
    unknown = [k for k in spec["keys"] if k not in reference]
    if unknown:
        raise ValueError(f"figure_claims: figure {number} names unknown reference keys {unknown}")
    head = f"**Fig. {number}, the thesis** ({spec['where']}): “{spec['claim']}”"
    if not spec["keys"]:
        line = (f"**Ours:** {badge('new', 'nothing to check')} the thesis makes no checkable "
                "claim about this figure.")
    else:
        st = verdict(spec["keys"], reference, values or {})
        n_ok = sum(status(reference[k], (values or {}).get(k)) == "reproduced"
                   for k in spec["keys"])
        notebooks = dict.fromkeys(k.split(".", 1)[0] for k in spec["keys"])
        where = ", ".join(f"{{ref}}`ledger <{ledger_label(n)}>`" for n in notebooks)
        words = ("shows it" if st == "reproduced"
                 else "shows it in part" if st == "deviates" and n_ok else STATUS_WORDS[st])
        line = (f"**Ours:** {badge(st, words)} checks reproduced: {n_ok} of {len(spec['keys'])} "
                f"({', '.join('`' + k.split('.', 1)[1] + '`' for k in spec['keys'])}; {where}).")
    return f":::{{container}} asoc-caption\n{head}\n\n{line}\n:::\n"


STATUS_WORDS = {"deviates": "does not show it", "missing": "not computed",
                "not-resolved": "not resolved"}


def figure_caption(number: str):
    """Markdown for a notebook cell: the caption of figure ``number`` from the current values.

    Examples
    --------
    In a temporary checkout with a claim on figure own.1, its reference entry and a committed value:

    >>> from asoc_companion.recorder import Recorder
    >>> with paths.scratch_project() as root:
    ...     _ = (root / "tests/reference/figure_claims.yaml").write_text(
    ...         "own.1: {where: p. 1, claim: The loop is stable., keys: [sec_demo.rho]}")
    ...     _ = (root / "tests/reference/thesis_values/sec_demo.yaml").write_text(
    ...         "sec_demo.rho: {where: p. 1, kind: deterministic, thesis: 0.25, tol: 5.0e-5}")
    ...     _ = Recorder("sec_demo", "full", root / "figures").record("rho", 0.2502)
    ...     print(figure_caption("own.1").data.splitlines()[3])
    **Ours:** {bdg-warning}`does not show it` checks reproduced: 0 of 1 (`rho`;
    {ref}`ledger <ledger-sec_demo>`).
    """
    from IPython.display import Markdown

    from .recorder import current_values

    return Markdown(caption_markdown(str(number), values=current_values()))


def _caption_cell(number, output, count):
    import nbformat

    cell = nbformat.v4.new_code_cell(f'repro.figure_caption("{number}")',
                                     metadata={"tags": ["remove-input"]})
    if output is not None:
        cell.execution_count = count          # nbval rejects stored outputs of a cell never run
        cell.outputs = [nbformat.v4.new_output("display_data", data={
            "text/markdown": output, "text/plain": "<IPython.core.display.Markdown object>"})]
    return cell


def _insert_caption_cells(path, with_output=False) -> list:
    """Add a ``repro.figure_caption`` cell after each figure of the notebook at
    ``path`` that lacks one.

    The cell goes right after the cell that saves the figure (after its Markdown caption, if
    one follows). Other cells are left untouched; ``with_output`` stores the caption rendered
    from the committed values (what executing the new cell gives). Returns the numbers added.

    Examples
    --------
    >>> import nbformat, pathlib, tempfile
    >>> nb = nbformat.v4.new_notebook(metadata={"asoc": {"figures": ["own.1"]}})
    >>> nb.cells = [nbformat.v4.new_code_cell('save_figure(fig, "own.1")'),
    ...             nbformat.v4.new_markdown_cell("**Figure own.1.** The closed loop."),
    ...             nbformat.v4.new_markdown_cell("## Next section")]
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "demo.ipynb"
    ...     nbformat.write(nb, path)
    ...     print(_insert_caption_cells(path), _insert_caption_cells(path))
    ...     print([cell.source for cell in nbformat.read(path, as_version=4).cells][2])
    ['own.1'] []
    repro.figure_caption("own.1")
    """
    import re

    import nbformat

    from .values import load_all_values

    nb = nbformat.read(path, as_version=4)
    values = load_all_values() if with_output else None
    added = []
    for number in nb.metadata.get("asoc", {}).get("figures", []):
        call = f'figure_caption("{number}")'
        if any(call in c.source for c in nb.cells):
            continue
        saves = [i for i, c in enumerate(nb.cells) if c.cell_type == "code"
                 # save_figure(fig, "N"), f(..., "N")
                 and re.search(rf',\s*"{re.escape(number)}"\)', c.source)]
        if not saves:
            raise ValueError(f"path: {path} saves no figure {number}")
        at = saves[0] + 1
        if (at < len(nb.cells) and nb.cells[at].cell_type == "markdown"
                and nb.cells[at].source.startswith("**Figure")):
            at += 1
        count = max((c.get("execution_count") or 0 for c in nb.cells[:at] if c.cell_type == "code"),
                    default=0)
        caption = caption_markdown(number, values=values) if with_output else None
        nb.cells.insert(at, _caption_cell(number, caption, count))
        added.append(number)
    if added:
        nbformat.write(nb, path)
    return added


