"""The house rules (the architecture page), checked on the source of both packages: no module over
500 non-blank lines, no private name imported from another module, no internals of numpy, scipy or
numdifftools, no import circle between files, and no notebook that assigns to a module's global."""

import ast
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src"
PACKAGES = sorted({path.parent for path in SRC.rglob("*.py")})
MAX_NON_BLANK_LINES = 500
THIRD_PARTY = ("numpy", "scipy", "numdifftools")


def _modules(folder):
    return sorted(Path(folder).glob("*.py"))


def _imports(path):
    """(line, level, module, names) of every ``from ... import ...`` in ``path``."""
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom):
            yield node.lineno, node.level, node.module, [alias.name for alias in node.names]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, 0, alias.name, []


def private_imports(folder):
    """``file:line: name`` for every private name or private module imported from another module."""
    found = []
    for path in _modules(folder):
        for line, level, module, names in _imports(path):
            own = level > 0 or (module or "").split(".")[0] in ("asoc", "asoc_companion")
            if not own:
                continue
            private = [n for n in names if n.startswith("_") and n != "__version__"]
            private += [p for p in (module or "").split(".") if p.startswith("_")]
            found += [f"{path.name}:{line}: {name}" for name in private]
    return found


def internals(folder):
    """``file:line: module`` for every private module of numpy, scipy or numdifftools imported."""
    found = []
    for path in _modules(folder):
        for line, _, module, names in _imports(path):
            if module and module.split(".")[0] in THIRD_PARTY:
                parts = module.split(".") + [n for n in names]
                found += [
                    f"{path.name}:{line}: {module}.{p}"
                    if p in names
                    else f"{path.name}:{line}: {module}"
                    for p in parts
                    if p.startswith("_")
                ][:1]
    return found


def import_graph(folder):
    """Module stem -> the stems of the modules of the package ``folder`` that it imports
    relatively."""
    stems = {path.stem for path in _modules(folder)}
    graph = {}
    for path in _modules(folder):
        targets = set()
        for _, level, module, names in _imports(path):
            if level == 1:
                targets |= {module.split(".")[0]} if module else {n for n in names if n in stems}
        graph[path.stem] = targets & stems - {path.stem}
    return graph


def circles(graph):
    """Every import circle of ``graph``, as a list of stems that starts and ends with the same
    one."""
    found = []

    def visit(stem, path):
        for target in sorted(graph[stem]):
            if target in path:
                found.append(path[path.index(target) :] + [target])
            else:
                visit(target, path + [target])

    for stem in sorted(graph):
        visit(stem, [stem])
    return found


def global_assignments(source):
    """Lines of notebook code that assign to an attribute of a module (``module.NAME = ...``)."""
    return [
        line
        for line in source.splitlines()
        if re.match(r"^\s*[a-z_][a-z_0-9]*\.[A-Z_][A-Z_0-9]*\s*=[^=]", line)
    ]


def _name(folder):
    return str(folder.relative_to(SRC))


@pytest.mark.parametrize("folder", PACKAGES, ids=_name)
def test_no_module_over_500_non_blank_lines(folder):
    sizes = {
        path.name: sum(1 for line in path.read_text().splitlines() if line.strip())
        for path in _modules(folder)
    }
    assert {name: n for name, n in sizes.items() if n > MAX_NON_BLANK_LINES} == {}


@pytest.mark.parametrize("folder", PACKAGES, ids=_name)
def test_no_private_name_imported_across_modules(folder):
    assert private_imports(folder) == []


@pytest.mark.parametrize("folder", PACKAGES, ids=_name)
def test_no_internals_of_other_libraries(folder):
    assert internals(folder) == []


@pytest.mark.parametrize("folder", PACKAGES, ids=_name)
def test_no_import_circle(folder):
    assert circles(import_graph(folder)) == []


def test_no_notebook_patches_a_module_global():
    found = {}
    for path in sorted((ROOT / "book").glob("*.ipynb")):
        cells = json.loads(path.read_text())["cells"]
        lines = [
            line
            for c in cells
            if c["cell_type"] == "code"
            for line in global_assignments("".join(c["source"]))
        ]
        if lines:
            found[path.name] = lines
    assert found == {}


def test_the_checks_catch_planted_violations(tmp_path):
    """The circle trajectory <-> simulate that this layout removed, the private imports it replaced,
    numpy's private linalg module, and a notebook line that patched Alg. 3.2's rank threshold."""
    (tmp_path / "trajectory.py").write_text("from .simulate import _simulate, draw_noise\n")
    (tmp_path / "simulate.py").write_text(
        "from .trajectory import AffinePolicy\nfrom . import _validate as v\n"
    )
    (tmp_path / "models.py").write_text(
        "from numpy.linalg import _umath_linalg\nfrom asoc.mjls.static import _Cycle\n"
    )
    assert private_imports(tmp_path) == [
        "models.py:2: _Cycle",
        "simulate.py:2: _validate",
        "trajectory.py:1: _simulate",
    ]
    assert internals(tmp_path) == ["models.py:1: numpy.linalg._umath_linalg"]
    assert circles(import_graph(tmp_path)) == [
        ["simulate", "trajectory", "simulate"],
        ["trajectory", "simulate", "trajectory"],
    ]
    assert global_assignments("dynamic.RANK_RTOL = 1e-8\nx = dynamic.RANK_RTOL == 2\n") == [
        "dynamic.RANK_RTOL = 1e-8"
    ]
