"""Belief-space trajectory optimisation by statistical Taylor expansion (thesis Sec. 2.5).

* models: nonlinear stochastic models (2.1)-(2.2), Gaussian noise samplers, the cost (2.3),
  the example of Sec. 2.5.3;
* filters: Dirac mixtures (2.5), UKF, particle filter, EKF, Lemma 2.1;
* taylor: Definition 2.2 and the linearisation errors of Fig. 2.2;
* trajectory: Algorithms 2.1-2.3 and Theorems 2.4-2.5;
* vdberg: the competitor [159], belief-space iLQG with EKF beliefs;
* simulate: closed-loop Monte Carlo of both controllers.
"""

from .filters import (UKF, DiracMixture, ParticleFilter, ekf_step, lemma_2_1, sigma_points)
from .models import (GaussianNoise, LandmarkExample, NonlinearModel, QuadraticCost, landmark_example,
                     linear_gaussian_model)
from .simulate import (BeliefAffineController, ClosedLoop, MeanAffineController, draw_noise, simulate)
from .taylor import (QuadraticExpansion, fig2_2_linearizations, statistical_taylor_expansion,
                     statistical_taylor_linearization_error)
from .trajectory import (AffinePolicy, Alg22Result, Value, affine_policy_value, algorithm_2_2,
                         backward_pass, line_search, reference_trajectory, terminal_value,
                         theorem_2_5_value)
from .vdberg import BeliefDynamics, BeliefILQGResult, belief_ilqg, belief_vector

__all__ = ["UKF", "DiracMixture", "ParticleFilter", "ekf_step", "lemma_2_1", "sigma_points",
           "GaussianNoise", "LandmarkExample", "NonlinearModel", "QuadraticCost", "landmark_example",
           "linear_gaussian_model", "BeliefAffineController", "ClosedLoop", "MeanAffineController",
           "draw_noise", "simulate", "QuadraticExpansion", "fig2_2_linearizations",
           "statistical_taylor_expansion", "statistical_taylor_linearization_error", "AffinePolicy",
           "Alg22Result", "Value", "affine_policy_value", "algorithm_2_2", "backward_pass", "line_search",
           "reference_trajectory", "terminal_value", "theorem_2_5_value", "BeliefDynamics",
           "BeliefILQGResult", "belief_ilqg", "belief_vector"]
