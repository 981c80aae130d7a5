"""The stopping rule of the fixed-point iterations of Algs. 3.1 and 3.2, and why they stop.

Both algorithms iterate a map whose fixed point solves their optimality conditions ((3.31)-
(3.33), resp. (3.49)-(3.52)), and neither map need converge: Thm. 3.19 assumes a
stabilisable system, and Alg. 3.2's (3.51) may be ill-posed. So both stop on the same rule
(:class:`StoppingRule`): converged, a cycle, no progress, or divergence, each with its reason
(:class:`StopStatus`).
"""

from collections import deque

import numpy as np

from .. import config
from ..result import Status
from ..threads import concurrently

__all__ = ["StopStatus", "StoppingRule"]

# iterates of at least this many numbers are compared with their earlier ones on threads
# (asoc.threads.concurrently): at n = M = 100 (2 x 10^6 numbers, 6 lags) 14 ms a step on one;
# a distance of 10^6 numbers takes about 1 ms, ahead of the 0.4 ms of waking a thread
_LARGE = 1_000_000


#: Why a fixed-point iteration of Alg. 3.1 or 3.2 stopped: the status codes of
#: :class:`asoc.result.Status` (``StopStatus.CYCLE == "cycle"``).
StopStatus = Status


class StoppingRule:
    """The stopping rule of Algs. 3.1 and 3.2 on the iterates (a tuple of arrays per iteration).

    Keeps the last ``mjls.alg32_max_period`` iterates. After each, the relative change
    (:func:`asoc.linalg.relative_change`, the largest over the parts of the iterate, e.g.
    Xbar, Xunder, Pbar, Punder of Alg. 3.2) against the iterate p steps back,
    p = 1 .. max period, gives the verdict:

    - ``"converged"`` when it is below tol for p = 1;
    - ``"cycle"`` when it is for some p >= 2 while the change for p = 1 stays above
      sqrt(tol) (an iteration converging with an oscillation, e.g. a contraction factor
      near -1, has a small lag-2 change too, but its lag-1 change then follows it down);
      with ``early_cycles`` (Alg. 3.1) also when the lag-p change is below sqrt(tol) and
      below 1e-4 times the lag-1 change: a contraction factor -(1 - e) has lag-2 / lag-1
      changes of about e, so only e < 1e-4 is taken for a cycle, and such an iteration
      would need more than 2e5 iterations to reach tol = 1e-10; and with ``early_cycles``
      when the iterates approach a cycle (:meth:`approaches_cycle`): the lag-p change is
      below 1e-2 of the lag-1 change and their ratio falls steadily over
      ``mjls.alg31_cycle_window`` iterations, while the lag-1 change is too slow to reach tol
      within ``max_iter``;
    - ``"diverged"`` when the iterates grow by more than 1e6 within a window of
      w = ``mjls.alg32_patience`` iterations while not settling;
    - ``"no_progress"`` when the smallest change (over p) of the last w iterations is not
      below that of the w before, or when the rate between the two windows predicts that
      tol would not be reached before ``max_iter``.

    Examples
    --------
    Iterates that alternate between two values are a cycle of period 2:

    >>> rule = StoppingRule(tol=1e-10, max_iter=100)
    >>> a, b = np.ones((4, 1, 1, 1)), 2 * np.ones((4, 1, 1, 1))
    >>> [rule.status(it, x) for it, x in enumerate((a, b, a), start=1)], rule.period
    ([None, None, 'cycle'], 2)
    """

    def __init__(self, tol, max_iter, window=None, early_cycles=False):
        self.tol, self.max_iter, self.early_cycles = tol, max_iter, early_cycles
        self.max_period = config.defaults["mjls.alg32_max_period"]
        self.window = config.defaults["mjls.alg32_patience"] if window is None else window
        self.recent = deque(maxlen=self.max_period)
        self.cycle_window = config.defaults["mjls.alg31_cycle_window"]
        # the changes at lags 1 .. max_period of the last iterations
        self.lag_changes = deque(maxlen=self.max_period * self.cycle_window + 1)
        self.smallest, self.norms = [], []
        self.change, self.period, self.predicted, self.lag1_change = np.inf, 1, np.inf, np.inf

    def status(self, it, parts):
        """The :class:`StopStatus` after iteration ``it`` with the new iterate ``parts`` (a
        sequence of arrays, or one array whose first axis lists the parts), or None.
        """
        new = [np.ravel(part) for part in parts]
        if not self.recent:
            self.recent.append(new)
            return None
        squares = [float(np.vdot(part, part)) for part in new]
        # relative_change of each part against each lag, its norm computed once
        floor = config.defaults["linalg.norm_floor"]
        sizes = [max(np.sqrt(square), floor) for square in squares]
        lags = [
            lambda old=old: max(_distance(old_part, new_part) / size
                                for old_part, new_part, size in zip(old, new, sizes))
            for old in reversed(self.recent)
        ]  # largest over the parts, per lag
        large = sum(part.size for part in new) >= _LARGE
        changes = concurrently(*lags) if large else [lag() for lag in lags]
        self.recent.append(new)
        self.lag_changes.append(changes)
        self.change = changes[0]
        if it > 1 and changes[0] < self.tol:
            return StopStatus.CONVERGED
        for period, change in enumerate(changes[1:], start=2):
            if self._cycles(change, changes[0]) or (self.early_cycles
                                                    and self.approaches_cycle(it, period)):
                self.change, self.period, self.lag1_change = change, period, changes[0]
                return StopStatus.CYCLE
        self.smallest.append(min(changes))
        self.norms.append(float(np.sqrt(sum(squares))))
        return self._progress(it)

    def _cycles(self, change, change_1):
        """Whether a change ``change`` at a lag p >= 2 with ``change_1`` at lag 1 is a cycle."""
        if change < self.tol and change_1 > np.sqrt(self.tol):
            return True
        return self.early_cycles and change < np.sqrt(self.tol) and change < 1e-4 * change_1

    def approaches_cycle(self, it, period):
        """Whether the iterates approach a cycle of ``period`` faster than they settle.

        The iterates are compared over the last W iterations (``mjls.alg31_cycle_window``,
        rounded up to a multiple of four periods, so that every point is in the same phase) at
        five points, a quarter apart, by the ratio r = c_p / c_1 of the change against
        ``period`` iterations back to the change against the last iterate. An iteration that
        converges with an oscillation (a contraction factor -(1 - e)) has r near e, constant;
        one that approaches a cycle has r falling geometrically; a transient that passes near
        a cycle dips and rises again. Taken for a cycle: r < 1e-2, r falls by 5 % or more in
        every quarter and to half over the window, c_p is below its value one period back,
        and c_1 at its rate over the window would not reach tol within ``max_iter`` iterations.

        Examples
        --------
        Iterates x_k = (-1)^k (1 + 0.9^k) approach the 2-cycle +-1:

        >>> rule = StoppingRule(tol=1e-10, max_iter=1000, early_cycles=True)
        >>> x = [np.full(1, (-1) ** k * (1 + 0.9 ** k)) for k in range(200)]
        >>> next(k for k in range(1, 200) if rule.status(k, [x[k]])), rule.period
        (43, 2)

        Iterates x_k = 1 + (-0.9)^k, a contraction with factor -0.9, converge:

        >>> rule = StoppingRule(tol=1e-10, max_iter=1000, early_cycles=True)
        >>> x = [np.full(1, 1 + (-0.9) ** k) for k in range(300)]
        >>> [(k, s) for k in range(1, 300) if (s := rule.status(k, [x[k]]))][0]
        (226, 'converged')
        """
        quarter = period * -(-self.cycle_window // (4 * period))
        window = 4 * quarter
        if len(self.lag_changes) <= window or len(self.lag_changes[-1 - window]) < period:
            return False
        # (c_1, c_p) at five points of the window, oldest first, all in the same phase
        points = [(self.lag_changes[-1 - k][0], self.lag_changes[-1 - k][period - 1])
                  for k in range(window, -1, -quarter)]
        if min(min(pair) for pair in points) <= 0:
            return False
        ratios = [cp / c1 for c1, cp in points]
        (c1, cp), (c1_then, _) = points[-1], points[0]
        cp_last = self.lag_changes[-1 - period][period - 1]   # one period back
        steady = all(later < 0.95 * earlier for earlier, later in zip(ratios, ratios[1:]))
        if not (ratios[-1] < 1e-2 and cp < cp_last and steady and ratios[-1] < 0.5 * ratios[0]):
            return False
        g1 = c1 / c1_then
        return bool(g1 >= 1 or window * np.log(self.tol / c1) / np.log(g1) > self.max_iter - it)

    def _progress(self, it):
        """Return "diverged" or "no_progress" from the last two windows of changes, else None."""
        w = self.window
        if len(self.smallest) < 2 * w:
            return None
        before, last = min(self.smallest[-2 * w : -w]), min(self.smallest[-w:])
        if self.norms[-1] > 1e6 * self.norms[-w]:
            return StopStatus.DIVERGED
        if not last < before:
            return StopStatus.NO_PROGRESS
        self.predicted = w * np.log(self.tol / last) / np.log(last / before)
        return StopStatus.NO_PROGRESS if self.predicted > self.max_iter - it else None


def _distance(old, new):
    """||new - old||_2 of two flat arrays (the numerator of :func:`asoc.linalg.relative_change`)."""
    d = new - old
    return np.sqrt(np.vdot(d, d))
