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

import numpy as np

from ..progress import progress_bar
from .filters import ekf_gain, ekf_predict
from .models import check_horizon


def _tril_indices(n):
    """Lower-triangle entries stacked column by column (i >= j)."""
    return [(i, j) for j in range(n) for i in range(j, n)]


def duplication(n):
    """D with vec(A) = D vech(A) for symmetric A (our vech order: columns of the lower triangle)."""
    idx = _tril_indices(n)
    D = np.zeros((n * n, len(idx)))
    for c, (i, j) in enumerate(idx):
        D[i + n * j, c] = D[j + n * i, c] = 1.0
    return D


def psd_sqrt(M):
    """Principal square root of a batch of symmetric PSD matrices."""
    lam, vec = np.linalg.eigh(0.5 * (M + np.swapaxes(M, -1, -2)))
    return (vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]) @ np.swapaxes(vec, -1, -2)


def belief_vector(mean, cov):
    """b = (mean, vech(sqrt(cov))), broadcasting over leading axes.

    Parameters
    ----------
    mean : array_like, (..., n)
    cov : array_like, (..., n, n)

    Returns
    -------
    numpy.ndarray, (..., n + n (n + 1) / 2)

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    n = np.shape(mean)[-1]
    root = psd_sqrt(np.asarray(cov, dtype=float))
    i, j = np.array(_tril_indices(n)).T
    return np.concatenate([np.asarray(mean, dtype=float), root[..., i, j]], axis=-1)


def unpack(b, n):
    """(mean, sqrt(cov)) from a belief vector."""
    b = np.asarray(b, dtype=float)
    root = np.zeros(b.shape[:-1] + (n, n))
    i, j = np.array(_tril_indices(n)).T
    root[..., i, j] = b[..., n:]
    root[..., j, i] = b[..., n:]
    return b[..., :n], root


class BeliefDynamics:
    """g(b, u) and W(b, u) of the EKF belief dynamics ([159], Sec. 4.1)."""

    def __init__(self, model):
        self.model, self.n = model, model.n_x

    def __call__(self, b, u):
        """(g(b, u), W(b, u))."""
        mean, root = unpack(b, self.n)
        mean_p, Gamma = ekf_predict(self.model, mean, root @ root, np.asarray(u, dtype=float))
        _, K, S, post = ekf_gain(self.model, mean_p, Gamma)
        # principal root of K H Gamma = (K S^1/2)(K S^1/2)^T from the thin SVD of K S^1/2
        U, sv, _ = np.linalg.svd(K @ psd_sqrt(S), full_matrices=False)
        W_mean = (U * sv) @ U.T
        W = np.zeros((b.shape[-1], self.n))
        W[: self.n] = W_mean
        return belief_vector(mean_p, post), W


@dataclass
class BeliefILQGResult:
    """Result of the belief-space iLQG [159]: nominal b_bar (K+1, l), u_bar (K, n_u),
    gains L (K, n_u, l), cost history of the nominal trajectories, expected cost s_0 of
    the last backward pass, ``converged`` and ``iterations``."""

    b_bar: np.ndarray
    u_bar: np.ndarray
    L: np.ndarray
    costs: list
    expected_cost: float
    converged: bool
    iterations: int


class BeliefCost:
    """The cost (2.20) in the belief, with its analytic gradient and Hessian in (b, u)."""

    def __init__(self, cost, n):
        self.cost, self.n = cost, n
        D = duplication(n)
        self._H_sqrt = 2 * D.T @ np.kron(np.eye(n), cost.Q) @ D
        self._H_sqrt_K = 2 * D.T @ np.kron(np.eye(n), cost.Q_K) @ D

    def stage(self, b, u):
        mean, root = unpack(b, self.n)
        return self.cost.gaussian_stage(mean, root @ root, u)

    def terminal(self, b):
        mean, root = unpack(b, self.n)
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
        g, W = dyn(z[:lb], z[lb:])
        return np.concatenate([g, W.T.ravel()])

    # one central difference of step 1e-4 (no Richardson extrapolation): within 1e-8 of
    # numdifftools' adaptive default on this problem, at an eighth of the evaluations
    step = nd.MinStepGenerator(base_step=1e-4, num_steps=1)
    Jz = nd.Jacobian(stacked, method="central", order=2, step=step, richardson_terms=0)(np.concatenate([b, u]))
    g, W = dyn(b, u)
    m = W.shape[1]
    A, B = Jz[:lb, :lb], Jz[:lb, lb:]
    FG = Jz[lb:].reshape(m, lb, -1)
    return g, A, B, FG[:, :, :lb], FG[:, :, lb:], W.T


def rollout(dyn, bcost, b0, u_bar, b_bar=None, L=None, l=None, eps=1.0):
    """Forward pass with w = 0: u_t = u_bar_t + L_t (b_t - b_bar_t) + eps l_t. Returns (b, u, cost)."""
    K = u_bar.shape[0]
    b, bs, us, total = b0, [b0], [], 0.0
    for t in range(K):
        u = u_bar[t] if L is None else u_bar[t] + L[t] @ (b - b_bar[t]) + eps * l[t]
        total += float(bcost.stage(b, u))
        b = dyn(b, u)[0]
        bs.append(b), us.append(u)
    total += float(bcost.terminal(b))
    return np.array(bs), np.array(us), total


def belief_ilqg(model, cost, mean0, cov0, u_init=None, max_iterations=100, rtol=1e-4,
                eps_min=2.0 ** -12, progress=False) -> BeliefILQGResult:
    """Belief-space iLQG of [159] for the model (2.1)-(2.2) and the cost (2.20).

    Parameters
    ----------
    model : NonlinearModel
        EKF Jacobians: analytic if the model gives them.
    cost : QuadraticCost
        Written in the belief by :class:`BeliefCost`.
    mean0, cov0 : array_like
        The initial Gaussian belief.
    u_init : array_like (K, n_u), optional
        Initial nominal inputs; default zeros.
    max_iterations, rtol : stop when the nominal cost changes by less than rtol (relative).
    eps_min : stop (converged) when the line search needs eps below this value.

    Returns
    -------
    BeliefILQGResult

    Raises
    ------
    ValueError
        If the horizon is invalid or ``u_init`` has the wrong shape.
    """
    K = check_horizon(cost.K)
    n = model.n_x
    dyn, bcost = BeliefDynamics(model), BeliefCost(cost, n)
    u_bar = np.zeros((K, model.n_u)) if u_init is None else np.array(u_init, dtype=float)
    if u_bar.shape != (K, model.n_u):
        raise ValueError(f"u_init: expected shape {(K, model.n_u)}, found {u_bar.shape}")
    b0 = belief_vector(np.asarray(mean0, dtype=float), np.asarray(cov0, dtype=float))
    b_bar, u_bar, J = rollout(dyn, bcost, b0, u_bar)
    costs, converged, expected, L = [J], False, np.nan, np.zeros((K, model.n_u, b0.size))
    bar = progress_bar(total=max_iterations, enabled=progress, desc="belief iLQG [159]")
    it = 0
    for it in range(1, max_iterations + 1):
        bar.update()
        L, l, expected, ok = _backward(dyn, bcost, b_bar, u_bar)
        if not ok:
            warnings.warn("belief iLQG [159]: D_t is not positive definite; stopping", RuntimeWarning, stacklevel=2)
            break
        eps, accepted = 1.0, False
        while eps >= eps_min:
            b_new, u_new, J_new = rollout(dyn, bcost, b0, u_bar, b_bar, L, l, eps)
            if J_new < J:
                accepted = True
                break
            eps /= 2
        if not accepted:
            converged = True
            break
        change = abs(J - J_new)
        b_bar, u_bar, J = b_new, u_new, J_new
        costs.append(J)
        if change <= rtol * abs(J):
            converged = True
            break
    bar.close()
    if not converged:
        warnings.warn(f"belief iLQG [159] did not converge in {max_iterations} iterations", RuntimeWarning,
                      stacklevel=2)
    L, _, expected, _ = _backward(dyn, bcost, b_bar, u_bar)
    return BeliefILQGResult(b_bar, u_bar, L, costs, float(expected), converged, it)


def _backward(dyn, bcost, b_bar, u_bar):
    """The backward recursion of [159] (Sec. 5) in deviations from the nominal trajectory."""
    K = u_bar.shape[0]
    q, S = bcost.terminal_derivatives(b_bar[K])
    s, s0 = q, float(bcost.terminal(b_bar[K]))
    L, l = np.zeros((K,) + u_bar.shape[1:] + b_bar.shape[1:]), np.zeros_like(u_bar)
    for t in range(K - 1, -1, -1):
        _, A, B, F, G, e = _linearize(dyn, b_bar[t], u_bar[t])
        qb, Qb, ru, Ru = bcost.stage_derivatives(b_bar[t], u_bar[t])
        D = Ru + B.T @ S @ B + np.einsum("iab,ac,icd->bd", G, S, G)
        E = B.T @ S @ A + np.einsum("iab,ac,icd->bd", G, S, F)
        d = ru + B.T @ s + np.einsum("iab,ac,ic->b", G, S, e)
        if np.linalg.eigvalsh(0.5 * (D + D.T)).min() <= 0:
            return L, l, np.nan, False
        L[t], l[t] = -np.linalg.solve(D, E), -np.linalg.solve(D, d)
        s0 = (float(bcost.stage(b_bar[t], u_bar[t])) + s0 + 0.5 * np.einsum("ia,ab,ib->", e, S, e)
              - 0.5 * d @ np.linalg.solve(D, d))
        s_new = qb + A.T @ s + np.einsum("iab,ac,ic->b", F, S, e) - E.T @ np.linalg.solve(D, d)
        S = Qb + A.T @ S @ A + np.einsum("iab,ac,icd->bd", F, S, F) - E.T @ np.linalg.solve(D, E)
        S, s = 0.5 * (S + S.T), s_new
    return L, l, s0, True
