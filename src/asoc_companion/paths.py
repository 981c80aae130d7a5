"""Where the project's files live, found by configuration, not by the package's location.

The project root is, in this order:

1. the folder in the environment variable ``ASOC_COMPANION_ROOT`` (the command line's
   ``--root`` sets it, so notebook kernels started by the harness inherit it);
2. the nearest folder, from the current directory upwards, that holds ``book/_toc.yml``
   and ``figures/`` (the checkout you work in; notebooks run with ``book/`` as their
   current directory).

The reference data (``tests/reference/``) is read from the root found, never from the
installed package. ``ROOT``, ``BOOK``, ``FIGURES``, ``REFERENCE``, ``CI_OUTPUT`` and ``RUNS``
are looked up on first access (``from asoc_companion.paths import BOOK`` works), so
importing the package outside a checkout does not fail; using a path there does, with a
message saying how to point at a checkout.
"""

import os
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from unittest import mock

__all__ = ["ENV_VAR", "MARKERS", "Project", "project", "scratch_project"]


ENV_VAR = "ASOC_COMPANION_ROOT"
MARKERS = (Path("book") / "_toc.yml", Path("figures"))


@dataclass(frozen=True)
class Project:
    """The folders of one checkout of the companion.

    Examples
    --------
    >>> p = Project(Path("/checkout"))
    >>> p.book.as_posix(), p.reference.as_posix(), p.staging.as_posix()
    ('/checkout/book', '/checkout/tests/reference/thesis_values', '/checkout/book/_build/staging')
    """

    root: Path

    @property
    def book(self) -> Path:
        """``book``: the notebooks and pages of the Jupyter Book."""
        return self.root / "book"

    @property
    def figures(self) -> Path:
        """``figures``: the committed figures and ``values/*.json``."""
        return self.root / "figures"

    @property
    def reference(self) -> Path:
        """``tests/reference/thesis_values``: one ``<notebook>.yaml`` each."""
        return self.root / "tests" / "reference" / "thesis_values"

    @property
    def src(self) -> Path:
        """``src``: the library and the companion's tooling."""
        return self.root / "src"

    @property
    def environment(self) -> Path:
        """``environment.txt``: the pinned environment of the runs."""
        return self.root / "environment.txt"

    @property
    def ci_output(self) -> Path:
        """``book/_build/ci``: where ``--fidelity ci`` runs write."""
        return self.book / "_build" / "ci"

    @property
    def runs(self) -> Path:
        """``book/_build/runs``: runs with overridden parameters."""
        return self.book / "_build" / "runs"

    @property
    def staging(self) -> Path:
        """Where runs execute before their results move into place (crash safety)."""
        return self.book / "_build" / "staging"


def _is_project(folder) -> bool:
    """Whether ``folder`` holds ``book/_toc.yml`` and ``figures/``.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     before = _is_project(folder)
    ...     (Path(folder) / "book").mkdir(); (Path(folder) / "book" / "_toc.yml").touch()
    ...     (Path(folder) / "figures").mkdir()
    ...     print(before, _is_project(folder))
    False True
    """
    return all((Path(folder) / marker).exists() for marker in MARKERS)


def _find_root(start=None) -> Path:
    """The project root: ``$ASOC_COMPANION_ROOT``, else the nearest project folder above ``start``.

    Parameters
    ----------
    start : path, optional
        Where the upward search begins; default the current directory.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    RuntimeError
        If the variable names a folder that is not a project, or no project is found.

    Examples
    --------
    A checkout's root is found from a folder inside it (here with ``$ASOC_COMPANION_ROOT`` unset):

    >>> import tempfile
    >>> from unittest import mock
    >>> with tempfile.TemporaryDirectory() as folder, mock.patch.dict(os.environ, {ENV_VAR: ""}):
    ...     root = Path(folder).resolve()
    ...     (root / "book").mkdir(); (root / "book" / "_toc.yml").touch()
    ...     (root / "figures").mkdir()
    ...     print(_find_root(root / "book") == root)
    True
    >>> with mock.patch.dict(os.environ, {ENV_VAR: "/"}):
    ...     _find_root()
    Traceback (most recent call last):
    ...
    RuntimeError: ASOC_COMPANION_ROOT='/' is not a checkout of the companion (expected
    book/_toc.yml and figures/ in it)
    """
    configured = os.environ.get(ENV_VAR)
    if configured:
        root = Path(configured).expanduser().resolve()
        if not _is_project(root):
            raise RuntimeError(f"{ENV_VAR}={configured!r} is not a checkout of the companion "
                               f"(expected book/_toc.yml and figures/ in it)")
        return root
    here = Path(start or Path.cwd()).resolve()
    for folder in (here, *here.parents):
        if _is_project(folder):
            return folder
    raise RuntimeError(f"no checkout of the companion found above {here} (a folder with "
                       "book/_toc.yml and figures/): run from inside one, pass --root, or set "
                       f"{ENV_VAR}")


def project(root=None) -> Project:
    """The :class:`Project` at ``root`` (default ``_find_root``).

    Examples
    --------
    >>> project("/checkout").figures.as_posix()
    '/checkout/figures'
    """
    return Project(Path(root).resolve() if root is not None else _find_root())


@contextmanager
def scratch_project():
    """An empty project in a temporary folder (``book/_toc.yml``, ``figures/``, the reference
    folder), made the project for the block through ``ASOC_COMPANION_ROOT``; yields its root,
    removes it after.

    For Examples and experiments that write into a project without touching the checkout.

    Examples
    --------
    >>> with scratch_project() as root:
    ...     print(project().root == root, project().reference.relative_to(root).as_posix())
    True tests/reference/thesis_values
    >>> root.exists()
    False
    """
    with tempfile.TemporaryDirectory() as folder, mock.patch.dict(os.environ, {ENV_VAR: folder}):
        root = Path(folder).resolve()
        (root / "book").mkdir()
        (root / "book" / "_toc.yml").write_text("")
        for sub in ("figures", project(root).reference.relative_to(root)):
            (root / sub).mkdir(parents=True)
        yield root


_NAMES = {"ROOT": "root", "BOOK": "book", "FIGURES": "figures", "REFERENCE": "reference",
          "CI_OUTPUT": "ci_output", "RUNS": "runs", "SRC": "src"}


def __getattr__(name):
    if name in _NAMES:
        return getattr(project(), _NAMES[name])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
