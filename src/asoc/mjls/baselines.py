"""Baselines of Table 3.2 for control without mode observation.

[52] J. B. R. do Val, J. C. Geromel, A. P. C. Goncalves, "The H2-control for jump linear
     systems: cluster observations of the Markov state", Automatica 38(2):343-349, 2002:
     H2 state feedback u = K x by an LMI, here with the cluster of observed modes empty.
[165] A. N. Vargas, E. F. Costa, J. B. R. do Val, "On the control of Markov jump linear
     systems with no mode observation: application to a DC motor device", Int. J. Robust
     Nonlinear Control 23(10):1136-1150, 2013: finite-horizon time-variant state feedback
     u_k = G_k x_k from the necessary optimality condition, solved by their variational
     (coordinate-descent) method, which decreases the cost monotonically.
[163] A. N. Vargas, L. Acho, G. Pujol, E. F. Costa, J. Y. Ishihara, J. B. R. do Val, "Output
     feedback of Markov jump linear systems with no mode observation: an automotive
     throttle application", Int. J. Robust Nonlinear Control, 2015: the same method for
     static output feedback u_k = G_k y_k.

The papers' full texts were not available to this project; the equations used are the
necessary conditions derived from the model (as in the papers' abstracts and in the
thesis's Secs. 3.4-3.5) and are stated in each docstring.
"""

import time
import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from ..linalg import kronecker_sum
from ..validation import boolean, integer, probability_vector, real_array, real_scalar, semidefinite
from .controllers import TimeVariantGain
from .design_result import DesignResult
from .lmi import EPS, certificate, check_solver, lmi_result, performance_output, solve_quietly
from .stability import mean_square_stability
from .system import check_system

__all__ = ["do_val_h2_state_feedback", "TimeVariantResult", "time_variant_feedback"]


def do_val_h2_state_feedback(sys, eps=EPS, solver="CLARABEL"):
    """[52] with an empty observed cluster: one mode-independent state-feedback gain K.

    minimise sum_i tr W_i over W_i, Y_i = Y_i^T, G, F subject to, for every mode i,

        [[W_i, D_i G + E_i F], [*, G + G^T - Xbar_i]] > 0,
        [[Y_i - mu_i H_i H_i^T, A_i G + B_i F], [*, G + G^T - Xbar_i]] > 0,

    with Xbar_i = sum_j p_ji Y_j; K = F G^{-1}. Using G^T Xbar^{-1} G >= G + G^T - Xbar, the
    optimum bounds the H2 cost sum_i tr((Q_i + K^T R_i K) X_i) of the closed loop from above.

    Parameters
    ----------
    sys : MJLS
        The state-feedback model (C_i is not used: u = K x).
    eps : float
        Margin of the strict inequalities (>= eps I), > 0.
    solver : str
        An installed cvxpy solver.

    Returns
    -------
    LMIResult
        The gain K (nu, nx) in ``L``; feasible when the solver is optimal and K stabilises.

    Raises
    ------
    TypeError, ValueError
        For a sys that is not an MJLS, eps <= 0 or an unknown solver.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = do_val_h2_state_feedback(sec354_system(1, "state"))
    >>> res.feasible, res.L.shape
    (True, (1, 2))
    """
    check_system(sys)
    eps = real_scalar(eps, "eps", low=0, low_open=True)
    check_solver(solver)
    M_, nx, nu = sys.M, sys.nx, sys.nu
    D, E = performance_output(sys)
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    mu = sys.mu_inf
    G = cp.Variable((nx, nx))
    F = cp.Variable((nu, nx))
    W = [cp.Variable((nx + nu, nx + nu), symmetric=True) for _ in range(M_)]
    Y = [cp.Variable((nx, nx), symmetric=True) for _ in range(M_)]
    cons = []
    for i in range(M_):
        Xbar = sum(sys.T[j, i] * Y[j] for j in range(M_))
        corner = G + G.T - Xbar
        top = D[i] @ G + E[i] @ F
        mid = sys.A[i] @ G + sys.B[i] @ F
        lmi1 = cp.bmat([[W[i], top], [top.T, corner]])
        lmi2 = cp.bmat([[Y[i] - mu[i] * HHt[i], mid], [mid.T, corner]])
        cons += [0.5 * (lmi1 + lmi1.T) >> eps * np.eye(2 * nx + nu),
                 0.5 * (lmi2 + lmi2.T) >> eps * np.eye(2 * nx), Y[i] >> eps * np.eye(nx)]
    prob = cp.Problem(cp.Minimize(sum(cp.trace(Wi) for Wi in W)), cons)
    status = solve_quietly(prob, solver)
    if G.value is None or F.value is None:
        return lmi_result(status)
    K = F.value @ np.linalg.inv(G.value)
    margin, equality_residual = certificate(cons)
    return lmi_result(status, K, float(prob.value), margin=margin,
                      equality_residual=equality_residual, eps=eps,
                      stability=mean_square_stability(sys.A + sys.B @ K, sys.T, check=False))


@dataclass(kw_only=True)
class TimeVariantResult(DesignResult):
    """Result of :func:`time_variant_feedback` ([163], [165]).

    Attributes
    ----------
    G : numpy.ndarray, shape (horizon, nu, ny)
        The gain sequence.
    costs : numpy.ndarray
        J(G) after each sweep (non-increasing).
    converged, status, message
        Why the sweeps stopped: ``"converged"``, ``"max_iterations"`` or ``"diverged"``
        (the cost became non-finite).
    iterations : int
    seconds : float
    controller : TimeVariantGain
        u_k = G_k y_k, for :func:`asoc.mjls.simulate`
        (:class:`asoc.mjls.design_result.DesignResult`).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = time_variant_feedback(sec354_system(1, "state"), 5, [3.0, 0.0])
    >>> res.status, res.G.shape, res.controller
    ('converged', (5, 1, 2), TimeVariantGain(horizon=5, nu=1, ny=2))
    """

    controller_type = TimeVariantGain
    controller_fields = ("G",)

    G: np.ndarray
    costs: np.ndarray
    iterations: int
    seconds: float


def _forward_moments(sys, G, X0, mu0):
    """X_j(k+1) = sum_i p_ij [(A_i + B_i G_k C_i) X_i(k) (.)^T + pi_i(k) H_i H_i^T]; pi(k)."""
    K = len(G)
    X = np.empty((K + 1,) + X0.shape)
    pi = np.empty((K + 1, sys.M))
    X[0], pi[0] = X0, mu0
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    for k in range(K):
        Acl = sys.A + sys.B @ G[k] @ sys.C
        moment = Acl @ X[k] @ np.swapaxes(Acl, 1, 2) + pi[k][:, None, None] * HHt
        X[k + 1] = sys.predecessor_sum(moment)
        pi[k + 1] = pi[k] @ sys.T
    return X, pi


def _gain(sys, X, EL):
    """G solving sum_i (R_i + B_i^T EL_i B_i) G C_i X_i C_i^T = -sum_i B_i^T EL_i A_i X_i C_i^T.

    Least squares (minimum norm) where the second moments are singular (e.g. x_0 = 0), in
    which case the gain does not influence the cost.
    """
    BT = np.swapaxes(sys.B, 1, 2)
    S = sys.R + BT @ EL @ sys.B
    W = sys.C @ X @ np.swapaxes(sys.C, 1, 2)
    N = (BT @ EL @ sys.A @ X @ np.swapaxes(sys.C, 1, 2)).sum(axis=0)
    vec, *_ = np.linalg.lstsq(kronecker_sum(W, S), -N.reshape(-1, order="F"), rcond=1e-12)
    return vec.reshape(S.shape[1], W.shape[1], order="F")


def _backward_sweep(sys, G, X, pi):
    """Update G_{K-1}, ..., G_0 in turn (coordinate descent); return new G and the cost."""
    K = len(G)
    G = G.copy()
    L = sys.Q.copy()                                  # L_i(K) = Q_i (terminal weight of (3.3))
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    noise = 0.0
    for k in range(K - 1, -1, -1):
        EL = sys.successor_average(L)
        G[k] = _gain(sys, X[k], EL)
        Acl = sys.A + sys.B @ G[k] @ sys.C
        GC = G[k] @ sys.C
        noise += float(np.einsum("i,iab,iba->", pi[k], EL, HHt))
        L = sys.Q + np.swapaxes(GC, 1, 2) @ sys.R @ GC + np.swapaxes(Acl, 1, 2) @ EL @ Acl
    return G, float(np.einsum("iab,iba->", L, X[0])) + noise


def time_variant_feedback(sys, horizon, x0, mu0=None, x0_cov=None, G0=None, tol=1e-10,
                          max_iter=500, warn=True):
    """[163] (u_k = G_k y_k), and [165] when C_i = I: the variational method.

    Minimises the finite-horizon cost (3.3) with noise, J(G) = <L(0), X(0)> +
    sum_k sum_i pi_i(k) tr(H_i^T E_i(L(k+1)) H_i), over gain sequences G_0..G_{K-1}, where
    X_i(k) = E{x_k x_k^T 1(theta_k = i)} runs forward and L_i(k) = Q_i + C_i^T G_k^T R_i G_k C_i
    + (A_i + B_i G_k C_i)^T E_i(L(k+1)) (A_i + B_i G_k C_i) backward from L_i(K) = Q_i.
    Each sweep computes X(k) with the current gains, then updates G_k from k = K-1 down to 0
    by the necessary condition (the gain minimising J with the other gains fixed), so the
    cost never increases. Stops when the relative decrease is below ``tol``.

    Parameters
    ----------
    horizon : int >= 1.
    x0 : (nx,) known initial state; ``x0_cov`` an optional (nx, nx) covariance.
    mu0 : initial mode distribution (default stationary).
    G0 : initial gain sequence (horizon, nu, ny), default zeros (the thesis suggests Alg. 3.1's
        gain as a faster start, Sec. 3.5.4).
    tol : stop when the relative decrease of J is below tol (> 0).
    max_iter : sweep limit.
    warn : warn when the sweeps do not converge.

    Returns
    -------
    TimeVariantResult

    Raises
    ------
    TypeError
        For a sys that is not an MJLS, a non-integer horizon or max_iter, a non-bool warn or a
        non-real array.
    ValueError
        For horizon or max_iter < 1, tol <= 0, or x0, mu0, x0_cov, G0 of the wrong shape or
        invalid (non-finite, x0_cov not positive semidefinite).

    Examples
    --------
    [165] on the state-feedback example of Sec. 3.5.4 over 20 steps from x0 = [3, 0]:

    >>> from asoc.mjls.examples import sec354_system
    >>> res = time_variant_feedback(sec354_system(1, "state"), 20, [3.0, 0.0])
    >>> res.status, res.G.shape, bool(res.costs[-1] <= res.costs[0])
    ('converged', (20, 1, 2), True)
    """
    check_system(sys)
    K = integer(horizon, "horizon", minimum=1)
    x0 = real_array(x0, "x0", shape=(sys.nx,))
    mu0 = sys.mu_inf if mu0 is None else probability_vector(mu0, "mu0", sys.M)
    if x0_cov is not None:
        x0_cov = semidefinite(real_array(x0_cov, "x0_cov", shape=(sys.nx, sys.nx)), "x0_cov")
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn = boolean(warn, "warn")
    second = np.outer(x0, x0) + (0 if x0_cov is None else x0_cov)
    X0 = mu0[:, None, None] * second
    shape = (K, sys.nu, sys.ny)
    G = np.zeros(shape) if G0 is None else real_array(G0, "G0", shape=shape)
    start = time.perf_counter()
    costs, status = [], "max_iterations"
    for it in range(1, max_iter + 1):
        X, pi = _forward_moments(sys, G, X0, mu0)
        G, J = _backward_sweep(sys, G, X, pi)
        costs.append(J)
        if not np.isfinite(J):
            status = "diverged"
            break
        if it > 1 and costs[-2] - J <= tol * abs(J):
            status = "converged"
            break
    decrease = (costs[-2] - costs[-1]) / abs(costs[-1]) if len(costs) > 1 else np.inf
    message = {"converged": f"converged after {it} sweeps "
                            f"(relative decrease {decrease:.2g} <= tol = {tol:.2g})",
               "max_iterations": f"did not converge in {it} sweeps "
                                 f"(relative decrease {decrease:.2g} > tol = {tol:.2g})",
               "diverged": f"stopped at sweep {it}: the cost became non-finite"}[status]
    if warn and status != "converged":
        warnings.warn(f"variational method {message}", RuntimeWarning, stacklevel=2)
    return TimeVariantResult(G=G, costs=np.array(costs), converged=status == "converged",
                             status=status, message=message, iterations=it,
                             seconds=time.perf_counter() - start)
