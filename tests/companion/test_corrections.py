"""The diagnoses and corrected statements of the failing theorems (issue 23, items 3-4).

Each corrected statement must hold on seeded random instances and its mutant must fail on
some; the closed-form counterexamples are checked exactly (fractions) or to rounding.
"""

import re
from fractions import Fraction

import numpy as np
import pytest

from asoc.mjls import MJLS, static_output_feedback
from asoc_companion.theorems import bounds, corrections
from asoc_companion.theorems.counterexamples import (
    THM_3_19_SYSTEM,
    kernel_example,
    prop_3_26_example,
    thm_3_19_example,
    thm_3_31_example,
)


def _verdicts(check, n, seed=3):
    return [
        check(np.random.default_rng(child))[:2] for child in np.random.SeedSequence(seed).spawn(n)
    ]


@pytest.mark.parametrize(
    "check, n",
    [
        (corrections.check_kernels, 40),
        (corrections.check_3_19, 15),
        (corrections.check_3_26, 30),
        (corrections.check_3_27, 8),
        (corrections.check_3_31, 40),
        (corrections.check_3_32, 15),
    ],
)
def test_corrected_statement_holds_and_its_mutant_is_caught(check, n):
    verdicts = [v for v in _verdicts(check, n) if v[0] != "not_applicable"]
    assert verdicts, "no applicable instance"
    assert all(corrected == "holds" for corrected, _ in verdicts)
    assert any(mutant == "fails" for _, mutant in verdicts)


def test_prop_3_26_counterexample_is_exact():
    ex = prop_3_26_example()
    assert ex["X"] == [[1, 0], [0, 1]]
    # not PSD: bound - X~ indefinite
    assert ex["printed_gap_determinant"] == -1
    assert ex["corrected_gap_determinant"] > 0 and ex["corrected_gap"][0][0] > 0


@pytest.mark.parametrize("gain", [Fraction(-1, 4), Fraction(0), Fraction(1, 3), Fraction(-2)])
def test_thm_3_31_counterexample_bound_depends_on_a_gain_without_effect(gain):
    ex = thm_3_31_example(gain)
    assert ex["exact"] == 2
    assert ex["bound"] == 2 + 2 * gain + 4 * gain**2
    assert (ex["bound"] < ex["exact"]) == (-Fraction(1, 2) < gain < 0)
    assert ex["costate_gap_offdiagonal"] == -gain * (2 * gain + 1)


def test_thm_3_19_counterexample_cycles_although_a_stabilising_gain_exists():
    ex = thm_3_19_example(grid=4001)
    assert all(c["period_2"] and min(c["rho"]) > 1 for c in ex["cycles"])
    assert ex["best_rho"] < 1
    sys = MJLS(T=np.eye(1), J=None, **{k: np.array(v)[None] for k, v in THM_3_19_SYSTEM.items()})
    run = static_output_feedback(sys, warn=False)  # the library's Alg. 3.1 agrees
    assert not (run.converged and run.stabilizing)


def test_kernel_counterexample():
    ex = kernel_example()
    assert ex["printed"] == pytest.approx(-0.272, abs=1e-3)
    assert ex["usual"] > -1e-12


def test_difference_of_3_65_and_b4_is_the_stated_trace():
    errors = [
        corrections.check_3_32(np.random.default_rng(c))[2]
        for c in np.random.SeedSequence(8).spawn(10)
    ]
    assert max(errors) < 1e-10


def test_costate_solves_the_multiplier_equation():
    rng = np.random.default_rng(0)
    At = 0.4 * rng.standard_normal((2, 3, 3))
    Qt = np.stack([np.eye(3), 2 * np.eye(3)])
    T = np.array([[0.7, 0.3], [0.4, 0.6]])
    P = bounds.costate(At, Qt, T)
    EP = np.einsum("ij,jab->iab", T, P)
    assert np.allclose(P, Qt + np.swapaxes(At, 1, 2) @ EP @ At)


def test_a_planted_false_bound_is_caught(monkeypatch):
    """The 3.26 check is not true by construction: with the factor replaced by 1.5 it fails."""
    original = bounds.moment_bound
    monkeypatch.setattr(bounds, "moment_bound", lambda X, factor=2.0: original(X, 0.75 * factor))
    verdicts = _verdicts(corrections.check_3_26, 20)
    assert any(corrected == "fails" for corrected, _ in verdicts)


ASCII_MATH = re.compile(r"\^|_\{|_\w|<=|>=|~|\bsqrt|\btr\[|\[\[|bar\b|bar_|\b[XP]u\b")
"""Marks of math written in ASCII (x_k, x^T, X~, <=, Xbar, Xu, [[a, b], [c, d]])."""
CODE_NAME = re.compile(r"\b(?:[a-z]+[._])+[a-z]{4,}\b")
"""A library name in prose (gp.mcvmd, mcvmd_integral), not math."""


def _assert_latex_math(text):
    """``text``'s math is in ``$...$`` (paired), none written in ASCII outside it."""
    parts = text.split("$")
    assert len(parts) % 2 == 1, f"unpaired $ in {text!r}"
    prose = CODE_NAME.sub("", " ".join(parts[::2]))
    assert not ASCII_MATH.search(prose), ASCII_MATH.findall(prose)


def test_records_have_the_interface_the_study_merges():
    records = corrections.correction_records(
        np.random.SeedSequence(5), n_instances=3, mutant_instances=2
    )
    assert sorted(records) == sorted(corrections.STATEMENT_IDS)
    for key, record in records.items():
        assert isinstance(record["diagnosis"], str) and record["diagnosis"]
        assert ("corrected" in record) != ("no_correction" in record), key
        _assert_latex_math(record["diagnosis"])
        _assert_latex_math(record.get("no_correction", ""))
        if "corrected" in record:
            c = record["corrected"]
            assert c["holds"] + c["fails"] == c["instances"]
            assert set(c["mutant"]) >= {"description", "fails", "instances"}
            assert c["mutant"]["instances"] <= 2


@pytest.mark.parametrize(
    "kwargs, error",
    [
        (dict(seed_sequence=2017), TypeError),
        (dict(seed_sequence=np.random.SeedSequence(1), n_instances=0), ValueError),
        (dict(seed_sequence=np.random.SeedSequence(1), mutant_instances=1.5), ValueError),
    ],
)
def test_bad_arguments_are_named(kwargs, error):
    with pytest.raises(
        error,
        match=next(
            k
            for k in ("mutant_instances", "n_instances", "seed_sequence")
            if k in kwargs and (k != "seed_sequence" or error is TypeError)
        ),
    ):
        corrections.correction_records(**kwargs)


def test_thm_3_27_instance_13_has_two_verified_fixed_points():
    from asoc_companion.theorems.counterexamples import thm_3_27_fixed_points

    ex = thm_3_27_fixed_points(random_starts=3)
    assert (ex["M"], ex["nx"], ex["nu"], ex["ny"]) == (2, 1, 2, 1)
    low, high = ex["fixed_points"]
    assert low["cost"] == pytest.approx(1.952, abs=1e-3) and "1e-4 I" in low["starts"]
    assert high["cost"] == pytest.approx(2.424, abs=1e-3) and len(high["starts"]) == 3
    for point in (low, high):
        assert point["residual_3_45_3_48"] < 1e-12 and point["residual_3_49"] < 1e-12
        assert point["min_eig_Xu"] > 1e-3 and point["min_eig_Pu"] > 1e-3 and point["rho"] < 1


def test_thm_3_19_needs_nonsingular_noise():
    from asoc_companion.theorems.counterexamples import thm_3_19_noiseless_example

    ex = thm_3_19_noiseless_example()
    assert not ex["reaches_lq_gain"] and ex["reaches_lq_gain_with_noise"]
    outcomes = [
        corrections.check_3_19(np.random.default_rng(c))
        for c in np.random.SeedSequence(3).spawn(40)
    ]
    singular = [o for o in outcomes if o[2] is not None]
    assert singular and all(o[:2] == ("not_applicable", "not_applicable") for o in singular)
    # the hypothesis excludes real failures
    assert any(o[2] == "fails" for o in singular)
    assert all(o[0] == "holds" for o in outcomes if o[2] is None and o[0] != "not_applicable")


def test_mcvmd_integral_matches_quadrature_and_the_closed_form_fails_when_spread():
    from asoc import gp
    from asoc_companion.theorems.counterexamples import mcvmd_integral

    x, y = [0.0, 1.0, 2.5], [0.3, 4.0]
    quadrature = gp.mcvmd_quadrature(
        lambda m, b: gp.lcd_dirac(x, None, m, b),
        lambda m, b: gp.lcd_dirac(y, None, m, b),
        b_max=10.0,
        center=2.0,
        spread=6.0,
        points=x + y,
    )
    assert mcvmd_integral(x, y, 10.0) == pytest.approx(quadrature, rel=1e-8)
    outcomes = [
        corrections.check_kernels(np.random.default_rng(c))
        for c in np.random.SeedSequence(3).spawn(60)
    ]
    spread = [o[2] for o in outcomes if o[2] is not None]
    assert all(o[0] == "holds" for o in outcomes)
    assert spread and any(verdict == "fails" and lowest < -0.1 for verdict, lowest in spread)


def test_thm_3_9_c12_infeasibility_is_certified_by_two_solvers():
    from asoc.mjls.examples import sec354_system
    from asoc_companion.theorems.h2_lmi import certified_margins, lmi_C12_margin

    margins = lmi_C12_margin()
    assert all(m["verdict"] == "infeasible" for m in margins.values())
    assert all(v < 0 for m in margins.values() for v in m["margins"].values())
    # the margin separates: feasible here
    stable = sec354_system(1).replace(A=0.1 * sec354_system(1).A)
    assert certified_margins(stable)["verdict"] == "feasible"


def test_prop_3_15_diagnosis_points_at_3_11():
    from asoc_companion.theorems.static_feedback import summarise_3_15

    assert "starts in (3.11)" in summarise_3_15([])["diagnosis"]
    _assert_latex_math(summarise_3_15([])["diagnosis"])
