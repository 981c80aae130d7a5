"""Every notebook runs at ci fidelity (once per session, under nbval: conftest's ``ci_execution``);
recorded values are
checked against
the reference file (deterministic values against the thesis or, where the ledger
documents a deviation, against our full-fidelity value) and against our own
full-fidelity values (Monte Carlo medians, within ``ci_rtol``). A ``ci_rtol`` tighter than
the Monte Carlo error of the comparison (four combined standard errors) is itself a failure:
tolerances are derived from the quantity's accuracy (src/asoc_companion/reference.py)."""

import pytest

from asoc_companion import load_reference, load_values, status
from asoc_companion.figures import file_stem
from asoc_companion.reference import agrees_with_full, monte_carlo_rtol
from conftest import NOTEBOOKS

REFERENCE = load_reference()


def _entries(name):
    return [e for e in REFERENCE.values() if e.notebook == name]


@pytest.mark.notebook
@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_notebook_at_ci_fidelity(name, ci_run):
    out = ci_run(name)
    ours_ci = load_values(name, out)
    ours_full = load_values(name)
    entries = _entries(name)
    info = NOTEBOOKS[name]
    # a numerical section records what the thesis prints; a page such as the findings may only quote
    assert entries or not (info.figures or info.tables), f"no reference entries for {name}"
    problems = []
    for entry in entries:
        if entry.name not in ours_ci:
            problems.append(f"{entry.key}: not recorded at ci fidelity")
            continue
        if entry.name not in ours_full:
            problems.append(f"{entry.key}: no full-fidelity value committed (run `make figures`)")
            continue
        if (
            entry.kind == "deterministic"
            and entry.expect == "reproduced"
            and status(entry, ours_ci[entry.name]) != "reproduced"
        ):
            problems.append(
                f"{entry.key}: {ours_ci[entry.name]} vs thesis {entry.thesis} (tol {entry.tol})"
            )
        ok, how = agrees_with_full(entry, ours_ci[entry.name], ours_full[entry.name])
        if not ok:
            problems.append(f"{entry.key}: ci run disagrees with committed full run: {how}")
        mc_error = monte_carlo_rtol(ours_ci[entry.name], ours_full[entry.name])
        if entry.ci_rtol is not None and mc_error is not None and entry.ci_rtol < mc_error:
            problems.append(
                f"{entry.key}: ci_rtol {entry.ci_rtol} is tighter than the Monte Carlo "
                "error "
                f"of the comparison, {mc_error:.3g} (4 combined standard errors)"
            )
    assert not problems, "\n".join(problems)


@pytest.mark.notebook
@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_notebook_writes_its_figures_and_tables(name, ci_run):
    out = ci_run(name)
    info = NOTEBOOKS[name]
    for number in info.figures:
        stem = file_stem("fig", number)
        for ext in ("png", "pdf"):
            assert (out / f"{stem}.{ext}").stat().st_size > 1000, f"{stem}.{ext} missing or empty"
    for number in info.tables:
        stem = file_stem("table", number)
        assert (out / f"{stem}.csv").exists() and (out / f"{stem}.md").exists()
