"""Gaussian process regression over probability distributions (thesis Sec. 2.6).

* cramer_von_mises: the modified Cramer-von Mises distance (closed form for Dirac mixtures,
  quadrature
  of its definition) and localized cumulative distributions;
* transport: Wasserstein-2 of Gaussians, OMAT (2.23) and OSPA;
* densities: L_q, Hellinger and Jensen-Shannon (quadrature, Gaussians, piecewise-constant
  densities);
* kernels: covariance functions of a distance (Table 2.1), bilinear product, mean kernel (2.22);
* sampling: deterministic LCD / mCvMd Dirac approximation of Gaussians [82];
* experiment: Sec. 2.6.4: the test functions v_1 (:func:`quadratic_function`) and v_2
  (:func:`modified_rosenbrock`), training and test Gaussians, error metrics;
* regression: DistributionGP (Sec. 2.6.3) and the mean-kernel GP of Dallaire et al. [42].

Which pairs of distribution types each distance accepts, as the thesis discusses them:

Which pairs of distribution types each distance accepts, as the thesis discusses them:

================================  ======================  ==========  ================
distance                          continuous/continuous   Dirac/Dirac continuous/Dirac
================================  ======================  ==========  ================
L_q (:func:`lq_distance`)         yes (quadrature)        no          no
Hellinger (:func:`hellinger`)     yes (quadrature; closed no          no
                                  form for Gaussians)
Jensen-Shannon                    yes (quadrature)        no          no
Wasserstein-2                     Gaussians (closed form) OMAT/OSPA   intractable here
modified Cramer-von Mises         via LCD quadrature      closed form via LCD quadrature
================================  ======================  ==========  ================

Every distance has a pairwise ``*_matrix`` form on arrays of distributions: Dirac mixtures
(N, L, d) for :func:`mcvmd_matrix` and :func:`omat_matrix`, sequences of point sets for
:func:`ospa_matrix`, Gaussians (means (N, d), covariances (N, d, d)) for
:func:`wasserstein_gaussian_matrix` and :func:`hellinger_gaussian_matrix`, and
piecewise-constant densities (heights (N, B) on common cells) for :func:`lq_distance_matrix`,
:func:`hellinger_matrix` and :func:`jensen_shannon_matrix`.
"""

from .cramer_von_mises import (
    lcd_dirac,
    lcd_gaussian,
    mcvmd,
    mcvmd_constant,
    mcvmd_matrix,
    mcvmd_quadrature,
)
from .densities import (
    hellinger,
    hellinger_gaussian,
    hellinger_gaussian_matrix,
    hellinger_matrix,
    jensen_shannon,
    jensen_shannon_matrix,
    lq_distance,
    lq_distance_matrix,
)
from .experiment import (
    error_metrics,
    evaluation_grid,
    modified_rosenbrock,
    quadratic_function,
    training_gaussians,
)
from .kernels import (
    COVARIANCES,
    TABLE_2_1,
    bilinear_product,
    exponential,
    gamma_exponential,
    matern,
    mean_kernel_dirac,
    mean_kernel_gaussian,
    rational_quadratic,
    squared_exponential,
)
from .regression import DistributionGP, FitResult, MeanKernelGP
from .sampling import (
    DiracApproximation,
    gaussian_dirac_mixtures,
    mcvmd_standard_normal_dirac,
    standard_normal_dirac_approximation,
)
from .study import KernelStudy, kernel_study
from .transport import (
    omat,
    omat_matrix,
    ospa,
    ospa_matrix,
    wasserstein_gaussian,
    wasserstein_gaussian_matrix,
)

__all__ = ["hellinger", "hellinger_gaussian", "hellinger_gaussian_matrix", "hellinger_matrix",
           "jensen_shannon", "jensen_shannon_matrix", "lcd_dirac", "lcd_gaussian", "lq_distance",
           "lq_distance_matrix", "mcvmd", "mcvmd_constant", "mcvmd_matrix", "mcvmd_quadrature",
           "omat", "omat_matrix", "ospa", "ospa_matrix", "wasserstein_gaussian",
           "wasserstein_gaussian_matrix", "error_metrics", "evaluation_grid",
           "modified_rosenbrock", "quadratic_function", "training_gaussians", "COVARIANCES",
           "TABLE_2_1", "bilinear_product", "exponential", "gamma_exponential", "matern",
           "mean_kernel_dirac", "mean_kernel_gaussian", "rational_quadratic",
           "squared_exponential", "DistributionGP", "FitResult", "MeanKernelGP",
           "DiracApproximation", "gaussian_dirac_mixtures", "mcvmd_standard_normal_dirac",
           "standard_normal_dirac_approximation", "KernelStudy", "kernel_study"]
