"""Performance targets of issue 5 (``make bench``): one full run of Alg. 2.2 and of the
belief-space iLQG [159] on the example of Sec. 2.5.3, each under 60 s on 2 cores."""

import time
import warnings

import numpy as np

from .models import landmark_example
from .trajectory import algorithm_2_2
from .vdberg import belief_ilqg


def _alg22():
    ex = landmark_example()
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        algorithm_2_2(ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(2017))
    return time.perf_counter() - start


def _vdberg():
    ex = landmark_example()
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        belief_ilqg(ex.model, ex.cost, ex.mean0, ex.cov0)
    return time.perf_counter() - start


BENCHMARKS = [
    ("Alg. 2.2 full run, Sec. 2.5.3 example (K = 20)", 60.0, _alg22, 3),
    ("belief-space iLQG [159] full run, Sec. 2.5.3 example", 60.0, _vdberg, 3),
]
