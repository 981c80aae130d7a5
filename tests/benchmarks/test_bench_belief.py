"""Performance targets of Sec. 2.5: one full run of Alg. 2.2 and of the belief-space iLQG [159]
on the example of Sec. 2.5.3, each under 60 s on 2 cores."""

import warnings

import numpy as np

from asoc.belief.models import landmark_example
from asoc.belief.trajectory import optimize_belief_trajectory
from asoc.belief.vdberg import belief_ilqg


def _quiet(fn):
    def run(*args, **kwargs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return fn(*args, **kwargs)

    return run


def test_alg22_full_run(benchmark):
    """Alg. 2.2 full run, Sec. 2.5.3 example (K = 20)."""
    ex = landmark_example()
    benchmark.extra_info["target_s"] = 60.0
    # a fresh generator per round (set-up, not timed): every round runs the same computation
    benchmark.pedantic(
        _quiet(optimize_belief_trajectory),
        rounds=3,
        setup=lambda: (
            (ex.model, ex.cost, ex.mean0, ex.cov0),
            {"rng": np.random.default_rng(2017)},
        ),
    )


def test_belief_ilqg_full_run(benchmark):
    """belief-space iLQG [159] full run, Sec. 2.5.3 example."""
    ex = landmark_example()
    benchmark.extra_info["target_s"] = 60.0
    benchmark.pedantic(_quiet(belief_ilqg), args=(ex.model, ex.cost, ex.mean0, ex.cov0), rounds=3)
