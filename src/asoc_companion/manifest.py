"""Input hashes of each executed notebook, so a build re-executes only what changed.

``<output_dir>/values/manifest.json`` (``figures/values/manifest.json`` for the committed
full-fidelity run) holds, per notebook, content hashes of everything its results depend on:

``source``       the notebook's cells (type and source, not outputs; papermill's injected
                 parameters cell excluded) and its ``asoc`` metadata;
``parameters``   the parameters papermill injects (fidelity, output folder, overrides:
                 the plan's ``injected``);
``modules``      ``{path under src/: hash}`` of the modules the notebook imports, directly
                 or transitively (:mod:`asoc_companion.imports`): the library modules it
                 calls and the tooling modules that write its values and figures;
``environment``  ``environment.txt``, the pinned requirements;
``depends``      the recorded values of the notebooks named in its metadata
                 (``metadata.asoc.depends``, e.g. a findings page that quotes other pages).

Every function of one run reads its :class:`asoc_companion.plan.RunPlan` (the values file,
the executed notebook, the manifest path); none derives a path itself. A notebook is up to
date when its entry equals the hashes computed now and its outputs are complete
(``_incomplete_outputs``); ``python -m asoc_companion reproduce`` skips it then
(``--force`` re-executes everything).
"""

import hashlib
import json
from pathlib import Path

from . import paths
from .atomic_files import atomic_write_json
from .imports import notebook_modules
from .plan import manifest_file
from .values import CorruptValuesError, read_values_file

__all__ = ["source_hash", "tree_hash", "HARNESS_ONLY", "module_hashes", "dependencies", "entry",
           "load_manifest", "incomplete_notebook", "last_seconds", "changed_inputs",
           "update_manifest"]


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def source_hash(path) -> str:
    """Hash of a notebook's cell types and sources and its ``asoc`` metadata (outputs ignored).

    Examples
    --------
    Outputs and execution counts do not change the hash; an edited source does:

    >>> import tempfile
    >>> def notebook(source, outputs):
    ...     cell = {"cell_type": "code", "source": source, "outputs": outputs, "metadata": {}}
    ...     return json.dumps({"cells": [cell], "metadata": {"asoc": {"title": "Demo"}}})
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "demo.ipynb"
    ...     hashes = []
    ...     for text in (notebook("x = 1", []), notebook("x = 1", ["1"]), notebook("x = 2", [])):
    ...         _ = path.write_text(text)
    ...         hashes.append(source_hash(path))
    >>> hashes[0] == hashes[1], hashes[0] == hashes[2], len(hashes[0])
    (True, False, 64)
    """
    nb = json.loads(Path(path).read_text())
    source = lambda c: "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
    cells = [[c["cell_type"], source(c)] for c in nb["cells"]
             if "injected-parameters" not in c.get("metadata", {}).get("tags", [])]
    return _sha256(json.dumps([cells, nb["metadata"].get("asoc")], sort_keys=True).encode())


def tree_hash(folder) -> str:
    """Hash of every file below ``folder`` (relative paths and contents; caches skipped).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = (Path(folder) / "a.py").write_text("x = 1")
    ...     first = tree_hash(folder)
    ...     (Path(folder) / "__pycache__").mkdir()
    ...     _ = (Path(folder) / "__pycache__" / "a.pyc").write_bytes(b"cache")
    ...     cached = tree_hash(folder)
    ...     _ = (Path(folder) / "a.py").write_text("x = 2")
    ...     print(first == cached, first == tree_hash(folder))
    True False
    """
    folder = Path(folder)
    files = sorted(p for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                   and p.suffix != ".pyc" and not p.name.endswith(".tmp"))
    lines = [f"{p.relative_to(folder).as_posix()}\0{_sha256(p.read_bytes())}\n" for p in files]
    return _sha256("".join(lines).encode())


# The harness's own machinery: it runs in the process that starts the kernels, never inside a
# notebook, so an edit to it re-runs nothing (an edit to recording, figures, captions, prose,
# the ledger's badges or the library does).
HARNESS_ONLY = ("asoc_companion.__main__", "asoc_companion.build", "asoc_companion.notebooks",
                "asoc_companion.manifest", "asoc_companion.imports", "asoc_companion.book")


def module_hashes(notebook_path, src=None) -> dict:
    """``{path relative to src: hash}`` of the modules the notebook imports, directly or
    transitively (the harness's own modules, :data:`HARNESS_ONLY`, excepted).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     src = Path(folder) / "src"
    ...     (src / "pkg").mkdir(parents=True)
    ...     for name in ("__init__.py", "a.py", "b.py"):
    ...         _ = (src / "pkg" / name).write_text("")
    ...     cells = [{"cell_type": "code", "source": "import pkg.a", "metadata": {}}]
    ...     _ = (Path(folder) / "demo.ipynb").write_text(json.dumps({"cells": cells,
    ...     "metadata": {}}))
    ...     print(sorted(module_hashes(Path(folder) / "demo.ipynb", src)))
    ['pkg/__init__.py', 'pkg/a.py']
    """
    src = Path(src or paths.project().src)
    files = notebook_modules(notebook_path, src, exclude=HARNESS_ONLY).values()
    return {p.relative_to(src).as_posix(): _sha256(p.read_bytes()) for p in sorted(files)}


def dependencies(path) -> list:
    """Names of the notebooks whose recorded values the notebook reads (``metadata.asoc.depends``).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "findings.ipynb"
    ...     _ = path.write_text(json.dumps({"cells": [],
    ...     "metadata": {"asoc": {"depends": ["sec3_5"]}}}))
    ...     print(dependencies(path))
    ['sec3_5']
    """
    depends = json.loads(Path(path).read_text())["metadata"].get("asoc", {}).get("depends", [])
    if isinstance(depends, str) or not all(isinstance(d, str) for d in depends):
        raise ValueError(f"{Path(path).name}: metadata.asoc.depends must be a list of notebook "
                         f"names, found {depends!r}")
    return list(depends)


def entry(plan) -> dict:
    """The input hashes of the run ``plan`` (a :class:`asoc_companion.plan.RunPlan`).

    Examples
    --------
    In a temporary checkout with a notebook ``demo`` that imports ``pkg``:

    >>> from asoc_companion.notebooks import NotebookInfo
    >>> from asoc_companion.plan import make_plan
    >>> with paths.scratch_project() as root:
    ...     (root / "src/pkg").mkdir(parents=True)
    ...     for name in ("src/pkg/__init__.py", "environment.txt"):
    ...         _ = (root / name).write_text("")
    ...     cells = [{"cell_type": "code", "source": "import pkg", "metadata": {}}]
    ...     _ = (root / "book" / "demo.ipynb").write_text(json.dumps({"cells": cells,
    ...     "metadata": {"asoc": {}}}))
    ...     info = NotebookInfo("demo", root / "book" / "demo.ipynb", "Demo", (), ())
    ...     hashes = entry(make_plan(paths.project(), info, "ci"))
    >>> sorted(hashes), list(hashes["modules"]), hashes["depends"]
    (['depends', 'environment', 'modules', 'parameters', 'source'], ['pkg/__init__.py'], {})
    """
    source = plan.notebook.path
    depends = {}
    for name in dependencies(source):
        values = plan.values_of(name)
        depends[name] = _sha256(values.read_bytes()) if values.exists() else None
    environment = paths.project().environment
    return {"source": source_hash(source),
            "parameters": _sha256(json.dumps(plan.injected, sort_keys=True).encode()),
            "modules": module_hashes(source),
            "environment": _sha256(environment.read_bytes()) if environment.exists() else None,
            "depends": depends}


def load_manifest(output_dir) -> dict:
    """``{notebook: entry}`` of the runs recorded in ``output_dir`` (``{}`` if none).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     empty = load_manifest(folder)
    ...     _ = atomic_write_json(manifest_file(folder), {"sec3_5": {"seconds": 4.0}})
    ...     print(empty, load_manifest(folder))
    {} {'sec3_5': {'seconds': 4.0}}
    """
    path = manifest_file(output_dir)
    if not path.exists():
        return {}
    try:
        return json.loads(path.read_text())
    except ValueError:
        return {}          # a corrupt manifest: every notebook counts as never run


def incomplete_notebook(path) -> str:
    """Why the executed notebook at ``path`` is incomplete ("" if it is not): a code cell never
    executed, or papermill's record of an exception.

    Examples
    --------
    >>> import tempfile
    >>> cells = [{"cell_type": "code", "source": "x = 1", "execution_count": 1},
    ...          {"cell_type": "code", "source": "y = 2", "execution_count": None}]
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "demo.ipynb"
    ...     _ = path.write_text(json.dumps({"cells": cells, "metadata": {}}))
    ...     print(incomplete_notebook(path))
    code cells [1] were not executed
    """
    nb = json.loads(Path(path).read_text())
    if nb.get("metadata", {}).get("papermill", {}).get("exception"):
        return "papermill recorded an exception"
    unrun = [i for i, c in enumerate(nb["cells"]) if c["cell_type"] == "code"
             and "".join(c["source"]).strip() and c.get("execution_count") is None]
    return f"code cells {unrun} were not executed" if unrun else ""


def _incomplete_outputs(plan, reference=None) -> list:
    """What is missing from the results of the last run ``plan`` (empty: complete).

    The values file (``plan.values``) must exist and parse and hold every key the reference
    expects of the notebook; the executed notebook (``plan.executed``) must have every code
    cell executed.

    Examples
    --------
    The reference expects ``demo.rho`` and ``demo.gain``; the run recorded only ``rho``:

    >>> import tempfile
    >>> from asoc_companion.notebooks import NotebookInfo
    >>> from asoc_companion.reference import Entry
    >>> from asoc_companion.recorder import Recorder
    >>> reference = {f"demo.{k}": Entry(f"demo.{k}", where="an example",
    ...     kind="measured") for k in ("rho", "gain")}
    >>> from asoc_companion.plan import make_plan
    >>> with paths.scratch_project() as root:
    ...     info = NotebookInfo("demo", root / "book" / "demo.ipynb", "Demo", (), ())
    ...     plan = make_plan(paths.project(), info, "ci")
    ...     before = _incomplete_outputs(plan, reference=reference)
    ...     _ = Recorder("demo", "ci", plan.output_dir).record("rho", 0.25)
    ...     print(before, _incomplete_outputs(plan, reference=reference))
    ['no values file', 'no executed notebook'] ['values missing: gain', 'no executed notebook']
    """
    from .reference import load_reference

    problems = []
    path, executed = plan.values, plan.executed
    try:
        recorded = read_values_file(path)["values"] if path.exists() else None
    except CorruptValuesError:
        recorded, problems = None, problems + ["values file corrupt"]
    if recorded is None and not problems:
        problems.append("no values file")
    if recorded is not None:
        reference = reference if reference is not None else load_reference()
        missing = [e.name for e in reference.values()
                   if e.notebook == plan.name and e.name not in recorded]
        if missing:
            problems.append("values missing: "
                            f"{', '.join(missing[:3])}{' ...' if len(missing) > 3 else ''}")
    try:
        why = incomplete_notebook(executed) if executed.exists() else "no executed notebook"
    except (ValueError, KeyError):
        why = "executed notebook unreadable"
    return problems + ([why] if why else [])


def last_seconds(output_dir) -> dict:
    """``{notebook: wall time of its last recorded run}`` (notebooks without one are left out).

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> _ = atomic_write_json(manifest_file(out), {"sec3_2": {"seconds": 4.0},
    ...     "sec3_4": {"source": "ab12"}})
    >>> last_seconds(out)
    {'sec3_2': 4.0}
    """
    return {name: e["seconds"] for name, e in load_manifest(output_dir).items()
            if isinstance(e, dict) and isinstance(e.get("seconds"), (int, float))}


def changed_inputs(plan) -> list:
    """What changed since the run ``plan`` was made, or what its outputs lack (empty: up to date).

    Examples
    --------
    In a temporary checkout with a notebook ``demo`` that imports ``pkg``: never run, then up to
    date after a recorded run, then out of date once ``pkg`` is edited:

    >>> from asoc_companion.notebooks import NotebookInfo
    >>> from asoc_companion.plan import make_plan
    >>> from asoc_companion.recorder import Recorder
    >>> with paths.scratch_project() as root:
    ...     (root / "src/pkg").mkdir(parents=True)
    ...     for name in ("src/pkg/__init__.py", "environment.txt"):
    ...         _ = (root / name).write_text("")
    ...     cells = [{"cell_type": "code", "source": "import pkg", "metadata": {},
    ...     "execution_count": 1}]
    ...     info = NotebookInfo("demo", root / "book" / "demo.ipynb", "Demo", (), ())
    ...     _ = info.path.write_text(json.dumps({"cells": cells, "metadata": {"asoc": {}}}))
    ...     plan = make_plan(paths.project(), info, "full")      # executed in place
    ...     print(changed_inputs(plan))
    ...     _ = Recorder("demo", "full", plan.output_dir).record("rho", 0.25)
    ...     _ = update_manifest(plan)
    ...     print(changed_inputs(plan))
    ...     _ = (root / "src" / "pkg" / "__init__.py").write_text("x = 1")
    ...     print(changed_inputs(plan))
    ['never run']
    []
    ['modules (pkg/__init__.py)']
    """
    old = load_manifest(plan.output_dir).get(plan.name)
    if old is None:
        return ["never run"]
    incomplete = _incomplete_outputs(plan)
    if incomplete:
        return [f"outputs incomplete ({'; '.join(incomplete)})"]
    new = entry(plan)
    changed = []
    for key in new:
        if key == "modules" and isinstance(old.get(key), dict):
            edited = sorted(p for p in set(new[key]) | set(old[key])
                            if new[key].get(p) != old[key].get(p))
            if edited:
                changed.append("modules "
                               f"({', '.join(edited[:3])}{', ...' if len(edited) > 3 else ''})")
        elif old.get(key) != new[key]:
            changed.append(key)
    return changed


def update_manifest(plan, seconds=None) -> dict:
    """Record the finished run ``plan``'s input hashes in ``plan.manifest`` atomically; return it.

    ``seconds``, the run's wall time, is kept beside the hashes (not compared by
    :func:`changed_inputs`): the parallel build starts the longest notebooks first.

    Examples
    --------
    >>> from asoc_companion.notebooks import NotebookInfo
    >>> from asoc_companion.plan import make_plan
    >>> with paths.scratch_project() as root:
    ...     info = NotebookInfo("demo", root / "book" / "demo.ipynb", "Demo", (), ())
    ...     _ = info.path.write_text(json.dumps({"cells": [], "metadata": {"asoc": {}}}))
    ...     plan = make_plan(paths.project(), info, "ci")
    ...     recorded = update_manifest(plan, seconds=12.34)
    ...     print(recorded["seconds"], list(load_manifest(plan.output_dir)),
    ...     recorded["environment"])
    12.3 ['demo'] None
    """
    manifest = load_manifest(plan.output_dir)
    manifest[plan.name] = entry(plan)
    if seconds is not None:
        manifest[plan.name]["seconds"] = round(float(seconds), 1)
    atomic_write_json(plan.manifest, manifest)
    return manifest[plan.name]
