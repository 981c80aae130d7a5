"""Beside scikit-learn (issue 33, item 6): on point masses, DistributionGP is an ordinary GP.

The distance between two Dirac distributions (the 2-Wasserstein distance of Gaussians with zero
covariance, asoc.gp.wasserstein_gaussian_matrix) is the Euclidean distance of their locations, so
DistributionGP with a covariance of Table 2.1 must give what scikit-learn's
GaussianProcessRegressor gives with the same stationary kernel, amplitude and noise on the
locations: with fixed hyperparameters the same mean, variance and log marginal likelihood to
rounding (1e-13), and fitted by maximum likelihood within the same bounds, the same optimum (the
library stops at a projected gradient of gp.gradient_tol in log-parameters, scikit-learn at
L-BFGS-B's default, so the parameters agree to 1e-4 relative and the likelihood to 1e-8).
scikit-learn's own diagonal jitter (``alpha=1e-10``) is switched off, and the library's prior mean
(the sample mean of y) is subtracted before scikit-learn sees the outputs.
"""

import numpy as np
import pytest

from asoc.gp import DistributionGP, wasserstein_gaussian_matrix

sklearn = pytest.importorskip("sklearn")
from sklearn.gaussian_process import GaussianProcessRegressor  # noqa: E402
from sklearn.gaussian_process.kernels import (
    RBF,
    ConstantKernel,
    Matern,  # noqa: E402
    RationalQuadratic,
    WhiteKernel,
)

#: (library covariance, its shape parameters, scikit-learn's kernel of a length scale and
#: its bounds)
KERNELS = [
    ("se", {}, lambda l, b="fixed": RBF(l, b)),
    ("matern", {"nu": 2.5}, lambda l, b="fixed": Matern(l, b, nu=2.5)),
    ("matern", {"nu": 1.5}, lambda l, b="fixed": Matern(l, b, nu=1.5)),
    ("exponential", {}, lambda l, b="fixed": Matern(l, b, nu=0.5)),
    (
        "rational_quadratic",
        {"alpha_rq": 2.0},
        lambda l, b="fixed": RationalQuadratic(l, 2.0, b, "fixed"),
    ),
]
IDS = ["se", "matern-2.5", "matern-1.5", "exponential", "rational-quadratic"]


def point_masses():
    """25 noisy training points and 10 test points in the plane, with their Dirac distances."""
    rng = np.random.default_rng(7)
    X = rng.uniform(-2, 2, (25, 2))
    y = np.sin(X[:, 0]) * np.cos(X[:, 1]) + 0.05 * rng.standard_normal(25)
    X_star = rng.uniform(-2, 2, (10, 2))
    D = wasserstein_gaussian_matrix(X, np.zeros((25, 2, 2)))
    D_star = wasserstein_gaussian_matrix(X_star, np.zeros((10, 2, 2)), X, np.zeros((25, 2, 2)))
    return X, y, X_star, D, D_star


def test_dirac_distances_are_euclidean():
    X, _, _, D, _ = point_masses()
    np.testing.assert_allclose(
        D, np.linalg.norm(X[:, None] - X[None], axis=-1), rtol=1e-14, atol=1e-14
    )


@pytest.mark.parametrize("covariance, shape, kernel", KERNELS, ids=IDS)
def test_fixed_hyperparameters_agree_with_scikit_learn(covariance, shape, kernel):
    X, y, X_star, D, D_star = point_masses()
    alpha, l, sigma_n = 0.9, 0.7, 0.1
    ours = DistributionGP(covariance, **shape).condition(D, y, alpha, l, sigma_n)
    mean, var = ours.predict(D_star, return_var=True)
    peer = GaussianProcessRegressor(
        ConstantKernel(alpha**2, "fixed") * kernel(l) + WhiteKernel(sigma_n**2, "fixed"),
        optimizer=None,
        alpha=0.0,
    )
    peer.fit(X, y - y.mean())
    peer_mean, peer_std = peer.predict(X_star, return_std=True)
    np.testing.assert_allclose(mean, peer_mean + y.mean(), rtol=0, atol=1e-13)
    # scikit-learn's predictive variance includes the white noise at the test points
    np.testing.assert_allclose(var + sigma_n**2, peer_std**2, rtol=0, atol=1e-13)
    assert ours.log_marginal_likelihood(alpha, l, sigma_n) == pytest.approx(
        peer.log_marginal_likelihood_value_, rel=1e-13, abs=1e-13
    )


@pytest.mark.parametrize(
    "covariance, shape, kernel", [KERNELS[i] for i in (0, 1, 4)], ids=[IDS[i] for i in (0, 1, 4)]
)
def test_fitted_optimum_agrees_with_scikit_learn(covariance, shape, kernel):
    X, y, _, D, _ = point_masses()
    sy, l0 = float(np.std(y)), float(np.median(D[D > 0]))
    bounds = {
        "alpha": (1e-3 * sy, 1e3 * sy),
        "l": (1e-3 * l0, 1e3 * l0),
        "sigma_n": (1e-4 * sy, sy),
    }
    ours = DistributionGP(covariance, n_restarts=3, bounds=bounds, **shape)
    fit = ours.fit(D, y, np.random.default_rng(1)).result
    squared = lambda pair: tuple(np.square(pair))  # scikit-learn bounds variances
    peer_kernel = ConstantKernel(sy**2, squared(bounds["alpha"])) * kernel(
        l0, bounds["l"]
    ) + WhiteKernel((1e-2 * sy) ** 2, squared(bounds["sigma_n"]))
    peer = GaussianProcessRegressor(peer_kernel, alpha=0.0, n_restarts_optimizer=3, random_state=0)
    peer.fit(X, y - y.mean())
    amplitude, length, noise = np.exp(peer.kernel_.theta)
    assert fit.converged
    np.testing.assert_allclose(
        [fit.alpha, fit.l, fit.sigma_n], [np.sqrt(amplitude), length, np.sqrt(noise)], rtol=1e-4
    )
    assert fit.log_ml == pytest.approx(peer.log_marginal_likelihood_value_, rel=1e-8)
