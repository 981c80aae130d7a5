"""Belief-space trajectory optimisation by statistical Taylor expansion (Sec. 2.5.2).

Algorithm 2.1 (reference trajectory), Theorem 2.4 (terminal value), Theorem 2.5
(value along the reference, eqs. 2.10-2.13), Algorithm 2.3 (line search on epsilon_k)
and Algorithm 2.2 (the iteration) for the affine policy u_k = L_k E{x_k} + d_k (2.18).
"""

import warnings
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from ..result import IterativeResult
from .filters import UKF, DiracMixture, _NextCovariance, _sigma_points, KAPPA
from .models import NonlinearModel, QuadraticCost, _cost_for
from .simulate import MeanAffineController, _draw_noise, _simulate
from .taylor import QuadraticExpansion, statistical_taylor_expansion

FILTER_METHODS = ("initial", "step", "mean", "mixture", "next_covariance")


@dataclass(frozen=True)
class AffinePolicy:
    """u_k = L_k E{x_k} + d_k for k = 0..K-1 (eq. 2.18); L (K, n_u, n_x), d (K, n_u).

    Raises
    ------
    ValueError, TypeError
        If ``L`` is not a finite real (K, n_u, n_x) array or ``d`` not (K, n_u).

    Examples
    --------
    >>> policy = AffinePolicy.zero(3, 1, 2)
    >>> policy.L.shape, policy(0, np.array([1.0, 2.0])).tolist()
    ((3, 1, 2), [0.0])
    """

    L: np.ndarray
    d: np.ndarray

    def __post_init__(self):
        L = check.real_array(self.L, "L", ndim=3)
        if 0 in L.shape:
            raise ValueError(f"L: expected a non-empty array of shape (K, n_u, n_x), found shape {L.shape}")
        object.__setattr__(self, "L", L)
        object.__setattr__(self, "d", check.real_array(self.d, "d", shape=L.shape[:2]))

    @classmethod
    def zero(cls, K, n_u, n_x):
        """The initial policy L_k = 0, d_k = 0 (Sec. 2.5.2)."""
        K, n_u, n_x = (check.integer(v, name, minimum=1) for v, name in ((K, "K"), (n_u, "n_u"), (n_x, "n_x")))
        return cls(np.zeros((K, n_u, n_x)), np.zeros((K, n_u)))

    def __call__(self, k, mean):
        return self.L[k] @ mean + self.d[k]


def _policy_for(policy, K, model, name="policy") -> AffinePolicy:
    """Raise unless ``policy`` is an AffinePolicy of horizon ``K`` for ``model``."""
    check.instance(policy, AffinePolicy, name)
    if policy.L.shape != (K, model.n_u, model.n_x):
        raise ValueError(f"{name}: expected L of shape {(K, model.n_u, model.n_x)} and d of shape "
                         f"{(K, model.n_u)}, found {policy.L.shape} and {policy.d.shape}")
    return policy


def _filter_for(filt, model, name="filt"):
    """The filter (default: a :class:`UKF` of ``model``); raise unless it has the filter methods."""
    if filt is None:
        return UKF(model)
    missing = [m for m in FILTER_METHODS if not callable(getattr(filt, m, None))]
    if missing:
        raise TypeError(f"{name}: expected a filter (UKF, ParticleFilter or an object with methods "
                        f"{', '.join(FILTER_METHODS)}), found {type(filt).__name__} without {', '.join(missing)}")
    return filt


@dataclass(frozen=True)
class Reference:
    """Reference trajectory {p_bar_{0:K}, u_bar_{0:K-1}} of Algorithm 2.1.

    Examples
    --------
    >>> ref = Reference([(np.zeros(1), np.eye(1))] * 2, np.zeros((1, 1)))
    >>> len(ref.estimates), ref.u_bar.shape
    (2, (1, 1))
    """

    estimates: list
    u_bar: np.ndarray

    def __post_init__(self):
        u_bar = check.real_array(self.u_bar, "u_bar", ndim=2)
        check.instance(self.estimates, (list, tuple), "estimates", "a list of estimates")
        if len(self.estimates) != u_bar.shape[0] + 1:
            raise ValueError(f"estimates: expected {u_bar.shape[0] + 1} estimates (one more than inputs), "
                             f"found {len(self.estimates)}")
        object.__setattr__(self, "u_bar", u_bar)


def reference_trajectory(model, filt, policy: AffinePolicy, mean0, cov0, mode="nominal", rng=None) -> Reference:
    """Algorithm 2.1: simulate the reference estimates under ``policy``.

    ``mode="nominal"`` uses the means E{x_k}, E{w_k}, E{v_k} (the variant the thesis
    mentions after Alg. 2.1); ``mode="sampled"`` draws one sample of each from ``rng``.

    Parameters
    ----------
    model : NonlinearModel
    filt : filter
        E.g. :class:`~asoc.belief.UKF` or :class:`~asoc.belief.ParticleFilter`.
    policy : AffinePolicy
    mean0, cov0 : array_like
        Initial estimate, (n_x,) and (n_x, n_x) positive semi-definite.
    mode : {"nominal", "sampled"}
    rng : numpy.random.Generator, optional
        Needed for ``mode="sampled"``.

    Returns
    -------
    Reference

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, ``mode`` is unknown, or ``rng`` is
        not a Generator when sampling.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> ref = reference_trajectory(ex.model, UKF(ex.model), AffinePolicy.zero(3, 2, 2), ex.mean0, ex.cov0)
    >>> len(ref.estimates), ref.u_bar.shape
    (4, (3, 2))
    """
    model = check.instance(model, NonlinearModel, "model")
    filt = _filter_for(filt, model)
    policy = _policy_for(policy, check.instance(policy, AffinePolicy, "policy").L.shape[0], model)
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    mode = check.choice(mode, "mode", ("nominal", "sampled"))
    if mode == "sampled":
        rng = check.generator(rng)
    return _reference_trajectory(model, filt, policy, mean0, cov0, mode, rng)


def _reference_trajectory(model, filt, policy, mean0, cov0, mode, rng):
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
        return q.expectation(mean, cov) + 0.5 * float(np.trace(self.S @ np.asarray(cov, dtype=float)))


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
    q = statistical_taylor_expansion(cost.terminal, mixture, lambda x: derivs(x)[0], lambda x: derivs(x)[1])
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
    ...                 P=np.zeros((1, 1, 1)), R=2 * np.eye(1)[None], points=np.zeros((1, 1)), alpha=np.ones(1))
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
            raise ValueError(f"points, r: expected non-empty (M, n_x) and (M, n_u), found {points.shape} and {r.shape}")
        shapes = {"phi": (M,), "p": (M, n_x), "Q": (M, n_x, n_x), "P": (M, n_u, n_x), "R": (M, n_u, n_u)}
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


COVARIANCE_HESSIANS = ("psd", "exact", "shift")


class StageProblem:
    """phi_k of eq. (2.13) at time step k for the reference estimate p_bar_k.

    phi_k(x, u) = sum_m beta_m [C_k(x, u) + s_{k+1} + v_{k+1}^T a(x, u, w_m)
    + 1/2 a^T V_{k+1} a] + 1/2 tr[S_{k+1} C_{k+1}(u)], where C_{k+1}(u) is the covariance of the next estimate from Lemma 2.1 (the filter's
    ``next_covariance``), which is what makes the controller dual. ``covariance_term=False``
    drops that term (the certainty-equivalent control run of the notebook).

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost
    filt : filter
    estimate : the filter's estimate p_bar_k (for the UKF a tuple (mean, cov))
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
    >>> from asoc.belief import landmark_example, sigma_points
    >>> ex = landmark_example(K=1)
    >>> filt = UKF(ex.model)
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> nxt = Value(0.0, np.zeros(2), np.zeros((2, 2)), np.zeros((2, 2)))
    >>> stage = StageProblem(ex.model, ex.cost, filt, filt.initial(ex.mean0, ex.cov0), nxt, w, beta)
    >>> round(stage.cost_to_go(np.zeros(2)), 2)     # E{(x - x_T)^T (x - x_T)} = 25 + tr C_0
    25.08
    """

    def __init__(self, model, cost, filt, estimate, nxt: Value, w_points, beta, covariance_hessian="psd",
                 covariance_term=True):
        self.model = check.instance(model, NonlinearModel, "model")
        self.cost, self.filt = _cost_for(cost, model), _filter_for(filt, model)
        self.covariance_hessian = check.choice(covariance_hessian, "covariance_hessian", COVARIANCE_HESSIANS)
        self.covariance_term = check.boolean(covariance_term, "covariance_term")
        self.nxt = check.instance(nxt, Value, "nxt")
        if nxt.v.shape != (model.n_x,):
            raise ValueError(f"nxt: expected a value of state dimension {model.n_x}, found v of shape {nxt.v.shape}")
        self.w_points = check.real_array(w_points, "w_points", shape=(None, model.w.dim))
        self.beta = check.probability_vector(beta, "beta", self.w_points.shape[0])
        try:
            self.mixture = filt.mixture(estimate)
        except (TypeError, ValueError, IndexError, AttributeError) as err:
            raise TypeError(f"estimate: expected an estimate of the filter {type(filt).__name__}, found "
                            f"{type(estimate).__name__} ({err})") from None
        check.real_array(self.mixture.points, "estimate", shape=(None, model.n_x))
        self._next_covariance = _next_covariance_function(self.filt, estimate)
        self._has_covariance_term = self.covariance_term and bool(np.any(nxt.S))
        self._S_transposed = np.ascontiguousarray(nxt.S.T)     # what np.vdot would copy at every call
        self._prefetched = {}            # u.tobytes() -> 1/2 tr[S C(u)]: :meth:`_prefetch_covariance_part`

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
        """:meth:`covariance_part` for a float array u (n_u,), unchecked: numdifftools' inner loop.

        A value that :meth:`_prefetch_covariance_part` computed for u is looked up by the
        bytes of u (the same number).
        """
        if not self._has_covariance_term:
            return 0.0
        value = self._prefetched.get(u.tobytes()) if u.dtype == np.float64 and u.ndim == 1 else None
        if value is None:
            value = 0.5 * float(np.vdot(self._S_transposed, self._next_covariance(u)))     # tr[S C]
        return value

    def _prefetch_covariance_part(self, u_bar):
        """Compute :meth:`_covariance_part` at numdifftools' evaluation points for ``u_bar`` at once.

        numdifftools' Gradient and Hessian choose their evaluation points from ``u_bar`` alone
        (:func:`_numdifftools_points`), not from the function's values; the UKF's
        :meth:`_NextCovariance.many` evaluates C_{k+1} at all of them in one stacked
        evaluation (bit-identical to one evaluation per point with this project's BLAS
        kernels, within rounding with others), and :meth:`_covariance_part` then looks them
        up: the derivatives are numdifftools' on these numbers. These
        values replace those of an earlier call. Nothing is prefetched without the UKF's
        stacked evaluation or the covariance term, or if the stacked value at ``u_bar``
        differs from the direct one (a model whose ``a`` or ``h`` rounds differently on a
        stack of inputs).
        """
        self._prefetched = {}
        if not (self._has_covariance_term and isinstance(self._next_covariance, _NextCovariance)):
            return
        points = _numdifftools_points(u_bar)                  # points[0] is u_bar; None: not predictable
        if points is None:
            return
        values = [0.5 * float(np.vdot(self._S_transposed, C)) for C in self._next_covariance.many(points)]
        if values[0] == self._covariance_part(u_bar):
            self._prefetched = {point.tobytes(): float(value) for point, value in zip(points, values)}

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
        derivatives = check.choice(derivatives, "derivatives", ("analytic", "numdifftools"))
        u_bar = check.real_array(u_bar, "u_bar", shape=(self.model.n_u,))
        X, alpha = self.mixture.points, self.mixture.weights
        nx, nu = X.shape[1], np.size(u_bar)
        analytic = derivatives == "analytic" and self.model.jacobians is not None and self.model.affine
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
            self._prefetch_covariance_part(u_bar)
            G[:, nx:] += np.atleast_1d(nd.Gradient(self._covariance_part)(u_bar))
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
        a_x, a_u = m.jacobians(xs, us, self.w_points, np.broadcast_to(m.v.mean, (R,) + m.v.mean.shape))[:2]
        J = np.concatenate([np.broadcast_to(a_x, (R,) + a_x.shape[-2:]),
                            np.broadcast_to(a_u, (R,) + a_u.shape[-2:])], axis=-1)  # (R, n_x, n_x + n_u)
        lam = a @ nxt.V + nxt.v                                       # dV_{k+1}/dx at a
        g = gC + np.einsum("m,mij,mi->j", self.beta, J, lam)
        Hs = HC + np.einsum("m,mij,ik,mkl->jl", self.beta, J, nxt.V, J)
        return g, Hs


def _numdifftools_points(x):
    """The points at which numdifftools' Gradient and Hessian (default settings: central
    differences) evaluate a function of ``x`` (n,), as an array (number of points, n).

    The points depend on ``x`` only: numdifftools' steps h at ``x`` (its step generator),
    combined as its central-difference rules combine them, with the same floating-point
    additions: x (first), x +- h_k e_k (Gradient), x +- 2 h_k e_k and (x +- h_i e_i) +- h_j e_j
    for i < j (Hessian). The steps come from numdifftools' ``_get_steps`` (what its
    ``__call__`` uses). Used to prefetch function values only: a point numdifftools asks for
    that is not here is evaluated directly (tests check that there is none). None when this
    numdifftools has no ``_get_steps`` (a version other than the pinned one): then nothing is
    prefetched, and the derivatives are the same, only slower.
    """
    import numdifftools as nd
    n = x.size
    try:
        gradient, hessian = (_step_offsets(derivative, x) for derivative in (nd.Gradient(None), nd.Hessian(None)))
    except AttributeError:
        return None
    first, second = (hessian[:, index] for index in np.triu_indices(n, 1))
    parts = [x[None], x + gradient, x - gradient, x + 2 * hessian, x - 2 * hessian]
    for shifted in (x + first, x - first):
        parts += [shifted + second, shifted - second]
    return np.concatenate([part.reshape(-1, n) for part in parts])


def _step_offsets(derivative, x):
    """h_k e_k for each of numdifftools' steps h at ``x``: (number of steps, n, n), row k of
    each the vector with h_k at k and zeros elsewhere (its rules' increments)."""
    steps, _ = derivative._get_steps(x)
    return np.array(steps)[:, None, :] * np.eye(x.size)


def _next_covariance_function(filt, estimate):
    """u -> C_{k+1}(u) for the estimate: the UKF's unchecked one, else the filter's ``next_covariance``."""
    if isinstance(filt, UKF):
        return filt._covariance_function(estimate)
    return partial(filt.next_covariance, estimate)


def _expansion(exp, name="exp"):
    """An Expansion whose R~_k is positive definite (Assumption 2.3), and its tilde terms."""
    check.instance(exp, Expansion, name)
    tilde = exp.tilde
    lam = np.linalg.eigvalsh(tilde[3]).min()
    if not lam > 0:
        raise ValueError(f"{name}: expected R~_k positive definite (Assumption 2.3), found smallest eigenvalue {lam:.3g}")
    return tilde


def improved_policy_value(exp: Expansion, eps: float) -> Value:
    """Theorem 2.5: s_k, v_k, V_k, S_k of eq. (2.11) for the improved policy (2.17) with step ``eps``.

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
    >>> exp = Expansion(phi=np.array([1.0]), p=np.zeros((1, 1)), r=np.array([[2.0]]), Q=np.eye(1)[None],
    ...                 P=np.zeros((1, 1, 1)), R=np.eye(1)[None], points=np.zeros((1, 1)), alpha=np.ones(1))
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
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X) + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
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
    >>> exp = Expansion(phi=np.array([1.0]), p=np.zeros((1, 1)), r=np.array([[2.0]]), Q=np.eye(1)[None],
    ...                 P=np.zeros((1, 1, 1)), R=np.eye(1)[None], points=np.zeros((1, 1)), alpha=np.ones(1))
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
         + a @ (exp.phi - np.einsum("ij,ij->i", exp.p, X) + 0.5 * np.einsum("ij,ijk,ik->i", X, exp.Q, X)))
    v = L.T @ g + P_t.T @ delta + L.T @ R_t @ delta + a @ (exp.p - np.einsum("ijk,ik->ij", exp.Q, X))
    V = np.einsum("i,ijk->jk", a, exp.Q) + M
    return Value(float(s), v, 0.5 * (V + V.T), -0.5 * (M + M.T))


def _policy_step(exp: Expansion, u_bar, eps):
    """L_k = -R~^{-1} P~, d_k = R~^{-1} p~ - eps R~^{-1} r~ + u_bar_k (Alg. 2.2, Step 6)."""
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
            return LineSearch(eps=eps, cost_before=before, cost_after=after, converged=True, status="converged",
                              message=f"the step eps = {eps:g} does not increase the costs-to-go")
        eps /= 2
    return LineSearch(eps=eps, cost_before=before, cost_after=before, converged=False, status="no_progress",
                      message=f"no step eps >= alpha_min = {alpha_min:g} decreases the costs-to-go")


@dataclass(kw_only=True)
class TrajectoryOptimizationResult(IterativeResult):
    """Result of Algorithm 2.2 (belief-space trajectory optimisation by statistical Taylor expansion).

    ``policy`` the final affine policy; ``policies`` the policy of every iteration
    (policies[0] the initial one); ``costs`` J of each policy in ``policies`` (Monte Carlo
    with common random numbers); ``predicted`` the value approximation V_0(p_0) of each
    new policy; ``eps`` the line-search steps (iterations x K); ``rejected`` how many time
    steps kept their policy; ``iterations``; ``reference`` the last reference trajectory;
    ``converged``, ``status`` and ``message`` say why the iteration stopped (``converged``:
    the relative change of J met ``rtol``; ``max_iterations``; ``diverged``: J became
    non-finite; ``linalg_error``: a linear-algebra step failed).

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = optimize_belief_trajectory(ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0),
    ...                                  n_cost_runs=10)
    >>> res.status, res.iterations, round(res.costs[-1], 2) < round(res.costs[0], 2)
    ('converged', 2, True)
    """

    policy: AffinePolicy
    policies: list
    costs: list
    predicted: list = field(default_factory=list)
    eps: list = field(default_factory=list)
    rejected: list = field(default_factory=list)
    iterations: int = 0
    reference: Reference | None = None


def backward_pass(model, cost, filt, ref: Reference, policy: AffinePolicy, w_points, beta,
                  derivatives="analytic", alpha_min=2.0 ** -10, covariance_hessian="psd", covariance_term=True):
    """Steps 3-8 of Algorithm 2.2 along ``ref``; returns (new policy, V_0, eps, rejected).

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost
    filt : filter
        Its Dirac mixture is the expansion point.
    ref : Reference
        The reference trajectory (Alg. 2.1).
    policy : AffinePolicy
        The current policy.
    w_points, beta : array_like, (R, n_w) and (R,)
        Process-noise points and weights.
    derivatives : {"analytic", "numdifftools"}
    alpha_min : float
        Line-search threshold of Alg. 2.3, in (0, 1].
    covariance_hessian : {"psd", "exact", "shift"}
    covariance_term : bool
        False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.

    Returns
    -------
    policy : AffinePolicy
    V0 : Value
    eps : numpy.ndarray
    rejected : int

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or an option is unknown.

    Examples
    --------
    >>> from asoc.belief import landmark_example, sigma_points
    >>> ex = landmark_example(K=2)
    >>> filt, policy = UKF(ex.model), AffinePolicy.zero(2, 2, 2)
    >>> ref = reference_trajectory(ex.model, filt, policy, ex.mean0, ex.cov0)
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> new, V0, eps, rejected = backward_pass(ex.model, ex.cost, filt, ref, policy, w, beta)
    >>> eps.tolist(), rejected, new.d.round(2).tolist()
    ([1.0, 1.0], 0, [[0.0, 2.73], [0.0, 2.73]])
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = _cost_for(cost, model)
    filt = _filter_for(filt, model)
    check.instance(ref, Reference, "ref")
    K = ref.u_bar.shape[0]
    if K != cost.K or len(ref.estimates) != K + 1:
        raise ValueError(f"ref: expected a reference of horizon cost.K = {cost.K}, found {K} inputs and "
                         f"{len(ref.estimates)} estimates")
    policy = _policy_for(policy, K, model)
    w_points = check.real_array(w_points, "w_points", shape=(None, model.w.dim))
    beta = check.probability_vector(beta, "beta", w_points.shape[0])
    return _backward_pass(model, cost, filt, ref, policy, w_points, beta, *_options(
        derivatives, alpha_min, covariance_hessian, covariance_term))


def _options(derivatives, alpha_min, covariance_hessian, covariance_term):
    return (check.choice(derivatives, "derivatives", ("analytic", "numdifftools")),
            check.real_scalar(alpha_min, "alpha_min", low=0, high=1, low_open=True),
            check.choice(covariance_hessian, "covariance_hessian", COVARIANCE_HESSIANS),
            check.boolean(covariance_term, "covariance_term"))


def _backward_pass(model, cost, filt, ref, policy, w_points, beta, derivatives, alpha_min, covariance_hessian,
                   covariance_term):
    K = ref.u_bar.shape[0]
    value = _terminal_value(cost, filt.mixture(ref.estimates[K]))
    L_new, d_new = policy.L.copy(), policy.d.copy()
    eps_k, rejected = np.zeros(K), 0
    for k in range(K - 1, -1, -1):
        stage = StageProblem(model, cost, filt, ref.estimates[k], value, w_points, beta, covariance_hessian,
                             covariance_term)
        exp = stage.expansion(ref.u_bar[k], derivatives)
        lam = np.linalg.eigvalsh(exp.tilde[3]).min()
        if not lam > 0:
            warnings.warn(f"Assumption 2.3 fails at k={k}: R~_k is not positive definite "
                          f"(minimal eigenvalue {lam:.3g}); keeping the policy", RuntimeWarning, stacklevel=3)
            accepted, eps = False, 0.0
        else:
            ls = _line_search(stage, exp, ref.u_bar[k], filt.mean(ref.estimates[k]), alpha_min)
            accepted, eps = ls.accepted, ls.eps
        if accepted:
            L_new[k], d_new[k] = _policy_step(exp, ref.u_bar[k], eps)
            value = _improved_policy_value(exp, eps)
        else:
            rejected += 1
            value = _affine_policy_value(exp, policy.L[k], policy.d[k], ref.u_bar[k])
        eps_k[k] = eps if accepted else 0.0
    return AffinePolicy(L_new, d_new), value, eps_k, rejected


def optimize_belief_trajectory(model, cost, mean0, cov0, filt=None, policy=None, max_iterations=50, rtol=1e-4,
                               n_cost_runs=200, rng=None, derivatives="analytic", reference_mode="nominal",
                               alpha_min=2.0 ** -10, covariance_hessian="psd", covariance_term=True,
                               progress=False) -> TrajectoryOptimizationResult:
    """Algorithm 2.2: belief-space trajectory optimisation by statistical Taylor expansion.

    Iterates the reference trajectory (Alg. 2.1) and the backward pass (Thms. 2.4-2.5,
    line search Alg. 2.3) for the affine policy u_k = L_k E{x_k} + d_k (2.18).

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost (its ``K`` is the horizon).
    mean0, cov0 : the initial estimate p_0^x (Gaussian), (n_x,) and (n_x, n_x) PSD.
    filt : the filter (default :class:`UKF`); its Dirac mixture is the expansion point.
    policy : initial AffinePolicy (default L = 0, d = 0).
    max_iterations : int
        Iteration limit, >= 1.
    rtol : float
        Stop when abs(J^[eta+1] - J^[eta]) <= rtol abs(J^[eta]) (Step 9), rtol > 0.
    n_cost_runs, rng : J^[eta] is the mean cost of ``n_cost_runs`` (>= 1) closed-loop runs whose
        random draws are the same in every iteration (common random numbers from ``rng``).
    derivatives : "analytic" (model/cost derivatives where available) or "numdifftools".
    reference_mode : "nominal" or "sampled" (Alg. 2.1); "sampled" draws from ``rng``.
    alpha_min : the constant alpha of Alg. 2.3 below which a step is rejected, in (0, 1].
    covariance_hessian : "psd" (default), "exact" or "shift", see :meth:`StageProblem._covariance_hessian`.
    covariance_term : False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.
    progress : bool
        Show a progress bar.

    Returns
    -------
    TrajectoryOptimizationResult
        The policy, the policies and costs per iteration, line-search steps, and why it stopped.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Warns
    -----
    RuntimeWarning
        If the iteration stops without meeting ``rtol``.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = optimize_belief_trajectory(ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0),
    ...                                  n_cost_runs=10)
    >>> res.converged, res.iterations, res.policy.L.shape
    (True, 2, (3, 2, 2))
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = _cost_for(cost, model)
    K = cost.K
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    filt = _filter_for(filt, model)
    policy = AffinePolicy.zero(K, model.n_u, model.n_x) if policy is None else _policy_for(policy, K, model)
    max_iterations = check.integer(max_iterations, "max_iterations", minimum=1)
    rtol = check.real_scalar(rtol, "rtol", low=0, low_open=True)
    n_cost_runs = check.integer(n_cost_runs, "n_cost_runs", minimum=1)
    rng = check.generator(rng)
    reference_mode = check.choice(reference_mode, "reference_mode", ("nominal", "sampled"))
    options = _options(derivatives, alpha_min, covariance_hessian, covariance_term)
    progress = check.boolean(progress, "progress")
    w_points, beta = _sigma_points(model.w.mean, model.w.cov, KAPPA)
    noise = _draw_noise(model, mean0, cov0, K, n_cost_runs, rng)

    def J(pol):
        return float(_simulate(model, cost, mean0, cov0, MeanAffineController(model, pol), noise).costs.mean())

    policies, costs, predicted, eps_all, rejected_all = [policy], [J(policy)], [], [], []
    status, ref, error = "max_iterations", None, None
    for _ in progress_bar(range(max_iterations), progress, desc="Alg. 2.2"):
        try:
            ref = _reference_trajectory(model, filt, policy, mean0, cov0, reference_mode, rng)
            policy, value, eps, rejected = _backward_pass(model, cost, filt, ref, policy, w_points, beta, *options)
        except np.linalg.LinAlgError as err:
            status, error = "linalg_error", err
            break
        except ValueError as err:       # the inputs are checked: a non-finite intermediate (value, policy)
            status, error = "diverged", err
            break
        policies.append(policy), costs.append(J(policy)), eps_all.append(eps), rejected_all.append(rejected)
        predicted.append(value.at(mean0, cov0))
        if not np.isfinite(costs[-1]):
            status = "diverged"
            break
        if abs(costs[-1] - costs[-2]) <= rtol * abs(costs[-2]):
            status = "converged"
            break
    iterations = len(costs) - 1
    messages = {
        "converged": lambda: f"the relative change of J, {_change(costs):.3g}, met rtol = {rtol:g} "
                             f"after {iterations} iterations",
        "max_iterations": lambda: f"stopped after max_iterations = {max_iterations} with relative change of J "
                                  f"{_change(costs):.3g} > rtol = {rtol:g}",
        "diverged": lambda: (f"J became non-finite ({costs[-1]}) at iteration {iterations}" if error is None
                             else f"an iterate became non-finite at iteration {iterations + 1}: {error}"),
        "linalg_error": lambda: f"a linear-algebra step failed at iteration {iterations + 1}: {error}",
    }
    result = TrajectoryOptimizationResult(
        policy=policy, policies=policies, costs=costs, predicted=predicted, eps=eps_all, rejected=rejected_all,
        iterations=iterations, reference=ref, converged=status == "converged", status=status,
        message=messages[status]())
    if not result.converged:
        warnings.warn(f"Algorithm 2.2 did not converge: {result.message}", RuntimeWarning, stacklevel=2)
    return result


def _change(costs):
    return abs(costs[-1] - costs[-2]) / abs(costs[-2]) if len(costs) > 1 and costs[-2] != 0 else float("inf")
