"""python-control interop: MJLS.from_statespace / MJLS.to_statespace (issue 14, item 7).

Tested against python-control 0.10.x: a round trip keeps every matrix, and a continuous-time
mode, inconsistent or wrong sampling times, mismatched sizes and a nonzero feedthrough D
give a ValueError that names the argument.
"""

import numpy as np
import pytest

control = pytest.importorskip("control")

from asoc.mjls import MJLS, static_output_feedback  # noqa: E402
from asoc.mjls.examples import sec354_system  # noqa: E402

T = [[0.9, 0.1], [0.3, 0.7]]
KEYWORDS = dict(Q=np.eye(2), R=np.eye(1), H=0.1 * np.eye(2))


def _modes(dt=0.1):
    sys = sec354_system(1)
    return [control.ss(sys.A[i], sys.B[i], sys.C[i], np.zeros((1, 1)), dt) for i in range(sys.M)]


def test_round_trip_keeps_the_matrices_and_the_sampling_time():
    sys = MJLS.from_statespace(_modes(0.1), T, **KEYWORDS)
    assert sys.dt == 0.1
    back = sys.to_statespace()
    assert len(back) == 2 and all(s.dt == 0.1 for s in back)
    again = MJLS.from_statespace(back, T, **KEYWORDS)
    for name in "ABCHQRT":
        np.testing.assert_array_equal(getattr(again, name), getattr(sys, name))
    ref = sec354_system(1)
    np.testing.assert_array_equal(sys.A, ref.A)
    np.testing.assert_array_equal(sys.B, ref.B)
    np.testing.assert_array_equal(sys.C, ref.C)


def test_built_system_runs_algorithm_3_1_like_the_direct_one():
    ref = sec354_system(1)
    sys = MJLS.from_statespace(ref.to_statespace(dt=0.5), ref.T, Q=ref.Q, R=ref.R, H=ref.H)
    np.testing.assert_array_equal(static_output_feedback(sys).L, static_output_feedback(ref).L)


def test_unspecified_sampling_time_is_discrete():
    sys = MJLS.from_statespace(_modes(True), T, **KEYWORDS)
    assert sys.dt is True and all(s.dt is True for s in sys.to_statespace())
    assert MJLS.from_statespace(_modes(True), T, dt=0.2, **KEYWORDS).dt == 0.2


def test_c2d_plant_matches_the_zero_order_hold_exponential():
    from scipy.linalg import expm

    Ac, Bc, C = (
        np.array([[0.0, 1.0], [2.0, -1.0]]),
        np.array([[0.0], [1.0]]),
        np.array([[1.0, 0.0]]),
    )
    plant = control.c2d(control.ss(Ac, Bc, C, 0), 0.2, method="zoh")
    zoh = expm(np.block([[Ac, Bc], [np.zeros((1, 3))]]) * 0.2)
    sys = MJLS.from_statespace([plant, plant], T, **KEYWORDS)
    np.testing.assert_allclose(sys.A[0], zoh[:2, :2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sys.B[1], zoh[:2, 2:], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "modes, kwargs, error, match",
    [
        (
            lambda: [
                control.ss([[1.0]], [[1.0]], [[1.0]], 0),
                control.ss([[1.0]], [[1.0]], [[1.0]], 0),
            ],
            {},
            ValueError,
            r"systems\[0\]: expected a discrete-time system .*continuous-time dt = 0",
        ),
        (
            lambda: [_modes(0.1)[0], _modes(0.2)[1]],
            {},
            ValueError,
            r"systems: expected one sampling "
            r"time",
        ),
        (
            lambda: _modes(0.1),
            {"dt": 0.2},
            ValueError,
            r"dt: expected the systems' sampling time 0.1, found 0.2",
        ),
        (lambda: _modes(0.1), {"dt": -1.0}, ValueError, r"dt: expected a finite real number > 0"),
        (
            lambda: [_modes()[0], control.ss(np.eye(3), np.ones((3, 1)), np.ones((1, 3)), 0, 0.1)],
            {},
            ValueError,
            r"systems: expected equal sizes",
        ),
        (lambda: _modes()[:1], {}, ValueError, r"systems: expected 2 systems"),
        (
            lambda: [control.ss(np.eye(2), np.ones((2, 1)), np.ones((1, 2)), [[0.5]], 0.1)] * 2,
            {},
            ValueError,
            r"systems\[0\]: expected D = 0 .*no feedthrough.*0.5",
        ),
        (lambda: _modes()[0], {}, TypeError, r"systems: expected a list of 2 control.StateSpace"),
        (
            lambda: [_modes()[0], "plant"],
            {},
            TypeError,
            r"systems\[1\]: expected a control.StateSpace, found str",
        ),
        (
            lambda: [control.tf([1], [1, 0.5], 0.1)] * 2,
            {},
            TypeError,
            r"systems\[0\]: expected a "
            r"control.StateSpace",
        ),
    ],
)
def test_bad_systems_are_named(modes, kwargs, error, match):
    with pytest.raises(error, match=match):
        MJLS.from_statespace(modes(), T, **KEYWORDS, **kwargs)


def test_to_statespace_rejects_a_contradicting_sampling_time():
    sys = MJLS.from_statespace(_modes(0.1), T, **KEYWORDS)
    with pytest.raises(ValueError, match=r"dt: expected the system's sampling time 0.1, found 0.3"):
        sys.to_statespace(dt=0.3)
    with pytest.raises(ValueError, match=r"dt: expected a finite real number > 0, found 0"):
        sec354_system(1).to_statespace(dt=0)


def test_asoc_imports_without_python_control():
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['control'] = None\n"
        "import asoc.mjls\n"
        "from asoc.mjls.examples import sec354_system\n"
        "try:\n    sec354_system(1).to_statespace()\n"
        "except ImportError as e:\n    print('ImportError', e)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.startswith("ImportError python-control is needed")


def test_the_engineers_path_from_statespace_to_simulation_without_weights():
    """Issue 26: Q, R, H default to identities; every design result carries a controller that
    simulate and average_cost accept, and the Monte Carlo cost agrees with the exact one."""
    from asoc.mjls import (
        average_cost,
        dynamic_output_feedback,
        exact_dynamic_output_feedback,
        simulate,
    )

    plain = MJLS.from_statespace(_modes(0.1), T)
    assert np.array_equal(plain.Q, np.broadcast_to(np.eye(2), (2, 2, 2)))
    assert np.array_equal(plain.R, np.ones((2, 1, 1))) and np.array_equal(plain.H, plain.Q)
    designs = [
        static_output_feedback(plain, warn=False),
        dynamic_output_feedback(plain, warn=False),
        exact_dynamic_output_feedback(plain, warn=False),
    ]
    for res in designs:
        if not res.stabilizing:
            assert average_cost(plain, res) == np.inf
            continue
        assert average_cost(plain, res) == pytest.approx(res.cost, rel=1e-9)
        mc = simulate(plain, res, np.zeros(2), 200, 2000, np.random.default_rng(0))
        assert mc.average_cost.mean() == pytest.approx(res.cost, rel=0.1)
    with pytest.raises(TypeError, match="controller: expected an asoc.mjls.Controller"):
        simulate(plain, designs[0].L, np.zeros(2), 5, 5, np.random.default_rng(0))
