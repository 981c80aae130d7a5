"""The iterates of Algorithm 3.1 in scaled variables, and the detection of an exact cycle.

:func:`asoc.mjls.static_output_feedback` carries X^i = s_X Xs and P^i = s_P Ps so that
iterates that grow geometrically (a gain that does not stabilise) do not overflow
(:class:`ScaledPair`), and skips whole periods when its rounded state repeats exactly
(:class:`Cycle`).
"""

import math

import numpy as np

__all__ = ["ScaledPair", "Cycle"]


class ScaledPair:
    """The iterates of Alg. 3.1 in scaled variables, X^i = s_X Xs and P^i = s_P Ps, as one stack
    [Xs, Ps] of shape (2, M, nx, nx).

    Keeps the log scales, the directions Xs / ||Xs||_F and Ps / ||Ps||_F of Step 4's test and
    the diagonals of every iterate (the trace histories), so that each new pair is scaled,
    checked and normalised once; ``next`` receives the unscaled pair of (3.35).

    Examples
    --------
    >>> pair = ScaledPair(1e-4, 2, 3)
    >>> pair.next[:] = 5.0
    >>> changes = pair.accept(pair.largest_entries())
    >>> float(pair.stack.max()), round(float(pair.unscaled().max()), 12), pair.traces()[0].shape
    (1.0, 5.0, (2, 2))
    """

    def __init__(self, init, M, n):
        self.stack = np.broadcast_to(init * np.eye(n), (2, M, n, n)).copy()
        self.log_scales = np.zeros((2, 1, 1, 1))
        self.next = np.empty_like(self.stack)
        self._magnitudes = np.empty_like(self.stack)
        self._units = _unit(self.stack[0]), _unit(self.stack[1])
        self._diagonals = [self.stack.diagonal(0, 2, 3).copy()]
        self._logs = [self.log_scales]

    def largest_entries(self):
        """max |X| and max |P| over the pair in ``next``, shape (2, 1, 1, 1); NaN where it holds a
        NaN, and 1 where it is zero (a zero iterate, e.g. of a system without noise, stays zero)."""
        largest = np.abs(self.next, out=self._magnitudes).max(axis=(1, 2, 3), keepdims=True)
        return np.where(largest == 0.0, 1.0, largest)

    def accept(self, scales):
        """Make ``next / scales`` the current pair; return the changes of the directions of X and P."""
        self.stack = self.next / scales
        self.log_scales = self.log_scales + np.log(scales)
        self._diagonals.append(self.stack.diagonal(0, 2, 3).copy())
        self._logs.append(self.log_scales)
        units = _unit(self.stack[0]), _unit(self.stack[1])
        change_X, change_P = units[0] - self._units[0], units[1] - self._units[1]
        self._units = units
        return math.sqrt(change_X.dot(change_X)), math.sqrt(change_P.dot(change_P))

    def repeat(self, period, times):
        """Extend the histories by ``times`` repetitions of their last ``period`` iterates."""
        self._diagonals.extend(self._diagonals[-period:] * times)
        self._logs.extend(self._logs[-period:] * times)

    def unscaled(self):
        """X^i and P^i."""
        return np.exp(self.log_scales) * self.stack

    def traces(self):
        """tr X^i and tr P^i of every iterate, each (iterations + 1, M)."""
        traces = np.exp(np.array(self._logs).reshape(-1, 2, 1)) * np.array(self._diagonals).sum(axis=3)
        return traces[:, 0], traces[:, 1]


class Cycle:
    """Detects an exact cycle of the iteration's state (Brent's method: the state is compared
    with a checkpoint that moves to the current state after 1, 2, 4, ... steps).

    A step of the scaled iteration is a function of the state (L, Xs, Ps, log scales) alone.
    When the state after step ``it`` equals, bit for bit, the state after an earlier step,
    the iteration repeats that period forever: it cannot converge (no step of the period
    did), and ``max_iter`` is reached with the iterates, changes and histories of the
    period. Non-stabilising gains can make the rounded iterates cycle in this way.

    Examples
    --------
    A state that never changes repeats after any number of steps (here: after 1, then 2):

    >>> pair, cycle, L = ScaledPair(1.0, 1, 1), Cycle(), np.zeros((1, 1))
    >>> [cycle.period(it, L, pair) for it in (1, 2, 3)]
    [None, 1, 2]
    """

    def __init__(self):
        self.state, self.step, self.window = None, 0, 1

    def period(self, it, L, pair):
        """The period if the state after step ``it`` repeats the checkpoint's, else None."""
        if self.state is not None and L.flat[0] == self.state[0].flat[0] and all(
                a.tobytes() == b.tobytes() for a, b in zip((L, pair.stack, pair.log_scales), self.state)):
            return it - self.step
        if it - self.step == self.window:
            self.state, self.step, self.window = (L, pair.stack, pair.log_scales), it, 2 * self.window
        return None


def _unit(S):
    """S / ||S||_F as a flat vector."""
    flat = S.ravel()
    return flat / math.sqrt(flat.dot(flat))
