"""House rules of issue 22 for asoc.belief and asoc.gp, checked on the source: no module over 500
non-blank lines, no private name imported from another module, no import circle between files."""

import ast
from pathlib import Path

import pytest

LIBRARY = Path(__file__).resolve().parents[2] / "src" / "asoc"
PACKAGES = ("belief", "gp")
MAX_NON_BLANK_LINES = 500


def _modules(folder):
    return sorted(Path(folder).glob("*.py"))


def _relative_imports(path):
    """(line, module imported from, names) of every ``from . import`` / ``from .x import`` in ``path``."""
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            yield node.lineno, node.module, [alias.name for alias in node.names]


def private_imports(folder):
    """``file:line: name`` for every private name (or private module) imported within the package ``folder``."""
    found = []
    for path in _modules(folder):
        for line, module, names in _relative_imports(path):
            private = [n for n in names if n.startswith("_")] + ([module] if module and module.startswith("_") else [])
            found += [f"{path.name}:{line}: {name}" for name in private]
    return found


def import_graph(folder):
    """Module stem -> the stems of the modules of the package ``folder`` that it imports."""
    stems = {path.stem for path in _modules(folder)}
    graph = {}
    for path in _modules(folder):
        targets = set()
        for _, module, names in _relative_imports(path):
            targets |= {module} if module else {n for n in names if n in stems}
        graph[path.stem] = targets & stems
    return graph


def circles(graph):
    """Every import circle of ``graph``, as a list of stems that starts and ends with the same one."""
    found = []

    def visit(stem, path):
        for target in sorted(graph[stem]):
            if target in path:
                found.append(path[path.index(target):] + [target])
            else:
                visit(target, path + [target])

    for stem in sorted(graph):
        visit(stem, [stem])
    return found


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_over_500_non_blank_lines(package):
    sizes = {path.name: sum(1 for line in path.read_text().splitlines() if line.strip())
             for path in _modules(LIBRARY / package)}
    assert {name: n for name, n in sizes.items() if n > MAX_NON_BLANK_LINES} == {}


@pytest.mark.parametrize("package", PACKAGES)
def test_no_private_name_imported_across_modules(package):
    assert private_imports(LIBRARY / package) == []


@pytest.mark.parametrize("package", PACKAGES)
def test_no_import_circle(package):
    assert circles(import_graph(LIBRARY / package)) == []


def test_the_checks_catch_planted_violations(tmp_path):
    """The circle trajectory <-> simulate that this layout removed, and the private imports it replaced."""
    (tmp_path / "trajectory.py").write_text("from .simulate import _simulate, draw_noise\n")
    (tmp_path / "simulate.py").write_text("from .trajectory import AffinePolicy\nfrom . import _validate as v\n")
    (tmp_path / "models.py").write_text("import numpy as np\n")
    assert private_imports(tmp_path) == ["simulate.py:2: _validate", "trajectory.py:1: _simulate"]
    assert circles(import_graph(tmp_path)) == [["simulate", "trajectory", "simulate"],
                                               ["trajectory", "simulate", "trajectory"]]
