"""Nonlinear stochastic models (eqs. 2.1-2.2), noise samplers and the cost (2.3).

Every function of the state works on the last axis and broadcasts over leading axes,
so a batch of particles, sigma points or Monte Carlo runs is one call.
"""

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import validation as check

__all__ = ["GaussianNoise", "NonlinearModel", "QuadraticCost", "cost_for", "LandmarkExample",
           "landmark_example", "linear_gaussian_model"]


@dataclass(frozen=True)
class GaussianNoise:
    """Gaussian noise N(mean, cov) with a sampler (Sec. 2.2: "we can draw samples").

    Parameters
    ----------
    mean : array_like, shape (n,)
    cov : array_like, shape (n, n)
        Symmetric positive semi-definite.

    Raises
    ------
    ValueError, TypeError
        If ``mean`` is not a finite real vector or ``cov`` not a PSD ``(n, n)`` matrix.

    Examples
    --------
    >>> noise = GaussianNoise([0.0, 1.0], [[1.0, 0.0], [0.0, 4.0]])
    >>> noise.sample(np.random.default_rng(0), 3).shape
    (3, 2)
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self):
        mean = check.vector(self.mean, "mean")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", check.covariance(self.cov, "cov", mean.size))

    @property
    def dim(self) -> int:
        """The dimension n."""
        return self.mean.size

    def sample(self, rng: np.random.Generator, size=()) -> np.ndarray:
        """Draw samples of shape ``size + (dim,)`` from ``rng`` (``size``: an int or ints)."""
        rng = check.generator(rng)
        shape = (size,) if not isinstance(size, tuple) else size
        shape = tuple(check.integer(s, "size", minimum=0) for s in shape)
        return self.mean + rng.standard_normal(shape + (self.dim,)) @ _psd_root(self.cov).T


def _psd_root(cov):
    """A square root ``S`` with ``S S^T = cov`` that also works for singular ``cov``."""
    lam, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]


@dataclass(frozen=True)
class NonlinearModel:
    """x_{k+1} = a(x_k, u_k, w_k), y_k = h(x_k, v_k) (eqs. 2.1-2.2), time-invariant.

    Parameters
    ----------
    a : callable
        ``a(x, u, w)``, broadcasting over leading axes.
    h : callable
        ``h(x, v)``, returning shape ``(..., n_y)``.
    w, v : GaussianNoise
        Process and measurement noise; the filters use their moments, simulation and particle
        filters their samplers.
    n_x, n_u : int
        State and input dimensions, >= 1.
    likelihood : callable, optional
        ``likelihood(y, x)``, the density p(y | x) (particle filter).
    jacobians : optional ``jacobians(x, u, w, v)`` returning analytic
        ``(a_x, a_u, a_w, h_x, h_v)`` with shapes broadcasting over leading axes.
    affine : bool
        True if ``a`` is affine in (x, u) for every w, so its second derivatives vanish.

    Raises
    ------
    TypeError, ValueError
        If an argument has the wrong type, or ``a``, ``h`` do not return finite arrays of
        shapes ``(n_x,)`` and ``(n_y,)`` at the zero state and input and the noise means.

    Examples
    --------
    >>> m = NonlinearModel(a=lambda x, u, w: x + u + w, h=lambda x, v: x + v,
    ...                    w=GaussianNoise([0.0], [[1.0]]), v=GaussianNoise([0.0], [[1.0]]),
    ...                    n_x=1, n_u=1)
    >>> m.n_y
    1
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

    def __post_init__(self):
        check.function(self.a, "a"), check.function(self.h, "h")
        check.instance(self.w, GaussianNoise, "w"), check.instance(self.v, GaussianNoise, "v")
        object.__setattr__(self, "n_x", check.integer(self.n_x, "n_x", minimum=1))
        object.__setattr__(self, "n_u", check.integer(self.n_u, "n_u", minimum=1))
        for name in ("likelihood", "jacobians"):
            if getattr(self, name) is not None:
                check.function(getattr(self, name), name)
        object.__setattr__(self, "affine", check.boolean(self.affine, "affine"))
        x_next = np.asarray(self.a(np.zeros(self.n_x), np.zeros(self.n_u), self.w.mean))
        if x_next.shape != (self.n_x,) or not np.all(np.isfinite(x_next)):
            raise ValueError(f"a: expected a finite state of shape ({self.n_x},) at x = 0, u = 0, "
                             f"w = E{{w}}, found {x_next!r}")
        y = np.asarray(self.h(np.zeros(self.n_x), self.v.mean))
        if y.ndim != 1 or y.size == 0 or not np.all(np.isfinite(y)):
            raise ValueError("h: expected a finite non-empty measurement vector at x = 0, "
                             f"v = E{{v}}, found {y!r}")

    @property
    def n_y(self) -> int:
        """The measurement dimension."""
        return np.asarray(self.h(np.zeros(self.n_x), self.v.mean)).shape[-1]


@dataclass(frozen=True)
class QuadraticCost:
    """Cost (2.3) with C_k(x, u) = (x - x_T)^T Q (x - x_T) + u^T R u and
    C_K(x) = (x - x_T)^T Q_K (x - x_T).

    This is the form of the example's cost (2.19). ``R`` must be positive definite and
    ``Q``, ``Q_K`` positive semi-definite (Assumption 2.3, eq. 2.9); ``K`` is the horizon.

    Raises
    ------
    ValueError, TypeError
        If a matrix has the wrong shape or violates Assumption 2.3, or ``K`` is not an
        integer >= 1.

    Examples
    --------
    >>> c = QuadraticCost(Q=np.eye(2), R=0.1 * np.eye(2), Q_K=np.eye(2), x_target=[0.0, 3.0], K=20)
    >>> float(c.stage(np.array([1.0, 3.0]), np.array([1.0, 0.0])))
    1.1
    """

    Q: np.ndarray
    R: np.ndarray
    Q_K: np.ndarray
    x_target: np.ndarray
    K: int

    def __post_init__(self):
        x_t = check.vector(self.x_target, "x_target")
        n = x_t.size
        object.__setattr__(self, "x_target", x_t)
        for name, definite, meaning in (("Q", False, "grad_xx C_k >= 0"),
                                        ("Q_K", False, "grad_xx C_K >= 0"),
                                        ("R", True, "grad_uu C_k > 0")):
            try:
                value = check.covariance(getattr(self, name), name, None if name == "R" else n,
                                         definite=definite, scalar=name == "R")
            except ValueError as err:
                raise ValueError(f"{err} (Assumption 2.3: {meaning})") from None
            object.__setattr__(self, name, value)
        object.__setattr__(self, "K", check.integer(self.K, "K (horizon)", minimum=1))

    def stage(self, x, u):
        """C_k(x, u), broadcasting over leading axes."""
        e = np.asarray(x) - self.x_target
        u = np.asarray(u)
        return (np.einsum("...i,ij,...j->...", e, self.Q, e)
                + np.einsum("...i,ij,...j->...", u, self.R, u))

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
        return (np.einsum("...i,ij,...j->...", e, self.Q, e)
                + np.einsum("ij,...ji->...", self.Q, cov)
                + np.einsum("...i,ij,...j->...", np.asarray(u), self.R, np.asarray(u)))

    def gaussian_terminal(self, mean, cov):
        """E{C_K(x)} for x ~ (mean, cov), eq. (2.20)."""
        e = np.asarray(mean) - self.x_target
        return (np.einsum("...i,ij,...j->...", e, self.Q_K, e)
                + np.einsum("ij,...ji->...", self.Q_K, cov))


def cost_for(cost, model_, name: str = "cost") -> QuadraticCost:
    """Raise unless ``cost`` is a :class:`QuadraticCost` matching the model's dimensions.

    Examples
    --------
    >>> ex = landmark_example()
    >>> cost_for(ex.cost, ex.model) is ex.cost
    True
    """
    check.instance(cost, QuadraticCost, name)
    if cost.Q.shape[0] != model_.n_x or cost.R.shape[0] != model_.n_u:
        raise ValueError(f"{name}: expected Q of shape ({model_.n_x}, {model_.n_x}) and R of shape "
                         f"({model_.n_u}, {model_.n_u}) (the model's n_x, n_u), "
                         f"found {cost.Q.shape} and {cost.R.shape}")
    return cost


@dataclass(frozen=True)
class LandmarkExample:
    """The numerical example of Sec. 2.5.3: model, cost (2.19) and initial estimate.

    Examples
    --------
    >>> ex = landmark_example(K=5)
    >>> ex.cost.K, ex.mean0.tolist(), ex.landmark.tolist()
    (5, [-5.0, 3.0], [-3.0, 0.0])
    """

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
        Standard deviation of each component of x_0, > 0.
    x_target : tuple of float
        Target position of the cost (2.19).
    noise_gain : float
        Process-noise gain (0.5 in the thesis), >= 0.
    range_noise : float
        Relative range noise (0.1 in the thesis), > 0.
    input_weight : float
        Input weight of the cost, > 0.

    Returns
    -------
    LandmarkExample
        The model, the cost and the initial estimate.

    Raises
    ------
    ValueError, TypeError
        If ``K`` is not an integer >= 1, a position is not a finite 2-vector, or a
        noise level or weight is out of range.

    Examples
    --------
    >>> ex = landmark_example()
    >>> ex.model.n_x, ex.model.n_y, ex.cost.K
    (2, 1, 20)
    >>> float(ex.model.h(np.array([0.0, 0.0]), np.zeros(1))[0])
    3.0
    """
    K = check.integer(K, "K", minimum=1)
    lm = check.vector(landmark, "landmark", 2)
    mean0 = check.vector(mean0, "mean0", 2)
    x_target = check.vector(x_target, "x_target", 2)
    std0 = check.real_scalar(std0, "std0", low=0, low_open=True)
    noise_gain = check.real_scalar(noise_gain, "noise_gain", low=0)
    range_noise = check.real_scalar(range_noise, "range_noise", low=0, low_open=True)
    input_weight = check.real_scalar(input_weight, "input_weight", low=0, low_open=True)
    n = 2

    def a(x, u, w):
        return np.asarray(x) + np.asarray(u) + noise_gain * np.asarray(w)

    def distance(x):
        """||x - x^|| (last axis kept): np.linalg.norm's sum of squares, without its checks."""
        diff = np.asarray(x) - lm
        return np.sqrt(np.add.reduce(diff * diff, axis=-1, keepdims=True))

    def h(x, v):
        return distance(x) * (1.0 + range_noise * np.asarray(v))

    def likelihood(y, x):
        d = distance(x)[..., 0]
        sd = range_noise * d
        return np.exp(-0.5 * ((np.asarray(y)[..., 0] - d) / sd) ** 2) / (np.sqrt(2 * np.pi) * sd)

    identity, gain_identity = np.eye(n), noise_gain * np.eye(n)
    identity.flags.writeable = gain_identity.flags.writeable = False

    def jacobians(x, u, w, v):
        x = np.asarray(x, dtype=float)
        diff = x - lm
        d = distance(x)
        batch = x.shape[:-1]
        eye, gain_eye = ((identity, gain_identity) if not batch else
                         (np.broadcast_to(identity, batch + (n, n)),
                          np.broadcast_to(gain_identity, batch + (n, n))))
        h_x = ((1.0 + range_noise * np.asarray(v)) * diff / d)[..., None, :]
        h_v = (range_noise * d)[..., None]
        return eye, eye, gain_eye, h_x, h_v

    model_ = NonlinearModel(a=a, h=h, w=GaussianNoise(np.zeros(n), np.eye(n)),
                            v=GaussianNoise(np.zeros(1), np.eye(1)), n_x=n, n_u=n,
                            likelihood=likelihood, jacobians=jacobians, affine=True)
    cost = QuadraticCost(Q=np.eye(n), R=input_weight * np.eye(n), Q_K=np.eye(n),
                         x_target=x_target, K=K)
    return LandmarkExample(model_, cost, mean0, std0 ** 2 * np.eye(n), lm)


def linear_gaussian_model(A, B, H, C, J) -> NonlinearModel:
    """x_{k+1} = A x + B u + H w, y = C x + J v with w, v ~ N(0, I) (the LQG case, Sec. 2.3).

    Parameters
    ----------
    A, B, H, C, J : array_like
        System (n, n), input (n, m), process-noise (n, p), output (q, n) and
        measurement-noise (q, r) matrices; J J^T must be positive definite.

    Returns
    -------
    NonlinearModel
        With analytic Jacobians.

    Raises
    ------
    ValueError, TypeError
        If a matrix is not a finite real 2-D array, the shapes do not fit together, or
        J J^T is singular.

    Examples
    --------
    >>> m = linear_gaussian_model([[1.0]], [[1.0]], [[0.1]], [[1.0]], [[0.5]])
    >>> m.a(np.array([1.0]), np.array([2.0]), np.array([0.0])).tolist()
    [3.0]
    """
    A, B, H, C, J = (check.real_array(M, name, ndim=2) for M, name in ((A, "A"), (B, "B"), (H, "H"),
                                                                        (C, "C"), (J, "J")))
    n_x = A.shape[0]
    check.real_array(A, "A", shape=(n_x, n_x))
    check.real_array(B, "B", shape=(n_x, None))
    check.real_array(H, "H", shape=(n_x, None))
    check.real_array(C, "C", shape=(None, n_x))
    check.real_array(J, "J", shape=(C.shape[0], None))
    if 0 in B.shape + H.shape + C.shape + J.shape + (n_x,):
        raise ValueError(f"A, B, H, C, J: expected non-empty matrices, found shapes "
                         f"{A.shape}, {B.shape}, {H.shape}, {C.shape}, {J.shape}")
    try:
        check.semidefinite(J @ J.T, "J", definite=True)
    except ValueError as err:
        raise ValueError(f"J: expected J J^T positive definite (non-degenerate measurement noise), "
                         f"found {str(err).split('found ')[-1]}") from None
    R = J @ J.T
    n_u = B.shape[1]

    def a(x, u, w):
        return np.asarray(x) @ A.T + np.asarray(u) @ B.T + np.asarray(w) @ H.T

    def h(x, v):
        return np.asarray(x) @ C.T + np.asarray(v) @ J.T

    def likelihood(y, x):
        e = np.asarray(y) - np.asarray(x) @ C.T
        quad = np.einsum("...i,ij,...j->...", e, np.linalg.inv(R), e)
        return np.exp(-0.5 * quad) / np.sqrt(np.linalg.det(2 * np.pi * R))

    def jacobians(x, u, w, v):
        batch = np.asarray(x).shape[:-1]
        return tuple(np.broadcast_to(M, batch + M.shape) for M in (A, B, H, C, J))

    return NonlinearModel(a=a, h=h, w=GaussianNoise(np.zeros(H.shape[1]), np.eye(H.shape[1])),
                          v=GaussianNoise(np.zeros(J.shape[1]), np.eye(J.shape[1])),
                          n_x=n_x, n_u=n_u, likelihood=likelihood, jacobians=jacobians, affine=True)
