"""The library installs on its own (issue 14): a wheel built from this checkout goes into a
fresh virtual environment and runs Alg. 3.1 from a folder outside the checkout, and
``import asoc.mjls, asoc.belief, asoc.gp`` loads neither the book's tools nor the companion.

Offline, pip cannot fetch the dependencies, so the fresh environment gets them from the
project's environment through a ``.pth`` line appended *after* its own site-packages: the
dependencies (numpy, scipy, cvxpy, ...) resolve there, while ``asoc`` must resolve to the
wheel's copy in the fresh environment, which the test checks. (That folder also holds
matplotlib, papermill, nbformat and IPython, which makes the "loads none of them" check a
real one: they are importable, and must not be imported.)
"""

import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
FORBIDDEN = (
    "matplotlib",
    "papermill",
    "nbformat",
    "IPython",
    "sphinx",
    "asoc_companion",
    "yaml",
    "nbclient",
)

PROBE = textwrap.dedent("""
    import json, sys
    import asoc.mjls, asoc.belief, asoc.gp
    loaded = sorted({name.split('.')[0] for name in sys.modules} & set(sys.argv[1].split(',')))
    from asoc.mjls import static_output_feedback
    from asoc.mjls.examples import sec354_system
    result = static_output_feedback(sec354_system(1))
    print(json.dumps({"asoc": asoc.__file__, "numpy": __import__("numpy").__file__,
                      "loaded": loaded, "converged": bool(result.converged),
                      "L": result.L.tolist()}))
""")


def _clean_env():
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "ASOC_COMPANION_ROOT", "PYTHONHOME")
    }
    env["PIP_NO_INDEX"] = "1"
    return env


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A fresh venv with the wheel of this checkout installed; returns its python."""
    tmp = tmp_path_factory.mktemp("packaging")
    # build from a copy: no build/ or egg-info in the checkout
    source = tmp / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    shutil.copytree(
        ROOT / "src", source / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
    )
    dist = tmp / "dist"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "-q",
            "-w",
            str(dist),
            str(source),
        ],
        check=True,
        env=_clean_env(),
        timeout=300,
    )
    (wheel,) = dist.glob("asoc-*.whl")
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    python = venv / "bin" / "python"
    subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)],
        check=True,
        env=_clean_env(),
        timeout=300,
    )
    site = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    (Path(site) / "zz_project_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return python, Path(site), wheel


@pytest.mark.packaging
def test_wheel_declares_the_runtime_dependencies_and_both_packages(installed):
    import zipfile

    _, _, wheel = installed
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        metadata = archive.read(
            next(n for n in names if n.endswith(".dist-info/METADATA"))
        ).decode()
    requires = [
        line.split(":", 1)[1].strip()
        for line in metadata.splitlines()
        if line.startswith("Requires-Dist:")
    ]
    core = {
        r.split(">")[0].split("=")[0].split("<")[0].strip() for r in requires if "extra ==" not in r
    }
    assert {
        "numpy",
        "scipy",
        "cvxpy",
        "clarabel",
        "scs",
        "numdifftools",
        "tqdm",
        "threadpoolctl",
    } <= core
    assert not core & {"matplotlib", "papermill", "nbformat", "pyyaml", "jupyter-book"}, (
        "book tools are not runtime deps"
    )
    extras = {
        line.split(":", 1)[1].strip()
        for line in metadata.splitlines()
        if line.startswith("Provides-Extra:")
    }
    assert {"control", "companion", "test"} <= extras
    assert "asoc/mjls/static.py" in names and "asoc_companion/__main__.py" in names
    assert not [n for n in names if "bench" in n.split("/")[-1]], (
        "benchmarks belong to tests/benchmarks"
    )


@pytest.mark.packaging
def test_installed_wheel_runs_alg_3_1_outside_the_checkout(installed, tmp_path):
    python, site, _ = installed
    proc = subprocess.run(
        [str(python), "-c", PROBE, ",".join(FORBIDDEN)],
        cwd=tmp_path,
        env=_clean_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert Path(out["asoc"]).resolve().is_relative_to(site.resolve()), (
        f"asoc not from the wheel: {out['asoc']}"
    )
    assert not Path(out["asoc"]).resolve().is_relative_to(ROOT), "asoc imported from the checkout"
    assert out["loaded"] == [], f"importing the library loaded {out['loaded']}"
    from asoc.mjls import static_output_feedback
    from asoc.mjls.examples import sec354_system

    here = static_output_feedback(sec354_system(1))
    assert out["converged"] and np.allclose(out["L"], here.L, rtol=1e-9, atol=1e-12)


@pytest.mark.packaging
def test_building_the_wheel_prints_no_warning(tmp_path):
    """No deprecation warning from setuptools (a license table or classifier, a beta notice)."""
    source = tmp_path / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    shutil.copytree(
        ROOT / "src", source / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
    )
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "-v",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "-w",
            str(tmp_path / "dist"),
            str(source),
        ],
        capture_output=True,
        text=True,
        env=_clean_env(),
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    noise = [
        line.strip()
        for line in (proc.stdout + proc.stderr).splitlines()
        if re.search(r"Deprecat|BuildBackendWarning|SetuptoolsWarning|\bbeta\b", line)
    ]
    assert not noise, noise
