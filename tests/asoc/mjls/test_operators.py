"""Matrix-free second-moment operators (asoc.mjls.moment_operator, stability, lyapunov) against the
dense
Kronecker path."""

import numpy as np
import pytest

from asoc import config
from asoc.mjls import ms_operator, ms_spectral_radius, static_output_feedback
from asoc.mjls.lyapunov import (
    coupled_lyapunov_solver,
    radii_and_moments,
    radius_and_moments,
    solve_coupled_lyapunov,
)
from asoc.mjls.moment_operator import costate_map, second_moment_map, shifted_map
from asoc.mjls.stability import Verdict, mean_square_stability
from asoc.mjls.static_iterates import Recursion
from asoc_companion.scaling import scaling_system
from asoc_companion.timing import fitted_exponent


def switch_points(radius=None, solve=None):
    """The dense/iterative switch points set for a block (None: unchanged)."""
    values = {
        key: value
        for key, value in (("mjls.dense_max_radius", radius), ("mjls.dense_max_solve", solve))
        if value is not None
    }
    return config.option_context(**values)


def stack(rng, M, n):
    G = rng.standard_normal((M, n, n))
    return G @ np.swapaxes(G, 1, 2)


@pytest.mark.parametrize("n, M", [(2, 2), (3, 4), (5, 3)])
def test_maps_match_kronecker_matrix_and_are_adjoint(n, M):
    s = scaling_system(np.random.default_rng(n + 10 * M), n, M)
    rng = np.random.default_rng(1)
    X, P = stack(rng, M, n), stack(rng, M, n)
    K = ms_operator(s.A, s.T)
    np.testing.assert_allclose(
        second_moment_map(s.A, s.T, X).ravel(), K @ X.ravel(), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(
        costate_map(s.A, s.T, P).ravel(), K.T @ P.ravel(), rtol=1e-12, atol=1e-12
    )
    lhs = np.vdot(second_moment_map(s.A, s.T, X), P)
    assert lhs == pytest.approx(np.vdot(X, costate_map(s.A, s.T, P)), rel=1e-12)


@pytest.mark.parametrize("n, M, scale", [(4, 2, 1.0), (6, 4, 1.0), (6, 4, 1.9), (9, 3, 1.3)])
def test_spectral_radius_methods_agree_with_cor_3_2(n, M, scale):
    s = scaling_system(np.random.default_rng(7 * n + M), n, M)
    A = np.sqrt(scale) * s.A
    dense = float(np.max(np.abs(np.linalg.eigvals(ms_operator(A, s.T)))))
    assert mean_square_stability(A, s.T, method="dense", check=False).rho == pytest.approx(
        dense, rel=1e-12
    )
    assert mean_square_stability(A, s.T, method="arnoldi", check=False).rho == pytest.approx(
        dense, rel=1e-10
    )
    assert mean_square_stability(A, s.T, method="power", check=False).rho == pytest.approx(
        dense, rel=1e-8
    )
    assert ms_spectral_radius(A, s.T) == pytest.approx(dense, rel=1e-10)


def test_auto_switches_at_the_measured_sizes():
    assert config.defaults["mjls.dense_max_radius"] < config.defaults["mjls.dense_max_solve"]
    s = scaling_system(np.random.default_rng(3), 12, 4)  # M n^2 = 576: matrix-free
    W = stack(np.random.default_rng(4), 4, 12)
    sol = coupled_lyapunov_solver(s.A, s.T)(W)
    assert sol.method.startswith("bicgstab") and sol.residual < 1e-11
    dense = solve_coupled_lyapunov(s.A, s.T, W, method="dense")
    np.testing.assert_allclose(sol.X, dense.X, rtol=1e-9, atol=1e-9 * np.abs(dense.X).max())


@pytest.mark.parametrize("method", ["dense", "bicgstab", "gmres", "fixed_point"])
@pytest.mark.parametrize("adjoint", [False, True])
def test_coupled_lyapunov_solvers_reach_their_residual(method, adjoint):
    s = scaling_system(np.random.default_rng(5), 5, 3)
    # rho = 0.97: slow contraction
    A = s.A * np.sqrt(0.97 / mean_square_stability(s.A, s.T, check=False).rho)
    W = stack(np.random.default_rng(6), 3, 5)
    sol = solve_coupled_lyapunov(A, s.T, W, adjoint=adjoint, method=method)
    assert sol.residual < 1e-11
    apply = costate_map if adjoint else second_moment_map
    np.testing.assert_allclose(sol.X - apply(A, s.T, sol.X), W, atol=1e-9 * np.abs(W).max())
    assert np.all(np.linalg.eigvalsh(sol.X) > 0)  # stable: the solution is > 0


@pytest.mark.parametrize("adjoint", [False, True])
def test_dense_solve_is_the_kronecker_solve(adjoint):
    """The dense path (LAPACK getrf/getrs) against numpy's solve of the Kronecker system, to
    rounding."""
    s = scaling_system(np.random.default_rng(8), 3, 3)
    W = stack(np.random.default_rng(9), 3, 3)
    K = ms_operator(s.A, s.T)
    X = np.linalg.solve(np.eye(27) - (K.T if adjoint else K), W.ravel()).reshape(W.shape)
    sol = solve_coupled_lyapunov(s.A, s.T, W, adjoint=adjoint, method="dense")
    np.testing.assert_allclose(
        sol.X, 0.5 * (X + np.swapaxes(X, 1, 2)), rtol=1e-10, atol=1e-12 * np.abs(X).max()
    )
    with pytest.raises(ValueError, match="infs or NaNs"):
        solve_coupled_lyapunov(s.A, s.T, np.full_like(W, np.nan), method="dense")


@pytest.mark.parametrize("scale", [0.5, 0.99, 1.5])
@pytest.mark.parametrize("switch", [None, 0])
def test_radius_and_moments_is_the_pair_of_radius_and_solve(scale, switch):
    """One Kronecker matrix for rho and X: the same numbers as spectral_radius and
    solve_coupled_lyapunov
    (dense sizes; with the switch points at 0, through those functions' matrix-free paths)."""
    s = scaling_system(np.random.default_rng(10), 3, 2)
    A = s.A * np.sqrt(scale / mean_square_stability(s.A, s.T, check=False).rho)
    W = stack(np.random.default_rng(11), 2, 3)
    with switch_points(radius=switch, solve=switch):
        rho, X = radius_and_moments(A, s.T, W)
        assert rho == pytest.approx(mean_square_stability(A, s.T, check=False).rho, rel=1e-12)
        if scale < 1:
            np.testing.assert_allclose(
                X, solve_coupled_lyapunov(A, s.T, W).X, rtol=1e-9, atol=1e-12
            )
        else:
            assert X is None


@pytest.mark.parametrize("switch", [None, 0])
def test_radii_and_moments_is_each_loop_alone(switch):
    """The stacked fast path: each closed loop's rho and X as from the checked functions."""
    s = scaling_system(np.random.default_rng(12), 3, 3)
    loops = np.stack(
        [
            s.A * np.sqrt(scale / mean_square_stability(s.A, s.T, check=False).rho)
            for scale in (0.3, 1.2, 0.9, 2.0)
        ]
    )
    W = stack(np.random.default_rng(13), 3, 3)
    with switch_points(radius=switch, solve=switch):
        rho, X = radii_and_moments(loops, s.T, W)
        for loop, r, x in zip(loops, rho, X):
            assert r == pytest.approx(mean_square_stability(loop, s.T, check=False).rho, rel=1e-12)
            if r >= 1:
                assert x is None
            else:
                np.testing.assert_allclose(
                    x, solve_coupled_lyapunov(loop, s.T, W).X, rtol=1e-9, atol=1e-12
                )


def test_verdict_is_undecided_within_rounding_of_one():
    T = np.array([[0.3, 0.7], [0.6, 0.4]])
    A = np.stack([np.diag([0.9, 0.2]), np.diag([0.5, 1.1])])
    rho = mean_square_stability(A, T, check=False).rho
    on_boundary = A / np.sqrt(rho)  # rho = 1 up to rounding
    assert mean_square_stability(on_boundary, T).verdict is Verdict.UNDECIDED
    assert mean_square_stability(A * np.sqrt(0.99 / rho), T).verdict is Verdict.STABLE
    assert mean_square_stability(A * np.sqrt(1.01 / rho), T).verdict is Verdict.UNSTABLE
    near = mean_square_stability(A / np.sqrt(rho) * (1 - 1e-6), T)
    assert near.stable and near.margin == pytest.approx(2e-6, rel=1e-3)
    assert near.rho_lower <= near.rho <= near.rho_upper < 1


def test_fitted_exponent_recovers_a_power_law():
    assert fitted_exponent([4, 8, 16, 32], [2.0 * n**2.5 for n in (4, 8, 16, 32)]) == pytest.approx(
        2.5
    )


@pytest.mark.parametrize("case", ["stall", "subdominant"])
def test_arnoldi_radius_on_the_larger_plants_hard_closed_loops(case):
    """Two closed loops of the larger-plant page (tests/reference/arnoldi_hard_cases.json). With 20
    Krylov vectors ARPACK stalled on the first (a fourfold dominant eigenvalue; the cone power
    method then took 70 s) and returned a subdominant eigenvalue for the second; the spaces of
    mjls.arnoldi_subspaces must give rho itself, without any fallback, inside a narrow certified
    bracket."""
    import json
    from pathlib import Path

    cases = json.loads(
        (Path(__file__).parents[2] / "reference" / "arnoldi_hard_cases.json").read_text()
    )
    A, T = np.array(cases[case]["A"]), np.array(cases[case]["T"])
    result = mean_square_stability(A, T, method="arnoldi")
    # rho_dense: the largest modulus of np.linalg.eigvals(ms_operator(A, T)), stored (2048^2 is
    # slow)
    rho_dense = cases[case]["rho_dense"]
    assert result.method == "arnoldi" and result.rho == pytest.approx(rho_dense, rel=1e-10)
    assert (
        result.rho_lower <= rho_dense * (1 + 1e-12) and rho_dense * (1 - 1e-12) <= result.rho_upper
    )
    assert result.verdict is Verdict.STABLE and result.rho_upper - rho_dense <= 1e-5 * rho_dense


def test_the_maps_and_alg31_steps_on_threads_are_the_maps_and_steps_in_one_piece():
    """mjls.parallel_from = 0 runs the products in parts of the modes on threads: the same
    numbers, to rounding (each part's products are the same products; the operator's input is
    symmetrised mode by mode in the parts, its result formed in one pass)."""
    s = scaling_system(np.random.default_rng(11), 6, 5)
    X, P = stack(np.random.default_rng(12), 5, 6), stack(np.random.default_rng(13), 5, 6)
    raw = np.random.default_rng(15).standard_normal(5 * 6 * 6)      # not symmetric
    L = 0.1 * np.random.default_rng(14).standard_normal((s.nu, s.ny))
    results = {}
    for parallel_from in (10**9, 0):
        with config.option_context(**{"mjls.parallel_from": parallel_from}):
            rec = Recursion(s)
            out = np.empty((2, 5, 6, 6))
            rec.moments(L, X, rec.successor_average(P), 0.5, 2.0, out)
            results[parallel_from] = (second_moment_map(s.A, s.T, X), costate_map(s.A, s.T, P),
                                      out, static_output_feedback(s, warn=False).L,
                                      *(shifted_map(s.A, s.T, raw, adjoint, shift, identity)
                                        for adjoint in (False, True)
                                        for shift, identity in ((0.0, 1.0), (0.0, 0.7), (0.3, 0.0),
                                                                (0.0, 0.0))))
        assert rec.parallel is (parallel_from == 0)
    for one_piece, on_threads in zip(results[10**9], results[0]):
        np.testing.assert_allclose(on_threads, one_piece, rtol=1e-13, atol=1e-13)


def test_alg31_auto_hands_over_when_the_moments_contract_slowly():
    """A closed loop at rho = 0.99 (the open loop scaled; M n^2 = 576, solved matrix-free): the
    moments contract by 0.99 a step, and "auto" hands over to the exact iteration at its first
    check, after 11 steps, to the fixed point of the thesis's iteration."""
    s = scaling_system(np.random.default_rng(3), 12, 4)
    s = s.replace(A=s.A * np.sqrt(0.99 / mean_square_stability(s).rho))
    auto = static_output_feedback(s, warn=False)
    exact = static_output_feedback(s, warn=False, moments="exact")
    assert auto.converged and exact.converged
    assert auto.iterations - 11 <= exact.iterations < 20
    np.testing.assert_allclose(auto.L, exact.L, rtol=1e-8, atol=1e-10)
