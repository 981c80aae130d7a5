"""Infinite-horizon dynamic output feedback without mode observation (Sec. 3.6, Alg. 3.2).

The controller (3.37) is x^_{k+1} = F x^_k + K y_k, u_k = L x^_k with constant F, K, L.
With it the MJLS (3.36) forms the augmented closed loop (3.39)-(3.40) in x~ = [x; x^].
Alg. 3.2 does not minimise the true cost (3.42) but the cost of the bounded second moments
of Prop. 3.26 (:mod:`asoc.mjls.moment_bounds`); the gains solve the linear system (3.49) built from
(3.50) (:mod:`asoc.mjls.optimality`). :func:`steady_state_cost` gives the true cost of any
controller (Prop. 3.24), to set next to the bound.

Why Alg. 3.2 may not stop. Its Step 3 asks for unchanged gains, and gains need not settle:

- the matrix H of (3.51) is (numerically) singular near the fixed point when the controller
  state does not excite every direction (Xunder of low numerical rank), so (3.51) is
  ill-posed: its minimum-norm solution (threshold ``mjls.rank_rtol``) fixes the gains only
  up to a null space, and where the iteration goes depends on that truncation;
- on the networked loop of :func:`asoc.mjls.examples.networked_loop` (y = C x, input packets
  lost) H has four singular values below 1e-16 ||H|| (the next is 1e-3 ||H||), and the
  iteration settles into a 2-cycle: the bounds of alternate iterates converge to two
  different limits, whose Markov parameters L F^k K differ (L K = -0.1652 and -0.1656):
  two controllers, with true costs 0.137689 and 0.137694 (exact optimum 0.137634). With
  ``mjls.rank_rtol`` = 1e-14 the same loop converges in 87 iterations (true cost 0.1376346),
  with 1e-12 to 1e-6 it cycles; 1e-10 is the default because smaller thresholds let
  Alg. 3.2 diverge on the Scaling page (n = 8, 16);
- on the random family of the Scaling page (n = 16, M = 4) the bounds wander: in the first
  200 iterations the bound varies between 1.94 and 2.74 and the relative change per
  iteration stays between 0.03 and 0.9, while the true cost stays within 6e-4 of the exact
  optimum (1.94012 to 1.94101 against 1.94005);
- the similarity (F, K, L) ~ (S F S^-1, S K, L S^-1), which leaves the closed loop
  unchanged, is not the cause: the Markov parameters, which it leaves invariant, change
  between the iterates as well.

So :func:`dynamic_output_feedback` stops on the bounds (as the author's reference code):
converged when they stop changing, ``"cycle"`` when they repeat with a period of 2 to
``mjls.alg32_max_period`` iterations, ``"no_progress"`` when their changes stop falling
or fall too slowly to reach tol within ``max_iter``, ``"diverged"`` when they blow up
(:class:`StoppingRule`, window ``mjls.alg32_patience``). The exact design
:func:`asoc.mjls.exact_dynamic_output_feedback` minimises the true cost and converges there.
"""

import time
import warnings
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .. import config
from ..result import Status
from ..validation import boolean, choice, integer, real_scalar
from .closed_loops import augmented_closed_loop, noise_covariances
from .controllers import DynamicOutputFeedback
from .design_result import CertifiedDesignResult
from .moment_bounds import bound_cost, bound_costate_step, bound_moment_step, initial_bounds
from .moments import certified_second_moment
from .optimality import METHODS, GainSolve, solve_gains
from .stability import mean_square_stability
from .stopping import StoppingRule
from .system import check_system, successor_average

__all__ = ["steady_state_cost", "DynamicOutputFeedbackResult", "dynamic_output_feedback",
           "BoundIterate", "BoundIteration", "iterate_bounds"]


def steady_state_cost(sys, F, K=None, L=None):
    """True average cost (3.38) of (3.37): sum_i tr[Q~_i X~_inf^i] by Prop. 3.24.

    X~_inf solves the coupled Lyapunov equations of Prop. 3.23 with mu = mu_inf.

    Parameters
    ----------
    sys : MJLS
    F, K, L : array_like, shapes (nc, nc), (nc, ny), (nu, nc)
        Gains of the controller (3.37); or F a time-invariant
        :class:`asoc.mjls.DynamicOutputFeedback` or a dynamic design's result, and K, L
        omitted (as :func:`asoc.mjls.augmented_closed_loop`). For any time-invariant
        controller, static ones too, :func:`asoc.mjls.average_cost` gives the cost alone.

    Returns
    -------
    cost : float
        inf unless the closed loop is certified mean-square stable (Cor. 3.2,
        :func:`asoc.mjls.mean_square_stability`).
    X : numpy.ndarray, shape (M, nx + nc, nx + nc), or None
        X~_inf (None when not stable).
    rho : float
        Mean-square spectral radius of the augmented closed loop.

    Raises
    ------
    ValueError
        If a gain has the wrong shape or non-finite entries.
    TypeError
        If F is a controller other than a time-invariant DynamicOutputFeedback (or a result
        holding one).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> r = dynamic_output_feedback(sys)
    >>> cost, X, rho = steady_state_cost(sys, r.F, r.K, r.L)
    >>> round(cost, 3) == round(r.cost, 3), bool(rho < 1), steady_state_cost(sys, r)[0] == cost
    (True, True, True)
    """
    cost, X, stability = _certified_steady_state_cost(sys, F, K, L)
    return cost, X, stability.rho


def _certified_steady_state_cost(sys, F, K=None, L=None):
    """:func:`steady_state_cost` with the closed loop's certificate (a MeanSquareStability) in
    place of its rho, for callers that report the bracket too: one spectral radius per controller.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> r = dynamic_output_feedback(sys)
    >>> cost, X, stability = _certified_steady_state_cost(sys, r.F, r.K, r.L)
    >>> same_bracket = stability.bracket == r.rho_bracket
    >>> round(cost, 3) == round(r.cost, 3), stability.stabilizing, same_bracket
    (True, True, True)
    """
    At, HHt_cl, Qt = augmented_closed_loop(sys, F, K, L)
    stability = mean_square_stability(At, sys.T)
    if not stability.stable:
        return np.inf, None, stability
    X = certified_second_moment(At, HHt_cl, sys.T, sys.mu_inf, stability)
    return float(np.einsum("iab,iba->", Qt, X)), X, stability


@dataclass(kw_only=True)
class DynamicOutputFeedbackResult(CertifiedDesignResult):
    """Result of Algorithm 3.2 (:func:`dynamic_output_feedback`).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (nx, nx), (nx, ny), (nu, nx)
        The controller (3.37).
    converged, status, message
        Whether and why the iteration stopped (:class:`asoc.result.IterativeResult`):
        ``"converged"`` (the bounds stopped changing), ``"cycle"`` (the bounds repeat with a
        period of 2 or more iterations), ``"no_progress"`` (the bounds neither settle nor
        repeat), ``"max_iterations"``, ``"diverged"`` (the bounds grew beyond
        ``mjls.divergence_threshold``) or ``"linalg_error"`` (solving (3.51) failed).
    iterations : int
    stability : asoc.mjls.MeanSquareStability
        The certificate of the augmented closed loop (3.39) (Cor. 3.2); ``rho``,
        ``rho_bracket`` and ``stabilizing`` read it
        (:class:`asoc.mjls.design_result.CertifiedDesignResult`).
    cost : float
        True average cost (3.38) from Prop. 3.24 (inf if not stabilizing).
    bound : float
        sum_i tr[Q_i (Xbar_i + Xunder_i) + L^T R_i L Xunder_i], the cost of the bounded
        second moment of Prop. 3.26 that the algorithm minimises (not always an upper
        bound of ``cost``).
    Xbar, Xunder, Pbar, Punder : numpy.ndarray, shape (M, nx, nx)
        The last iterates.
    period : int
        The period of the cycle (status ``"cycle"``), else 1.
    history : dict
        Traces of Xbar_i, Xunder_i, Pbar_i, Punder_i per iteration, each (iterations + 1, M),
        and ``"bound"``, the bound after each iteration.
    seconds : float
        Wall time.
    solve : GainSolve
        How (3.51) was solved in the iteration whose gains are returned (dense
        np.linalg.lstsq or matrix-free conjugate gradients from
        ``mjls.matrix_free_min_unknowns`` unknowns on), with its relative residual.
    worst_residual : float
        Largest relative residual ||H z + rho|| / ||rho|| of (3.51) over the iterations.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> res = dynamic_output_feedback(sys)
    >>> res.converged, res.status, res.Xbar.shape, res.controller.F.shape
    (True, 'converged', (2, 2, 2), (2, 2))
    """

    controller_type = DynamicOutputFeedback
    controller_fields = ("F", "K", "L")

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    iterations: int
    cost: float
    bound: float
    Xbar: np.ndarray
    Xunder: np.ndarray
    Pbar: np.ndarray
    Punder: np.ndarray
    history: dict = field(repr=False)
    seconds: float = 0.0
    solve: GainSolve = None
    worst_residual: float = 0.0
    period: int = 1


@config.accepts_settings("mjls.rank_rtol", "mjls.divergence_threshold", "mjls.alg32_max_period",
                         "mjls.alg32_patience", "mjls.matrix_free_min_unknowns",
                         "mjls.cg_tolerance")
def dynamic_output_feedback(sys, tol=1e-10, max_iter=10000, init=1e-4, rng=None, method="lstsq",
                            warn=True):
    """Algorithm 3.2: the time-invariant controller (3.37) for the MJLS (3.36), mode not observed.

    Iterates Step 2 (gains from (3.51)) and Step 4 (bounds (3.52)) with mu = mu_inf. The
    iteration minimises a bound, not the true cost, and need not converge (see the module
    docstring); it then stops early and says why. For the controller of smallest true cost
    use :func:`asoc.mjls.exact_dynamic_output_feedback`.

    Parameters
    ----------
    sys : MJLS
        With measurement noise J (Sec. 3.6; J = None means y = C x).
    tol : float
        Stop when the relative changes of Xbar, Xunder, Pbar, Punder (Frobenius norms) all
        fall below ``tol``: the criterion of the author's reference code (Mxttak/MJLS,
        MJLS_ClassMeasurementFeedbackConstGains.m). Step 3's unchanged gains are not
        required: where (3.51) is singular they need not settle. The same change against
        the iterate 2 to ``mjls.alg32_max_period`` steps back detects a cycle.
    max_iter : int
        Iteration limit.
    init : float
        Scale of the initial bounds. With ``rng=None`` all four start at init * I, as in
        the author's reference code (1e-4 I); with a Generator they are random symmetric
        positive definite matrices of that scale (Step 1).
    rng : numpy.random.Generator, optional
        Source of random initial bounds.
    method : {"lstsq", "sdp"}
        Minimum-norm solution of (3.51) (relative threshold ``mjls.rank_rtol``; matrix-free
        from ``mjls.matrix_free_min_unknowns`` unknowns on, see
        :func:`asoc.mjls.optimality.gains_from_bounds`), or the SDP after Alg. 3.2.
    warn : bool
        Warn (RuntimeWarning) when the iteration does not converge or the controller does
        not stabilise.

    Returns
    -------
    DynamicOutputFeedbackResult
        Gains and controller, status, rho, the true cost (Prop. 3.24) and the bound (Prop.
        3.26). On a cycle, the member of the period with the smallest bound.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, ``max_iter`` is not an integer, ``rng`` is not a
        Generator or ``warn`` not a bool.
    ValueError
        If ``tol`` or ``init`` is not a finite positive number, ``max_iter`` < 1 or
        ``method`` is unknown.
    FloatingPointError
        If the bounds diverge (or (3.51) fails) already in the first iteration.

    Examples
    --------
    The example of Sec. 3.7.3 with T[1]:

    >>> from asoc.mjls.examples import sec373_system, networked_loop
    >>> res = dynamic_output_feedback(sec373_system(1))
    >>> res.status, res.stabilizing, round(res.cost, 3), round(res.bound, 3)
    ('converged', True, 23.313, 18.03)

    A loop where the iteration settles into a 2-cycle:

    >>> res = dynamic_output_feedback(networked_loop(), warn=False)
    >>> res.status, res.period, res.iterations < 500
    ('cycle', 2, True)
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    init = real_scalar(init, "init", low=0, low_open=True)
    choice(method, "method", METHODS)
    warn = boolean(warn, "warn")
    return _dynamic_output_feedback(sys, tol, max_iter, init, rng, method, warn)


@dataclass(frozen=True)
class BoundIterate:
    """One iterate of Alg. 3.2: the gains of Step 2 and the bounds of Step 4 they give.

    Attributes
    ----------
    bound : float
        The cost of the bounded second moments (:func:`asoc.mjls.moment_bounds.bound_cost`).
    gains : tuple of numpy.ndarray
        (F, K, L) of (3.37).
    bounds : tuple of numpy.ndarray
        (Xbar, Xunder, Pbar, Punder), each (M, nx, nx).
    solve : GainSolve
        How (3.51) was solved.
    """

    bound: float
    gains: tuple
    bounds: tuple
    solve: GainSolve


@dataclass(frozen=True)
class BoundIteration:
    """A run of Alg. 3.2 (:func:`iterate_bounds`) to its stopping rule.

    Attributes
    ----------
    status : Status
        Why it stopped (:class:`StoppingRule`, or ``"max_iterations"``, ``"linalg_error"``).
    iterations : int
    stopping : StoppingRule
        The rule, with its last change and period.
    best : BoundIterate or None
        The returned iterate: the smallest bound of the last period; None when the first
        iteration failed.
    traces : numpy.ndarray, shape (iterations + 1, 4, M)
        Traces of Xbar_i, Xunder_i, Pbar_i, Punder_i per iteration.
    worst_residual : float
        Largest relative residual of (3.51) over the iterations.
    failure : str
        The error message of a failed solve of (3.51), else empty.
    """

    status: Status
    iterations: int
    stopping: StoppingRule
    best: BoundIterate | None
    traces: np.ndarray
    worst_residual: float
    failure: str


def iterate_bounds(sys, tol, max_iter, init=1e-4, rng=None, method="lstsq"):
    """The iteration of Alg. 3.2 (Steps 2-4) until its stopping rule; arguments not validated.

    Returns
    -------
    BoundIteration

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> run = iterate_bounds(sec373_system(1), 1e-10, 20)
    >>> run.status, run.iterations, run.traces.shape, run.best.gains[0].shape
    ('max_iterations', 20, (21, 4, 2), (2, 2))
    """
    HHt, JJt = noise_covariances(sys)
    mu = sys.mu_inf
    divergence = config.defaults["mjls.divergence_threshold"]
    rank_rtol = config.defaults["mjls.rank_rtol"]
    bounds = tuple(initial_bounds(sys, init, rng))
    traces = [np.trace(np.array(bounds), axis1=-2, axis2=-1)]
    stopping = StoppingRule(tol, max_iter)
    stopping.status(0, bounds)
    iterates = deque(maxlen=stopping.max_period)         # BoundIterate of the last iterations
    worst_residual, failure, status, it = 0.0, "", Status.MAX_ITERATIONS, 0
    for it in range(1, max_iter + 1):
        Xbar, Xunder, Pbar, Punder = bounds
        EPbar, EPunder = (successor_average(sys.T, P, check=False) for P in (Pbar, Punder))
        try:
            F, K, L, solve = solve_gains(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt, method,
                                         rank_rtol)
        except np.linalg.LinAlgError as error:
            status, failure = Status.LINALG_ERROR, str(error)
            break
        worst_residual = (max(worst_residual, solve.residual) if np.isfinite(solve.residual)
                          else np.nan)
        new = (*bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt),
               *bound_costate_step(sys, F, K, L, EPbar, EPunder))
        if not all(np.abs(v).max() < divergence for v in new):
            status = Status.DIVERGED                # the bounds diverge: not stabilisable this way
            break
        bounds = new
        traces.append(np.trace(np.array(bounds), axis1=-2, axis2=-1))
        bound = bound_cost(sys, L, bounds[0], bounds[1])
        iterates.append(BoundIterate(bound, (F, K, L), bounds, solve))
        verdict = stopping.status(it, bounds)
        if verdict is not None:
            status = verdict
            break
    best = min(list(iterates)[-stopping.period:], key=lambda m: m.bound) if iterates else None
    return BoundIteration(status=status, iterations=it, stopping=stopping, best=best,
                          traces=np.array(traces), worst_residual=worst_residual, failure=failure)


def _dynamic_output_feedback(sys, tol, max_iter, init, rng, method, warn):
    start = time.perf_counter()
    run = iterate_bounds(sys, tol, max_iter, init, rng, method)
    seconds = time.perf_counter() - start
    status, it, stopping, failure = run.status, run.iterations, run.stopping, run.failure
    if run.best is None:
        what = ("(3.51) could not be solved" if status is Status.LINALG_ERROR else
                "the bounds diverged")
        raise FloatingPointError(f"Algorithm 3.2: {what} in the first iteration"
                                 f"{': ' + failure if failure else ''}")
    best = run.best
    (F, K, L), (Xbar, Xunder, Pbar, Punder) = best.gains, best.bounds
    cost, _, stability = _certified_steady_state_cost(sys, F, K, L)
    rho = stability.rho
    stabilizing = stability.stabilizing
    message = _message(status, it, stopping, tol, rho, failure, best.solve, run.worst_residual)
    if warn and status is not Status.CONVERGED:
        warnings.warn(f"Algorithm 3.2 {message}", RuntimeWarning, stacklevel=3)
    elif warn and not stabilizing:
        verb = "does not stabilise" if stabilizing is False else "is not certified to stabilise"
        warnings.warn(f"Algorithm 3.2 converged, but the controller {verb} the MJLS "
                      f"in the mean-square sense ({stability.sentence()}, Cor. 3.2)",
                      RuntimeWarning, stacklevel=3)
    names = ("Xbar", "Xunder", "Pbar", "Punder")
    history = {f"trace_{k}": run.traces[:, j] for j, k in enumerate(names)}
    return DynamicOutputFeedbackResult(
        F=F, K=K, L=L, converged=status is Status.CONVERGED, status=status, message=message,
        iterations=it, stability=stability, cost=cost, bound=best.bound, Xbar=Xbar,
        Xunder=Xunder, Pbar=Pbar, Punder=Punder, history=history, seconds=seconds,
        solve=best.solve, worst_residual=run.worst_residual, period=stopping.period)


_EXACT = ("; exact_dynamic_output_feedback minimises the true cost and converges where Alg. 3.2 "
          "does not")


def _message(status, it, stopping, tol, rho, failure, solve, worst_residual):
    """One sentence: why Alg. 3.2 stopped (naming the exact design where it did not converge)."""
    change = stopping.change
    message = {
        "converged": f"converged after {it} iterations "
                     f"(relative change of the bounds {change:.2g} < tol = {tol:.2g})",
        "cycle": f"stopped at iteration {it} on a cycle of period {stopping.period}: the bounds "
                 f"repeat (relative change {change:.2g} < tol = {tol:.2g}) without converging; "
                 f"returned the member of smallest bound (rho = {rho:.4f}){_EXACT}",
        "no_progress": f"stopped at iteration {it}: the relative change of the bounds "
                       f"({min(stopping.smallest):.2g} at best) "
                       + ("stopped decreasing" if not np.isfinite(stopping.predicted) else
                          f"would need about {stopping.predicted:.0f} more iterations to reach "
                          f"tol = {tol:.2g}")
                       + f" (the ill-posed (3.51), rho = {rho:.4f}){_EXACT}",
        "max_iterations": f"did not converge within {it} iterations (relative change {change:.2g} "
                          f">= tol = {tol:.2g}, rho = {rho:.4f}){_EXACT}",
        "diverged": f"stopped at iteration {it}: the bounds diverged (beyond "
                    f"{config.defaults['mjls.divergence_threshold']:.0e}, or grew 1e6-fold in "
                    f"{stopping.window} iterations; rho = {rho:.4f}){_EXACT}",
        "linalg_error": f"stopped at iteration {it}: solving (3.51) failed "
                        f"(rho = {rho:.4f}; {failure}){_EXACT}",
    }[status]
    if solve is not None and solve.method == "cg":
        message += (f"; (3.51) solved by conjugate gradients, largest relative residual "
                    f"||H z + rho|| / ||rho|| = {worst_residual:.1e}")
    return message
