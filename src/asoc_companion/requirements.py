"""Whether the companion's own dependencies (the ``companion`` extra) are installed.

``pip install asoc`` installs the library and puts the ``asoc-companion`` command on the
PATH; the command and ``import asoc_companion`` then say in one line what to install,
instead of failing on the first missing import. This module imports nothing beyond the
standard library, so it works in a library-only installation.
"""

from importlib.util import find_spec

__all__ = ["COMPANION_MODULES", "INSTALL_HINT", "missing_requirements"]


COMPANION_MODULES = ("yaml", "matplotlib", "nbformat", "papermill", "IPython")
"""Modules of the ``companion`` extra that the companion imports when it starts."""

INSTALL_HINT = "install the companion's dependencies: pip install 'asoc[companion]'"


def missing_requirements() -> list:
    """The modules of :data:`COMPANION_MODULES` that cannot be imported.

    Examples
    --------
    >>> missing_requirements()
    []
    """
    def absent(name):
        try:
            return find_spec(name) is None
        except (ImportError, ValueError):         # a parent package or a blocked module
            return True

    return [name for name in COMPANION_MODULES if absent(name)]
