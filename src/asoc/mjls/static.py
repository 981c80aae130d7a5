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

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..validation import boolean, choice, integer, real_array, real_scalar, semidefinite
from .. import config
from ..linalg import relative_change, transpose
from .lyapunov import coupled_lyapunov_solver
from .closed_loops import closed_loop, gain_matrix, noise_covariances
from .design_result import CertifiedDesignResult
from .stability import mean_square_stability
from .static_iterates import Cycle, ScaledPair
from .system import check_system, predecessor_sum, successor_average

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
        Whether and why the iteration stopped (:class:`asoc.result.IterativeResult`):
        ``"converged"``, ``"max_iterations"``, ``"diverged"`` (an iterate became
        non-finite) or ``"linalg_error"`` (the gain equation (3.34) was singular).
    iterations : int
    stability : MeanSquareStability
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
    EP = successor_average(sys.T, P)
    S = sys.R + transpose(sys.B) @ EP @ sys.B                     # (M, nu, nu)
    W = sys.C @ X @ transpose(sys.C) + sys.mu_inf[:, None, None] * noise_covariances(sys)[1]   # (M, ny, ny)
    N = (np.swapaxes(sys.B, 1, 2) @ EP @ sys.A @ X @ np.swapaxes(sys.C, 1, 2)).sum(axis=0)
    if method == "sdp":
        return _gain_sdp(S, W, N)
    lhs = np.einsum("iab,icd->acbd", W, S).reshape(W.shape[1] * S.shape[1], -1)  # sum W_i (x) S_i
    vec_L = -np.linalg.solve(lhs, N.reshape(-1, order="F"))
    return vec_L.reshape(S.shape[1], W.shape[1], order="F")


def _gain_sdp(S, W, N):
    """The SDP of Prop. 3.18: min lambda s.t. [[lambda I, L], [L^T, I]] >= 0 and (3.31)."""
    import cvxpy as cp

    nu, ny = S.shape[1], W.shape[1]
    L = cp.Variable((nu, ny))
    lam = cp.Variable()
    eq = sum(S[i] @ L @ W[i] for i in range(S.shape[0])) + N
    block = cp.bmat([[lam * np.eye(nu), L], [L.T, np.eye(ny)]])
    prob = cp.Problem(cp.Minimize(lam), [0.5 * (block + block.T) >> 0, eq == 0])
    prob.solve(solver=cp.CLARABEL)
    if L.value is None:
        raise np.linalg.LinAlgError(f"SDP of Prop. 3.18 failed: {prob.status}")
    return np.asarray(L.value)


class _Recursion:
    """One step of (3.34)-(3.35) in scaled variables, with the mode stacks precomputed."""

    def __init__(self, sys):
        swap = lambda S: np.ascontiguousarray(np.swapaxes(S, 1, 2))
        self.A, self.B, self.C, self.Bt, self.Ct = sys.A, sys.B, sys.C, swap(sys.B), swap(sys.C)
        self.Q, self.R, self.T, self.Tt = sys.Q, sys.R, sys.T, np.ascontiguousarray(sys.T.T)
        self.muHHt = sys.mu_inf[:, None, None] * (sys.H @ swap(sys.H))
        self.muJJt = None if sys.J is None else sys.mu_inf[:, None, None] * (sys.J @ swap(sys.J))
        self.nu, self.ny = sys.nu, sys.ny
        self.scalar_gain = sys.nu == sys.ny == 1

    def terms(self, Xs, EP, cX, cP):
        """S_i = R_i cP + B_i^T E_i(P) B_i, W_i = C_i Xs_i C_i^T + cX mu_i J_i J_i^T and
        N = sum_i B_i^T E_i(P) A_i Xs_i C_i^T of (3.34), in the scaled variables."""
        BtEP = self.Bt @ EP
        S = cP * self.R + BtEP @ self.B
        XCt = Xs @ self.Ct
        W = self.C @ XCt if self.muJJt is None else self.C @ XCt + cX * self.muJJt
        return S, W, (BtEP @ self.A @ XCt).sum(axis=0)

    def gain(self, Xs, EP, cX, cP):
        """(3.34) with R scaled by cP = 1 / s_P and the measurement noise by cX = 1 / s_X."""
        S, W, N = self.terms(Xs, EP, cX, cP)
        if self.scalar_gain:
            return -N / (W * S).sum()
        lhs = np.einsum("iab,icd->acbd", W, S).reshape(self.ny * self.nu, -1)
        return -np.linalg.solve(lhs, N.reshape(-1, order="F")).reshape(self.nu, self.ny, order="F")

    def noise(self, L):
        """mu_i (H_i H_i^T + B_i L J_i J_i^T L^T B_i^T): the constant term of (3.35) for the gain L."""
        if self.muJJt is None:
            return self.muHHt
        BL = self.B @ L
        return self.muHHt + BL @ self.muJJt @ transpose(BL)

    def moments(self, L, Xs, EP, cX, cP, out):
        """(3.35) into out[0] (next X, constant term scaled by cX = 1 / s_X) and out[1] (next P, by cP).

        With one input and one output, the products B L C and C^T L^T R L C contract over
        dimensions of size 1: each entry is one product, formed by broadcasting (the same
        numbers as the matrix products, in fewer operations).
        """
        if self.scalar_gain:
            gain = L[0, 0]
            Acl = self.A + (self.B * gain) * self.C
            LC = gain * self.C
            LtRL = (LC.swapaxes(1, 2) * self.R) * LC
        else:
            Acl = self.A + (self.B @ L) @ self.C
            LC = L @ self.C
            LtRL = LC.swapaxes(1, 2) @ self.R @ LC
        Aclt = Acl.swapaxes(1, 2)
        Y = Acl @ Xs @ Aclt + cX * self.noise(L)
        np.matmul(self.Tt, Y.reshape(len(Y), -1), out=out[0].reshape(len(Y), -1))
        np.add(Aclt @ EP @ Acl, cP * (self.Q + LtRL), out=out[1])


def _finite(L):
    """Whether every entry of the gain is finite."""
    return math.isfinite(L[0, 0]) if L.size == 1 else bool(np.isfinite(L).all())


MOMENTS = ("auto", "step", "exact")


def _step_iteration(sys, rec, tol, max_iter, init, method, until_stabilizing, skip_cycles=True):
    """The thesis's iteration (3.34)-(3.35) in scaled variables (see static_output_feedback).

    ``until_stabilizing``: False, "each" (stop at the first stabilising gain, moments="exact")
    or "slow" (moments="auto": stop at a stabilising gain once :class:`_Rate` predicts more
    than ``mjls.auto_switch_iterations`` further iterations). With
    ``skip_cycles`` (method "vec"), an exact cycle of the state (:class:`asoc.mjls.static_iterates.Cycle`) is skipped to
    ``max_iter`` in whole periods: the same result as iterating through them. Returns a dict
    with L, the unscaled X, P, converged, iterations, stabilized and the trace histories.
    """
    M = sys.M
    pair = ScaledPair(init, M, sys.nx)
    cycle = Cycle() if skip_cycles and method == "vec" else None
    stabilized = False
    rate = _Rate(tol)
    status, change = "max_iterations", np.inf
    L = np.zeros((sys.nu, sys.ny))
    T = sys.T
    it = 0
    while it < max_iter:
        it += 1
        cX, cP = np.exp(-pair.log_scales)
        Xs, Ps = pair.stack
        EP = (T @ Ps.reshape(M, -1)).reshape(Ps.shape)
        try:
            if method == "vec":
                L_new = rec.gain(Xs, EP, cX, cP)
            else:
                L_new = _gain_sdp(*rec.terms(Xs, EP, cX, cP))
        except np.linalg.LinAlgError:
            status = "linalg_error"
            break
        rec.moments(L_new, Xs, EP, cX, cP, out=pair.next)
        scales = pair.largest_entries()
        sX, sP = scales.ravel().tolist()
        if not (math.isfinite(sX) and math.isfinite(sP) and _finite(L_new)):
            status = "diverged"
            break
        change = max(relative_change(L, L_new), *pair.accept(scales))
        L = L_new
        if it > 1 and change < tol:
            status = "converged"
            break
        if until_stabilizing == "each" or (until_stabilizing == "slow" and rate.slow(it, change)):
            if mean_square_stability(closed_loop(sys, L, check=False), sys.T, check=False).rho < 1:
                stabilized = True
                break
        period = cycle.period(it, L, pair) if cycle is not None else None
        if period is not None:                          # skip whole periods: the same state after them
            times = (max_iter - it) // period
            pair.repeat(period, times)
            it += period * times
            cycle = None
    X, P = pair.unscaled()
    trace_X, trace_P = pair.traces()
    return dict(L=L, X=X, P=P, status=status, change=change, iterations=it, stabilized=stabilized,
                trace_X=trace_X, trace_P=trace_P)


class _Rate:
    """When the thesis's iteration is slow: its change falls by a rate r per iteration,
    estimated over the last ``window`` iterations; it is slow when log(tol / change) / log r,
    the iterations still to go, exceeds ``mjls.auto_switch_iterations``. Checked after
    ``window`` iterations, then at doubling intervals (each check may cost a spectral radius)."""

    window = 10

    def __init__(self, tol):
        self.tol, self.changes, self.next_check = tol, [], self.window
        self.threshold = config.defaults["mjls.auto_switch_iterations"]

    def slow(self, it, change):
        self.changes.append(change)
        if it < self.next_check or len(self.changes) <= self.window:
            return False
        self.next_check = 2 * it
        first, last = self.changes[-self.window - 1], self.changes[-1]
        if not (0 < last < first):
            return True                                 # not contracting: try the exact moments
        remaining = np.log(self.tol / last) / np.log(last / first) * self.window
        return remaining > self.threshold


def _exact_iteration(sys, rec, L, tol, max_iter, method):
    """(3.34) alternated with the exact solve of the moment equations (3.32)-(3.33) for L.

    Each step solves the two coupled linear equations X = predecessor_sum(Acl X Acl^T + mu H H^T) and
    P = Q + C^T L^T R L C + Acl^T successor_average(P) Acl (:func:`asoc.mjls.lyapunov.coupled_lyapunov_solver`:
    one LU factorisation of size M nx^2 for both when small, else BiCGSTAB on the operator).
    Returns the same dict as :func:`_step_iteration`; ``stabilized`` is False when an iterate
    does not stabilise (the moments have no solution then). Each gain is first checked by the
    coupled Lyapunov certificate (:func:`_certified`: P_i > 0 solving P = L*(P) + W with
    W_i > 0 proves mean-square stability, Costa, Fragoso and Marques 2005, Thm. 3.9), and only
    where it does not apply by the spectral radius (at n = 100, M = 100 one radius costs
    about 40 Lyapunov-operator products).
    """
    M = sys.M
    trace_X, trace_P = [], []
    stabilized = True
    status, change = "max_iterations", np.inf
    X = P = None
    it = 0
    for it in range(1, max_iter + 1):
        Acl = closed_loop(sys, L, check=False)
        solve = coupled_lyapunov_solver(Acl, sys.T)
        LC = L @ sys.C
        weight = sys.Q + np.swapaxes(LC, 1, 2) @ sys.R @ LC
        P_solution = solve(weight, adjoint=True)
        if not (_certified(P_solution, weight) or mean_square_stability(Acl, sys.T, check=False).rho < 1):
            stabilized, status = False, "diverged"
            break
        P = P_solution.X
        X = solve(predecessor_sum(sys.T, rec.noise(L))).X
        trace_X.append(np.trace(X, axis1=1, axis2=2))
        trace_P.append(np.trace(P, axis1=1, axis2=2))
        try:
            EP = successor_average(sys.T, P)
            L_new = rec.gain(X, EP, 1.0, 1.0) if method == "vec" else _gain_sdp(*rec.terms(X, EP, 1.0, 1.0))
        except np.linalg.LinAlgError:
            status = "linalg_error"
            break
        change = relative_change(L, L_new)
        L = L_new
        if change < tol:
            status = "converged"
            break
    return dict(L=L, X=X, P=P, status=status, change=change, iterations=it, stabilized=stabilized,
                trace_X=np.array(trace_X).reshape(-1, M), trace_P=np.array(trace_P).reshape(-1, M))


def _certified(solution, weight):
    """Whether P of ``solution`` (P = L*(P) + weight, solved to its stated residual) and every
    weight_i are positive definite: then the closed loop is mean-square stable."""
    if not solution.residual <= 10 * config.defaults["mjls.solve_tolerance"]:
        return False
    try:
        np.linalg.cholesky(weight)
        np.linalg.cholesky(solution.X)
    except np.linalg.LinAlgError:
        return False
    return bool(np.all(np.isfinite(solution.X)))


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
        Iteration limit; ``converged=False`` and a warning when reached. When the rounded
        iterates repeat exactly (a cycle, seen with non-stabilising gains), the remaining whole
        periods are skipped with the same result as iterating through them.
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
        switch, with the thesis's iterates; a hard one switches early. ``"step"``: the thesis's iteration (one step of each recursion (3.35) per gain
        update; Fig. 3.4 shows its iterates). ``"exact"`` (not in the thesis): run the
        thesis's iteration until its gain stabilises the MJLS, then alternate (3.34) with
        the exact solution of the two moment equations (3.32)-(3.33) for the current gain
        (linear systems of size M nx^2). Same fixed point, far fewer iterations when the
        recursions contract slowly. Where no iterate stabilises (or an exact iterate does
        not), the result of the thesis's iteration is returned.

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
    rec = _Recursion(sys)
    run = _step_iteration(sys, rec, tol, max_iter, init, method, {"auto": "slow", "exact": "each"}.get(moments, False))
    if run["stabilized"]:
        exact = _exact_iteration(sys, rec, run["L"], tol, max_iter - run["iterations"], method)
        if exact["stabilized"]:
            exact["iterations"] += run["iterations"]
            for key in ("trace_X", "trace_P"):
                exact[key] = np.concatenate([run[key], exact[key]])
            run = exact
        else:                                           # an exact iterate left the stabilising set
            run = _step_iteration(sys, rec, tol, max_iter, init, method, False)
    seconds = time.perf_counter() - start
    L = run["L"]
    cost, _, stability = _static_cost(sys, L)
    rho, stabilizing = stability.rho, stability.stabilizing
    status, message = run["status"], _message(run, tol)
    if warn and status != "converged":
        warnings.warn(f"Algorithm 3.1 {message}", RuntimeWarning, stacklevel=2)
    elif warn and not stabilizing:
        verb = "does not stabilise" if stabilizing is False else "is not certified to stabilise"
        warnings.warn(f"Algorithm 3.1 converged, but the gain {verb} the MJLS in the "
                      f"mean-square sense ({stability.sentence()}, Cor. 3.2)", RuntimeWarning, stacklevel=2)
    history = {"trace_X": run["trace_X"], "trace_P": run["trace_P"]}
    return StaticOutputFeedbackResult(L=L, converged=status == "converged", status=status,
                                      message=message, iterations=run["iterations"],
                                      stability=stability, cost=cost, X=run["X"],
                                      P=run["P"], history=history, seconds=seconds)


def _message(run, tol):
    """One sentence: why the iteration stopped."""
    it, change = run["iterations"], run["change"]
    return {"converged": f"converged after {it} iterations (relative change {change:.2g} < tol = {tol:.2g})",
            "max_iterations": f"did not converge within {it} iterations (relative change {change:.2g} "
                              f">= tol = {tol:.2g})",
            "diverged": f"stopped at iteration {it}: an iterate became non-finite (or, with "
                        f"moments='exact', left the stabilising set)",
            "linalg_error": f"stopped at iteration {it}: the gain equation (3.34) is singular"}[run["status"]]


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
    stability : MeanSquareStability
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


def _static_cost(sys, L):
    Acl = closed_loop(sys, L, check=False)
    stability = mean_square_stability(Acl, sys.T)
    if not stability.stable:
        return np.inf, None, stability
    noise = _Recursion(sys).noise(L)
    X = coupled_lyapunov_solver(Acl, sys.T)(predecessor_sum(sys.T, noise)).X
    LC = L @ sys.C
    cost = np.einsum("iab,iba->", sys.Q + transpose(LC) @ sys.R @ LC, X)
    if sys.J is not None:
        LJ = L @ sys.J
        cost += np.einsum("i,iab,iba->", sys.mu_inf, sys.R, LJ @ transpose(LJ))
    return float(cost), X, stability
