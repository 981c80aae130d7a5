"""The build plan (asoc_companion.plan): one run's paths, derived in one place."""

import ast
import json
from pathlib import Path

import pytest

from asoc_companion.notebooks import NotebookInfo
from asoc_companion.paths import Project
from asoc_companion.plan import make_plan

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "asoc_companion"
PROJECT = Project(Path("/checkout"))
INFO = NotebookInfo("sec3_2", PROJECT.book / "sec3_2.ipynb", "Sec. 3.2", ("3.2",), ())


def _rel(path):
    return path.relative_to(PROJECT.root).as_posix()


def test_full_run_writes_figures_and_executes_in_place():
    plan = make_plan(PROJECT, INFO, "full")
    assert (plan.name, plan.fidelity, plan.parameters) == ("sec3_2", "full", {})
    assert plan.executed == INFO.path
    shown = [
        _rel(p)
        for p in (
            plan.output_dir,
            plan.values,
            plan.figures,
            plan.tables,
            plan.manifest,
            plan.staging,
        )
    ]
    assert shown == [
        "figures",
        "figures/values/sec3_2.json",
        "figures",
        "figures",
        "figures/values/manifest.json",
        "book/_build/staging",
    ]
    assert plan.injected == {"fidelity": "full", "output_dir": "../figures"}
    assert _rel(plan.values_of("sec3_5")) == "figures/values/sec3_5.json"


def test_ci_run_writes_build_ci():
    plan = make_plan(PROJECT, INFO, "ci")
    assert [_rel(p) for p in (plan.output_dir, plan.executed, plan.values, plan.manifest)] == [
        "book/_build/ci",
        "book/_build/ci/notebooks/sec3_2.ipynb",
        "book/_build/ci/values/sec3_2.json",
        "book/_build/ci/values/manifest.json",
    ]
    assert plan.injected == {"fidelity": "ci", "output_dir": "_build/ci"}


@pytest.mark.parametrize("fidelity", ["full", "ci"])
def test_run_with_parameters_writes_its_own_runs_folder(fidelity):
    plan = make_plan(PROJECT, INFO, fidelity, {"steps": 10})
    folder = _rel(plan.output_dir)
    assert folder.startswith("book/_build/runs/sec3_2-") and len(folder.rsplit("-", 1)[1]) == 10
    assert _rel(plan.executed) == f"{folder}/notebooks/sec3_2.ipynb"
    assert _rel(plan.values) == f"{folder}/values/sec3_2.json"
    assert _rel(plan.manifest) == f"{folder}/values/manifest.json"
    injected = {"fidelity": fidelity, "output_dir": folder.removeprefix("book/"), "steps": 10}
    assert plan.injected == injected
    other = make_plan(PROJECT, INFO, fidelity, {"steps": 11})
    assert other.output_dir != plan.output_dir != make_plan(PROJECT, INFO, fidelity).output_dir


def test_staged_run_names_the_stage_not_the_output_folder():
    plan = make_plan(PROJECT, INFO, "ci", {"steps": 10})
    staged, injected = plan.staged(PROJECT.staging / "sec3_2-abc")
    assert _rel(staged) == "book/_build/staging/sec3_2-abc/notebooks/sec3_2.ipynb"
    assert injected == {"fidelity": "ci", "output_dir": "_build/staging/sec3_2-abc", "steps": 10}


def test_unknown_fidelity_is_refused():
    with pytest.raises(ValueError, match="fidelity must be one of"):
        make_plan(PROJECT, INFO, "fast")


# A ``/`` join with one of these names outside plan.py and paths.py re-derives a path of a run.
# (``_build`` alone is not one: Jupyter Book's own ``_build/latex`` is no run's path.)
RUN_PATH_NAMES = {"values", "manifest.json", "ci", "runs", "staging", "notebooks"}


def _run_path_joins(tree) -> list:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
            for side in (node.left, node.right):
                if isinstance(side, ast.Constant) and side.value in RUN_PATH_NAMES:
                    found.append((node.lineno, side.value))
                elif (
                    isinstance(side, ast.JoinedStr)
                    and isinstance(side.values[-1], ast.Constant)
                    and str(side.values[-1].value).endswith(".json")
                ):
                    found.append((node.lineno, "<name>.json"))
        elif isinstance(node, ast.Constant) and node.value == "manifest.json":
            found.append((node.lineno, node.value))
    return found


def test_the_scan_finds_a_path_built_by_hand():
    code = (
        'out / "values" / f"{name}.json"\nPath(out) / "book" / "_build" / "ci"\nx = "manifest.json"'
    )
    assert sorted(v for _, v in _run_path_joins(ast.parse(code))) == [
        "<name>.json",
        "ci",
        "manifest.json",
        "values",
    ]


def test_only_plan_and_paths_build_the_paths_of_a_run():
    offenders = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name in ("plan.py", "paths.py") and path.parent == PACKAGE:
            continue
        found = _run_path_joins(ast.parse(path.read_text()))
        if found:
            offenders[path.relative_to(PACKAGE).as_posix()] = found
    assert not offenders, f"run paths built outside asoc_companion/plan.py: {json.dumps(offenders)}"
