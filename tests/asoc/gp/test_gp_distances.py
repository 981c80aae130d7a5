"""Correctness of the distances of Sec. 2.6.3 (asoc.gp.cramer_von_mises, transport, densities)."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.special import xlogy
from scipy.stats import norm

from asoc import gp

small = arrays(
    float,
    st.tuples(st.integers(1, 5), st.integers(1, 2)),
    elements=st.floats(-5, 5, allow_nan=False),
)


@settings(max_examples=30, deadline=None)
@given(small)
def test_mcvmd_of_mixture_with_itself_is_zero(x):
    assert gp.mcvmd(x, None, x, None) == pytest.approx(0.0, abs=1e-6)


@settings(max_examples=30, deadline=None)
@given(small, st.data())
def test_mcvmd_symmetric_and_order_invariant(x, data):
    y = data.draw(
        arrays(
            float,
            (data.draw(st.integers(1, 5)), x.shape[1]),
            elements=st.floats(-5, 5, allow_nan=False),
        )
    )
    perm = data.draw(st.permutations(range(len(x))))
    d = gp.mcvmd(x, None, y, None)
    # d^2 is a difference of sums of magnitude S; it is exact up to rounding, 64 eps S (d itself,
    # a square root, is not: near d = 0 its rounding error is of order sqrt(eps S))
    allowed = 64 * np.finfo(float).eps * mcvmd_term_magnitude(x, y)
    assert abs(d**2 - gp.mcvmd(y, None, x, None) ** 2) <= allowed
    assert abs(d**2 - gp.mcvmd(x[list(perm)], None, y, None) ** 2) <= allowed


def mcvmd_term_magnitude(x, y, b_max=gp.cramer_von_mises.DEFAULT_B_MAX):
    """pi^(d/2) / 8 (|D1| + 2 |D12| + |D2| + 2 c_b Dm) with absolute values inside the sums (equal
    weights)."""

    def term(a, b):  # |a - b|^2 log |a - b|^2, with 0 log 0 = 0
        sq = np.sum((a[:, None] - b[None]) ** 2, axis=-1)
        return np.abs(xlogy(sq, sq)).mean()

    Dm = float(np.sum((x.mean(axis=0) - y.mean(axis=0)) ** 2))
    total = term(x, x) + 2 * term(x, y) + term(y, y) + 2 * abs(gp.mcvmd_constant(b_max)) * Dm
    return np.pi ** (x.shape[1] / 2) / 8 * total


@pytest.mark.parametrize("b_max", [50.0, 200.0])
def test_mcvmd_closed_form_matches_quadrature_of_definition(b_max):
    rng = np.random.default_rng(3)
    x, y = rng.normal(size=3), rng.normal(size=4) + 0.4
    wx = np.array([0.2, 0.5, 0.3])
    quad = gp.mcvmd_quadrature(
        lambda m, b: gp.lcd_dirac(x, wx, m, b),
        lambda m, b: gp.lcd_dirac(y, None, m, b),
        b_max=b_max,
        spread=4,
        points=np.r_[x, y],
    )
    # the closed form drops O(1 / b_max^2) terms
    assert gp.mcvmd(x, wx, y, None, b_max=b_max) == pytest.approx(
        quad, rel=5e-4 * (50 / b_max) ** 2
    )


def test_mcvmd_matrix_matches_pairwise_calls():
    rng = np.random.default_rng(0)
    X, Y = rng.normal(size=(4, 3, 2)), rng.normal(size=(5, 3, 2))
    D = gp.mcvmd_matrix(X, Y)
    ref = [[gp.mcvmd(a, None, b, None) for b in Y] for a in X]
    np.testing.assert_allclose(D, ref, rtol=1e-10, atol=1e-12)
    S = gp.mcvmd_matrix(X)
    np.testing.assert_allclose(S, S.T)
    assert np.all(np.diag(S) == 0)
    # one computation of the sums, one matrix per b_max
    several = gp.mcvmd_matrix(X, Y, b_max=[10.0, 1000.0])
    assert several.shape == (2, 4, 5)
    for D_b, b_max in zip(several, (10.0, 1000.0)):
        np.testing.assert_allclose(
            D_b, [[gp.mcvmd(a, None, b, None, b_max) for b in Y] for a in X], rtol=1e-10
        )
    with pytest.raises(ValueError, match="^b_max: expected"):
        gp.mcvmd_matrix(X, b_max=[10.0, -1.0])


def test_lcd_gaussian_matches_quadrature_of_definition():
    m, b = np.array([[0.3]]), 0.7
    from scipy.integrate import quad

    ref = quad(lambda x: norm.pdf(x, 0.5, 1.3) * np.exp(-0.5 * (x - 0.3) ** 2 / b**2), -20, 20)[0]
    assert gp.lcd_gaussian(0.5, 1.3**2, m, b)[0] == pytest.approx(ref, rel=1e-9)


def test_omat_equals_brute_force_over_permutations():
    rng = np.random.default_rng(1)
    for q in (1, 2, 3):
        x, y = rng.normal(size=(5, 2)), rng.normal(size=(5, 2))
        brute = min(
            np.mean(np.linalg.norm(x - y[list(p)], axis=1) ** q)
            for p in itertools.permutations(range(5))
        ) ** (1 / q)
        assert gp.omat(x, y, q) == pytest.approx(brute, rel=1e-12)


def test_omat_matrix_matches_pairwise_calls():
    rng = np.random.default_rng(2)
    X, Y = rng.normal(size=(3, 4, 1)), rng.normal(size=(2, 4, 1))
    np.testing.assert_allclose(gp.omat_matrix(X, Y), [[gp.omat(a, b) for b in Y] for a in X])
    S = gp.omat_matrix(X)
    np.testing.assert_allclose(S, [[gp.omat(a, b) for b in X] for a in X], atol=1e-12)


def test_ospa_reduces_to_omat_and_penalises_cardinality():
    rng = np.random.default_rng(4)
    x, y = rng.normal(size=(4, 2)), rng.normal(size=(4, 2))
    assert gp.ospa(x, y, c=1e6) == pytest.approx(gp.omat(x, y))
    assert gp.ospa(x, x[:2], c=3.0, p=2) == pytest.approx(np.sqrt(2 * 9 / 4))


def test_wasserstein_gaussian_agrees_with_omat_of_large_deterministic_samples():
    m1, v1, m2, v2 = 0.5, 0.8, -1.0, 2.5
    u = norm.ppf((np.arange(2000) + 0.5) / 2000)  # large equally weighted sample of N(0, 1)
    u = u / np.sqrt(np.mean(u**2))
    w_omat = gp.omat(m1 + np.sqrt(v1) * u, m2 + np.sqrt(v2) * u)
    assert gp.wasserstein_gaussian(m1, v1, m2, v2) == pytest.approx(w_omat, rel=1e-6)


def test_wasserstein_gaussian_commuting_case():
    C1, C2 = np.diag([1.0, 4.0]), np.diag([9.0, 1.0])
    expected = np.sqrt(1 + (1 - 3) ** 2 + (2 - 1) ** 2)
    assert gp.wasserstein_gaussian([0, 0], C1, [1, 0], C2) == pytest.approx(expected)


def test_density_distances_against_closed_forms():
    p1, p2 = norm(0, 1).pdf, norm(1, 1.5).pdf
    assert gp.hellinger(p1, p2) == pytest.approx(gp.hellinger_gaussian(0, 1, 1, 1.5**2), rel=1e-7)
    assert gp.hellinger(p1, p1) == pytest.approx(0, abs=1e-6)
    assert 0 < gp.jensen_shannon(p1, p2) < np.log(2)
    assert gp.jensen_shannon(p1, p1) == pytest.approx(0, abs=1e-10)
    # L2 distance between two Gaussians: closed form via Gaussian product integrals
    l2sq = (
        1 / (2 * np.sqrt(np.pi))
        + 1 / (2 * np.sqrt(np.pi) * 1.5)
        - 2 * norm(0, np.sqrt(1 + 1.5**2)).pdf(1)
    )
    assert gp.lq_distance(p1, p2, 2) == pytest.approx(np.sqrt(l2sq), rel=1e-7)


def test_lcd_dirac_approximation_of_standard_normal():
    a = gp.standard_normal_dirac_approximation(10)
    # converged by the gradient norm against sqrt(eps S), never BFGS's status (which flips with the
    # BLAS kernel)
    assert a.converged and a.status == "converged"
    assert a.gradient_norm <= gp.sampling.gradient_tolerance(a.b_max)
    np.testing.assert_allclose(a.x, -a.x[::-1], atol=1e-6)  # symmetric
    # the approximation is better than the midpoint-quantile start
    start = norm.ppf((2 * np.arange(1, 11) - 1) / 20)
    assert a.distance < gp.mcvmd_standard_normal_dirac(start)
    # the semi-analytic distance agrees with quadrature of the LCD definition
    quad = gp.mcvmd_quadrature(
        lambda m, b: gp.lcd_gaussian(0, 1, m, b),
        lambda m, b: gp.lcd_dirac(a.x, None, m, b),
        b_max=10,
        spread=9,
        points=a.x,
    )
    assert gp.mcvmd_standard_normal_dirac(a.x, b_max=10) == pytest.approx(quad, rel=1e-8)
    X = gp.gaussian_dirac_mixtures([1.0, -2.0], [4.0, 0.25], 10)
    np.testing.assert_allclose(X[:, :, 0], [1 + 2 * a.x, -2 + 0.5 * a.x])


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: gp.mcvmd([0.0, 1.0], [0.7, -0.7 + 1], [0.0], None), None),
        (lambda: gp.mcvmd([0.0, 1.0], [-0.5, 1.5], [0.0], None), "wx"),
        (lambda: gp.mcvmd([0.0, 1.0], [0.5, 0.6], [0.0], None), "wx"),
        (lambda: gp.mcvmd(np.zeros((2, 2)), None, np.zeros((2, 3)), None), "x, y"),
        (lambda: gp.mcvmd(np.zeros((0, 1)), None, [0.0], None), "x"),
        (lambda: gp.omat(np.zeros((2, 1)), np.zeros((3, 1))), "x, y"),
        (lambda: gp.wasserstein_gaussian(0, [[1.0, 2.0], [2.0, 1.0]], 0, np.eye(2)), "C1"),
        (lambda: gp.mcvmd([0.0], None, [1.0], None, b_max=-1), "b_max"),
        (lambda: gp.omat_matrix(np.zeros((2, 3, 1)), np.zeros((2, 3, 2))), "X, Y"),
    ],
)
def test_bad_input_raises_value_error_naming_the_argument(call, name):
    if name is None:  # valid weights: no error
        call()
        return
    with pytest.raises(ValueError, match=name):
        call()


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: gp.mcvmd([0.0, 1.0], [0.5, float("nan")], [0.0], None), "wx"),
        (lambda: gp.mcvmd_matrix(np.zeros((2, 2, 1)), WX=[[0.5, 0.5], [float("nan"), 1.0]]), "WX"),
        (lambda: gp.lcd_dirac([0.0], [float("nan")], [[0.0]], 1.0), "wx"),
        (lambda: gp.lcd_dirac([0.0], None, [[0.0]], 0.0), "b"),
        (
            lambda: gp.mean_kernel_dirac(
                np.zeros((2, 2, 1)), WX=[[1.0, 0.0], [0.5, float("nan")]], alpha=1.0, Lambda=1.0
            ),
            "WX",
        ),
        (lambda: gp.mcvmd([complex(0, 1)], None, [0.0], None), "x"),
        (lambda: gp.standard_normal_dirac_approximation(float("nan")), "L"),
        (lambda: gp.standard_normal_dirac_approximation(2.5), "L"),
        (lambda: gp.standard_normal_dirac_approximation("10"), "L"),
        # (nodes x L x L) arrays: named, no MemoryError
        (lambda: gp.gaussian_dirac_mixtures([0.0], [1.0], L=10**6), "L"),
        (lambda: gp.DistributionGP(n_restarts=float("inf")), "n_restarts"),
        (lambda: gp.DistributionGP(n_restarts=True), "n_restarts"),
        (lambda: gp.training_gaussians(2.5, np.random.default_rng(0)), "n"),
        (lambda: gp.error_metrics([1.0, 2.0], [1.0, 1.0]), "truth"),
    ],
)
def test_nan_weights_and_bad_counts_are_named(call, name):
    with pytest.raises((ValueError, TypeError), match=f"^{name}: expected"):
        call()


def test_omat_matrix_rows_equal_the_pairwise_assignment_means():
    from scipy.optimize import linear_sum_assignment

    X, Y = np.random.default_rng(5).normal(size=(2, 12, 7, 2))
    D = gp.omat_matrix(X, Y, q=3)
    for i, j in itertools.product(range(len(X)), range(len(Y))):
        cost = np.sum((X[i][:, None] - Y[j][None]) ** 2, axis=-1) ** 1.5
        rows, cols = linear_sum_assignment(cost)
        assert D[i, j] == pytest.approx(cost[rows, cols].mean() ** (1 / 3), rel=1e-12)


@pytest.mark.parametrize("q", [1.5, 2, 3])
def test_omat_matrix_of_scalar_locations_sorts_as_the_assignments_do(q):
    """d = 1, q > 1: the monotone matching gives the linear assignments' means (distinct, unsorted
    locations)."""
    rng = np.random.default_rng(int(10 * q))
    X, Y = rng.normal(size=(9, 7, 1)), rng.normal(size=(11, 7, 1)) * 2
    pairwise = np.array([[gp.omat(x, y, q=q) for y in Y] for x in X])
    np.testing.assert_allclose(gp.omat_matrix(X, Y, q=q), pairwise, rtol=1e-12)
    within = np.array([[gp.omat(x, y, q=q) for y in X] for x in X])
    np.testing.assert_allclose(gp.omat_matrix(X, q=q), within, rtol=1e-12, atol=1e-15)


def test_gaussian_distance_matrices_equal_the_pairwise_distances():
    rng = np.random.default_rng(6)
    means, roots = rng.normal(size=(5, 2)), rng.normal(size=(5, 2, 2))
    covs = roots @ roots.transpose(0, 2, 1) + 0.1 * np.eye(2)
    for matrix, pairwise in (
        (gp.wasserstein_gaussian_matrix, gp.wasserstein_gaussian),
        (gp.hellinger_gaussian_matrix, gp.hellinger_gaussian),
    ):
        expected = np.array(
            [
                [pairwise(m1, C1, m2, C2) for m2, C2 in zip(means[:3], covs[:3])]
                for m1, C1 in zip(means, covs)
            ]
        )
        # atol: a distance 0 comes out as the square root of rounding, ~3e-8
        np.testing.assert_allclose(
            matrix(means, covs, means[:3], covs[:3]), expected, rtol=1e-10, atol=1e-7
        )
        D = matrix(means, covs)
        assert np.all(np.diag(D) == 0) and np.array_equal(D, D.T)
        # sqrt of rounding at d = 0
        np.testing.assert_allclose(D[:, :3], expected, rtol=1e-10, atol=1e-7)
    # 1-D: (N,) means and variances
    one_d = gp.hellinger_gaussian_matrix([0.0, 1.0], [1.0, 4.0])
    assert one_d[0, 1] == pytest.approx(
        gp.hellinger_gaussian([0.0], [[1.0]], [1.0], [[4.0]]), rel=1e-12
    )
    with pytest.raises(ValueError, match="^covs_i: expected"):
        gp.hellinger_gaussian_matrix(means, -covs)


def test_ospa_matrix_equals_the_pairwise_ospa():
    rng = np.random.default_rng(7)
    sets = [rng.normal(size=(k, 2)) for k in (1, 3, 2, 3)]
    D = gp.ospa_matrix(sets, c=1.5, p=2)
    expected = np.array(
        [
            [0.0 if i == j else gp.ospa(x, y, c=1.5) for j, y in enumerate(sets)]
            for i, x in enumerate(sets)
        ]
    )
    np.testing.assert_allclose(D, expected, rtol=1e-12)
    np.testing.assert_allclose(
        gp.ospa_matrix(sets, sets[:2], c=1.5), expected[:, :2], rtol=1e-12, atol=1e-15
    )
    with pytest.raises(
        ValueError, match="X\\[0\\], X\\[1\\]: expected mixtures of the same dimension"
    ):
        gp.ospa_matrix([np.zeros((1, 2)), np.zeros((2, 3))])


def test_piecewise_constant_matrices_equal_the_quadrature_of_their_densities():
    rng = np.random.default_rng(8)
    edges = np.array([0.0, 0.2, 0.5, 0.6, 1.0])
    heights = rng.dirichlet(np.ones(4), size=3) / np.diff(edges)  # densities: integral one
    heights[0, 2] = 0.0
    heights[0] /= heights[0] @ np.diff(edges)

    def density(h):
        return lambda x: (
            float(h[min(np.searchsorted(edges, x, side="right") - 1, 3)]) if 0 <= x <= 1 else 0.0
        )

    for q in (1, 2, 3):
        D = gp.lq_distance_matrix(heights, edges, q=q)
        assert D[0, 1] == pytest.approx(
            gp.lq_distance(density(heights[0]), density(heights[1]), q, 0.0, 1.0), rel=1e-8
        )
    for matrix, quadrature in (
        (gp.hellinger_matrix, gp.hellinger),
        (gp.jensen_shannon_matrix, gp.jensen_shannon),
    ):
        D = matrix(heights, edges)
        assert np.all(np.diag(D) == 0) and D[0, 2] == pytest.approx(
            quadrature(density(heights[0]), density(heights[2]), 0.0, 1.0), rel=1e-8
        )
        np.testing.assert_allclose(
            matrix(heights, edges, heights[:1]), D[:, :1], rtol=1e-12, atol=1e-15
        )
    with pytest.raises(ValueError, match="^edges: expected at least two increasing"):
        gp.lq_distance_matrix(heights, edges[::-1])
    with pytest.raises(ValueError, match="^heights: expected non-empty non-negative"):
        gp.jensen_shannon_matrix(-heights, edges)
