"""Atomic file writing: a failed run leaves the previous file in place (book/architecture.md)."""

import json
import os
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["atomic_write_bytes", "atomic_write_text", "to_jsonable", "atomic_write_json"]


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename.

    Examples
    --------
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = atomic_write_bytes(Path(folder) / "sub" / "a.bin", b"rho")
    ...     print(path.name, path.read_bytes(), sorted(p.name for p in path.parent.iterdir()))
    a.bin b'rho' ['a.bin']
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) atomically.

    Examples
    --------
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     print(atomic_write_text(Path(folder) / "a.txt", "rho = 0.25").read_text())
    rho = 0.25
    """
    return atomic_write_bytes(path, text.encode("utf-8"))


def to_jsonable(value):
    """Convert numpy scalars/arrays (also nested in dicts, lists, tuples) to JSON types.

    Examples
    --------
    >>> to_jsonable({"rho": np.float64(0.25), 1: np.arange(3), "ok": np.bool_(True), "t": (1,
    ...     None)})
    {'rho': 0.25, '1': [0, 1, 2], 'ok': True, 't': [1, None]}
    >>> to_jsonable({1, 2})
    Traceback (most recent call last):
    ...
    TypeError: value of type set cannot be recorded as JSON
    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    raise TypeError(f"value of type {type(value).__name__} cannot be recorded as JSON")


def atomic_write_json(path, obj) -> Path:
    """Write ``obj`` as indented, key-sorted JSON atomically.

    Examples
    --------
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     print(atomic_write_json(Path(folder) / "v.json", {"b": np.int64(2),
    ...     "a": [0.5]}).read_text(), end="")
    {
     "a": [
      0.5
     ],
     "b": 2
    }
    """
    text = json.dumps(to_jsonable(obj), indent=1, sort_keys=True, allow_nan=True)
    return atomic_write_text(path, text + "\n")
