"""The static gain u = L y minimising the exact average cost (3.9) (Prop. 3.15); not in the thesis.

Alg. 3.1 looks for a fixed point of (3.34)-(3.35); Thm. 3.19 promises convergence for a
stabilisable system, yet the recursion may cycle between two gains (Sec. 3.5 page, the
lossy networked loop of :func:`asoc.mjls.examples.networked_loop_lossy`). Here the cost of
Prop. 3.15 is minimised over L directly, by BFGS (:func:`asoc.optimize.bfgs`) with its
analytic gradient, inside the mean-square stabilising set (the cost is inf outside it, and
the line search rejects such steps). With the closed loop A_i + B_i L C_i, W_i = H_i H_i^T +
B_i L J_i J_i^T L^T B_i^T, the moments X_j = sum_i p_ij [Acl_i X_i Acl_i^T + mu_i W_i] (3.32)
and the costate P_i = Q_i + C_i^T L^T R_i L C_i + Acl_i^T E_i(P) Acl_i (3.33), the cost
J = sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_i] + mu_i tr[R_i L J_i J_i^T L^T] has the gradient

    dJ/dL = 2 sum_i [R_i L C_i X_i C_i^T + B_i^T E_i(P) Acl_i X_i C_i^T
                     + mu_i (R_i + B_i^T E_i(P) B_i) L J_i J_i^T],

(the adjoint of (3.32), as in :mod:`asoc.mjls.gradients`); it vanishes exactly where (3.31)
holds, so a converged Alg. 3.1 gain is a stationary point of this design too.
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from .. import config
from ..linalg import transpose
from ..optimize import bfgs
from ..validation import boolean, integer, real_scalar
from .closed_loops import closed_loop
from .design_result import CertifiedDesignResult
from .gradients import positive_definite
from .lyapunov import coupled_lyapunov_solver
from .static import StaticOutputFeedbackResult, static_cost, static_output_feedback
from .static_iterates import Recursion
from .system import check_system, predecessor_sum, successor_average

__all__ = ["ExactStaticOutputFeedbackResult", "static_cost_and_gradient", "averaged_output_gain",
           "exact_static_output_feedback"]


@dataclass(kw_only=True)
class ExactStaticOutputFeedbackResult(CertifiedDesignResult):
    """Result of :func:`exact_static_output_feedback`.

    Attributes
    ----------
    L : numpy.ndarray, shape (nu, ny)
        The gain.
    converged, status, message
        ``"converged"`` when the scaled gradient ||dJ/dL||_F max(1, ||L||_F) / J is below
        ``gtol`` (a stationary point), else why not: ``"max_iterations"``, ``"no_progress"``
        (no descent step, or no stabilising start).
    iterations : int
        BFGS iterations of the run that gave L.
    stability : asoc.mjls.MeanSquareStability
        The certificate of the closed loop (Cor. 3.2); ``rho``, ``rho_bracket`` and
        ``stabilizing`` read it (:class:`asoc.mjls.design_result.CertifiedDesignResult`).
    cost : float
        The exact average cost (3.9) (inf if not stabilising).
    scaled_gradient : float
        ||dJ/dL||_F max(1, ||L||_F) / J at L.
    start : str
        Which start gave L: ``"alg31"`` (the best member of Alg. 3.1's run) or ``"averaged_lq"``.
    history : dict
        ``"cost"``: the cost after each accepted BFGS step of that run.
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = exact_static_output_feedback(sec354_system(1))
    >>> res.status, round(res.cost, 4), res.controller.L.shape
    ('converged', 0.5673, (1, 1))
    """

    L: np.ndarray
    iterations: int
    cost: float
    scaled_gradient: float = np.nan
    start: str = ""
    history: dict = field(repr=False, default_factory=dict)
    seconds: float = 0.0


def static_cost_and_gradient(sys, L):
    """The exact average cost (3.9) of u = L y and its gradient over L (module docstring).

    Mean-square stability is tested by the coupled Lyapunov certificate: Y = L(Y) + I solved
    to its residual (at most 1e-8) and positive definite (cf. Thm. 3.9); X and P come from the
    same solver (:func:`asoc.mjls.lyapunov.coupled_lyapunov_solver`).

    Parameters
    ----------
    sys : MJLS
    L : numpy.ndarray, shape (nu, ny)

    Returns
    -------
    cost : float
        The exact average cost (3.9); inf when the certificate fails.
    gradient : numpy.ndarray, shape (nu, ny), or None
        dJ/dL (None when the certificate fails).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> cost, gradient = static_cost_and_gradient(sec354_system(1), np.array([[-0.635]]))
    >>> round(cost, 4), bool(abs(gradient[0, 0]) < 1e-3)
    (0.5673, True)
    """
    Acl = closed_loop(sys, L, check=False)
    M, n, _ = Acl.shape
    solve = coupled_lyapunov_solver(Acl, sys.T)
    Y = solve(np.broadcast_to(np.eye(n), (M, n, n)), on_miss="report")
    if not (np.all(np.isfinite(Y.X)) and Y.residual < config.defaults["mjls.solve_residual_max"]
            and positive_definite(Y.X)):
        return np.inf, None
    rec = Recursion(sys)
    LC = L @ sys.C
    weight = sys.Q + transpose(LC) @ sys.R @ LC
    X = solve(predecessor_sum(sys.T, rec.noise(L), check=False)).X
    EP = successor_average(sys.T, solve(weight, adjoint=True).X, check=False)
    cost = float(np.einsum("iab,iba->", weight, X))
    XCt = X @ transpose(sys.C)
    gradient = (sys.R @ LC @ XCt + transpose(sys.B) @ EP @ Acl @ XCt).sum(axis=0)
    if rec.muJJt is not None:
        cost += float(np.einsum("iab,iba->", sys.R, L @ rec.muJJt @ L.T))
        gradient += ((sys.R + transpose(sys.B) @ EP @ sys.B) @ L @ rec.muJJt).sum(axis=0)
    return cost, 2.0 * gradient


def averaged_output_gain(sys):
    """The LQ gain of the mode-averaged system (sum_i mu_inf,i A_i, ...) read through the outputs.

    K = -(R + B^T X B)^{-1} B^T X A from the Riccati equation of the averaged (A, B, Q, R),
    and L = K C^+ (C the averaged output matrix, ^+ its pseudo-inverse): with C = I it is
    the LQ gain. None when the Riccati equation has no stabilising solution.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> averaged_output_gain(sec354_system(1, "state")).shape
    (1, 2)
    """
    mu = sys.mu_inf
    A, B, C, Q, R = (np.einsum("i,iab->ab", mu, S) for S in (sys.A, sys.B, sys.C, sys.Q, sys.R))
    regularisation = config.defaults["mjls.lqg_start_regularisation"] * max(1.0, np.abs(Q).max())
    Q = Q + regularisation * np.eye(sys.nx)
    try:
        X = scipy.linalg.solve_discrete_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError):
        return None
    K = -np.linalg.solve(R + B.T @ X @ B, B.T @ X @ A)
    return K @ np.linalg.pinv(C)


def _scaled_gradient(cost, gradient, L):
    return float(np.linalg.norm(gradient) * max(1.0, np.linalg.norm(L)) / abs(cost))


def _minimise(sys, L0, gtol, max_iter):
    """BFGS from L0 (restarted from its end point while it stops short of gtol and still
    lowers the cost). Returns (L, cost, scaled gradient, bfgs status, iterations, history).
    """
    shape = L0.shape
    fun = lambda z: _flat(static_cost_and_gradient(sys, z.reshape(shape)))
    z, history, iterations, status = L0.ravel(), [], 0, "max_iterations"
    while iterations < max_iter:
        run = bfgs(fun, z, 1e-16, max_iter - iterations, gtol=gtol)
        iterations += run.iterations
        history.extend(run.history if not history else run.history[1:])
        improved = run.f < fun(z)[0]
        z = run.z
        cost, gradient = static_cost_and_gradient(sys, z.reshape(shape))
        scaled = _scaled_gradient(cost, gradient, z)
        status = "converged" if scaled < gtol else run.status
        if status == "converged" or not improved:
            break
    return z.reshape(shape), cost, scaled, status, iterations, np.array(history)


def _flat(out):
    cost, gradient = out
    return cost, (None if gradient is None else gradient.ravel())


def exact_static_output_feedback(sys, gtol=1e-6, max_iter=500, warn=True, alg31=None):
    """The static gain minimising the exact average cost (3.9) (Prop. 3.15); not in the thesis.

    BFGS over L with the analytic gradient of
    :func:`asoc.mjls.exact_static_design.static_cost_and_gradient`, inside the mean-square
    stabilising set (certified by the coupled Lyapunov test at every evaluated gain; steps
    leaving the set are rejected), from two starts: the best member of Alg. 3.1's run
    (:func:`asoc.mjls.static_output_feedback`, its cheapest cycle member when it cycles) and
    the averaged LQ gain (:func:`asoc.mjls.exact_static_design.averaged_output_gain`). The
    cheaper end point is returned. This is the design to use when Alg. 3.1 cycles or stops
    without converging; where Alg. 3.1 converges to a stabilising gain, that gain is already
    stationary here.

    Parameters
    ----------
    sys : MJLS
        With measurement noise J (Sec. 3.6; J = None means y = C x).
    gtol : float
        Converged when ||dJ/dL||_F max(1, ||L||_F) / J < gtol (a stationary point).
    max_iter : int
        BFGS iterations per start.
    warn : bool
        Warn (RuntimeWarning) when no start stabilises or no stationary point is reached.
    alg31 : StaticOutputFeedbackResult, optional
        A finished Alg. 3.1 run to start from (default: run it, without warnings).

    Returns
    -------
    ExactStaticOutputFeedbackResult

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, ``max_iter`` not an integer, ``warn`` not a bool or
        ``alg31`` not a StaticOutputFeedbackResult.
    ValueError
        If ``gtol`` is not a finite positive number or ``max_iter`` < 1.

    Examples
    --------
    Where Alg. 3.1 converges (Sec. 3.5.4, T[1]) both designs agree:

    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> exact, alg31 = exact_static_output_feedback(sys), static_output_feedback(sys)
    >>> exact.status, bool(abs(exact.L - alg31.L).max() < 1e-8)
    ('converged', True)
    """
    check_system(sys)
    gtol = real_scalar(gtol, "gtol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn = boolean(warn, "warn")
    if alg31 is not None and not isinstance(alg31, StaticOutputFeedbackResult):
        raise TypeError(
            f"alg31: expected a StaticOutputFeedbackResult, found {type(alg31).__name__}"
        )
    start = time.perf_counter()
    if alg31 is None:
        alg31 = static_output_feedback(sys, warn=False)
    starts = {"alg31": alg31.L, "averaged_lq": averaged_output_gain(sys)}
    ends = []
    for name, L0 in starts.items():
        if L0 is not None and np.isfinite(static_cost_and_gradient(sys, L0)[0]):
            ends.append((name, *_minimise(sys, L0, gtol, max_iter)))
    if not ends:
        message = (
            "found no mean-square stabilising start (Alg. 3.1's gain and the averaged LQ gain "
            f"both fail the coupled Lyapunov test; Alg. 3.1: rho = {alg31.rho:.4f})"
        )
        return _result(
            sys, alg31.L, "no_progress", message, 0, "alg31", np.inf, np.array([]), start, warn
        )
    name, L, cost, scaled, status, iterations, history = min(ends, key=lambda e: e[2])
    message = (
        f"{'reached' if status == 'converged' else 'did not reach'} a stationary point from the "
        f"{name} start after {iterations} BFGS iterations (scaled gradient {scaled:.2g} "
        f"{'<' if status == 'converged' else '>='} gtol = {gtol:.2g}; cost {cost:.6g})"
    )
    if status == "no_progress":
        message += ": the line search found no descent step"
    return _result(sys, L, status, message, iterations, name, scaled, history, start, warn)


def _result(sys, L, status, message, iterations, name, scaled, history, start, warn):
    cost, _, stability = static_cost(sys, L)
    if warn and status != "converged":
        warnings.warn(f"exact_static_output_feedback {message}", RuntimeWarning, stacklevel=3)
    return ExactStaticOutputFeedbackResult(
        L=L,
        converged=status == "converged",
        status=status,
        message=message,
        iterations=iterations,
        stability=stability,
        cost=cost,
        scaled_gradient=scaled,
        start=name,
        history={"cost": history},
        seconds=time.perf_counter() - start,
    )
