"""One build plan per notebook run: every path of the run, derived once.

A :class:`RunPlan` is made by :func:`make_plan` from the project, the notebook, the fidelity and
the parameter overrides, and passed along: :mod:`asoc_companion.notebooks` runs it,
:mod:`asoc_companion.manifest` hashes and records it, :mod:`asoc_companion.build` schedules it.
No other module joins ``values/<name>.json``, ``values/manifest.json``, ``book/_build/ci`` or
``book/_build/runs/<name>-<hash>``: the functions below are the only place these paths are
built (``tests/companion/test_plan.py`` scans the package for joins elsewhere).

Where a run writes:

- ``full`` at the default parameters: ``figures/`` (the executed notebook replaces the
  notebook in ``book/``, which the book renders);
- ``ci`` at the default parameters: ``book/_build/ci/``;
- any run with parameter overrides: ``book/_build/runs/<notebook>-<hash>/``, the hash of
  the fidelity and the overrides.
"""

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["FIDELITIES", "MANIFEST_NAME", "values_folder", "values_file", "manifest_file",
           "output_folder", "RunPlan", "make_plan"]


FIDELITIES = ("full", "ci")
MANIFEST_NAME = "manifest.json"


def values_folder(output_dir) -> Path:
    """``<output_dir>/values``: the values files of the runs into ``output_dir`` and their manifest.

    Examples
    --------
    >>> values_folder("/tmp/run").as_posix()
    '/tmp/run/values'
    """
    return Path(output_dir) / "values"


def values_file(output_dir, notebook: str) -> Path:
    """``<output_dir>/values/<notebook>.json``: the values ``notebook`` recorded in ``output_dir``.

    Examples
    --------
    >>> values_file("/tmp/run", "sec3_5").as_posix()
    '/tmp/run/values/sec3_5.json'
    """
    return values_folder(output_dir) / f"{notebook}.json"


def manifest_file(output_dir) -> Path:
    """``<output_dir>/values/manifest.json``: the input hashes of the runs into ``output_dir``.

    Examples
    --------
    >>> manifest_file("/tmp/run").as_posix()
    '/tmp/run/values/manifest.json'
    """
    return values_folder(output_dir) / MANIFEST_NAME


def output_folder(project, fidelity: str, name: str = "", parameters=None) -> Path:
    """Where a run of notebook ``name`` at ``fidelity`` with ``parameters`` (overrides) writes.

    ``figures/`` at full fidelity, ``book/_build/ci/`` at ci fidelity, and
    ``book/_build/runs/<name>-<hash of fidelity and overrides>`` with overrides.

    Raises
    ------
    ValueError
        If ``fidelity`` is not one of :data:`FIDELITIES`.

    Examples
    --------
    >>> from asoc_companion.paths import Project
    >>> project = Project(Path("/checkout"))
    >>> [output_folder(project, f).as_posix() for f in FIDELITIES]
    ['/checkout/figures', '/checkout/book/_build/ci']
    >>> output_folder(project, "ci", "sec3_2", {"steps": 10}).as_posix()
    '/checkout/book/_build/runs/sec3_2-6bc049f579'
    """
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, found {fidelity!r}")
    if parameters:
        key = json.dumps({"fidelity": fidelity, **parameters}, sort_keys=True).encode()
        return project.runs / f"{name}-{hashlib.sha256(key).hexdigest()[:10]}"
    return project.figures if fidelity == "full" else project.ci_output


@dataclass(frozen=True)
class RunPlan:
    """One notebook run and every path derived from it (made by :func:`make_plan`).

    Attributes
    ----------
    notebook : NotebookInfo
        The notebook (its name and source file).
    fidelity : {"full", "ci"}
    parameters : dict
        The overrides of the ``parameters`` cell (``{}``: the defaults).
    output_dir : pathlib.Path
        Where the figures, tables and values go (:func:`output_folder`).
    executed : pathlib.Path
        The executed notebook: the source itself for a default full run, else
        ``<output_dir>/notebooks/<notebook>.ipynb``.
    values : pathlib.Path
        ``<output_dir>/values/<notebook>.json``.
    figures, tables : pathlib.Path
        The folders the figures and tables are saved into (the output folder).
    manifest : pathlib.Path
        ``<output_dir>/values/manifest.json``.
    staging : pathlib.Path
        The folder the run's staging folder is made in (``book/_build/staging``).
    injected : dict
        The parameters papermill injects: fidelity, ``output_dir`` relative to the
        notebook's folder (no machine paths in committed notebooks), overrides.
    """

    notebook: object
    fidelity: str
    parameters: dict
    output_dir: Path
    executed: Path
    values: Path
    figures: Path
    tables: Path
    manifest: Path
    staging: Path
    injected: dict

    @property
    def name(self) -> str:
        """The notebook's name (its file name without ``.ipynb``)."""
        return self.notebook.name

    def values_of(self, notebook: str) -> Path:
        """The values file of another ``notebook`` in this run's output folder (a dependency)."""
        return values_file(self.output_dir, notebook)

    def staged(self, stage) -> tuple:
        """``(executed notebook, injected parameters)`` of the run executing into ``stage``."""
        staged = Path(stage) / "notebooks" / self.notebook.path.name
        return staged, _injected(self.notebook, self.fidelity, stage, self.parameters)


def _injected(notebook, fidelity, output_dir, parameters) -> dict:
    out = os.path.relpath(Path(output_dir).resolve(), notebook.path.parent.resolve())
    return {"fidelity": fidelity, "output_dir": out, **parameters}


def make_plan(project, notebook, fidelity: str, parameters=None, output_dir=None) -> RunPlan:
    """The :class:`RunPlan` of a run of ``notebook`` (a NotebookInfo) at ``fidelity`` with
    ``parameters`` (overrides, already checked) in ``project``.

    ``output_dir`` replaces the folder :func:`output_folder` gives (a test's scratch folder);
    every other path still follows from it.

    Raises
    ------
    ValueError
        If ``fidelity`` is not one of :data:`FIDELITIES`.

    Examples
    --------
    >>> from asoc_companion.paths import Project
    >>> from asoc_companion.notebooks import NotebookInfo
    >>> project = Project(Path("/checkout"))
    >>> info = NotebookInfo("sec3_2", project.book / "sec3_2.ipynb", "Sec. 3.2", (), ())
    >>> plan = make_plan(project, info, "full")
    >>> plan.executed == info.path, plan.values.as_posix(), plan.injected
    (True, '/checkout/figures/values/sec3_2.json', {'fidelity': 'full', 'output_dir': '../figures'})
    >>> make_plan(project, info, "ci", {"steps": 10}).executed.as_posix()
    '/checkout/book/_build/runs/sec3_2-6bc049f579/notebooks/sec3_2.ipynb'
    """
    parameters = dict(parameters or {})
    if output_dir is None:
        output_dir = output_folder(project, fidelity, notebook.name, parameters)
    out = Path(output_dir).resolve()
    in_place = fidelity == "full" and not parameters and out == project.figures.resolve()
    executed = notebook.path if in_place else out / "notebooks" / notebook.path.name
    return RunPlan(notebook=notebook, fidelity=fidelity, parameters=parameters, output_dir=out,
                   executed=executed, values=values_file(out, notebook.name), figures=out,
                   tables=out, manifest=manifest_file(out), staging=project.staging,
                   injected=_injected(notebook, fidelity, out, parameters))
