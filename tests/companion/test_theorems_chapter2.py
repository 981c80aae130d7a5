"""The Chapter 2 checks of the theorems study: they hold where they must, fail where they must, and
are deterministic and re-runnable from an instance's index."""

import json
import warnings
import zlib

import numpy as np
import pytest

from asoc_companion.theorems import Outcome, kernels
from asoc_companion.theorems import chapter2 as c2
from asoc_companion.theorems.engine import run_instance

CHEAP = ["statement_2_1", "statement_2_4", "statement_2_5", "statement_2_7"]
BY_KEY = {s.key: s for s in c2.STATEMENTS}


def rngs(n, seed=20171):
    return [np.random.default_rng(child) for child in np.random.SeedSequence(seed).spawn(n)]


def test_every_numbered_statement_of_chapter_2_has_a_row():
    # Definitions 2.2 and 2.6 and Assumption 2.3 get no row
    assert set(BY_KEY) == {
        "statement_2_1",
        "statement_2_4",
        "statement_2_5",
        "statement_2_7",
        "statement_2_6_3_kernels",
    }
    assert BY_KEY["statement_2_6_3_kernels"].expensive
    assert not any(BY_KEY[k].expensive for k in CHEAP)


@pytest.mark.parametrize("key", CHEAP)
def test_identity_holds_on_random_instances(key):
    outcomes = [BY_KEY[key].check(rng) for rng in rngs(6)]
    assert all(isinstance(o, Outcome) and o.verdict == "holds" for o in outcomes), [
        o.numbers for o in outcomes if o.verdict != "holds"
    ]


@pytest.mark.parametrize("key", CHEAP)
def test_identity_checks_are_deterministic(key):
    a, b = (BY_KEY[key].check(np.random.default_rng(7)) for _ in range(2))
    assert a == b


# The identity checks can fail: each compares against an independent computation, so a wrong
# library result (here: a deliberately broken one) is caught, as is each check's own mutant.


@pytest.mark.parametrize("key", CHEAP)
def test_identity_check_catches_its_mutant_on_every_instance(key):
    assert all(BY_KEY[key].check(rng, mutant=True).verdict == "fails" for rng in rngs(4))


def test_lemma_2_1_check_catches_a_missing_schur_complement(monkeypatch):
    def without_measurement(points, weights, u, model, w_points, v_points, beta, gamma):
        x = model.a(points[:, None, :], u, w_points[None])
        w = (weights[:, None] * beta[None]).ravel()
        x = x.reshape(-1, x.shape[-1])
        e = x - w @ x
        return (w[:, None] * e).T @ e  # C^xx only: the prediction

    monkeypatch.setattr(c2, "library_lemma_2_1", without_measurement)
    assert c2.check_lemma_2_1(np.random.default_rng(3)).verdict == "fails"


def test_theorem_2_4_check_catches_a_wrong_constant(monkeypatch):
    right = c2.library_terminal_value
    monkeypatch.setattr(
        c2, "library_terminal_value", lambda *a: (right(*a)[0] + 1e-6,) + right(*a)[1:]
    )
    assert c2.check_theorem_2_4(np.random.default_rng(3)).verdict == "fails"


def test_theorem_2_5_check_catches_a_dropped_covariance_term(monkeypatch):
    right = c2.library_theorem_2_5_backward

    def without_S(*args):
        (s, v, V, S), gains, offsets = right(*args)
        return (s, v, V, 0 * S), gains, offsets

    monkeypatch.setattr(c2, "library_theorem_2_5_backward", without_S)
    verdicts = [c2.check_theorem_2_5(rng).verdict for rng in rngs(5)]
    assert "fails" in verdicts


def test_proposition_2_7_check_catches_the_prior_variance(monkeypatch):
    right = c2.library_gp_posterior

    def prior_variance(covariance, shape, D, y, alpha, l, *rest):
        mean, var, cov = right(covariance, shape, D, y, alpha, l, *rest)
        return mean, np.full_like(var, alpha**2), cov

    monkeypatch.setattr(c2, "library_gp_posterior", prior_variance)
    assert c2.check_proposition_2_7(np.random.default_rng(3)).verdict == "fails"


def test_theorem_2_5_exact_cost_agrees_with_monte_carlo():
    """The independent forward-moment cost against a simulation of the Kalman filter loop."""
    rng = np.random.default_rng(11)
    A, B, H, C, J = c2.random_linear_gaussian(rng, 2, 1, 1)
    Q, R, Q_K = np.eye(2), np.eye(1), 2 * np.eye(2)
    x_target, mean, Sigma = np.array([1.0, -1.0]), np.array([0.5, 0.2]), 0.3 * np.eye(2)
    gains, offsets = c2.lq_tracking_policy(A, B, Q, R, Q_K, x_target, 3)
    exact = c2.expected_cost_of_affine_policy(
        A, B, H, C, J, Q, R, Q_K, x_target, gains, offsets, mean, Sigma
    )
    n = 100_000
    x = mean + rng.standard_normal((n, 2)) @ np.linalg.cholesky(Sigma).T
    x_hat, S, total = np.tile(mean, (n, 1)), Sigma, 0.0
    for L, d in zip(gains, offsets):
        u = x_hat @ L.T + d
        total = (
            total
            + np.einsum("ni,ij,nj->n", x - x_target, Q, x - x_target)
            + np.einsum("ni,ij,nj->n", u, R, u)
        )
        x = x @ A.T + u @ B.T + rng.standard_normal((n, 2)) @ H.T
        P, S_next = c2.kalman_posterior(A, H, C, J, S)
        y = x @ C.T + rng.standard_normal((n, 1)) @ J.T
        pred = x_hat @ A.T + u @ B.T
        gain = S_next @ C.T @ np.linalg.inv(J @ J.T)
        x_hat, S = pred + (y - pred @ C.T) @ gain.T, S_next
    total = total + np.einsum("ni,ij,nj->n", x - x_target, Q_K, x - x_target)
    assert abs(total.mean() - exact) < 4 * total.std() / np.sqrt(n)


# --- Sec. 2.6.3: the kernel claim ---------------------------------------------------------


def test_gaussian_kernel_over_printed_hellinger_is_not_positive_definite():
    """Hand-made: N(0, 1), N(1, 1), N(2, 1), D = (1 - BC)^2 as printed, SE with l = 0.03."""
    config = {"items": [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]], "exponent": "printed"}
    cert = kernels.gram_certificate("hellinger", config, "se", {}, 0.03)
    assert (
        cert["lambda_min"] < -0.2 and cert["rayleigh_exact"] < -0.2 < 0 < cert["tolerance"] < 1e-12
    )
    usual = kernels.gram_certificate("hellinger", {**config, "exponent": "usual"}, "se", {}, 0.03)
    assert usual["lambda_min"] > -usual["tolerance"]  # sqrt(1 - BC) is a Hilbert metric


def test_gaussian_kernel_over_wasserstein_2_of_2d_gaussians_is_not_positive_definite():
    """Hand-made (rounded from a search): four 2-D Gaussians, SE with l = 30.87."""
    items = [
        [[1.74, -3.8], [[7.34, -0.95], [-0.95, 0.18]]],
        [[-3.01, -3.38], [[0.46, -1.12], [-1.12, 4.27]]],
        [[-3.57, 0.6], [[0.14, 0.67], [0.67, 12.79]]],
        [[4.92, 2.75], [[11.29, 4.91], [4.91, 2.29]]],
    ]
    cert = kernels.gram_certificate("wasserstein_gaussian", {"items": items}, "se", {}, 30.87)
    assert cert["lambda_min"] < -1e-4 < 0 < 1e3 * cert["tolerance"] < 1e-4
    assert cert["rayleigh_exact"] < -1e-4 and cert["lambda_min_scipy_evr"] < -1e-4


def test_quadrature_distances_carry_their_error_into_the_tolerance():
    config = {
        "items": [[0.1, 0.2, 0.3, 0.4], [0.4, 0.3, 0.2, 0.1], [0.25, 0.25, 0.25, 0.25]],
        "q": 1,
    }
    cert = kernels.gram_certificate("lq", config, "se", {}, 0.5)
    D = kernels.distance_matrix("lq", config)
    # L_1 of the step densities: sum |w - w'|
    np.testing.assert_allclose(D[0, 1], 0.8, rtol=1e-8)
    assert 64 * kernels.EPS * D.max() <= cert["delta_D"] < 1e-6


@pytest.mark.parametrize(
    "family, fixed", [("mcvmd", {"N": 4, "points": 2}), ("lq", {"N": 4, "bins": 4, "q": 2})]
)
def test_search_finds_nothing_for_hilbert_metrics(family, fixed):
    """Sanity: mCvMd (an L2 norm of LCDs) and L_2 embed in a Hilbert space, so the SE kernel is
    PSD."""
    outcome = kernels.search_counterexample(np.random.default_rng(0), family, "se", {}, **fixed)
    assert outcome.verdict == "holds"
    assert outcome.numbers["lambda_min"] > -outcome.numbers["tolerance"]


def test_search_finds_a_counterexample_for_one_dimensional_hellinger_as_printed():
    outcome = kernels.search_counterexample(
        np.random.default_rng(0), "hellinger", "se", {}, N=4, exponent="printed"
    )
    assert outcome.verdict == "fails"


def test_search_catches_the_mutant_covariance_over_a_hilbert_metric():
    """exp(-(d/l)^4) is not positive definite even on the real line: the search must find it over
    mCvMd."""
    outcome = kernels.search_counterexample(
        np.random.default_rng(1), "mcvmd", kernels.MUTANT_COVARIANCE, {}, N=4, points=2
    )
    assert outcome.verdict == "fails"


def test_kernel_check_is_deterministic_and_rerunnable():
    key = "statement_2_6_3_kernels"
    # the engine's seeds
    children = np.random.SeedSequence((2017, zlib.crc32(key.encode()))).spawn(40)
    index = next(
        i
        for i, child in enumerate(children)
        if kernels.FAMILIES[int(np.random.default_rng(child).integers(len(kernels.FAMILIES)))]
        == "hellinger"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        outcome = BY_KEY[key].check(np.random.default_rng(children[index]))
    again = run_instance(key, 2017, index)
    assert outcome == again
    summary = kernels.summarise_kernels([outcome, again])
    assert summary["by_distance"][kernels.distance_label(outcome.numbers)]["instances"] == 2
    replay = kernels.replay_kernel_counterexample(outcome.numbers)
    np.testing.assert_allclose(
        replay["lambda_min"], outcome.numbers["lambda_min"], rtol=1e-9, atol=1e-15
    )
    assert json.loads(outcome.numbers["configuration"])["items"]


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="family"):
        kernels.search_counterexample(np.random.default_rng(0), "kl", "se", {})
    with pytest.raises(ValueError, match="name"):
        kernels.search_counterexample(np.random.default_rng(0), "omat", "cosine", {})
    with pytest.raises(ValueError, match="family"):
        kernels.gram_certificate("kl", {"items": []}, "se", {}, 1.0)
