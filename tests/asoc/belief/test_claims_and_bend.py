"""Statistical decision of the Secs. 2.5/2.6 claims, damped Alg. 2.2, covariance-aware planner."""

import numpy as np
import pytest

from asoc.belief import UKF, landmark_example
from asoc.belief.damped import optimize_damped
from asoc.belief.planning import (
    belief_cost,
    bend_toward_landmark,
    covariance_aware_optimum,
    ekf_belief_plan,
)
from asoc.stats import decide_claim

# -- decide_claim: a planted false variant must not pass


def test_zero_mean_difference_is_not_resolved():
    rng = np.random.default_rng(1)
    verdicts = [decide_claim(rng.standard_normal(40), below=0.0)["verdict"] for _ in range(400)]
    # a zero-median difference "holds" only by chance: about 2.5 % of draws at the 95 % level
    # (allowing for the small-n anti-conservatism of the percentile interval); mostly not resolved
    assert verdicts.count("holds") / len(verdicts) <= 0.06
    assert verdicts.count("not resolved") / len(verdicts) >= 0.88
    # the exact interval of the median of a symmetric sample around 0 straddles 0
    assert decide_claim(np.linspace(-1, 1, 41), below=0.0)["verdict"] == "not resolved"


def test_clearly_positive_difference_holds_and_its_reversal_fails():
    rng = np.random.default_rng(2)
    gain = 1.0 + 0.2 * rng.standard_normal(30)
    assert decide_claim(gain, above=0.0)["verdict"] == "holds"
    assert decide_claim(-gain, above=0.0)["verdict"] == "fails"  # planted: the reversed ordering


def test_record_has_the_ledger_fields():
    d = decide_claim(np.arange(1.0, 31.0), above=9.5, below=30.5, what="iterations")
    assert set(d) == {
        "verdict",
        "n",
        "estimate",
        "ci_low",
        "ci_high",
        "test",
        "above",
        "below",
        "level",
        "samples",
    }
    assert d["n"] == 30 and d["ci_low"] <= d["estimate"] <= d["ci_high"]
    assert d["verdict"] == "holds" and "iterations" in d["test"] and "are equal" not in d["test"]
    # the record repeats its own decision
    again = decide_claim(d["samples"], above=d["above"], below=d["below"], level=d["level"])
    assert again["verdict"] == d["verdict"] and again["ci_low"] == d["ci_low"]


def test_equal_samples_are_called_exact_not_statistical():
    d = decide_claim(np.full(1000, -0.003), below=0.0)
    assert d["verdict"] == "holds" and "all 1000 samples are equal" in d["test"]


def test_interval_claim_straddling_a_bound_is_not_resolved():
    assert (
        decide_claim(np.linspace(1.5, 2.5, 31), above=1.0, below=2.0)["verdict"] == "not resolved"
    )


@pytest.mark.parametrize(
    "kwargs, message",
    [({}, "at least one bound"), ({"above": 1.0, "below": 0.0}, "above must be smaller")],
)
def test_decide_claim_rejects_bad_bounds(kwargs, message):
    with pytest.raises(ValueError, match=message):
        decide_claim([1.0, 2.0], **kwargs)


# -- bend and planner


def test_bend_is_signed_toward_the_landmark():
    line = ([-5.0, 3.0], [0.0, 3.0], [-3.0, 0.0])
    assert bend_toward_landmark([[-5, 3], [-2, 2.5], [0, 3]], *line) == pytest.approx(0.5)
    assert bend_toward_landmark([[-5, 3], [-2, 3.5], [0, 3]], *line) == pytest.approx(0.0)
    with pytest.raises(ValueError, match="landmark"):
        bend_toward_landmark([[0, 0]], [0, 0], [1, 0], [2, 0])


def test_ekf_plan_matches_a_hand_computed_update():
    ex = landmark_example(K=1)
    means, covs = ekf_belief_plan(np.array([[1.0, -2.0]]), ex)
    P = ex.cov0 + 0.25 * np.eye(2)
    mean = ex.mean0 + np.array([1.0, -2.0])
    h = (mean - ex.landmark) / np.linalg.norm(mean - ex.landmark)
    expected = P - np.outer(P @ h, P @ h) / (h @ P @ h + 0.01 * np.sum((mean - ex.landmark) ** 2))
    np.testing.assert_allclose(means[-1], mean)
    assert np.all(np.isfinite(covs))
    np.testing.assert_allclose(covs[-1], expected, rtol=1e-12)


def test_batched_cost_equals_single_costs():
    ex = landmark_example(K=3)
    u = np.random.default_rng(0).standard_normal((4, 3, 2))
    batch = belief_cost(u, ex)
    np.testing.assert_allclose(batch, [belief_cost(ui, ex) for ui in u], rtol=1e-12)
    # the covariance terms only add: dropping them lowers every cost
    assert np.all(belief_cost(u, ex, covariance=False) < batch)


def test_covariance_aware_optimum_beats_the_straight_plan_and_bends():
    res = covariance_aware_optimum(landmark_example())
    assert res["cost"] < 0.9 * res["cost_straight"]  # the model rewards leaving the line
    assert res["bend"] > 0.5 > res["bend_straight"]
    assert res["gradient_norm"] < 1e-4


# -- damped Alg. 2.2


def test_damped_iteration_is_monotone_and_keeps_a_finite_reference():
    ex = landmark_example(K=6)
    res = optimize_damped(
        ex.model,
        ex.cost,
        ex.mean0,
        ex.cov0,
        rng=np.random.default_rng(0),
        n_cost_runs=20,
        max_iterations=15,
    )
    assert np.all(np.diff(res.costs) < 0)  # accepted steps only decrease J
    assert res.passes >= res.iterations >= 1 and len(res.damping) == res.iterations
    means = [UKF.mean(e) for e in res.reference.estimates]
    assert np.isfinite(bend_toward_landmark(means, ex.mean0, ex.cost.x_target, ex.landmark))


def test_damped_rejects_bad_factor():
    ex = landmark_example(K=2)
    with pytest.raises(ValueError, match="factor"):
        optimize_damped(
            ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0), factor=1.0
        )
