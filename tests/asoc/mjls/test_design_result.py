"""One object, every tool (issues 32.3 and 33.4): every design result holds its certificate
(``stability``), shares one ``controller``, and the analysis tools take a result or its
controller as well as arrays; controllers print readably and go to python-control."""

import json
import warnings

import numpy as np
import pytest

import asoc.mjls as mjls
from asoc.mjls.closed_loops import controller_closed_loop
from asoc.mjls.design_result import CertifiedDesignResult, DesignResult
from asoc.mjls.examples import (
    SEC373_COV0,
    SEC373_MEAN0,
    SEC373_MU0,
    networked_loop,
    sec354_system,
    sec373_system,
)
from asoc.result import STATUS_CODES, IterativeResult, Status

control = pytest.importorskip("control")


@pytest.fixture(scope="module")
def designs():
    """One result of every time-invariant design, with the system it was designed for."""
    sys354, state, sys373 = sec354_system(1), sec354_system(1, "state"), sec373_system(1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return {
            "static": (sys354, mjls.static_output_feedback(sys354)),
            "lmi": (state, mjls.static_output_lmi(state)),
            "lmi_mode": (state, mjls.static_output_lmi(state, mode_observed=True)),
            "observed": (state, mjls.observed_mode_state_feedback(state)),
            "dynamic": (sys373, mjls.dynamic_output_feedback(sys373)),
            "exact": (sys373, mjls.exact_dynamic_output_feedback(sys373)),
            "min_radius": (sys373, mjls.min_radius_dynamic_output_feedback(sys373, max_iter=5)),
        }


@pytest.mark.parametrize(
    "name", ["static", "lmi", "lmi_mode", "observed", "dynamic", "exact", "min_radius"]
)
def test_every_design_holds_its_certificate_and_controller(designs, name):
    sys, res = designs[name]
    assert isinstance(res, CertifiedDesignResult)
    assert isinstance(res.stability, mjls.MeanSquareStability)
    assert (res.rho, res.rho_bracket, res.stabilizing) == (
        res.stability.rho,
        res.stability.bracket,
        res.stability.stabilizing,
    )
    again = mjls.mean_square_stability(sys, res)  # recomputed from the system
    assert again.verdict is res.stability.verdict
    assert again.rho == pytest.approx(res.rho, rel=1e-10)
    assert mjls.mean_square_stability(res) is res.stability
    assert mjls.ms_spectral_radius(res) == res.rho
    controller = res.controller
    assert controller.stability is res.stability
    assert "object at 0x" not in repr(controller) and res.stability.sentence() in repr(controller)
    assert mjls.mean_square_stability(sys, controller).rho == pytest.approx(res.rho, rel=1e-10)


def test_the_closed_loop_tools_take_a_result_or_its_controller(designs):
    sys, res = designs["exact"]
    by_gains = mjls.augmented_closed_loop(sys, res.F, res.K, res.L)
    for value in (res, res.controller):
        for a, b in zip(mjls.augmented_closed_loop(sys, value), by_gains):
            np.testing.assert_array_equal(a, b)
        cost, X, rho = mjls.steady_state_cost(sys, value)
        assert cost == pytest.approx(res.cost, rel=1e-9)
        assert rho == pytest.approx(res.rho, rel=1e-10)
        X_direct = mjls.steady_state_second_moment(sys, value)
        np.testing.assert_allclose(X_direct, X, rtol=1e-9, atol=1e-12)
    sys, static = designs["static"]
    np.testing.assert_array_equal(mjls.closed_loop(sys, static), mjls.closed_loop(sys, static.L))
    assert mjls.average_cost(sys, static) == pytest.approx(static.cost, rel=1e-12)


def test_a_static_gain_closed_loop_carries_its_measurement_noise():
    sys = sec373_system(1)  # J != 0
    L = np.array([[-0.2]])
    Acl, HHt_cl = controller_closed_loop(sys, mjls.StaticGain(L))
    BL = sys.B @ L
    np.testing.assert_allclose(
        HHt_cl,
        sys.H @ np.swapaxes(sys.H, 1, 2)
        + BL @ sys.J @ np.swapaxes(sys.J, 1, 2) @ np.swapaxes(BL, 1, 2),
    )
    np.testing.assert_allclose(Acl, sys.A + BL @ sys.C)


def test_simulate_takes_every_result(designs):
    sys, res = designs["static"]
    rng = np.random.default_rng(3)
    a = mjls.simulate(sys, res, [1.0, 0.0], 5, 4, rng=np.random.default_rng(3)).cost
    b = mjls.simulate(sys, res.controller, [1.0, 0.0], 5, 4, rng=rng).cost
    np.testing.assert_array_equal(a, b)
    sys = sec373_system(1)
    observed = mjls.mode_observed_lqg(sys, 5, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0)
    runs = mjls.simulate(
        sys, observed, SEC373_MEAN0[1], 5, 3, np.random.default_rng(0), x0_cov=SEC373_COV0
    )
    assert runs.cost.shape == (3,)


def test_errors_name_the_callers_argument(designs):
    sys, res = designs["dynamic"]
    with pytest.raises(TypeError, match=r"^A_stack: a controller's closed loop needs its system"):
        mjls.mean_square_stability(res.controller)
    second = r"^A_stack: .* comes second: mean_square_stability\(sys, controller\)"
    with pytest.raises(TypeError, match=second):
        mjls.mean_square_stability(res, sys)
    static = r"^F: expected a DynamicOutputFeedback or its gains, found a StaticGain"
    with pytest.raises(TypeError, match=static):
        mjls.augmented_closed_loop(sys, mjls.StaticGain([[0.1]]))
    with pytest.raises(TypeError, match=r"^F: .* found a time-variant DynamicOutputFeedback"):
        varying = mjls.DynamicOutputFeedback(
            np.zeros((3, 2, 2)), np.zeros((3, 2, 1)), np.zeros((3, 1, 2))
        )
        mjls.steady_state_cost(sys, varying)
    with pytest.raises(TypeError, match=r"^K, L: expected to be omitted"):
        mjls.augmented_closed_loop(sys, res, res.K, res.L)
    with pytest.raises(TypeError, match=r"^K: expected the gain"):
        mjls.augmented_closed_loop(sys, res.F)
    with pytest.raises(ValueError, match=r"^L: expected shape \(1, 1\) for the system"):
        mjls.mean_square_stability(sys, mjls.StaticGain([[0.1, 0.2]]))
    horizon = mjls.finite_horizon_dynamic_output_feedback(
        sys, 5, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0
    )
    finite = r"^A_stack: a finite-horizon design \(FiniteHorizonResult\)"
    with pytest.raises(TypeError, match=finite):
        mjls.mean_square_stability(horizon)
    with pytest.raises(TypeError, match=r"^T: expected a time-invariant controller"):
        mjls.mean_square_stability(sys, horizon)


def test_a_design_without_a_gain_has_no_certificate_and_no_controller():
    res = mjls.static_output_lmi(sec354_system(1, "C=[1 0]"))  # Thm. 3.9 infeasible (Sec. 3.5.4)
    assert not res.feasible
    assert res.stability is None and res.stabilizing is False and np.isnan(res.rho)
    with pytest.raises(ValueError, match=r"^A_stack: the design returned no gain to certify"):
        mjls.mean_square_stability(res)
    with pytest.raises(ValueError, match=r"^controller: the design returned no gain"):
        res.controller


def test_finite_horizon_designs_share_the_controller_without_a_certificate():
    sys = sec373_system(1)
    res = mjls.finite_horizon_dynamic_output_feedback(
        sys, 5, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0
    )
    assert isinstance(res, DesignResult) and not isinstance(res, CertifiedDesignResult)
    c = res.controller
    assert c.time_variant and c.stability is None and c.xhat0.tolist() == [5.0, 0.0]
    assert repr(c) == "DynamicOutputFeedback(horizon=5, nc=2, ny=1, nu=1)"
    with pytest.raises(TypeError, match="no time-invariant state-space realisation"):
        c.to_statespace()


def test_reprs_are_readable():
    assert repr(mjls.StaticGain([[1.0, 2.0]])) == "StaticGain(nu=1, ny=2)"
    assert repr(mjls.ModeDependentGain(np.zeros((3, 2, 1)))) == "ModeDependentGain(M=3, nu=2, ny=1)"
    varying = mjls.TimeVariantGain(np.zeros((4, 1, 2)))
    assert repr(varying) == "TimeVariantGain(horizon=4, nu=1, ny=2)"
    c = mjls.DynamicOutputFeedback(np.eye(2), np.ones((2, 1)), np.ones((1, 2)))
    assert repr(c) == "DynamicOutputFeedback(nc=2, ny=1, nu=1)"
    with pytest.raises(TypeError, match="^stability: expected an asoc.mjls.MeanSquareStability"):
        mjls.StaticGain([[1.0]], stability=0.5)


@pytest.mark.parametrize("design", ["static", "exact"])
def test_to_statespace_round_trips_through_python_control(designs, design):
    """python-control closes the loop of each plant mode and the returned controller (feedback
    and interconnect by signal names); its A equals the library's closed loop."""
    sys = networked_loop()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = (
            mjls.static_output_feedback(sys, max_iter=200)
            if design == "static"
            else mjls.exact_dynamic_output_feedback(sys)
        )
    controller = res.controller.to_statespace(0.1)
    assert isinstance(controller, control.StateSpace) and controller.dt == 0.1
    ours = controller_closed_loop(sys, res)[0]
    for i, plant in enumerate(sys.to_statespace(0.1)):
        loop = control.feedback(plant, controller, sign=1)
        np.testing.assert_allclose(loop.A, ours[i], rtol=0, atol=1e-14)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # no external inputs or outputs
            wired = control.interconnect([plant, controller], inplist=[], outlist=[])
        np.testing.assert_allclose(wired.A, ours[i], rtol=0, atol=1e-14)


def test_a_mode_dependent_controller_gives_one_statespace_per_mode(designs):
    sys, res = designs["observed"]
    modes = res.controller.to_statespace()
    assert isinstance(modes, list) and len(modes) == sys.M
    for i, (plant, gain) in enumerate(zip(sys.to_statespace(), modes)):
        loop = control.feedback(plant, gain, sign=1)
        np.testing.assert_allclose(loop.A, sys.A[i] + sys.B[i] @ res.L[i], rtol=0, atol=1e-14)
    with pytest.raises(ValueError, match="^dt: expected"):
        res.controller.to_statespace(-1.0)


def test_status_is_a_str_enum_equal_to_the_old_codes():
    r = IterativeResult(converged=True, status="converged", message="")
    assert r.status is Status.CONVERGED and r.status == "converged" and f"{r.status}" == "converged"
    assert json.dumps({"status": r.status}) == '{"status": "converged"}'
    assert set(STATUS_CODES) == set(Status)
    res = mjls.dynamic_output_feedback(networked_loop(), warn=False)
    assert res.status is Status.CYCLE and repr(res.status) == "'cycle'"
