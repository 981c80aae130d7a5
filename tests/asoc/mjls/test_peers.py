"""Beside python-control and QuantEcon (issue 33, item 6).

With one mode an MJLS is an ordinary linear system, and the library's designs must give what
python-control gives: the observed-mode Riccati iteration [38] its ``dlqr`` (P and the gain), the
coupled Lyapunov solve its ``dlyap``, and Alg. 3.2 the LQG compensator built from ``dlqr`` and
``dlqe`` (compared by its Markov parameters L F^k K, which do not depend on the compensator's
coordinates, and by the closed loop's cost from python-control's ``dlyap``).

QuantEcon's ``LQMarkov`` (mode observed) was run once (tests/reference/quantecon_lqmarkov.json,
with its version; it is not a dependency). Its P differs from the coupled Riccati equations of
[38]: its ``solve_discrete_riccati_system`` averages Pi_ij A'P_j B (Q + B'P_j B)^{-1} B'P_j A over
j, the expectation outside the inverse. The tests show that the library's P solves the coupled
equations (a direct root solve agrees), that QuantEcon's recorded P is the fixed point of the
expectation-outside recursion, and that it is not the value of QuantEcon's own policy (whose cost,
evaluated exactly by a coupled Lyapunov solve, is above the library's on every recorded system).
"""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

from asoc.mjls import MJLS, dynamic_output_feedback, observed_mode_state_feedback
from asoc.mjls.lyapunov import solve_coupled_lyapunov

control = pytest.importorskip("control")

QUANTECON = Path(__file__).resolve().parents[2] / "reference" / "quantecon_lqmarkov.json"


def one_mode_plant():
    """An open-loop unstable 3-state plant with two inputs, two noisy outputs and process noise."""
    rng = np.random.default_rng(3)
    A = rng.standard_normal((3, 3)) / 1.5
    B, C = rng.standard_normal((3, 2)), rng.standard_normal((2, 3))
    H, J = 0.3 * rng.standard_normal((3, 3)), 0.2 * np.eye(2)
    return dict(A=A, B=B, C=C, H=H, J=J, Q=np.eye(3), R=0.5 * np.eye(2))


def test_observed_mode_feedback_is_dlqr_with_one_mode():
    p = one_mode_plant()
    assert max(abs(np.linalg.eigvals(p["A"]))) > 1
    ours = observed_mode_state_feedback(MJLS(T=[[1.0]], **p))
    K, S, _ = control.dlqr(p["A"], p["B"], p["Q"], p["R"])
    np.testing.assert_allclose(ours.P[0], S, rtol=1e-11, atol=1e-11 * np.abs(S).max())
    np.testing.assert_allclose(ours.L[0], -K, rtol=1e-11, atol=1e-11 * np.abs(K).max())


def test_coupled_lyapunov_is_dlyap_with_one_mode():
    p = one_mode_plant()
    A = p["A"] / (1.1 * max(abs(np.linalg.eigvals(p["A"]))))
    W = p["H"] @ p["H"].T
    X = control.dlyap(A, W)
    for adjoint, peer in ((False, X), (True, control.dlyap(A.T, p["Q"]))):
        rhs = (p["Q"] if adjoint else W)[None]
        ours = solve_coupled_lyapunov(A[None], np.array([[1.0]]), rhs, adjoint=adjoint).X[0]
        np.testing.assert_allclose(ours, peer, rtol=1e-12, atol=1e-12 * np.abs(peer).max())


def test_alg32_is_the_lqg_compensator_with_one_mode():
    p = one_mode_plant()
    A, B, C = p["A"], p["B"], p["C"]
    ours = dynamic_output_feedback(MJLS(T=[[1.0]], **p))
    K_lq, _, _ = control.dlqr(A, B, p["Q"], p["R"])
    K_kf, _, _ = control.dlqe(A, p["H"], C, np.eye(3), p["J"] @ p["J"].T)  # predictor form
    F, K, L = A - B @ K_lq - K_kf @ C, K_kf, -K_lq
    assert ours.converged
    for k in range(6):
        peer = L @ np.linalg.matrix_power(F, k) @ K
        mine = ours.L @ np.linalg.matrix_power(ours.F, k) @ ours.K
        np.testing.assert_allclose(mine, peer, rtol=0, atol=1e-10 * np.abs(peer).max())
    # the closed loop's average cost from python-control's dlyap
    A_cl = np.block([[A, B @ L], [K @ C, F]])
    noise = np.block([[p["H"], np.zeros((3, 2))], [np.zeros((3, 3)), K @ p["J"]]])
    X = control.dlyap(A_cl, noise @ noise.T)
    cost = np.trace(
        np.block([[p["Q"], np.zeros((3, 3))], [np.zeros((3, 3)), L.T @ p["R"] @ L]]) @ X
    )
    assert ours.cost == pytest.approx(cost, rel=1e-10)


def quantecon_cases():
    record = json.loads(QUANTECON.read_text())
    return [
        {key: np.array(value) if key not in ("name",) else value for key, value in case.items()}
        for case in record["cases"]
    ]


def observed(case):
    n = case["A"].shape[1]
    return MJLS(
        A=case["A"],
        B=case["B"],
        C=np.eye(n),
        H=np.zeros((n, 1)),
        Q=case["Q"],
        R=case["R"],
        T=case["Pi"],
    )


def coupled_riccati_residual(case, P):
    """X_i - (A_i' E_i A_i + Q_i - A_i' E_i B_i (R_i + B_i' E_i B_i)^{-1} B_i' E_i A_i), [38]."""
    A, B, Q, R, Pi = (case[k] for k in ("A", "B", "Q", "R", "Pi"))
    E = np.einsum("ij,jab->iab", Pi, P)
    At, Bt = np.swapaxes(A, 1, 2), np.swapaxes(B, 1, 2)
    return P - (At @ E @ A + Q - At @ E @ B @ np.linalg.solve(R + Bt @ E @ B, Bt @ E @ A))


def expectation_outside(case, steps=20000):
    """QuantEcon's recursion: sum_j Pi_ij [A'P_j A - A'P_j B (R + B'P_j B)^{-1} B'P_j A] + Q."""
    A, B, Q, R, Pi = (case[k] for k in ("A", "B", "Q", "R", "Pi"))
    At, Bt = np.swapaxes(A, 1, 2), np.swapaxes(B, 1, 2)
    P = np.stack([np.eye(A.shape[1])] * len(A))
    for _ in range(steps):
        per_j = At[:, None] @ P[None] @ A[:, None] - At[:, None] @ P[None] @ B[
            :, None
        ] @ np.linalg.solve(
            R[:, None] + Bt[:, None] @ P[None] @ B[:, None], Bt[:, None] @ P[None] @ A[:, None]
        )
        P = Q + np.einsum("ij,ijab->iab", Pi, per_j)
    return P


def policy_value(case, F):
    """The exact cost-to-go x' P_i x of u = -F_i x: P = Q + F'RF + (A - BF)' E(P) (A - BF)."""
    A_cl = case["A"] - case["B"] @ F
    weight = case["Q"] + np.swapaxes(F, 1, 2) @ case["R"] @ F
    return solve_coupled_lyapunov(A_cl, case["Pi"], weight, adjoint=True).X


def test_scalar_reproducer_solves_the_coupled_riccati_equations():
    case = quantecon_cases()[0]
    ours = observed_mode_state_feedback(observed(case))
    np.testing.assert_allclose(ours.P.ravel(), [3.86414530, 1.17900908], rtol=0, atol=5e-9)
    direct = scipy.optimize.root(
        lambda p: coupled_riccati_residual(case, p.reshape(2, 1, 1)).ravel(), np.ones(2), tol=1e-14
    )
    assert direct.success
    np.testing.assert_allclose(ours.P.ravel(), direct.x, rtol=1e-12)


@pytest.mark.parametrize("index", range(6))
def test_quantecon_puts_the_expectation_outside_the_inverse(index):
    case = quantecon_cases()[index]
    ours = observed_mode_state_feedback(observed(case))
    assert np.abs(coupled_riccati_residual(case, ours.P)).max() < 1e-10 * np.abs(ours.P).max()
    np.testing.assert_allclose(expectation_outside(case), case["P"], rtol=1e-8)
    value = policy_value(case, case["F"])  # QuantEcon's policy, evaluated exactly
    assert np.abs(value - case["P"]).max() > 1e-3 * np.abs(value).max()  # P is not its value
    assert np.trace(value, axis1=1, axis2=2).sum() > np.trace(ours.P, axis1=1, axis2=2).sum()
