"""The iterates of Alg. 3.1 in scaled variables (:class:`ScaledPair`): X^i = s_X Xs and
P^i = s_P Ps, so that iterates that grow geometrically (a gain that does not stabilise) do not
overflow (:func:`asoc.mjls.static_iterates.step_iteration`).
"""

import math

import numpy as np

__all__ = ["ScaledPair"]


class ScaledPair:
    """The iterates of Alg. 3.1 in scaled variables, X^i = s_X Xs and P^i = s_P Ps, as one stack
    [Xs, Ps] of shape (2, M, nx, nx).

    Keeps the log scales, the directions Xs / ||Xs||_F and Ps / ||Ps||_F (``units``, what Step
    4's test compares) and the diagonals of every iterate (the trace histories), so that each
    new pair is scaled, checked and normalised once; ``next`` receives the unscaled pair of (3.35).

    Examples
    --------
    >>> pair = ScaledPair(1e-4, 2, 3)
    >>> pair.next[:] = 5.0
    >>> pair.accept(pair.largest_entries())
    >>> float(pair.stack.max()), round(float(pair.unscaled().max()), 12), pair.traces()[0].shape
    (1.0, 5.0, (2, 2))
    """

    def __init__(self, init, M, n):
        self.stack = np.broadcast_to(init * np.eye(n), (2, M, n, n)).copy()
        self.log_scales = np.zeros((2, 1, 1, 1))
        self.next = np.empty_like(self.stack)
        self._magnitudes = np.empty_like(self.stack)
        self.units = _unit(self.stack[0]), _unit(self.stack[1])
        self._diagonals = [self.stack.diagonal(0, 2, 3).copy()]
        self._logs = [self.log_scales]

    def largest_entries(self):
        """Max |X| and max |P| over the pair in ``next``, shape (2, 1, 1, 1); NaN where it holds a
        NaN, and 1 where it is zero (a zero iterate, e.g. of a system without noise, stays zero).
        """
        largest = np.abs(self.next, out=self._magnitudes).max(axis=(1, 2, 3), keepdims=True)
        return np.where(largest == 0.0, 1.0, largest)

    def accept(self, scales):
        """Make ``next / scales`` the current pair (a new array: earlier stacks stay valid)."""
        self.stack = self.next / scales
        self.log_scales = self.log_scales + np.log(scales)
        self._diagonals.append(self.stack.diagonal(0, 2, 3).copy())
        self._logs.append(self.log_scales)
        self.units = _unit(self.stack[0]), _unit(self.stack[1])

    def unscaled(self, stack=None, log_scales=None):
        """X^i and P^i (of the current pair, or of an earlier ``stack`` and ``log_scales``)."""
        if stack is None:
            stack, log_scales = self.stack, self.log_scales
        return np.exp(log_scales) * stack

    def traces(self):
        """Tr X^i and tr P^i of every iterate, each (iterations + 1, M)."""
        traces = np.exp(np.array(self._logs).reshape(-1, 2, 1)) * np.array(self._diagonals).sum(
            axis=3
        )
        return traces[:, 0], traces[:, 1]


def _unit(S):
    """S / ||S||_F as a flat vector."""
    flat = S.ravel()
    return flat / math.sqrt(flat.dot(flat))
