"""The vocabulary of the theorems study: a numbered statement, its check, one instance's outcome.

A *statement* of the thesis (``Statement``) is checked on random instances: its ``check``
takes a seeded ``numpy.random.Generator`` (one per instance, from ``SeedSequence.spawn``),
draws an instance, and returns an ``Outcome``: ``"holds"``, ``"fails"`` or
``"not_applicable"`` (the premise is false for this instance), with the numbers that decide
it. A statement with no checkable content has ``check=None`` and says why in ``not_checkable``.
"""

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

VERDICTS = ("holds", "fails", "not_applicable")


@dataclass(frozen=True)
class Outcome:
    """One instance's verdict and the numbers that decide it (plain floats, ints or strings)."""

    verdict: str
    numbers: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict: expected one of {VERDICTS}, found {self.verdict!r}")


@dataclass(frozen=True)
class Statement:
    """A numbered statement of the thesis and how it is checked.

    key            ``statement_<chapter>_<number>``, e.g. ``statement_3_19`` (the record key)
    label          as the thesis names it, e.g. ``"Theorem 3.19"``
    summary        a short statement in words
    checked        what one instance checks, and against what independent computation
    check          ``check(rng) -> Outcome``; ``None`` when there is nothing to check
    not_checkable  why there is nothing to check (when ``check`` is ``None``)
    expensive      one instance costs more than a second (the study then runs >= 100, not >= 1000)
    """

    key: str
    label: str
    summary: str
    checked: str
    check: Callable[[np.random.Generator], Outcome] | None = None
    not_checkable: str = ""
    expensive: bool = False

    def __post_init__(self):
        if (self.check is None) == (not self.not_checkable):
            raise ValueError(f"{self.key}: give either a check or the reason it is not checkable")
