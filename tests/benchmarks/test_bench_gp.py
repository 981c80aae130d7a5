"""Performance targets of Sec. 2.6: distance matrices 4040 test x 200 training mixtures, a GP
fit."""

import numpy as np
import pytest

from asoc.gp import (
    DistributionGP,
    evaluation_grid,
    gaussian_dirac_mixtures,
    mcvmd_matrix,
    modified_rosenbrock,
    omat_matrix,
    training_gaussians,
)


@pytest.fixture(scope="module")
def inputs():
    """200 training Gaussians of Sec. 2.6.4 and the 4040-point test grid, as 10-point Dirac
    mixtures."""
    mu, var = training_gaussians(200, np.random.default_rng(2017))
    mu_axis, var_axis = evaluation_grid(0.1)
    MU, VAR = np.meshgrid(mu_axis, var_axis)
    return (
        mu,
        var,
        gaussian_dirac_mixtures(mu, var, 10),
        gaussian_dirac_mixtures(MU.ravel(), VAR.ravel(), 10),
    )


def test_mcvmd_distance_matrix(benchmark, inputs):
    """mCvMd distance matrix, 4040 test x 200 training mixtures (L = 10)."""
    _, _, train, test = inputs
    benchmark.extra_info["target_s"] = 10.0
    benchmark.pedantic(mcvmd_matrix, args=(test, train), rounds=3)


def test_omat_distance_matrix(benchmark, inputs):
    """OMAT distance matrix, 4040 test x 200 training mixtures (L = 10)."""
    _, _, train, test = inputs
    benchmark.extra_info["target_s"] = 30.0
    benchmark.pedantic(omat_matrix, args=(test, train), rounds=1)


def test_gp_fit(benchmark, inputs):
    """DistributionGP fit, 200 inputs, SE kernel, 1 + 4 starts."""
    mu, var, train, _ = inputs
    distances, targets = mcvmd_matrix(train), modified_rosenbrock(mu, var)
    benchmark.extra_info["target_s"] = 10.0
    benchmark.pedantic(
        lambda: DistributionGP("se", n_restarts=4).fit(
            distances, targets, np.random.default_rng(7)
        ),
        rounds=3,
    )
