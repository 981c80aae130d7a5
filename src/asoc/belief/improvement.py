"""Theorem 2.5 (the improved policy's value), the policy (2.17) and Algorithm 2.3 (line search).

From the :class:`~asoc.belief.stage.Expansion` (2.15) of phi_k at the reference:
:func:`policy_step` is the improved policy (2.17) with step epsilon_k, :func:`line_search`
chooses epsilon_k (Algorithm 2.3), and :func:`improved_policy_value` /
:func:`affine_policy_value` give the value (2.10)-(2.11) that the backward pass carries to k - 1.
"""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..result import IterativeResult
from .stage import Expansion, StageProblem, Value

__all__ = ["improved_policy_value", "affine_policy_value", "policy_step", "LineSearch",
           "line_search"]


def _expansion(exp, name="exp"):
    """An Expansion whose R~_k is positive definite (Assumption 2.3), and its tilde terms."""
    check.instance(exp, Expansion, name)
    tilde = exp.tilde
    lam = np.linalg.eigvalsh(tilde[3]).min()
    if not lam > 0:
        raise ValueError(f"{name}: expected R~_k positive definite (Assumption 2.3), "
                         f"found smallest eigenvalue {lam:.3g}")
    return tilde


def improved_policy_value(exp: Expansion, eps: float) -> Value:
    """Theorem 2.5: s_k, v_k, V_k, S_k of eq. (2.11) for the improved policy (2.17), step ``eps``.

    Parameters
    ----------
    exp : Expansion
        The expansion (2.15) at one time step (:meth:`StageProblem.expansion`).
    eps : float
        Line-search step of the policy (2.17), in (0, 1].

    Returns
    -------
    Value

    Raises
    ------
    ValueError, TypeError
        If ``exp`` is not an Expansion with R~_k > 0, or ``eps`` is outside (0, 1].

    Examples
    --------
    >>> exp = Expansion(phi=np.array([1.0]), p=np.zeros((1, 1)), r=np.array([[2.0]]),
    ...                 Q=np.eye(1)[None], P=np.zeros((1, 1, 1)), R=np.eye(1)[None],
    ...                 points=np.zeros((1, 1)), alpha=np.ones(1))
    >>> improved_policy_value(exp, 1.0).s     # phi - r^2 / (2 R): the minimum over u
    -1.0
    """
    p_t, r_t, P_t, R_t = _expansion(exp)
    eps = check.real_scalar(eps, "eps", low=0, high=1, low_open=True)
    return _improved_policy_value(exp, eps)


def _improved_policy_value(exp, eps):
    p_t, r_t, P_t, R_t = exp.tilde
    Ri = np.linalg.inv(R_t)
    a, X = exp.alpha, exp.points
    s = ((eps ** 2 / 2 - eps) * r_t @ Ri @ r_t - 0.5 * p_t @ Ri @ p_t + r_t @ Ri @ p_t
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X)
                + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
    v = P_t.T @ Ri @ p_t - P_t.T @ Ri @ r_t + a @ (exp.p - np.einsum("ijk,ik->ij", exp.Q, X))
    S = P_t.T @ Ri @ P_t
    V = -S + np.einsum("i,ijk->jk", a, exp.Q)
    return Value(float(s), v, 0.5 * (V + V.T), 0.5 * (S + S.T))


def affine_policy_value(exp: Expansion, L, d, u_bar) -> Value:
    """Value (2.10) of an arbitrary affine policy u = L E{x} + d under the expansion (2.15).

    For the policy (2.17) it equals :func:`improved_policy_value`; Alg. 2.2 uses it for a
    time step whose policy the line search keeps.

    Parameters
    ----------
    exp : Expansion
        The expansion (2.15) at one time step.
    L, d : array_like, (n_u, n_x) and (n_u,)
        The policy's gain and offset.
    u_bar : array_like, (n_u,)
        The reference input.

    Returns
    -------
    Value

    Raises
    ------
    ValueError, TypeError
        If ``exp`` is not an Expansion or the shapes do not match it.

    Examples
    --------
    >>> exp = Expansion(phi=np.array([1.0]), p=np.zeros((1, 1)), r=np.array([[2.0]]),
    ...                 Q=np.eye(1)[None], P=np.zeros((1, 1, 1)), R=np.eye(1)[None],
    ...                 points=np.zeros((1, 1)), alpha=np.ones(1))
    >>> affine_policy_value(exp, np.zeros((1, 1)), np.array([-2.0]), np.zeros(1)).s
    -1.0
    """
    check.instance(exp, Expansion, "exp")
    n_u, n_x = exp.P.shape[1:]
    L = check.real_array(L, "L", shape=(n_u, n_x))
    d = check.real_array(d, "d", shape=(n_u,))
    u_bar = check.real_array(u_bar, "u_bar", shape=(n_u,))
    return _affine_policy_value(exp, L, d, u_bar)


def _affine_policy_value(exp, L, d, u_bar):
    p_t, r_t, P_t, R_t = exp.tilde
    a, X = exp.alpha, exp.points
    delta = d - u_bar
    g = r_t - p_t
    M = P_t.T @ L + L.T @ P_t + L.T @ R_t @ L
    s = (g @ delta + 0.5 * delta @ R_t @ delta
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X)
                + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
    v = (L.T @ g + P_t.T @ delta + L.T @ R_t @ delta
         + a @ (exp.p - np.einsum("ijk,ik->ij", exp.Q, X)))
    V = np.einsum("i,ijk->jk", a, exp.Q) + M
    return Value(float(s), v, 0.5 * (V + V.T), -0.5 * (M + M.T))


def policy_step(exp: Expansion, u_bar, eps):
    """The improved policy (2.17) of Alg. 2.2, Step 6.

    L_k = -R~^{-1} P~ and d_k = R~^{-1} p~ - eps R~^{-1} r~ + u_bar_k.

    Parameters
    ----------
    exp : Expansion
        The expansion (2.15) at one time step, with R~_k > 0.
    u_bar : array_like, (n_u,)
        The reference input.
    eps : float
        Line-search step, in (0, 1].

    Returns
    -------
    L : numpy.ndarray, (n_u, n_x)
        The new feedback gain.
    d : numpy.ndarray, (n_u,)
        The new feed-forward term.

    Raises
    ------
    ValueError, TypeError
        If ``exp`` is not an Expansion with R~_k > 0, ``u_bar`` has the wrong shape or ``eps``
        is outside (0, 1].

    Examples
    --------
    >>> exp = Expansion(phi=np.array([1.0]), p=np.zeros((1, 1)), r=np.array([[2.0]]),
    ...                 Q=np.eye(1)[None], P=np.zeros((1, 1, 1)), R=np.eye(1)[None],
    ...                 points=np.zeros((1, 1)), alpha=np.ones(1))
    >>> L, d = policy_step(exp, np.zeros(1), 0.5)
    >>> L.tolist(), d.tolist()
    ([[-0.0]], [-1.0])
    """
    _expansion(exp)
    u_bar = check.real_array(u_bar, "u_bar", shape=(exp.P.shape[1],))
    eps = check.real_scalar(eps, "eps", low=0, high=1, low_open=True)
    return _policy_step(exp, u_bar, eps)


def _policy_step(exp, u_bar, eps):
    p_t, r_t, P_t, R_t = exp.tilde
    return -np.linalg.solve(R_t, P_t), np.linalg.solve(R_t, p_t - eps * r_t) + u_bar


@dataclass(kw_only=True)
class LineSearch(IterativeResult):
    """Result of Algorithm 2.3: the step ``eps``, the costs-to-go before and after it.

    ``converged`` (also ``accepted``) is True when a step eps >= alpha_min did not increase
    the costs-to-go; status ``no_progress`` otherwise (the current policy is locally optimal
    at this step).

    Examples
    --------
    >>> LineSearch(eps=0.5, cost_before=2.0, cost_after=1.0, converged=True, status="converged",
    ...            message="eps = 0.5 decreases the costs-to-go").accepted
    True
    """

    eps: float
    cost_before: float
    cost_after: float

    @property
    def accepted(self) -> bool:
        """Whether the step is taken (the same as ``converged``)."""
        return self.converged


def line_search(stage, exp: Expansion, u_bar, mean_bar, alpha_min=2.0 ** -10) -> LineSearch:
    """Algorithm 2.3: halve eps_k from 1 until the costs-to-go at p_bar_k do not increase.

    Parameters
    ----------
    stage : StageProblem
    exp : Expansion
        Its expansion at ``u_bar``, with R~_k > 0.
    u_bar, mean_bar : array_like, (n_u,) and (n_x,)
        Reference input and estimate mean.
    alpha_min : float
        Smallest step tried, in (0, 1].

    Returns
    -------
    LineSearch
        The step, whether it was accepted (False: no eps >= ``alpha_min`` decreased the
        costs-to-go, the current policy is locally optimal at this step) and the costs.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or ``alpha_min`` is outside (0, 1].

    Examples
    --------
    >>> from asoc.belief import UKF, landmark_example, sigma_points
    >>> ex = landmark_example(K=1)
    >>> filt = UKF(ex.model)
    >>> est = filt.initial(ex.mean0, ex.cov0)
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> nxt = Value(0.0, np.zeros(2), np.zeros((2, 2)), np.zeros((2, 2)))
    >>> stage = StageProblem(ex.model, ex.cost, filt, est, nxt, w, beta)
    >>> ls = line_search(stage, stage.expansion(np.zeros(2)), np.zeros(2), ex.mean0)
    >>> ls.accepted, ls.eps, round(ls.cost_after, 4)
    (True, 1.0, 25.08)
    """
    check.instance(stage, StageProblem, "stage")
    _expansion(exp)
    n_u, n_x = exp.P.shape[1:]
    u_bar = check.real_array(u_bar, "u_bar", shape=(n_u,))
    mean_bar = check.real_array(mean_bar, "mean_bar", shape=(n_x,))
    alpha_min = check.real_scalar(alpha_min, "alpha_min", low=0, high=1, low_open=True)
    return _line_search(stage, exp, u_bar, mean_bar, alpha_min)


def _line_search(stage, exp, u_bar, mean_bar, alpha_min):
    before = stage.cost_to_go(u_bar)
    eps = 1.0
    while eps >= alpha_min:
        L, d = _policy_step(exp, u_bar, eps)
        after = stage.cost_to_go(L @ mean_bar + d)
        if after <= before:
            return LineSearch(eps=eps, cost_before=before, cost_after=after, converged=True,
                              status="converged",
                              message=f"the step eps = {eps:g} does not increase the costs-to-go")
        eps /= 2
    return LineSearch(eps=eps, cost_before=before, cost_after=before, converged=False,
                      status="no_progress",
                      message=f"no step eps >= alpha_min = {alpha_min:g} decreases the costs-to-go")
