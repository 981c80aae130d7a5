"""Recording the numbers a notebook computes (DESIGN.md, "The flow of one number").

A notebook calls :func:`setup` once, right after its ``parameters`` cell, then
:func:`record` for every number the thesis prints. Values are written at once to
``<output_dir>/values/<notebook>.json`` (atomically), so a crashed run keeps what it had.
"""

import json
from dataclasses import dataclass, field
from pathlib import Path

from .io import atomic_write_json, to_jsonable
from .paths import FIGURES

FIDELITIES = ("full", "ci")


@dataclass
class _Session:
    notebook: str | None = None
    fidelity: str = "full"
    output_dir: Path = FIGURES
    values: dict = field(default_factory=dict)


_session = _Session()


def setup(notebook: str, fidelity: str = "full", output_dir=None) -> Path:
    """Start recording for ``notebook`` at ``fidelity`` into ``output_dir`` (default figures/).

    Also applies the project's plotting style.

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
        The output folder.

    Raises
    ------
    ValueError
        If ``fidelity`` is unknown or ``notebook`` is not a plain name.
    """
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, found {fidelity!r}")
    if not notebook or "/" in notebook or "." in notebook:
        raise ValueError(f"notebook must be a plain name such as 'sec3_5', found {notebook!r}")
    from .figures import apply_style

    out = Path(output_dir) if output_dir else FIGURES
    _session.notebook, _session.fidelity, _session.output_dir = notebook, fidelity, out
    _session.values = {}
    apply_style()
    _write()
    return out


def current_output_dir() -> Path:
    """The folder figures and tables of the current notebook are saved to."""
    return _session.output_dir


def record(key: str, value):
    """Record ``value`` under ``key`` for the current notebook and return it unchanged.

    ``value`` may be a number, bool, string, list/array, or a dict of those (e.g. a Monte
    Carlo median with its bootstrap interval: ``{"median": m, "ci": [lo, hi], "n": N}``).

    Parameters
    ----------
    key : str
        Non-empty, without spaces.
    value : object

    Returns
    -------
    object
        ``value``.

    Raises
    ------
    RuntimeError
        If :func:`setup` has not been called.
    ValueError
        If ``key`` is empty or contains spaces.
    """
    if _session.notebook is None:
        raise RuntimeError("call asoc_companion.setup(notebook, fidelity, output_dir) before record()")
    if not isinstance(key, str) or not key or " " in key:
        raise ValueError(f"key must be a non-empty string without spaces, found {key!r}")
    _session.values[key] = to_jsonable(value)
    _write()
    return value


def _write():
    path = values_path(_session.notebook, _session.output_dir)
    atomic_write_json(path, {"notebook": _session.notebook, "fidelity": _session.fidelity,
                             "values": _session.values})


def values_path(notebook: str, output_dir=None) -> Path:
    """Path of the JSON file holding ``notebook``'s recorded values."""
    return Path(output_dir or FIGURES) / "values" / f"{notebook}.json"


def load_values(notebook: str, output_dir=None) -> dict:
    """The recorded values of ``notebook`` (``{}`` if it has not been run).

    Parameters
    ----------
    notebook : str
    output_dir : path, optional
        Default ``figures/``.

    Returns
    -------
    dict

    Raises
    ------
    json.JSONDecodeError
        If the values file is not valid JSON.
    """
    path = values_path(notebook, output_dir)
    if not path.exists():
        return {}
    return json.loads(path.read_text())["values"]


def load_all_values(output_dir=None) -> dict:
    """All recorded values as ``{"<notebook>.<key>": value}`` (the build manifest is skipped).

    Parameters
    ----------
    output_dir : path, optional
        Default ``figures/``.

    Returns
    -------
    dict

    Raises
    ------
    json.JSONDecodeError
        If a values file is not valid JSON.
    """
    folder = Path(output_dir or FIGURES) / "values"
    out = {}
    for path in sorted(folder.glob("*.json")):
        if path.name == "manifest.json":
            continue
        data = json.loads(path.read_text())
        for key, value in data["values"].items():
            out[f"{data['notebook']}.{key}"] = value
    return out
