"""Belief-space trajectory optimisation by statistical Taylor expansion (thesis Sec. 2.5).

* models: nonlinear stochastic models (2.1)-(2.2), Gaussian noise samplers, the cost (2.3),
  the example of Sec. 2.5.3;
* filters: the filter protocol of Alg. 2.2, Dirac mixtures (2.5), sigma points, the next
  estimate's covariance (Lemma 2.1); ukf, particle, ekf: the UKF, the particle filter and
  the EKF (used by the competitor [159]);
* taylor: the statistical Taylor expansion (Definition 2.2) and the linearisations of Fig. 2.2;
* policy: the affine policy (2.18) and the controller that applies it;
* stage: Theorem 2.4 and the stage problem (2.13) with its expansion (2.15);
* improvement: Theorem 2.5, the improved policy (2.17) and Algorithm 2.3;
* trajectory: Algorithms 2.1 and 2.2 (:func:`optimize_belief_trajectory` is Algorithm 2.2);
* vdberg: the competitor [159], belief-space iLQG with EKF beliefs, and its controller;
* simulate: closed-loop Monte Carlo of both controllers; sweep: Alg. 2.2 over perturbations.
"""

from .damped import DampedResult, optimize_damped
from .ekf import ekf_step
from .filters import BeliefFilter, DiracMixture, next_estimate_covariance, sigma_points
from .improvement import (
    LineSearch,
    affine_policy_value,
    improved_policy_value,
    line_search,
    policy_step,
)
from .models import (
    GaussianNoise,
    LandmarkExample,
    NonlinearModel,
    QuadraticCost,
    landmark_example,
    linear_gaussian_model,
)
from .particle import ParticleFilter
from .planning import bend_toward_landmark, covariance_aware_optimum
from .policy import AffinePolicy, MeanAffineController
from .simulate import ClosedLoop, Noise, draw_noise, simulate
from .stage import Expansion, StageProblem, Value, terminal_value
from .taylor import (
    QuadraticExpansion,
    sigma_point_linearizations,
    statistical_taylor_expansion,
    statistical_taylor_linearization_error,
)
from .trajectory import (
    IndefiniteStep,
    Reference,
    TrajectoryOptimizationResult,
    backward_pass,
    optimize_belief_trajectory,
    reference_trajectory,
)
from .ukf import UKF
from .vdberg import (
    BeliefAffineController,
    BeliefDynamics,
    BeliefILQGResult,
    belief_ilqg,
    belief_vector,
)

__all__ = ["UKF", "BeliefFilter", "DiracMixture", "ParticleFilter", "ekf_step",
           "next_estimate_covariance", "sigma_points", "GaussianNoise", "LandmarkExample",
           "NonlinearModel", "QuadraticCost", "landmark_example", "linear_gaussian_model",
           "BeliefAffineController", "ClosedLoop", "MeanAffineController", "Noise", "draw_noise",
           "simulate", "QuadraticExpansion", "sigma_point_linearizations",
           "statistical_taylor_expansion", "statistical_taylor_linearization_error",
           "AffinePolicy", "Expansion", "LineSearch", "Reference", "StageProblem",
           "TrajectoryOptimizationResult", "Value", "affine_policy_value", "backward_pass",
           "improved_policy_value", "line_search", "policy_step", "optimize_belief_trajectory",
           "reference_trajectory", "terminal_value", "BeliefDynamics", "BeliefILQGResult",
           "belief_ilqg", "belief_vector", "IndefiniteStep", "DampedResult", "optimize_damped",
           "bend_toward_landmark", "covariance_aware_optimum"]
