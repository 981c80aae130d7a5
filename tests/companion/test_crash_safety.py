"""Crash-safe runs (issue 15): an interrupted or failed run leaves every tracked file
byte-identical, and ``reproduce`` repairs incomplete outputs even when the hashes agree.

The kill test starts real full-fidelity runs of the fastest notebook (Sec. 3.2) through
the command line in a throwaway clone of this checkout (the code under test is this
checkout's ``src``; the clone is the project, via ``ASOC_COMPANION_ROOT``), kills each
with SIGINT (to the process group, like Ctrl-C), SIGTERM (to the command) or SIGKILL (to
the process group, like the out-of-memory killer) at several points, and checks
``git status --porcelain`` of the clone.
"""

import json
import os
import shutil
import signal
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
from asoc_companion.plan import make_plan
from conftest import write_toy_notebook

SRC = Path(__file__).resolve().parents[2] / "src"


def _git(*args, cwd):
    return subprocess.run(
        ["git", *args], cwd=cwd, capture_output=True, text=True, check=True
    ).stdout


@pytest.fixture(scope="module")
def clone(tmp_path_factory):
    """A throwaway clone of the committed checkout (figures and notebooks as committed)."""
    root = paths.project().root
    if shutil.which("git") is None or not (root / ".git").exists():
        pytest.fail("the kill test needs git and the project's git checkout")
    target = tmp_path_factory.mktemp("clone") / "companion"
    subprocess.run(["git", "clone", "-q", "--no-hardlinks", str(root), str(target)], check=True)
    assert _git("status", "--porcelain", cwd=target) == ""
    return target


def _as_foreground_command():
    """SIGINT at its default, as for a command started from an interactive shell: a test run
    started as a background job of a script (``make test &``) inherits SIGINT ignored, and the
    Ctrl-C this test sends would not arrive."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(clone):
    env = {**os.environ, "PYTHONPATH": str(SRC), paths.ENV_VAR: str(clone)}
    return subprocess.Popen(
        [sys.executable, "-m", "asoc_companion", "figure", "3.2"],
        cwd=clone,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,
        preexec_fn=_as_foreground_command,
    )


def _wait_for(proc, condition, timeout=60.0):
    start = time.monotonic()
    while not condition():
        assert proc.poll() is None, (
            "the run ended before the kill point: " + proc.stdout.read().decode()[-2000:]
        )
        assert time.monotonic() - start < timeout, "kill point not reached"
        time.sleep(0.02)


def _values_written(clone, since):
    """Whether the run has written a values file of Sec. 3.2 anywhere in the clone (staged or
    not)."""
    return lambda: any(p.stat().st_mtime > since for p in clone.rglob("sec3_2.json"))


POINTS = {
    "after 1 s (kernel starting)": lambda clone, t0, wall: lambda: time.monotonic() - t0 >= 1.0,
    "after 2 s": lambda clone, t0, wall: lambda: time.monotonic() - t0 >= 2.0,
    "mid-run (values being recorded)": lambda clone, t0, wall: _values_written(clone, wall),
}


@pytest.mark.notebook
@pytest.mark.parametrize(
    "sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL], ids=lambda s: s.name
)
@pytest.mark.parametrize("point", list(POINTS))
def test_killed_run_leaves_tracked_files_identical(clone, sig, point):
    shutil.rmtree(clone / "book" / "_build" / "staging", ignore_errors=True)
    wall = time.time() - 0.01
    proc = _start(clone)
    try:
        _wait_for(proc, POINTS[point](clone, time.monotonic(), wall))
        if sig == signal.SIGTERM:
            proc.send_signal(sig)  # the command alone; it shuts its kernel down
        else:
            os.killpg(proc.pid, sig)  # Ctrl-C / OOM kill: the whole process group
        output = proc.communicate(timeout=60)[0].decode(errors="replace")
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # no kernel outlives the test
        except ProcessLookupError:
            pass
    assert proc.returncode != 0
    assert _git("status", "--porcelain", cwd=clone) == "", (
        f"{sig.name} {point}: tracked files changed"
    )
    # a handled interrupt also removes its staging folder
    if sig != signal.SIGKILL:
        left = sorted(
            str(p.relative_to(clone)) for p in (clone / "book" / "_build" / "staging").rglob("*")
        )
        assert not left, (
            f"{sig.name} {point}: exit code {proc.returncode}, staging left {left}; "
            f"output:\n{output[-3000:]}"
        )


def _project(tmp_path, monkeypatch):
    """A minimal project: book/_toc.yml, figures/, an empty reference folder."""
    (tmp_path / "book").mkdir()
    (tmp_path / "book" / "_toc.yml").write_text("format: jb-book\nroot: intro\n")
    (tmp_path / "figures" / "values").mkdir(parents=True)
    (tmp_path / "tests" / "reference" / "thesis_values").mkdir(parents=True)
    (tmp_path / "environment.txt").write_text("numpy\n")
    monkeypatch.setenv(paths.ENV_VAR, str(tmp_path))
    return paths.project()


def _notebook(book, name, cells):
    write_toy_notebook(book, name, cells)
    return nbs.notebooks(book)[name]


@pytest.mark.notebook
def test_failed_run_moves_nothing(tmp_path, monkeypatch):
    project = _project(tmp_path, monkeypatch)
    monkeypatch.setenv("PYTHONPATH", str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    info = _notebook(
        project.book,
        "secX_9",
        [
            "import asoc_companion as repro\nrepro.setup('secX_9', fidelity=fidelity, "
            "output_dir=output_dir)",
            "repro.record('a', 2.0)",
            "raise RuntimeError('the computation failed')",
        ],
    )
    committed = {"notebook": "secX_9", "fidelity": "full", "values": {"a": 1.0}}
    atomic_write_json(project.figures / "values" / "secX_9.json", committed)
    before = {p: p.read_bytes() for p in [info.path, project.figures / "values" / "secX_9.json"]}
    with pytest.raises(Exception, match="the computation failed"):
        nbs.run(make_plan(project, info, "full"), progress_bar=False)
    assert {p: p.read_bytes() for p in before} == before
    assert sorted(p.name for p in project.figures.rglob("*")) == ["secX_9.json", "values"]
    assert not list(project.staging.iterdir()), "the failed run's staging folder was left behind"


def test_reproduce_reruns_incomplete_outputs_although_hashes_agree(tmp_path, monkeypatch, capsys):
    project = _project(tmp_path, monkeypatch)
    (project.reference / "secX_8.yaml").write_text(
        "secX_8.a: {where: 'Sec. X', kind: measured}\nsecX_8.b: {where: 'Sec. X', kind: measured}\n"
    )
    info = _notebook(project.book, "secX_8", ["x = 1"])
    ran = []

    def fake_run(plan, **kwargs):
        ran.append(plan.name)
        atomic_write_json(
            project.figures / "values" / "secX_8.json",
            {"notebook": "secX_8", "fidelity": "full", "values": {"a": 1, "b": 2}},
        )
        nb = nbformat.read(info.path, as_version=4)
        for count, cell in enumerate(nb.cells, 1):
            cell.execution_count = count
        nbformat.write(nb, info.path)
        return info.path

    monkeypatch.setattr(nbs, "run", fake_run)
    monkeypatch.setattr(cli, "_ledger", lambda fidelity: None)
    assert cli.main(["reproduce", "--jobs", "1"]) == 0 and ran == ["secX_8"]
    assert cli.main(["reproduce", "--jobs", "1"]) == 0 and ran == ["secX_8"]
    assert "up to date, skipped" in capsys.readouterr().out
    # a value the reference expects goes missing (hashes unchanged): re-run
    atomic_write_json(
        project.figures / "values" / "secX_8.json",
        {"notebook": "secX_8", "fidelity": "full", "values": {"a": 1}},
    )
    assert cli.main(["reproduce", "--jobs", "1"]) == 0 and ran == ["secX_8"] * 2
    assert "values missing: b" in capsys.readouterr().out
    # a code cell lost its outputs and execution count: re-run
    nb = nbformat.read(info.path, as_version=4)
    nb.cells[1].execution_count, nb.cells[1].outputs = None, []
    nbformat.write(nb, info.path)
    assert manifest.changed_inputs(make_plan(project, info, "full"))
    assert cli.main(["reproduce", "--jobs", "1"]) == 0 and ran == ["secX_8"] * 3
    # a truncated values file: re-run, not a JSONDecodeError
    (project.figures / "values" / "secX_8.json").write_text('{"notebook": "secX_8", "val')
    assert cli.main(["reproduce", "--jobs", "1"]) == 0 and ran == ["secX_8"] * 4
    assert json.loads((project.figures / "values" / "secX_8.json").read_text())["values"] == {
        "a": 1,
        "b": 2,
    }


@pytest.mark.notebook
def test_every_kernel_computes_with_one_blas_thread(tmp_path, monkeypatch):
    """A run alone gives the numbers of a run beside others: the kernel has one BLAS thread, even
    when the caller's environment asks for more."""
    project = _project(tmp_path, monkeypatch)
    monkeypatch.setenv("PYTHONPATH", str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    info = _notebook(
        project.book,
        "secX_7",
        [
            "import os\nimport asoc_companion as repro\nrepro.setup('secX_7', fidelity=fidelity, "
            "output_dir=output_dir)",
            "repro.record('threads', [os.environ.get(name) for name in ('OPENBLAS_NUM_THREADS', "
            "'OMP_NUM_THREADS')])",
        ],
    )
    nbs.run(make_plan(project, info, "full"), progress_bar=False)
    recorded = json.loads((project.figures / "values" / "secX_7.json").read_text())["values"]
    assert recorded["threads"] == ["1", "1"]
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2" and "OMP_NUM_THREADS" not in os.environ


def test_staging_folder_refilled_by_a_late_write_is_removed(tmp_path, monkeypatch):
    """A kernel still shutting down writes one last values file after the folder was emptied: the
    removal is repeated until the folder is gone (with one attempt, the planted variant, it
    stays)."""
    from asoc_companion import staging

    real_rmtree, calls = shutil.rmtree, []

    def rmtree_then_late_write(path, ignore_errors=False):
        real_rmtree(path, ignore_errors=ignore_errors)
        calls.append(path)
        if len(calls) == 1:  # the kernel's last write lands now
            (Path(path) / "values").mkdir(parents=True)
            (Path(path) / "values" / "sec3_2.json").write_text("{}")

    monkeypatch.setattr(staging.shutil, "rmtree", rmtree_then_late_write)
    stage = tmp_path / "sec3_2-x"
    stage.mkdir()
    staging.remove_stage(stage)
    assert not stage.exists() and len(calls) == 2
    calls.clear()
    stage.mkdir()
    staging.remove_stage(stage, attempts=1)
    assert stage.exists()
