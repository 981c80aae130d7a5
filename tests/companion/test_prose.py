"""Numbers in prose: placeholders filled from recorded values, unknown ones rejected."""

import pytest

from asoc_companion.prose import fill

VALUES = {
    "sec9_9.cost": {"value": 93.16, "ci": [88.5, 98.1], "n": 1000},
    "sec9_9.claim": {"holds": False, "value": 0.1905},
    "sec9_9.iters": [13, 26],
    "sec9_9.flag": True,
    "sec9_9.gains": {"T1": -0.63501},
}


def test_fill_formats_records_and_parts():
    text = (
        "cost {{sec9_9.cost:.1f}}, lo {{sec9_9.cost.ci[0]:.2f}}, bend {{sec9_9.claim:.3f}}, "
        "iters {{sec9_9.iters[1]}}, {{sec9_9.flag}}, L {{sec9_9.gains.T1:.4f}}, $x_{K-1}$"
    )
    assert (
        fill(text, VALUES) == "cost 93.2 [88.5, 98.1], lo 88.50, bend 0.191, iters 26, yes, "
        "L -0.6350, $x_{K-1}$"
    )


def test_fill_local_keys_inside_a_notebook():
    assert (
        fill("{{iters:d}} and {{sec9_9.iters[0]}}", VALUES, notebook="sec9_9") == "[13, 26] and 13"
    )


@pytest.mark.parametrize(
    "text", ["{{sec9_9.missing}}", "{{sec9_9.iters[5]}}", "{{other.cost}}", "{{cost}}"]
)
def test_fill_rejects_unknown_paths(text):
    with pytest.raises(KeyError):
        fill(text, VALUES)


def test_thesis_values_are_available_to_prose():
    from asoc_companion.prose import thesis_values
    from asoc_companion.reference import Entry

    ref = {
        "sec9_9.rho": Entry(
            key="sec9_9.rho", where="", kind="deterministic", thesis=1.297, tol=6e-5
        ),
        "sec9_9.new": Entry(key="sec9_9.new", where="", kind="measured"),
    }
    values = {**thesis_values(ref), **VALUES}
    assert fill("{{thesis_sec9_9.rho:.4f}} vs {{sec9_9.iters[0]}}", values) == "1.2970 vs 13"
    with pytest.raises(KeyError):
        fill("{{thesis_sec9_9.new}}", values)


@pytest.mark.parametrize(
    "name", sorted(__import__("asoc_companion.notebooks", fromlist=["notebooks"]).notebooks())
)
def test_prose_cells_hide_their_template(name):
    """A cell that renders prose from recorded values shows the text, not its template as well."""
    import json

    from asoc_companion.notebooks import notebooks

    cells = json.loads(notebooks()[name].path.read_text())["cells"]
    shown = [
        i
        for i, c in enumerate(cells)
        if c["cell_type"] == "code"
        and "".join(c["source"]).lstrip().startswith("repro.prose(")
        and "remove-input" not in c["metadata"].get("tags", [])
    ]
    assert not shown, f"{name}: prose cells {shown} lack the remove-input tag"
