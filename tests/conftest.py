"""Shared fixtures: the notebooks are run once per session at ci fidelity."""

import pytest

from asoc.repro import notebooks as nbs
from asoc.repro.paths import CI_OUTPUT

NOTEBOOKS = nbs.notebooks()


@pytest.fixture(scope="session")
def ci_run():
    """Run a notebook at ci fidelity (once per session) and return its output folder."""
    done = {}

    def run(name):
        if name not in done:
            out = CI_OUTPUT / "test" / name
            nbs.run(NOTEBOOKS[name], "ci", output_dir=out)
            done[name] = out
        return done[name]

    return run
