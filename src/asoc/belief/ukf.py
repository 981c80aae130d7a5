"""The unscented Kalman filter [101] whose sigma points are the Dirac mixture of the estimate.

In the form of the Nonlinear Estimation Toolbox [144] the thesis used: sigma points of the
joint Gaussian of state and noise, sample scaling kappa = 0.5, which gives the 2n+1 points
equal weights 1/(2n+1) (Sec. 2.2). ``predict``/``update`` broadcast over leading axes of
``mean`` (batches of Monte Carlo runs).
"""

from functools import partial

import numpy as np
from scipy.linalg import lapack

from .. import validation as check
from .filters import (
    KAPPA,
    DiracMixture,
    checked_estimate,
    conditional_covariance,
    covariance_root,
    points_around,
    sigma_points,
    unscented_weights,
    weighted_covariance,
    weighted_moments,
)
from .models import NonlinearModel

__all__ = ["UKF"]


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


class _Augmented:
    """Sigma points of a state estimate augmented by a noise:
    N([mean, E{w}], [[cov, 0], [0, Cov{w}]]).

    The root of the block-diagonal covariance is the Cholesky factor, whose blocks are those
    of ``cov`` and Cov{w}: the noise's offsets of the sigma points and the weights are
    computed once, and each estimate fills in the scaled Cholesky factor of its ``cov``.
    Where a Cholesky factor does not exist, the root is
    :func:`~asoc.belief.filters.covariance_root`'s of the whole matrix, as in
    :func:`~asoc.belief.filters.sigma_points`.
    """

    def __init__(self, noise, n_x, kappa):
        n = n_x + noise.dim
        self.noise, self.n_x, self.n, self.scale = noise, n_x, n, np.sqrt(n + kappa)
        self.weights = unscented_weights(n, kappa)
        try:
            noise_root = np.linalg.cholesky(noise.cov)
        except np.linalg.LinAlgError:
            self.noise_offsets = None
        else:
            noise_block = _block_diag(np.zeros((n_x, n_x)), noise_root)
            self.noise_offsets = points_around(np.zeros(n), self.scale * noise_block)

    def points(self, mean, cov):
        """State part (..., 2n+1, n_x) and noise part (..., 2n+1, n_w) of the sigma points."""
        offsets = self._offsets(cov)
        states = mean[..., None, :] + offsets[..., :self.n_x]
        return states, self.noise.mean + offsets[..., self.n_x:]

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
        return points_around(np.zeros(self.n),
                             self.scale * covariance_root(_block_diag(cov, self.noise.cov)))


def _block_diag(P, Q):
    """Batch block-diagonal [[P, 0], [0, Q]] with Q shared."""
    n, m = P.shape[-1], Q.shape[-1]
    out = np.zeros(P.shape[:-2] + (n + m, n + m))
    out[..., :n, :n] = P
    out[..., n:, n:] = Q
    return out


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
        self.kappa = check.real_scalar(kappa, "kappa",
                                       low=-(model.n_x + min(model.w.dim, model.v.dim)),
                                       low_open=True)
        self._process = _Augmented(model.w, model.n_x, self.kappa)
        self._sensor = _Augmented(model.v, model.n_x, self.kappa)

    def initial(self, mean, cov, rng=None):
        """The initial estimate (mean0, cov0) after checking it."""
        mean = check.vector(mean, "mean", self.model.n_x)
        return mean, check.covariance(cov, "cov", mean.size)

    def mixture(self, estimate) -> DiracMixture:
        """The sigma points of the estimate as a :class:`DiracMixture`."""
        points, weights = sigma_points(*self._checked(*_pair(estimate)), self.kappa, check=False)
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
        mean, cov = checked_estimate(mean, cov, "mean", "cov", self.model.n_x, definite_check=False)
        if extra_name is None:
            return mean, cov
        if extra is None:
            raise TypeError(f"{extra_name}: expected a real array of shape (..., {size}), "
                            "found None")
        extra = check.real_array(extra, extra_name)
        if extra.ndim == 0 or extra.shape[-1] != size:
            raise ValueError(f"{extra_name}: expected shape (..., {size}), "
                             f"found shape {extra.shape}")
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
        next_points = self.model.a(x_points, np.asarray(u)[..., None, :], w_points)
        mean_p, e = weighted_moments(next_points, weights)
        return mean_p, weighted_covariance(e, weights)

    def _measurement(self, mean, cov):
        x_points, v_points = self._sensor.points(mean, cov)
        weights = self._sensor.weights
        n = x_points.shape[-1]
        joint = np.concatenate([x_points, self.model.h(x_points, v_points)], axis=-1)
        joint_mean, e = weighted_moments(joint, weights)
        post, gain = conditional_covariance(e, n, weights)
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
        sigma points; it does not depend on the measurement's value).
        """
        mean, cov, u = self._checked(*_pair(estimate), u, self.model.n_u, "u")
        return self._next_covariance((mean, cov), u)

    def _next_covariance(self, estimate, u):
        return self._covariance_after(self._prior(*estimate), u)

    def _covariance_after(self, prior, u):
        """C_{k+1}(u) from the prior's joint sigma points (:meth:`_prior`), unchecked."""
        return self._measurement(*self._propagate(prior, u))[2]

    def covariance_map(self, estimate):
        """U -> C_{k+1}(u) of :meth:`next_covariance` for one estimate, checked once.

        The returned function does not check u (a float array (n_u,)): the stage problem
        (2.13) differentiates it numerically, thousands of evaluations for the same
        estimate; the joint sigma points of the estimate and the process noise, which do
        not depend on u, are computed once.

        Examples
        --------
        >>> from asoc.belief import landmark_example
        >>> ex = landmark_example()
        >>> ukf = UKF(ex.model)
        >>> C = ukf.covariance_map((ex.mean0, ex.cov0))
        >>> direct = ukf.next_covariance((ex.mean0, ex.cov0), [1.0, 0.0])
        >>> bool(np.allclose(C(np.array([1.0, 0.0])), direct))
        True
        """
        mean, cov = self._checked(*_pair(estimate))
        return partial(self._covariance_after, self._prior(mean, cov))


def _pair(estimate):
    if not isinstance(estimate, tuple) or len(estimate) != 2:
        raise TypeError(f"estimate: expected a tuple (mean, cov), found {type(estimate).__name__}")
    return estimate
