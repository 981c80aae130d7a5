"""A quasi-Newton minimiser for functions that are infinite outside their domain.

:func:`bfgs` minimises a smooth function z -> (f, grad f) by BFGS (dense inverse Hessian) or
L-BFGS (the last few curvature pairs), with a backtracking Armijo line search that rejects
steps out of the domain (f = inf) like any other step that does not decrease f. The
exact-cost designs of :mod:`asoc.mjls.exact_cost_design` use it on the mean-square stabilising
set, where the cost is finite; nothing in it is specific to them.

Nocedal and Wright, Numerical Optimization, 2nd ed., 2006: Alg. 6.1 (BFGS), Alg. 7.4
(two-loop recursion), Alg. 3.1 (backtracking).
"""

from dataclasses import dataclass, field

import numpy as np

from . import config
from .progress import progress_bar
from .result import IterativeResult
from .validation import boolean, integer, real_array, real_scalar

__all__ = ["BFGS_STATUS", "BFGSResult", "bfgs"]


#: Why :func:`bfgs` stopped, by status code (codes of :data:`asoc.result.STATUS_CODES`).
BFGS_STATUS = {"converged": "the decrease the quasi-Newton model predicts fell below tol * |f|",
               "max_iterations": "the iteration limit was reached",
               "no_progress": "the line search found no decrease even along the gradient, or the "
                              "last patience steps lowered f by less than stall * |f|"}


@dataclass(kw_only=True)
class BFGSResult(IterativeResult):
    """What :func:`bfgs` returns: an :class:`asoc.result.IterativeResult` with the last point.

    Attributes
    ----------
    z : numpy.ndarray
        The last accepted point.
    f : float
        The function value there.
    converged, status, message
        ``status`` a key of :data:`BFGS_STATUS`, ``message`` its sentence with the iterations.
    iterations : int
        Passes of the iteration (at most ``max_iter``; a pass that ends in a stop test or a
        line-search restart counts too).
    history : numpy.ndarray
        The function value at the start and after each accepted step (``len(history) - 1``
        accepted steps).

    Examples
    --------
    >>> result = bfgs(lambda z: (float((z[0] - 3) ** 2), 2 * (z - 3)), [0.0])
    >>> result.status, result.z.round(9), result.history.round(9)
    ('converged', array([3.]), array([9., 4., 0.]))
    >>> round(result.f, 9), result.iterations, result.converged
    (0.0, 3, True)
    """

    z: np.ndarray
    f: float
    iterations: int
    history: np.ndarray = field(repr=False)


class _InverseHessian:
    """The BFGS inverse-Hessian approximation: dense, or limited-memory (the last ``memory``
    pairs, two-loop recursion) for many variables; empty means a scaled identity.
    """

    def __init__(self, n, memory):
        self.n, self.memory = n, memory
        self.reset()

    def reset(self):
        self.pairs, self.dense, self.scale = [], None, None

    @property
    def empty(self):
        return self.scale is None

    def apply(self, g):
        if self.empty:
            return g / max(1.0, float(np.linalg.norm(g)))
        if self.memory is None:
            return self.dense @ g
        q, alphas = g.copy(), []
        for s, y, r in reversed(self.pairs):
            alphas.append(r * float(s @ q))
            q -= alphas[-1] * y
        q *= self.scale
        for (s, y, r), a in zip(self.pairs, reversed(alphas)):
            q += (a - r * float(y @ q)) * s
        return q

    def update(self, s, y):
        sy = float(s @ y)
        scale = np.linalg.norm(s) * np.linalg.norm(y)
        if not sy > config.defaults["optimize.curvature_rtol"] * scale:
            return                                     # curvature condition fails: skip
        if self.memory is not None:
            self.scale = sy / float(y @ y)
            self.pairs = (self.pairs + [(s, y, 1.0 / sy)])[-self.memory:]
            return
        if self.empty:
            self.scale = sy / float(y @ y)
            self.dense = self.scale * np.eye(self.n)
        Hy = self.dense @ y                            # rank-2 update as one product
        a = (1.0 + float(y @ Hy) / sy) / sy
        self.dense += np.column_stack([s, Hy]) @ np.column_stack([a * s - Hy / sy, -s / sy]).T


def bfgs(fun, z0, tol=1e-10, max_iter=1000, progress=False, desc="BFGS", memory=None,
         target=-np.inf, gtol=0.0, patience=None, stall=1e-4):
    """Minimise ``fun`` (z -> (f, grad); f = inf outside the domain) by BFGS or L-BFGS.

    The line search backtracks from the full quasi-Newton step until the Armijo condition
    holds (constant ``config.defaults["optimize.armijo"]``, up to rounding of f), giving up
    below the step ``config.defaults["optimize.min_step"]``; a step out of the domain
    (f = inf) is rejected like any other. The iteration stops (converged) when the decrease
    the quasi-Newton model predicts, g^T H^-1 g / 2, is below ``tol * |f|``, when the scaled
    gradient ``||g|| max(1, ||z||) / |f|`` is below ``gtol``, or once f <= ``target``.

    Parameters
    ----------
    fun : callable
        z -> (f, gradient); f is a float (inf outside the domain), the gradient an array
        like z (ignored where f is inf).
    z0 : array_like, 1-D
        The start; f(z0) must be finite.
    tol : float
        Relative tolerance of the predicted decrease.
    max_iter : int
        Iteration limit.
    progress : bool
        Show a tqdm bar over iterations.
    desc : str
        Label of the bar.
    memory : int, optional
        None for dense BFGS, else L-BFGS keeping that many pairs.
    target : float
        Stop as soon as f <= target.
    gtol : float
        Stop (converged) once ``||g|| max(1, ||z||) / |f| < gtol`` (0: never).
    patience, stall : int or None, float
        Stop (``"no_progress"``) once the last ``patience`` accepted steps together lowered f
        by less than ``stall * |f|`` (None: never): for objectives, like a spectral radius,
        that are not smooth at their minimum and on which BFGS crawls.

    Returns
    -------
    BFGSResult
        z, f, status (a key of :data:`BFGS_STATUS`), message, iterations, history.

    Raises
    ------
    ValueError
        If ``z0`` is outside the domain (f infinite) or not a finite vector, ``tol`` is
        not positive, or ``max_iter`` or ``memory`` is below 1.

    Examples
    --------
    >>> fun = lambda z: ((z[0] - 1) ** 2 + 10 * (z[1] - z[0] ** 2) ** 2,
    ...                  np.array([2 * (z[0] - 1) - 40 * z[0] * (z[1] - z[0] ** 2),
    ...                            20 * (z[1] - z[0] ** 2)]))
    >>> result = bfgs(fun, [-1.0, 1.0], 1e-14, 200)
    >>> result.status, result.z.round(4)
    ('converged', array([1., 1.]))
    """
    z0 = real_array(z0, "z0", ndim=1)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    progress = boolean(progress, "progress")
    if memory is not None:
        memory = integer(memory, "memory", minimum=1)
    gtol = real_scalar(gtol, "gtol", low=0)
    if patience is not None:
        patience = integer(patience, "patience", minimum=1)
    stall = real_scalar(stall, "stall", low=0)
    return _bfgs(fun, z0, tol, max_iter, progress, desc, memory, target, gtol, patience, stall)


def _bfgs(fun, z, tol, max_iter, progress, desc, memory, target, gtol=0.0, patience=None,
          stall=0.0):
    armijo, min_step = config.defaults["optimize.armijo"], config.defaults["optimize.min_step"]
    f, g = fun(z)
    if not np.isfinite(f):
        raise ValueError("z0: the start is outside the domain (the function is infinite there)")
    Hinv = _InverseHessian(z.size, memory)
    history = [f]
    status = "max_iterations"
    it = 0
    for it in progress_bar(range(1, max_iter + 1), progress, desc=desc, leave=False):
        fresh = Hinv.empty
        d = -Hinv.apply(g)
        slope = float(g @ d)
        stationary = gtol > 0 and np.linalg.norm(g) * max(1.0, np.linalg.norm(z)) < gtol * abs(f)
        if -0.5 * slope <= tol * abs(f) or f <= target or stationary:
            status = "converged"
            break
        t = 1.0
        while t >= min_step:
            z_new = z + t * d
            f_new, g_new = fun(z_new)
            if f_new <= f + armijo * t * slope + 4 * np.finfo(float).eps * abs(f):
                break
            t *= 0.5
        else:
            if fresh:                                  # no descent even along -g: stop
                status = "no_progress"
                break
            Hinv.reset()                               # restart from a scaled gradient step
            continue
        Hinv.update(z_new - z, g_new - g)
        z, f, g = z_new, f_new, g_new
        history.append(f)
        stalled = patience is not None and len(history) > patience
        if stalled and history[-1 - patience] - f < stall * abs(f):
            status = "no_progress"
            break
    return BFGSResult(z=z, f=f, converged=status == "converged", status=status,
                      message=f"{BFGS_STATUS[status]} after {it} iterations (f = {f:.6g})",
                      iterations=it, history=np.array(history))
