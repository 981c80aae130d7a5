"""Gaussian process regression over probability distributions (thesis Sec. 2.6).

* distances: distances between distributions: mCvMd (closed form for Dirac mixtures),
  OMAT (2.23), OSPA, Wasserstein-2 of Gaussians, Hellinger, Jensen-Shannon, L_q;
* kernels: covariance functions of a distance (Table 2.1), bilinear product, mean kernel (2.22);
* sampling: deterministic LCD / mCvMd Dirac approximation of Gaussians [82];
* experiment: Sec. 2.6.4: test functions v1, v2, training and test Gaussians, error metrics;
* regression: DistributionGP (Sec. 2.6.3) and the mean-kernel GP of Dallaire et al. [42].
"""

from .distances import (c_b, hellinger, hellinger_gaussian, jensen_shannon, lcd_dirac,
                        lcd_gaussian, lq_distance, mcvmd, mcvmd_matrix, mcvmd_quadrature, omat,
                        omat_matrix, ospa, wasserstein_gaussian)
from .experiment import error_metrics, test_grid, training_gaussians, v1, v2
from .kernels import (COVARIANCES, TABLE_2_1, bilinear_product, exponential, gamma_exponential,
                      matern, mean_kernel_dirac, mean_kernel_gaussian, rational_quadratic,
                      squared_exponential)
from .regression import DistributionGP, FitResult, MeanKernelGP
from .sampling import gaussian_dirac_mixtures, lcd_standard_normal, mcvmd_standard_normal_dirac

__all__ = ["c_b", "hellinger", "hellinger_gaussian", "jensen_shannon", "lcd_dirac", "lcd_gaussian",
           "lq_distance", "mcvmd", "mcvmd_matrix", "mcvmd_quadrature", "omat", "omat_matrix",
           "ospa", "wasserstein_gaussian", "COVARIANCES", "TABLE_2_1", "bilinear_product",
           "exponential", "gamma_exponential", "matern", "mean_kernel_dirac",
           "mean_kernel_gaussian", "rational_quadratic", "squared_exponential",
           "DistributionGP", "FitResult", "MeanKernelGP", "gaussian_dirac_mixtures", "error_metrics", "test_grid", "training_gaussians", "v1", "v2", "lcd_standard_normal", "mcvmd_standard_normal_dirac"]
