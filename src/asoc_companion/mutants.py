"""Planted false variants of the ledger's claim checks, and whether each check catches its variant.

:func:`ledger_mutants` runs, for every claim key of the reference, the predicate the notebook
uses (:mod:`asoc_companion.claim_checks`) on a planted false variant and records
``{description, caught}`` (caught: the check returns ``holds = False``). Claims whose notebooks
do not yet decide them through such a predicate are listed with ``caught: False`` and say so,
so the file shows what is missing instead of hiding it. ``python -m asoc_companion ledger``
writes it to ``figures/values/ledger_mutants.json``.
"""

import json

import numpy as np

from . import claim_checks as checks
from . import paths
from .atomic_files import atomic_write_text
from .plan import values_file
from .reference import load_reference
from .values import load_all_values

__all__ = ["NOT_PLANTED", "ledger_mutants", "mutants_path", "write_ledger_mutants"]


NOT_PLANTED = (
    "no planted variant: the notebook does not decide this claim through a predicate "
    "of claim_checks"
)


def _slow_traces():
    return np.stack([1 + 0.97 ** np.arange(400), 2 - 0.95 ** np.arange(400)])


def _quadratic_grid():
    X, U = np.meshgrid(np.linspace(-5, 5, 101), np.linspace(-5, 5, 101), indexing="ij")
    return X, U, 3 + 0.5 * X**2 + 0.2 * X * U + 1.3 * U**2


def _quadratic_with_quadrature_error(error=1e-9):
    """A quadratic cost computed with a relative quadrature error ``error`` (an oscillating one)."""
    X, U, quadratic = _quadratic_grid()
    return X, U, quadratic * (1 + error * np.cos(3 * X) * np.sin(2 * U)), error


def _lmi_cases():
    from asoc.mjls.examples import sec354_system
    from asoc.mjls.lmi import static_output_lmi

    return static_output_lmi(sec354_system(1, "state")), static_output_lmi(
        sec354_system(1, "C=[1 0]")
    )


def _separation_variant():
    feasible, _ = _lmi_cases()
    return checks.lmi_separates(feasible, feasible)


def _feasible_variant():
    _, infeasible = _lmi_cases()
    return {"holds": bool(infeasible.feasible)}


def _stabilising_variant():
    from asoc.mjls import static_output_feedback
    from asoc.mjls.examples import sec354_system

    return checks.converged_not_stabilizing(
        static_output_feedback(sec354_system(1, "C1=[1 2], C2=[2 1]"), moments="step")
    )


def _swapped_163():
    rec = lambda v: {"value": v, "ci": [v, v]}  # noqa: E731 (one-line record)
    steady, transient = [(1.0, 1.0), (1.0, 1.0)], [(1.05, 1.0), (1.05, 1.0)]
    as_records = lambda pairs: [(rec(a), rec(b)) for a, b in pairs]  # noqa: E731
    return checks.almost_equal_then_slightly_worse(
        as_records(steady), as_records([(b, a) for a, b in transient]), steady, transient
    )


def _beyond_the_bound(record):
    """A recorded :func:`asoc.stats.decide_claim` decision repeated on its samples shifted so
    that every one lies beyond the claimed bound (past ``below``, else below ``above``).
    """
    from asoc.stats import decide_claim

    samples, above, below = np.asarray(record["samples"]), record["above"], record["below"]
    margin = max(float(np.ptp(samples)), abs(below if below is not None else above), 1.0) * 1e-3
    shifted = (samples - samples.min() + below + margin if below is not None
               else samples - samples.max() + above - margin)
    decision = decide_claim(shifted, above=above, below=below, level=record["level"])
    return {"holds": decision["verdict"] == "holds"}


def _decided_variant(record):
    bound = f"< {record['below']:g}" if record["below"] is not None else f"> {record['above']:g}"
    return (f"the recorded n = {len(record['samples'])} samples shifted so that each one violates "
            f"the claimed median {bound}, decided again",
            lambda: _beyond_the_bound(record))


def _decided_claims(values):
    """``{claim key: variant}`` of every recorded value decided by
    :func:`asoc.stats.decide_claim`.
    """
    return {key: _decided_variant(value) for key, value in values.items()
            if isinstance(value, dict) and {"samples", "above", "below", "level"} <= set(value)}


def _sec32_variants():
    from asoc.mjls.examples import SEC32_A, SEC32_T, SEC32_X0

    steps = 20
    return {
        "sec3_2.mjls_unstable": (
            "the modes of Sec. 3.2 with A_i halved (rho / 4 < 1)",
            lambda: checks.mean_square_unstable(np.asarray(SEC32_A) / 2, SEC32_T),
        ),
        "sec3_2.mjls_trajectory_diverges": (
            f"1,000 runs contracting by half a step: x_K = 2^-K x_0 after K = {steps} steps",
            lambda: checks.diverges(np.tile(np.asarray(SEC32_X0) * 0.5**steps, (1000, 1)),
                                    SEC32_X0),
        ),
    }


def _sec26_variants():
    x = np.linspace(-2.4, 2.4, 97)
    truth = 0.25 * x + np.sin(x)
    off_by = (
        "a closed form 1e-3 (relative) off the quadrature of the definition",
        lambda: checks.matches(1.001, 1.0),
    )
    return {
        "sec2_6.mcvmd_closed_form_matches_definition": off_by,
        "sec2_6.thesis_c_b_matches_definition": off_by,
        "sec2_6.fig26_samples_resemble_true_function": (
            "20 samples of the true function of Fig. 2.6 shifted by 0.6 (RMS deviation 0.6 > 0.5)",
            lambda: checks.resembles(np.tile(truth + 0.6, (20, 1)), truth),
        ),
    }


def _variants():
    """``{claim key: (description, callable returning the check's record on the variant)}``."""
    slow = (
        "traces contracting at rates 0.97 and 0.95, which settle after 75-150 iterations",
        lambda about: checks.settles_about(_slow_traces(), about),
    )
    reversed_order = (
        "the two controllers' medians swapped (a reversed ordering)",
        lambda: checks.ordered([2.0, 3.0], [1.0, 2.5]),
    )
    out = {
        "sec3_4.not_quadratic": (
            "a quadratic cost on the grid of Fig. 3.3 with a relative quadrature error 1e-9",
            lambda: checks.not_quadratic(*_quadratic_with_quadrature_error()),
        ),
        "sec3_4.not_convex": (
            "a convex quadratic cost on the grid of Fig. 3.3",
            lambda: checks.not_convex(lambda x, u: x**2 + x * u + u**2, *_quadratic_grid()[:2]),
        ),
        "sec3_5.fig3_4_settling_iterations": (slow[0], lambda: slow[1](15)),
        "sec3_6.alg32_settles_in_about_15_iterations": (slow[0], lambda: slow[1](15)),
        "sec3_6.alg33_converges_in_about_5_iterations": (slow[0], lambda: slow[1](5)),
        "sec3_6.alg33_bound_non_increasing": (
            "a bound sequence that rises by 1e-6 once",
            lambda: checks.non_increasing([3.0, 2.0, 2.000002, 1.5]),
        ),
        "sec3_6.bound_prop326_holds": (
            "the closed-form counterexample of findings: exact cost 2, 'bound' 1.75",
            lambda: checks.bounded([2.0], [1.75]),
        ),
        "sec3_6.time_variant_better_than_time_invariant": reversed_order,
        "sec3_6.optimal_38_best": reversed_order,
        "sec3_5.proposed_almost_equal_163": (
            "the printed transient ratio reversed: the proposed controller better than [163] by 5 "
            "%",
            _swapped_163,
        ),
    }
    out["sec3_6.bound_thm331_holds"] = out["sec3_6.bound_prop326_holds"]
    for t in (1, 2):
        out[f"sec3_5.lmi_C10_T{t}"] = (
            "the state-feedback case (C = I, feasible) in place of C = [1 0]",
            _separation_variant,
        )
        out[f"sec3_5.lmi_C12_T{t}"] = (
            "C = [1 0], where the LMIs are infeasible",
            _feasible_variant,
        )
        out[f"sec3_5.converged_not_stabilizing_C10_T{t}"] = (
            "Alg. 3.1 on C1 = [1 2], C2 = [2 1], whose gain stabilises",
            _stabilising_variant,
        )
        out[f"sec3_5.alg31_faster_than_163_T{t}"] = (
            "Alg. 3.1's time and [163]'s swapped",
            lambda: checks.ordered([2.0], [1.0]),
        )
    out["findings.lmi_C12_feasible"] = out["sec3_5.lmi_C12_T1"]
    out["findings.lmi_C12_feasible_author_mu"] = out["sec3_5.lmi_C12_T1"]
    return {**out, **_sec26_variants(), **_sec32_variants()}


def ledger_mutants(reference=None, values=None) -> dict:
    """``{claim key: {"description", "caught"}}`` for every claim of the reference.

    A claim the notebook decided by :func:`asoc.stats.decide_claim` gets its variant from its
    recorded decision in ``values`` (default: the committed values): the same samples shifted
    past the claimed bound.

    Examples
    --------
    >>> from asoc_companion.reference import Entry
    >>> claim = Entry("sec3_6.optimal_38_best", where="Table 3.3", kind="claim", thesis="[38] best")
    >>> ledger_mutants({claim.key: claim})["sec3_6.optimal_38_best"]["caught"]
    True
    >>> from asoc.stats import decide_claim
    >>> decided = Entry("demo.smaller", where="an example", kind="claim", thesis="smaller")
    >>> record = decide_claim(-1.0 - np.arange(9.0), below=0.0)
    >>> ledger_mutants({decided.key: decided}, {decided.key: record})["demo.smaller"]
    {'description': 'the recorded n = 9 samples shifted so that each one violates the claimed
    median < 0, decided again', 'caught': True}
    """
    reference = reference if reference is not None else load_reference()
    values = load_all_values() if values is None else values
    variants = {**_decided_claims(values), **_variants()}
    out = {}
    for key, entry in reference.items():
        if entry.kind != "claim":
            continue
        if key in variants:
            description, run = variants[key]
            out[key] = {"description": description, "caught": not run()["holds"]}
        else:
            out[key] = {"description": NOT_PLANTED, "caught": False}
    return out


def mutants_path():
    """``figures/values/ledger_mutants.json`` of the project."""
    return values_file(paths.project().figures, "ledger_mutants")


def write_ledger_mutants(path=None) -> dict:
    """Write :func:`ledger_mutants` to ``figures/values/ledger_mutants.json`` in the layout of a
    values file (``{"notebook": "ledger_mutants", "values": {claim key: record}}``); return
    the records.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     mutants = write_ledger_mutants(pathlib.Path(folder) / "ledger_mutants.json")
    >>> all(set(m) == {"description", "caught"} for m in mutants.values())
    True
    """
    mutants = ledger_mutants()
    atomic_write_text(
        path or mutants_path(),
        json.dumps({"notebook": "ledger_mutants", "values": mutants}, indent=1, sort_keys=True)
        + "\n",
    )
    return mutants
