"""The arrow runs one way (the architecture page, book/architecture.md): the library ``asoc`` never
imports the
companion's
tooling ``asoc_companion``, nor the book's tools. Checked statically (every import statement
of every file under src/asoc, including imports inside functions) and by importing every
module of the library in a fresh interpreter."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
LIBRARY = SRC / "asoc"
TOOLING = ("asoc_companion",)
BOOK_TOOLS = (
    "matplotlib",
    "papermill",
    "nbformat",
    "nbclient",
    "IPython",
    "sphinx",
    "yaml",
    "nbval",
)


def _imports(path: Path):
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            yield node.lineno, node.module


def test_no_library_file_imports_the_tooling():
    files = sorted(LIBRARY.rglob("*.py"))
    assert len(files) > 20
    offending = [
        f"{path.relative_to(SRC)}:{line}: import {name}"
        for path in files
        for line, name in _imports(path)
        if name.split(".")[0] in TOOLING
    ]
    assert not offending, "the library imports the companion's tooling:\n" + "\n".join(offending)


def test_importing_every_library_module_loads_neither_tooling_nor_book_tools():
    modules = sorted(
        ".".join(
            p.relative_to(SRC).with_suffix("").parts[:-1]
            if p.name == "__init__.py"
            else p.relative_to(SRC).with_suffix("").parts
        )
        for p in LIBRARY.rglob("*.py")
    )
    probe = (
        "import importlib, json, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & "
        f"{set(TOOLING + BOOK_TOOLS)!r})))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        timeout=300,
        env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"},
        cwd="/",
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == []


@pytest.mark.parametrize(
    "name", ["asoc_companion.figures", "asoc_companion.values", "asoc_companion.recorder"]
)
def test_the_tooling_has_no_import_circle(name):
    """figures and values do not import each other (the recorder, in session, uses both)."""
    imported = {n for _, n in _imports(SRC / Path(*name.split(".")).with_suffix(".py"))}
    rel = {
        node.module
        for node in ast.walk(
            ast.parse((SRC / Path(*name.split(".")).with_suffix(".py")).read_text())
        )
        if isinstance(node, ast.ImportFrom) and node.level and node.module
    }
    rel |= {
        alias.name
        for node in ast.walk(
            ast.parse((SRC / Path(*name.split(".")).with_suffix(".py")).read_text())
        )
        if isinstance(node, ast.ImportFrom) and node.level and not node.module
        for alias in node.names
    }
    if name.endswith("figures"):
        assert (
            "values" not in rel and "session" not in rel and "asoc_companion.values" not in imported
        )
    if name.endswith("values"):
        assert "figures" not in rel and "session" not in rel
