"""Markov jump linear systems whose mode the controller does not observe (Chapter 3).

The model: x_{k+1} = A_i x_k + B_i u_k + H_i w_k, y_k = C_i x_k + J_i v_k while the mode
theta_k = i, a Markov chain with transition matrix T. By task:

Build a system
    :class:`MJLS` (matrices per mode), :meth:`MJLS.from_statespace` (python-control
    StateSpace objects, weights optional), :func:`random_mjls`; the thesis's examples and a
    networked loop in :mod:`asoc.mjls.examples`.
Analyse
    :func:`ms_spectral_radius` (mean-square stable iff < 1), :func:`mean_square_stability`
    (a certified bracket of the spectral radius and its verdict), :func:`closed_loop`,
    :func:`second_moments`, :func:`steady_state_second_moment`.
Design a static gain u = L y
    :func:`exact_static_output_feedback` (smallest exact cost; the one to use),
    :func:`static_output_feedback` (the thesis's Alg. 3.1, which may stop on a cycle; with
    ``moments="auto"`` it picks the faster of two exact iterations), :func:`static_output_lmi`
    (a stabilising gain from a sufficient LMI condition).
Design a dynamic controller x^+ = F x^ + K y, u = L x^
    :func:`exact_dynamic_output_feedback` (smallest exact cost; the one to use),
    :func:`dynamic_output_feedback` (the thesis's Alg. 3.2, which minimises a bound and may
    stop on a cycle), :func:`min_radius_dynamic_output_feedback` (most stable), and for a
    finite horizon :func:`finite_horizon_dynamic_output_feedback`,
    :func:`exact_finite_horizon_dynamic_output_feedback`.
Simulate
    :func:`simulate` (Monte Carlo) takes any design result or :class:`Controller`.
Compare
    :func:`average_cost` (exact), :func:`finite_horizon_cost`,
    :mod:`asoc.mjls.monte_carlo_comparison` (Table 3.2's Monte Carlo comparison),
    :func:`mode_observed_lqg` (the mode-observing optimum, a lower bound).

Every design returns a result with ``.controller``, ``.cost``, ``.status`` and ``.message``;
a time-invariant design's also holds ``.stability``, the certificate of its closed loop
(``.rho``, ``.rho_bracket``, ``.stabilizing``). The analysis functions take a result or its
controller in place of gains: ``mean_square_stability(sys, result)``,
``augmented_closed_loop(sys, result)``, ``steady_state_cost(sys, result)``, ``simulate``;
``result.controller.to_statespace(dt)`` hands it to python-control. Example, a loop that loses
input packets:

>>> import numpy as np
>>> from asoc.mjls.examples import networked_loop
>>> sys = networked_loop()
>>> round(ms_spectral_radius(sys.A, sys.T), 3)
0.811
>>> static = static_output_feedback(sys)
>>> dynamic = exact_dynamic_output_feedback(sys)
>>> static.status, dynamic.status, bool(dynamic.cost < static.cost)
('converged', 'converged', True)
>>> mean_square_stability(dynamic) is dynamic.stability
True
>>> dynamic.controller.to_statespace(0.1).nstates
3
>>> runs = simulate(sys, dynamic, np.zeros(3), 100, 500, np.random.default_rng(0))
>>> bool(abs(runs.average_cost.mean() - dynamic.cost) < 0.1 * dynamic.cost)
True

Modules, by the thesis's numbers: ``system`` (the model (3.7)), ``moment_operator`` (the
second-moment operator L of (3.29) and its adjoint), ``closed_loops`` ((3.10), (3.39)-(3.40)),
``stability`` -> ``certificate`` -> ``spectral_estimate`` (Cor. 3.2: the verdict, the certified
bracket, the eigen-solver's estimate), ``lyapunov`` (coupled Lyapunov equations), ``moments``
(Prop. 3.7, 3.14), ``static`` and ``static_iterates`` (Alg. 3.1), ``stopping`` (the stopping rule of
Algs. 3.1 and 3.2), ``exact_static_design`` (the exact-cost static gain, not in the thesis), ``lmi``
(Thms. 3.9, 3.12), ``moment_bounds``, ``optimality`` and ``dynamic``
(Alg. 3.2: Prop. 3.26, (3.49)-(3.51)), ``finite_horizon_model`` (the time-variant MJLS (3.54) over a
horizon) and ``finite_horizon`` (Alg. 3.3), ``observed_mode_feedback`` and ``observed_mode_lqg``
(the mode-observing optima [38]), ``baselines`` ([52], [163], [165]), ``intractability`` (Sec. 3.4),
``gradients`` and ``exact_cost_design`` (exact-cost optimisation of (3.37) and (3.55), not in the
thesis), ``costs`` (the exact average cost (3.9)), ``monte_carlo`` (simulation),
``monte_carlo_comparison`` (Table 3.2), ``controllers`` and ``design_result`` (the controllers and
what every design's result shares), ``examples`` (the thesis's examples), ``random``.
"""

from .closed_loops import closed_loop
from .controllers import (
    Controller,
    DynamicOutputFeedback,
    ModeDependentGain,
    StaticGain,
    TimeVariantGain,
)
from .costs import average_cost
from .dynamic import (
    DynamicOutputFeedbackResult,
    augmented_closed_loop,
    dynamic_output_feedback,
    steady_state_cost,
)
from .exact_cost_design import (
    ExactDynamicOutputFeedbackResult,
    ExactFiniteHorizonResult,
    exact_dynamic_output_feedback,
    exact_finite_horizon_dynamic_output_feedback,
    min_radius_dynamic_output_feedback,
)
from .exact_static_design import ExactStaticOutputFeedbackResult, exact_static_output_feedback
from .finite_horizon import (
    FiniteHorizonResult,
    finite_horizon_cost,
    finite_horizon_dynamic_output_feedback,
)
from .gradients import average_cost_and_gradient, radius_and_gradient
from .lmi import LMIResult, static_output_lmi
from .moment_operator import ms_operator
from .moments import h2_cost, second_moment_step, second_moments, steady_state_second_moment
from .monte_carlo import SimulationResult, simulate
from .observed_mode_feedback import ObservedModeResult, observed_mode_state_feedback
from .observed_mode_lqg import ModeObservedLQG, ModeObservedResult, mode_observed_lqg
from .random import random_mjls
from .stability import MeanSquareStability, Verdict, mean_square_stability, ms_spectral_radius
from .static import (
    StaticOutputFeedbackResult,
    gain_from_moments,
    static_cost,
    static_output_feedback,
)
from .system import MJLS, predecessor_sum, stationary_distribution, successor_average

__all__ = ["MJLS", "predecessor_sum", "successor_average", "stationary_distribution",
           "ms_operator", "ms_spectral_radius", "mean_square_stability", "MeanSquareStability",
           "Verdict", "closed_loop", "second_moment_step", "second_moments",
           "steady_state_second_moment", "h2_cost", "static_output_feedback",
           "StaticOutputFeedbackResult", "gain_from_moments", "static_output_lmi", "LMIResult",
           "observed_mode_state_feedback", "ObservedModeResult", "dynamic_output_feedback",
           "DynamicOutputFeedbackResult", "augmented_closed_loop", "steady_state_cost",
           "finite_horizon_dynamic_output_feedback", "FiniteHorizonResult", "finite_horizon_cost",
           "mode_observed_lqg", "ModeObservedLQG", "ModeObservedResult", "simulate",
           "SimulationResult", "Controller", "StaticGain", "ModeDependentGain", "TimeVariantGain",
           "DynamicOutputFeedback", "exact_dynamic_output_feedback",
           "exact_finite_horizon_dynamic_output_feedback", "average_cost_and_gradient",
           "min_radius_dynamic_output_feedback", "radius_and_gradient",
           "ExactDynamicOutputFeedbackResult", "ExactFiniteHorizonResult", "random_mjls",
           "average_cost", "static_cost", "exact_static_output_feedback",
           "ExactStaticOutputFeedbackResult"]
