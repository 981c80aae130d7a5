"""The build redoes only what changed (issue 14): a notebook's manifest entry hashes the modules
it imports, directly or transitively, so an edit to ``asoc/gp`` re-runs Sec. 2.6 and the pages
that quote its values, nothing else; ``reproduce`` runs independent notebooks in parallel, in
dependency order, one BLAS thread each."""

import json
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

from asoc_companion import __main__ as cli
from asoc_companion import manifest, paths
from asoc_companion import notebooks as nbs
from asoc_companion.atomic_files import atomic_write_json
from asoc_companion.imports import closure, imported_names
from asoc_companion.plan import make_plan
from conftest import write_toy_notebook

SRC = Path(__file__).resolve().parents[2] / "src"

MODULES = {
    "asoc/__init__.py": '"""lib"""\n',
    "asoc/gp/__init__.py": "from .kernels import se\n",
    "asoc/gp/kernels.py": "import numpy as np\n\ndef se(x):\n    return np.exp(-x)\n",
    "asoc/mjls/__init__.py": "from .system import MJLS\n",
    "asoc/mjls/system.py": "from ..stats import median\n\nclass MJLS:\n    pass\n",
    "asoc/stats.py": "def median(x):\n    return x\n",
    "asoc_companion/__init__.py": "from .recorder import record\nfrom asoc.stats import median\n",
    "asoc_companion/recorder.py": "def record(key, value):\n    return value\n",
    "asoc_companion/manifest.py": "def entry():\n    pass\n",
}


def _project(tmp_path, monkeypatch):
    for rel, text in MODULES.items():
        (tmp_path / "src" / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "src" / rel).write_text(text)
    (tmp_path / "book").mkdir()
    (tmp_path / "book" / "_toc.yml").write_text("format: jb-book\nroot: intro\n")
    (tmp_path / "figures" / "values").mkdir(parents=True)
    (tmp_path / "tests" / "reference" / "thesis_values").mkdir(parents=True)
    (tmp_path / "environment.txt").write_text("numpy==2.4.6\n")
    monkeypatch.setenv(paths.ENV_VAR, str(tmp_path))
    return paths.project()


def _notebook(book, name, source, depends=None):
    write_toy_notebook(book, name, [source], depends=depends)


def test_imports_are_read_statically_with_relative_and_lazy_ones():
    code = (
        "import a.b\nfrom c import d, e\nfrom . import f\nfrom ..g import h\n"
        "def k():\n    import lazy\n"
    )
    assert imported_names(code, package="p.q") == {
        "a.b",
        "c",
        "c.d",
        "c.e",
        "p.q",
        "p.q.f",
        "p.g",
        "p.g.h",
        "lazy",
    }


def test_closure_follows_packages_and_relative_imports(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    found = closure({"asoc.mjls"}, project.src)
    assert sorted(found) == ["asoc", "asoc.mjls", "asoc.mjls.system", "asoc.stats"]


def _entries(project):
    return {
        name: manifest.changed_inputs(make_plan(project, info, "full"))
        for name, info in nbs.notebooks().items()
    }


def test_editing_gp_reruns_sec2_6_and_the_pages_quoting_it_nothing_else(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    _notebook(project.book, "sec2_6", "import asoc_companion as repro\nfrom asoc import gp")
    _notebook(project.book, "sec3_2", "import asoc_companion as repro\nfrom asoc.mjls import MJLS")
    _notebook(
        project.book, "findings", "import asoc_companion as repro", depends=["sec2_6", "sec3_2"]
    )
    out = project.figures
    for name, info in nbs.notebooks().items():
        atomic_write_json(out / "values" / f"{name}.json", {"notebook": name, "values": {"x": 1}})
        nb = nbformat.read(info.path, as_version=4)
        for count, cell in enumerate(nb.cells, 1):
            cell.execution_count = count
        nbformat.write(nb, info.path)
    for info in nbs.build_order(nbs.notebooks().values()):
        manifest.update_manifest(make_plan(project, info, "full"))
    assert _entries(project) == {"sec2_6": [], "sec3_2": [], "findings": []}
    entry = manifest.load_manifest(out)["sec3_2"]["modules"]
    assert "asoc/mjls/system.py" in entry and "asoc_companion/recorder.py" in entry
    assert (
        not [p for p in entry if p.startswith("asoc/gp")]
        and "asoc_companion/manifest.py" not in entry
    )

    (project.src / "asoc" / "gp" / "kernels.py").write_text(
        MODULES["asoc/gp/kernels.py"] + "# edited\n"
    )
    assert _entries(project) == {
        "sec2_6": ["modules (asoc/gp/kernels.py)"],
        "sec3_2": [],
        "findings": [],
    }
    # Sec. 2.6 re-runs and records a new value: the findings page, which quotes it, follows
    atomic_write_json(out / "values" / "sec2_6.json", {"notebook": "sec2_6", "values": {"x": 2}})
    manifest.update_manifest(make_plan(project, nbs.notebooks()["sec2_6"], "full"))
    assert _entries(project) == {"sec2_6": [], "sec3_2": [], "findings": ["depends"]}
    # an edit to the harness's own machinery re-runs nothing; one to recording re-runs all
    (project.src / "asoc_companion" / "manifest.py").write_text("def entry():\n    return 1\n")
    assert _entries(project) == {"sec2_6": [], "sec3_2": [], "findings": ["depends"]}
    (project.src / "asoc_companion" / "recorder.py").write_text(
        "def record(key, value):\n    return 2 * value\n"
    )
    assert all(
        any("asoc_companion/recorder.py" in c for c in changed)
        for changed in _entries(project).values()
    )


def test_every_notebook_of_the_book_hashes_its_own_import_closure():
    src = paths.project().src
    for name, info in nbs.notebooks().items():
        modules = manifest.module_hashes(info.path)
        assert modules, f"{name}: no project module found among its imports"
        assert all((src / p).is_file() for p in modules)
        assert not [
            p
            for p in modules
            if p.startswith(("asoc_companion/__main__", "asoc_companion/notebooks"))
        ]
    # the section on MJLS stability never runs the Gaussian-process code
    assert not [
        p
        for p in manifest.module_hashes(nbs.notebooks()["sec3_2"].path)
        if p.startswith("asoc/gp/")
    ]


@pytest.mark.notebook
def test_reproduce_runs_independent_notebooks_in_parallel_after_their_dependencies(
    tmp_path, monkeypatch, capsys
):
    project = _project(tmp_path, monkeypatch)
    monkeypatch.setenv("PYTHONPATH", str(SRC))
    record = (
        "import os, time, asoc_companion as repro\n"
        "repro.setup('{name}', fidelity=fidelity, output_dir=output_dir)\n"
        "repro.record('start', time.time()); time.sleep(2.0)\n"
        "repro.record('threads', os.environ.get('OPENBLAS_NUM_THREADS'))\n"
        "_ = repro.record('end', time.time())"
    )
    for name in ("secA_1", "secB_1"):
        _notebook(project.book, name, record.format(name=name))
    _notebook(project.book, "findings", record.format(name="findings"), depends=["secA_1"])
    start = time.monotonic()
    # the real entry point: spawned workers must find their functions under `python -m`
    proc = subprocess.run(
        [sys.executable, "-m", "asoc_companion", "reproduce", "--jobs", "2"],
        cwd=project.book,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "2 at a time" in proc.stdout
    values = {
        n: json.loads((project.figures / "values" / f"{n}.json").read_text())["values"]
        for n in ("secA_1", "secB_1", "findings")
    }
    assert (
        values["secA_1"]["start"] < values["secB_1"]["end"]
        and values["secB_1"]["start"] < values["secA_1"]["end"]
    ), "the two independent notebooks did not overlap"
    assert values["findings"]["start"] >= values["secA_1"]["end"], (
        "findings started before the notebook it quotes"
    )
    assert {v["threads"] for v in values.values()} == {"1"}
    assert set(manifest.load_manifest(project.figures)) == {"secA_1", "secB_1", "findings"}
    # each entry keeps the run's wall time (the next build starts the longest first), and the
    # time is no input: the second build below skips all three
    assert all(seconds >= 2.0 for seconds in manifest.last_seconds(project.figures).values())
    assert set(manifest.last_seconds(project.figures)) == {"secA_1", "secB_1", "findings"}
    monkeypatch.setattr(cli, "_ledger", lambda fidelity: None)
    assert cli.main(["reproduce", "--jobs", "2"]) == 0
    assert capsys.readouterr().out.count("up to date, skipped") == 3
    assert time.monotonic() - start < 120
