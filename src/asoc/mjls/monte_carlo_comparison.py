"""Table 3.2's Monte Carlo comparison of controllers: the designs of its rows, simulated with
common random numbers, and medians with exact bootstrap intervals. Exact average costs are in
:mod:`asoc.mjls.costs`.
"""

import time
from dataclasses import dataclass

import numpy as np

from ..progress import progress_bar
from ..stats import bootstrap_median_ci
from ..validation import boolean, integer, real_scalar
from .baselines import do_val_h2_state_feedback, time_variant_feedback
from .controllers import ModeDependentGain, StaticGain, TimeVariantGain
from .examples import sec354_system
from .monte_carlo import simulate
from .observed_mode_feedback import observed_mode_state_feedback
from .static import static_output_feedback

__all__ = ["TABLE_3_2_ROWS", "Design", "table_3_2_designs", "median_costs"]


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


def table_3_2_designs(T, x0, horizon, H=None, rows=TABLE_3_2_ROWS):
    """The controllers of Table 3.2 (all six, or those in ``rows``) for transition matrix T[``T``]
    and initial state x0.

    State-feedback rows use C_i = I; output-feedback rows C1 = [1 2], C2 = [2 1]. The
    time-variant designs [165], [163] are computed for the scenario's x0, horizon and the
    stationary initial mode distribution. Each design is computed on its own, so a subset
    gives the same controllers as the whole table.

    Raises
    ------
    TypeError
        If ``rows`` is not a sequence of rows.
    ValueError
        If ``rows`` names a row that is not one of ``TABLE_3_2_ROWS``.

    Examples
    --------
    >>> designs = table_3_2_designs(1, [3.0, 0.0], 10)
    >>> len(designs), TABLE_3_2_ROWS[3] in designs
    (6, True)
    >>> list(table_3_2_designs(1, [3.0, 0.0], 10, rows=[TABLE_3_2_ROWS[3]])) == [TABLE_3_2_ROWS[3]]
    True
    """
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise TypeError("rows: expected a sequence of rows of TABLE_3_2_ROWS, "
                        f"found {type(rows).__name__}")
    unknown = [row for row in rows if row not in TABLE_3_2_ROWS]
    if unknown:
        raise ValueError(f"rows: expected rows of TABLE_3_2_ROWS, found {unknown}")
    kw = {} if H is None else {"H": H}
    systems = {"state feedback": sec354_system(T, "state", **kw),
               "output feedback": sec354_system(T, "C1=[1 2], C2=[2 1]", **kw)}
    return {row: _DESIGNERS[row[1]](systems[row[0]], T, x0, horizon)
            for row in TABLE_3_2_ROWS if row in rows}


def _observed_mode_38(sys, T, x0, horizon):
    r = observed_mode_state_feedback(sys)
    return Design(sys, ModeDependentGain(r.L), r.seconds)


def _h2_lmi_52(sys, T, x0, horizon):
    start = time.perf_counter()
    r = do_val_h2_state_feedback(sys)
    if not (r.feasible and r.stabilizing):
        raise RuntimeError(f"[52] LMI gives no certified stabilising gain for T[{T}]: {r.message}")
    return Design(sys, StaticGain(r.L), time.perf_counter() - start)


def _variational(sys, T, x0, horizon):
    r = time_variant_feedback(sys, horizon, x0)
    return Design(sys, TimeVariantGain(r.G), r.seconds)


def _proposed(sys, T, x0, horizon):
    r = static_output_feedback(sys)
    return Design(sys, StaticGain(r.L), r.seconds)


# the designer of each row's method ([165] and [163] are the same variational method)
_DESIGNERS = {TABLE_3_2_ROWS[0][1]: _observed_mode_38, TABLE_3_2_ROWS[1][1]: _h2_lmi_52,
              TABLE_3_2_ROWS[2][1]: _variational, TABLE_3_2_ROWS[4][1]: _variational,
              "proposed": _proposed}


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
        raise TypeError("designs: expected a dict of Design (from table_3_2_designs), "
                        f"found {type(designs).__name__}")
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
