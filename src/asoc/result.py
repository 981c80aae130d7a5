"""The common base of every iterative algorithm's result: why it stopped, in a code and a sentence.

Like ``scipy.optimize.OptimizeResult``, each result carries ``converged`` (the library's own
criterion, a tolerance the computation can reach, never an optimiser's status string),
``status`` (a short code from :data:`STATUS_CODES`) and ``message`` (one sentence). Concrete
results subclass :class:`IterativeResult` and add only the fields they fill.
"""

from dataclasses import dataclass

__all__ = ["STATUS_CODES", "IterativeResult"]


#: The reasons an iterative algorithm stops, and what each means.
STATUS_CODES = {
    "converged": "the stopping criterion was met within its tolerance",
    "max_iterations": "the iteration limit was reached before the stopping criterion",
    "diverged": "an iterate or the cost became non-finite or grew without bound",
    "linalg_error": "a linear-algebra step failed (singular or indefinite matrix)",
    "infeasible": "the problem has no solution (e.g. infeasible LMIs)",
    "inaccurate": "the solver stopped short of its accuracy and its answer could not be verified",
    "no_progress": "the iteration stopped making progress before the stopping criterion",
    "cycle": "the iterates repeat with a period of two or more iterations instead of converging",
}


@dataclass(kw_only=True)
class IterativeResult:
    """Base of the result of an iterative algorithm: whether and why it stopped.

    Attributes
    ----------
    converged : bool
        True when the algorithm's own stopping criterion was met within its tolerance.
    status : str
        A short code, one of :data:`STATUS_CODES`.
    message : str
        One sentence saying why the algorithm stopped.

    Examples
    --------
    >>> r = IterativeResult(converged=False, status="max_iterations",
    ...                     message="stopped after 10 iterations, relative change 3e-2 > 1e-10")
    >>> r.status, r.converged
    ('max_iterations', False)
    """

    converged: bool
    status: str
    message: str

    def __post_init__(self):
        if self.status not in STATUS_CODES:
            raise ValueError(f"status: expected one of {sorted(STATUS_CODES)}, found {self.status!r}")
        if self.converged != (self.status == "converged"):
            raise ValueError(f"converged={self.converged} contradicts status={self.status!r}")
