"""Where the project's files live (src layout: this file is src/asoc_companion/paths.py)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BOOK = ROOT / "book"
FIGURES = ROOT / "figures"
REFERENCE = ROOT / "tests" / "reference" / "thesis_values"   # one <notebook>.yaml each
CI_OUTPUT = BOOK / "_build" / "ci"
