"""Nonlinear stochastic models (eqs. 2.1-2.2), noise samplers and the cost (2.3).

Every function of the state works on the last axis and broadcasts over leading axes,
so a batch of particles, sigma points or Monte Carlo runs is one call.
"""

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ._validate import check_psd, check_pd, check_vector


@dataclass(frozen=True)
class GaussianNoise:
    """Gaussian noise N(mean, cov) with a sampler (Sec. 2.2: "we can draw samples").

    Parameters
    ----------
    mean : array_like, shape (n,)
    cov : array_like, shape (n, n), symmetric positive semi-definite.
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self):
        mean = check_vector(self.mean, "mean")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", check_psd(self.cov, "cov", mean.size))

    @property
    def dim(self) -> int:
        return self.mean.size

    def sample(self, rng: np.random.Generator, size=()) -> np.ndarray:
        """Draw samples of shape ``size + (dim,)`` from ``rng``."""
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng: expected a numpy.random.Generator, found {type(rng).__name__}")
        size = (size,) if np.isscalar(size) else tuple(size)
        root = _psd_root(self.cov)
        return self.mean + rng.standard_normal(size + (self.dim,)) @ root.T


def _psd_root(cov):
    """A square root ``S`` with ``S S^T = cov`` that also works for singular ``cov``."""
    lam, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.clip(lam, 0.0, None))


@dataclass(frozen=True)
class NonlinearModel:
    """x_{k+1} = a(x_k, u_k, w_k), y_k = h(x_k, v_k) (eqs. 2.1-2.2), time-invariant.

    Parameters
    ----------
    a : callable ``a(x, u, w)`` broadcasting over leading axes.
    h : callable ``h(x, v)`` returning shape ``(..., n_y)``.
    w, v : :class:`GaussianNoise` (process and measurement noise; the filters use their
        moments, simulation and particle filters their samplers).
    n_u : input dimension.
    likelihood : optional ``likelihood(y, x)``, the density p(y | x) (particle filter).
    jacobians : optional ``jacobians(x, u, w, v)`` returning analytic
        ``(a_x, a_u, a_w, h_x, h_v)`` with shapes broadcasting over leading axes.
    affine : True if ``a`` is affine in (x, u) for every w, so its second derivatives vanish.
    """

    a: Callable
    h: Callable
    w: GaussianNoise
    v: GaussianNoise
    n_x: int
    n_u: int
    likelihood: Callable | None = None
    jacobians: Callable | None = None
    affine: bool = False

    @property
    def n_y(self) -> int:
        return np.asarray(self.h(np.zeros(self.n_x), self.v.mean)).shape[-1]


@dataclass(frozen=True)
class QuadraticCost:
    """Cost (2.3) with C_k(x, u) = (x - x_T)^T Q (x - x_T) + u^T R u, C_K(x) = (x - x_T)^T Q_K (x - x_T).

    This is the form of the example's cost (2.19). ``R`` must be positive definite and
    ``Q``, ``Q_K`` positive semi-definite (Assumption 2.3, eq. 2.9).
    """

    Q: np.ndarray
    R: np.ndarray
    Q_K: np.ndarray
    x_target: np.ndarray
    K: int

    def __post_init__(self):
        x_t = check_vector(self.x_target, "x_target")
        n = x_t.size
        object.__setattr__(self, "x_target", x_t)
        object.__setattr__(self, "Q", check_psd(self.Q, "Q (Assumption 2.3: grad_xx C_k >= 0)", n))
        object.__setattr__(self, "Q_K", check_psd(self.Q_K, "Q_K (Assumption 2.3)", n))
        R = np.atleast_2d(np.asarray(self.R, dtype=float))
        object.__setattr__(self, "R", check_pd(R, "R (Assumption 2.3: grad_uu C_k > 0)", R.shape[0]))
        check_horizon(self.K)

    def stage(self, x, u):
        """C_k(x, u), broadcasting over leading axes."""
        e = np.asarray(x) - self.x_target
        u = np.asarray(u)
        return np.einsum("...i,ij,...j->...", e, self.Q, e) + np.einsum("...i,ij,...j->...", u, self.R, u)

    def terminal(self, x):
        """C_K(x)."""
        e = np.asarray(x) - self.x_target
        return np.einsum("...i,ij,...j->...", e, self.Q_K, e)

    def stage_derivatives(self, x, u):
        """Analytic gradient and Hessian of C_k in z = (x, u): ``(grad, hess)``."""
        g = np.concatenate([2 * self.Q @ (x - self.x_target), 2 * self.R @ u])
        nx, nu = self.Q.shape[0], self.R.shape[0]
        H = np.zeros((nx + nu, nx + nu))
        H[:nx, :nx], H[nx:, nx:] = 2 * self.Q, 2 * self.R
        return g, H

    def terminal_derivatives(self, x):
        """Analytic gradient and Hessian of C_K."""
        return 2 * self.Q_K @ (x - self.x_target), 2 * self.Q_K

    def gaussian_stage(self, mean, cov, u):
        """E{C_k(x, u)} for x ~ (mean, cov): the cost written in the belief, eq. (2.20)."""
        e = np.asarray(mean) - self.x_target
        return (np.einsum("...i,ij,...j->...", e, self.Q, e) + np.einsum("ij,...ji->...", self.Q, cov)
                + np.einsum("...i,ij,...j->...", np.asarray(u), self.R, np.asarray(u)))

    def gaussian_terminal(self, mean, cov):
        """E{C_K(x)} for x ~ (mean, cov), eq. (2.20)."""
        e = np.asarray(mean) - self.x_target
        return np.einsum("...i,ij,...j->...", e, self.Q_K, e) + np.einsum("ij,...ji->...", self.Q_K, cov)


def check_horizon(K):
    """Raise unless the horizon ``K`` is an integer >= 1."""
    if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
        raise ValueError(f"K (horizon) must be an integer >= 1, found {K!r}")
    return int(K)


@dataclass(frozen=True)
class LandmarkExample:
    """The numerical example of Sec. 2.5.3: model, cost (2.19) and initial estimate."""

    model: NonlinearModel
    cost: QuadraticCost
    mean0: np.ndarray
    cov0: np.ndarray
    landmark: np.ndarray = field(default_factory=lambda: np.array([-3.0, 0.0]))


def landmark_example(K: int = 20, landmark=(-3.0, 0.0), mean0=(-5.0, 3.0), std0=0.2,
                     x_target=(0.0, 3.0), noise_gain=0.5, range_noise=0.1,
                     input_weight=0.1) -> LandmarkExample:
    """Sec. 2.5.3: x_{k+1} = x_k + u_k + 0.5 w_k, y_k = ||x_k - x^|| + v_k.

    The measurement noise is v_k ~ N(0, 0.1^2 ||x_k - x^||^2); we write it as
    v_k = 0.1 ||x_k - x^|| nu_k with nu_k ~ N(0, 1), so h(x, nu) is non-additive.
    x_0 ~ N([-5, 3], 0.2^2 I), target [0, 3], K = 20, cost (2.19).

    Parameters
    ----------
    K : int
        Horizon, >= 1.
    landmark : tuple of float
        Position x^ of the landmark.
    mean0 : tuple of float
        Mean of x_0.
    std0 : float
        Standard deviation of each component of x_0.
    x_target : tuple of float
        Target position of the cost (2.19).
    noise_gain : float
        Process-noise gain (0.5 in the thesis).
    range_noise : float
        Relative range noise (0.1 in the thesis).
    input_weight : float
        Input weight of the cost.

    Returns
    -------
    LandmarkExample
        The model, the cost and the initial estimate.

    Raises
    ------
    ValueError
        If ``K`` is not an integer >= 1, or the cost matrices violate Assumption 2.3.
    """
    lm = np.asarray(landmark, dtype=float)
    n = 2

    def a(x, u, w):
        return np.asarray(x) + np.asarray(u) + noise_gain * np.asarray(w)

    def h(x, v):
        d = np.linalg.norm(np.asarray(x) - lm, axis=-1, keepdims=True)
        return d * (1.0 + range_noise * np.asarray(v))

    def likelihood(y, x):
        d = np.linalg.norm(np.asarray(x) - lm, axis=-1)
        sd = range_noise * d
        return np.exp(-0.5 * ((np.asarray(y)[..., 0] - d) / sd) ** 2) / (np.sqrt(2 * np.pi) * sd)

    def jacobians(x, u, w, v):
        x = np.asarray(x, dtype=float)
        diff = x - lm
        d = np.linalg.norm(diff, axis=-1, keepdims=True)
        batch = x.shape[:-1]
        eye = np.broadcast_to(np.eye(n), batch + (n, n))
        h_x = ((1.0 + range_noise * np.asarray(v)) * diff / d)[..., None, :]
        h_v = (range_noise * d)[..., None]
        return eye, eye, noise_gain * eye, h_x, h_v

    model = NonlinearModel(a=a, h=h, w=GaussianNoise(np.zeros(n), np.eye(n)),
                           v=GaussianNoise(np.zeros(1), np.eye(1)), n_x=n, n_u=n,
                           likelihood=likelihood, jacobians=jacobians, affine=True)
    cost = QuadraticCost(Q=np.eye(n), R=input_weight * np.eye(n), Q_K=np.eye(n),
                         x_target=np.asarray(x_target, dtype=float), K=K)
    return LandmarkExample(model, cost, np.asarray(mean0, dtype=float), std0 ** 2 * np.eye(n), lm)


def linear_gaussian_model(A, B, H, C, J) -> NonlinearModel:
    """x_{k+1} = A x + B u + H w, y = C x + J v with w, v ~ N(0, I) (the LQG case, Sec. 2.3).

    Parameters
    ----------
    A, B, H, C, J : array_like
        System, input, process-noise, output and measurement-noise matrices.

    Returns
    -------
    NonlinearModel
        With analytic Jacobians.

    Raises
    ------
    ValueError
        If ``B`` is not 2-D after ``numpy.atleast_2d``; the shapes are otherwise checked when
        the model is evaluated (by NumPy).
    """
    A, B, H, C, J = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, H, C, J))
    n_x, n_u = B.shape

    def a(x, u, w):
        return np.asarray(x) @ A.T + np.asarray(u) @ B.T + np.asarray(w) @ H.T

    def h(x, v):
        return np.asarray(x) @ C.T + np.asarray(v) @ J.T

    def likelihood(y, x):
        R = J @ J.T
        e = np.asarray(y) - np.asarray(x) @ C.T
        quad = np.einsum("...i,ij,...j->...", e, np.linalg.inv(R), e)
        return np.exp(-0.5 * quad) / np.sqrt(np.linalg.det(2 * np.pi * R))

    def jacobians(x, u, w, v):
        batch = np.asarray(x).shape[:-1]
        return tuple(np.broadcast_to(M, batch + M.shape) for M in (A, B, H, C, J))

    return NonlinearModel(a=a, h=h, w=GaussianNoise(np.zeros(H.shape[1]), np.eye(H.shape[1])),
                          v=GaussianNoise(np.zeros(J.shape[1]), np.eye(J.shape[1])), n_x=n_x, n_u=n_u,
                          likelihood=likelihood, jacobians=jacobians, affine=True)
