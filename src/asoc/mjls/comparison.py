"""Monte Carlo comparison of controllers (Table 3.2): common random numbers, medians with
exact bootstrap intervals."""

import time
from dataclasses import dataclass

import numpy as np
from ..progress import progress_bar

from ..stats import bootstrap_median_ci
from ..validation import boolean, integer, real_scalar
from .baselines import do_val_h2_state_feedback, time_variant_feedback
from .examples import sec354_system
from .observed import observed_mode_state_feedback
from .simulate import ModeDependentGain, StaticGain, TimeVariantGain, simulate
from .static import static_output_feedback

TABLE_3_2_ROWS = (
    ("state feedback", "time-invariant optimal with observed mode [38]"),
    ("state feedback", "time-invariant with non-observed mode [52]"),
    ("state feedback", "time-variant with non-observed mode [165]"),
    ("state feedback", "proposed"),
    ("output feedback", "time-variant with non-observed mode [163]"),
    ("output feedback", "proposed"),
)


@dataclass
class Design:
    """A controller designed for one scenario: the system it runs on, the controller, the
    gain computation time in seconds.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> d = Design(sec354_system(1), StaticGain([[-0.6]]), 0.01)
    >>> d.controller.L
    array([[-0.6]])
    """

    sys: object
    controller: object
    seconds: float


def table_3_2_designs(T, x0, horizon, H=None):
    """The six controllers of Table 3.2 for transition matrix T[``T``] and initial state x0.

    State-feedback rows use C_i = I; output-feedback rows C1 = [1 2], C2 = [2 1]. The
    time-variant designs [165], [163] are computed for the scenario's x0, horizon and the
    stationary initial mode distribution.

    Examples
    --------
    >>> designs = table_3_2_designs(1, [3.0, 0.0], 10)
    >>> len(designs), TABLE_3_2_ROWS[3] in designs
    (6, True)
    """
    kw = {} if H is None else {"H": H}
    sf = sec354_system(T, "state", **kw)
    of = sec354_system(T, "C1=[1 2], C2=[2 1]", **kw)
    designs = {}
    r38 = observed_mode_state_feedback(sf)
    designs[TABLE_3_2_ROWS[0]] = Design(sf, ModeDependentGain(r38.L), r38.seconds)
    t = time.perf_counter()
    r52 = do_val_h2_state_feedback(sf)
    if not r52.feasible:
        raise RuntimeError(f"[52] LMI infeasible for T[{T}]: {r52.message}")
    designs[TABLE_3_2_ROWS[1]] = Design(sf, StaticGain(r52.L), time.perf_counter() - t)
    r165 = time_variant_feedback(sf, horizon, x0)
    designs[TABLE_3_2_ROWS[2]] = Design(sf, TimeVariantGain(r165.G), r165.seconds)
    rsf = static_output_feedback(sf)
    designs[TABLE_3_2_ROWS[3]] = Design(sf, StaticGain(rsf.L), rsf.seconds)
    r163 = time_variant_feedback(of, horizon, x0)
    designs[TABLE_3_2_ROWS[4]] = Design(of, TimeVariantGain(r163.G), r163.seconds)
    rof = static_output_feedback(of)
    designs[TABLE_3_2_ROWS[5]] = Design(of, StaticGain(rof.L), rof.seconds)
    return designs


def median_costs(designs, x0, horizon, n_runs, seed, normalise=True, mode0=None, level=0.95):
    """Median per-run cost of each design with its exact bootstrap interval.

    Every design sees the same random numbers (same ``seed``): common random numbers make
    the differences between rows sharper than independent runs would. ``normalise``
    divides each run's cost (3.3) by the horizon (the finite-horizon reading of (3.9)).

    Examples
    --------
    >>> designs = table_3_2_designs(1, [3.0, 0.0], 10)
    >>> out = median_costs(designs, [3.0, 0.0], 10, 200, seed=1)
    >>> sorted(out[TABLE_3_2_ROWS[3]])
    ['ci', 'n', 'value']
    """
    if not isinstance(designs, dict) or not all(isinstance(d, Design) for d in designs.values()):
        raise TypeError(f"designs: expected a dict of Design (from table_3_2_designs), found {type(designs).__name__}")
    seed = integer(seed, "seed", minimum=0)
    normalise = boolean(normalise, "normalise")
    level = real_scalar(level, "level", low=0, high=1, low_open=True, high_open=True)
    out = {}
    for row, d in progress_bar(designs.items(), n_runs >= 20000, desc="controllers", leave=False):
        res = simulate(d.sys, d.controller, x0, horizon, n_runs, np.random.default_rng(seed),
                       mode0=mode0)
        cost = res.average_cost if normalise else res.cost
        out[row] = bootstrap_median_ci(cost, level)
    return out
