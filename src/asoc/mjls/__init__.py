"""Chapter 3: Markov jump linear systems (MJLS) without mode observation.

The model (3.7): x_{k+1} = A_theta x_k + B_theta u_k + H_theta w_k, y_k = C_theta x_k (+ J_theta v_k),
with a Markov chain theta_k (transition matrix T) that the controller does not observe.

Modules: ``system`` (the model), ``stability`` (Cor. 3.2), ``moments`` (Prop. 3.7, 3.14),
``static`` (Alg. 3.1), ``lmi`` (Thms. 3.9, 3.12), ``dynamic`` (Alg. 3.2), ``finite_horizon``
(Alg. 3.3), ``observed`` and ``optimal_observed`` (the mode-observing optimum [38] for
state feedback and for output feedback), ``baselines`` ([52], [163], [165]),
``intractability`` (Sec. 3.4), ``exact`` (exact-cost optimisation of (3.37) and (3.55),
not in the thesis), ``simulate`` (Monte Carlo), ``examples`` (the thesis's
examples), ``comparison`` (Table 3.2).
"""

from .dynamic import (DynamicOutputFeedbackResult, augmented_closed_loop, dynamic_output_feedback,
                      steady_state_cost)
from .exact import (ExactDynamicOutputFeedbackResult, ExactFiniteHorizonResult, exact_dynamic_output_feedback,
                    exact_finite_horizon_dynamic_output_feedback, min_radius_dynamic_output_feedback)
from .gradients import average_cost_and_gradient, radius_and_gradient
from .finite_horizon import (FiniteHorizonResult, finite_horizon_cost,
                             finite_horizon_dynamic_output_feedback)
from .lmi import LMIResult, static_output_lmi
from .moments import h2_cost, second_moment_step, second_moments, steady_state_second_moment
from .observed import ObservedModeResult, observed_mode_state_feedback
from .optimal_observed import ModeObservedLQG, ModeObservedResult, mode_observed_lqg
from .random import random_mjls
from .simulate import (Controller, DynamicOutputFeedback, ModeDependentGain, SimulationResult,
                       StaticGain, TimeVariantGain, simulate)
from .stability import closed_loop, ms_operator, ms_spectral_radius
from .static import StaticOutputFeedbackResult, gain_from_moments, static_output_feedback
from .system import MJLS, predecessor_sum, successor_average, stationary_distribution

__all__ = ["MJLS", "predecessor_sum", "successor_average", "stationary_distribution", "ms_operator", "ms_spectral_radius",
           "closed_loop", "second_moment_step", "second_moments", "steady_state_second_moment",
           "h2_cost", "static_output_feedback", "StaticOutputFeedbackResult", "gain_from_moments",
           "static_output_lmi", "LMIResult", "observed_mode_state_feedback", "ObservedModeResult",
           "dynamic_output_feedback", "DynamicOutputFeedbackResult", "augmented_closed_loop",
           "steady_state_cost", "finite_horizon_dynamic_output_feedback", "FiniteHorizonResult",
           "finite_horizon_cost", "mode_observed_lqg", "ModeObservedLQG", "ModeObservedResult",
           "simulate", "SimulationResult", "Controller", "StaticGain", "ModeDependentGain",
           "TimeVariantGain", "DynamicOutputFeedback", "exact_dynamic_output_feedback",
           "exact_finite_horizon_dynamic_output_feedback", "average_cost_and_gradient",
           "min_radius_dynamic_output_feedback", "radius_and_gradient", "ExactDynamicOutputFeedbackResult",
           "ExactFiniteHorizonResult", "random_mjls"]
