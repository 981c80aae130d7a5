"""The recorder of one notebook run (book/architecture.md, "The flow of one number").

A notebook calls :func:`setup` once, right after its ``parameters`` cell; it creates a
:class:`Recorder` and makes it the *active* one (:func:`active`), which :func:`record`,
:func:`save_figure`, :func:`save_table`, :func:`asoc_companion.prose` and
:func:`asoc_companion.figure_caption` use (the notebook-facing calls stay one-liners, as
``matplotlib.pyplot`` keeps a current figure). Code outside a notebook creates a :class:`Recorder`
and calls its methods.

Values are written at once to ``<output_dir>/values/<notebook>.json`` (atomically). The
harness gives every run a staging folder as ``output_dir`` and moves the results into
place only when the run succeeds (:mod:`asoc_companion.notebooks`), so writing early never
touches committed files.
"""

import tempfile
from contextlib import contextmanager
from pathlib import Path

from . import figures, paths
from .atomic_files import atomic_write_json, to_jsonable
from .plan import FIDELITIES, values_file

__all__ = ["Recorder", "setup", "scratch_run", "active", "record", "save_figure", "save_table",
           "current_values"]


class Recorder:
    """Records the numbers of one notebook run and saves its figures and tables.

    Parameters
    ----------
    notebook : str
        Plain name such as "sec3_5".
    fidelity : {"full", "ci"}
    output_dir : path, optional
        Default ``figures/`` of the project.

    Raises
    ------
    ValueError
        If ``fidelity`` is unknown or ``notebook`` is not a plain name.

    Examples
    --------
    >>> import tempfile
    >>> from asoc_companion.values import load_values
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     recorder = Recorder("demo", "ci", folder)
    ...     print(recorder.record("rho", 0.25), recorder.qualified_values(), load_values("demo",
    ...     folder))
    0.25 {'demo.rho': 0.25} {'rho': 0.25}
    >>> Recorder("sec3.5")
    Traceback (most recent call last):
    ...
    ValueError: notebook must be a plain name such as 'sec3_5', found 'sec3.5'
    """

    def __init__(self, notebook: str, fidelity: str = "full", output_dir=None):
        if fidelity not in FIDELITIES:
            raise ValueError(f"fidelity must be one of {FIDELITIES}, found {fidelity!r}")
        if not isinstance(notebook, str) or not notebook or "/" in notebook or "." in notebook:
            raise ValueError(f"notebook must be a plain name such as 'sec3_5', found {notebook!r}")
        self.notebook, self.fidelity = notebook, fidelity
        self.output_dir = Path(output_dir) if output_dir else paths.project().figures
        self.values = {}

    def record(self, key: str, value):
        """Record ``value`` under ``key`` and return it unchanged.

        ``value`` may be a number, bool, string, list/array, or a dict of those (e.g. a
        Monte Carlo median with its bootstrap interval: ``{"median": m, "ci": [lo, hi], "n": N}``).

        Raises
        ------
        ValueError
            If ``key`` is empty or contains spaces.
        TypeError
            If ``value`` cannot be stored as JSON.
        """
        if not isinstance(key, str) or not key or " " in key:
            raise ValueError(f"key must be a non-empty string without spaces, found {key!r}")
        self.values[key] = to_jsonable(value)
        self.write()
        return value

    def write(self) -> Path:
        """Write the values recorded so far (atomically); return the file."""
        return atomic_write_json(values_file(self.output_dir, self.notebook),
                                 {"notebook": self.notebook, "fidelity": self.fidelity,
                                  "values": self.values})

    def save_figure(self, fig, number: str) -> Path:
        """:func:`asoc_companion.save_figure` into this run's folder."""
        return figures.save_figure(fig, number, self.output_dir)

    def save_table(self, number: str, header, rows) -> str:
        """:func:`asoc_companion.save_table` into this run's folder."""
        return figures.save_table(number, header, rows, self.output_dir)

    def qualified_values(self) -> dict:
        """The values recorded so far as ``{"<notebook>.<key>": value}``."""
        return {f"{self.notebook}.{k}": v for k, v in self.values.items()}


_active: Recorder | None = None


def setup(notebook: str, fidelity: str = "full", output_dir=None) -> Path:
    """Start recording for ``notebook``: a new active :class:`Recorder` (:func:`active`); applies
    the plotting style; returns the output folder.

    Parameters
    ----------
    notebook : str
        Plain name such as "sec3_5".
    fidelity : {"full", "ci"}
    output_dir : path, optional
        Default ``figures/``.

    Returns
    -------
    pathlib.Path
        The output folder (a notebook shows it; the recorder itself is :func:`active`).

    Raises
    ------
    ValueError
        If ``fidelity`` is unknown or ``notebook`` is not a plain name.

    Examples
    --------
    The examples of this module run inside ``scratch_run``, which restores the active recorder
    and the style afterwards:

    >>> with scratch_run() as folder:
    ...     out = setup("demo", "ci", folder)
    ...     print(out == folder, active().notebook, [p.name for p in (out / "values").iterdir()])
    True demo ['demo.json']
    """
    global _active
    recorder = Recorder(notebook, fidelity, output_dir)
    figures.apply_style()
    recorder.write()
    _active = recorder
    return recorder.output_dir


@contextmanager
def scratch_run(notebook: str = "demo", output_dir=None):
    """A throwaway run of ``notebook`` at ci fidelity: :func:`setup` into ``output_dir`` (default a
    temporary folder, removed after); yields the output folder. The recorder that was active before
    and the plotting style are restored after the block. For Examples and experiments outside a
    notebook.

    Examples
    --------
    >>> before = active(required=False)
    >>> with scratch_run() as out:
    ...     print(active().notebook, record("rho", 0.25),
    ...     [p.name for p in (out / "values").iterdir()])
    demo 0.25 ['demo.json']
    >>> active(required=False) is before
    True
    """
    import matplotlib

    global _active
    previous = _active
    try:
        with tempfile.TemporaryDirectory() as folder, matplotlib.rc_context():
            yield setup(notebook, "ci", output_dir or folder)
    finally:
        _active = previous


def active(required: bool = True) -> Recorder | None:
    """The running notebook's recorder (:func:`setup`); None if there is none and not ``required``.

    Raises
    ------
    RuntimeError
        If ``required`` and :func:`setup` has not been called.

    Examples
    --------
    >>> from unittest import mock
    >>> import asoc_companion.recorder as session
    >>> with mock.patch.object(session, "_active", None):
    ...     print(active(required=False))
    None
    >>> with mock.patch.object(session, "_active", None):
    ...     active()
    Traceback (most recent call last):
    ...
    RuntimeError: call asoc_companion.setup(notebook, fidelity, output_dir) first
    """
    if _active is None and required:
        raise RuntimeError("call asoc_companion.setup(notebook, fidelity, output_dir) first")
    return _active


def record(key: str, value):
    """Record ``value`` under ``key`` with the active recorder (:meth:`Recorder.record`); return it.

    Examples
    --------
    >>> from asoc_companion.values import load_values
    >>> with scratch_run() as folder:
    ...     print(record("rho", 0.25), load_values("demo", folder))
    0.25 {'rho': 0.25}
    """
    return active().record(key, value)


def save_figure(fig, number: str, output_dir=None) -> Path:
    """Save ``fig`` as ``fig<number>.png`` and ``.pdf`` in ``output_dir`` (default: the run's).

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> with scratch_run():
    ...     print(save_figure(Figure(), "own.1").name)
    fig_own_1.png
    """
    return figures.save_figure(fig, number, output_dir or active().output_dir)


def save_table(number: str, header, rows, output_dir=None) -> str:
    """Save a table as ``table<number>.csv`` and ``.md`` (default folder: the active run's);
    return the Markdown.

    Examples
    --------
    >>> with scratch_run():
    ...     print(save_table("own.1", ["k", "rho"], [[0, 0.25]]), end="")
    | k | rho |
    |---|---|
    | 0 | 0.25 |
    """
    return figures.save_table(number, header, rows, output_dir or active().output_dir)


def current_values() -> dict:
    """The committed values with the active run's values on top, ``{"<notebook>.<key>": value}``.

    Examples
    --------
    In a temporary checkout whose ``figures/values`` holds a committed ``sec0.a``, a run of
    ``demo`` in a staging folder adds its own values on top:

    >>> with paths.scratch_project() as root:
    ...     _ = Recorder("sec0", "full", root / "figures").record("a", 1)
    ...     with scratch_run(output_dir=root / "staging"):
    ...         _ = record("b", 2)
    ...         print(current_values())
    {'sec0.a': 1, 'demo.b': 2}
    """
    from .values import load_all_values

    values = load_all_values()
    if _active is not None:
        values.update(_active.qualified_values())
    return values
