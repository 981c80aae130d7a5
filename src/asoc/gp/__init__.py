"""Gaussian process regression over probability distributions (thesis Sec. 2.6).

* distances: distances between distributions: mCvMd (closed form for Dirac mixtures),
  OMAT (2.23), OSPA, Wasserstein-2 of Gaussians, Hellinger, Jensen-Shannon, L_q;
* kernels: covariance functions of a distance (Table 2.1), bilinear product, mean kernel (2.22);
* sampling: deterministic LCD / mCvMd Dirac approximation of Gaussians [82];
* experiment: Sec. 2.6.4: the test functions v_1 (:func:`quadratic_function`) and v_2
  (:func:`modified_rosenbrock`), training and test Gaussians, error metrics;
* regression: DistributionGP (Sec. 2.6.3) and the mean-kernel GP of Dallaire et al. [42].
"""

from .distances import (hellinger, hellinger_gaussian, jensen_shannon, lcd_dirac, lcd_gaussian, lq_distance,
                        mcvmd, mcvmd_constant, mcvmd_matrix, mcvmd_quadrature, omat, omat_matrix, ospa,
                        wasserstein_gaussian)
from .experiment import error_metrics, evaluation_grid, modified_rosenbrock, quadratic_function, training_gaussians
from .kernels import (COVARIANCES, TABLE_2_1, bilinear_product, exponential, gamma_exponential,
                      matern, mean_kernel_dirac, mean_kernel_gaussian, rational_quadratic,
                      squared_exponential)
from .regression import DistributionGP, FitResult, MeanKernelGP
from .sampling import (DiracApproximation, gaussian_dirac_mixtures, mcvmd_standard_normal_dirac,
                       standard_normal_dirac_approximation)

__all__ = ["hellinger", "hellinger_gaussian", "jensen_shannon", "lcd_dirac", "lcd_gaussian", "lq_distance",
           "mcvmd", "mcvmd_constant", "mcvmd_matrix", "mcvmd_quadrature", "omat", "omat_matrix", "ospa",
           "wasserstein_gaussian", "error_metrics", "evaluation_grid", "modified_rosenbrock",
           "quadratic_function", "training_gaussians", "COVARIANCES", "TABLE_2_1", "bilinear_product",
           "exponential", "gamma_exponential", "matern", "mean_kernel_dirac", "mean_kernel_gaussian",
           "rational_quadratic", "squared_exponential", "DistributionGP", "FitResult", "MeanKernelGP",
           "DiracApproximation", "gaussian_dirac_mixtures", "mcvmd_standard_normal_dirac",
           "standard_normal_dirac_approximation"]
