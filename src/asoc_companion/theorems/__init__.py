"""The theorems study: every numbered statement of Chapters 2-3, checked on random instances."""

from .chapter2 import STATEMENTS as CHAPTER_2
from .chapter3 import STATEMENTS as CHAPTER_3
from .statement import VERDICTS, Outcome, Statement

STATEMENTS = [*CHAPTER_2, *CHAPTER_3]

__all__ = ["STATEMENTS", "Outcome", "Statement", "VERDICTS"]
