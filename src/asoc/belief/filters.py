"""Filters whose state estimate is a Dirac mixture (eq. 2.5), and Lemma 2.1.

* :class:`UKF`: the unscented Kalman filter [101] in the form of the Nonlinear
  Estimation Toolbox [144] the thesis used (sigma points of the joint Gaussian of state
  and noise, sample scaling kappa = 0.5, which gives the 2n+1 points equal weights
  1/(2n+1)). Its sigma points are the Dirac mixture of the estimate (Sec. 2.2).
* :class:`ParticleFilter`: the bootstrap particle filter [6] with systematic resampling.
* :func:`next_estimate_covariance`: the empirical covariance of the next estimate from joint samples.
* :func:`ekf_step`: the extended Kalman filter (used by the competitor [159]).

UKF functions broadcast over leading axes of ``mean`` (batches of Monte Carlo runs).
"""

from dataclasses import dataclass
from functools import partial

import numpy as np
from scipy.linalg import lapack

from .. import validation as check
from .models import GaussianNoise, NonlinearModel

KAPPA = 0.5  # sample scaling of the toolbox's UKF: w_0 = kappa / (n + kappa)


@dataclass(frozen=True)
class DiracMixture:
    """p(x) = sum_i alpha_i delta(x - x_i), eq. (2.5).

    Parameters
    ----------
    points : array_like, shape (M, n)
        Finite locations, M >= 1, n >= 1.
    weights : array_like, shape (M,), non-negative, summing to one (None: equal weights).

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
        pts = check.real_array(self.points, "points", ndim=2)
        if 0 in pts.shape:
            raise ValueError(f"points: expected a non-empty array of shape (M, n), found shape {pts.shape}")
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "weights", check.weights_or_equal(self.weights, "weights", pts.shape[0]))

    @property
    def mean(self) -> np.ndarray:
        """sum_i alpha_i x_i."""
        return self.weights @ self.points

    @property
    def cov(self) -> np.ndarray:
        """sum_i alpha_i (x_i - mean)(x_i - mean)^T."""
        e = self.points - self.mean
        return (self.weights[:, None] * e).T @ e


def _root(cov):
    """Lower Cholesky factor of a batch of covariances (eigen root if singular)."""
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        lam, vec = np.linalg.eigh(cov)
        return vec * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]


def _estimate(mean, cov, mean_name, cov_name, n=None, definite_check=True):
    """A batch of Gaussian estimates: mean (..., n), cov (..., n, n) PSD, broadcastable."""
    mean = check.real_array(mean, mean_name)
    if mean.ndim == 0 or mean.shape[-1] == 0 or (n is not None and mean.shape[-1] != n):
        raise ValueError(f"{mean_name}: expected shape (..., {n or 'n'}) with n >= 1, found shape {mean.shape}")
    n = mean.shape[-1]
    cov = check.real_array(cov, cov_name)
    if cov.ndim < 2 or cov.shape[-2:] != (n, n):
        raise ValueError(f"{cov_name}: expected shape (..., {n}, {n}), found shape {cov.shape}")
    try:
        np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
    except ValueError:
        raise ValueError(f"{mean_name}, {cov_name}: expected broadcastable batch shapes, found "
                         f"{mean.shape} and {cov.shape}") from None
    if definite_check:
        cov = check.semidefinite(cov, cov_name)
    return mean, cov


def sigma_points(mean, cov, kappa: float = KAPPA):
    """Sigma points m, m +- sqrt(n + kappa) L_j of N(mean, cov) and their weights [101].

    Parameters
    ----------
    mean : array_like, (..., n)
    cov : array_like, (..., n, n)
        Symmetric positive semi-definite.
    kappa : float
        Spread parameter, kappa > -n.

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
    mean, cov = _estimate(mean, cov, "mean", "cov")
    n = mean.shape[-1]
    kappa = check.real_scalar(kappa, "kappa", low=-n, low_open=True)
    return _sigma_points(mean, cov, kappa)


def _cholesky(cov):
    """Lower Cholesky factor of a covariance or a batch; LinAlgError unless positive definite.

    One matrix goes to LAPACK's dpotrf directly: on the small matrices of the filters,
    numpy.linalg.cholesky's argument handling costs several times the factorisation.
    """
    if cov.ndim > 2:
        return np.linalg.cholesky(cov)
    L, info = lapack.dpotrf(cov, lower=True, clean=True)
    if info != 0:
        raise np.linalg.LinAlgError(f"Matrix is not positive definite (dpotrf info {info})")
    return L


def _sigma_points(mean, cov, kappa):
    n = mean.shape[-1]
    return _points_around(mean, np.sqrt(n + kappa) * _root(cov)), _unscented_weights(n, kappa)


def _points_around(mean, L):
    """mean, mean + L_j and mean - L_j for the columns L_j of L; broadcasts over leading axes."""
    Lt = L.swapaxes(-1, -2)
    return mean[..., None, :] + np.concatenate([np.zeros(Lt.shape[:-2] + (1, Lt.shape[-1])), Lt, -Lt], axis=-2)


def _unscented_weights(n, kappa):
    """kappa / (n + kappa) for the mean and 1 / (2 (n + kappa)) for the other 2n sigma points."""
    weights = np.full(2 * n + 1, 1.0 / (2 * (n + kappa)))
    weights[0] = kappa / (n + kappa)
    return weights


class _Augmented:
    """Sigma points of a state estimate augmented by a noise, N([mean, E{w}], [[cov, 0], [0, Cov{w}]]).

    The root of the block-diagonal covariance is the Cholesky factor, whose blocks are those
    of ``cov`` and Cov{w}: the noise's offsets of the sigma points and the weights are
    computed once, and each estimate fills in the scaled Cholesky factor of its ``cov``.
    Where a Cholesky factor does not exist, the root is :func:`_root`'s of the whole
    matrix, as in :func:`_sigma_points`.
    """

    def __init__(self, noise, n_x, kappa):
        n = n_x + noise.dim
        self.noise, self.n_x, self.n, self.scale = noise, n_x, n, np.sqrt(n + kappa)
        self.weights = _unscented_weights(n, kappa)
        try:
            noise_root = np.linalg.cholesky(noise.cov)
        except np.linalg.LinAlgError:
            self.noise_offsets = None
        else:
            self.noise_offsets = _points_around(np.zeros(n), self.scale * _block_diag(np.zeros((n_x, n_x)), noise_root))

    def points(self, mean, cov):
        """State part (..., 2n+1, n_x) and noise part (..., 2n+1, n_w) of the sigma points."""
        offsets = self._offsets(cov)
        return mean[..., None, :] + offsets[..., :self.n_x], self.noise.mean + offsets[..., self.n_x:]

    def _offsets(self, cov):
        """Sigma points of N(0, [[cov, 0], [0, Cov{w}]])."""
        if self.noise_offsets is not None:
            try:
                Lt = (self.scale * _cholesky(cov)).swapaxes(-1, -2)
            except np.linalg.LinAlgError:
                pass
            else:
                offsets = np.empty(cov.shape[:-2] + self.noise_offsets.shape)
                offsets[...] = self.noise_offsets
                offsets[..., 1:1 + self.n_x, :self.n_x] = Lt
                offsets[..., 1 + self.n:1 + self.n + self.n_x, :self.n_x] = -Lt
                return offsets
        return _points_around(np.zeros(self.n), self.scale * _root(_block_diag(cov, self.noise.cov)))


def _moments(points, weights):
    """The weighted mean of the points (last axis) and the points centred at it."""
    mean = weights @ points
    return mean, points - mean[..., None, :]


def _weighted_covariance(e, weights):
    """sum_i weights_i e_i e_i^T of centred samples e (..., M, n)."""
    return (weights[:, None] * e).swapaxes(-1, -2) @ e


def _block_diag(P, Q):
    """Batch block-diagonal [[P, 0], [0, Q]] with Q shared."""
    n, m = P.shape[-1], Q.shape[-1]
    out = np.zeros(P.shape[:-2] + (n + m, n + m))
    out[..., :n, :n] = P
    out[..., n:, n:] = Q
    return out


def _solve(S, B):
    """S^{-1} B, with the pseudo-inverse where S is singular (a degenerate measurement).

    A scalar S != 0 divides.
    """
    if S.shape[-1] == 1 and S.all():
        return B / S
    try:
        return np.linalg.solve(S, B)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(S, hermitian=True) @ B


def _conditional_covariance(e, n, weights):
    """C^{xx} - C^{xy} (C^{yy})^{-1} C^{yx} and the gain from centred joint samples e = [x, y] (Lemma 2.1).

    ``e`` is (..., M, n + n_y), its first ``n`` columns the state.
    """
    C = _weighted_covariance(e, weights)
    Cxx, Cyx, Cyy = C[..., :n, :n], C[..., n:, :n], C[..., n:, n:]
    gain = _solve(Cyy, Cyx).swapaxes(-1, -2)
    post = Cxx - gain @ Cyx
    return 0.5 * (post + post.swapaxes(-1, -2)), gain


def next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta=None, gamma=None):
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
    model = check.instance(model, NonlinearModel, "model")
    mixture = check.instance(mixture, DiracMixture, "mixture")
    check.real_array(mixture.points, "mixture.points", shape=(None, model.n_x))
    u = check.vector(u, "u", model.n_u)
    w_samples = check.real_array(w_samples, "w_samples", shape=(None, model.w.dim))
    v_samples = check.real_array(v_samples, "v_samples", shape=(None, model.v.dim))
    for name, samples in (("w_samples", w_samples), ("v_samples", v_samples)):
        if samples.shape[0] == 0:
            raise ValueError(f"{name}: expected at least one sample, found shape {samples.shape}")
    beta = check.weights_or_equal(beta, "beta", w_samples.shape[0])
    gamma = check.weights_or_equal(gamma, "gamma", v_samples.shape[0])
    return _next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta, gamma)


def _next_estimate_covariance(mixture, u, model, w_samples, v_samples, beta, gamma):
    x_im = model.a(mixture.points[:, None, :], u, w_samples[None, :, :])
    y_imn = model.h(x_im[:, :, None, :], v_samples[None, None, :, :])
    weights = (mixture.weights[:, None, None] * beta[None, :, None] * gamma[None, None, :]).ravel()
    xs = np.broadcast_to(x_im[:, :, None, :], y_imn.shape[:3] + x_im.shape[-1:]).reshape(-1, x_im.shape[-1])
    ys = y_imn.reshape(-1, y_imn.shape[-1])
    _, e = _moments(np.concatenate([xs, ys], axis=-1), weights)
    return _conditional_covariance(e, xs.shape[-1], weights)[0]


class UKF:
    """Unscented Kalman filter with non-additive noise (joint sigma points of state and noise).

    The estimate is ``(mean, cov)``; its Dirac mixture is :meth:`mixture` (sigma points).
    ``predict``/``update`` broadcast over leading axes (batches of runs).

    Parameters
    ----------
    model : NonlinearModel
    kappa : float
        Sample scaling of the joint sigma points, > -(n_x + min(n_w, n_v)).

    Raises
    ------
    ValueError, TypeError
        If ``model`` is not a NonlinearModel or ``kappa`` is out of range.

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> ukf = UKF(linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]]))
    >>> mean, cov = ukf.step(ukf.initial([0.0], [[1.0]]), [0.0], [1.0])
    >>> mean.round(4).tolist(), cov.round(4).tolist()
    ([0.6667], [[0.6667]])
    """

    def __init__(self, model, kappa: float = KAPPA):
        self.model = check.instance(model, NonlinearModel, "model")
        self.kappa = check.real_scalar(kappa, "kappa", low=-(model.n_x + min(model.w.dim, model.v.dim)),
                                       low_open=True)
        self._process = _Augmented(model.w, model.n_x, self.kappa)
        self._sensor = _Augmented(model.v, model.n_x, self.kappa)

    def initial(self, mean, cov, rng=None):
        """The initial estimate (mean0, cov0) after checking it."""
        mean = check.vector(mean, "mean", self.model.n_x)
        return mean, check.covariance(cov, "cov", mean.size)

    def mixture(self, estimate) -> DiracMixture:
        """The sigma points of the estimate as a :class:`DiracMixture`."""
        points, weights = _sigma_points(*self._checked(*_pair(estimate)), self.kappa)
        return DiracMixture(points, weights)

    @staticmethod
    def mean(estimate):
        """The estimate's mean."""
        return estimate[0]

    @staticmethod
    def cov(estimate):
        """The estimate's covariance."""
        return estimate[1]

    def _checked(self, mean, cov, extra=None, size=None, extra_name=None):
        mean, cov = _estimate(mean, cov, "mean", "cov", self.model.n_x, definite_check=False)
        if extra_name is None:
            return mean, cov
        if extra is None:
            raise TypeError(f"{extra_name}: expected a real array of shape (..., {size}), found None")
        extra = check.real_array(extra, extra_name)
        if extra.ndim == 0 or extra.shape[-1] != size:
            raise ValueError(f"{extra_name}: expected shape (..., {size}), found shape {extra.shape}")
        return mean, cov, extra

    def predict(self, mean, cov, u):
        """Time update through x_{k+1} = a(x_k, u_k, w_k) (eq. 2.1)."""
        return self._predict(*self._checked(mean, cov, u, self.model.n_u, "u"))

    def _predict(self, mean, cov, u):
        return self._propagate(self._prior(mean, cov), u)

    def _prior(self, mean, cov):
        """The joint sigma points of state and process noise: (state part, noise part)."""
        return self._process.points(mean, cov)

    def _propagate(self, prior, u):
        """Predicted mean and covariance from the prior's joint sigma points (:meth:`_prior`)."""
        x_points, w_points = prior
        weights = self._process.weights
        mean_p, e = _moments(self.model.a(x_points, np.asarray(u)[..., None, :], w_points), weights)
        return mean_p, _weighted_covariance(e, weights)

    def _measurement(self, mean, cov):
        x_points, v_points = self._sensor.points(mean, cov)
        weights = self._sensor.weights
        n = x_points.shape[-1]
        joint_mean, e = _moments(np.concatenate([x_points, self.model.h(x_points, v_points)], axis=-1), weights)
        post, gain = _conditional_covariance(e, n, weights)
        return joint_mean[..., n:], gain, post

    def update(self, mean, cov, y):
        """Measurement update with y_k = h(x_k, v_k) (eq. 2.2)."""
        return self._update(*self._checked(mean, cov, y, self.model.n_y, "y"))

    def _update(self, mean, cov, y):
        y_hat, gain, post = self._measurement(mean, cov)
        return mean + np.einsum("...ij,...j->...i", gain, np.asarray(y) - y_hat), post

    def step(self, estimate, u, y, rng=None):
        """Predict with ``u`` and update with ``y``: the next estimate."""
        mean, cov, u = self._checked(*_pair(estimate), u, self.model.n_u, "u")
        y = self._checked(mean, cov, y, self.model.n_y, "y")[2]
        return self._step((mean, cov), u, y)

    def _step(self, estimate, u, y, rng=None):
        return self._update(*self._predict(*estimate, u), y)

    def next_covariance(self, estimate, u):
        """C_{k+1} after predicting with ``u`` and fusing any measurement (Lemma 2.1 at the
        sigma points; it does not depend on the measurement's value)."""
        mean, cov, u = self._checked(*_pair(estimate), u, self.model.n_u, "u")
        return self._next_covariance((mean, cov), u)

    def _next_covariance(self, estimate, u):
        return self._covariance_after(self._prior(*estimate), u)

    def _covariance_after(self, prior, u):
        """C_{k+1}(u) from the prior's joint sigma points (:meth:`_prior`), unchecked."""
        return self._measurement(*self._propagate(prior, u))[2]

    def _covariance_function(self, estimate):
        """u -> C_{k+1}(u) of :meth:`next_covariance` for one estimate, checked once.

        The returned function does not check u (a float array (n_u,)): it is the inner loop
        of Algorithm 2.2, whose numerical derivatives evaluate it thousands of times for
        the same estimate; the sigma points of the estimate and the process noise, which do
        not depend on u, are computed once.

        Examples
        --------
        >>> from asoc.belief import landmark_example
        >>> ex = landmark_example()
        >>> ukf = UKF(ex.model)
        >>> C = ukf._covariance_function((ex.mean0, ex.cov0))
        >>> bool(np.allclose(C(np.array([1.0, 0.0])), ukf.next_covariance((ex.mean0, ex.cov0), [1.0, 0.0])))
        True
        """
        mean, cov = self._checked(*_pair(estimate))
        if mean.ndim == 1 and cov.ndim == 2:
            return _NextCovariance(self, self._prior(mean, cov))
        return partial(self._covariance_after, self._prior(mean, cov))


class _NextCovariance:
    """u -> C_{k+1}(u) of :meth:`UKF._covariance_after` for one estimate (mean (n_x,)), unchecked.

    The same floating-point operations on the same operands, with less numpy call
    overhead on the tiny arrays of the inner loop of Algorithm 2.2: what does not depend
    on u (the weights as columns, the measurement noise's part of the sensor's sigma
    points, the zero rows of their state offsets) is prepared once, and a scalar
    measurement's division is decided without ``ndarray.all``. Where Cov{v} or the
    predicted covariance has no Cholesky factor, the measurement is :meth:`UKF._measurement`.
    :meth:`many` evaluates a stack of inputs at once (numdifftools' evaluation points).
    """

    def __init__(self, ukf, prior):
        process, sensor = ukf._process, ukf._sensor
        self._ukf, self._prior, self._n_x, self._sensor_n = ukf, prior, ukf.model.n_x, sensor.n
        self._process_weights, self._process_column = process.weights, process.weights[:, None]
        self._sensor_weights, self._sensor_column = sensor.weights, sensor.weights[:, None]
        self._scale, self._v_points = sensor.scale, None
        if sensor.noise_offsets is not None:
            self._state_offsets = sensor.noise_offsets[:, :self._n_x].copy()     # rows of L^T filled per call
            self._v_points = sensor.noise.mean + sensor.noise_offsets[:, self._n_x:]

    def __call__(self, u):
        mean, cov = self._predicted(u)
        if self._v_points is None:
            return self._ukf._measurement(mean, cov)[2]
        try:
            x_points = self._sensor_state_points(mean, cov)
        except np.linalg.LinAlgError:
            return self._ukf._measurement(mean, cov)[2]
        joint = np.concatenate([x_points, self._ukf.model.h(x_points, self._v_points)], axis=-1)
        e = joint - (self._sensor_weights @ joint)[None, :]
        return self._posterior((self._sensor_column * e).T @ e)

    def _predicted(self, u):
        """:meth:`UKF._propagate` of the prior: the predicted mean and covariance."""
        x_points, w_points = self._prior
        points = self._ukf.model.a(x_points, u[None, :], w_points)
        mean = self._process_weights @ points
        e = points - mean[None, :]
        return mean, (self._process_column * e).T @ e

    def _sensor_state_points(self, mean, cov):
        """The state part of the sensor's :meth:`_Augmented.points`; LinAlgError without a Cholesky factor."""
        Lt = (self._scale * _cholesky(cov)).T
        offsets, n_x, n = self._state_offsets, self._n_x, self._sensor_n
        offsets[1:1 + n_x] = Lt
        offsets[1 + n:1 + n + n_x] = -Lt
        return mean + offsets

    def _posterior(self, C):
        """The posterior of :func:`_conditional_covariance` from the joint covariance C."""
        n_x = self._n_x
        Cxx, Cyx, Cyy = C[:n_x, :n_x], C[n_x:, :n_x], C[n_x:, n_x:]
        gain = (Cyx / Cyy if Cyy.shape[0] == 1 and Cyy[0, 0] != 0 else _solve(Cyy, Cyx)).T
        post = Cxx - gain @ Cyx
        return 0.5 * (post + post.T)

    def many(self, inputs):
        """C_{k+1}(u) for every row u of ``inputs`` (B, n_u), B >= 1: the same operations as one call per row.

        The rows go through the same operations stacked along a leading axis: elementwise
        arithmetic, numpy.matmul (whose loop over the leading axis makes each row's BLAS call
        of the 2-D product), np.linalg.solve (LAPACK per matrix), LAPACK's dpotrf per row
        (:func:`_cholesky`), and the model's ``a`` and ``h`` on the stack (they broadcast over
        leading axes; bit-identical for elementwise and matmul models such as
        :func:`~asoc.belief.landmark_example` and :func:`~asoc.belief.linear_gaussian_model`).
        Rows that leave the common case (no Cholesky factor of the predicted covariance,
        C^{yy} = 0 or singular) are evaluated one at a time, as is everything when Cov{v}
        has no Cholesky factor. With this project's numpy and OpenBLAS kernels the result is
        bit-identical to one call per row; other BLAS kernels (e.g. OPENBLAS_CORETYPE=Prescott)
        may round the stacked products differently, within rounding.
        """
        if self._v_points is None:
            return np.array([self(u) for u in inputs])
        mean, cov = self._predicted_many(inputs)
        roots, regular = self._roots(cov)
        covariances = np.empty(cov.shape)
        if regular.any():
            covariances[regular] = self._measurement_many(mean[regular], roots[regular])
        for row in np.flatnonzero(~regular):
            covariances[row] = self(inputs[row])
        return covariances

    def _predicted_many(self, inputs):
        """:meth:`_predicted` for a stack of inputs (B, n_u)."""
        x_points, w_points = self._prior
        points = self._ukf.model.a(x_points, inputs[:, None, :], w_points)
        mean = self._process_weights @ points
        e = points - mean[:, None, :]
        return mean, (self._process_column * e).swapaxes(-1, -2) @ e

    @staticmethod
    def _roots(cov):
        """The Cholesky factor of each covariance (LAPACK's dpotrf per matrix, as :func:`_cholesky`)
        and which have one (the other factors are zero)."""
        roots, regular = np.zeros(cov.shape), np.ones(cov.shape[0], dtype=bool)
        for row, matrix in enumerate(cov):
            root, info = lapack.dpotrf(matrix, lower=True, clean=True)
            if info == 0:
                roots[row] = root
            else:
                regular[row] = False
        return roots, regular

    def _measurement_many(self, mean, roots):
        """The posterior covariance of :meth:`__call__` for stacked predicted means and Cholesky
        factors; rows whose C^{yy} is singular are recomputed through :func:`_solve`."""
        n_x, n = self._n_x, self._sensor_n
        Lt = (self._scale * roots).swapaxes(-1, -2)
        offsets = np.zeros(mean.shape[:1] + self._state_offsets.shape)
        offsets[:, 1:1 + n_x] = Lt
        offsets[:, 1 + n:1 + n + n_x] = -Lt
        x_points = mean[:, None, :] + offsets
        joint = np.concatenate([x_points, self._ukf.model.h(x_points, self._v_points)], axis=-1)
        e = joint - (self._sensor_weights @ joint)[:, None, :]
        return self._posterior_many((self._sensor_column * e).swapaxes(-1, -2) @ e)

    def _posterior_many(self, C):
        """:meth:`_posterior` of stacked joint covariances C (B, n, n)."""
        n_x = self._n_x
        Cxx, Cyx, Cyy = C[:, :n_x, :n_x], C[:, n_x:, :n_x], C[:, n_x:, n_x:]
        try:
            gain = self._gains(Cyx, Cyy)
        except np.linalg.LinAlgError:                 # a singular C^{yy}: the pseudo-inverse, row by row
            return np.array([self._posterior(matrix) for matrix in C])
        post = Cxx - gain @ Cyx
        return 0.5 * (post + post.swapaxes(-1, -2))

    @staticmethod
    def _gains(Cyx, Cyy):
        """The transposed gains (C^{yy})^{-1} C^{yx} of :meth:`_posterior` for stacked blocks;
        LinAlgError if a C^{yy} is singular."""
        if Cyy.shape[1] > 1:
            return np.linalg.solve(Cyy, Cyx).swapaxes(-1, -2)
        if not Cyy.all():
            raise np.linalg.LinAlgError("a scalar C^{yy} is zero")
        return (Cyx / Cyy).swapaxes(-1, -2)


def _pair(estimate):
    if not isinstance(estimate, tuple) or len(estimate) != 2:
        raise TypeError(f"estimate: expected a tuple (mean, cov), found {type(estimate).__name__}")
    return estimate


class ParticleFilter:
    """Bootstrap particle filter [6]: the estimate is a :class:`DiracMixture` of particles.

    Parameters
    ----------
    model : NonlinearModel with a ``likelihood``.
    n_particles : int
        Number of particles M, >= 1.
    rng : numpy.random.Generator for propagation and resampling.
    resample_threshold : float
        Resample (systematic) when the effective sample size is below this fraction of M,
        in [0, 1].

    Raises
    ------
    ValueError, TypeError
        If the model has no likelihood, or an argument has the wrong type or range.

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> pf = ParticleFilter(model, 20_000, np.random.default_rng(0))
    >>> est = pf.step(pf.initial([0.0], [[1.0]]), [0.0], [1.0])
    >>> round(float(est.mean[0]), 1), round(float(est.cov[0, 0]), 1)
    (0.7, 0.7)
    """

    def __init__(self, model, n_particles: int, rng, resample_threshold: float = 0.5):
        self.model = check.instance(model, NonlinearModel, "model")
        if model.likelihood is None:
            raise ValueError("model: expected a model with a likelihood(y, x) for the particle filter, found likelihood None")
        self.M = check.integer(n_particles, "n_particles", minimum=1)
        self.rng = check.generator(rng)
        self.threshold = check.real_scalar(resample_threshold, "resample_threshold", low=0, high=1)
        self._w_points, self._beta = _sigma_points(model.w.mean, model.w.cov, KAPPA)
        self._v_points, self._gamma = _sigma_points(model.v.mean, model.v.cov, KAPPA)

    def initial(self, mean, cov, rng=None):
        """M particles drawn from N(mean, cov)."""
        check.vector(mean, "mean", self.model.n_x)
        return DiracMixture(GaussianNoise(mean, cov).sample(self.rng, self.M))

    @staticmethod
    def mixture(estimate):
        """The particles (the estimate itself)."""
        return estimate

    @staticmethod
    def mean(estimate):
        """The particles' weighted mean."""
        return estimate.mean

    @staticmethod
    def cov(estimate):
        """The particles' weighted covariance."""
        return estimate.cov

    def _checked(self, estimate, u, y=None):
        check.instance(estimate, DiracMixture, "estimate")
        check.real_array(estimate.points, "estimate.points", shape=(None, self.model.n_x))
        u = check.vector(u, "u", self.model.n_u)
        return estimate, u, (None if y is None else check.vector(y, "y", self.model.n_y))

    def step(self, estimate, u, y, rng=None):
        """Propagate with ``u``, weight by the likelihood of ``y``, resample if degenerate."""
        estimate, u, y = self._checked(estimate, u, y)
        rng = self.rng if rng is None else check.generator(rng)
        m = self.model
        x = m.a(estimate.points, u, m.w.sample(rng, estimate.points.shape[0]))
        w = estimate.weights * m.likelihood(y, x)
        if not np.isfinite(w.sum()) or w.sum() <= 0:
            raise ValueError("y: expected a measurement with positive likelihood under some particle, found zero under all")
        w = w / w.sum()
        if 1.0 / np.sum(w ** 2) < self.threshold * w.size:
            idx = np.searchsorted(np.cumsum(w), (rng.random() + np.arange(w.size)) / w.size)
            x, w = x[np.minimum(idx, w.size - 1)], None
        return DiracMixture(x, w)

    def next_covariance(self, estimate, u):
        """Lemma 2.1 with the particles and the sigma points of the noises as samples."""
        estimate, u, _ = self._checked(estimate, u)
        return self._next_covariance(estimate, u)

    def _next_covariance(self, estimate, u):
        return _next_estimate_covariance(estimate, u, self.model, self._w_points, self._v_points,
                                         self._beta, self._gamma)


def _numeric_jacobians(model, x, u, w, v):
    import numdifftools as nd
    x, u, w, v = (np.asarray(z, dtype=float) for z in (x, u, w, v))
    a_x = nd.Jacobian(lambda z: model.a(z, u, w))(x)
    a_u = nd.Jacobian(lambda z: model.a(x, z, w))(u)
    a_w = nd.Jacobian(lambda z: model.a(x, u, z))(w)
    h_x = nd.Jacobian(lambda z: model.h(z, v))(x)
    h_v = nd.Jacobian(lambda z: model.h(x, z))(v)
    return tuple(np.atleast_2d(J) for J in (a_x, a_u, a_w, h_x, h_v))


def _jacobians(model, x, u, w, v):
    """(a_x, a_u, a_w, h_x, h_v): the model's analytic Jacobians, else numdifftools [46]."""
    if model.jacobians is not None:
        return model.jacobians(x, u, w, v)
    if np.asarray(x).ndim > 1:
        raise ValueError("mean: expected one state (numerical Jacobians), found a batch; give model.jacobians")
    return _numeric_jacobians(model, x, u, w, v)


def _read_only_broadcast(vector, batch):
    """``vector`` broadcast to ``batch + vector.shape``, read-only (np.broadcast_to's result).

    Without a batch a read-only view: np.broadcast_to's argument handling costs more than
    the EKF's arithmetic on one small belief (the inner loop of [159]'s linearisation).
    """
    if batch:
        return np.broadcast_to(vector, batch + vector.shape)
    view = vector.view()
    view.flags.writeable = False
    return view


def ekf_predict(model, mean, cov, u):
    """EKF time update [10]: linearisation of a at (mean, u, E{w}); (predicted mean, Gamma).

    Broadcasts over leading axes; the arguments are not checked (see :func:`ekf_step`).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> mean, Gamma = ekf_predict(model, np.array([1.0]), np.array([[1.0]]), np.array([0.5]))
    >>> mean.tolist(), Gamma.tolist()
    ([1.5], [[2.0]])
    """
    w0 = _read_only_broadcast(model.w.mean, mean.shape[:-1])
    v0 = _read_only_broadcast(model.v.mean, mean.shape[:-1])
    a_x, _, a_w, _, _ = _jacobians(model, mean, u, w0, v0)
    Gamma = a_x @ cov @ np.swapaxes(a_x, -1, -2) + a_w @ model.w.cov @ np.swapaxes(a_w, -1, -2)
    return model.a(mean, u, w0), Gamma


def ekf_gain(model, mean, cov):
    """EKF measurement linearisation at (mean, E{v}): (y_hat, gain K, innovation covariance, posterior).

    Broadcasts over leading axes; the arguments are not checked (see :func:`ekf_step`).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> y_hat, K, S, post = ekf_gain(model, np.array([1.0]), np.array([[1.0]]))
    >>> y_hat.tolist(), K.tolist(), S.tolist(), post.tolist()
    ([1.0], [[0.5]], [[2.0]], [[0.5]])
    """
    w0 = _read_only_broadcast(model.w.mean, mean.shape[:-1])
    v0 = _read_only_broadcast(model.v.mean, mean.shape[:-1])
    u0 = np.zeros(mean.shape[:-1] + (model.n_u,))
    _, _, _, h_x, h_v = _jacobians(model, mean, u0, w0, v0)
    S = h_x @ cov @ np.swapaxes(h_x, -1, -2) + h_v @ model.v.cov @ np.swapaxes(h_v, -1, -2)
    K = _solve(S, h_x @ cov).swapaxes(-1, -2)
    post = cov - K @ h_x @ cov
    return model.h(mean, v0), K, S, 0.5 * (post + post.swapaxes(-1, -2))


def ekf_step(model, mean, cov, u, y):
    """One step of the extended Kalman filter [10] (predict with u, update with y); broadcasts
    over leading axes.

    Parameters
    ----------
    model : NonlinearModel
        With ``a``, ``h`` and (optionally) ``jacobians``.
    mean : array_like, (..., n_x)
    cov : array_like, (..., n_x, n_x)
        Symmetric positive semi-definite.
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
    ValueError, TypeError
        If an argument has the wrong type or shape, or the model has no Jacobians and a
        batch of states is passed (numerical Jacobians take one state).

    Examples
    --------
    >>> from asoc.belief import linear_gaussian_model
    >>> model = linear_gaussian_model([[1.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]])
    >>> mean, cov = ekf_step(model, [0.0], [[1.0]], [0.0], [1.0])
    >>> mean.round(4).tolist(), cov.round(4).tolist()
    ([0.6667], [[0.6667]])
    """
    model = check.instance(model, NonlinearModel, "model")
    mean, cov = _estimate(mean, cov, "mean", "cov", model.n_x)
    u = check.real_array(u, "u")
    y = check.real_array(y, "y")
    for name, value, size in (("u", u, model.n_u), ("y", y, model.n_y)):
        if value.ndim == 0 or value.shape[-1] != size:
            raise ValueError(f"{name}: expected shape (..., {size}), found shape {value.shape}")
    mean_p, cov_p = ekf_predict(model, mean, cov, u)
    y_hat, K, _, post = ekf_gain(model, mean_p, cov_p)
    return mean_p + np.einsum("...ij,...j->...i", K, y - y_hat), post
