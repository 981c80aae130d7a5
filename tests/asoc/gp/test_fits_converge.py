"""The likelihood maximisations of Sec. 2.6.4 reach their tolerance; the study over seeds."""

import warnings

import numpy as np
import pytest

from asoc import config, gp
from asoc.gp.regression import ALPHA_CAP, NOISE_FLOOR
from asoc.gp.study import kernel_study


@pytest.fixture(scope="module")
def omat_problem():
    mu, var = gp.training_gaussians(200, np.random.default_rng(2017))
    X = gp.gaussian_dirac_mixtures(mu, var, 10, 100.0)
    return gp.omat_matrix(X), mu, var


@pytest.mark.parametrize("function", [gp.quadratic_function, gp.modified_rosenbrock])
def test_omat_fits_of_sec_2_6_4_converge(omat_problem, function):
    D, mu, var = omat_problem
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # an unconverged fit warns: fail here
        g = gp.DistributionGP("se", n_restarts=1).fit(
            D, function(mu, var), np.random.default_rng(7)
        )
    assert g.result.converged and g.result.gradient_norm <= config.defaults["gp.gradient_tol"]


def test_planted_old_bounds_drive_the_omat_fit_into_the_ill_conditioned_corner(omat_problem):
    """The bounds before the fix (alpha <= 1e3 std(y), sigma_n >= 1e-4 std(y)): the fit runs into
    both bounds, alpha^2 / sigma_n^2 = 1e14, where the kernel matrix's condition leaves the
    likelihood's gradient to rounding (its projected norm at the end was 0.04, 0.38, 0.98 and 4.9
    on four emulated CPUs, so whether the fit "converges" is not a property of the bounds). The
    default bounds keep the ratio below (ALPHA_CAP / NOISE_FLOOR)^2 = 1e10."""
    D, mu, var = omat_problem
    y = gp.quadratic_function(mu, var)
    sy, med = y.std(), np.median(D[D > 0])
    old = {"alpha": (1e-3 * sy, 1e3 * sy), "l": (1e-3 * med, 1e3 * med), "sigma_n": (1e-4 * sy, sy)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        g = gp.DistributionGP("se", n_restarts=0, bounds=old).fit(D, y, np.random.default_rng(7))
    r = g.result
    np.testing.assert_allclose([r.alpha / sy, r.sigma_n / sy], [1e3, 1e-4], rtol=1e-9)
    assert (r.alpha / r.sigma_n) ** 2 > 0.99e4 * (ALPHA_CAP / NOISE_FLOOR) ** 2


def test_default_bounds_bound_the_condition_number():
    x = np.linspace(-2, 2, 30)
    g = gp.DistributionGP("se", n_restarts=0).fit(
        np.abs(x[:, None] - x[None]), x**2, np.random.default_rng(0)
    )
    r, sy = g.result, float(np.std(x**2))
    assert r.alpha <= ALPHA_CAP * sy * (1 + 1e-9) and r.sigma_n >= NOISE_FLOOR * sy * (1 - 1e-9)


def test_kernel_study_shapes_and_convergence():
    s = kernel_study(2, np.random.default_rng(0), n_train=30, grid_step=1.0)
    assert s.n_seeds == 2 and s.n_fits == 12
    assert set(s.rmse) == {(f, k) for f in ("v1", "v2") for k in ("mcvmd", "omat", "mean_kernel")}
    assert all(np.all(v > 0) for v in s.rmse.values())
    assert all(np.all(v <= 1.0 + 1e-12) for v in s.r2.values())
    # seeds are independent training sets: the errors differ between them
    assert not np.allclose(s.rmse["v1", "mcvmd"][0], s.rmse["v1", "mcvmd"][1])


def test_kernel_study_is_reproducible_and_rejects_bad_input():
    a = kernel_study(1, np.random.default_rng(3), n_train=20, grid_step=1.0)
    b = kernel_study(1, np.random.default_rng(3), n_train=20, grid_step=1.0)
    np.testing.assert_allclose(a.rmse["v2", "omat"], b.rmse["v2", "omat"], rtol=1e-10)
    with pytest.raises(ValueError, match="n_seeds"):
        kernel_study(0, np.random.default_rng(0))
