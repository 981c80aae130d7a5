"""Which source files a notebook runs: its imports of the project's packages, and their closure.

Static analysis (no code is executed): the ``import`` statements of the notebook's code
cells that name a package under ``src/`` (``asoc``, ``asoc_companion``), then, file by file,
the imports of those modules (absolute and relative, at any depth of a module, including
imports inside functions), until nothing new is found. Importing ``a.b.c`` runs
``a/__init__.py`` and ``a/b/__init__.py`` too, so they belong to the closure. The build
manifest hashes exactly these files (:mod:`asoc_companion.manifest`), so editing
``asoc/gp`` re-runs only the notebooks that import it.
"""

import ast
import json
from functools import lru_cache
from pathlib import Path

__all__ = ["imported_names", "closure", "notebook_modules"]


def _code_of_notebook(path) -> list:
    """The sources of a notebook's code cells, IPython magics and shell lines removed."""
    nb = json.loads(Path(path).read_text())
    cells = []
    for cell in nb["cells"]:
        if cell["cell_type"] != "code":
            continue
        source = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        cells.append("\n".join("" if line.lstrip().startswith(("%", "!")) else line
                               for line in source.splitlines()))
    return cells


def imported_names(code: str, package: str | None = None) -> set:
    """Dotted names ``code`` imports; for ``from X import a`` both ``X`` and ``X.a``.

    ``package`` resolves relative imports (the package the code belongs to).

    Raises
    ------
    SyntaxError
        If ``code`` does not parse.

    Examples
    --------
    >>> sorted(imported_names("import numpy as np; from asoc.mjls import MJLS"))
    ['asoc.mjls', 'asoc.mjls.MJLS', 'numpy']
    >>> sorted(imported_names("from .operators import sym", package="asoc.mjls"))
    ['asoc.mjls.operators', 'asoc.mjls.operators.sym']
    """
    names = set()
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if package is None:
                    continue
                parts = package.split(".")
                named = [node.module] if node.module else []
                base = ".".join(parts[:len(parts) - node.level + 1] + named)
            else:
                base = node.module
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names if alias.name != "*")
    return names


@lru_cache(maxsize=4096)
def _file_imports(path: str, mtime_ns: int, size: int, package: str) -> frozenset:
    """:func:`imported_names` of a source file, cached while the file is unchanged."""
    return frozenset(imported_names(Path(path).read_text(), package))


def _module_file(name: str, src) -> Path | None:
    """The file of module ``name`` under ``src`` (``a/b.py`` or ``a/b/__init__.py``), or None.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as src:
    ...     (Path(src) / "pkg" / "sub").mkdir(parents=True)
    ...     for name in ("pkg/__init__.py", "pkg/a.py", "pkg/sub/__init__.py"):
    ...         _ = (Path(src) / name).write_text("")
    ...     print([_module_file(m, src).relative_to(src).as_posix() for m in ("pkg.a", "pkg.sub")],
    ...           _module_file("pkg.missing", src))
    ['pkg/a.py', 'pkg/sub/__init__.py'] None
    """
    base = Path(src).joinpath(*name.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def closure(names, src, exclude=()) -> dict:
    """``{module name: file}`` of the modules under ``src`` that importing ``names`` runs
    (modules in ``exclude`` are neither listed nor followed).

    Examples
    --------
    ``pkg.a`` imports ``pkg.b`` relatively; importing ``pkg.a`` runs ``pkg/__init__.py`` too, and
    ``numpy`` lies outside ``src``:

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as src:
    ...     (Path(src) / "pkg").mkdir()
    ...     _ = (Path(src) / "pkg" / "__init__.py").write_text("")
    ...     _ = (Path(src) / "pkg" / "a.py").write_text("import numpy; from . import b")
    ...     _ = (Path(src) / "pkg" / "b.py").write_text("")
    ...     print(sorted(closure(["pkg.a"], src)), sorted(closure(["pkg.a"], src,
    ...     exclude=("pkg.b",))))
    ['pkg', 'pkg.a', 'pkg.b'] ['pkg', 'pkg.a']
    """
    src = Path(src)
    found, todo = {}, list(names)
    while todo:
        name = todo.pop()
        parts = name.split(".")
        for depth in range(1, len(parts) + 1):          # parents run first
            module = ".".join(parts[:depth])
            if module in found or module in exclude:
                continue
            path = _module_file(module, src)
            if path is None:
                continue
            found[module] = path
            package = module if path.name == "__init__.py" else module.rpartition(".")[0]
            stat = path.stat()
            todo.extend(_file_imports(str(path), stat.st_mtime_ns, stat.st_size, package))
    return found


def notebook_modules(path, src, exclude=()) -> dict:
    """``{module name: file}`` of project modules the notebook at ``path`` imports, transitively.

    A cell that does not parse makes the whole of ``src`` count (a conservative answer).

    Examples
    --------
    A notebook whose code cell imports ``pkg.a`` (magics are skipped, markdown cells ignored):

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as src:
    ...     (Path(src) / "pkg").mkdir()
    ...     for name in ("__init__.py", "a.py", "b.py"):
    ...         _ = (Path(src) / "pkg" / name).write_text("")
    ...     cells = [{"cell_type": "code", "source": "%matplotlib inline"},
    ...              {"cell_type": "code", "source": ["import pkg.a"]},
    ...              {"cell_type": "markdown", "source": "import pkg.b"}]
    ...     notebook = Path(src) / "demo.ipynb"
    ...     _ = notebook.write_text(json.dumps({"cells": cells, "metadata": {}}))
    ...     print(sorted(notebook_modules(notebook, src)))
    ['pkg', 'pkg.a']
    """
    names = set()
    for code in _code_of_notebook(path):
        try:
            names |= imported_names(code)
        except SyntaxError:
            return {p.relative_to(src).with_suffix("").as_posix().replace("/", "."): p
                    for p in sorted(Path(src).rglob("*.py")) if "__pycache__" not in p.parts}
    return closure(names, src, exclude)
