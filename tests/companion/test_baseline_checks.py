"""The baselines [52], [165], [163] against formulations outside their own code (issue 30, item 6),
and the checks' own power: a wrong gain, an unconverged variational method are caught."""

import numpy as np
import pytest
import scipy.linalg

from asoc.mjls.baselines import do_val_h2_state_feedback, time_variant_feedback
from asoc_companion.baseline_checks import (
    brute_force_optimum,
    check_52,
    check_time_variant,
    exact_h2_cost,
    path_cost,
    random_instance,
)

TOL_52 = 1e-3  # the LMI's strictness margin 1e-6 moves the optimum by ~1e-5 relative
TOL_TIME_VARIANT = (
    1e-6  # the variational method stops at relative decrease 1e-10; Nelder-Mead at 1e-12
)


def test_52_matches_the_riccati_optimum_and_bounds_the_exact_h2_cost():
    out = check_52(np.random.default_rng(52), n_instances=2)
    assert out["max_rel_diff"] < TOL_52 and out["bound_holds"]


def test_a_wrong_52_gain_is_caught_by_the_exact_h2_cost():
    sys = random_instance(np.random.default_rng(7), 1, 2, state_feedback=True)
    P = scipy.linalg.solve_discrete_are(sys.A[0], sys.B[0], sys.Q[0], sys.R[0])
    optimum = float(np.trace(P @ sys.H[0] @ sys.H[0].T))
    gain = do_val_h2_state_feedback(sys).L
    assert abs(exact_h2_cost(sys, gain) / optimum - 1) < TOL_52
    assert exact_h2_cost(sys, 1.5 * gain) / optimum - 1 > TOL_52


@pytest.mark.parametrize("state_feedback, name", [(True, "165"), (False, "163")])
def test_time_variant_gains_reach_the_brute_force_optimum(state_feedback, name):
    out = check_time_variant(
        np.random.default_rng(165 if state_feedback else 163), state_feedback, n_instances=1
    )
    assert abs(out["max_rel_diff"]) < TOL_TIME_VARIANT, name
    assert out["max_cost_formula_diff"] < 1e-10, name


def test_an_unconverged_variational_method_is_caught_by_the_brute_force_optimum():
    rng = np.random.default_rng(3)
    sys = random_instance(rng, 2, 1)
    x0 = 2.0 * rng.standard_normal(sys.nx)
    one_sweep = time_variant_feedback(sys, 2, x0, mu0=sys.mu_inf, max_iter=1, warn=False)
    optimum, _ = brute_force_optimum(sys, 2, x0, sys.mu_inf)
    assert (
        path_cost(sys, one_sweep.G[None], x0, sys.mu_inf)[0] / optimum - 1 > 100 * TOL_TIME_VARIANT
    )
