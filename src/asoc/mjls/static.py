"""Static output feedback u_k = L y_k without mode observation (Sec. 3.5.3, Alg. 3.1).

Measurement noise. The thesis's model (3.7) for Alg. 3.1 has y = C x; with the noise of
Sec. 3.6, y = C x + J v (v standard normal), u = L y gives

    x_{k+1} = (A_i + B_i L C_i) x_k + B_i L J_i v_k + H_i w_k,

so the second-moment recursion (3.35) gains the term B_i L J_i J_i^T L^T B_i^T mu_i next to
H_i H_i^T mu_i, and the stage cost E{u^T R u 1(theta = i)} = tr[R_i L (C_i X_i C_i^T +
mu_i J_i J_i^T) L^T] the term tr[R_i L J_i J_i^T L^T] mu_i. The costate (3.33) does not
change (the noise enters neither A_cl nor the weights). Setting the derivative of the
Lagrangian over L to zero, the term of the noise adds R_i L mu_i J_i J_i^T and
B_i^T E_i(P) B_i L mu_i J_i J_i^T, so in (3.31) and (3.34) C_i X_i C_i^T becomes
C_i X_i C_i^T + mu_i J_i J_i^T. With J = 0 (J = None) nothing changes.
"""

import contextlib
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import config
from ..linalg import kronecker_sum, transpose
from ..threads import concurrently, single_threaded
from ..validation import boolean, choice, integer, real_array, real_scalar, semidefinite
from .closed_loops import closed_loop, gain_matrix, noise_covariances
from .design_result import CertifiedDesignResult
from .lyapunov import coupled_lyapunov_solver
from .stability import mean_square_stability
from .static_iterates import Recursion, UntilStabilizing, exact_iteration, gain_sdp, step_iteration
from .stopping import StopStatus
from .system import check_system, successor_average

__all__ = ["StaticOutputFeedbackResult", "gain_from_moments", "MOMENTS", "static_output_feedback",
           "static_cost"]


@dataclass(kw_only=True)
class StaticOutputFeedbackResult(CertifiedDesignResult):
    """Result of Algorithm 3.1 (:func:`static_output_feedback`).

    Attributes
    ----------
    L : numpy.ndarray, shape (nu, ny)
        Regulator gain.
    converged, status, message
        Whether and why the iteration stopped (:class:`asoc.result.IterativeResult`, the
        rule of :class:`asoc.mjls.stopping.StoppingRule`): ``"converged"``, ``"cycle"`` (the
        iterates repeat with a period of 2 or more), ``"no_progress"`` (they neither settle
        nor repeat, or too slowly to reach tol), ``"max_iterations"``, ``"diverged"`` (an
        iterate became non-finite) or ``"linalg_error"`` (the gain equation (3.34) was
        singular).
    iterations : int
    stability : asoc.mjls.MeanSquareStability
        The closed loop's certificate (Cor. 3.2); ``rho``, ``rho_bracket`` and ``stabilizing``
        read it (:class:`asoc.mjls.design_result.CertifiedDesignResult`).
    cost : float
        H2 cost (Prop. 3.7) of L; inf when not stabilizing.
    X, P : numpy.ndarray, shape (M, nx, nx)
        The last iterates.
    history : dict
        ``trace_X`` and ``trace_P``: traces of X^i and P^i per iteration, (iterations + 1, M).
    seconds : float
        Wall time of the iteration.
    period : int
        The period of the cycle (status ``"cycle"``; the member of smallest exact cost is
        returned), else 1.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_feedback(sec354_system(1), max_iter=3, warn=False)
    >>> res.converged, res.status, res.iterations, type(res.controller).__name__
    (False, 'max_iterations', 3, 'StaticGain')
    """

    L: np.ndarray
    iterations: int
    cost: float
    X: np.ndarray
    P: np.ndarray
    history: dict = field(repr=False)
    seconds: float = 0.0
    period: int = 1


def gain_from_moments(sys, X, P, method="vec"):
    """L solving (3.31) for given X^i, P^i: Prop. 3.18 (``"vec"``) or its SDP (``"sdp"``).

    With measurement noise J, C_i X_i C_i^T is C_i X_i C_i^T + mu_inf,i J_i J_i^T (module
    docstring).

    Parameters
    ----------
    sys : MJLS
    X, P : numpy.ndarray, shape (M, nx, nx)
        Second moments and multipliers.
    method : {"vec", "sdp"}
        Solve the vectorised linear equation (3.34) or the SDP of Prop. 3.18.

    Returns
    -------
    numpy.ndarray, shape (nu, ny)

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS or an array is not real.
    ValueError
        If ``method`` is not "vec" or "sdp", or an array has the wrong shape or is not finite.
    numpy.linalg.LinAlgError
        If the linear system is singular or the SDP fails.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> X = P = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> gain_from_moments(sys, X, P).round(4)
    array([[-0.1447]])
    """
    check_system(sys)
    X = semidefinite(real_array(X, "X", shape=(sys.M, sys.nx, sys.nx)), "X")
    P = semidefinite(real_array(P, "P", shape=(sys.M, sys.nx, sys.nx)), "P")
    choice(method, "method", ("vec", "sdp"))
    EP = successor_average(sys.T, P, check=False)
    S = sys.R + transpose(sys.B) @ EP @ sys.B                     # (M, nu, nu)
    # (M, ny, ny)
    W = sys.C @ X @ transpose(sys.C) + sys.mu_inf[:, None, None] * noise_covariances(sys)[1]
    N = (np.swapaxes(sys.B, 1, 2) @ EP @ sys.A @ X @ np.swapaxes(sys.C, 1, 2)).sum(axis=0)
    if method == "sdp":
        return gain_sdp(S, W, N)
    vec_L = -np.linalg.solve(kronecker_sum(W, S), N.reshape(-1, order="F"))
    return vec_L.reshape(S.shape[1], W.shape[1], order="F")


#: The values of ``moments`` of :func:`static_output_feedback`.
MOMENTS = ("auto", "step", "exact")


@config.accepts_settings("mjls.auto_switch_iterations", "mjls.solve_tolerance")
def static_output_feedback(sys, tol=1e-10, max_iter=20000, init=1e-4, method="vec", warn=True,
                           moments="auto"):
    """Algorithm 3.1: iterate (3.34)-(3.35) from X^i = P^i = init * I (Sec. 3.5.3).

    When the gain does not stabilise the MJLS, X^i and P^i grow geometrically while the
    gain still converges (Sec. 3.5.4, C = [1 0]: "the iterative algorithm converges ...
    however ... cannot be stabilized"). To follow that limit without overflow, the
    recursion is carried out exactly in scaled variables X = s_X Xs, P = s_P Ps (the
    constant terms mu H H^T, Q and C^T L^T R L C are divided by the scales; the gain
    (3.34) is invariant under that scaling). Step 4's test is applied to the scaled
    iterates (their directions) and to the gain, which is also what the author's
    reference implementation stops on (the sum of the absolute changes of L below 1e-8;
    M. Dolgov, MJLS_StaticOutputComputeRegulatorGain.m, github.com/Mxttak/MJLS). The
    moments themselves converge iff the limit gain stabilises the MJLS (``stabilizing``).

    Parameters
    ----------
    sys : MJLS
    tol : float
        Stop when the relative changes of L, Xs^i and Ps^i (Frobenius) are below tol
        (``moments="exact"``: the relative change of L).
    max_iter : int
        Iteration limit; ``converged=False`` and a warning when reached. Before it, the rule
        of Alg. 3.2 (:class:`asoc.mjls.stopping.StoppingRule`, windows of
        ``mjls.alg32_patience`` iterations, periods up to ``mjls.alg32_max_period``) stops a
        run that cycles (the member of smallest exact cost is returned), stalls or could not
        reach tol within max_iter. Thm. 3.19 promises convergence only for a stabilisable
        system, and even then the recursion may cycle (Sec. 3.5 page);
        :func:`asoc.mjls.exact_static_output_feedback` minimises the exact cost instead.
    init : float
        Scale of the initial X^i, P^i; the thesis recommends 1e-4 I (Sec. 3.5.3).
    method : {"vec", "sdp"}
        Solve (3.31) by Prop. 3.18 (vectorised) or by its SDP alternative.
    warn : bool
        Warn (RuntimeWarning) when the iteration does not converge, or converges to a gain
        that does not stabilise.
    moments : {"auto", "step", "exact"}
        ``"auto"`` (default): the thesis's iteration, switching to ``"exact"`` at a
        stabilising gain once the rate of its last 10 changes predicts more than
        ``config.defaults["mjls.auto_switch_iterations"]`` further iterations (checked after
        10 iterations, then at doubling intervals). An easy system converges before the
        switch, with the thesis's iterates; a hard one switches early. ``"step"``: the thesis's
        iteration (one step of each recursion (3.35) per gain update; Fig. 3.4 shows its iterates).
        ``"exact"`` (not in the thesis): run the thesis's iteration until its gain stabilises the
        MJLS, then alternate (3.34) with the exact solution of the two moment equations
        (3.32)-(3.33) for the current gain (linear systems of size M nx^2). Same fixed point, far
        fewer iterations when the recursions contract slowly. Where no iterate stabilises (or an
        exact iterate does not), the result of the thesis's iteration is returned.

    Returns
    -------
    StaticOutputFeedbackResult
        Gain, convergence, spectral radius, stability, cost and iterate history
        (for ``moments="exact"``, ``iterations`` and ``history`` cover both phases).

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, ``max_iter`` not an integer or ``warn`` not a bool.
    ValueError
        If ``tol`` or ``init`` is not a finite positive number, ``max_iter`` < 1, or
        ``method`` or ``moments`` is unknown.

    Examples
    --------
    The example of Sec. 3.5.4 with C1 = [1 2], C2 = [2 1] and T[1]:

    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_feedback(sec354_system(1))
    >>> res.status, res.stabilizing, res.L.round(4)
    ('converged', True, array([[-0.635]]))
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    init = real_scalar(init, "init", low=0, low_open=True)
    choice(method, "method", ("vec", "sdp"))
    choice(moments, "moments", MOMENTS)
    warn = boolean(warn, "warn")
    start = time.perf_counter()
    run = _iterate(sys, tol, max_iter, init, method, UntilStabilizing.for_moments(moments))
    seconds = time.perf_counter() - start
    L, X, P, (cost, stability) = _cheapest_member(sys, run)
    status, message = run.status, _message(run, tol, stability)
    if warn and status is not StopStatus.CONVERGED:
        warnings.warn(f"Algorithm 3.1 {message}", RuntimeWarning, stacklevel=2)
    elif warn and not stability.stabilizing:
        verb = ("does not stabilise" if stability.stabilizing is False else
                "is not certified to stabilise")
        warnings.warn(f"Algorithm 3.1 converged, but the gain {verb} the MJLS in the mean-square "
                      f"sense ({stability.sentence()}, Cor. 3.2){_EXACT}", RuntimeWarning,
                      stacklevel=2)
    history = {"trace_X": run.trace_X, "trace_P": run.trace_P}
    return StaticOutputFeedbackResult(
        L=L, converged=status is StopStatus.CONVERGED, status=status.value, message=message,
        iterations=run.iterations, stability=stability, cost=cost, X=X, P=P, history=history,
        seconds=seconds, period=run.period)


def _iterate(sys, tol, max_iter, init, method, until):
    """The thesis's iteration, handing over to the exact one at a stabilising gain (``until``);
    where its steps run on threads (:attr:`asoc.mjls.static_iterates.Recursion.parallel`), with
    single-threaded BLAS throughout, which its threads would otherwise switch on and off.
    """
    rec = Recursion(sys)
    with single_threaded() if rec.parallel else contextlib.nullcontext():
        return _phases(sys, rec, tol, max_iter, init, method, until)


def _phases(sys, rec, tol, max_iter, init, method, until):
    """The step iteration, then the exact one from its first stabilising gain (``until``)."""
    run = step_iteration(sys, rec, tol, max_iter, init, method, until)
    if not run.stabilized:
        return run
    exact = exact_iteration(sys, rec, run.L, tol, max_iter - run.iterations, method,
                            run.iterations + 1, guess=(run.X, run.P), change=run.change,
                            handover=run.handover)
    if not exact.stabilized:                            # an exact iterate left the stabilising set
        return step_iteration(sys, rec, tol, max_iter, init, method)
    exact.iterations += run.iterations
    exact.trace_X = np.concatenate([run.trace_X, exact.trace_X])
    exact.trace_P = np.concatenate([run.trace_P, exact.trace_P])
    return exact


def _cheapest_member(sys, run):
    """(L, X, P, (cost, stability)) of the returned iterate: the last, or on a cycle the member
    of the period of smallest exact cost (3.9).
    """
    members = run.members or [(run.L, run.X, run.P)]
    # the exact iteration's last gain is within its change of a certified stabilising one
    near_stable = run.stabilized and len(members) == 1
    costs = [_static_cost(sys, L, X, near_stable)[::2] for L, X, _ in members]
    best = min(range(len(members)), key=lambda i: costs[i][0])
    return (*members[best], costs[best])


_EXACT = ("; exact_static_output_feedback minimises the exact cost (3.9) over L and stops at a "
          "stationary point")


def _message(run, tol, stability):
    """One sentence: why the iteration stopped (naming the exact design unless it converged)."""
    it, change = run.iterations, run.change
    rho = stability.rho
    message = {
        StopStatus.CONVERGED: f"converged after {it} iterations (relative change {change:.2g} < "
                              f"tol = {tol:.2g})",
        StopStatus.CYCLE: f"stopped at iteration {it} on a cycle of period {run.period}: the "
                          f"iterates repeat (relative change {change:.2g} against {run.period} "
                          f"iterations back, {run.lag1_change:.2g} against the last) without "
                          f"converging; returned the member of smallest exact cost "
                          f"(rho = {rho:.4f})",
        StopStatus.NO_PROGRESS: f"stopped at iteration {it}: the relative change "
                                f"({change:.2g}) stopped decreasing, or too slowly to reach "
                                f"tol = {tol:.2g} within max_iter",
        StopStatus.MAX_ITERATIONS: f"did not converge within {it} iterations (relative change "
                                   f"{change:.2g} >= tol = {tol:.2g})",
        StopStatus.DIVERGED: f"stopped at iteration {it}: an iterate became non-finite (or, with "
                             f"moments='exact', left the stabilising set)",
        StopStatus.LINALG_ERROR: f"stopped at iteration {it}: the gain equation (3.34) is singular",
    }[run.status]
    return message if run.status is StopStatus.CONVERGED else message + _EXACT


def static_cost(sys, L):
    """The average cost (3.9) of u = L y (Prop. 3.7), with the measurement noise J of Sec. 3.6.

    sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_i] + mu_i tr[R_i L J_i J_i^T L^T], with X the
    stationary second moment of (3.32) with the noise term mu_i (H_i H_i^T + B_i L J_i J_i^T
    L^T B_i^T) (module docstring); with J = None, Prop. 3.7 as it stands.

    Parameters
    ----------
    sys : MJLS
    L : array_like, shape (nu, ny)

    Returns
    -------
    cost : float
        inf unless the closed loop is certified mean-square stable.
    X : numpy.ndarray, shape (M, nx, nx), or None
        The stationary second moments (None when not stable).
    stability : asoc.mjls.MeanSquareStability
        rho of Cor. 3.2 and its verdict (:func:`asoc.mjls.mean_square_stability`).

    Raises
    ------
    TypeError, ValueError
        If ``sys`` is not an MJLS, or ``L`` not a finite real (nu, ny) array.

    Examples
    --------
    Noise on the measurement raises the cost of a gain:

    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> noisy = sys.replace(J=0.5 * np.ones((1, 1)))
    >>> round(static_cost(sys, [[-0.4]])[0], 4), round(static_cost(noisy, [[-0.4]])[0], 4)
    (0.7999, 1.7781)
    """
    check_system(sys)
    return _static_cost(sys, gain_matrix(L, "L", sys.nu, sys.ny))


def _static_cost(sys, L, X_guess=None, near_stable=False):
    """(cost, X, stability) of :func:`static_cost`, the moment equation solved from
    ``X_guess`` (e.g. the last iterate's moments) where it is solved iteratively. ``near_stable``
    (L next to a certified stabilising gain, X_guess its stationary moments): on threads, X is
    solved beside the certificate instead of after it (unused where L does not stabilise), and
    the certificate's estimate starts from X_guess (``start`` of
    :func:`asoc.mjls.mean_square_stability`).
    """
    Acl = closed_loop(sys, L, check=False)
    rec = Recursion(sys)
    start = X_guess if X_guess is not None and np.all(np.isfinite(X_guess)) else None

    def moments():
        return coupled_lyapunov_solver(Acl, sys.T)(rec.predecessor_sum(rec.noise(L)), x0=start).X

    if near_stable and rec.parallel and start is not None:  # X_guess is near the Perron stack
        stability, X = concurrently(lambda: mean_square_stability(Acl, sys.T, start=start),
                                    moments)
    else:
        stability = mean_square_stability(Acl, sys.T)
        X = moments() if stability.stable else None
    if not stability.stable:
        return np.inf, None, stability
    LC = L @ sys.C
    cost = np.einsum("iab,iba->", sys.Q + transpose(LC) @ sys.R @ LC, X)
    if sys.J is not None:
        LJ = L @ sys.J
        cost += np.einsum("i,iab,iba->", sys.mu_inf, sys.R, LJ @ transpose(LJ))
    return float(cost), X, stability
