"""The stage problem of Algorithm 2.2: phi_k of eq. (2.13), expanded as (2.15) at the reference.

Theorem 2.4 (:func:`terminal_value`) starts the backward pass; :class:`StageProblem` is
phi_k at one time step, whose gradient and Hessian at the particles of the reference
estimate (:meth:`StageProblem.expansion`, eq. 2.12) give the :class:`Expansion` that
Theorem 2.5 and Algorithm 2.3 (:mod:`asoc.belief.improvement`) turn into the new policy.
"""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from .filters import FILTER_METHODS, DiracMixture
from .models import NonlinearModel, QuadraticCost, cost_for
from .taylor import QuadraticExpansion, statistical_taylor_expansion
from .ukf import UKF

__all__ = ["COVARIANCE_HESSIANS", "filter_for", "Value", "terminal_value", "Expansion",
           "StageProblem"]


COVARIANCE_HESSIANS = ("psd", "exact", "shift")


def filter_for(filt, model, name="filt"):
    """The filter (default: a :class:`~asoc.belief.UKF` of ``model``); raise unless it has the
    methods of :class:`~asoc.belief.BeliefFilter`.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> type(filter_for(None, landmark_example().model)).__name__
    'UKF'
    """
    if filt is None:
        return UKF(model)
    missing = [m for m in FILTER_METHODS if not callable(getattr(filt, m, None))]
    if missing:
        raise TypeError(f"{name}: expected a filter (UKF, ParticleFilter or an object with methods "
                        f"{', '.join(FILTER_METHODS)}), "
                        f"found {type(filt).__name__} without {', '.join(missing)}")
    return filt


@dataclass(frozen=True)
class Value:
    """V_k(p) ~ E{s + v^T x + 1/2 x^T V x + 1/2 tr[S C]} (eq. 2.10).

    Examples
    --------
    >>> V = Value(0.0, np.zeros(2), 2 * np.eye(2), np.eye(2))
    >>> round(V.at([1.0, 0.0], 0.1 * np.eye(2)), 6)
    1.3
    """

    s: float
    v: np.ndarray
    V: np.ndarray
    S: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "s", check.real_scalar(self.s, "s"))
        v = check.vector(self.v, "v")
        object.__setattr__(self, "v", v)
        object.__setattr__(self, "V", check.real_array(self.V, "V", shape=(v.size, v.size)))
        object.__setattr__(self, "S", check.real_array(self.S, "S", shape=(v.size, v.size)))

    def at(self, mean, cov) -> float:
        """The approximation for an estimate with the given mean and covariance."""
        q = QuadraticExpansion(self.s, self.v, self.V)
        covariance_term = 0.5 * float(np.trace(self.S @ np.asarray(cov, dtype=float)))
        return q.expectation(mean, cov) + covariance_term


def terminal_value(cost, mixture) -> Value:
    """Theorem 2.4: statistical expansion of C_K at p_bar_K, S_K = 0.

    Parameters
    ----------
    cost : QuadraticCost
    mixture : DiracMixture
        The terminal estimate p_bar_K, of the cost's state dimension.

    Returns
    -------
    Value

    Raises
    ------
    ValueError, TypeError
        If ``cost`` is not a QuadraticCost or ``mixture`` not a DiracMixture of its dimension.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example()
    >>> V = terminal_value(ex.cost, DiracMixture([[0.0, 3.0]]))
    >>> round(V.s, 6), V.v.round(6).tolist(), V.V.round(6).tolist()
    (9.0, [0.0, -6.0], [[2.0, 0.0], [0.0, 2.0]])
    """
    check.instance(cost, QuadraticCost, "cost")
    check.instance(mixture, DiracMixture, "mixture")
    check.real_array(mixture.points, "mixture.points", shape=(None, cost.Q.shape[0]))
    return _terminal_value(cost, mixture)


def _terminal_value(cost, mixture):
    derivs = cost.terminal_derivatives
    q = statistical_taylor_expansion(cost.terminal, mixture, lambda x: derivs(x)[0],
                                     lambda x: derivs(x)[1])
    return Value(q.s, q.v, q.V, np.zeros_like(q.V))


@dataclass(frozen=True)
class Expansion:
    """Derivatives of phi_k at the particles (eq. 2.12) and their weighted sums.

    Raises
    ------
    ValueError, TypeError
        If the arrays are not finite, real and of consistent shapes, or ``alpha`` is not
        probability weights.

    Examples
    --------
    >>> exp = Expansion(phi=np.zeros(1), p=np.zeros((1, 1)), r=np.ones((1, 1)), Q=np.eye(1)[None],
    ...                 P=np.zeros((1, 1, 1)), R=2 * np.eye(1)[None], points=np.zeros((1, 1)),
    ...                 alpha=np.ones(1))
    >>> [t.tolist() for t in exp.tilde]
    [[0.0], [1.0], [[0.0]], [[2.0]]]
    """

    phi: np.ndarray      # phi_k(x_i, u_bar), (M,)
    p: np.ndarray        # (M, n_x)
    r: np.ndarray        # (M, n_u)
    Q: np.ndarray        # (M, n_x, n_x)
    P: np.ndarray        # (M, n_u, n_x)
    R: np.ndarray        # (M, n_u, n_u)
    points: np.ndarray
    alpha: np.ndarray

    def __post_init__(self):
        points = check.real_array(self.points, "points", ndim=2)
        r = check.real_array(self.r, "r", shape=(points.shape[0], None))
        M, n_x, n_u = points.shape[0], points.shape[1], r.shape[1]
        if 0 in (M, n_x, n_u):
            raise ValueError("points, r: expected non-empty (M, n_x) and (M, n_u), "
                             f"found {points.shape} and {r.shape}")
        shapes = {"phi": (M,), "p": (M, n_x), "Q": (M, n_x, n_x), "P": (M, n_u, n_x),
                  "R": (M, n_u, n_u)}
        for name, shape in shapes.items():
            object.__setattr__(self, name, check.real_array(getattr(self, name), name, shape=shape))
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "r", r)
        object.__setattr__(self, "alpha", check.probability_vector(self.alpha, "alpha", M))

    @property
    def tilde(self):
        """(p~, r~, P~, R~) of eq. (2.12)."""
        a = self.alpha
        return (np.einsum("i,iuj,ij->u", a, self.P, self.points), a @ self.r,
                np.einsum("i,iuj->uj", a, self.P), np.einsum("i,iuv->uv", a, self.R))


class StageProblem:
    """phi_k of eq. (2.13) at time step k for the reference estimate p_bar_k.

    phi_k(x, u) = sum_m beta_m [C_k(x, u) + s_{k+1} + v_{k+1}^T a(x, u, w_m)
    + 1/2 a^T V_{k+1} a] + 1/2 tr[S_{k+1} C_{k+1}(u)], where C_{k+1}(u) is the covariance of the
    next estimate from Lemma 2.1 (the filter's ``covariance_map``), which is what makes the
    controller dual. ``covariance_term=False`` drops that term (the certainty-equivalent control
    run of the notebook).

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost
    filt : BeliefFilter
        Used through :class:`~asoc.belief.BeliefFilter` only (``mixture``, ``covariance_map``).
    estimate : object
        The filter's estimate p_bar_k (for the UKF a tuple (mean, cov)).
    nxt : Value
        V_{k+1} of eq. (2.10).
    w_points, beta : array_like, (R, n_w) and (R,)
        Process-noise points and weights.
    covariance_hessian : {"psd", "exact", "shift"}
    covariance_term : bool

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or value.

    Examples
    --------
    >>> from asoc.belief import UKF, landmark_example, sigma_points
    >>> ex = landmark_example(K=1)
    >>> filt = UKF(ex.model)
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> nxt = Value(0.0, np.zeros(2), np.zeros((2, 2)), np.zeros((2, 2)))
    >>> stage = StageProblem(ex.model, ex.cost, filt, filt.initial(ex.mean0, ex.cov0), nxt, w, beta)
    >>> round(stage.cost_to_go(np.zeros(2)), 2)     # E{(x - x_T)^T (x - x_T)} = 25 + tr C_0
    25.08
    """

    def __init__(self, model, cost, filt, estimate, nxt: Value, w_points, beta,
                 covariance_hessian="psd", covariance_term=True):
        self.model = check.instance(model, NonlinearModel, "model")
        self.cost, self.filt = cost_for(cost, model), filter_for(filt, model)
        self.covariance_hessian = check.choice(covariance_hessian, "covariance_hessian",
                                               COVARIANCE_HESSIANS)
        self.covariance_term = check.boolean(covariance_term, "covariance_term")
        self.nxt = check.instance(nxt, Value, "nxt")
        if nxt.v.shape != (model.n_x,):
            raise ValueError(f"nxt: expected a value of state dimension {model.n_x}, "
                             f"found v of shape {nxt.v.shape}")
        self.w_points = check.real_array(w_points, "w_points", shape=(None, model.w.dim))
        self.beta = check.probability_vector(beta, "beta", self.w_points.shape[0])
        try:
            self.mixture = filt.mixture(estimate)
        except (TypeError, ValueError, IndexError, AttributeError) as err:
            raise TypeError(f"estimate: expected an estimate of the filter {type(filt).__name__}, "
                            f"found {type(estimate).__name__} ({err})") from None
        check.real_array(self.mixture.points, "estimate", shape=(None, model.n_x))
        self._next_covariance = self.filt.covariance_map(estimate)
        self._has_covariance_term = self.covariance_term and bool(np.any(nxt.S))

    def particle_part(self, x, u):
        """All of phi_k except the covariance term, for x (..., n_x) and u (..., n_u)."""
        x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
        a = self.model.a(x[..., None, :], u[..., None, :], self.w_points)
        nxt = self.nxt
        inner = a @ nxt.v + 0.5 * np.einsum("...mi,ij,...mj->...m", a, nxt.V, a)
        return self.cost.stage(x, u) + nxt.s + inner @ self.beta

    def covariance_part(self, u):
        """1/2 tr[S_{k+1} C_{k+1}(u)] (0 without the covariance term)."""
        return self._covariance_part(check.vector(u, "u", self.model.n_u))

    def _covariance_part(self, u):
        """:meth:`covariance_part` for an unchecked float array u (n_u,), in numdifftools' loop."""
        if not self._has_covariance_term:
            return 0.0
        return 0.5 * float(np.trace(self.nxt.S @ self._next_covariance(u)))

    def cost_to_go(self, u) -> float:
        """sum_i alpha_i phi_k(x_i, u): the costs-to-go at p_bar_k compared in Alg. 2.3."""
        particles = float(self.mixture.weights @ self.particle_part(self.mixture.points, u))
        return particles + self.covariance_part(u)

    def expansion(self, u_bar, derivatives="analytic") -> Expansion:
        """Gradient and Hessian of phi_k at (x_i, u_bar) for every particle (eq. 2.12).

        ``derivatives="analytic"`` uses the model's Jacobians and the cost's derivatives
        where they exist (affine dynamics); the covariance term and everything else is
        differentiated by numdifftools [46]. ``"numdifftools"`` differentiates all of phi.
        """
        import numdifftools as nd
        derivatives = check.choice(derivatives, "derivatives", ("analytic", "numdifftools"))
        u_bar = check.real_array(u_bar, "u_bar", shape=(self.model.n_u,))
        X, alpha = self.mixture.points, self.mixture.weights
        nx, nu = X.shape[1], np.size(u_bar)
        analytic = (derivatives == "analytic" and self.model.jacobians is not None
                    and self.model.affine)
        G = np.zeros((X.shape[0], nx + nu))
        H = np.zeros((X.shape[0], nx + nu, nx + nu))
        for i, x in enumerate(X):
            if analytic:
                G[i], H[i] = self._analytic(x, u_bar)
            else:
                f = lambda z: self.particle_part(z[:nx], z[nx:])
                z = np.concatenate([x, u_bar])
                G[i], H[i] = nd.Gradient(f)(z), nd.Hessian(f)(z)
        if self._has_covariance_term:
            G[:, nx:] += np.atleast_1d(nd.Gradient(self._covariance_part)(u_bar))
            H[:, nx:, nx:] += self._covariance_hessian(u_bar)
        H = 0.5 * (H + np.swapaxes(H, 1, 2))
        if self.covariance_hessian == "shift":
            H[:, nx:, nx:] += self.levenberg_marquardt_shift(alpha, H, nx) * np.eye(nu)
        phi = self.particle_part(X, u_bar) + self.covariance_part(u_bar)
        return Expansion(phi, G[:, :nx], G[:, nx:], H[:, :nx, :nx], H[:, nx:, :nx], H[:, nx:, nx:],
                         X, alpha)

    @staticmethod
    def levenberg_marquardt_shift(alpha, H, nx):
        """Levenberg-Marquardt shift mu >= 0 of R~_k for ``covariance_hessian="shift"`` (2.9).

        The smallest mu (bisection, relative accuracy 1e-6) for which the weighted Hessian
        [[Q~, P~^T], [P~, R~ + mu I]] of phi_k satisfies the conditions (2.9) of Assumption
        2.3: R~_k + mu I > 0 and the Schur complement Q~ - P~^T (R~_k + mu I)^{-1} P~ >= 0.
        The Schur complement is V_k + S_k - S_k of eq. (2.11), so the value function stays
        convex in E{x_k}. mu = 0 when the exact Hessian already satisfies (2.9).

        Parameters
        ----------
        alpha : array_like, shape (N,)
            Weights of the N sample Hessians.
        H : array_like, shape (N, nx + nu, nx + nu)
            Hessians of phi_k in (x, u) at the samples.
        nx : int
            State dimension: the leading block of H is the state's.

        Examples
        --------
        >>> H = np.array([[[2.0, 1.0], [1.0, 0.0]]])
        >>> round(StageProblem.levenberg_marquardt_shift([1.0], H, 1), 4)
        0.5
        """
        H = check.real_array(H, "H", ndim=3)
        alpha = check.real_array(alpha, "alpha", shape=(len(H),))
        nx = check.integer(nx, "nx", minimum=1)
        if H.shape[1] != H.shape[2] or H.shape[1] <= nx:
            raise ValueError(f"H: expected shape (N, nx + nu, nx + nu) with nx = {nx} and nu >= 1, "
                             f"found shape {H.shape}")
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
        return float(hi)

    def _covariance_hessian(self, u_bar):
        """Hessian of 1/2 tr[S_{k+1} C_{k+1}(u)] in u (numdifftools); the safeguard against
        its negative curvature depends on ``covariance_hessian``.

        The thesis asserts R~_k > 0 (after Theorem 2.5) from Assumption 2.3, which covers
        C_k but not this term; its curvature can be negative and then R~_k loses
        definiteness. ``"psd"`` sets the term's negative eigenvalues to zero (R~_k >=
        grad_uu C_k > 0; the gradient, the first-order dual effect, is unchanged);
        ``"exact"`` keeps the Hessian (Alg. 2.2 then keeps the old policy where R~_k is
        indefinite); ``"shift"`` keeps it and shifts R~_k by mu I only as far as needed
        (:meth:`levenberg_marquardt_shift`), as in Levenberg-Marquardt-regularised DDP.
        """
        import numdifftools as nd
        Hc = np.atleast_2d(nd.Hessian(self._covariance_part)(u_bar))
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
        v_mean = np.broadcast_to(m.v.mean, (R,) + m.v.mean.shape)
        a_x, a_u = m.jacobians(xs, us, self.w_points, v_mean)[:2]
        # J: (R, n_x, n_x + n_u)
        J = np.concatenate([np.broadcast_to(a_x, (R,) + a_x.shape[-2:]),
                            np.broadcast_to(a_u, (R,) + a_u.shape[-2:])], axis=-1)
        lam = a @ nxt.V + nxt.v                                       # dV_{k+1}/dx at a
        g = gC + np.einsum("m,mij,mi->j", self.beta, J, lam)
        Hs = HC + np.einsum("m,mij,ik,mkl->jl", self.beta, J, nxt.V, J)
        return g, Hs

