"""The bootstrap particle filter [6] with systematic resampling: the estimate is a Dirac mixture."""

from functools import partial

import numpy as np

from .. import validation as check
from .filters import KAPPA, DiracMixture, next_estimate_covariance, sigma_points
from .models import GaussianNoise, NonlinearModel

__all__ = ["ParticleFilter"]


class ParticleFilter:
    """Bootstrap particle filter [6]: the estimate is a :class:`DiracMixture` of particles.

    Parameters
    ----------
    model : NonlinearModel
        A model with a ``likelihood``.
    n_particles : int
        Number of particles M, >= 1.
    rng : numpy.random.Generator
        For propagation and resampling.
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
            raise ValueError("model: expected a model with a likelihood(y, x) for the particle "
                             "filter, found likelihood None")
        self.M = check.integer(n_particles, "n_particles", minimum=1)
        self.rng = check.generator(rng)
        self.threshold = check.real_scalar(resample_threshold, "resample_threshold", low=0, high=1)
        self._w_points, self._beta = sigma_points(model.w.mean, model.w.cov, KAPPA, check=False)
        self._v_points, self._gamma = sigma_points(model.v.mean, model.v.cov, KAPPA, check=False)

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
            raise ValueError("y: expected a measurement with positive likelihood under some "
                             "particle, found zero under all")
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
        return next_estimate_covariance(estimate, u, self.model, self._w_points, self._v_points,
                                        self._beta, self._gamma, check=False)

    def covariance_map(self, estimate):
        """U -> C_{k+1}(u) of :meth:`next_covariance` for one estimate, checked once (u not)."""
        estimate = self._checked(estimate, np.zeros(self.model.n_u))[0]
        return partial(self._next_covariance, estimate)

