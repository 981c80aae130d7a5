"""Finite-horizon dynamic output feedback without mode observation (Sec. 3.7, Alg. 3.3).

The time-variant controller (3.55) x^_{k+1} = F_k x^_k + K_k y_k, u_k = L_k x^_k for the
MJLS (3.54) over k = 0..K-1 minimises the bound Jbar_0 (3.65) of the cost (3.56). Each
iteration of Alg. 3.3 runs the bounds Xbar_k, Xunder_k forward ((3.66)-(3.67), Step 2)
with the current gains and then, backwards from k = K - 1, solves (3.70)/(3.71) for the
gains at step k and updates Pbar_k, Punder_k, omega_k ((3.68)-(3.69), Step 6).

The initial state is a Gaussian mixture: given theta_0 = i (probability mu0_i), x_0 has
mean ``mean0[i]`` and covariance ``cov0[i]``. The controller starts at x^_0 = E{x_0} =
sum_i mu0_i mean0[i], so that Xunder_{i,0} = mu0_i x^_0 x^_0^T and
Xbar_{i,0} = mu0_i (cov0[i] + (mean0[i] - x^_0)(mean0[i] - x^_0)^T). This is the
initialisation of Thm. 3.31/Alg. 3.3 Step 2 (Xbar_{i,0} = Xi_0^i, Xunder_{i,0} = xi_0^i
xi_0^i^T, with mu0_i as the factor of the author's reference code, Mxttak/MJLS,
MJLS_ClassMeasurementFeedbackVariantGains.m, PredictXuXl) whenever the mode-conditional
means coincide or mu0 is a unit vector, as in Sec. 3.7.3; otherwise it is the exact
second moment of (x_0 - x^_0, x^_0) without the cross term, the same bound as later steps.

The model over the horizon (:class:`~asoc.mjls.finite_horizon_model.Stages`) and the
validation of the initial state live in :mod:`asoc.mjls.finite_horizon_model`.
"""

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import config
from ..linalg import transpose
from ..progress import progress_bar
from ..result import Status
from ..validation import boolean, choice, integer, real_array, real_scalar
from .controllers import DynamicOutputFeedback
from .design_result import DesignResult
from .dynamic import dynamic_output_feedback
from .finite_horizon_model import check_initial_state, mode_distributions, stages
from .moment_bounds import bound_costate_step, bound_moment_step
from .moments import second_moment_step
from .optimality import METHODS, gains_from_bounds
from .system import successor_average

__all__ = ["FiniteHorizonResult", "initial_bounds", "augmented_initial_moment", "augmented_cost",
           "finite_horizon_cost", "initial_gains", "finite_horizon_dynamic_output_feedback"]


@dataclass(kw_only=True)
class FiniteHorizonResult(DesignResult):
    """Result of Algorithm 3.3 (:func:`finite_horizon_dynamic_output_feedback`).

    Attributes
    ----------
    F, K, L : numpy.ndarray, shapes (horizon, nx, nx), (horizon, nx, ny), (horizon, nu, nx)
        The gains of (3.55) for k = 0..horizon-1.
    xhat0 : numpy.ndarray, shape (nx,)
        The controller's initial state E{x_0}.
    cost_bounds : numpy.ndarray
        Jbar_0 (3.72) after each iteration (Thm. 3.33: non-increasing).
    converged, status, message
        Whether and why the iteration stopped (:class:`asoc.result.IterativeResult`):
        ``"converged"``, ``"max_iterations"`` or ``"diverged"`` (Jbar_0 became non-finite).
    iterations : int
    cost : float
        The true expected cost (3.56) of the final gains, from the exact augmented
        second-moment recursion (3.58).
    Xbar, Xunder, Pbar, Punder : numpy.ndarray, shape (horizon + 1, M, nx, nx)
        The bounds of the last iteration.
    rejected : int
        Number of step updates Step 5 rejected in the last iteration.
    seconds : float
        Wall time.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = finite_horizon_dynamic_output_feedback(sys, 5, SEC373_MEAN0[1], SEC373_COV0,
    ...                                              SEC373_MU0)
    >>> res.status, res.Xbar.shape, res.controller.time_variant
    ('converged', (6, 2, 2, 2), True)
    """

    controller_type = DynamicOutputFeedback
    controller_fields = ("F", "K", "L", "xhat0")

    F: np.ndarray
    K: np.ndarray
    L: np.ndarray
    xhat0: np.ndarray
    cost_bounds: np.ndarray
    iterations: int
    cost: float
    Xbar: np.ndarray = field(repr=False)
    Xunder: np.ndarray = field(repr=False)
    Pbar: np.ndarray = field(repr=False)
    Punder: np.ndarray = field(repr=False)
    rejected: int = 0
    seconds: float = 0.0


def initial_bounds(mean0, cov0, mu0):
    """x^_0 = E{x_0} and the bounds Xbar_{i,0}, Xunder_{i,0} (Thm. 3.31, Alg. 3.3 Step 2).

    Examples
    --------
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> xhat0, Xbar0, Xunder0 = initial_bounds(SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0)
    >>> xhat0.tolist(), float(Xunder0[0, 0, 0])
    ([5.0, 0.0], 25.0)
    """
    xhat0 = mu0 @ mean0
    dev = mean0 - xhat0
    m = mu0[:, None, None]
    Xbar0 = m * (cov0 + np.einsum("ia,ib->iab", dev, dev))
    Xunder0 = m * np.outer(xhat0, xhat0)
    return xhat0, Xbar0, Xunder0


def augmented_initial_moment(mean0, cov0, mu0, xhat0):
    """X~_0^i = E{[x_0; x^_0][x_0; x^_0]^T 1(theta_0 = i)} for a constant x^_0 = xhat0.

    Examples
    --------
    >>> X0 = augmented_initial_moment(np.array([[1.0]]), np.zeros((1, 1, 1)), np.array([1.0]),
    ...                               np.array([1.0]))
    >>> X0.tolist()
    [[[1.0, 1.0], [1.0, 1.0]]]
    """
    M, nx = mean0.shape
    nc = xhat0.size
    X0 = np.zeros((M, nx + nc, nx + nc))
    X0[:, :nx, :nx] = cov0 + np.einsum("ia,ib->iab", mean0, mean0)
    X0[:, :nx, nx:] = np.einsum("ia,b->iab", mean0, xhat0)
    X0[:, nx:, :nx] = transpose(X0[:, :nx, nx:])
    X0[:, nx:, nx:] = np.outer(xhat0, xhat0)
    return mu0[:, None, None] * X0


def augmented_cost(Acl, HHt_cl, Qcl, Q_final, Ts, X0, mu0):
    """Exact expected cost of a time-variant MJLS closed loop over K steps (3.57)-(3.58).

    Acl, HHt_cl, Qcl: sequences of K stacks (M, n, n) (mode-dependent, e.g. the augmented
    closed loop (3.59)-(3.60)); Q_final (M, n, n); Ts: K transition matrices; X0 (M, n, n):
    E{x~_0 x~_0^T 1(theta_0 = i)}. Returns
    sum_k sum_i tr[Q~_{i,k} X~_k^i] + sum_i tr[Q~_{i,K} X~_K^i].

    Examples
    --------
    >>> A = [np.array([[[0.5]]])] * 2
    >>> ones = np.ones((1, 1, 1))
    >>> cost = augmented_cost(A, [ones] * 2, [ones] * 2, ones, [np.ones((1, 1))] * 2, ones,
    ...                       np.array([1.0]))
    >>> round(cost, 4)
    3.5625
    """
    X, mu = X0, np.asarray(mu0, dtype=float)
    cost = 0.0
    for A, HH, Q, T in zip(Acl, HHt_cl, Qcl, Ts):
        cost += float(np.einsum("iab,iba->", Q, X))
        X = second_moment_step(A, HH, T, X, mu)
        mu = mu @ T
    return cost + float(np.einsum("iab,iba->", Q_final, X))


def finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0=None):
    """True expected cost (3.56) of the time-variant controller (3.55), by the recursion (3.58).

    Parameters
    ----------
    sys : MJLS or sequence of MJLS
        As in :func:`finite_horizon_dynamic_output_feedback`.
    F, K, L : array_like, shapes (horizon, nc, nc), (horizon, nc, ny), (horizon, nu, nc)
        Gains per step; the horizon is their length.
    mean0, cov0 : array_like, shapes (M, nx) and (M, nx, nx)
        Mean and covariance of x_0 given theta_0 = i.
    mu0 : array_like, shape (M,)
        Distribution of theta_0.
    xhat0 : array_like, shape (nc,), optional
        Controller initial state; default E{x_0}.

    Returns
    -------
    float
        E{sum_{k<K} (x_k^T Q x_k + u_k^T R u_k) + x_K^T Q_K x_K}.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS (sequence) or an array is not real.
    ValueError
        If the gains, the initial state or ``sys`` are invalid (see
        :func:`finite_horizon_dynamic_output_feedback`).

    Examples
    --------
    Alg. 3.2's time-invariant controller used for 10 steps of the example of Sec. 3.7.3:

    >>> from asoc.mjls import dynamic_output_feedback
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> sys = sec373_system(1)
    >>> r = dynamic_output_feedback(sys)
    >>> gains = [np.broadcast_to(g, (10,) + g.shape) for g in (r.F, r.K, r.L)]
    >>> round(finite_horizon_cost(sys, *gains, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0), 2)
    211.71
    """
    F = real_array(F, "F", ndim=3)
    horizon, nc = F.shape[0], F.shape[1]
    st = stages(sys, horizon)
    s0 = st.systems[0]
    F = real_array(F, "F", shape=(horizon, nc, nc))
    K = real_array(K, "K", shape=(horizon, nc, s0.ny))
    L = real_array(L, "L", shape=(horizon, s0.nu, nc))
    mean0, cov0, mu0 = check_initial_state(s0.M, s0.nx, mean0, cov0, mu0)
    xhat0 = mu0 @ mean0 if xhat0 is None else real_array(xhat0, "xhat0", shape=(nc,))
    nx = s0.nx
    Acl, HHcl, Qcl = [], [], []
    for k, s in enumerate(st.systems):
        A = np.zeros((s.M, nx + nc, nx + nc))
        A[:, :nx, :nx], A[:, :nx, nx:] = s.A, s.B @ L[k]
        A[:, nx:, :nx], A[:, nx:, nx:] = K[k] @ s.C, F[k]
        HH = np.zeros_like(A)
        HH[:, :nx, :nx], HH[:, nx:, nx:] = st.HHt[k], K[k] @ st.JJt[k] @ K[k].T
        Q = np.zeros_like(A)
        Q[:, :nx, :nx], Q[:, nx:, nx:] = s.Q, L[k].T @ s.R @ L[k]
        Acl.append(A), HHcl.append(HH), Qcl.append(Q)
    Q_final = np.zeros_like(Acl[0])
    Q_final[:, :nx, :nx] = st.Q_final
    X0 = augmented_initial_moment(mean0, cov0, mu0, np.asarray(xhat0, dtype=float))
    return augmented_cost(Acl, HHcl, Qcl, Q_final, [s.T for s in st.systems], X0, mu0)


def _bound_to_go(s, F, K, L, Xbar, Xunder, EPbar, EPunder, Eomega, mu, HHt, JJt):
    """Pbar_k, Punder_k (3.68)-(3.69), omega_k and Jbar_k (3.72) for the gains at step k."""
    Pbar, Punder = bound_costate_step(s, F, K, L, EPbar, EPunder)
    omega = (np.einsum("iab,iba->i", EPbar + EPunder, HHt)
             + np.einsum("iab,iba->i", EPunder, K @ JJt @ K.T) + Eomega)
    J = float(np.einsum("iab,iba->", Pbar, Xbar + Xunder) + np.einsum("iab,iba->", Punder, Xbar)
              + mu @ omega)
    return Pbar, Punder, omega, J


def initial_gains(init, st, nx, ny, nu):
    """Step 1: the initial gain sequence (see :func:`finite_horizon_dynamic_output_feedback`).

    ``init``: None (Alg. 3.2's controller), a Generator (uniform random gains), a result
    with F, K, L or a tuple (F, K, L), constant or per step; returns (F, K, L) per step.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> st = stages(sec373_system(1), 3)
    >>> F, K, L = initial_gains((np.eye(2), np.ones((2, 1)), np.ones((1, 2))), st, 2, 1, 1)
    >>> F.shape, K.shape, L.shape
    ((3, 2, 2), (3, 2, 1), (3, 1, 2))
    """
    horizon = st.horizon
    if init is None:
        init = dynamic_output_feedback(st.systems[0], warn=False)
    elif isinstance(init, np.random.Generator):
        return (init.random((horizon, nx, nx)) - 0.5, init.random((horizon, nx, ny)) - 0.5,
                init.random((horizon, nu, nx)) - 0.5)
    if all(hasattr(init, g) for g in "FKL"):
        init = (init.F, init.K, init.L)
    if not (isinstance(init, (tuple, list)) and len(init) == 3):
        raise TypeError("init: expected None, a Generator, a result with F, K, L or a tuple "
                        f"(F, K, L), found {type(init).__name__}")
    out = []
    for name, g, shape in (("F", init[0], (nx, nx)), ("K", init[1], (nx, ny)),
                           ("L", init[2], (nu, nx))):
        g = real_array(g, f"init {name}")
        if g.shape == shape:
            g = np.broadcast_to(g, (horizon,) + shape)
        if g.shape != (horizon,) + shape:
            raise ValueError(f"init {name}: expected shape {shape} or {(horizon,) + shape}, "
                             f"found {g.shape}")
        out.append(g.copy())
    return tuple(out)


@config.accepts_settings("mjls.rank_rtol", "mjls.matrix_free_min_unknowns", "mjls.cg_tolerance")
def finite_horizon_dynamic_output_feedback(sys, horizon=100, mean0=None, cov0=None, mu0=None,
                                           init=None, tol=1e-9, max_iter=500, method="lstsq",
                                           safeguard=True, warn=True, progress=False):
    """Algorithm 3.3: the time-variant controller (3.55) for the MJLS (3.54), mode not observed.

    Parameters
    ----------
    sys : MJLS or sequence of MJLS
        One MJLS, or ``horizon`` (or ``horizon + 1``, the last giving Q_K) MJLS for
        time-variant system matrices (3.54).
    horizon : int
        Number of steps, >= 1.
    mean0, cov0 : array_like, shapes (M, nx) and (M, nx, nx)
        Mean and covariance of x_0 given theta_0 = i.
    mu0 : array_like, shape (M,)
        Distribution of theta_0.
    init : None, numpy.random.Generator, DynamicOutputFeedbackResult or tuple (F, K, L)
        Initial gains (Step 1, "an arbitrary sequence"). None: the time-invariant
        controller of Alg. 3.2 for the (first-step) system, as the author's simulation of
        Sec. 3.7.3 passes it to the time-variant design (Mxttak/MJLS,
        sim_MJLS_ClassMeasurementFeedbackVariantGains.m); a Generator: entries uniform in
        [-0.5, 0.5) as in the author's MJLS_ClassMeasurementFeedbackVariantGains.m; or a
        result of :func:`dynamic_output_feedback` / a tuple (F, K, L), constant or per step.
        All-zero gains are a fixed point of the iteration (Xunder_k = 0 for k >= 1 makes
        (3.71) leave F_k, L_k at their minimum-norm value 0, and then Punder_k = 0 leaves K_k
        at 0), so they are a poor start.
    tol : float
        Stop (Step 7) when Jbar_0 changed by less than ``tol * max(1, Jbar_0)``.
    max_iter : int
        Iteration limit; ``converged=False`` and a warning when reached.
    method : {"lstsq", "sdp"}
        Minimum-norm solution of (3.71) (the QP (3.73)) or the SDP.
    safeguard : bool
        Step 5: keep the previous gains at step k when the new ones increase the
        bounded cost-to-go Jbar_k (3.72) (evaluated for both with the same Xbar_k, Xunder_k
        and P_{k+1}). The author's reference code always accepts (safeguard=False).
    warn : bool
        Warn (RuntimeWarning) on non-convergence and when Jbar_0 increases (contradicting
        Thm. 3.33).
    progress : bool
        Show a tqdm bar over iterations.

    Returns
    -------
    FiniteHorizonResult

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS (sequence), ``horizon`` or ``max_iter`` is not an integer,
        a flag is not a bool, or ``init`` has the wrong type.
    ValueError
        If ``horizon``, ``tol``, ``max_iter``, ``method``, the initial state (``mean0``,
        ``cov0``, ``mu0``) or the shapes of ``init`` are invalid, or ``sys`` is not an MJLS
        (sequence) of consistent dimensions.

    Examples
    --------
    The example of Sec. 3.7.3 (T[1], xi_0[1]) over 20 steps:

    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = finite_horizon_dynamic_output_feedback(sec373_system(1), 20, SEC373_MEAN0[1],
    ...                                              SEC373_COV0, SEC373_MU0)
    >>> res.status, res.F.shape, round(res.cost, 2)
    ('converged', (20, 2, 2), 308.22)
    """
    start = time.perf_counter()
    st = stages(sys, horizon)
    K_ = st.horizon
    s0 = st.systems[0]
    M, nx, nu, ny = s0.M, s0.nx, s0.nu, s0.ny
    mean0, cov0, mu0 = check_initial_state(M, nx, mean0, cov0, mu0)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    choice(method, "method", METHODS)
    safeguard, warn, progress = (boolean(v, n) for v, n in ((safeguard, "safeguard"),
                                                            (warn, "warn"), (progress, "progress")))
    F, K, L = initial_gains(init, st, nx, ny, nu)
    xhat0, Xbar0, Xunder0 = initial_bounds(mean0, cov0, mu0)
    mu = mode_distributions(st, mu0)
    Xbar = np.empty((K_ + 1, M, nx, nx))
    Xunder = np.empty_like(Xbar)
    Pbar = np.empty_like(Xbar)
    Punder = np.empty_like(Xbar)
    Xbar[0], Xunder[0] = Xbar0, Xunder0
    bounds = []
    status = Status.MAX_ITERATIONS
    rejected = 0
    it = 0

    for it in progress_bar(range(1, int(max_iter) + 1), progress, desc="Alg. 3.3", leave=False):
        for k, s in enumerate(st.systems):                                    # Step 2
            Xbar[k + 1], Xunder[k + 1] = bound_moment_step(s, F[k], K[k], L[k], Xbar[k], Xunder[k],
                                                           mu[k], st.HHt[k], st.JJt[k])
        Pbar[K_], Punder[K_] = st.Q_final, 0.0                               # Step 3
        omega = np.zeros(M)
        rejected = 0
        for k in range(K_ - 1, -1, -1):                                      # Steps 4-6
            s = st.systems[k]
            EPbar = successor_average(s.T, Pbar[k + 1], check=False)
            EPunder = successor_average(s.T, Punder[k + 1], check=False)
            Eomega = s.T @ omega
            args = (Xbar[k], Xunder[k], EPbar, EPunder, Eomega, mu[k], st.HHt[k], st.JJt[k])
            Fn, Kn, Ln = gains_from_bounds(s, Xbar[k], Xunder[k], EPbar, EPunder, mu[k],
                                           st.JJt[k], method)
            new = _bound_to_go(s, Fn, Kn, Ln, *args)
            if safeguard and it > 1:
                old = _bound_to_go(s, F[k], K[k], L[k], *args)
                if old[3] < new[3] - 1e-12 * abs(new[3]):
                    rejected += 1
                    Pbar[k], Punder[k], omega = old[:3]
                    continue
            F[k], K[k], L[k] = Fn, Kn, Ln
            Pbar[k], Punder[k], omega = new[:3]
        J0 = float(np.einsum("iab,iba->", Pbar[0], Xbar[0] + Xunder[0])
                   + np.einsum("iab,iba->", Punder[0], Xbar[0]) + mu0 @ omega)   # Step 7, (3.72)
        if not np.isfinite(J0):
            status = Status.DIVERGED
            break
        bounds.append(J0)
        if len(bounds) > 1 and abs(bounds[-2] - J0) <= tol * max(1.0, abs(J0)):
            status = Status.CONVERGED
            break
    bounds = np.array(bounds)
    seconds = time.perf_counter() - start
    change = (abs(bounds[-1] - bounds[-2]) / max(1.0, abs(bounds[-1])) if len(bounds) > 1
              else np.inf)
    message = {"converged": f"converged after {it} iterations "
                            f"(change of Jbar_0 {change:.2g} <= tol = {tol:.2g})",
               "max_iterations": f"did not converge within {it} iterations "
                                 f"(change of Jbar_0 {change:.2g} > tol = {tol:.2g})",
               "diverged": f"stopped at iteration {it}: the bound Jbar_0 became non-finite"}[status]
    if warn and status is not Status.CONVERGED:
        warnings.warn(f"Algorithm 3.3 {message}", RuntimeWarning, stacklevel=2)
    increases = np.diff(bounds) > 1e-8 * np.maximum(1.0, np.abs(bounds[1:]))   # beyond rounding
    if warn and np.any(increases):
        warnings.warn(f"Algorithm 3.3: Jbar_0 increased in {int(increases.sum())} iterations "
                      "(Thm. 3.33 asserts a non-increasing sequence)", RuntimeWarning, stacklevel=2)
    cost = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0)
    return FiniteHorizonResult(F=F, K=K, L=L, xhat0=xhat0, cost_bounds=bounds,
                               converged=status is Status.CONVERGED, status=status, message=message,
                               iterations=it, cost=cost, Xbar=Xbar, Xunder=Xunder, Pbar=Pbar,
                               Punder=Punder, rejected=rejected, seconds=seconds)
