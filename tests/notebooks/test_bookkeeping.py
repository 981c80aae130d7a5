"""Bookkeeping out of the reader's way: every ``record`` call sits in a hidden record cell.

A reader of the book came for the computation, not for the ledger's bookkeeping. So a code
cell that calls ``repro.record`` (or ``record``) is a *record cell*:

- it is tagged ``remove-cell`` (or ``remove-input``), so the built page does not show it;
- it only records: each top-level statement is a ``record(...)`` call (``_ = record(...)`` is
  allowed), a comment, or a ``for``/``if`` whose body only records; it assigns no name, defines
  no function and prints nothing, so no computation a reader would want to see is hidden;
- it prints and displays nothing (the value its last ``record`` returns may be stored, unseen).

Computation cells stay as the reader sees them; their record cell follows directly below.
"""

import ast

import nbformat
import pytest

from conftest import NOTEBOOKS

HIDDEN_TAGS = {"remove-cell", "remove-input"}


def _parse(source: str) -> list:
    code = "\n".join(
        "pass" if line.lstrip().startswith(("%", "!")) else line for line in source.splitlines()
    )
    return ast.parse(code).body


def _is_record_call(node) -> bool:
    if not isinstance(node, ast.Call):
        return False
    return getattr(node.func, "attr", getattr(node.func, "id", None)) == "record"


def _calls_record(source: str) -> bool:
    return any(
        _is_record_call(node) for node in ast.walk(ast.Module(body=_parse(source), type_ignores=[]))
    )


def _only_records(statements) -> bool:
    """Whether every statement only records (recursively through ``for`` and ``if``)."""
    for stmt in statements:
        if isinstance(stmt, ast.Expr) and _is_record_call(stmt.value):
            continue
        if (
            isinstance(stmt, ast.Assign)
            and _is_record_call(stmt.value)
            and all(isinstance(t, ast.Name) and t.id == "_" for t in stmt.targets)
        ):
            continue
        if isinstance(stmt, ast.For) and not stmt.orelse and _only_records(stmt.body):
            continue
        if isinstance(stmt, ast.If) and _only_records(stmt.body) and _only_records(stmt.orelse):
            continue
        if isinstance(stmt, ast.Pass):
            continue
        return False
    return True


def record_cell_problems(nb) -> list:
    """The faults of ``nb``'s record cells, one line each (empty if none)."""
    problems = []
    for index, cell in enumerate(nb.cells):
        if cell.cell_type != "code" or not _calls_record(cell.source):
            continue
        name = f"cell {index} ({cell.get('id', '?')})"
        if not HIDDEN_TAGS & set(cell.metadata.get("tags", [])):
            problems.append(f"{name} calls record but is not tagged remove-cell or remove-input")
        if not _only_records(_parse(cell.source)):
            problems.append(
                f"{name} does more than record: move the computation into the visible cell above"
            )
        if any(o.output_type != "execute_result" for o in cell.get("outputs", [])):
            problems.append(f"{name} prints or displays: a record cell shows nothing")
    return problems


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_record_calls_are_in_hidden_record_cells(name):
    nb = nbformat.read(NOTEBOOKS[name].path, as_version=4)
    problems = record_cell_problems(nb)
    assert not problems, f"{name}:\n" + "\n".join(problems)


@pytest.mark.parametrize(
    "source, tags, outputs, fault",
    [
        ("x = solve(sys)\nrepro.record('x', x)", ["remove-cell"], [], "does more than record"),
        ("repro.record('x', x)", [], [], "not tagged"),
        (
            "repro.record('x', x)",
            ["remove-cell"],
            [nbformat.v4.new_output("stream", text="1\n")],
            "prints or displays",
        ),
        (
            "for t, r in res.items():\n    print(t)\n    repro.record(f'x{t}', r)",
            ["remove-cell"],
            [],
            "does more",
        ),
        ("y = repro.record('x', x)", ["remove-cell"], [], "does more than record"),
    ],
)
def test_planted_bookkeeping_faults_are_caught(source, tags, outputs, fault):
    cell = nbformat.v4.new_code_cell(source, metadata={"tags": tags})
    cell.outputs = outputs
    problems = record_cell_problems(nbformat.v4.new_notebook(cells=[cell]))
    assert any(fault in p for p in problems), problems


def test_a_proper_record_cell_passes():
    source = (
        "# the iterations of Alg. 3.2\nfor t, r in alg32.items():\n"
        "    repro.record(f'alg32_T{t}', [r.rho, r.cost])\n    if r.converged:\n"
        "        _ = repro.record(f'alg32_T{t}_ok', True)"
    )
    cell = nbformat.v4.new_code_cell(source, metadata={"tags": ["remove-cell"]})
    assert record_cell_problems(nbformat.v4.new_notebook(cells=[cell])) == []
