"""What a filter is to Algorithm 2.2, and the pieces every filter shares (Sec. 2.2, Lemma 2.1).

* :class:`BeliefFilter`: the protocol of a filter whose estimate has a Dirac mixture (2.5);
  :class:`~asoc.belief.UKF` and :class:`~asoc.belief.ParticleFilter` implement it;
* :class:`DiracMixture`: p(x) = sum_i alpha_i delta(x - x_i), eq. (2.5);
* :func:`sigma_points`: the unscented transform's points of a Gaussian [101];
* :func:`next_estimate_covariance`: Lemma 2.1, the next estimate's covariance from joint samples.

Functions of Gaussian estimates broadcast over leading axes of ``mean`` (batches of runs).
"""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .. import validation
from .models import NonlinearModel

__all__ = ["KAPPA", "BeliefFilter", "FILTER_METHODS", "DiracMixture", "checked_estimate",
           "covariance_root", "sigma_points", "points_around", "unscented_weights",
           "weighted_moments", "weighted_covariance", "solve_or_pinv", "conditional_covariance",
           "next_estimate_covariance"]


KAPPA = 0.5  # sample scaling of the toolbox's UKF: w_0 = kappa / (n + kappa)


@runtime_checkable
class BeliefFilter(Protocol):
    """What Algorithms 2.1-2.3 need from a filter (the estimate's type is the filter's own).

    * ``initial(mean, cov)``: the estimate p_0 of a Gaussian initial state;
    * ``step(estimate, u, y)``: the next estimate after the input u and the measurement y;
    * ``mean(estimate)``: E{x} under the estimate (the policy (2.18) acts on it);
    * ``mixture(estimate)``: its Dirac mixture, the expansion point of Definition 2.2;
    * ``next_covariance(estimate, u)``: C_{k+1}(u) of Lemma 2.1 (checked arguments);
    * ``covariance_map(estimate)``: the function u -> C_{k+1}(u) for one estimate, which the
      stage problem (2.13) differentiates; it takes a float array u of shape (n_u,) unchecked
      (numerical differentiation calls it thousands of times).

    Examples
    --------
    >>> from asoc.belief import UKF, landmark_example
    >>> isinstance(UKF(landmark_example().model), BeliefFilter)
    True
    """

    def initial(self, mean, cov):
        """The estimate p_0 of a Gaussian initial state with ``mean`` and ``cov``."""

    def step(self, estimate, u, y):
        """The next estimate after the input ``u`` and the measurement ``y``."""

    def mean(self, estimate) -> np.ndarray:
        """E{x} under the estimate (the policy (2.18) acts on it)."""

    def mixture(self, estimate) -> "DiracMixture":
        """The estimate's Dirac mixture, the expansion point of Definition 2.2."""

    def next_covariance(self, estimate, u) -> np.ndarray:
        """C_{k+1}(u) of Lemma 2.1 (checked arguments)."""

    def covariance_map(self, estimate) -> Callable[[np.ndarray], np.ndarray]:
        """The function u -> C_{k+1}(u) for one estimate (u a float array (n_u,), unchecked)."""


#: The methods of :class:`BeliefFilter`, in the order of its documentation.
FILTER_METHODS = ("initial", "step", "mean", "mixture", "next_covariance", "covariance_map")


@dataclass(frozen=True)
class DiracMixture:
    """p(x) = sum_i alpha_i delta(x - x_i), eq. (2.5).

    Parameters
    ----------
    points : array_like, shape (M, n)
        Finite locations, M >= 1, n >= 1.
    weights : array_like, shape (M,), optional
        Non-negative, summing to one (None: equal weights).

    Raises
    ------
    ValueError, TypeError
        If ``points`` is not a finite real (M, n) array or ``weights`` not probability weights.

    Examples
    --------
    >>> mix = DiracMixture([[0.0, 0.0], [2.0, 4.0]])
    >>> mix.mean.tolist(), mix.cov.tolist()
    ([1.0, 2.0], [[1.0, 2.0], [2.0, 4.0]])
    """

    points: np.ndarray
    weights: np.ndarray = None

    def __post_init__(self):
        pts = validation.real_array(self.points, "points", ndim=2)
        if 0 in pts.shape:
            raise ValueError("points: expected a non-empty array of shape (M, n), "
                             f"found shape {pts.shape}")
        weights = validation.weights_or_equal(self.weights, "weights", pts.shape[0])
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "weights", weights)

    @property
    def mean(self) -> np.ndarray:
        """sum_i alpha_i x_i."""
        return self.weights @ self.points

    @property
    def cov(self) -> np.ndarray:
        """sum_i alpha_i (x_i - mean)(x_i - mean)^T."""
        e = self.points - self.mean
        return (self.weights[:, None] * e).T @ e


def checked_estimate(mean, cov, mean_name, cov_name, n=None, definite_check=True):
    """The validated batch of Gaussian estimates: mean (..., n), cov (..., n, n) PSD, broadcastable.

    Examples
    --------
    >>> mean, cov = checked_estimate([0.0, 1.0], np.eye(2), "mean", "cov")
    >>> mean.shape, cov.shape
    ((2,), (2, 2))
    """
    mean = validation.real_array(mean, mean_name)
    if mean.ndim == 0 or mean.shape[-1] == 0 or (n is not None and mean.shape[-1] != n):
        raise ValueError(f"{mean_name}: expected shape (..., {n or 'n'}) with n >= 1, "
                         f"found shape {mean.shape}")
    n = mean.shape[-1]
    cov = validation.real_array(cov, cov_name)
    if cov.ndim < 2 or cov.shape[-2:] != (n, n):
        raise ValueError(f"{cov_name}: expected shape (..., {n}, {n}), found shape {cov.shape}")
    try:
        np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
    except ValueError:
        raise ValueError(f"{mean_name}, {cov_name}: expected broadcastable batch shapes, found "
                         f"{mean.shape} and {cov.shape}") from None
    if definite_check:
        cov = validation.semidefinite(cov, cov_name)
    return mean, cov


def covariance_root(cov):
    """Lower Cholesky factor of a batch of covariances (an eigen root if one is singular).

    Examples
    --------
    >>> covariance_root(np.diag([4.0, 1.0])).tolist()
    [[2.0, 0.0], [0.0, 1.0]]
    >>> R = covariance_root(np.diag([4.0, 0.0]))          # singular: R R^T is still the covariance
    >>> (R @ R.T).tolist()
    [[4.0, 0.0], [0.0, 0.0]]
    """
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        lam, vec = np.linalg.eigh(cov)
        return vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]


def sigma_points(mean, cov, kappa: float = KAPPA, check: bool = True):
    """Sigma points m, m +- sqrt(n + kappa) L_j of N(mean, cov) and their weights [101].

    Parameters
    ----------
    mean : array_like, (..., n)
    cov : array_like, (..., n, n)
        Symmetric positive semi-definite.
    kappa : float
        Spread parameter, kappa > -n.
    check : bool
        False skips the checks (float arrays of matching shapes, the library's own loops).

    Returns
    -------
    points : numpy.ndarray, (..., 2n+1, n)
    weights : numpy.ndarray, (2n+1,)

    Raises
    ------
    ValueError, TypeError
        If the shapes do not match, ``cov`` is not PSD or kappa <= -n.

    Examples
    --------
    >>> points, weights = sigma_points([4.0], [[1.5]])
    >>> points[:, 0].round(4).tolist(), weights.round(4).tolist()
    ([4.0, 5.5, 2.5], [0.3333, 0.3333, 0.3333])
    """
    if check:
        mean, cov = checked_estimate(mean, cov, "mean", "cov")
        kappa = validation.real_scalar(kappa, "kappa", low=-mean.shape[-1], low_open=True)
    return _sigma_points(mean, cov, kappa)


def _sigma_points(mean, cov, kappa):
    n = mean.shape[-1]
    points = points_around(mean, np.sqrt(n + kappa) * covariance_root(cov))
    return points, unscented_weights(n, kappa)


def points_around(mean, L):
    """mean, mean + L_j and mean - L_j for the columns L_j of L; broadcasts over leading axes.

    Examples
    --------
    >>> points_around(np.zeros(1), np.eye(1)).ravel().tolist()
    [0.0, 1.0, -1.0]
    """
    Lt = L.swapaxes(-1, -2)
    centre = np.zeros(Lt.shape[:-2] + (1, Lt.shape[-1]))
    return mean[..., None, :] + np.concatenate([centre, Lt, -Lt], axis=-2)


def unscented_weights(n, kappa):
    """Kappa / (n + kappa) for the mean and 1 / (2 (n + kappa)) for the other 2n sigma points.

    Examples
    --------
    >>> unscented_weights(1, 1.0).tolist()
    [0.5, 0.25, 0.25]
    """
    weights = np.full(2 * n + 1, 1.0 / (2 * (n + kappa)))
    weights[0] = kappa / (n + kappa)
    return weights


def weighted_moments(points, weights):
    """The weighted mean of the points (last axis) and the points centred at it.

    Examples
    --------
    >>> mean, e = weighted_moments(np.array([[0.0], [2.0]]), np.array([0.5, 0.5]))
    >>> mean.tolist(), e.ravel().tolist()
    ([1.0], [-1.0, 1.0])
    """
    mean = weights @ points
    return mean, points - mean[..., None, :]


def weighted_covariance(e, weights):
    """sum_i weights_i e_i e_i^T of centred samples e (..., M, n).

    Examples
    --------
    >>> weighted_covariance(np.array([[-1.0], [1.0]]), np.array([0.5, 0.5])).tolist()
    [[1.0]]
    """
    return (weights[:, None] * e).swapaxes(-1, -2) @ e


def solve_or_pinv(S, B):
    """S^{-1} B, with the pseudo-inverse where S is singular (a degenerate measurement).

    Examples
    --------
    >>> solve_or_pinv(np.zeros((1, 1)), np.ones((1, 1))).tolist()
    [[0.0]]
    """
    if S.shape[-1] == 1 and S.all():
        return B / S
    try:
        return np.linalg.solve(S, B)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(S, hermitian=True) @ B


def conditional_covariance(e, n, weights):
    """C^{xx} - C^{xy} (C^{yy})^{-1} C^{yx} and the gain from centred samples [x, y] (Lemma 2.1).

    ``e`` is (..., M, n + n_y), its first ``n`` columns the state.

    Examples
    --------
    >>> e = np.array([[-1.0, -1.0], [1.0, 1.0]])   # y = x: the measurement removes all uncertainty
    >>> post, gain = conditional_covariance(e, 1, np.array([0.5, 0.5]))
    >>> post.tolist(), gain.tolist()
    ([[0.0]], [[1.0]])
    """
    C = weighted_covariance(e, weights)
    Cxx, Cyx, Cyy = C[..., :n, :n], C[..., n:, :n], C[..., n:, n:]
    gain = solve_or_pinv(Cyy, Cyx).swapaxes(-1, -2)
    post = Cxx - gain @ Cyx
    return 0.5 * (post + post.swapaxes(-1, -2)), gain


def next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta=None, gamma=None,
                             check: bool = True):
    """Lemma 2.1: covariance C^{xx|y}_{k+1} of the next estimate from joint samples.

    Parameters
    ----------
    mixture : DiracMixture
        The estimate p_k^x (points x_k^i, weights alpha_k^i).
    u : array_like, shape (n_u,)
        The input u_k.
    model : NonlinearModel
        With ``a`` and ``h``.
    w_samples, v_samples : array_like, (R, n_w) and (S, n_v)
        Process and measurement noise samples.
    beta, gamma : array_like (R,) and (S,), optional
        Their weights (None: equal weights).
    check : bool
        False skips the checks (float arrays and weights given, the library's own loops).

    Returns
    -------
    numpy.ndarray, (n_x, n_x)
        C^{xx} - C^{xy} (C^{yy})^{-1} (C^{xy})^T over all M R S combinations (the
        pseudo-inverse where C^{yy} is singular).

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or ``beta``, ``gamma`` are not weights.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example()
    >>> mix = DiracMixture(sigma_points(ex.mean0, ex.cov0)[0])
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> v, gamma = sigma_points(ex.model.v.mean, ex.model.v.cov)
    >>> C = next_estimate_covariance(mix, [1.0, 0.0], ex.model, w, v, beta, gamma)
    >>> np.trace(C).round(4)
    np.float64(0.3699)
    """
    if check:
        model = validation.instance(model, NonlinearModel, "model")
        mixture = validation.instance(mixture, DiracMixture, "mixture")
        validation.real_array(mixture.points, "mixture.points", shape=(None, model.n_x))
        u = validation.vector(u, "u", model.n_u)
        w_samples = validation.real_array(w_samples, "w_samples", shape=(None, model.w.dim))
        v_samples = validation.real_array(v_samples, "v_samples", shape=(None, model.v.dim))
        for name, samples in (("w_samples", w_samples), ("v_samples", v_samples)):
            if samples.shape[0] == 0:
                raise ValueError(f"{name}: expected at least one sample, "
                                 f"found shape {samples.shape}")
        beta = validation.weights_or_equal(beta, "beta", w_samples.shape[0])
        gamma = validation.weights_or_equal(gamma, "gamma", v_samples.shape[0])
    return _next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta, gamma)


def _next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta, gamma):
    x_im = model.a(mixture.points[:, None, :], u, w_samples[None, :, :])
    y_imn = model.h(x_im[:, :, None, :], v_samples[None, None, :, :])
    weights = (mixture.weights[:, None, None] * beta[None, :, None] * gamma[None, None, :]).ravel()
    n_x = x_im.shape[-1]
    xs = np.broadcast_to(x_im[:, :, None, :], y_imn.shape[:3] + (n_x,)).reshape(-1, n_x)
    ys = y_imn.reshape(-1, y_imn.shape[-1])
    _, e = weighted_moments(np.concatenate([xs, ys], axis=-1), weights)
    return conditional_covariance(e, xs.shape[-1], weights)[0]
