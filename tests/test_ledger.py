"""The committed full-fidelity values give every reference entry its expected status, and
the committed ledger page is the one the generator writes from them."""

import pytest

from asoc.repro import load_all_values, load_reference, status
from asoc.repro.ledger import ledger_markdown
from asoc.repro.paths import BOOK

REFERENCE = load_reference()
VALUES = load_all_values()


@pytest.mark.parametrize("key", sorted(REFERENCE))
def test_full_fidelity_status_is_the_expected_one(key):
    entry = REFERENCE[key]
    assert key in VALUES, f"{key} has no full-fidelity value in figures/values"
    assert status(entry, VALUES[key]) == entry.expect, (
        f"{key}: ours {VALUES[key]!r}, thesis {entry.thesis!r}: status changed")


def test_every_recorded_value_is_in_the_reference():
    missing = sorted(set(VALUES) - set(REFERENCE))
    assert not missing, f"recorded but not in tests/reference/thesis_values/<notebook>.yaml: {missing}"


def test_committed_ledger_is_current():
    assert (BOOK / "ledger.md").read_text() == ledger_markdown(REFERENCE, VALUES), \
        "book/ledger.md is stale: run `python -m asoc ledger`"


def test_notebooks_have_figures_in_figures_folder():
    from asoc.repro.paths import FIGURES
    from asoc.repro.notebooks import notebooks
    for info in notebooks().values():
        for number in info.figures:
            assert (FIGURES / f"fig{number.replace('.', '_')}.png").exists(), number
        for number in info.tables:
            assert (FIGURES / f"table{number.replace('.', '_')}.md").exists(), number
