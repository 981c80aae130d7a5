"""The iterations of Algorithm 3.1: the thesis's step (3.34)-(3.35) in scaled variables, and
the alternation of (3.34) with exact moment solves.

:func:`asoc.mjls.static_output_feedback` carries X^i = s_X Xs and P^i = s_P Ps so that
iterates that grow geometrically (a gain that does not stabilise) do not overflow
(:class:`ScaledPair`), and stops on the rule of Alg. 3.2
(:class:`asoc.mjls.stopping.StoppingRule`): converged, a cycle, no progress or divergence.
Each iteration returns an :class:`IterationRun`.
"""

import math
from collections import deque
from dataclasses import dataclass
from enum import Enum

import numpy as np

from .. import config
from ..linalg import kronecker_sum, transpose
from ..threads import concurrently, in_parts, stacked_in_parts
from .closed_loops import closed_loop
from .lyapunov import coupled_lyapunov_solver
from .moment_operator import in_parallel, mix_modes
from .scaled_pair import ScaledPair
from .stability import mean_square_stability
from .stopping import StoppingRule, StopStatus

__all__ = ["ALG31_PATIENCE", "UntilStabilizing", "IterationRun", "Recursion",
           "gain_sdp", "step_iteration", "exact_iteration", "lyapunov_certified"]


#: The window of Alg. 3.1's progress test (:class:`asoc.mjls.stopping.StoppingRule`).
ALG31_PATIENCE = 500


class UntilStabilizing(str, Enum):
    """When the thesis's iteration hands over to the exact one (``moments`` of
    :func:`asoc.mjls.static_output_feedback`): ``NEVER`` ("step"), at the first stabilising
    gain (``EACH``, "exact"), or at a stabilising gain once the iteration is slow (``SLOW``,
    "auto").

    Examples
    --------
    >>> UntilStabilizing.for_moments("auto")
    <UntilStabilizing.SLOW: 'slow'>
    """

    NEVER = "never"
    EACH = "each"
    SLOW = "slow"

    @classmethod
    def for_moments(cls, moments):
        """The mode of ``moments`` ("auto", "step" or "exact")."""
        return {"auto": cls.SLOW, "exact": cls.EACH, "step": cls.NEVER}[moments]


@dataclass
class IterationRun:
    """What one iteration of Alg. 3.1 returns.

    Attributes
    ----------
    L : numpy.ndarray, shape (nu, ny)
        The returned gain: the last, or on a cycle the member of the period of smallest exact cost.
    X, P : numpy.ndarray, shape (M, nx, nx)
        The (unscaled) moments of that iterate; where the step iteration stopped at a
        stabilising gain, the solutions of (3.33) (and of (3.32), where it was solved beside it)
        for that gain.
    status : StopStatus
    change : float
        The relative change that decided the status.
    iterations : int
    period : int
        The period of a cycle, else 1.
    lag1_change : float
        On a cycle, the relative change against the previous iterate (``change`` is the one
        against the iterate a period back).
    members : list of tuple
        On a cycle, the (L, X, P) of each member of the period; else empty.
    stabilized : bool
        Whether the iteration stopped at a stabilising gain to hand over to the exact one
        (step iteration), resp. every exact iterate stabilised (exact iteration).
    trace_X, trace_P : numpy.ndarray, shape (iterations + 1, M)
        tr X^i and tr P^i of every iterate.
    handover : tuple or None
        Where the step iteration stopped at a stabilising gain: the moment equations of that gain
        and their solutions P and X (X None unless solved beside P), for :func:`exact_iteration`
        to start from.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> run = step_iteration(sys, Recursion(sys), 1e-10, 20, 1e-4)
    >>> run.status, run.iterations, run.trace_X.shape
    ('max_iterations', 20, (21, 2))
    """

    L: np.ndarray
    X: np.ndarray
    P: np.ndarray
    status: StopStatus
    change: float
    iterations: int
    stabilized: bool
    trace_X: np.ndarray
    trace_P: np.ndarray
    period: int = 1
    members: list = None
    lag1_change: float = np.nan
    handover: tuple = None


class Recursion:
    """One step of (3.34)-(3.35) in scaled variables, with the mode stacks precomputed.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> rec = Recursion(sec354_system(1))
    >>> X = P = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> rec.gain(X, rec.successor_average(P), 1.0, 1.0).round(4)
    array([[-0.1447]])
    """

    def __init__(self, sys):
        swap = lambda S: np.ascontiguousarray(np.swapaxes(S, 1, 2))
        self.A, self.B, self.C, self.Bt, self.Ct = sys.A, sys.B, sys.C, swap(sys.B), swap(sys.C)
        self.Q, self.R, self.T, self.Tt = sys.Q, sys.R, sys.T, np.ascontiguousarray(sys.T.T)
        self.muHHt = sys.mu_inf[:, None, None] * (sys.H @ swap(sys.H))
        self.muJJt = None if sys.J is None else sys.mu_inf[:, None, None] * (sys.J @ swap(sys.J))
        self.nu, self.ny = sys.nu, sys.ny
        self.scalar_gain = sys.nu == sys.ny == 1
        # the two recursions (and the two moment equations) of a gain on two threads
        self.parallel = in_parallel(sys.A)
        self._arrays = {}

    def terms(self, Xs, EP, cX, cP):
        """S_i = R_i cP + B_i^T E_i(P) B_i, W_i = C_i Xs_i C_i^T + cX mu_i J_i J_i^T and
        N = sum_i B_i^T E_i(P) A_i Xs_i C_i^T of (3.34), in the scaled variables (the products in
        parts of the modes on threads where :attr:`parallel`, the sum in one piece, so that the
        number of cores does not change it).
        """
        M = len(self.A)
        S, W = np.empty((M, self.nu, self.nu)), np.empty((M, self.ny, self.ny))
        N_terms = np.empty((M, self.nu, self.ny))

        def products(modes):
            BtEP = self.Bt[modes] @ EP[modes]
            S[modes] = cP * self.R[modes] + BtEP @ self.B[modes]
            XCt = Xs[modes] @ self.Ct[modes]
            W[modes] = self.C[modes] @ XCt
            if self.muJJt is not None:
                W[modes] += cX * self.muJJt[modes]
            N_terms[modes] = BtEP @ self.A[modes] @ XCt

        self._run(products)
        return S, W, N_terms.sum(axis=0)

    def gain(self, Xs, EP, cX, cP, method="vec"):
        """(3.34) with R scaled by cP = 1 / s_P and the measurement noise by cX = 1 / s_X
        (``method="sdp"``: the SDP of Prop. 3.18).
        """
        S, W, N = self.terms(Xs, EP, cX, cP)
        if method == "sdp":
            return gain_sdp(S, W, N)
        if self.scalar_gain:
            return -N / (W * S).sum()
        return -np.linalg.solve(kronecker_sum(W, S),
                                N.reshape(-1, order="F")).reshape(self.nu, self.ny, order="F")

    def noise(self, L, modes=slice(None)):
        """mu_i (H_i H_i^T + B_i L J_i J_i^T L^T B_i^T): the constant term of (3.35) for the gain
        L (of the ``modes``).
        """
        if self.muJJt is None:
            return self.muHHt[modes]
        BL = self.B[modes] @ L
        return self.muHHt[modes] + BL @ self.muJJt[modes] @ transpose(BL)

    def moments(self, L, Xs, EP, cX, cP, out):
        """(3.35) into out[0] (next X, constant term scaled by cX = 1 / s_X) and out[1] (next P, by
        cP).

        From M n^3 = ``mjls.parallel_from`` on, the products run in parts of the modes on threads
        (:func:`asoc.threads.concurrently`), then the sums over the predecessors in parts of the
        rows (one product with two BLAS threads is as fast, but switching the BLAS threads back
        and forth between the two costs more than the threads gain).
        """
        Y, half = self._scratch(out[0].shape, "Y"), self._scratch(out[0].shape, "half")
        Acl, weight = self._scratch(out[0].shape, "Acl"), self._scratch(out[0].shape, "weight")

        def products(modes):
            self._closed_loop(L, modes, Acl[modes], weight[modes])
            Aclt = Acl[modes].swapaxes(1, 2)
            np.matmul(np.matmul(Acl[modes], Xs[modes], out=half[modes]), Aclt, out=Y[modes])
            Y[modes] += np.multiply(self.noise(L, modes), cX, out=half[modes])
            np.matmul(np.matmul(Aclt, EP[modes], out=half[modes]), Acl[modes], out=out[1][modes])
            weight[modes] += self.Q[modes]
            out[1][modes] += np.multiply(weight[modes], cP, out=weight[modes])

        self._run(products)
        self._run(lambda rows: mix_modes(self.Tt[rows], Y, out[0][rows]))

    def successor_average(self, P):
        """E_i(P) = sum_j p_ij P_j of the stack P (in parts of the rows on threads, as
        :meth:`moments`), in an array that the next call overwrites.
        """
        EP = self._scratch(P.shape, "EP")
        self._run(lambda rows: mix_modes(self.T[rows], P, EP[rows]))
        return EP

    def predecessor_sum(self, Y):
        """D_i(Y) = sum_j p_ji Y_j of the stack Y (in parts of the rows on threads, as
        :meth:`moments`), in a new array.
        """
        D = np.empty_like(Y)
        self._run(lambda rows: mix_modes(self.Tt[rows], Y, D[rows]))
        return D

    def _scratch(self, shape, name):
        """An array kept between steps (its pages mapped once: threads writing a new array wait
        for each other there); the result of the last call is overwritten by the next.
        """
        if name not in self._arrays or self._arrays[name].shape != shape:
            self._arrays[name] = np.empty(shape)
        return self._arrays[name]

    def _closed_loop(self, L, modes, Acl, LtRL):
        """A_i + B_i L C_i into Acl and C_i^T L^T R_i L C_i into LtRL, for the ``modes``.

        With one input and one output, the products contract over dimensions of size 1: each
        entry is one product, formed by broadcasting (the same numbers as the matrix products,
        in fewer operations).
        """
        A, B, C, R = self.A[modes], self.B[modes], self.C[modes], self.R[modes]
        if self.scalar_gain:
            gain = L[0, 0]
            LC = gain * C
            np.multiply(B * gain, C, out=Acl)
            np.multiply(LC.swapaxes(1, 2) * R, LC, out=LtRL)
        else:
            LC = L @ C
            np.matmul(B @ L, C, out=Acl)
            np.matmul(LC.swapaxes(1, 2) @ R, LC, out=LtRL)
        Acl += A

    def _run(self, task):
        """task(modes) for all modes: in parts on threads where :attr:`parallel`, else at once."""
        if self.parallel:
            in_parts(task, len(self.A))
        else:
            task(slice(None))


def gain_sdp(S, W, N):
    """The SDP of Prop. 3.18: min lambda s.t. [[lambda I, L], [L^T, I]] >= 0 and (3.31), from
    the terms S_i, W_i, N of (3.34) (:meth:`Recursion.terms`).

    Examples
    --------
    >>> S, W, N = np.ones((1, 1, 1)), np.ones((1, 1, 1)), np.array([[2.0]])
    >>> gain_sdp(S, W, N).round(6)
    array([[-2.]])
    """
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


def _finite(L):
    """Whether every entry of the gain is finite."""
    return math.isfinite(L[0, 0]) if L.size == 1 else bool(np.isfinite(L).all())


def step_iteration(sys, rec, tol, max_iter, init, method="vec", until=UntilStabilizing.NEVER):
    """The thesis's iteration (3.34)-(3.35) in scaled variables, to the stopping rule.

    Stops as :class:`asoc.mjls.stopping.StoppingRule` says on (L, Xs / ||Xs||, Ps / ||Ps||)
    (the relative changes of Step 4's test), at a non-finite iterate (``"diverged"``) or a
    singular (3.34) (``"linalg_error"``). ``until``: stop at a stabilising gain to hand over
    to :func:`exact_iteration` (:class:`UntilStabilizing`); then ``stabilized`` is True.
    On a cycle, ``members`` holds (L, X, P) of each member of the period, the last first.
    """
    pair = ScaledPair(init, sys.M, sys.nx)
    rule = StoppingRule(tol, max_iter, window=ALG31_PATIENCE, early_cycles=True)
    L = np.zeros((sys.nu, sys.ny))
    rule.status(0, (L, *pair.units))
    recent = deque([(L, pair.stack, pair.log_scales)], maxlen=rule.max_period)
    rate, stabilized, status, it = _Rate(tol), False, StopStatus.MAX_ITERATIONS, 0
    for it in range(1, max_iter + 1):
        cX, cP = np.exp(-pair.log_scales).ravel().tolist()
        Xs, Ps = pair.stack
        EP = rec.successor_average(Ps)
        try:
            L_new = rec.gain(Xs, EP, cX, cP, method)
        except np.linalg.LinAlgError:
            status = StopStatus.LINALG_ERROR
            break
        rec.moments(L_new, Xs, EP, cX, cP, out=pair.next)
        scales = pair.largest_entries()
        if not (np.all(np.isfinite(scales)) and _finite(L_new)):
            status = StopStatus.DIVERGED
            break
        pair.accept(scales)
        L = L_new
        recent.appendleft((L, pair.stack, pair.log_scales))
        verdict = rule.status(it, (L, *pair.units))
        if verdict is not None:
            status = verdict
            break
        if until is UntilStabilizing.EACH or (
            until is UntilStabilizing.SLOW and rate.slow(it, rule.change, pair.traces)
        ):
            stable, handover = _stabilizes(sys, rec, L, pair.unscaled(), rule.change)
            if stable:
                stabilized = True
                break
    trace_X, trace_P = pair.traces()
    period = rule.period if status is StopStatus.CYCLE else 1
    members = [(G, *pair.unscaled(stack, logs)) for G, stack, logs in list(recent)[:period]]
    L, X, P = members[0]
    if stabilized:
        _, P_solution, X_solution = handover   # the solutions of (3.33) (and (3.32)) for L
        P, X = P_solution.X, X if X_solution is None else X_solution.X
    return IterationRun(
        L=L,
        X=X,
        P=P,
        status=status,
        change=rule.change,
        iterations=it,
        stabilized=stabilized,
        trace_X=trace_X,
        trace_P=trace_P,
        period=period,
        members=members if period > 1 else [],
        lag1_change=rule.lag1_change,
        handover=handover if stabilized else None,
    )


class _Rate:
    """When the thesis's iteration is slow: its change falls by a rate r per iteration,
    estimated over the last ``window`` iterations; it is slow when log(tol / change) / log r,
    the iterations still to go, exceeds ``mjls.auto_switch_iterations``. Checked after
    ``window`` iterations, then at doubling intervals (each check may cost a spectral radius).

    r is the larger of the rate of the changes and the rate of the moments: the iterates
    X^k = L(X^{k-1}) + N approach their limit as rho^k (rho of the closed loop, Cor. 3.2), and
    so do their directions, which Step 4's test compares; the increments of tr X^k and of tr P^k
    over the window estimate that rate, where they shrink, and the smaller of the two counts
    (both tend to rho; a transient slows one of them for a while: on Sec. 3.5.4's first system,
    rho 0.82, tr P^k's increments shrank by 0.91 a step over the first 11). The changes alone
    can fall fast for a while and predict too few iterations (at n = M = 100 with rho 0.99 they
    predicted 105 further iterations after 20, where about 1,500 were needed).
    """

    window = 10

    def __init__(self, tol):
        self.tol, self.changes, self.next_check = tol, [], self.window
        self.threshold = config.defaults["mjls.auto_switch_iterations"]

    def slow(self, it, change, traces):
        """Whether to try the exact iteration after iteration ``it`` with its ``change``;
        ``traces()`` returns tr X^k and tr P^k of every iterate so far (:meth:`ScaledPair.traces`).
        """
        self.changes.append(change)
        if it < self.next_check or len(self.changes) <= self.window:
            return False
        self.next_check = 2 * it
        first, last = self.changes[-self.window - 1], self.changes[-1]
        if not (0 < last < first):
            return True  # not contracting: try the exact moments
        rate = max(last / first, min(self._moment_rate(trace) for trace in traces()))
        remaining = np.log(self.tol / last) / np.log(rate) * self.window
        return bool(remaining > self.threshold)

    def _moment_rate(self, trace):
        """The factor by which the increment of sum_i tr X_i^k shrank over the window (0 where it
        did not shrink: no evidence of a slow contraction).
        """
        increments = np.abs(np.diff(trace[-self.window - 2:].sum(axis=1)))
        first, last = increments[0], increments[-1]
        return float(last / first) if 0 < last < first else 0.0


def exact_iteration(sys, rec, L, tol, max_iter, method="vec", first=1, guess=None, change=np.inf,
                    handover=None):
    """(3.34) alternated with the exact solve of the moment equations (3.32)-(3.33) for L.

    Each step solves the two coupled linear equations X = predecessor_sum(Acl X Acl^T + mu H H^T)
    and P = Q + C^T L^T R L C + Acl^T successor_average(P) Acl
    (:func:`asoc.mjls.lyapunov.coupled_lyapunov_solver`: one LU factorisation of size M nx^2
    for both when small, else BiCGSTAB on the operator, started from the previous solutions
    and first from ``guess`` = (X, P), e.g. the thesis's last iterates, or for the first gain
    the solutions of the step iteration's check, ``handover``), and stops on the rule of
    :class:`asoc.mjls.stopping.StoppingRule` on L (iterations counted from ``first``).
    ``stabilized`` is False when an iterate does not stabilise (the moments have no solution
    then). Each gain is first checked by the coupled Lyapunov certificate
    (:func:`lyapunov_certified`:
    P_i > 0 solving P = L*(P) + W with W_i > 0 proves mean-square stability, Costa, Fragoso and
    Marques 2005, Thm. 3.9), and only where it does not apply by the spectral radius (at
    n = 100, M = 100 one radius costs about 40 Lyapunov-operator products).
    """
    rule = StoppingRule(tol, first - 1 + max_iter)
    rule.status(first - 1, (L,))
    trace_X, trace_P = [], []
    stabilized, status = True, StopStatus.MAX_ITERATIONS
    X, P = guess if guess is not None else (None, None)
    for it in range(first, first + max_iter):
        if handover is not None:                # the step iteration's check solved them for L
            (equations, P_solution, X_solution), handover = handover, None
        else:  # warm starts from the last solutions, solved as far as the gain's change needs
            equations = _MomentEquations(sys, rec, L, change)
            P_solution, X_solution = equations.solutions(X, P)
        if not equations.stabilizing(P_solution):
            stabilized, status = False, StopStatus.DIVERGED
            break
        P = P_solution.X
        X = (X_solution or equations.second_moments(X)).X
        trace_X.append(np.trace(X, axis1=1, axis2=2))
        trace_P.append(np.trace(P, axis1=1, axis2=2))
        try:
            L_new = rec.gain(X, rec.successor_average(P), 1.0, 1.0, method)
        except np.linalg.LinAlgError:
            status = StopStatus.LINALG_ERROR
            break
        L = L_new
        verdict = rule.status(it, (L,))
        change = rule.change
        if verdict is not None:
            status = verdict
            break
    return IterationRun(
        L=L,
        X=X,
        P=P,
        status=status,
        change=rule.change,
        iterations=it - first + 1,
        stabilized=stabilized,
        trace_X=np.array(trace_X).reshape(-1, sys.M),
        trace_P=np.array(trace_P).reshape(-1, sys.M),
        members=[],
    )


def _inexact_tolerance(change):
    """The relative residual to which the exact iteration solves its moment equations when its
    gain last changed by ``change`` (relative): 1e-2 of it, between ``mjls.solve_tolerance`` and
    ``mjls.inexact_solve_max``. An error of the moments moves the next gain by about as much,
    so the iteration keeps its pace while the gain still moves, and its last steps solve to the
    full tolerance.
    """
    floor = config.defaults["mjls.solve_tolerance"]
    loosest = max(floor, config.defaults["mjls.inexact_solve_max"])
    return float(np.clip(1e-2 * change, floor, loosest))


class _MomentEquations:
    """The moment equations (3.32)-(3.33) of one gain L, solved as far as its last relative
    ``change`` needs (:func:`_inexact_tolerance`; an inexact solve's residual is checked by the
    certificate, not reported as a miss): X = L(X) + predecessor_sum(mu (H H^T + B L J J^T L^T
    B^T)) and P = L*(P) + Q + C^T L^T R L C (the ``weight``).
    """

    def __init__(self, sys, rec, L, change):
        self.sys, self.rec = sys, rec
        self.Acl = closed_loop(sys, L, check=False)
        tol = _inexact_tolerance(change)
        self.solve = coupled_lyapunov_solver(self.Acl, sys.T, tol=tol)
        self.on_miss = "fallback" if tol <= config.defaults["mjls.solve_tolerance"] else "report"
        LC = L @ sys.C
        self.weight = sys.Q + transpose(LC) @ sys.R @ LC
        self.noise = rec.predecessor_sum(rec.noise(L))

    def costates(self, P_guess):
        """The solution P of (3.33) from ``P_guess``."""
        return self.solve(self.weight, adjoint=True, x0=P_guess, on_miss=self.on_miss)

    def second_moments(self, X_guess):
        """The solution X of (3.32) from ``X_guess``."""
        return self.solve(self.noise, x0=X_guess, on_miss=self.on_miss)

    def solutions(self, X_guess, P_guess):
        """(P, X) solutions: both at once on two threads where the recursion runs in parallel
        (:attr:`Recursion.parallel`), else P alone and None (X waits until L is known to
        stabilise).
        """
        if self.rec.parallel:
            return concurrently(lambda: self.costates(P_guess),
                                lambda: self.second_moments(X_guess))
        return self.costates(P_guess), None

    def stabilizing(self, P_solution):
        """The coupled Lyapunov certificate of P (:func:`lyapunov_certified`), else rho < 1
        (Cor. 3.2).
        """
        return (lyapunov_certified(P_solution, self.weight)
                or mean_square_stability(self.Acl, self.sys.T, check=False).rho < 1)


def _stabilizes(sys, rec, L, guess, change):
    """Whether L stabilises, and (its moment equations, the solution P of (3.33), the solution X
    of (3.32) or None unless solved beside P, :meth:`_MomentEquations.solutions`): the coupled
    Lyapunov certificate (:func:`lyapunov_certified`, one solve from the iterate ``guess`` =
    (X, P)), else rho < 1 (Cor. 3.2). The same verdict as rho alone, since a certified P implies
    rho < 1, at the cost of a solve (which the exact iteration continues from) instead of a
    certified spectral radius. The solve goes as far as the gain's last relative ``change`` needs
    (:func:`_inexact_tolerance`); the certificate accounts for its residual.
    """
    equations = _MomentEquations(sys, rec, L, change)
    P_solution, X_solution = equations.solutions(*guess)
    return equations.stabilizing(P_solution), (equations, P_solution, X_solution)


def lyapunov_certified(solution, weight):
    """Whether P of ``solution`` (P = L*(P) + weight, solved to its stated residual) and every
    weight_i are positive definite: then the closed loop is mean-square stable (Costa, Fragoso
    and Marques 2005, Thm. 3.9).

    The solution need not be exact: with E = P - L*(P) - weight, ||E_i||_2 <= ||E||_F =
    residual ||weight||_F, so P solves P = L*(P) + (weight - E) exactly, and weight - E is
    positive definite when the smallest eigenvalue of every weight_i exceeds twice that bound:
    when every weight_i minus twice the bound times I has a Cholesky factor (at n = M = 100 a
    tenth of the time of the eigenvalues).

    Examples
    --------
    >>> W = np.ones((1, 1, 1))
    >>> stable = coupled_lyapunov_solver(np.array([[[0.9]]]), np.eye(1))(W, adjoint=True)
    >>> lyapunov_certified(stable, W)
    True
    """
    margin = 2.0 * solution.residual * np.linalg.norm(weight)
    if not (np.isfinite(margin) and np.all(np.isfinite(solution.X))):
        return False
    def factors(weights, P):                      # raise LinAlgError where one is not definite
        shifted = weights - margin * np.eye(weights.shape[-1])
        return np.linalg.cholesky(shifted), np.linalg.cholesky(P)

    try:
        if in_parallel(weight):
            stacked_in_parts(factors, weight, solution.X)
        else:
            factors(weight, solution.X)
    except np.linalg.LinAlgError:
        return False
    return True
