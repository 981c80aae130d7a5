"""The values files ``<output_dir>/values/<notebook>.json``: where they are, reading them.

Writing happens through a :class:`asoc_companion.session.Recorder`. A values file that is not
valid JSON (a truncated write from an old version, a bad merge) is reported with its path and
the command that regenerates it (:class:`CorruptValuesError`), never as a bare
``JSONDecodeError``.
"""

import json
from pathlib import Path

from . import paths

FIDELITIES = ("full", "ci")
MANIFEST_NAME = "manifest.json"


class CorruptValuesError(ValueError):
    """A values file that cannot be read; the message names it and how to regenerate it."""


def values_path(notebook: str, output_dir=None) -> Path:
    """Path of the JSON file holding ``notebook``'s recorded values (default folder ``figures/``)."""
    return Path(output_dir or paths.project().figures) / "values" / f"{notebook}.json"


def regenerate_command(notebook: str, output_dir=None) -> str:
    """The command line that rewrites ``notebook``'s values in ``output_dir``."""
    command = f"python -m asoc_companion run {notebook}"
    try:
        ci = Path(output_dir).resolve() == paths.project().ci_output.resolve() if output_dir else False
    except RuntimeError:
        ci = False
    return command + (" --fidelity ci" if ci else "")


def _shown(path) -> str:
    """``path`` relative to the project root when it lies inside it."""
    try:
        return str(Path(path).resolve().relative_to(paths.project().root))
    except (RuntimeError, ValueError):
        return str(path)


def _repair_hint(path) -> str:
    """How to get a good values file back: the command that regenerates it (and, for a committed
    file, the git command that restores it)."""
    hint = f"regenerate it with `{regenerate_command(path.stem, path.parent.parent)}`"
    try:
        committed = path.resolve().parent == (paths.project().figures / "values").resolve()
    except RuntimeError:
        committed = False
    return hint + (f" or restore the committed one with `git checkout -- {_shown(path)}`" if committed else "")


def read_values_file(path) -> dict:
    """The parsed values file at ``path`` (``{"notebook", "fidelity", "values"}``).

    Raises
    ------
    CorruptValuesError
        If the file is not valid JSON or lacks ``values``; the message names the file and
        the command that regenerates it.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
        if not isinstance(data, dict) or not isinstance(data.get("values"), dict):
            raise ValueError("no 'values' object")
    except ValueError as err:      # json.JSONDecodeError is a ValueError
        raise CorruptValuesError(f"{_shown(path)}: corrupt values file ({err}); {_repair_hint(path)}") from None
    return data


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
    CorruptValuesError
        If the values file is not valid JSON (a ``ValueError`` naming the file).
    """
    path = values_path(notebook, output_dir)
    if not path.exists():
        return {}
    return read_values_file(path)["values"]


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
    CorruptValuesError
        If a values file is not valid JSON (a ``ValueError`` naming the file).
    """
    folder = Path(output_dir or paths.project().figures) / "values"
    out = {}
    for path in sorted(folder.glob("*.json")):
        if path.name == MANIFEST_NAME:
            continue
        data = read_values_file(path)
        for key, value in data["values"].items():
            out[f"{data.get('notebook', path.stem)}.{key}"] = value
    return out
