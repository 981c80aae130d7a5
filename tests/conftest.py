"""Shared fixtures: the notebooks are run once per session at ci fidelity; the book is built
once and opened in headless Chromium.

The benchmark suite (``tests/benchmarks``) is collected only by ``make bench``
(``--benchmark-only``): its full-fidelity workloads take minutes and time the machine, not
the code's correctness, so the normal test run leaves them out.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from hypothesis import settings
from papermill.parameterize import parameterize_notebook

from asoc_companion import notebooks as nbs
from asoc_companion import paths
from asoc_companion.paths import BOOK, CI_OUTPUT

NOTEBOOKS = nbs.notebooks()
HERE = Path(__file__).resolve().parent


def pytest_ignore_collect(collection_path, config):
    if Path(collection_path).resolve() == HERE / "benchmarks" and not config.getoption(
        "benchmark_only", False
    ):
        return True
    return None


# module-scoped clone / wheel / full run of a notebook
SHARED_FIXTURE_MODULES = ("test_crash_safety", "test_packaging", "test_your_system")
GROUP = pytest.StashKey[str]()
#: seconds each group took in `make test` on 2 cores (tests/notebooks: the ci runs, the PDF and
#: the book), for the order in which the groups are handed out
GROUP_SECONDS = {
    "book": 110.0,
    "pdf": 95.0,
    "ci-sec3_4": 60.0,
    "ci-sec3_6": 52.0,
    "ci-sec2_6": 44.0,
    "ci-theorems": 41.0,
    "ci-sec2_5": 40.0,
    "ci-findings": 37.0,
    "ci-large_system": 35.0,
    "ci-sec3_5": 28.0,
    "ci-your_system": 24.0,
    "test_your_system": 36.0,
    "test_crash_safety": 22.0,
    "ci-scaling": 20.0,
    "ci-peers": 15.0,
    "test_packaging": 12.0,
    "ci-sec3_2": 9.0,
}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under pytest-xdist (``--dist loadgroup``), tests that share an expensive fixture run on one
    worker: the book build, the PDF build, one notebook's ci run, a module's clone or wheel."""
    for item in items:
        fixtures = getattr(item, "fixturenames", ())
        if "pdf" in fixtures:
            group = "pdf"
        elif item.get_closest_marker("book") or "html" in fixtures:
            group = "book"
        elif ("ci_run" in fixtures or "ci_execution" in fixtures) and hasattr(item, "callspec"):
            group = f"ci-{item.callspec.params.get('name')}"
        elif Path(str(item.fspath)).stem in SHARED_FIXTURE_MODULES:
            group = Path(str(item.fspath)).stem
        else:
            continue
        item.add_marker(pytest.mark.xdist_group(group))
        item.stash[GROUP] = group
    # longest first (the scheduler hands out groups in this order): the long groups start
    # at once on both workers and the short tests fill the gaps, instead of one long group
    # running alone at the end
    items.sort(key=lambda item: -GROUP_SECONDS.get(item.stash.get(GROUP, None), 0.0))


# Property tests draw the same examples on every run and machine (no example database), so a
# test run is reproducible like everything else (book/architecture.md, "Portability and
# tolerances").
settings.register_profile("deterministic", derandomize=True, database=None)
settings.load_profile("deterministic")


@pytest.fixture(scope="session")
def ci_execution():
    """Execute a notebook once per session at ci fidelity, under nbval; ``run(name)`` returns
    (output folder, nbval's completed process).

    One execution serves both notebook tests: nbval re-executes the committed notebook with
    papermill's ci parameters injected and compares the cells tagged ``nbval-check-output``
    with their stored outputs (tests/notebooks/test_nbval.py), and the same execution records the
    values,
    figures and tables that tests/notebooks/test_notebooks.py checks against the reference.
    """
    done = {}

    def run(name):
        if name not in done:
            out = CI_OUTPUT / "test" / name
            shutil.rmtree(out, ignore_errors=True)
            out.mkdir(parents=True)
            nb = nbformat.read(NOTEBOOKS[name].path, as_version=4)
            nb = parameterize_notebook(nb, {"fidelity": "ci", "output_dir": str(out)})
            copy = out / f"{name}.ipynb"
            nbformat.write(nb, copy)
            proc = _nbval(copy, out)
            if proc.returncode != 0 and PORT_TAKEN in proc.stdout + proc.stderr:
                proc = _nbval(copy, out)  # nbval's kernel talks TCP: a port race, not a result
            done[name] = out, proc
        return done[name]

    return run


PORT_TAKEN = "Address already in use"
"""What a kernel dies of when another kernel, started at the same moment, took its TCP port."""


def _nbval(copy, out):
    """nbval (lax mode) on the notebook ``copy``, in the folder ``out``; the completed process."""
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-p",
            "no:xdist",
            "-o",
            "addopts=",
            "--nbval-lax",
            "--nbval-sanitize-with",
            str(HERE / "notebooks" / "nbval_sanitize.cfg"),
            str(copy),
        ],
        cwd=out,
        capture_output=True,
        text=True,
        timeout=1800,
        # the kernel runs next to the copy, outside book/: name the project explicitly
        env={**os.environ, paths.ENV_VAR: str(paths.project().root)},
    )


@pytest.fixture(scope="session")
def ci_run(ci_execution):
    """The output folder of a notebook's ci-fidelity execution (values, figures, tables)."""
    return lambda name: ci_execution(name)[0]


@pytest.fixture(scope="session")
def html(tmp_path_factory):
    """The book built once per session from the committed notebooks; its HTML folder."""
    out = tmp_path_factory.mktemp("book")
    subprocess.run([sys.executable, "-m", "asoc_companion.book"], check=True)
    jb = Path(sys.executable).parent / "jupyter-book"
    proc = subprocess.run(
        [str(jb), "build", str(BOOK), "--path-output", str(out), "--quiet"],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    (out / "build.log").write_text(proc.stdout + proc.stderr)
    return out / "_build" / "html"


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium in a 1280 x 900 window, keeping its console ("browser") and network
    ("performance") logs for tests/notebooks/test_book.py."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    if not shutil.which("chromium") or not shutil.which("chromedriver"):
        pytest.fail("chromium and chromedriver are required (make test installs them)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--allow-file-access-from-files",
    ):
        opts.add_argument(flag)
    opts.add_argument("--window-size=1280,900")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    driver.set_window_size(1280, 900)
    yield driver
    driver.quit()


def write_toy_notebook(
    book, name, cells, params='fidelity = "full"\noutput_dir = "../figures"', depends=None
):
    """Write a minimal harness notebook ``book/<name>.ipynb`` (the ``asoc`` metadata, a tagged
    ``parameters`` cell with ``params``, then one code cell per entry of ``cells``); its path."""
    nb = nbformat.v4.new_notebook()
    nb.metadata["asoc"] = {
        "title": name,
        "figures": [],
        "tables": [],
        **({"depends": depends} if depends else {}),
    }
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    parameters = nbformat.v4.new_code_cell(params)
    parameters.metadata["tags"] = ["parameters"]
    nb.cells = [parameters] + [nbformat.v4.new_code_cell(c) for c in cells]
    path = book / f"{name}.ipynb"
    nbformat.write(nb, path)
    return path
