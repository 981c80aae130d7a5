"""The common base of every iterative algorithm's result: why it stopped, in a code and a sentence.

Like ``scipy.optimize.OptimizeResult``, each result carries ``converged`` (the library's own
criterion, a tolerance the computation can reach, never an optimiser's status string),
``status`` (a :class:`Status`, one of :data:`STATUS_CODES`) and ``message`` (one sentence).
Concrete results subclass :class:`IterativeResult` and add only the fields they fill.
"""

import enum
from dataclasses import dataclass

__all__ = ["Status", "STATUS_CODES", "IterativeResult"]


class Status(enum.StrEnum):
    """Why an iterative algorithm stopped.

    A ``str`` enum: a member equals, prints and serialises (json) as its code, so
    ``result.status == "converged"`` and records of the codes keep working; its repr is the
    code's too.

    Examples
    --------
    >>> Status("cycle") is Status.CYCLE, Status.CONVERGED == "converged", Status.CYCLE
    (True, True, 'cycle')
    >>> f"stopped: {Status.NO_PROGRESS}"
    'stopped: no_progress'
    """

    CONVERGED = "converged"
    MAX_ITERATIONS = "max_iterations"
    DIVERGED = "diverged"
    LINALG_ERROR = "linalg_error"
    INFEASIBLE = "infeasible"
    INACCURATE = "inaccurate"
    NO_PROGRESS = "no_progress"
    CYCLE = "cycle"

    def __repr__(self):
        return repr(self.value)


#: The reasons an iterative algorithm stops, and what each means.
STATUS_CODES = {
    Status.CONVERGED: "the stopping criterion was met within its tolerance",
    Status.MAX_ITERATIONS: "the iteration limit was reached before the stopping criterion",
    Status.DIVERGED: "an iterate or the cost became non-finite or grew without bound",
    Status.LINALG_ERROR: "a linear-algebra step failed (singular or indefinite matrix)",
    Status.INFEASIBLE: "the problem has no solution (e.g. infeasible LMIs)",
    Status.INACCURATE: "the solver stopped short of its accuracy and its answer could not be "
                       "verified",
    Status.NO_PROGRESS: "the iteration stopped making progress before the stopping criterion",
    Status.CYCLE: "the iterates repeat with a period of two or more iterations instead of "
                  "converging",
}


@dataclass(kw_only=True)
class IterativeResult:
    """Base of the result of an iterative algorithm: whether and why it stopped.

    Attributes
    ----------
    converged : bool
        True when the algorithm's own stopping criterion was met within its tolerance.
    status : Status
        Why it stopped, one of :data:`STATUS_CODES`; given as a :class:`Status` or its code.
    message : str
        One sentence saying why the algorithm stopped.

    Examples
    --------
    >>> r = IterativeResult(converged=False, status="max_iterations",
    ...                     message="stopped after 10 iterations, relative change 3e-2 > 1e-10")
    >>> r.status, r.status is Status.MAX_ITERATIONS, r.converged
    ('max_iterations', True, False)
    >>> IterativeResult(converged=True, status="done", message="")
    Traceback (most recent call last):
    ...
    ValueError: status: expected one of ['converged', 'cycle', 'diverged', 'inaccurate', \
'infeasible', 'linalg_error', 'max_iterations', 'no_progress'], found 'done'
    """

    converged: bool
    status: Status
    message: str

    def __post_init__(self):
        if self.status not in STATUS_CODES:
            raise ValueError(f"status: expected one of {sorted(STATUS_CODES)}, "
                             f"found {self.status!r}")
        self.status = Status(self.status)
        if self.converged != (self.status is Status.CONVERGED):
            raise ValueError(f"converged={self.converged} contradicts status={self.status!r}")
