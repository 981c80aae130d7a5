"""The notebooks of the book and how to run them through papermill, crash-safely.

Every notebook in ``book/`` whose metadata has an ``asoc`` entry is run by the harness;
the entry declares which thesis figures and tables it regenerates
(``metadata.asoc = {"title": ..., "figures": [...], "tables": [...]}``) and, optionally,
the notebooks whose recorded values it reads (``"depends": ["sec3_5", ...]``, run first).
A run is described by its :class:`asoc_companion.plan.RunPlan` (made once, by
:func:`asoc_companion.plan.make_plan`), which holds every path of the run: ``full`` fidelity
at the default parameters replaces the notebook in ``book/`` (the book renders the executed
file) and its results in ``figures/``; ``ci`` fidelity writes to ``book/_build/ci/``; a run
with parameter overrides writes to ``book/_build/runs/<notebook>-<hash>/``. Only the first
changes tracked files.

Crash safety (book/architecture.md, "The manifest and crash safety"): every run executes into a
fresh staging folder ``<plan.staging>/<notebook>-<random>/``; only when papermill finishes without
error are its figures, tables, values and executed notebook moved into place
(:mod:`asoc_companion.staging`: ``os.replace``, signals held off); the caller writes the manifest
entry last. An interrupted or failed run leaves every tracked file as it was, and its staging folder
is removed.

Executed notebooks are normalised (no timestamps, durations or machine paths; the
injected parameters name the final folder, not the staging one), so an unchanged
computation gives a byte-identical file.
"""

import ast
import json
import math
import os
import re
import sys
import tempfile
import uuid
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from . import paths
from .manifest import dependencies, incomplete_notebook
from .staging import commit, one_blas_thread, remove_stage

__all__ = ["HARNESS_PARAMETERS", "KERNEL_ARGUMENTS", "NotebookInfo", "notebooks", "find",
           "natural_key", "build_order", "by_name", "default_parameters", "parse_value",
           "parse_overrides", "run", "PAPERMILL_TIMES", "KERNEL_CELL_FILE", "normalise",
           "parameters_reaching", "socket_file_kernel_manager"]


HARNESS_PARAMETERS = ("fidelity", "output_dir")   # set by the harness, not by -p
KERNEL_ARGUMENTS = ["--IPKernelApp.log_level=ERROR"]
"""The kernel's own log shows errors only: its start-up notices are noise on the command line
(a notebook's warnings are cell outputs, not this log)."""


@cache
def socket_file_kernel_manager():
    """jupyter_client's kernel manager, talking to the kernel over Unix socket files, not TCP.

    Over TCP, the manager picks free ports and the kernel binds them a moment later; two runs
    starting at once (the tests' two workers, say) can pick the same port, and the second
    kernel dies with "Address already in use". Socket files carry a random name of their
    own, so runs started together never collide.

    Examples
    --------
    >>> manager = socket_file_kernel_manager()(kernel_name="python3")
    >>> manager.transport, manager.ip.startswith(tempfile.gettempdir())
    ('ipc', True)
    """
    from jupyter_client.manager import KernelManager
    from traitlets import default

    class SocketFileKernelManager(KernelManager):
        @default("transport")
        def _socket_files(self):
            return "ipc"

        @default("ip")
        def _socket_file_prefix(self):
            return os.path.join(tempfile.gettempdir(), f"asoc-kernel-{uuid.uuid4().hex[:16]}")

    return SocketFileKernelManager


@dataclass(frozen=True)
class NotebookInfo:
    """A notebook of the book: name, file, title and the thesis figures and tables it regenerates.

    Examples
    --------
    >>> NotebookInfo("sec3_5", Path("book/sec3_5.ipynb"), "Sec. 3.5", ("3.4", "3.5"),
    ...     ("3.2",)).figures
    ('3.4', '3.5')
    """

    name: str
    path: Path
    title: str
    figures: tuple
    tables: tuple


def notebooks(book=None) -> dict:
    """``{name: NotebookInfo}`` for every notebook with ``asoc`` metadata, in thesis order
    (sections, then others).

    Examples
    --------
    >>> names = list(notebooks())                        # the book of the checkout this runs in
    >>> names.index("sec3_6") < names.index("findings") < names.index("your_system")
    True
    """
    found = {}
    for path in sorted(Path(book or paths.project().book).glob("*.ipynb")):
        meta = json.loads(path.read_text())["metadata"].get("asoc")
        if meta is None:
            continue
        found[path.stem] = NotebookInfo(path.stem, path, meta.get("title", path.stem),
                                        tuple(meta.get("figures", ())),
                                        tuple(meta.get("tables", ())))
    return dict(sorted(found.items(), key=lambda item: (not item[0].startswith("sec"), item[0])))


def find(kind: str, number: str, book=None) -> NotebookInfo:
    """The notebook that regenerates figure or table ``number``.

    Examples
    --------
    >>> find("figure", "3.2").name
    'sec3_2'
    """
    for info in notebooks(book).values():
        if number in (info.figures if kind == "figure" else info.tables):
            return info
    known = sorted((n for i in notebooks(book).values()
                    for n in (i.figures if kind == "figure" else i.tables)), key=natural_key)
    raise ValueError(f"{kind} {number!r} is not regenerated by any notebook; known: "
                     f"{', '.join(known)}")


def natural_key(text: str) -> tuple:
    """Sort key that orders the numbers inside ``text`` by value: 2.2 before 2.10.

    Examples
    --------
    >>> sorted(["2.10", "own.4", "2.2", "3.1"], key=natural_key)
    ['2.2', '2.10', '3.1', 'own.4']
    """
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part)
                 for part in re.split(r"(\d+)", text) if part)


def build_order(infos) -> list:
    """``infos`` ordered so that every notebook runs after the notebooks it depends on.

    Examples
    --------
    >>> order = [info.name for info in build_order(notebooks().values())]
    >>> order.index("findings") > order.index("sec3_5")          # findings quotes sec3_5's values
    True
    """
    infos = {info.name: info for info in infos}
    ordered, done = [], set()

    def visit(name, chain):
        if name in chain:
            raise ValueError("metadata.asoc.depends: circular dependency "
                             f"{' -> '.join(chain + [name])}")
        if name in done:
            return
        for dep in dependencies(infos[name].path):
            if dep not in infos:
                raise ValueError(f"{name}: metadata.asoc.depends names {dep!r}, which is not a "
                                 f"notebook of the book; known: {', '.join(sorted(infos))}")
            visit(dep, chain + [name])
        done.add(name)
        ordered.append(infos[name])

    for name in infos:
        visit(name, [])
    return ordered


def by_name(name: str, book=None) -> NotebookInfo:
    """The notebook called ``name`` (e.g. "sec3_5", "findings").

    Examples
    --------
    >>> by_name("sec3_2").path.name
    'sec3_2.ipynb'
    """
    found = notebooks(book)
    if name not in found:
        raise ValueError(f"notebook {name!r} is not a notebook of the book; known: "
                         f"{', '.join(found)}")
    return found[name]


def _parameter_specs(info: NotebookInfo) -> dict:
    """``{name: papermill's inspection}`` of the notebook's ``parameters`` cell (defaults as text).

    Examples
    --------
    >>> _parameter_specs(by_name("sec3_2"))["output_dir"]["name"]
    'output_dir'
    """
    import papermill

    return dict(papermill.inspect_notebook(str(info.path)))


def default_parameters(info: NotebookInfo) -> dict:
    """``{name: default source text}`` of the ``parameters`` cell (papermill's inspection).

    Examples
    --------
    >>> {"fidelity", "output_dir"} <= set(default_parameters(by_name("sec3_2")))
    True
    """
    return {name: spec["default"] for name, spec in _parameter_specs(info).items()}


def parse_value(text: str):
    """A ``-p name value`` value, typed like papermill's command line (bool, None, int, float, str).

    Examples
    --------
    >>> [parse_value(text) for text in ("True", "None", "3", "0.5", "sec3_5")]
    [True, None, 3, 0.5, 'sec3_5']
    """
    if text in ("True", "False"):
        return text == "True"
    if text == "None":
        return None
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _default_value(source: str):
    try:
        return ast.literal_eval(source)
    except (ValueError, SyntaxError):
        return None          # an expression: no type to check against


def _check_value(name: str, value, default_source: str, notebook: str):
    """``value`` for parameter ``name`` if it has the default's type (and range); else ValueError.

    The type is the default's: an int parameter takes an int (not a bool, float or text), a
    float parameter a finite int or float, a bool ``True``/``False``, a string anything. The
    range follows the names: an int parameter called ``seed...`` takes a non-negative int;
    every other int parameter whose default is positive is a count (Monte Carlo runs, steps,
    grid points, iterations) and takes a positive int.

    Examples
    --------
    >>> _check_value("runs", 50, "100", "demo.ipynb"), _check_value("noise", 1, "0.5", "demo.ipynb")
    (50, 1.0)
    >>> _check_value("runs", 0, "100", "demo.ipynb")
    Traceback (most recent call last):
    ...
    ValueError: parameter runs of demo.ipynb (default 100) is a count: it takes an integer >= 1,
    found 0
    """
    default = _default_value(default_source)
    where = f"parameter {name} of {notebook} (default {default_source})"
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ValueError(f"{where} takes True or False, found {value!r}")
    elif isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where} takes an integer, found {value!r}")
        if name.startswith("seed") and value < 0:
            raise ValueError(f"{where} is a seed: it takes an integer >= 0, found {value}")
        if not name.startswith("seed") and default > 0 and value < 1:
            raise ValueError(f"{where} is a count: it takes an integer >= 1, found {value}")
    elif isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value,
                                                     (int, float)) or not math.isfinite(value):
            raise ValueError(f"{where} takes a finite number, found {value!r}")
        value = float(value)
    return value


def parse_overrides(info: NotebookInfo, pairs) -> dict:
    """``-p name value`` pairs as checked overrides ``{name: value}``, before anything runs.

    Raises
    ------
    ValueError
        A name given twice, a name that is not a parameter (the message lists the valid
        ones), or a value of the wrong type or range (``_check_value``).

    Examples
    --------
    >>> parse_overrides(by_name("sec3_2"), [("steps", "10")])
    {'steps': 10}
    """
    overrides = {}
    for name, text in pairs or ():
        if name in overrides:
            raise ValueError(f"parameters: -p {name} given twice ({overrides[name]!r} and "
                             f"{text!r}); give it once")
        overrides[name] = parse_value(text)
    return _check_overrides(info, overrides)


def _check_overrides(info: NotebookInfo, overrides: dict) -> dict:
    """``overrides`` if each names a parameter of the notebook and has its type and range.

    Examples
    --------
    >>> _check_overrides(by_name("sec3_2"), {"nosuch": 1})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: parameters: 'nosuch' is not a parameter of sec3_2.ipynb; valid names: ...
    """
    specs = _parameter_specs(info)
    valid = [name for name in specs if name not in HARNESS_PARAMETERS]
    checked = {}
    for name, value in overrides.items():
        if name == "fidelity":
            raise ValueError("parameters: set the fidelity with --fidelity, not -p fidelity")
        if name not in valid:
            raise ValueError(f"parameters: {name!r} is not a parameter of {info.path.name}; "
                             f"valid names: {', '.join(valid)}")
        checked[name] = _check_value(name, value, specs[name]["default"], info.path.name)
    return checked


def run(plan, log_output=False, progress_bar=None) -> Path:
    """Execute the run ``plan`` (a :class:`asoc_companion.plan.RunPlan`) with papermill,
    crash-safely; return the executed file.

    The plan's overrides replace defaults of the ``parameters`` cell (checked by
    ``_check_overrides``). The run executes into a staging folder in ``plan.staging``; its
    results move to ``plan.output_dir`` (and the executed notebook to ``plan.executed``) only
    on success.
    """
    import papermill

    info, output_dir, target, shown = plan.notebook, plan.output_dir, plan.executed, plan.injected
    _check_overrides(info, plan.parameters)
    plan.staging.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f"{info.name}-", dir=plan.staging))
    try:
        staged, staged_parameters = plan.staged(stage)
        staged.parent.mkdir(parents=True)
        if progress_bar is None:
            progress_bar = sys.stderr.isatty()
        with one_blas_thread():
            papermill.execute_notebook(str(info.path), str(staged), cwd=str(info.path.parent),
                                       parameters=staged_parameters, progress_bar=progress_bar,
                                       log_output=log_output, kernel_name="python3",
                                       extra_arguments=KERNEL_ARGUMENTS,
                                       kernel_manager_class=socket_file_kernel_manager())
        normalise(staged, shown_parameters=shown, output_path=target,
                  replace={str(stage): shown["output_dir"],
                           staged_parameters["output_dir"]: shown["output_dir"]})
        problems = incomplete_notebook(staged)
        if problems:
            raise RuntimeError(f"{info.path.name}: the executed notebook is incomplete "
                               f"({problems}); nothing moved")
        commit(stage, output_dir, staged, target)
    finally:
        remove_stage(stage)
    return target


PAPERMILL_TIMES = ("start_time", "end_time", "duration")
# a warning's source: a new name per kernel
KERNEL_CELL_FILE = re.compile(r"\S*ipykernel_\d+[/\\]\d+\.py")


def normalise(path: Path, shown_parameters=None, output_path=None, replace=None):
    r"""Make an executed notebook reproducible byte for byte.

    Stores papermill's input/output paths relative to the project (no machine paths) and
    drops what changes on every run: papermill's start/end times and durations (notebook
    and cells), the kernel's per-cell execution timestamps, the random id papermill
    gives its injected-parameters cell, the timing-dependent split of printed text into
    stream chunks (adjacent chunks of one stream are merged) and the per-kernel file name
    of a cell in warnings (``<cell>``). Paths inside the project are printed relative to it.
    A staged run is shown as the run it stands for: ``shown_parameters`` replace the injected
    ones, ``output_path`` papermill's output path, and ``replace`` ({staging path: output
    folder}) rewrites printed text.

    Examples
    --------
    >>> from nbformat import read, write, v4
    >>> outputs = [v4.new_output("stream", name="stdout", text=text) for text in ("1\n", "2\n")]
    >>> meta = {"papermill": {"start_time": "2026-01-01T00:00",
    ...     "input_path": str(paths.project().book / "a.ipynb")}}
    >>> cells = [v4.new_code_cell("print(1); print(2)", outputs=outputs)]
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     write(v4.new_notebook(cells=cells, metadata=meta), Path(folder) / "a.ipynb")
    ...     normalise(Path(folder) / "a.ipynb")
    ...     nb = read(Path(folder) / "a.ipynb", as_version=4)
    >>> nb.metadata.papermill, [out.text for out in nb.cells[0].outputs]
    ({'input_path': 'book/a.ipynb'}, ['1\n2\n'])
    """
    import nbformat
    from papermill.translators import translate_parameters

    root = paths.project().root
    nb = nbformat.read(path, as_version=4)
    meta = nb.metadata.get("papermill", {})
    if output_path is not None:
        meta["output_path"] = str(output_path)
    if shown_parameters is not None:
        meta["parameters"] = shown_parameters
    for key in ("input_path", "output_path"):
        if meta.get(key):
            meta[key] = os.path.relpath(meta[key], root)
    for key in PAPERMILL_TIMES:
        meta.pop(key, None)
    for cell in nb.cells:
        if "injected-parameters" in cell.metadata.get("tags", []):
            cell.id = "injected-parameters"
            if shown_parameters is not None:
                cell.source = translate_parameters("python3", "python", shown_parameters,
                                                   "Parameters")
        cell.metadata.pop("execution", None)
        for key in PAPERMILL_TIMES:
            cell.metadata.get("papermill", {}).pop(key, None)
        if cell.cell_type == "code":
            cell.outputs = _merged_streams(cell.outputs, root, replace)
            for out in cell.outputs:
                if "text/plain" in out.get("data", {}):
                    out.data["text/plain"] = _replaced(out.data["text/plain"], replace)
    nbformat.write(nb, path)


def _replaced(text, replace):
    for old, new in (replace or {}).items():
        text = text.replace(old, new)
    return text


def _merged_streams(outputs, root, replace=None) -> list:
    """Adjacent stream outputs of one name merged into one; project paths made relative."""
    merged = []
    for out in outputs:
        if out.output_type == "stream":
            out.text = KERNEL_CELL_FILE.sub("<cell>", _replaced(out.text,
                                                                replace).replace(f"{root}{os.sep}",
                                                                                 ""))
            if merged and merged[-1].output_type == "stream" and merged[-1].name == out.name:
                merged[-1].text += out.text
                continue
        merged.append(out)
    return merged


def _names(tree) -> tuple:
    """(names a cell reads or binds, names it imports)."""
    imported = {(a.asname or a.name).split(".")[0] for node in ast.walk(tree)
                if isinstance(node, (ast.Import, ast.ImportFrom)) for a in node.names}
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    return names - imported, imported


def _saves(tree, kind: str, number: str) -> bool:
    call = "save_figure" if kind == "figure" else "save_table"
    called = lambda n: getattr(n.func, "attr", getattr(n.func, "id", None))
    return any(isinstance(n, ast.Call) and called(n) == call
               and any(isinstance(a, ast.Constant) and a.value == number for a in n.args)
               for n in ast.walk(tree))


def parameters_reaching(info: NotebookInfo, kind: str, number: str) -> set:
    """The parameters that can change figure or table ``number`` (``kind``: "figure" or "table").

    A parameter reaches every name a cell reads or binds once the cell reads it or a name it
    reached before (a conservative data flow over the code cells in order: a call or a
    mutation in that cell may carry it anywhere the cell touches; imported modules carry
    nothing). The figure depends on what reaches the cells that save it. If no cell saves it
    by its literal number, every parameter is returned.

    Examples
    --------
    Fig. 3.2 shows trajectories of ``steps`` steps along a mode sequence drawn with ``seed``:

    >>> sorted(parameters_reaching(by_name("sec3_2"), "figure", "3.2"))
    ['seed', 'steps']
    """
    import nbformat

    params = set(default_parameters(info))
    nb = nbformat.read(info.path, as_version=4)
    carries, imported, found, saved = {p: {p} for p in params}, set(), set(), False
    for cell in nb.cells:
        if cell.cell_type != "code" or {"parameters",
                                        "injected-parameters"} & set(cell.metadata.get("tags", [])):
            continue
        try:
            tree = ast.parse("\n".join("pass" if line.lstrip().startswith(("%", "!")) else line
                                       for line in cell.source.splitlines()))
        except SyntaxError:
            return params
        names, new_imports = _names(tree)
        imported |= new_imports
        names -= imported
        reached = set().union(*(carries.get(n, set()) for n in names))
        for n in names:
            carries[n] = carries.get(n, set()) | reached
        if _saves(tree, kind, number):
            found |= reached
            saved = True
    return found if saved else params
