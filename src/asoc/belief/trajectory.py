"""Belief-space trajectory optimisation by statistical Taylor expansion (Sec. 2.5.2).

Algorithm 2.1 (reference trajectory), Theorem 2.4 (terminal value), Theorem 2.5
(value along the reference, eqs. 2.10-2.13), Algorithm 2.3 (line search on epsilon_k)
and Algorithm 2.2 (the iteration) for the affine policy u_k = L_k E{x_k} + d_k (2.18).
"""

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..progress import progress_bar
from ._validate import check_rng
from .filters import UKF, sigma_points
from .models import check_horizon
from .simulate import MeanAffineController, draw_noise, simulate
from .taylor import QuadraticExpansion, statistical_taylor_expansion


@dataclass(frozen=True)
class AffinePolicy:
    """u_k = L_k E{x_k} + d_k for k = 0..K-1 (eq. 2.18); L (K, n_u, n_x), d (K, n_u)."""

    L: np.ndarray
    d: np.ndarray

    @classmethod
    def zero(cls, K, n_u, n_x):
        """The initial policy L_k = 0, d_k = 0 (Sec. 2.5.2)."""
        return cls(np.zeros((check_horizon(K), n_u, n_x)), np.zeros((K, n_u)))

    def __call__(self, k, mean):
        return self.L[k] @ mean + self.d[k]


@dataclass(frozen=True)
class Reference:
    """Reference trajectory {p_bar_{0:K}, u_bar_{0:K-1}} of Algorithm 2.1."""

    estimates: list
    u_bar: np.ndarray


def reference_trajectory(model, filt, policy: AffinePolicy, mean0, cov0, mode="nominal", rng=None) -> Reference:
    """Algorithm 2.1: simulate the reference estimates under ``policy``.

    ``mode="nominal"`` uses the means E{x_k}, E{w_k}, E{v_k} (the variant the thesis
    mentions after Alg. 2.1); ``mode="sampled"`` draws one sample of each from ``rng``.

    Parameters
    ----------
    model : NonlinearModel
    filt : filter
    policy : AffinePolicy
    mean0, cov0 : array_like
        Initial estimate.
    mode : {"nominal", "sampled"}
    rng : numpy.random.Generator, optional
        Needed for ``mode="sampled"``.

    Returns
    -------
    Reference

    Raises
    ------
    ValueError
        If ``mode`` is unknown, or ``rng`` is not a Generator when sampling.
    """
    if mode not in ("nominal", "sampled"):
        raise ValueError(f"mode: expected 'nominal' or 'sampled', found {mode!r}")
    if mode == "sampled":
        rng = check_rng(rng)
    est = filt.initial(mean0, cov0)
    estimates, u_bar = [est], []
    for k in range(policy.L.shape[0]):
        u = policy(k, filt.mean(est))
        if mode == "nominal":
            x, w, v = filt.mean(est), model.w.mean, model.v.mean
        else:
            mix = filt.mixture(est)
            x = mix.points[rng.choice(mix.weights.size, p=mix.weights)]
            w, v = model.w.sample(rng), model.v.sample(rng)
        y = model.h(model.a(x, u, w), v)
        est = filt.step(est, u, y)
        estimates.append(est), u_bar.append(u)
    return Reference(estimates, np.array(u_bar))


@dataclass(frozen=True)
class Value:
    """V_k(p) ~ E{s + v^T x + 1/2 x^T V x + 1/2 tr[S C]} (eq. 2.10)."""

    s: float
    v: np.ndarray
    V: np.ndarray
    S: np.ndarray

    def at(self, mean, cov) -> float:
        """The approximation for an estimate with the given mean and covariance."""
        q = QuadraticExpansion(self.s, self.v, self.V)
        return q.expectation(mean, cov) + 0.5 * float(np.trace(self.S @ cov))


def terminal_value(cost, mixture) -> Value:
    """Theorem 2.4: statistical expansion of C_K at p_bar_K, S_K = 0.

    Parameters
    ----------
    cost : QuadraticCost
    mixture : DiracMixture
        The terminal estimate p_bar_K.

    Returns
    -------
    Value

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    derivs = cost.terminal_derivatives if hasattr(cost, "terminal_derivatives") else None
    q = statistical_taylor_expansion(cost.terminal, mixture,
                                     (lambda x: derivs(x)[0]) if derivs else None,
                                     (lambda x: derivs(x)[1]) if derivs else None)
    return Value(q.s, q.v, q.V, np.zeros_like(q.V))


@dataclass(frozen=True)
class Expansion:
    """Derivatives of phi_k at the particles (eq. 2.12) and their weighted sums."""

    phi: np.ndarray      # phi_k(x_i, u_bar), (M,)
    p: np.ndarray        # (M, n_x)
    r: np.ndarray        # (M, n_u)
    Q: np.ndarray        # (M, n_x, n_x)
    P: np.ndarray        # (M, n_u, n_x)
    R: np.ndarray        # (M, n_u, n_u)
    points: np.ndarray
    alpha: np.ndarray

    @property
    def tilde(self):
        """(p~, r~, P~, R~) of eq. (2.12)."""
        a = self.alpha
        return (np.einsum("i,iuj,ij->u", a, self.P, self.points), a @ self.r,
                np.einsum("i,iuj->uj", a, self.P), np.einsum("i,iuv->uv", a, self.R))


COVARIANCE_HESSIANS = ("psd", "exact", "shift")


class StageProblem:
    """phi_k of eq. (2.13) at time step k for the reference estimate p_bar_k.

    phi_k(x, u) = sum_m beta_m [C_k(x, u) + s_{k+1} + v_{k+1}^T a(x, u, w_m)
                  + 1/2 a^T V_{k+1} a] + 1/2 tr[S_{k+1} C_{k+1}(u)],
    where C_{k+1}(u) is the covariance of the next estimate from Lemma 2.1 (the filter's
    ``next_covariance``), which is what makes the controller dual. ``covariance_term=False``
    drops that term (the certainty-equivalent control run of the notebook).
    """

    def __init__(self, model, cost, filt, estimate, nxt: Value, w_points, beta, covariance_hessian="psd",
                 covariance_term=True):
        if covariance_hessian not in COVARIANCE_HESSIANS:
            raise ValueError(f"covariance_hessian: expected one of {COVARIANCE_HESSIANS}, found {covariance_hessian!r}")
        self.covariance_hessian, self.covariance_term = covariance_hessian, bool(covariance_term)
        self.model, self.cost, self.filt, self.est, self.nxt = model, cost, filt, estimate, nxt
        self.w_points, self.beta = w_points, beta
        self.mixture = filt.mixture(estimate)

    def particle_part(self, x, u):
        """All of phi_k except the covariance term, for x (..., n_x) and u (..., n_u)."""
        x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
        a = self.model.a(x[..., None, :], u[..., None, :], self.w_points)
        nxt = self.nxt
        inner = a @ nxt.v + 0.5 * np.einsum("...mi,ij,...mj->...m", a, nxt.V, a)
        return self.cost.stage(x, u) + nxt.s + inner @ self.beta

    def covariance_part(self, u):
        """1/2 tr[S_{k+1} C_{k+1}(u)] (0 without the covariance term)."""
        if not self.covariance_term or not np.any(self.nxt.S):
            return 0.0
        return 0.5 * float(np.trace(self.nxt.S @ self.filt.next_covariance(self.est, np.asarray(u, dtype=float))))

    def cost_to_go(self, u) -> float:
        """sum_i alpha_i phi_k(x_i, u): the costs-to-go at p_bar_k compared in Alg. 2.3."""
        return float(self.mixture.weights @ self.particle_part(self.mixture.points, u)) + self.covariance_part(u)

    def expansion(self, u_bar, derivatives="analytic") -> Expansion:
        """Gradient and Hessian of phi_k at (x_i, u_bar) for every particle (eq. 2.12).

        ``derivatives="analytic"`` uses the model's Jacobians and the cost's derivatives
        where they exist (affine dynamics); the covariance term and everything else is
        differentiated by numdifftools [46]. ``"numdifftools"`` differentiates all of phi.
        """
        import numdifftools as nd
        X, alpha = self.mixture.points, self.mixture.weights
        nx, nu = X.shape[1], np.size(u_bar)
        analytic = (derivatives == "analytic" and self.model.jacobians is not None and self.model.affine
                    and hasattr(self.cost, "stage_derivatives"))
        if derivatives not in ("analytic", "numdifftools"):
            raise ValueError(f"derivatives: expected 'analytic' or 'numdifftools', found {derivatives!r}")
        G = np.zeros((X.shape[0], nx + nu))
        H = np.zeros((X.shape[0], nx + nu, nx + nu))
        for i, x in enumerate(X):
            if analytic:
                G[i], H[i] = self._analytic(x, u_bar)
            else:
                f = lambda z: self.particle_part(z[:nx], z[nx:])
                z = np.concatenate([x, u_bar])
                G[i], H[i] = nd.Gradient(f)(z), nd.Hessian(f)(z)
        if self.covariance_term and np.any(self.nxt.S):
            G[:, nx:] += np.atleast_1d(nd.Gradient(self.covariance_part)(u_bar))
            H[:, nx:, nx:] += self._covariance_hessian(u_bar)
        H = 0.5 * (H + np.swapaxes(H, 1, 2))
        if self.covariance_hessian == "shift":
            H[:, nx:, nx:] += self._shift(alpha, H, nx) * np.eye(nu)
        phi = self.particle_part(X, u_bar) + self.covariance_part(u_bar)
        return Expansion(phi, G[:, :nx], G[:, nx:], H[:, :nx, :nx], H[:, nx:, :nx], H[:, nx:, nx:], X, alpha)

    @staticmethod
    def _shift(alpha, H, nx):
        """Levenberg-Marquardt shift mu >= 0 of R~_k for ``covariance_hessian="shift"``.

        The smallest mu (bisection, relative accuracy 1e-6) for which the weighted Hessian
        [[Q~, P~^T], [P~, R~ + mu I]] of phi_k satisfies the conditions (2.9) of Assumption
        2.3: R~_k + mu I > 0 and the Schur complement Q~ - P~^T (R~_k + mu I)^{-1} P~ >= 0.
        The Schur complement is V_k + S_k - S_k of eq. (2.11), so the value function stays
        convex in E{x_k}. mu = 0 when the exact Hessian already satisfies (2.9).
        """
        Hm = np.einsum("i,ijk->jk", alpha, H)
        Q, P, R = Hm[:nx, :nx], Hm[nx:, :nx], Hm[nx:, nx:]
        nu = R.shape[0]
        scale = max(1.0, np.abs(Hm).max())

        def ok(mu):
            Rm = R + mu * np.eye(nu)
            if np.linalg.eigvalsh(Rm).min() <= 1e-9 * scale:
                return False
            schur = Q - P.T @ np.linalg.solve(Rm, P)
            return np.linalg.eigvalsh(0.5 * (schur + schur.T)).min() >= -1e-9 * scale

        if ok(0.0):
            return 0.0
        lo, hi = 0.0, max(scale, 1e-9)
        while not ok(hi):
            lo, hi = hi, 2 * hi
        while hi - lo > 1e-6 * hi:
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if ok(mid) else (mid, hi)
        return hi

    def _covariance_hessian(self, u_bar):
        """Hessian of 1/2 tr[S_{k+1} C_{k+1}(u)] in u (numdifftools); the safeguard against
        its negative curvature depends on ``covariance_hessian``.

        The thesis asserts R~_k > 0 (after Theorem 2.5) from Assumption 2.3, which covers
        C_k but not this term; its curvature can be negative and then R~_k loses
        definiteness. ``"psd"`` sets the term's negative eigenvalues to zero (R~_k >=
        grad_uu C_k > 0; the gradient, the first-order dual effect, is unchanged);
        ``"exact"`` keeps the Hessian (Alg. 2.2 then keeps the old policy where R~_k is
        indefinite); ``"shift"`` keeps it and shifts R~_k by mu I only as far as needed
        (:meth:`_shift`), as in Levenberg-Marquardt-regularised DDP.
        """
        import numdifftools as nd
        Hc = np.atleast_2d(nd.Hessian(self.covariance_part)(u_bar))
        Hc = 0.5 * (Hc + Hc.T)
        if self.covariance_hessian in ("exact", "shift"):
            return Hc
        lam, vec = np.linalg.eigh(Hc)
        return (vec * np.clip(lam, 0.0, None)) @ vec.T

    def _analytic(self, x, u):
        """Derivatives of the particle part for dynamics affine in (x, u)."""
        m, nxt = self.model, self.nxt
        gC, HC = self.cost.stage_derivatives(x, u)
        R = len(self.beta)
        xs, us = np.broadcast_to(x, (R, x.size)), np.broadcast_to(u, (R, np.size(u)))
        a = m.a(xs, us, self.w_points)                                # (R, n_x)
        a_x, a_u = m.jacobians(xs, us, self.w_points, np.broadcast_to(m.v.mean, (R,) + m.v.mean.shape))[:2]
        J = np.concatenate([np.broadcast_to(a_x, (R,) + a_x.shape[-2:]),
                            np.broadcast_to(a_u, (R,) + a_u.shape[-2:])], axis=-1)  # (R, n_x, n_x + n_u)
        lam = a @ nxt.V + nxt.v                                       # dV_{k+1}/dx at a
        g = gC + np.einsum("m,mij,mi->j", self.beta, J, lam)
        Hs = HC + np.einsum("m,mij,ik,mkl->jl", self.beta, J, nxt.V, J)
        return g, Hs


def theorem_2_5_value(exp: Expansion, eps: float) -> Value:
    """s_k, v_k, V_k, S_k of eq. (2.11) for the policy (2.17) with step ``eps``.

    Parameters
    ----------
    exp : Expansion
    eps : float
        Line-search step of the policy (2.17).

    Returns
    -------
    Value

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    p_t, r_t, P_t, R_t = exp.tilde
    Ri = np.linalg.inv(R_t)
    a, X = exp.alpha, exp.points
    s = ((eps ** 2 / 2 - eps) * r_t @ Ri @ r_t - 0.5 * p_t @ Ri @ p_t + r_t @ Ri @ p_t
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X) + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
    v = P_t.T @ Ri @ p_t - P_t.T @ Ri @ r_t + a @ (exp.p - np.einsum("ijk,ik->ij", exp.Q, X))
    S = P_t.T @ Ri @ P_t
    V = -S + np.einsum("i,ijk->jk", a, exp.Q)
    return Value(float(s), v, 0.5 * (V + V.T), 0.5 * (S + S.T))


def affine_policy_value(exp: Expansion, L, d, u_bar) -> Value:
    """Value (2.10) of an arbitrary affine policy u = L E{x} + d under the expansion (2.15).

    For the policy (2.17) it equals :func:`theorem_2_5_value`; Alg. 2.2 uses it for a
    time step whose policy the line search keeps.

    Parameters
    ----------
    exp : Expansion
        The expansion (2.15) at one time step.
    L, d : numpy.ndarray
        The policy's gain and offset.
    u_bar : numpy.ndarray
        The reference input.

    Returns
    -------
    Value

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    p_t, r_t, P_t, R_t = exp.tilde
    a, X = exp.alpha, exp.points
    delta = d - u_bar
    g = r_t - p_t
    M = P_t.T @ L + L.T @ P_t + L.T @ R_t @ L
    s = (g @ delta + 0.5 * delta @ R_t @ delta
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X) + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
    v = L.T @ g + P_t.T @ delta + L.T @ R_t @ delta + a @ (exp.p - np.einsum("ijk,ik->ij", exp.Q, X))
    V = np.einsum("i,ijk->jk", a, exp.Q) + M
    return Value(float(s), v, 0.5 * (V + V.T), -0.5 * (M + M.T))


def policy_step(exp: Expansion, u_bar, eps):
    """L_k = -R~^{-1} P~, d_k = R~^{-1} p~ - eps R~^{-1} r~ + u_bar_k (Alg. 2.2, Step 6)."""
    p_t, r_t, P_t, R_t = exp.tilde
    return -np.linalg.solve(R_t, P_t), np.linalg.solve(R_t, p_t - eps * r_t) + u_bar


@dataclass(frozen=True)
class LineSearch:
    eps: float
    accepted: bool
    cost_before: float
    cost_after: float


def line_search(stage: StageProblem, exp: Expansion, u_bar, mean_bar, alpha_min=2.0 ** -10) -> LineSearch:
    """Algorithm 2.3: halve eps_k from 1 until the costs-to-go at p_bar_k do not increase.

    Parameters
    ----------
    stage : StageProblem
    exp : Expansion
    u_bar, mean_bar : numpy.ndarray
        Reference input and estimate mean.
    alpha_min : float
        Smallest step tried.

    Returns
    -------
    LineSearch
        The step, whether it was accepted (False: no eps >= ``alpha_min`` decreased the
        costs-to-go, the current policy is locally optimal at this step) and the costs.

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
    before = stage.cost_to_go(u_bar)
    eps = 1.0
    while eps >= alpha_min:
        L, d = policy_step(exp, u_bar, eps)
        after = stage.cost_to_go(L @ mean_bar + d)
        if after <= before:
            return LineSearch(eps, True, before, after)
        eps /= 2
    return LineSearch(eps, False, before, before)


@dataclass
class Alg22Result:
    """Result of Algorithm 2.2.

    ``policy`` the final affine policy; ``policies`` the policy of every iteration
    (policies[0] the initial one); ``costs`` J of each policy in ``policies`` (Monte Carlo
    with common random numbers); ``predicted`` the value approximation V_0(p_0) of each
    new policy; ``eps`` the line-search steps (iterations x K); ``rejected`` how many time
    steps kept their policy; ``converged`` and ``iterations``.
    """

    policy: AffinePolicy
    policies: list
    costs: list
    predicted: list = field(default_factory=list)
    eps: list = field(default_factory=list)
    rejected: list = field(default_factory=list)
    converged: bool = False
    iterations: int = 0
    reference: Reference | None = None


def backward_pass(model, cost, filt, ref: Reference, policy: AffinePolicy, w_points, beta,
                  derivatives="analytic", alpha_min=2.0 ** -10, covariance_hessian="psd", covariance_term=True):
    """Steps 3-8 of Algorithm 2.2 along ``ref``; returns (new policy, V_0, eps, rejected).

    Parameters
    ----------
    model, cost : NonlinearModel and cost
    filt : filter
        Its Dirac mixture is the expansion point.
    ref : Reference
        The reference trajectory (Alg. 2.1).
    policy : AffinePolicy
        The current policy.
    w_points, beta : numpy.ndarray
        Process-noise points and weights.
    derivatives : {"analytic", "numdifftools"}
    alpha_min : float
        Line-search threshold of Alg. 2.3.
    covariance_hessian : {"psd", "exact", "shift"}
    covariance_term : bool
        False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.

    Returns
    -------
    policy : AffinePolicy
    V0 : Value
    eps : list of float
    rejected : int

    Raises
    ------
    ValueError
        If ``derivatives`` or ``covariance_hessian`` is unknown.
    """
    K = ref.u_bar.shape[0]
    value = terminal_value(cost, filt.mixture(ref.estimates[K]))
    L_new, d_new = policy.L.copy(), policy.d.copy()
    eps_k, rejected = np.zeros(K), 0
    for k in range(K - 1, -1, -1):
        stage = StageProblem(model, cost, filt, ref.estimates[k], value, w_points, beta, covariance_hessian,
                             covariance_term)
        exp = stage.expansion(ref.u_bar[k], derivatives)
        R_t = exp.tilde[3]
        if np.linalg.eigvalsh(R_t).min() <= 0:
            warnings.warn(f"Assumption 2.3 fails at k={k}: R~_k is not positive definite "
                          f"(minimal eigenvalue {np.linalg.eigvalsh(R_t).min():.3g}); keeping the policy",
                          RuntimeWarning, stacklevel=2)
            ls = LineSearch(0.0, False, np.nan, np.nan)
        else:
            ls = line_search(stage, exp, ref.u_bar[k], filt.mean(ref.estimates[k]), alpha_min)
        if ls.accepted:
            L_new[k], d_new[k] = policy_step(exp, ref.u_bar[k], ls.eps)
            value = theorem_2_5_value(exp, ls.eps)
        else:
            rejected += 1
            value = affine_policy_value(exp, policy.L[k], policy.d[k], ref.u_bar[k])
        eps_k[k] = ls.eps if ls.accepted else 0.0
    return AffinePolicy(L_new, d_new), value, eps_k, rejected


def algorithm_2_2(model, cost, mean0, cov0, filt=None, policy=None, max_iterations=50, rtol=1e-4,
                  n_cost_runs=200, rng=None, derivatives="analytic", reference_mode="nominal",
                  alpha_min=2.0 ** -10, covariance_hessian="psd", covariance_term=True,
                  progress=False) -> Alg22Result:
    """Algorithm 2.2: iterate reference trajectory (Alg. 2.1) and backward pass (Thms. 2.4-2.5).

    Parameters
    ----------
    model, cost : NonlinearModel and a cost with ``stage``, ``terminal`` and derivatives.
    mean0, cov0 : the initial estimate p_0^x (Gaussian).
    filt : the filter (default :class:`UKF`); its Dirac mixture is the expansion point.
    policy : initial AffinePolicy (default L = 0, d = 0).
    max_iterations, rtol : stop when abs(J^[eta+1] - J^[eta]) <= rtol abs(J^[eta]) (Step 9).
    n_cost_runs, rng : J^[eta] is the mean cost of ``n_cost_runs`` closed-loop runs whose
        random draws are the same in every iteration (common random numbers from ``rng``).
    derivatives : "analytic" (model/cost derivatives where available) or "numdifftools".
    reference_mode : "nominal" or "sampled" (Alg. 2.1); "sampled" draws from ``rng``.
    alpha_min : the constant alpha of Alg. 2.3 below which a step is rejected.
    covariance_hessian : "psd" (default), "exact" or "shift", see :meth:`StageProblem._covariance_hessian`.
    covariance_term : False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.

    Returns
    -------
    Alg22Result
        The policy, the policies and costs per iteration, line-search steps, convergence.

    Raises
    ------
    ValueError
        If the horizon, ``rng``, ``policy``, ``derivatives``, ``reference_mode`` or
        ``covariance_hessian`` is invalid.
    """
    K = check_horizon(cost.K)
    rng = check_rng(rng)
    filt = UKF(model) if filt is None else filt
    policy = AffinePolicy.zero(K, model.n_u, model.n_x) if policy is None else policy
    if policy.L.shape != (K, model.n_u, model.n_x) or policy.d.shape != (K, model.n_u):
        raise ValueError(f"policy: expected L of shape {(K, model.n_u, model.n_x)} and d of shape "
                         f"{(K, model.n_u)}, found {policy.L.shape} and {policy.d.shape}")
    w_points, beta = sigma_points(model.w.mean, model.w.cov)
    noise = draw_noise(model, mean0, cov0, K, n_cost_runs, rng)

    def J(pol):
        return float(simulate(model, cost, mean0, cov0, MeanAffineController(model, pol), noise).costs.mean())

    result = Alg22Result(policy, [policy], [J(policy)])
    iterator = progress_bar(range(max_iterations), progress, desc="Alg. 2.2")
    ref = None
    for _ in iterator:
        ref = reference_trajectory(model, filt, policy, mean0, cov0, reference_mode, rng)
        policy, value, eps, rejected = backward_pass(model, cost, filt, ref, policy, w_points, beta,
                                                     derivatives, alpha_min, covariance_hessian,
                                                     covariance_term)
        result.policies.append(policy)
        result.costs.append(J(policy))
        result.predicted.append(value.at(np.asarray(mean0, float), np.asarray(cov0, float)))
        result.eps.append(eps)
        result.rejected.append(rejected)
        result.iterations += 1
        if abs(result.costs[-1] - result.costs[-2]) <= rtol * abs(result.costs[-2]):
            result.converged = True
            break
    result.policy, result.reference = policy, ref
    if not result.converged:
        warnings.warn(f"Algorithm 2.2 did not converge in {max_iterations} iterations "
                      f"(last change of J {abs(result.costs[-1] - result.costs[-2]):.3g})",
                      RuntimeWarning, stacklevel=2)
    return result
