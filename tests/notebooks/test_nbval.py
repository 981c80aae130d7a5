"""nbval (lax mode) on every committed notebook, re-executed at ci fidelity.

The committed notebooks in ``book/`` hold the outputs of the full-fidelity run. Cells
tagged ``nbval-check-output`` (nbval's cell tag for its ``# NBVAL_CHECK_OUTPUT`` marker)
print numbers that do not depend on the Monte Carlo size (spectral radii, gains, errors);
nbval re-executes the notebook with papermill's ci parameters injected and requires those
printed outputs to be identical. They print
numbers rounded to what is meant (the thesis's decimals, or a stated accuracy), never a
bare repr, so another CPU's BLAS kernels (``make test-portable``) cannot change them.
The same execution serves the value checks of tests/notebooks/test_notebooks.py (conftest's
``ci_execution``): each notebook runs once per test session, not twice.
"""

import ast

import nbformat
import pytest

from conftest import NOTEBOOKS

CHECK_TAG = "nbval-check-output"


def _checked_cells(nb):
    """The cells nbval compares in lax mode: tagged ``nbval-check-output`` (the tag replaces the
    ``# NBVAL_CHECK_OUTPUT`` comment, which readers of the book saw in the code)."""
    return [
        c for c in nb.cells if c.cell_type == "code" and CHECK_TAG in c.metadata.get("tags", [])
    ]


@pytest.mark.notebook
@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_nbval_checked_cells(name, ci_execution):
    nb = nbformat.read(NOTEBOOKS[name].path, as_version=4)
    checked = _checked_cells(nb)
    info = NOTEBOOKS[name]
    # every numerical section checks its key numbers; other pages are at least re-executed
    assert checked or not (info.figures or info.tables), f"{name}: no cell is tagged {CHECK_TAG}"
    assert all(c.get("outputs") for c in checked), f"{name}: a checked cell has no stored output"
    # nbval on the committed notebook with ci parameters injected
    _, proc = ci_execution(name)
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]


def _ends_in_displayed_expression(source: str) -> bool:
    """Whether a cell's last statement is an expression other than print, display or show (None).

    A trailing ';' does not help: IPython decides on it from the input history, which
    nbval's execution does not record, so nbval sees the full repr anyway.
    """
    code = "\n".join(
        line for line in source.splitlines() if not line.lstrip().startswith(("%", "!"))
    )
    body = ast.parse(code).body
    last = body[-1] if body else None
    if not isinstance(last, ast.Expr):
        return False
    func = last.value.func if isinstance(last.value, ast.Call) else None
    return getattr(func, "id", getattr(func, "attr", None)) not in ("print", "display", "show")


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_checked_cells_show_no_bare_repr(name):
    """A checked cell's last expression must not be displayed: its repr has every digit."""
    nb = nbformat.read(NOTEBOOKS[name].path, as_version=4)
    checked = _checked_cells(nb)
    shown = [
        c.id
        for c in checked
        if _ends_in_displayed_expression(c.source)
        or any(o.output_type == "execute_result" for o in c.get("outputs", []))
    ]
    assert not shown, (
        f"{name}: checked cells {shown} end in a displayed expression; assign it "
        f"(`_ = repro.record(...)`) or print rounded numbers"
    )
