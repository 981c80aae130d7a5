"""The values a setting of :mod:`asoc.config` accepts: a type and an interval, checked when set.

Examples
--------
>>> REAL(0, 1).check("mjls.rank_rtol", 1e-8)
>>> REAL(0, 1, optional=True).check("mjls.rank_rtol", None)
>>> INT(0).check("mjls.dense_max_radius", -1)
Traceback (most recent call last):
    ...
ValueError: mjls.dense_max_radius: expected an integer >= 0, found -1
"""

import math
import numbers

__all__ = ["Allowed", "REAL", "INT", "SIZES", "REALS"]


class Allowed:
    """The values one tunable accepts: a type and an interval, checked when the value is set."""

    def __init__(self, kind, low, high=math.inf, item=None, optional=False):
        self.kind, self.low, self.high, self.item, self.optional = kind, low, high, item, optional

    def check(self, key, value):
        """Raise TypeError or ValueError naming ``key`` unless ``value`` is allowed."""
        if value is None and self.optional:
            return
        if self.kind is tuple:
            if not isinstance(value, tuple) or not value:
                raise TypeError(f"{key}: expected {self}, found {type(value).__name__} {value!r}")
            for item in value:
                self.item.check(key, item)
            return
        real = isinstance(value, numbers.Real) and not isinstance(value, bool)
        if not real or (self.kind is int and not isinstance(value, numbers.Integral)):
            raise TypeError(f"{key}: expected {self}, found {type(value).__name__} {value!r}")
        inside = (
            self.low <= value <= self.high
            if self.kind is int
            else self.low < value <= self.high
            if self.kind == "closed"
            else self.low < value < self.high
        )
        if not inside:
            raise ValueError(f"{key}: expected {self}, found {value!r}")

    def __str__(self):
        if self.kind is tuple:
            return f"a non-empty tuple, each {self.item}"
        if self.kind is int:
            return f"an integer >= {self.low}"
        bracket = "]" if self.kind == "closed" else ")"
        text = f"a real number in ({self.low:g}, {self.high:g}{bracket}"
        return text + " or None" if self.optional else text


def REAL(low, high, closed=False, optional=False):  # noqa: N802 (reads as a type in the table)
    """A real number in the open interval (low, high), or (low, high] when ``closed``; also None
    when ``optional`` (a setting whose None means the solver's own default).
    """
    return Allowed("closed" if closed else float, low, high, optional=optional)


def INT(low):  # noqa: N802
    """An integer >= low."""
    return Allowed(int, low)


def SIZES(low):  # noqa: N802
    """A non-empty tuple of integers >= low."""
    return Allowed(tuple, low, item=INT(low))


def REALS(low, high, closed=False):  # noqa: N802
    """A non-empty tuple of real numbers, each as :func:`REAL` ``(low, high, closed)``."""
    return Allowed(tuple, low, high, item=REAL(low, high, closed))
