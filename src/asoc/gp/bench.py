"""``make bench`` targets of Sec. 2.6 (issue: distance matrices 200 x ~4000)."""

import time

import numpy as np

from . import (DistributionGP, gaussian_dirac_mixtures, mcvmd_matrix, omat_matrix, test_grid,
               training_gaussians, v2)


def _inputs():
    mu, var = training_gaussians(200, np.random.default_rng(2017))
    mu_axis, var_axis = test_grid(0.1)
    MU, VAR = np.meshgrid(mu_axis, var_axis)
    X_tr = gaussian_dirac_mixtures(mu, var, 10)
    X_te = gaussian_dirac_mixtures(MU.ravel(), VAR.ravel(), 10)
    return mu, var, X_tr, X_te


def _timed(fn):
    def run():
        args = _inputs()
        start = time.perf_counter()
        fn(*args)
        return time.perf_counter() - start
    return run


def _mcvmd(mu, var, X_tr, X_te):
    mcvmd_matrix(X_te, X_tr)


def _omat(mu, var, X_tr, X_te):
    omat_matrix(X_te, X_tr)


def _fit(mu, var, X_tr, X_te):
    DistributionGP("se", n_restarts=4).fit(mcvmd_matrix(X_tr), v2(mu, var), np.random.default_rng(7))


BENCHMARKS = [
    ("mCvMd distance matrix, 4040 test x 200 training mixtures (L=10)", 10.0, _timed(_mcvmd), 3),
    ("OMAT distance matrix, 4040 test x 200 training mixtures (L=10)", 30.0, _timed(_omat), 1),
    ("DistributionGP fit, 200 inputs, SE, 1 + 4 starts", 10.0, _timed(_fit), 3),
]
