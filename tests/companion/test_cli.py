"""The command line and the notebook runner: parameter overrides (-p), the build manifest,
incremental reproduce, dependency order, reproducible executed notebooks."""

import argparse
import json
import shutil
import subprocess
import sys

import nbformat
import pytest

from asoc_companion import __main__ as cli
from asoc_companion import manifest, paths
from asoc_companion import notebooks as nbs
from asoc_companion import plan as plan_module
from asoc_companion.atomic_files import atomic_write_json
from asoc_companion.paths import ROOT
from asoc_companion.plan import make_plan, output_folder
from conftest import write_toy_notebook


def _notebook(
    folder,
    name,
    source="x = 1",
    depends=None,
    params='fidelity = "full"\noutput_dir = "."\nseed = 3',
):
    write_toy_notebook(folder, name, [source], params=params, depends=depends)
    return nbs.notebooks(folder)[name]


def test_values_are_typed_like_papermill():
    assert [nbs.parse_value(v) for v in ("7", "0.5", "1e3", "True", "False", "None", "ci")] == [
        7,
        0.5,
        1000.0,
        True,
        False,
        None,
        "ci",
    ]
    assert isinstance(nbs.parse_value("7"), int)


def test_unknown_parameter_fails_with_the_valid_names(capsys):
    assert cli.main(["figure", "3.2", "-p", "sed", "7", "--fidelity", "ci"]) == 2
    err = capsys.readouterr().err
    assert "'sed' is not a parameter of sec3_2.ipynb" in err and "valid names: seed, steps" in err
    assert cli.main(["figure", "3.2", "-p", "fidelity", "ci"]) == 2
    assert "--fidelity" in capsys.readouterr().err
    assert cli.main(["figure", "3.2", "-p", "output_dir", "/tmp"]) == 2


@pytest.mark.notebook
def test_parameter_run_goes_to_build_runs_and_leaves_tracked_files_alone(capfd):
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.fail("this test needs the project's git checkout (git status of tracked files)")
    status = ["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"]
    before = subprocess.run(status, capture_output=True, text=True, check=True).stdout
    info = nbs.find("figure", "3.2")
    out = make_plan(paths.project(), info, "ci", {"seed": 7}).output_dir
    shutil.rmtree(out, ignore_errors=True)
    assert cli.main(["figure", "3.2", "-p", "seed", "7", "--fidelity", "ci"]) == 0
    # capfd: the kernel process writes to the same stderr
    printed, errors = capfd.readouterr()
    assert "without encryption" not in errors, "the kernel's TCP warning reached the terminal"
    assert "committed (full)" in printed and "this run (ci)" in printed
    assert "does not reach" not in printed, "Fig. 3.2 depends on the seed"
    after = subprocess.run(status, capture_output=True, text=True, check=True).stdout
    assert after == before, f"tracked files changed:\n{after}"
    assert out.parent == ROOT / "book" / "_build" / "runs" and out.name.startswith("sec3_2-")
    assert f"{out.relative_to(ROOT)}/" in printed
    assert (out / "fig3_2.png").exists() and (out / "notebooks" / "sec3_2.ipynb").exists()
    values = json.loads((out / "values" / "sec3_2.json").read_text())["values"]
    assert "key" in printed and "committed" in printed and "this run" in printed
    assert all(key in printed for key in values)
    executed = nbformat.read(out / "notebooks" / "sec3_2.ipynb", as_version=4)
    assert executed.metadata.papermill["parameters"]["seed"] == 7
    assert (
        output_folder(paths.project(), "ci", info.name, {"seed": 8})
        != out
        != output_folder(paths.project(), "full", info.name, {"seed": 7})
    )


def test_source_hash_ignores_outputs_and_injected_parameters(tmp_path):
    info = _notebook(tmp_path, "secX_1")
    h = manifest.source_hash(info.path)
    nb = nbformat.read(info.path, as_version=4)
    nb.cells[1].outputs = [nbformat.v4.new_output("stream", text="1\n")]
    injected = nbformat.v4.new_code_cell('fidelity = "ci"')
    injected.metadata["tags"] = ["injected-parameters"]
    nb.cells.insert(1, injected)
    nbformat.write(nb, info.path)
    assert manifest.source_hash(info.path) == h
    nb.cells[2].source = "x = 2"
    nbformat.write(nb, info.path)
    assert manifest.source_hash(info.path) != h


def test_tree_hash_follows_contents_not_caches(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    h = manifest.tree_hash(tmp_path)
    (tmp_path / "__pycache__").mkdir()
    (tmp_path / "__pycache__" / "a.cpython-311.pyc").write_bytes(b"\0")
    assert manifest.tree_hash(tmp_path) == h
    (tmp_path / "a.py").write_text("x = 2\n")
    assert manifest.tree_hash(tmp_path) != h


def test_reproduce_runs_only_what_changed(tmp_path, monkeypatch, capsys):
    book, out = tmp_path / "book", tmp_path / "out"
    book.mkdir()
    info = _notebook(book, "secX_1")
    ran = []

    def fake_run(plan, **kwargs):
        ran.append(plan.name)
        atomic_write_json(
            out / "values" / f"{plan.name}.json", {"notebook": plan.name, "values": {"a": 1}}
        )
        executed = nbformat.read(plan.notebook.path, as_version=4)
        for count, cell in enumerate(executed.cells, 1):
            cell.execution_count = count
        target = plan.executed
        target.parent.mkdir(parents=True, exist_ok=True)
        nbformat.write(executed, target)
        return target

    monkeypatch.setattr(nbs, "notebooks", lambda book=None: {"secX_1": info})
    monkeypatch.setattr(plan_module, "output_folder", lambda *args: out)
    monkeypatch.setattr(nbs, "run", fake_run)
    monkeypatch.setattr(cli, "_ledger", lambda fidelity: None)
    assert cli.main(["reproduce", "--fidelity", "ci", "--jobs", "1"]) == 0
    assert ran == ["secX_1"] and "never run" in capsys.readouterr().out
    assert cli.main(["reproduce", "--fidelity", "ci", "--jobs", "1"]) == 0
    assert ran == ["secX_1"] and "secX_1.ipynb: up to date, skipped" in capsys.readouterr().out
    nb = nbformat.read(info.path, as_version=4)
    nb.cells[1].source = "x = 2"
    nbformat.write(nb, info.path)
    assert cli.main(["reproduce", "--fidelity", "ci", "--jobs", "1"]) == 0
    assert ran == ["secX_1"] * 2 and "changed: source" in capsys.readouterr().out
    assert cli.main(["reproduce", "--fidelity", "ci", "--force", "--jobs", "1"]) == 0
    assert ran == ["secX_1"] * 3
    entry = manifest.load_manifest(out)["secX_1"]
    assert set(entry) == {"source", "parameters", "modules", "environment", "depends", "seconds"}
    assert entry["seconds"] >= 0  # the run's wall time, for the longest-first order


def test_dependencies_run_first_and_enter_the_hash(tmp_path):
    a = _notebook(tmp_path, "a_findings", depends=["b_sec"])
    b = _notebook(tmp_path, "b_sec")
    assert [i.name for i in nbs.build_order([a, b])] == ["b_sec", "a_findings"]
    plan = make_plan(paths.project(), a, "ci", output_dir=tmp_path)
    h = manifest.entry(plan)
    atomic_write_json(tmp_path / "values" / "b_sec.json", {"notebook": "b_sec", "values": {"x": 1}})
    assert manifest.entry(plan)["depends"] != h["depends"]
    _notebook(tmp_path, "b_sec", depends=["a_findings"])
    with pytest.raises(ValueError, match="circular"):
        nbs.build_order(nbs.notebooks(tmp_path).values())
    _notebook(tmp_path, "b_sec", depends=["nope"])
    with pytest.raises(ValueError, match="'nope', which is not a notebook"):
        nbs.build_order(nbs.notebooks(tmp_path).values())
    _notebook(tmp_path, "b_sec", depends="a_findings")
    with pytest.raises(ValueError, match="list of notebook names"):
        manifest.dependencies(tmp_path / "b_sec.ipynb")


def test_notebooks_are_discovered_by_their_asoc_metadata(tmp_path):
    _notebook(tmp_path, "findings")
    _notebook(tmp_path, "sec9_9")
    plain = nbformat.v4.new_notebook()
    nbformat.write(plain, tmp_path / "scratch.ipynb")
    assert list(nbs.notebooks(tmp_path)) == ["sec9_9", "findings"]  # sections first


@pytest.mark.notebook
def test_executed_notebook_is_byte_identical_on_rerun(tmp_path):
    source = (
        "import time, warnings\nprint(seed * 2, flush=True)\ntime.sleep(0.3)\n"
        "print('x')\nwarnings.warn('w')"
    )
    info = _notebook(tmp_path, "secX_2", source=source)

    def plan(overrides):
        return make_plan(paths.project(), info, "ci", overrides, output_dir=tmp_path / "out")

    first = nbs.run(plan({"seed": 5}))
    data = first.read_bytes()
    nb = nbformat.read(first, as_version=4)
    assert "start_time" not in nb.metadata.papermill and "duration" not in nb.metadata.papermill
    assert all(
        "execution" not in c.metadata and "duration" not in c.metadata.get("papermill", {})
        for c in nb.cells
    )
    stdout, stderr = nb.cells[-1].outputs  # one chunk per stream, whatever the timing
    assert stdout["text"] == "10\nx\n" and stderr["text"].startswith("<cell>:5: UserWarning: w")
    assert nbs.run(plan({"seed": 5})).read_bytes() == data
    with pytest.raises(ValueError, match="valid names: seed"):
        nbs.run(plan({"n": 5}))


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ["-p", "seed", "notanumber"],
            "parameter seed of sec3_2.ipynb (default 3) takes an integer, found 'notanumber'",
        ),
        (["-p", "seed", "-1"], "is a seed: it takes an integer >= 0, found -1"),
        (["-p", "seed", "2.5"], "takes an integer, found 2.5"),
        (["-p", "seed", "True"], "takes an integer, found True"),
        (
            ["-p", "steps", "0"],
            "parameter steps of sec3_2.ipynb (default 30) is a count: "
            "it takes an integer >= 1, found 0",
        ),
        (["-p", "steps", "-5"], "is a count: it takes an integer >= 1, found -5"),
        (["-p", "seed", "7", "-p", "seed", "8"], "-p seed given twice (7 and '8'); give it once"),
    ],
)
def test_bad_parameter_values_fail_before_anything_runs(args, message, capsys, monkeypatch):
    monkeypatch.setattr(
        nbs, "run", lambda *a, **k: pytest.fail("a notebook ran despite a bad -p value")
    )
    assert cli.main(["figure", "3.2", "--fidelity", "ci", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_parameter_values_are_checked_against_the_defaults_type(tmp_path):
    info = _notebook(
        tmp_path,
        "secX_3",
        params='fidelity = "full"\noutput_dir = "."\nseed = 3\nn_runs_ci = 2_000\n'
        'rate = 0.5\nflag = True\nlabel = "a"\nshift = 0',
    )
    assert nbs.parse_overrides(
        info,
        [
            ("n_runs_ci", "500"),
            ("rate", "2"),
            ("flag", "False"),
            ("label", "b"),
            ("shift", "-3"),
            ("seed", "0"),
        ],
    ) == {"n_runs_ci": 500, "rate": 2.0, "flag": False, "label": "b", "shift": -3, "seed": 0}
    for name, value, message in [
        ("n_runs_ci", "-5", "count"),
        ("rate", "nan", "finite number"),
        ("rate", "x", "finite number"),
        ("flag", "1", "True or False"),
    ]:
        with pytest.raises(ValueError, match=message):
            nbs.parse_overrides(info, [(name, value)])


def test_corrupt_values_file_is_named_with_the_command_that_regenerates_it(
    tmp_path, capsys, monkeypatch
):
    from asoc_companion.values import CorruptValuesError, load_all_values, load_values

    (tmp_path / "values").mkdir()
    (tmp_path / "values" / "sec3_5.json").write_text('{"notebook": "sec3_5", "values": {"rho": 1.2')
    for load in (lambda: load_values("sec3_5", tmp_path), lambda: load_all_values(tmp_path)):
        with pytest.raises(
            CorruptValuesError,
            match=r"sec3_5\.json: corrupt values file .*"
            r"`python -m asoc_companion run sec3_5`",
        ):
            load()
    monkeypatch.setattr("asoc_companion.values.load_all_values", lambda: load_all_values(tmp_path))
    assert cli.main(["ledger"]) == 2
    err = capsys.readouterr().err
    assert (
        "sec3_5.json: corrupt values file" in err and "python -m asoc_companion run sec3_5" in err
    )
    assert len(err.strip().splitlines()) == 1


def test_outside_a_checkout_the_command_says_how_to_find_one(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    # empty: not configured; restored afterwards
    monkeypatch.setenv("ASOC_COMPANION_ROOT", "")
    assert cli.main(["list"]) == 2
    assert "no checkout of the companion found" in capsys.readouterr().err
    assert cli.main(["--root", str(tmp_path), "list"]) == 2
    assert "is not a checkout of the companion" in capsys.readouterr().err


def _actions(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from ((f"{name} {a}", h) for a, h in _actions(sub))
        elif not isinstance(action, argparse._HelpAction):
            yield "/".join(action.option_strings) or action.dest, action.help


def test_every_argument_has_help_text():
    bare = [name for name, text in _actions(cli.build_parser()) if not text]
    assert not bare, f"arguments without help text: {bare}"


def test_the_cli_says_when_a_parameter_cannot_change_the_figure():
    """Fig. 3.4 is computed without the seed (Sec. 3.5's Monte Carlo runs make Table 3.2), Fig. 3.2
    with it."""
    note = cli.unused_parameters(
        nbs.find("figure", "3.4"), "figure", "3.4", {"seed": 7, "horizon": 20}
    )
    assert note.startswith("note: seed does not reach") and "horizon" not in note
    assert cli.unused_parameters(nbs.find("figure", "3.2"), "figure", "3.2", {"seed": 7}) == ""
    assert nbs.parameters_reaching(nbs.find("table", "3.2"), "table", "3.2") >= {
        "seed",
        "n_runs_full",
    }


def test_committed_column_names_its_fidelity():
    table = cli.compare_with_committed("sec3_2", ROOT / "figures", "ci")
    assert table.splitlines()[0].split() == ["key", "committed", "(full)", "this", "run", "(ci)"]


def test_without_the_companion_extra_the_command_prints_one_line():
    """A library-only install (`pip install asoc`) has no yaml: one line says what to install."""
    code = (
        "import sys; sys.modules['yaml'] = None\n"
        "from asoc_companion.__main__ import main\n"
        "sys.exit(main(['list']))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 1 and proc.stdout == ""
    assert proc.stderr.strip().splitlines() == [
        "asoc-companion needs yaml: install the companion's dependencies: pip install "
        "'asoc[companion]'"
    ]
    use = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; sys.modules['yaml'] = None\nimport asoc_companion; asoc_companion.record",
        ],
        capture_output=True,
        text=True,
    )
    assert "pip install 'asoc[companion]'" in use.stderr.splitlines()[-1]


# ---- plain help, aligned list, natural order, where outputs went (issue 31, item 5) ----------


def _all_help_texts():
    parser = cli.build_parser()
    texts = [parser.format_help()]
    for action in parser._subparsers._group_actions:
        texts += [sub.format_help() for sub in action.choices.values()]
    return texts


def test_help_is_plain_text():
    for text in _all_help_texts():
        assert "`" not in text and ":func:" not in text, text


def test_list_aligns_every_row_to_the_longest_name(capsys):
    assert cli.main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = [name for name in nbs.notebooks()]
    column = max(map(len, names)) + 2
    assert len(lines) == 3 * len(names)
    for k, name in enumerate(names):
        title, items, params = lines[3 * k : 3 * k + 3]
        assert (
            title.startswith(name) and title[column - 2 : column] == "  " and title[column] != " "
        )
        assert items[:column].strip() == "" and items[column] != " "
        assert params[:column].strip() == "" and params[column:].startswith("parameters (-p):")


def test_known_figures_are_in_natural_order(capsys):
    assert cli.main(["figure", "9.9", "--fidelity", "ci"]) == 2
    known = capsys.readouterr().err.split("known: ")[1].strip().split(", ")
    assert known.index("2.2") < known.index("2.10") and known == sorted(known, key=nbs.natural_key)


def test_a_run_prints_where_its_outputs_went(tmp_path, monkeypatch, capsys):
    from asoc_companion import build

    info = _notebook(tmp_path, "demo")

    def fake_run(plan, **kwargs):
        (plan.output_dir / "fig2_10.png").write_text("")
        (plan.output_dir / "fig2_2.png").write_text("")
        return plan.executed

    monkeypatch.setattr(nbs, "run", fake_run)
    build.run_one(make_plan(paths.project(), info, "ci", output_dir=tmp_path))
    out = capsys.readouterr().out
    assert f"outputs in {build.rel(tmp_path)}/: " in out and "fig2_2.png, fig2_10.png" in out, out
