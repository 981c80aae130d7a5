"""The competitor [159]: belief-space iterative LQG with EKF beliefs.

J. van den Berg, S. Patil and R. Alterovitz, "Motion planning under uncertainty using
iterative local optimization in belief space", Int. J. Robotics Research 31(11), 2012.
Implemented from the paper's algorithm (its Sec. 4, belief dynamics, and Sec. 5,
iterative LQG in belief space); its published description was found with the project's
search tool (e.g. the authors' project page robotics.cs.unc.edu/BeliefSpacePlanning and
public re-implementations citing "Section 4.1 of Van Den Berg et al. IJRR 2012").

* Belief b = (mean, vec of the lower triangle of the principal square root of the
  covariance), dimension n + n(n+1)/2.
* Belief dynamics from the EKF (paper Sec. 4.1): b_{t+1} = g(b_t, u_t) + W(b_t, u_t) xi,
  xi ~ N(0, I), with g = (a(mean, u, 0), vec sqrt(Gamma - K H Gamma)), Gamma = A Sigma A^T
  + M M^T, K = Gamma H^T (H Gamma H^T + N N^T)^{-1}, and W = (sqrt(K H Gamma), 0).
* iLQG (paper Sec. 5): linearise g and the columns w_i of W about the nominal belief
  trajectory (derivatives by numdifftools), quadratise the cost in (b, u), run the
  Riccati-like backward recursion with the noise terms sum_i F_i^T S F_i ..., the policy
  u = u_bar + L (b - b_bar) + eps l, and a forward pass with eps halved until the cost of
  the new nominal trajectory decreases.
* Cost: the example's cost written in the belief as in (2.20),
  c(b, u) = E{C_k(x, u)} = (m - x_T)^T Q (m - x_T) + tr(Q Sigma) + u^T R u.
"""

import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from ..result import IterativeResult
from .ekf import ekf_gain, ekf_predict, ekf_step
from .filters import checked_estimate
from .models import NonlinearModel, cost_for

__all__ = ["belief_vector", "belief_mean_and_root", "BeliefDynamics", "BeliefILQGResult",
           "belief_ilqg", "BeliefAffineController"]


def _tril_indices(n):
    """Lower-triangle entries stacked column by column (i >= j)."""
    return [(i, j) for j in range(n) for i in range(j, n)]


@lru_cache
def _tril_index_arrays(n):
    """Row and column indices of ``_tril_indices`` as read-only integer arrays."""
    rows, cols = np.array(_tril_indices(n)).T
    rows.flags.writeable = cols.flags.writeable = False
    return rows, cols


def _duplication(n):
    """D with vec(A) = D vech(A) for symmetric A (our vech order: columns of the lower triangle)."""
    idx = _tril_indices(n)
    D = np.zeros((n * n, len(idx)))
    for c, (i, j) in enumerate(idx):
        D[i + n * j, c] = D[j + n * i, c] = 1.0
    return D


def _psd_sqrt(M):
    """Principal square root of a batch of symmetric PSD matrices."""
    lam, vec = np.linalg.eigh(0.5 * (M + M.swapaxes(-1, -2)))
    return (vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]) @ vec.swapaxes(-1, -2)


def belief_vector(mean, cov):
    """B = (mean, vech(sqrt(cov))), broadcasting over leading axes.

    Parameters
    ----------
    mean : array_like, (..., n)
    cov : array_like, (..., n, n)

    Returns
    -------
    numpy.ndarray, (..., n + n (n + 1) / 2)

    Raises
    ------
    ValueError, TypeError
        If the shapes do not match or ``cov`` is not positive semi-definite.

    Examples
    --------
    >>> belief_vector([1.0, 2.0], [[4.0, 0.0], [0.0, 9.0]]).tolist()
    [1.0, 2.0, 2.0, 0.0, 3.0]
    """
    mean, cov = checked_estimate(mean, cov, "mean", "cov")
    return _belief_vector(mean, cov)


def _belief_vector(mean, cov):
    n = np.shape(mean)[-1]
    root = _psd_sqrt(np.asarray(cov, dtype=float))
    i, j = _tril_index_arrays(n)
    mean, tril = np.asarray(mean, dtype=float), root[..., i, j]
    if mean.shape[:-1] != tril.shape[:-1]:
        batch = np.broadcast_shapes(mean.shape[:-1], tril.shape[:-1])
        mean = np.broadcast_to(mean, batch + mean.shape[-1:])
        tril = np.broadcast_to(tril, batch + tril.shape[-1:])
    return np.concatenate([mean, tril], axis=-1)


def belief_mean_and_root(b, n):
    """(mean, sqrt(cov)) from a belief vector b = (mean, vech(sqrt(cov))) of [159] (the inverse of
    :func:`belief_vector`).

    Examples
    --------
    >>> mean, root = belief_mean_and_root(belief_vector([1.0, 2.0], [[4.0, 0.0], [0.0, 9.0]]), 2)
    >>> mean.tolist(), root.tolist()
    ([1.0, 2.0], [[2.0, 0.0], [0.0, 3.0]])
    """
    b = np.asarray(b, dtype=float)
    root = np.zeros(b.shape[:-1] + (n, n))
    i, j = _tril_index_arrays(n)
    root[..., i, j] = b[..., n:]
    root[..., j, i] = b[..., n:]
    return b[..., :n], root


class BeliefDynamics:
    """g(b, u) and W(b, u) of the EKF belief dynamics ([159], Sec. 4.1).

    Parameters
    ----------
    model : NonlinearModel

    Raises
    ------
    TypeError
        If ``model`` is not a NonlinearModel.

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> dyn = BeliefDynamics(linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]]))
    >>> g, W = dyn(belief_vector([0.0], [[1.0]]), [0.0])
    >>> g.round(4).tolist(), W.round(4).tolist()
    ([0.0, 0.8165], [[1.1547], [0.0]])
    """

    def __init__(self, model):
        self.model = check.instance(model, NonlinearModel, "model")
        self.n = model.n_x

    def __call__(self, b, u):
        """(g(b, u), W(b, u))."""
        n = self.n
        b = check.real_array(b, "b", shape=(n + n * (n + 1) // 2,))
        u = check.real_array(u, "u", shape=(self.model.n_u,))
        return self._dynamics(b, u)

    def _dynamics(self, b, u):
        mean, root = belief_mean_and_root(b, self.n)
        mean_p, Gamma = ekf_predict(self.model, mean, root @ root, np.asarray(u, dtype=float))
        _, K, S, post = ekf_gain(self.model, mean_p, Gamma)
        # principal root of K H Gamma = (K S^1/2)(K S^1/2)^T from the thin SVD of K S^1/2
        U, sv, _ = np.linalg.svd(K @ _psd_sqrt(S), full_matrices=False)
        W_mean = (U * sv) @ U.T
        W = np.zeros((b.shape[-1], self.n))
        W[: self.n] = W_mean
        return _belief_vector(mean_p, post), W


@dataclass(kw_only=True)
class BeliefILQGResult(IterativeResult):
    """Result of the belief-space iLQG [159]: nominal b_bar (K+1, l), u_bar (K, n_u),
    gains L (K, n_u, l), cost history of the nominal trajectories, expected cost s_0 of
    the last backward pass, ``iterations``, and why it stopped (``converged``: the
    relative cost change met ``rtol``, or no step decreases the cost and the predicted
    decrease of a full step is below ``rtol`` of the cost; ``no_progress``: the line search
    failed with a larger predicted decrease; ``linalg_error``: D_t not positive definite;
    ``max_iterations``).

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0)
    >>> res.status, res.b_bar.shape, res.L.shape
    ('converged', (4, 5), (3, 2, 5))
    """

    b_bar: np.ndarray
    u_bar: np.ndarray
    L: np.ndarray
    costs: list
    expected_cost: float
    iterations: int


class _BeliefCost:
    """The cost (2.20) in the belief, with its analytic gradient and Hessian in (b, u)."""

    def __init__(self, cost, n):
        self.cost, self.n = cost, n
        D = _duplication(n)
        self._H_sqrt = 2 * D.T @ np.kron(np.eye(n), cost.Q) @ D
        self._H_sqrt_K = 2 * D.T @ np.kron(np.eye(n), cost.Q_K) @ D

    def stage(self, b, u):
        mean, root = belief_mean_and_root(b, self.n)
        return self.cost.gaussian_stage(mean, root @ root, u)

    def terminal(self, b):
        mean, root = belief_mean_and_root(b, self.n)
        return self.cost.gaussian_terminal(mean, root @ root)

    def _quad(self, b, Qm, Hs):
        n = self.n
        H = np.zeros((b.size, b.size))
        H[:n, :n], H[n:, n:] = 2 * Qm, Hs
        g = np.concatenate([2 * Qm @ (b[:n] - self.cost.x_target), Hs @ b[n:]])
        return g, H

    def stage_derivatives(self, b, u):
        g, H = self._quad(b, self.cost.Q, self._H_sqrt)
        return g, H, 2 * self.cost.R @ u, 2 * self.cost.R

    def terminal_derivatives(self, b):
        return self._quad(b, self.cost.Q_K, self._H_sqrt_K)


def _linearize(dyn, b, u):
    """A, B, and F_i, G_i, e_i of g and the columns w_i of W at (b, u) (numdifftools [46])."""
    import numdifftools as nd
    lb = b.size

    def stacked(z):
        g, W = dyn._dynamics(z[:lb], z[lb:])
        return np.concatenate([g, W.T.ravel()])

    # one central difference of step 1e-4 (no Richardson extrapolation): within 1e-8 of
    # numdifftools' adaptive default on this problem, at an eighth of the evaluations
    step = nd.MinStepGenerator(base_step=1e-4, num_steps=1)
    jacobian = nd.Jacobian(stacked, method="central", order=2, step=step, richardson_terms=0)
    Jz = jacobian(np.concatenate([b, u]))
    g, W = dyn._dynamics(b, u)
    m = W.shape[1]
    A, B = Jz[:lb, :lb], Jz[:lb, lb:]
    FG = Jz[lb:].reshape(m, lb, -1)
    return g, A, B, FG[:, :, :lb], FG[:, :, lb:], W.T


def _rollout(dyn, bcost, b0, u_bar, b_bar=None, L=None, l=None, eps=1.0):
    """Forward pass with w = 0: u_t = u_bar_t + L_t (b_t - b_bar_t) + eps l_t; (b, u, cost)."""
    K = u_bar.shape[0]
    b, bs, us, total = b0, [b0], [], 0.0
    for t in range(K):
        u = u_bar[t] if L is None else u_bar[t] + L[t] @ (b - b_bar[t]) + eps * l[t]
        total += float(bcost.stage(b, u))
        b = dyn._dynamics(b, u)[0]
        bs.append(b), us.append(u)
    total += float(bcost.terminal(b))
    return np.array(bs), np.array(us), total


def belief_ilqg(model, cost, mean0, cov0, u_init=None, max_iterations=100, rtol=1e-4,
                eps_min=2.0 ** -12, progress=False) -> BeliefILQGResult:
    """Belief-space iLQG of [159] for the model (2.1)-(2.2) and the cost (2.20), Sec. 2.5.3's rival.

    Parameters
    ----------
    model : NonlinearModel
        EKF Jacobians: analytic if the model gives them.
    cost : QuadraticCost
        Written in the belief by ``_BeliefCost``; its ``K`` is the horizon.
    mean0, cov0 : array_like
        The initial Gaussian belief, (n_x,) and (n_x, n_x) PSD.
    u_init : array_like (K, n_u), optional
        Initial nominal inputs; default zeros.
    max_iterations : int
        Iteration limit, >= 1.
    rtol : float
        Stop when the nominal cost changes by at most rtol (relative), rtol > 0; when no
        step eps >= ``eps_min`` decreases the cost, the run has converged if the predicted
        decrease of the full step is at most rtol of the cost.
    eps_min : float
        Smallest line-search step, in (0, 1].
    progress : bool
        Show a progress bar.

    Returns
    -------
    BeliefILQGResult

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Warns
    -----
    RuntimeWarning
        If it stops without converging.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0)
    >>> res.converged, round(res.costs[-1], 2) < round(res.costs[0], 2)
    (True, True)
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    K, n = cost.K, model.n_x
    mean0 = check.vector(mean0, "mean0", n)
    cov0 = check.covariance(cov0, "cov0", n)
    u_bar = (np.zeros((K, model.n_u)) if u_init is None
             else check.real_array(u_init, "u_init", shape=(K, model.n_u)))
    max_iterations = check.integer(max_iterations, "max_iterations", minimum=1)
    rtol = check.real_scalar(rtol, "rtol", low=0, low_open=True)
    eps_min = check.real_scalar(eps_min, "eps_min", low=0, high=1, low_open=True)
    progress = check.boolean(progress, "progress")
    dyn, bcost = BeliefDynamics(model), _BeliefCost(cost, n)
    b0 = _belief_vector(mean0, cov0)
    b_bar, u_bar, J = _rollout(dyn, bcost, b0, u_bar)
    costs, status, it = [J], "max_iterations", 0
    bar = progress_bar(total=max_iterations, enabled=progress, desc="belief iLQG [159]")
    for it in range(1, max_iterations + 1):
        bar.update()
        L, l, expected, decrease = _backward(dyn, bcost, b_bar, u_bar)
        if decrease is None:
            status = "linalg_error"
            break
        eps, accepted = 1.0, False
        while eps >= eps_min:
            b_new, u_new, J_new = _rollout(dyn, bcost, b0, u_bar, b_bar, L, l, eps)
            if J_new < J:
                accepted = True
                break
            eps /= 2
        if not accepted:
            status = "converged" if decrease <= rtol * abs(J) else "no_progress"
            break
        change = abs(J - J_new)
        b_bar, u_bar, J = b_new, u_new, J_new
        costs.append(J)
        if change <= rtol * abs(J):
            status = "converged"
            break
    bar.close()
    messages = {"converged": lambda: f"converged after {it} iterations (relative cost change or "
                                     f"predicted decrease <= rtol = {rtol:g})",
                "no_progress": lambda: f"no step eps >= {eps_min:g} decreases the cost at "
                                       f"iteration {it}, although a full step predicts a decrease "
                                       f"of {decrease:.3g} > rtol |J| = {rtol * abs(J):.3g}",
                "linalg_error": lambda: f"D_t is not positive definite at iteration {it}",
                "max_iterations": lambda: f"stopped after max_iterations = {max_iterations}"}
    message = messages[status]()
    if status != "converged":
        warnings.warn(f"belief iLQG [159] did not converge: {message}", RuntimeWarning,
                      stacklevel=2)
    L, _, expected, _ = _backward(dyn, bcost, b_bar, u_bar)
    return BeliefILQGResult(b_bar=b_bar, u_bar=u_bar, L=L, costs=costs,
                            expected_cost=float(expected), iterations=it,
                            converged=status == "converged", status=status, message=message)


class BeliefAffineController:
    """u_k = u_bar_k + L_k (b_k - b_bar_k) with the EKF belief b = (mean, vec sqrt cov) [159].

    Parameters
    ----------
    model : NonlinearModel
    result : BeliefILQGResult
        From :func:`~asoc.belief.belief_ilqg` for the same model.

    Raises
    ------
    ValueError, TypeError
        If ``model`` or ``result`` has the wrong type or dimensions.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=2)
    >>> ctrl = BeliefAffineController(ex.model, belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0))
    >>> ctrl.control(0, ex.mean0, ex.cov0).round(2).tolist()
    [4.57, -0.01]
    """

    def __init__(self, model, result):
        self.model = check.instance(model, NonlinearModel, "model")
        self.result = check.instance(result, BeliefILQGResult, "result")
        n_belief = model.n_x + model.n_x * (model.n_x + 1) // 2
        if result.u_bar.shape[1] != model.n_u or result.b_bar.shape[1] != n_belief:
            raise ValueError(f"result: expected a belief iLQG result for n_x = {model.n_x}, "
                             f"n_u = {model.n_u}, found beliefs {result.b_bar.shape} and inputs "
                             f"{result.u_bar.shape}")
        self.horizon = result.u_bar.shape[0]

    def control(self, k, mean, cov):
        """The input at time k for the EKF belief (mean, cov)."""
        r = self.result
        return r.u_bar[k] + (belief_vector(mean, cov) - r.b_bar[k]) @ r.L[k].T

    def step(self, mean, cov, u, y):
        """The EKF's next belief."""
        return ekf_step(self.model, mean, cov, u, y)


def _backward(dyn, bcost, b_bar, u_bar):
    """The backward recursion of [159] (Sec. 5) in deviations from the nominal trajectory."""
    K = u_bar.shape[0]
    q, S = bcost.terminal_derivatives(b_bar[K])
    s, s0 = q, float(bcost.terminal(b_bar[K]))
    L, l = np.zeros((K,) + u_bar.shape[1:] + b_bar.shape[1:]), np.zeros_like(u_bar)
    decrease = 0.0
    for t in range(K - 1, -1, -1):
        _, A, B, F, G, e = _linearize(dyn, b_bar[t], u_bar[t])
        qb, Qb, ru, Ru = bcost.stage_derivatives(b_bar[t], u_bar[t])
        D = Ru + B.T @ S @ B + np.einsum("iab,ac,icd->bd", G, S, G)
        E = B.T @ S @ A + np.einsum("iab,ac,icd->bd", G, S, F)
        d = ru + B.T @ s + np.einsum("iab,ac,ic->b", G, S, e)
        if not np.linalg.eigvalsh(0.5 * (D + D.T)).min() > 0:
            return L, l, np.nan, None
        L[t], l[t] = -np.linalg.solve(D, E), -np.linalg.solve(D, d)
        decrease += 0.5 * d @ np.linalg.solve(D, d)
        s0 = (float(bcost.stage(b_bar[t], u_bar[t])) + s0 + 0.5 * np.einsum("ia,ab,ib->", e, S, e)
              - 0.5 * d @ np.linalg.solve(D, d))
        s_new = qb + A.T @ s + np.einsum("iab,ac,ic->b", F, S, e) - E.T @ np.linalg.solve(D, d)
        S = Qb + A.T @ S @ A + np.einsum("iab,ac,icd->bd", F, S, F) - E.T @ np.linalg.solve(D, E)
        S, s = 0.5 * (S + S.T), s_new
    return L, l, s0, decrease
