"""Filters whose state estimate is a Dirac mixture (eq. 2.5), and Lemma 2.1.

* :class:`UKF`: the unscented Kalman filter [101] in the form of the Nonlinear
  Estimation Toolbox [144] the thesis used (sigma points of the joint Gaussian of state
  and noise, sample scaling kappa = 0.5, which gives the 2n+1 points equal weights
  1/(2n+1)). Its sigma points are the Dirac mixture of the estimate (Sec. 2.2).
* :class:`ParticleFilter`: the bootstrap particle filter [6] with systematic resampling.
* :func:`lemma_2_1`: the empirical covariance of the next estimate from joint samples.
* :func:`ekf_step`: the extended Kalman filter (used by the competitor [159]).

UKF functions broadcast over leading axes of ``mean`` (batches of Monte Carlo runs).
"""

from dataclasses import dataclass

import numpy as np

from ._validate import check_psd, check_rng, check_vector, check_weights

KAPPA = 0.5  # sample scaling of the toolbox's UKF: w_0 = kappa / (n + kappa)


@dataclass(frozen=True)
class DiracMixture:
    """p(x) = sum_i alpha_i delta(x - x_i), eq. (2.5).

    Parameters
    ----------
    points : array_like, shape (M, n)
    weights : array_like, shape (M,), non-negative, summing to one (None: equal weights).
    """

    points: np.ndarray
    weights: np.ndarray = None

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[0] == 0 or not np.all(np.isfinite(pts)):
            raise ValueError(f"points: expected a finite array of shape (M, n), found shape {pts.shape}")
        w = np.full(pts.shape[0], 1.0 / pts.shape[0]) if self.weights is None else self.weights
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "weights", check_weights(w, pts.shape[0], "weights"))

    @property
    def mean(self) -> np.ndarray:
        return self.weights @ self.points

    @property
    def cov(self) -> np.ndarray:
        e = self.points - self.mean
        return (self.weights[:, None] * e).T @ e


def _root(cov):
    """Lower Cholesky factor of a batch of covariances (eigen root if singular)."""
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        lam, vec = np.linalg.eigh(cov)
        return vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]


def sigma_points(mean, cov, kappa: float = KAPPA):
    """Sigma points m, m +- sqrt(n + kappa) L_j of N(mean, cov) and their weights [101].

    Parameters
    ----------
    mean : array_like, (..., n)
    cov : array_like, (..., n, n)
    kappa : float
        Spread parameter, kappa > -n.

    Returns
    -------
    points : numpy.ndarray, (..., 2n+1, n)
    weights : numpy.ndarray, (2n+1,)

    Raises
    ------
    ValueError
        If kappa <= -n.
    """
    mean = np.asarray(mean, dtype=float)
    n = mean.shape[-1]
    if kappa <= -n:
        raise ValueError(f"kappa: expected kappa > -n = {-n}, found {kappa}")
    L = np.sqrt(n + kappa) * _root(np.asarray(cov, dtype=float))
    offsets = np.concatenate([np.zeros(L.shape[:-2] + (1, n)), np.swapaxes(L, -1, -2),
                              -np.swapaxes(L, -1, -2)], axis=-2)
    weights = np.full(2 * n + 1, 1.0 / (2 * (n + kappa)))
    weights[0] = kappa / (n + kappa)
    return mean[..., None, :] + offsets, weights


def _moments(points, weights):
    mean = np.einsum("i,...ij->...j", weights, points)
    e = points - mean[..., None, :]
    return mean, e


def _block_diag(P, Q):
    """Batch block-diagonal [[P, 0], [0, Q]] with Q shared."""
    n, m = P.shape[-1], Q.shape[-1]
    out = np.zeros(P.shape[:-2] + (n + m, n + m))
    out[..., :n, :n] = P
    out[..., n:, n:] = Q
    return out


def conditional_covariance(ex, ey, weights):
    """C^{xx} - C^{xy} (C^{yy})^{-1} (C^{xy})^T and the gain from centred samples (Lemma 2.1)."""
    Cxx = np.einsum("i,...ij,...ik->...jk", weights, ex, ex)
    Cxy = np.einsum("i,...ij,...ik->...jk", weights, ex, ey)
    Cyy = np.einsum("i,...ij,...ik->...jk", weights, ey, ey)
    gain = np.swapaxes(np.linalg.solve(Cyy, np.swapaxes(Cxy, -1, -2)), -1, -2)
    post = Cxx - gain @ np.swapaxes(Cxy, -1, -2)
    return 0.5 * (post + np.swapaxes(post, -1, -2)), gain


def lemma_2_1(mixture: DiracMixture, u, model, w_samples, v_samples, beta=None, gamma=None):
    """Covariance C^{xx|y}_{k+1} of the next estimate from joint samples (Lemma 2.1).

    Parameters
    ----------
    mixture : DiracMixture
        The estimate p_k^x (points x_k^i, weights alpha_k^i).
    u : array_like, shape (n_u,)
        The input u_k.
    model : NonlinearModel
        With ``a`` and ``h``.
    w_samples, v_samples : numpy.ndarray, (R, n_w) and (S, n_v)
        Process and measurement noise samples.
    beta, gamma : array_like (R,) and (S,), optional
        Their weights (None: equal weights).

    Returns
    -------
    numpy.ndarray, (n_x, n_x)
        C^{xx} - C^{xy} (C^{yy})^{-1} (C^{xy})^T over all M R S combinations.

    Raises
    ------
    ValueError
        If ``beta`` or ``gamma`` are not valid weights.
    """
    w_samples, v_samples = np.atleast_2d(w_samples), np.atleast_2d(v_samples)
    R, S = w_samples.shape[0], v_samples.shape[0]
    beta = np.full(R, 1.0 / R) if beta is None else check_weights(beta, R, "beta")
    gamma = np.full(S, 1.0 / S) if gamma is None else check_weights(gamma, S, "gamma")
    x_im = model.a(mixture.points[:, None, :], np.asarray(u, dtype=float), w_samples[None, :, :])
    y_imn = model.h(x_im[:, :, None, :], v_samples[None, None, :, :])
    weights = (mixture.weights[:, None, None] * beta[None, :, None] * gamma[None, None, :]).ravel()
    xs = np.broadcast_to(x_im[:, :, None, :], y_imn.shape[:3] + x_im.shape[-1:]).reshape(-1, x_im.shape[-1])
    ys = y_imn.reshape(-1, y_imn.shape[-1])
    _, ex = _moments(xs, weights)
    _, ey = _moments(ys, weights)
    return conditional_covariance(ex, ey, weights)[0]


class UKF:
    """Unscented Kalman filter with non-additive noise (joint sigma points of state and noise).

    The estimate is ``(mean, cov)``; its Dirac mixture is :meth:`mixture` (sigma points).
    ``predict``/``update`` broadcast over leading axes (batches of runs).
    """

    def __init__(self, model, kappa: float = KAPPA):
        self.model, self.kappa = model, kappa

    def initial(self, mean, cov, rng=None):
        mean = check_vector(mean, "mean0")
        return mean, check_psd(cov, "cov0", mean.size)

    def mixture(self, estimate) -> DiracMixture:
        points, weights = sigma_points(*estimate, self.kappa)
        return DiracMixture(points, weights)

    @staticmethod
    def mean(estimate):
        return estimate[0]

    @staticmethod
    def cov(estimate):
        return estimate[1]

    def predict(self, mean, cov, u):
        """Time update through x_{k+1} = a(x_k, u_k, w_k) (eq. 2.1)."""
        m = self.model
        n = mean.shape[-1]
        joint_mean = np.concatenate([mean, np.broadcast_to(m.w.mean, mean.shape[:-1] + m.w.mean.shape)], -1)
        pts, wts = sigma_points(joint_mean, _block_diag(cov, m.w.cov), self.kappa)
        x_next = m.a(pts[..., :n], np.asarray(u)[..., None, :], pts[..., n:])
        mean_p, e = _moments(x_next, wts)
        return mean_p, np.einsum("i,...ij,...ik->...jk", wts, e, e)

    def _measurement(self, mean, cov):
        m = self.model
        n = mean.shape[-1]
        joint_mean = np.concatenate([mean, np.broadcast_to(m.v.mean, mean.shape[:-1] + m.v.mean.shape)], -1)
        pts, wts = sigma_points(joint_mean, _block_diag(cov, m.v.cov), self.kappa)
        y = m.h(pts[..., :n], pts[..., n:])
        _, ex = _moments(pts[..., :n], wts)
        y_hat, ey = _moments(y, wts)
        post, gain = conditional_covariance(ex, ey, wts)
        return y_hat, gain, post

    def update(self, mean, cov, y):
        """Measurement update with y_k = h(x_k, v_k) (eq. 2.2)."""
        y_hat, gain, post = self._measurement(mean, cov)
        return mean + np.einsum("...ij,...j->...i", gain, np.asarray(y) - y_hat), post

    def step(self, estimate, u, y, rng=None):
        """Predict with ``u`` and update with ``y``: the next estimate."""
        return self.update(*self.predict(*estimate, u), y)

    def next_covariance(self, estimate, u):
        """C_{k+1} after predicting with ``u`` and fusing any measurement (Lemma 2.1 at the
        sigma points; it does not depend on the measurement's value)."""
        return self._measurement(*self.predict(*estimate, u))[2]


class ParticleFilter:
    """Bootstrap particle filter [6]: the estimate is a :class:`DiracMixture` of particles.

    Parameters
    ----------
    model : NonlinearModel with a ``likelihood``.
    n_particles : number of particles M.
    rng : numpy.random.Generator for propagation and resampling.
    resample_threshold : resample (systematic) when the effective sample size is below
        this fraction of M.
    """

    def __init__(self, model, n_particles: int, rng, resample_threshold: float = 0.5):
        if model.likelihood is None:
            raise ValueError("model: the particle filter needs model.likelihood(y, x), found None")
        if not isinstance(n_particles, (int, np.integer)) or n_particles < 1:
            raise ValueError(f"n_particles: expected an integer >= 1, found {n_particles!r}")
        self.model, self.M, self.rng = model, int(n_particles), check_rng(rng)
        self.threshold = resample_threshold
        wp, self._beta = sigma_points(model.w.mean, model.w.cov)
        vp, self._gamma = sigma_points(model.v.mean, model.v.cov)
        self._w_points, self._v_points = wp, vp

    def initial(self, mean, cov, rng=None):
        from .models import GaussianNoise
        return DiracMixture(GaussianNoise(mean, cov).sample(self.rng, self.M))

    @staticmethod
    def mixture(estimate):
        return estimate

    @staticmethod
    def mean(estimate):
        return estimate.mean

    @staticmethod
    def cov(estimate):
        return estimate.cov

    def step(self, estimate, u, y, rng=None):
        rng = self.rng if rng is None else check_rng(rng)
        m = self.model
        x = m.a(estimate.points, np.asarray(u, dtype=float), m.w.sample(rng, estimate.points.shape[0]))
        w = estimate.weights * m.likelihood(np.asarray(y, dtype=float), x)
        if not np.isfinite(w.sum()) or w.sum() <= 0:
            raise ValueError("y: the measurement has zero likelihood under every particle")
        w = w / w.sum()
        if 1.0 / np.sum(w ** 2) < self.threshold * w.size:
            idx = np.searchsorted(np.cumsum(w), (rng.random() + np.arange(w.size)) / w.size)
            x, w = x[np.minimum(idx, w.size - 1)], None
        return DiracMixture(x, w)

    def next_covariance(self, estimate, u):
        """Lemma 2.1 with the particles and the sigma points of the noises as samples."""
        return lemma_2_1(estimate, u, self.model, self._w_points, self._v_points, self._beta, self._gamma)


def _numeric_jacobians(model, x, u, w, v):
    import numdifftools as nd
    x, u, w, v = (np.asarray(z, dtype=float) for z in (x, u, w, v))
    a_x = nd.Jacobian(lambda z: model.a(z, u, w))(x)
    a_u = nd.Jacobian(lambda z: model.a(x, z, w))(u)
    a_w = nd.Jacobian(lambda z: model.a(x, u, z))(w)
    h_x = nd.Jacobian(lambda z: model.h(z, v))(x)
    h_v = nd.Jacobian(lambda z: model.h(x, z))(v)
    return tuple(np.atleast_2d(J) for J in (a_x, a_u, a_w, h_x, h_v))


def jacobians(model, x, u, w, v):
    """(a_x, a_u, a_w, h_x, h_v): the model's analytic Jacobians, else numdifftools [46]."""
    if model.jacobians is not None:
        return model.jacobians(x, u, w, v)
    if np.asarray(x).ndim > 1:
        raise ValueError("x: numerical Jacobians take one state, found a batch; give model.jacobians")
    return _numeric_jacobians(model, x, u, w, v)


def ekf_predict(model, mean, cov, u):
    """EKF time update [10]: linearisation of a at (mean, u, E{w})."""
    w0 = np.broadcast_to(model.w.mean, mean.shape[:-1] + model.w.mean.shape)
    v0 = np.broadcast_to(model.v.mean, mean.shape[:-1] + model.v.mean.shape)
    a_x, _, a_w, _, _ = jacobians(model, mean, u, w0, v0)
    Gamma = a_x @ cov @ np.swapaxes(a_x, -1, -2) + a_w @ model.w.cov @ np.swapaxes(a_w, -1, -2)
    return model.a(mean, u, w0), Gamma


def ekf_gain(model, mean, cov):
    """EKF measurement linearisation at (mean, E{v}): (y_hat, gain K, innovation covariance, posterior)."""
    w0 = np.broadcast_to(model.w.mean, mean.shape[:-1] + model.w.mean.shape)
    v0 = np.broadcast_to(model.v.mean, mean.shape[:-1] + model.v.mean.shape)
    u0 = np.zeros(mean.shape[:-1] + (model.n_u,))
    _, _, _, h_x, h_v = jacobians(model, mean, u0, w0, v0)
    S = h_x @ cov @ np.swapaxes(h_x, -1, -2) + h_v @ model.v.cov @ np.swapaxes(h_v, -1, -2)
    K = np.swapaxes(np.linalg.solve(S, h_x @ cov), -1, -2)
    post = cov - K @ h_x @ cov
    return model.h(mean, v0), K, S, 0.5 * (post + np.swapaxes(post, -1, -2))


def ekf_step(model, mean, cov, u, y):
    """One EKF step (predict with u, update with y); broadcasts over leading axes.

    Parameters
    ----------
    model : NonlinearModel
        With ``a``, ``h`` and (optionally) ``jacobians``.
    mean : array_like, (..., n_x)
    cov : array_like, (..., n_x, n_x)
    u : array_like, (..., n_u)
        Input applied between the estimate and the measurement.
    y : array_like, (..., n_y)
        The new measurement.

    Returns
    -------
    mean, cov : numpy.ndarray
        The updated estimate.

    Raises
    ------
    ValueError
        If the model has no Jacobians and a batch of states is passed (numerical Jacobians
        take one state).
    """
    mean_p, cov_p = ekf_predict(model, np.asarray(mean, dtype=float), np.asarray(cov, dtype=float), u)
    y_hat, K, _, post = ekf_gain(model, mean_p, cov_p)
    return mean_p + np.einsum("...ij,...j->...i", K, np.asarray(y) - y_hat), post
