"""Input hashes of each executed notebook, so a build re-executes only what changed.

``<output_dir>/values/manifest.json`` (``figures/values/manifest.json`` for the committed
full-fidelity run) holds, per notebook, content hashes of everything its results depend on:

``source``       the notebook's cells (type and source, not outputs; papermill's injected
                 parameters cell excluded) and its ``asoc`` metadata;
``parameters``   the parameters papermill injects (fidelity, output folder, overrides);
``src``          every file under ``src/asoc`` (sorted paths, content hashes);
``environment``  ``environment.txt``, the pinned requirements;
``depends``      the recorded values of the notebooks named in its metadata
                 (``metadata.asoc.depends``, e.g. a findings page that quotes other pages).

A notebook is up to date when its entry equals the hashes computed now and its values file
exists; ``python -m asoc_companion reproduce`` skips it then (``--force`` re-executes everything).
"""

import hashlib
import json
from pathlib import Path

from .io import atomic_write_json
from .paths import ROOT
from .values import values_path

SRC = ROOT / "src" / "asoc"
ENVIRONMENT = ROOT / "environment.txt"
MANIFEST_NAME = "manifest.json"


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def source_hash(path) -> str:
    """Hash of a notebook's cell types and sources and its ``asoc`` metadata (outputs ignored)."""
    nb = json.loads(Path(path).read_text())
    cells = [[c["cell_type"], "".join(c["source"]) if isinstance(c["source"], list) else c["source"]]
             for c in nb["cells"] if "injected-parameters" not in c.get("metadata", {}).get("tags", [])]
    return _sha256(json.dumps([cells, nb["metadata"].get("asoc")], sort_keys=True).encode())


def tree_hash(folder=SRC) -> str:
    """Hash of every file below ``folder`` (relative paths and contents; caches skipped)."""
    folder = Path(folder)
    files = sorted(p for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                   and p.suffix != ".pyc" and not p.name.endswith(".tmp"))
    lines = [f"{p.relative_to(folder).as_posix()}\0{_sha256(p.read_bytes())}\n" for p in files]
    return _sha256("".join(lines).encode())


def dependencies(path) -> list:
    """Names of the notebooks whose recorded values the notebook reads (``metadata.asoc.depends``)."""
    depends = json.loads(Path(path).read_text())["metadata"].get("asoc", {}).get("depends", [])
    if isinstance(depends, str) or not all(isinstance(d, str) for d in depends):
        raise ValueError(f"{Path(path).name}: metadata.asoc.depends must be a list of notebook names, "
                         f"found {depends!r}")
    return list(depends)


def entry(info, parameters: dict, output_dir) -> dict:
    """The input hashes of ``info``'s notebook run with ``parameters`` into ``output_dir``."""
    depends = {}
    for name in dependencies(info.path):
        values = values_path(name, output_dir)
        depends[name] = _sha256(values.read_bytes()) if values.exists() else None
    return {"source": source_hash(info.path),
            "parameters": _sha256(json.dumps(parameters, sort_keys=True).encode()),
            "src": tree_hash(SRC), "environment": _sha256(ENVIRONMENT.read_bytes()),
            "depends": depends}


def manifest_path(output_dir) -> Path:
    """Where the manifest of runs into ``output_dir`` lives."""
    return Path(output_dir) / "values" / MANIFEST_NAME


def load_manifest(output_dir) -> dict:
    """``{notebook: entry}`` of the runs recorded in ``output_dir`` (``{}`` if none)."""
    path = manifest_path(output_dir)
    return json.loads(path.read_text()) if path.exists() else {}


def changed_inputs(info, parameters: dict, output_dir) -> list:
    """What changed since ``info`` was last run into ``output_dir`` (empty: up to date)."""
    old = load_manifest(output_dir).get(info.name)
    if old is None or not values_path(info.name, output_dir).exists():
        return ["never run"]
    new = entry(info, parameters, output_dir)
    return [key for key in new if old.get(key) != new[key]]


def update_manifest(info, parameters: dict, output_dir) -> dict:
    """Record the input hashes of a finished run of ``info`` (atomically); return the entry."""
    manifest = load_manifest(output_dir)
    manifest[info.name] = entry(info, parameters, output_dir)
    atomic_write_json(manifest_path(output_dir), manifest)
    return manifest[info.name]
