"""Controllers (3.37) and (3.55) that minimise the exact cost, not its bound (not in the thesis).

Algorithms 3.2 and 3.3 minimise the costs of the bounded second moments of Prop. 3.26 and
Thm. 3.31, which are not upper bounds of the true costs (Secs. 3.6-3.7 page). Here the exact
average cost (3.42) (Prop. 3.24), resp. the exact expected cost J_0 (3.56) from the augmented
recursion (3.58), is minimised over the gains by BFGS (:func:`asoc.optimize.bfgs`) with the
analytic gradients of :mod:`asoc.mjls.gradients`. Two kinds of design, one result type each:
a time-invariant controller (3.37) (:class:`ExactDynamicOutputFeedbackResult`, also for the
controller of smallest mean-square spectral radius) and a time-variant one (3.55)
(:class:`ExactFiniteHorizonResult`).
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from .. import config
from ..linalg import pack, transpose, unpack
from ..optimize import BFGS_STATUS, bfgs
from ..validation import boolean, integer, real_scalar
from .closed_loops import augmented_closed_loop
from .controllers import DynamicOutputFeedback
from .design_result import CertifiedDesignResult, DesignResult
from .dynamic import iterate_bounds
from .finite_horizon import (
    augmented_initial_moment,
    finite_horizon_cost,
    finite_horizon_dynamic_output_feedback,
    initial_gains,
)
from .finite_horizon_model import check_initial_state, mode_distributions, stages
from .gradients import (
    average_cost_and_gradient,
    closed_loop_radius,
    finite_horizon_cost_and_gradient,
    radius_and_gradient,
)
from .stability import mean_square_stability
from .system import check_system

__all__ = ["ExactDynamicOutputFeedbackResult", "ExactFiniteHorizonResult", "averaged_lqg",
           "min_radius_dynamic_output_feedback", "exact_dynamic_output_feedback",
           "exact_finite_horizon_dynamic_output_feedback"]


@dataclass(kw_only=True)
class ExactDynamicOutputFeedbackResult(CertifiedDesignResult):
    """A time-invariant controller (3.37) found by BFGS: :func:`exact_dynamic_output_feedback`
    (on the exact cost (3.42)) or :func:`min_radius_dynamic_output_feedback` (on rho, Cor. 3.2).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (nc, nc), (nc, ny), (nu, nc)
        The controller (3.37).
    converged, status, message
        Why BFGS stopped: ``"converged"`` (the decrease its model predicts is below
        tol * objective, or rho fell below its target), ``"max_iterations"`` or
        ``"no_progress"`` (no descent step, or no mean-square stabilising start was found).
    iterations : int
    stability : asoc.mjls.MeanSquareStability
        The closed loop's certificate (Cor. 3.2); ``rho``, ``rho_bracket`` and ``stabilizing``
        read it (:class:`asoc.mjls.design_result.CertifiedDesignResult`).
    cost : float
        Exact average cost (3.42) (Prop. 3.24); inf if not stabilizing.
    history : dict
        The objective after each iteration: ``"cost"`` (exact design) or ``"rho"``.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> res = exact_dynamic_output_feedback(sys, max_iter=3, warn=False)
    >>> res.status, res.iterations, sorted(res.history), res.controller.F.shape
    ('max_iterations', 3, ['cost'], (2, 2))
    """

    controller_type = DynamicOutputFeedback
    controller_fields = ("F", "K", "L")

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    iterations: int
    cost: float
    history: dict = field(repr=False)
    seconds: float = 0.0


@dataclass(kw_only=True)
class ExactFiniteHorizonResult(DesignResult):
    """Result of :func:`exact_finite_horizon_dynamic_output_feedback` (L-BFGS on J_0 (3.56)).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (horizon, nc, nc), (horizon, nc, ny), (horizon, nu, nc)
        The gains of (3.55) per step.
    xhat0 : numpy.ndarray, shape (nc,)
        The controller's initial state E{x_0}.
    converged, status, message
        Why L-BFGS stopped (as :class:`ExactDynamicOutputFeedbackResult`).
    iterations : int
    cost : float
        The exact expected cost J_0 (3.56) of the final gains.
    costs : numpy.ndarray
        The exact J_0 after each iteration.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = exact_finite_horizon_dynamic_output_feedback(sec373_system(1), 5, SEC373_MEAN0[1],
    ...                                                    SEC373_COV0, SEC373_MU0, max_iter=3,
    ...                                                    warn=False)
    >>> res.status, res.F.shape, res.costs.size, res.controller.time_variant
    ('max_iterations', (5, 2, 2), 4, True)
    """

    controller_type = DynamicOutputFeedback
    controller_fields = ("F", "K", "L", "xhat0")

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    xhat0: np.ndarray
    iterations: int
    cost: float
    costs: np.ndarray = field(repr=False)
    seconds: float = 0.0


def averaged_lqg(sys, nc):
    """The LQG compensator of the mode-averaged system (sum_i mu_inf,i A_i, ...) in the form (3.37).

    A start of the exact design (predictor-form Kalman gain and LQ gain from the two discrete
    algebraic Riccati equations). Returns (F, K, L), or None when nc != nx or a Riccati
    equation has no stabilising solution.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> F, K, L = averaged_lqg(sys, 2)
    >>> F.shape, K.shape, L.shape
    ((2, 2), (2, 1), (1, 2))
    """
    if nc != sys.nx:
        return None
    mu = sys.mu_inf
    avg = lambda S: np.einsum("i,iab->ab", mu, S)
    A, B, C, Q, R = (avg(S) for S in (sys.A, sys.B, sys.C, sys.Q, sys.R))
    W = avg(sys.H @ transpose(sys.H))
    V = np.zeros((sys.ny, sys.ny)) if sys.J is None else avg(sys.J @ transpose(sys.J))
    eps = config.defaults["mjls.lqg_start_regularisation"]
    V = V + eps * max(1.0, np.abs(V).max()) * np.eye(sys.ny)       # y = C x: a regular filter DARE
    Q = Q + eps * max(1.0, np.abs(Q).max()) * np.eye(sys.nx)
    W = W + eps * max(1.0, np.abs(W).max()) * np.eye(sys.nx)
    try:
        X = scipy.linalg.solve_discrete_are(A, B, Q, R)
        S = scipy.linalg.solve_discrete_are(A.T, C.T, W, V)
    except (np.linalg.LinAlgError, ValueError):
        return None
    L = -np.linalg.solve(R + B.T @ X @ B, B.T @ X @ A)
    K = A @ S @ C.T @ np.linalg.inv(C @ S @ C.T + V)
    return A + B @ L - K @ C, K, L


def _bounded_alg32(sys, nc):
    """Alg. 3.2's controller after at most ``mjls.exact_warm_start_iterations`` iterations,
    padded with zeros or cut to nc states (None when Alg. 3.2 fails at once).
    """
    run = iterate_bounds(sys, config.defaults["mjls.exact_warm_start_tol"],
                         config.defaults["mjls.exact_warm_start_iterations"])
    if run.best is None:
        return None
    F0, K0, L0 = run.best.gains
    F, K, L = np.zeros((nc, nc)), np.zeros((nc, sys.ny)), np.zeros((sys.nu, nc))
    m = min(nc, sys.nx)
    F[:m, :m], K[:m], L[:, :m] = F0[:m, :m], K0[:m], L0[:, :m]
    return F, K, L


def _given_gains(sys, init, nc):
    """(F, K, L) from ``init``: a result with F, K, L or a tuple; validated against sys."""
    gains = (init.F, init.K, init.L) if all(hasattr(init, g) for g in "FKL") else init
    if not (isinstance(gains, (tuple, list)) and len(gains) == 3):
        raise TypeError("init: expected a result with F, K, L (e.g. of dynamic_output_feedback) "
                        f"or a tuple (F, K, L), found {type(init).__name__}"
                        f"{f' of length {len(init)}' if isinstance(init, (tuple, list)) else ''}")
    F = np.atleast_2d(np.asarray(gains[0], dtype=float))
    if nc is not None and F.shape[0] != nc:
        raise ValueError(f"nc: expected the controller order of init, {F.shape[0]}, found {nc}")
    augmented_closed_loop(sys, *gains)                  # validates the shapes
    return tuple(np.atleast_2d(np.asarray(g, dtype=float)) for g in gains)


def _starts(sys, init, nc):
    """The candidate starts (packed), best first, their exact costs (3.42) (inf where not
    stabilising) and the shapes of F, K, L: ``init`` when given, else Alg. 3.2's bounded run
    and the averaged LQG compensator (``averaged_lqg`` in this module).
    """
    if init is not None:
        candidates = [_given_gains(sys, init, nc)]
    else:
        nc = sys.nx if nc is None else nc
        candidates = [g for g in (_bounded_alg32(sys, nc), averaged_lqg(sys, nc)) if g is not None]
        zero = (np.zeros((nc, nc)), np.zeros((nc, sys.ny)), np.zeros((sys.nu, nc)))
        candidates = candidates or [zero]
    costs = [average_cost_and_gradient(sys, *g)[0] for g in candidates]
    order = np.argsort(costs, kind="stable")
    shapes = tuple(g.shape for g in candidates[0])
    return [pack(*candidates[i]) for i in order], [costs[i] for i in order], shapes


def _stabilising_start(sys, starts, costs, shapes):
    """The first start of finite cost (it stabilises: the coupled Lyapunov test of
    :func:`asoc.mjls.gradients.average_cost_and_gradient`); else the averaged LQG compensator
    is added, and rho is minimised from each candidate (in order of rho) until it falls below
    ``mjls.rho_start`` and the exact cost there is finite (an estimate of rho below 1 is not a
    certificate: rho exactly 1 rounds either way). Returns (z, stabilising), the smallest rho
    reached when none stabilises.
    """
    for z, cost in zip(starts, costs):
        if np.isfinite(cost):
            return z, True
    radii = [closed_loop_radius(sys, *unpack(z, shapes)) for z in starts]
    lqg = averaged_lqg(sys, shapes[0][0])
    if lqg is not None and not any(np.array_equal(pack(*lqg), z) for z in starts):
        starts, radii = starts + [pack(*lqg)], radii + [closed_loop_radius(sys, *lqg)]
    best = (starts[int(np.argmin(radii))], min(radii))
    for i in np.argsort(radii):
        if not np.isfinite(radii[i]):
            continue
        run = _min_radius(sys, starts[i], shapes, config.defaults["mjls.radius_max_iter"],
                          target=config.defaults["mjls.rho_start"])
        zi, rho = run.z, run.f
        if rho < 1 and np.isfinite(average_cost_and_gradient(sys, *unpack(zi, shapes))[0]):
            return zi, True                     # certified (finite exact cost), not rho's estimate
        best = min(best, (zi, rho), key=lambda b: b[1])
    return best[0], False


def _min_radius(sys, z, shapes, max_iter, target=-np.inf, progress=False, patience=None):
    """BFGS on rho (Cor. 3.2) over (F, K, L) from z, stopping early once rho <= target (or, with
    ``patience``, once that many steps lowered rho by less than ``_RADIUS_STALL`` relative).
    """
    fun = lambda v: _flat(radius_and_gradient(sys, *unpack(v, shapes)))
    return bfgs(fun, z, config.defaults["mjls.min_radius_tol"], max_iter, progress, "min rho",
                target=target, patience=patience, stall=_RADIUS_STALL)


#: min_radius_dynamic_output_feedback stops (no_progress) when ``_RADIUS_PATIENCE`` BFGS steps
#: lowered rho by less than ``_RADIUS_STALL`` relative: rho is not smooth at its minimum (Perron
#: eigenvalues coalesce), BFGS then crawls, and each step costs a certified Perron pair
#: (about 1 s on the networked loops at load 8 on 2 cores).
_RADIUS_PATIENCE, _RADIUS_STALL = 10, 1e-5


def _flat(out):
    value, grads = out
    return value, (None if grads is None else pack(*grads))


def _checked_order(nc):
    return None if nc is None else integer(nc, "nc", minimum=1)


def _bfgs_message(status, it, value, name):
    return f"{BFGS_STATUS[status]} after {it} iterations ({name} {value:.6g})"


def _controller_result(sys, z, shapes, status, it, history, name, start, message=None):
    """The result of a BFGS run over the gains of (3.37): the certified stability verdict of
    the final controller and its exact cost.
    """
    F, K, L = unpack(z, shapes)
    stability = mean_square_stability(augmented_closed_loop(sys, F, K, L)[0], sys.T)
    cost = average_cost_and_gradient(sys, F, K, L)[0] if stability.stable else np.inf
    value = history[-1] if len(history) else np.inf
    return ExactDynamicOutputFeedbackResult(
        F=F, K=K, L=L, converged=status == "converged", status=status,
        message=message or _bfgs_message(status, it, value, name), iterations=it,
        stability=stability, cost=cost, history={name: history},
        seconds=time.perf_counter() - start)


@config.accepts_settings("mjls.rho_start", "mjls.min_radius_tol", "mjls.lqg_start_regularisation")
def min_radius_dynamic_output_feedback(sys, init=None, nc=None, max_iter=None, progress=False,
                                       warn=True):
    """The controller (3.37) of locally smallest mean-square spectral radius (Cor. 3.2).

    Not in the thesis. BFGS on rho over (F, K, L) with the gradient of
    :func:`asoc.mjls.gradients.radius_and_gradient`. A rho that stays >= 1 from several starts is
    evidence, not proof, that no controller (3.37) of this order stabilises the system without
    observing the mode.

    Parameters
    ----------
    sys : MJLS
        The system (Sec. 3.6).
    init : DynamicOutputFeedbackResult, tuple or None
        The start: a result with F, K, L (e.g. :class:`DynamicOutputFeedbackResult`), a
        tuple (F, K, L), or None for the best default start of
        :func:`exact_dynamic_output_feedback`.
    nc : int, optional
        Controller order (default: that of ``init``, else nx).
    max_iter : int, optional
        BFGS iteration limit (default ``config.defaults["mjls.radius_max_iter"]``).
    progress : bool
        Show a tqdm bar over iterations.
    warn : bool
        Warn (RuntimeWarning, with the status) when BFGS stops without converging: after
        10 steps that together lowered rho by less than 1e-5 relative (``"no_progress"``), without a
        descent step, or at max_iter.

    Returns
    -------
    ExactDynamicOutputFeedbackResult
        F, K, L, controller; rho, stabilizing; cost: exact average cost (3.42) if
        stabilising, else inf; status (why BFGS stopped), iterations, seconds;
        history["rho"]: rho after each iteration.

    Raises
    ------
    TypeError
        if sys is not an MJLS, max_iter or nc not an integer, or init of the wrong type.
    ValueError
        if max_iter or nc is not positive, or init has the wrong shapes.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> res = min_radius_dynamic_output_feedback(sec373_system(1), max_iter=20, warn=False)
    >>> res.stabilizing, bool(res.history["rho"][-1] <= res.history["rho"][0])
    (True, True)
    """
    check_system(sys)
    max_iter = integer(config.defaults["mjls.radius_max_iter"] if max_iter is None else max_iter,
                       "max_iter", minimum=1)
    progress, warn = boolean(progress, "progress"), boolean(warn, "warn")
    start = time.perf_counter()
    z, _, shapes = _starts(sys, init, _checked_order(nc))
    run = _min_radius(sys, z[0], shapes, max_iter, progress=progress, patience=_RADIUS_PATIENCE)
    result = _controller_result(sys, run.z, shapes, run.status, run.iterations, run.history, "rho",
                                start)
    if warn and result.status != "converged":
        warnings.warn(f"min_radius_dynamic_output_feedback stopped with status {result.status!r}: "
                      f"{result.message}", RuntimeWarning, stacklevel=2)
    return result


@config.accepts_settings("mjls.exact_warm_start_iterations", "mjls.exact_warm_start_tol",
                         "mjls.lqg_start_regularisation", "mjls.rho_start", "mjls.radius_max_iter",
                         "mjls.min_radius_tol")
def exact_dynamic_output_feedback(sys, init=None, nc=None, tol=1e-10, max_iter=2000, warn=True,
                                  progress=False):
    """The controller (3.37) minimising the exact average cost (3.42) (Prop. 3.24).

    Not in the thesis. BFGS over (F, K, L) with the analytic gradient (adjoint of the augmented
    second-moment equations, Prop. 3.23), inside the mean-square stabilising set (steps that leave
    it, where the cost is inf, are rejected by the line search). This is the design to use when
    Algorithm 3.2 (:func:`dynamic_output_feedback`) stops on a cycle or without converging.

    Parameters
    ----------
    sys : MJLS
        With measurement noise J (Sec. 3.6; J = None means y = C x).
    init : DynamicOutputFeedbackResult, tuple or None
        The start: a result with F, K, L (e.g. :class:`DynamicOutputFeedbackResult`), a tuple
        (F, K, L), or None for the better (in exact cost) of Algorithm 3.2's controller after
        at most ``config.defaults["mjls.exact_warm_start_iterations"]`` iterations and the LQG
        compensator of the mode-averaged system (``averaged_lqg`` in this module). A non-stabilising
        start is first moved into the stabilising set by minimising the mean-square spectral
        radius (:func:`min_radius_dynamic_output_feedback`).
    nc : int, optional
        Controller order (default: that of ``init``, else nx; Alg. 3.2's controller is
        padded with zeros or cut to nc states).
    tol : float
        Stop when the decrease the quasi-Newton model predicts is below tol * cost.
    max_iter : int
        BFGS iteration limit.
    warn : bool
        Warn when no stabilising start is found or the iteration does not converge.
    progress : bool
        Show a tqdm bar over iterations.

    Returns
    -------
    ExactDynamicOutputFeedbackResult
        F, K, L, controller; cost (exact, Prop. 3.24), rho, stabilizing, status (why BFGS
        stopped), iterations, seconds; history["cost"]: exact cost after each iteration.

    Raises
    ------
    TypeError
        if sys is not an MJLS, max_iter or nc is not an integer, a flag not a bool, or init
        has the wrong type.
    ValueError
        if tol or max_iter are not positive, nc < 1, or init has the wrong shapes.

    Examples
    --------
    On the example of Sec. 3.7.3 the exact optimum is below Alg. 3.2's cost (23.313):

    >>> from asoc.mjls.examples import sec373_system
    >>> res = exact_dynamic_output_feedback(sec373_system(1))
    >>> res.status, round(res.cost, 3)
    ('converged', 22.892)
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn, progress = boolean(warn, "warn"), boolean(progress, "progress")
    start = time.perf_counter()
    starts, costs, shapes = _starts(sys, init, _checked_order(nc))
    z, stabilising = _stabilising_start(sys, starts, costs, shapes)
    if not stabilising:
        rho = closed_loop_radius(sys, *unpack(z, shapes))
        message = f"found no mean-square stabilising start (smallest rho reached {rho:.4f})"
        if warn:
            warnings.warn(f"exact_dynamic_output_feedback: {message}; pass a stabilising init",
                          RuntimeWarning, stacklevel=2)
        return _controller_result(sys, z, shapes, "no_progress", 0, np.array([np.inf]), "cost",
                                  start, message)
    fun = lambda v: _flat(average_cost_and_gradient(sys, *unpack(v, shapes)))
    run = bfgs(fun, z, tol, max_iter, progress, "exact (3.42)")
    result = _controller_result(sys, run.z, shapes, run.status, run.iterations, run.history, "cost",
                                start)
    if warn and run.status != "converged":
        warnings.warn(f"exact_dynamic_output_feedback: {result.message}", RuntimeWarning,
                      stacklevel=2)
    return result


@config.accepts_settings("mjls.lbfgs_memory")
def exact_finite_horizon_dynamic_output_feedback(sys, horizon, mean0, cov0, mu0, init=None,
                                                 tol=1e-12, max_iter=5000, warn=True,
                                                 progress=False):
    """The time-variant controller (3.55) minimising the exact J_0 (3.56)/(3.58); not in the thesis.

    L-BFGS over all gains F_k, K_k, L_k (k = 0..horizon-1) with the analytic gradient (the adjoint
    of the augmented forward recursion (3.58)); the controller starts at x^_0 = E{x_0} as in
    :func:`finite_horizon_dynamic_output_feedback`.

    Parameters
    ----------
    sys : MJLS or sequence of MJLS
        One system, or a sequence of ``horizon`` (or ``horizon + 1``) systems (3.54).
    horizon : int
        The horizon K >= 1.
    mean0, cov0, mu0 : array_like
        The Gaussian-mixture initial state, as for Alg. 3.3.
    init : FiniteHorizonResult, DynamicOutputFeedbackResult, tuple or None
        The start: None for Algorithm 3.3's result (itself started from Alg. 3.2), a result
        with F, K, L (e.g. FiniteHorizonResult, DynamicOutputFeedbackResult) or a tuple
        (F, K, L), constant or per step.
    tol : float
        Stop when the decrease the quasi-Newton model predicts is below tol * J_0. The
        problem is ill-conditioned (the time-variant state transformations of x^_k leave
        J_0 unchanged), so the model underestimates the remaining decrease: on Sec. 3.7.3,
        tol = 1e-12 stops within about 1e-8 (relative) of the limit, tol = 1e-10 within 1e-7.
    max_iter : int
        L-BFGS iteration limit (memory ``config.defaults["mjls.lbfgs_memory"]`` pairs).
    warn : bool
        Warn when the iteration does not converge.
    progress : bool
        Show a tqdm bar over iterations.

    Returns
    -------
    ExactFiniteHorizonResult
        F, K, L (per step), xhat0, controller, cost (exact J_0), status (why L-BFGS stopped),
        iterations, seconds; costs: exact J_0 after each iteration.

    Raises
    ------
    TypeError
        for a sys that is not an MJLS (sequence), a non-integer horizon or max_iter, a flag
        that is not a bool or an init of the wrong type.
    ValueError
        for an invalid horizon, initial state, init, tol or max_iter.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = exact_finite_horizon_dynamic_output_feedback(sec373_system(1), 10, SEC373_MEAN0[1],
    ...                                                    SEC373_COV0, SEC373_MU0)
    >>> res.status, bool(res.cost <= res.costs[0])
    ('converged', True)
    """
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn, progress = boolean(warn, "warn"), boolean(progress, "progress")
    start = time.perf_counter()
    st = stages(sys, horizon)
    s0 = st.systems[0]
    mean0, cov0, mu0 = check_initial_state(s0.M, s0.nx, mean0, cov0, mu0)
    if init is None:
        init = finite_horizon_dynamic_output_feedback(sys, horizon, mean0, cov0, mu0, warn=False)
    F, K, L = initial_gains(init, st, s0.nx, s0.ny, s0.nu)
    xhat0 = mu0 @ mean0
    X0 = augmented_initial_moment(mean0, cov0, mu0, xhat0)
    mu = mode_distributions(st, mu0)
    shapes = (F.shape, K.shape, L.shape)
    fun = lambda v: _flat(finite_horizon_cost_and_gradient(st, *unpack(v, shapes), X0, mu))
    run = bfgs(fun, pack(F, K, L), tol, max_iter, progress, "exact (3.56)",
               memory=config.defaults["mjls.lbfgs_memory"])
    F, K, L = unpack(run.z, shapes)
    status, it, history = run.status, run.iterations, run.history
    message = _bfgs_message(status, it, run.f, "J_0")
    if warn and status != "converged":
        warnings.warn(f"exact_finite_horizon_dynamic_output_feedback: {message}", RuntimeWarning,
                      stacklevel=2)
    return ExactFiniteHorizonResult(F=F, K=K, L=L, xhat0=xhat0, converged=status == "converged",
                                    status=status, message=message, iterations=it,
                                    cost=finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0),
                                    costs=history, seconds=time.perf_counter() - start)
