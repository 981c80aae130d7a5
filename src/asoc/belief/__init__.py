"""Belief-space trajectory optimisation by statistical Taylor expansion (thesis Sec. 2.5).

* models: nonlinear stochastic models (2.1)-(2.2), Gaussian noise samplers, the cost (2.3),
  the example of Sec. 2.5.3;
* filters: Dirac mixtures (2.5), UKF, particle filter, EKF, the next estimate's covariance
  (Lemma 2.1);
* taylor: the statistical Taylor expansion (Definition 2.2) and the linearisations of Fig. 2.2;
* trajectory: Algorithms 2.1-2.3 and Theorems 2.4-2.5
  (:func:`optimize_belief_trajectory` is Algorithm 2.2);
* vdberg: the competitor [159], belief-space iLQG with EKF beliefs;
* simulate: closed-loop Monte Carlo of both controllers.
"""

from .filters import UKF, DiracMixture, ParticleFilter, ekf_step, next_estimate_covariance, sigma_points
from .models import (GaussianNoise, LandmarkExample, NonlinearModel, QuadraticCost, landmark_example,
                     linear_gaussian_model)
from .simulate import BeliefAffineController, ClosedLoop, MeanAffineController, Noise, draw_noise, simulate
from .taylor import (QuadraticExpansion, sigma_point_linearizations, statistical_taylor_expansion,
                     statistical_taylor_linearization_error)
from .trajectory import (AffinePolicy, Expansion, LineSearch, Reference, StageProblem,
                         TrajectoryOptimizationResult, Value, affine_policy_value, backward_pass,
                         improved_policy_value, line_search, optimize_belief_trajectory, reference_trajectory,
                         terminal_value)
from .vdberg import BeliefDynamics, BeliefILQGResult, belief_ilqg, belief_vector

__all__ = ["UKF", "DiracMixture", "ParticleFilter", "ekf_step", "next_estimate_covariance", "sigma_points",
           "GaussianNoise", "LandmarkExample", "NonlinearModel", "QuadraticCost", "landmark_example",
           "linear_gaussian_model", "BeliefAffineController", "ClosedLoop", "MeanAffineController", "Noise",
           "draw_noise", "simulate", "QuadraticExpansion", "sigma_point_linearizations",
           "statistical_taylor_expansion", "statistical_taylor_linearization_error", "AffinePolicy", "Expansion",
           "LineSearch", "Reference", "StageProblem", "TrajectoryOptimizationResult", "Value",
           "affine_policy_value", "backward_pass", "improved_policy_value", "line_search",
           "optimize_belief_trajectory", "reference_trajectory", "terminal_value", "BeliefDynamics",
           "BeliefILQGResult", "belief_ilqg", "belief_vector"]
