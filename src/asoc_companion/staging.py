"""Crash-safe execution of a notebook run (book/architecture.md, "The manifest and crash safety"): a
run executes into a staging folder; :func:`commit` moves its files into place with SIGINT and
SIGTERM held off, and :func:`remove_stage` removes the folder whatever happened;
:func:`one_blas_thread` gives every kernel one BLAS thread, so one machine gives one set of numbers.
"""

import errno
import os
import shutil
import signal
import time
from contextlib import contextmanager
from pathlib import Path

from .atomic_files import atomic_write_bytes

__all__ = ["THREAD_VARIABLES", "remove_stage", "one_blas_thread", "commit"]


#: Every kernel computes with one BLAS/OpenMP thread, whoever starts it (``make book``, which runs
#: notebooks side by side, or ``run``/``figure`` alone): a multi-threaded BLAS sums in another
#: order,
#: and an iterative fit that stops unconverged (Sec. 2.6's OMAT GPs) ends elsewhere.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "NUMEXPR_NUM_THREADS")


def remove_stage(stage: Path, attempts: int = 5):
    """Remove a run's staging folder, with SIGINT and SIGTERM held off until it is gone.

    An interrupt that arrives while the folder is being removed would otherwise stop the
    removal half-way; a kernel that is still shutting down may write one last file into the
    folder after it was emptied, so the removal is repeated until the folder is gone.

    Examples
    --------
    >>> import tempfile
    >>> stage = Path(tempfile.mkdtemp()) / "sec3_2-x"
    >>> (stage / "values").mkdir(parents=True)
    >>> _ = (stage / "values" / "sec3_2.json").write_text("{}")
    >>> remove_stage(stage)
    >>> stage.exists()
    False
    """
    with _signals_held():
        for _ in range(attempts):
            shutil.rmtree(stage, ignore_errors=True)
            if not stage.exists():
                return
            time.sleep(0.1)


@contextmanager
def one_blas_thread():
    """Set :data:`THREAD_VARIABLES` to 1 for the kernels started inside; restore them after.

    Examples
    --------
    >>> before = os.environ.get("OPENBLAS_NUM_THREADS")
    >>> with one_blas_thread():
    ...     os.environ["OPENBLAS_NUM_THREADS"]
    '1'
    >>> os.environ.get("OPENBLAS_NUM_THREADS") == before
    True
    """
    saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextmanager
def _signals_held():
    """Hold off SIGINT and SIGTERM (delivered on exit) while files move into place.

    Examples
    --------
    >>> with _signals_held():
    ...     held = signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    >>> held, signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    (True, False)
    """
    held = {signal.SIGINT, signal.SIGTERM}
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    except (AttributeError, ValueError, OSError):       # no POSIX signal masks here
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _move(source: Path, target: Path):
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.replace(source, target)
    except OSError as err:
        if err.errno != errno.EXDEV:
            raise
        # another file system: copy, then rename
        atomic_write_bytes(target, source.read_bytes())


def commit(stage: Path, output_dir: Path, staged_notebook: Path, target_notebook: Path):
    """Move a finished run's files from ``stage`` into ``output_dir``: figures and tables, then
    values, then the executed notebook (the caller writes the manifest entry last).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as stage, tempfile.TemporaryDirectory() as out:
    ...     _ = [atomic_write_bytes(Path(stage) / name, b"{}") for name in ("a.png",
    ...     "values/a.json",
    ...     "notebooks/a.ipynb")]
    ...     commit(Path(stage), Path(out), Path(stage) / "notebooks" / "a.ipynb",
    ...     Path(out) / "a.ipynb")
    ...     print(sorted(p.relative_to(out).as_posix() for p in Path(out).rglob("*.*")),
    ...     list(Path(stage).rglob("*.*")))
    ['a.ipynb', 'a.png', 'values/a.json'] []
    """
    files = [p for p in stage.rglob("*") if p.is_file() and p != staged_notebook
             and not p.name.endswith(".tmp")]
    files.sort(key=lambda p: (p.parent.name == "values", str(p)))
    with _signals_held():
        for source in files:
            _move(source, Path(output_dir) / source.relative_to(stage))
        _move(staged_notebook, Path(target_notebook))
