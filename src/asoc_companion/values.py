"""The values files ``<output_dir>/values/<notebook>.json``: where they are, reading them.

Writing happens through a :class:`asoc_companion.recorder.Recorder`. A values file that is not
valid JSON (a truncated write from an old version, a bad merge) is reported with its path and
the command that regenerates it (:class:`CorruptValuesError`), never as a bare
``JSONDecodeError``.
"""

import json
from pathlib import Path

from . import paths
from .plan import MANIFEST_NAME, output_folder, values_file, values_folder

__all__ = ["CorruptValuesError", "read_values_file", "load_values", "load_all_values"]


class CorruptValuesError(ValueError):
    """A values file that cannot be read; the message names it and how to regenerate it.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "values" / "demo.json"
    ...     path.parent.mkdir()
    ...     _ = path.write_text('{"values": ')
    ...     try:
    ...         read_values_file(path)
    ...     except CorruptValuesError as err:
    ...         print(isinstance(err, ValueError),
    ...     "regenerate it with `python -m asoc_companion run demo`" in str(err))
    True True
    """


def _values_path(notebook: str, output_dir=None) -> Path:
    """Path of the JSON file holding ``notebook``'s recorded values (default folder ``figures/``).

    Examples
    --------
    >>> _values_path("sec3_5", "/tmp/run").as_posix()
    '/tmp/run/values/sec3_5.json'
    """
    return values_file(output_dir or _committed(), notebook)


def _committed() -> Path:
    """The output folder of the committed full-fidelity run (``figures/``)."""
    return output_folder(paths.project(), "full")


def _regenerate_command(notebook: str, output_dir=None) -> str:
    """The command line that rewrites ``notebook``'s values in ``output_dir``.

    Examples
    --------
    >>> _regenerate_command("sec3_5", "/tmp/run")
    'python -m asoc_companion run sec3_5'

    The ci output folder of a checkout (here a temporary one) asks for ``--fidelity ci``:

    >>> with paths.scratch_project() as root:
    ...     print(_regenerate_command("sec3_5", root / "book" / "_build" / "ci"))
    python -m asoc_companion run sec3_5 --fidelity ci
    """
    command = f"python -m asoc_companion run {notebook}"
    try:
        ci_output = output_folder(paths.project(), "ci")
        ci = Path(output_dir).resolve() == ci_output.resolve() if output_dir else False
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
    file, the git command that restores it).
    """
    hint = f"regenerate it with `{_regenerate_command(path.stem, path.parent.parent)}`"
    try:
        committed = path.resolve().parent == values_folder(_committed()).resolve()
    except RuntimeError:
        committed = False
    restore = f" or restore the committed one with `git checkout -- {_shown(path)}`"
    return hint + (restore if committed else "")


def read_values_file(path) -> dict:
    """The parsed values file at ``path`` (``{"notebook", "fidelity", "values"}``).

    Raises
    ------
    CorruptValuesError
        If the file is not valid JSON or lacks ``values``; the message names the file and
        the command that regenerates it.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "demo.json"
    ...     _ = path.write_text('{"notebook": "demo", "fidelity": "ci", "values": {"rho": 0.25}}')
    ...     print(read_values_file(path))
    {'notebook': 'demo', 'fidelity': 'ci', 'values': {'rho': 0.25}}
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
        if not isinstance(data, dict) or not isinstance(data.get("values"), dict):
            raise ValueError("no 'values' object")
    except ValueError as err:      # json.JSONDecodeError is a ValueError
        raise CorruptValuesError(f"{_shown(path)}: corrupt values file ({err}); "
                                 f"{_repair_hint(path)}") from None
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

    Examples
    --------
    >>> import tempfile
    >>> from asoc_companion.recorder import Recorder
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = Recorder("demo", "ci", folder).record("rho", 0.25)
    ...     print(load_values("demo", folder), load_values("not_run", folder))
    {'rho': 0.25} {}
    """
    path = _values_path(notebook, output_dir)
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

    Examples
    --------
    >>> import tempfile
    >>> from asoc_companion.recorder import Recorder
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = Recorder("sec0", "ci", folder).record("a", 1)
    ...     _ = Recorder("sec1", "ci", folder).record("b", [0.5, 0.75])
    ...     print(load_all_values(folder))
    {'sec0.a': 1, 'sec1.b': [0.5, 0.75]}
    """
    folder = values_folder(output_dir or _committed())
    out = {}
    for path in sorted(folder.glob("*.json")):
        if path.name == MANIFEST_NAME:
            continue
        data = read_values_file(path)
        for key, value in data["values"].items():
            out[f"{data.get('notebook', path.stem)}.{key}"] = value
    return out
