"""Prepare the book for an offline build: serve MathJax 3 from the book's own _static.

The stock Sphinx configuration loads MathJax from a CDN, which a machine without
network cannot reach; the HTML would then show raw TeX. The package
``django-static-mathjax`` ships MathJax 3's ``es5`` build, which is copied to
``book/_static/mathjax`` (ignored by git) and referenced in ``book/_config.yml``.
"""

import shutil
import sys
from importlib.util import find_spec
from pathlib import Path

from . import paths


def install_mathjax(book=None) -> Path:
    """Copy MathJax's es5 folder into ``book/_static/mathjax``; return the target."""
    spec = find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("MathJax not installed: pip install -r environment.txt")
    source = Path(list(spec.submodule_search_locations)[0]) / "static" / "mathjax" / "es5"
    target = Path(book or paths.project().book) / "_static" / "mathjax"
    if not (target / "tex-chtml.js").exists():
        shutil.copytree(source, target, dirs_exist_ok=True)
    return target


if __name__ == "__main__":
    print(f"MathJax ready in {install_mathjax()}")
    sys.exit(0)
