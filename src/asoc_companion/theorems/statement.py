"""The vocabulary of the theorems study: a numbered statement, its check, one instance's outcome.

A *statement* of the thesis (``Statement``) is checked on random instances: its ``check``
takes a seeded ``numpy.random.Generator`` (one per instance, from ``SeedSequence.spawn``),
draws an instance, and returns an ``Outcome``: ``"holds"``, ``"fails"`` or
``"not_applicable"`` (the premise is false for this instance), with the numbers that decide
it. A statement with no checkable content has ``check=None`` and says why in ``not_checkable``.

Every check can fail: called as ``check(rng, mutant=True)`` it runs the same comparison
against a planted false variant of the claim or of the computation it tests (a dropped term,
a flipped inequality, a factor changed), described in ``mutant``; the study records how often
the check catches it.
"""

from dataclasses import dataclass, field
from typing import Callable

__all__ = ["VERDICTS", "Outcome", "Statement"]


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
    summary        a short statement in words, math in MathJax ``$...$``
    checked        what one instance checks, and against what independent computation
    check          ``check(rng, mutant=False) -> Outcome``; ``None`` when there is nothing to check
    mutant         the planted false variant that ``check(rng, mutant=True)`` tests
    not_checkable  why there is nothing to check (when ``check`` is ``None``)
    expensive      one instance costs more than a second (the study then runs >= 100, not >= 1000)
    summarise      ``summarise(outcomes) -> dict``, recorded next to the counts (optional)
    why_not        why the mutant cannot be caught in at least half of its draws (recorded with it)
    """

    key: str
    label: str
    summary: str
    checked: str
    check: Callable[..., Outcome] | None = None
    mutant: str = ""
    not_checkable: str = ""
    expensive: bool = False
    summarise: Callable[[list], dict] | None = None
    why_not: str = ""

    def __post_init__(self):
        if (self.check is None) == (not self.not_checkable):
            raise ValueError(f"{self.key}: give either a check or the reason it is not checkable")
        if (self.check is None) != (not self.mutant):
            raise ValueError(f"{self.key}: a check needs the description of its mutant (and only a "
                             "check has one)")
