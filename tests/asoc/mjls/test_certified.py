"""The certified bracket of rho (asoc.mjls.stability) on hard spectra, against dense Kronecker
eigenvalues
(the independent computation at these sizes) and closed forms."""

import numpy as np
import pytest

from asoc import config
from asoc.mjls import MJLS, ms_operator, ms_spectral_radius
from asoc.mjls.certificate import certified_upper_bound
from asoc.mjls.examples import SEC32_A, SEC32_T, SEC354_A, SEC354_T, sec32_system
from asoc.mjls.stability import Verdict, mean_square_stability


def dense_rho(A, T):
    """rho from numpy's eigenvalues of the Kronecker matrix of Cor. 3.2 (independent of the
    library's paths)."""
    return float(np.max(np.abs(np.linalg.eigvals(ms_operator(A, T)))))


def rotation(angle):
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


def assert_contains(result, rho, rtol=1e-12):
    """rho in the bracket (widened by rtol for the rounding of the reference itself), the estimate
    inside."""
    assert result.rho_lower <= rho * (1 + rtol) and rho * (1 - rtol) <= result.rho_upper, (
        result,
        rho,
    )
    assert result.rho_lower <= result.rho <= result.rho_upper


def forced(method):
    """The eigen-solver path ``method`` at small sizes: Arnoldi by moving the dense switch point to
    0."""
    return (
        config.option_context(**{"mjls.dense_max_radius": 0})
        if method == "arnoldi"
        else config.option_context()
    )


# ------------------------------------------------------------------ the thesis's examples,
# unchanged


def test_thesis_examples_keep_their_radii_and_get_narrow_brackets():
    cases = [(SEC32_A, SEC32_T)] + [(SEC354_A, SEC354_T[t]) for t in (1, 2)]
    for (A, T), printed in zip(cases, (1.4198, 1.2970, 1.3295)):
        result = mean_square_stability(A, T)
        assert result.rho == pytest.approx(dense_rho(A, T), rel=1e-12, abs=0)
        assert round(result.rho, 4) == printed  # Sec. 3.2 and Sec. 3.5.4
        assert_contains(result, dense_rho(A, T))
        assert result.verdict is Verdict.UNSTABLE and result.stabilizing is False
        assert result.rho_upper - result.rho_lower <= 1e-4 * result.rho


def test_an_mjls_is_accepted_as_the_open_loop():
    sys = sec32_system()
    assert ms_spectral_radius(sys) == ms_spectral_radius(sys.A, sys.T)
    assert mean_square_stability(sys).rho_upper == mean_square_stability(sys.A, sys.T).rho_upper
    with pytest.raises(TypeError, match="T: expected None when A_stack is an MJLS"):
        ms_spectral_radius(sys, sys.T)
    with pytest.raises(TypeError, match="T: expected a transition matrix"):
        ms_spectral_radius(sys.A)
    assert isinstance(sys, MJLS)


# ------------------------------------------------------------------ random systems, both paths


@pytest.mark.parametrize("method", ["dense", "arnoldi", "power"])
@pytest.mark.parametrize("seed", range(6))
def test_bracket_contains_the_dense_radius_and_is_narrow(method, seed):
    rng = np.random.default_rng(seed)
    M, n = 2 + seed % 3, 2 + seed % 2
    A = rng.standard_normal((M, n, n)) / np.sqrt(n)
    T = rng.random((M, M))
    T /= T.sum(axis=1, keepdims=True)
    rho = dense_rho(A, T)
    for scale in (0.5, 0.999, 1.001, 2.0):
        B = A * np.sqrt(scale / rho)
        with forced(method):
            result = mean_square_stability(B, T, method="auto" if method == "arnoldi" else method)
        assert_contains(result, scale, rtol=1e-11)
        assert result.rho_upper - result.rho_lower <= 1e-6 * scale
        assert result.stabilizing is (scale < 1)


def test_a_planted_wrong_radius_lies_outside_the_bracket():
    """The bracket is narrow enough to catch an estimate that is off by 1e-6 (e.g. a subdominant
    eigenvalue)."""
    result = mean_square_stability(SEC32_A, SEC32_T)
    wrong = result.rho * (1 - 1e-6)
    assert not result.rho_lower <= wrong <= result.rho_upper


def test_upper_bound_at_a_lyapunov_solution_is_the_lyapunov_test():
    """Y = L(Y) + I is positive definite with a Collatz-Wielandt bound below 1 iff stable (Thm.
    3.1)."""
    A, T = SEC32_A * np.sqrt(0.9 / 1.4197762513475558), SEC32_T
    n2 = 8
    Y = np.linalg.solve(
        np.eye(n2) - ms_operator(A, T), np.broadcast_to(np.eye(2), (2, 2, 2)).ravel()
    )
    assert certified_upper_bound(A, T, Y.reshape(2, 2, 2)) < 1
    assert certified_upper_bound(A, T, -Y.reshape(2, 2, 2)) == np.inf


# ------------------------------------------------------------------ adversarial spectra


@pytest.mark.parametrize("method", ["dense", "arnoldi"])
def test_repeated_dominant_eigenvalue(method):
    """Identical diagonal modes: rho = 0.81 of multiplicity 3 (the three entries of X in the e1
    block... and more)."""
    A = np.stack([np.diag([0.9, 0.9, 0.3])] * 3)
    T = np.full((3, 3), 1 / 3)
    with forced(method):
        result = mean_square_stability(A, T)
    assert_contains(result, 0.81)
    assert result.rho == pytest.approx(0.81, rel=1e-12) and result.stable


@pytest.mark.parametrize("method", ["dense", "arnoldi"])
def test_complex_dominant_eigenvalues(method):
    """Scaled rotations: A (x) A has eigenvalues 0.81 e^{i(+-a+-a)}, all of modulus 0.81; the Perron
    one is real."""
    A = np.stack([0.9 * rotation(0.7), 0.9 * rotation(2.1)])
    T = np.array([[0.3, 0.7], [0.6, 0.4]])
    with forced(method):
        result = mean_square_stability(A, T)
    assert_contains(result, 0.81)
    assert result.rho_upper - result.rho_lower <= 1e-9


@pytest.mark.parametrize("method", ["dense", "arnoldi", "power"])
@pytest.mark.parametrize("M", [2, 5])
def test_periodic_chains(method, M):
    """A cyclic T: the eigenvalues of rho times the M-th roots of unity share the modulus rho.
    Scalar modes
    a_i give rho = (prod a_i^2)^(1/M) exactly."""
    a = np.linspace(0.5, 1.3, M)
    A = np.stack([np.diag([ai, 0.3 * ai]) for ai in a])
    T = np.roll(np.eye(M), 1, axis=1)
    rho = float(np.prod(a**2) ** (1 / M))
    assert dense_rho(A, T) == pytest.approx(rho, rel=1e-12)
    with forced(method):
        result = mean_square_stability(A, T, method="auto" if method == "arnoldi" else method)
    assert_contains(result, rho, rtol=1e-10)
    assert result.rho == pytest.approx(rho, rel=1e-9)
    assert result.stabilizing is (rho < 1)


def test_nearly_reducible_chain():
    """Two modes that almost never switch: rho is near max(a_i^2), and the bracket still holds
    it."""
    eps = 1e-9
    T = np.array([[1 - eps, eps], [eps, 1 - eps]])
    A = np.stack([np.array([[0.95, 0.2], [0.0, 0.4]]), np.array([[0.3, 0.0], [0.5, 0.99]])])
    rho = dense_rho(A, T)
    result = mean_square_stability(A, T)
    assert_contains(result, rho, rtol=1e-10)
    assert result.stable


def test_non_normal_modes():
    """Large off-diagonal entries (transient growth 1e2) with eigenvalues inside the unit disc."""
    A = np.stack([np.array([[0.5, 100.0], [0.0, 0.6]]), np.array([[0.6, 0.0], [0.001, 0.5]])])
    T = np.array([[0.5, 0.5], [0.5, 0.5]])
    rho = dense_rho(A, T)
    result = mean_square_stability(A, T)
    assert_contains(result, rho, rtol=1e-10)
    assert result.stabilizing is (rho < 1)


def test_augmented_closed_loop_of_a_dynamic_controller():
    """The augmented closed loop (3.39) is just an (A~, T) pair: its bracket holds the dense radius,
    and the
    verdict follows it, for a stabilising and a destabilising controller."""
    from asoc.mjls import augmented_closed_loop
    from asoc.mjls.examples import sec373_system

    sys = sec373_system(1)
    F, K = 0.5 * np.eye(2), np.array([[0.1], [0.2]])
    for L, stable in ((np.array([[-0.3, -0.2]]), False), (np.zeros((1, 2)), False)):
        At = augmented_closed_loop(sys, F, K, L)[0]
        result = mean_square_stability(At, sys.T)
        assert_contains(result, dense_rho(At, sys.T), rtol=1e-10)
        assert result.stabilizing is (dense_rho(At, sys.T) < 1) and result.stable is stable
    scaled = 0.5 * augmented_closed_loop(sys, F, K, np.zeros((1, 2)))[0]
    result = mean_square_stability(scaled, sys.T)
    assert_contains(result, dense_rho(scaled, sys.T), rtol=1e-10)
    assert result.stabilizing is True


def _alg32_closed_loop_n32_m8():
    """Alg. 3.2's final closed loop on the scaling family at n = 32, M = 8 (64 augmented states):
    its Perron
    stack is singular, so the Collatz-Wielandt bounds at it (or at it shifted by I) stay wide."""
    from asoc.mjls import augmented_closed_loop, dynamic_output_feedback
    from asoc_companion.scaling import scaling_system

    s = scaling_system(np.random.default_rng(1), 32, 8)
    r = dynamic_output_feedback(s, warn=False)
    return augmented_closed_loop(s, r.F, r.K, r.L)[0], s.T


def test_singular_perron_stack_gets_a_narrow_bracket_from_the_deflated_resolvent(monkeypatch):
    """The bracket is narrower than the warning width (1e-4 relative) and holds ARPACK's own
    estimate; with the
    deflated resolvent candidates removed (the planted regression) it is wider than that (8.8e-4
    measured)."""
    import scipy.sparse.linalg

    from asoc.mjls import certificate
    from asoc.mjls.moment_operator import linear_operator

    A, T = _alg32_closed_loop_n32_m8()
    result = mean_square_stability(A, T)
    width = config.defaults["mjls.bracket_warn_rtol"]
    assert result.rho_upper - result.rho_lower <= width * result.rho_upper, result.bracket
    arpack = abs(
        scipy.sparse.linalg.eigs(linear_operator(A, T, False), k=1, which="LM", ncv=60, tol=1e-14)[
            0
        ][0]
    )
    assert_contains(result, arpack, rtol=1e-10)
    monkeypatch.setattr(certificate, "deflated_resolvent_bounds", lambda *args: None)
    without = mean_square_stability(A, T)
    assert without.rho_upper - without.rho_lower > width * without.rho_upper


def test_a_start_near_the_perron_stack_is_used_and_a_poor_one_only_costs_time():
    """A closed loop with a large spectral gap, on the Arnoldi path: from its stationary second
    moments (mostly the Perron stack) the power method gives the estimate, in a narrow bracket
    around the dense radius; from a start that does not converge within the steps (a periodic
    chain, where |lambda_2| = rho) ARPACK gives it, and a start of the wrong shape is named."""
    rng = np.random.default_rng(8)
    M, n = 4, 5
    A = 0.1 * rng.standard_normal((M, n, n)) / np.sqrt(n)
    A[:, 0, 0] += 1.0                                   # one dominant direction in every mode
    T = np.tile(rng.dirichlet(np.ones(M)), (M, 1))      # i.i.d. modes: |lambda_2| / rho about 0.1
    A *= np.sqrt(0.95 / dense_rho(A, T))
    X = np.broadcast_to(np.eye(n), (M, n, n))
    for _ in range(400):                     # the stationary moments X = L(X) + I, by iteration
        X = np.einsum("ij,iab,icb->jac", T, A @ X, A) + np.eye(n)
    with forced("arnoldi"):
        warm = mean_square_stability(A, T, start=X)
        cold = mean_square_stability(A, T)
        with pytest.raises(ValueError, match="start"):
            mean_square_stability(A, T, start=X[:2])
        cycle = np.roll(np.eye(M), 1, axis=1)
        periodic = mean_square_stability(A, cycle, start=np.broadcast_to(np.eye(n), (M, n, n)))
    assert warm.method == "power" and cold.method == "arnoldi"
    for result in (warm, cold):
        assert_contains(result, 0.95)
    width = [result.rho_upper - result.rho_lower for result in (warm, cold)]
    assert width[0] <= 1e-6 and width[0] <= 10 * width[1], width
    assert periodic.method != "power"
    assert_contains(periodic, dense_rho(A, cycle))
