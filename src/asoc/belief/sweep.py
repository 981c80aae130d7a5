"""Alg. 2.2 over rounding-level perturbations: distributions instead of single chaotic runs.

With the exact Hessian of the covariance term (or the Levenberg-Marquardt shift) the
iterates of Alg. 2.2 depend on the last bits of the arithmetic: the same run gives 13
iterations with one BLAS kernel and 26 with another. :func:`perturbation_sweep` therefore
runs Alg. 2.2 from ``n_members`` initial policies L_k = 0, d_k = delta (delta ~ N(0,
``scale``^2 I), far below any modelling accuracy but far above rounding, so that the
spread it causes dominates the machine's), each with its own common random numbers for
J, and reports the spread of what a single run would show.
"""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from .models import NonlinearModel, _cost_for
from .simulate import MeanAffineController, simulate
from .trajectory import AffinePolicy, optimize_belief_trajectory


@dataclass(frozen=True)
class Sweep:
    """Per member: ``iterations``, ``converged``, ``costs`` (mean cost (2.19) of the final policy
    on the evaluation draws), ``diverged_iterates`` (fraction of iterates eta >= 1 with J^[eta] >
    J^[0]); ``baseline`` the mean cost of the zero policy on the evaluation draws.

    Examples
    --------
    >>> s = Sweep(np.array([3, 5]), np.array([True, True]), np.array([1.0, 9.0]), np.zeros(2), 5.0)
    >>> s.diverged.tolist()
    [False, True]
    """

    iterations: np.ndarray
    converged: np.ndarray
    costs: np.ndarray
    diverged_iterates: np.ndarray
    baseline: float

    @property
    def diverged(self) -> np.ndarray:
        """Members whose final policy costs more than doing nothing (the zero policy)."""
        return ~(self.costs <= self.baseline)


def distribution(samples) -> dict:
    """Median (also as ``value``, the number the ledger shows), range [min, max] and count n.

    Raises
    ------
    ValueError, TypeError
        If ``samples`` is empty or not finite real numbers.

    Examples
    --------
    >>> distribution([3.0, 1.0, 2.0])
    {'value': 2.0, 'median': 2.0, 'range': [1.0, 3.0], 'n': 3}
    """
    x = check.real_array(samples, "samples").ravel()
    if x.size == 0:
        raise ValueError("samples: expected at least one sample, found none")
    median = float(np.median(x))
    return {"value": median, "median": median, "range": [float(x.min()), float(x.max())], "n": int(x.size)}


def perturbation_sweep(model, cost, mean0, cov0, noise, n_members, rng, scale=1e-9, progress=False,
                       **options) -> Sweep:
    """Algorithm 2.2 from ``n_members`` perturbed zero policies; costs on the draws ``noise``.

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost.
    mean0, cov0 : the initial estimate.
    noise : :class:`~asoc.belief.simulate.Noise`, the common evaluation draws of every member.
    n_members : number of perturbed runs (>= 1).
    rng : seeded Generator; member i gets the child ``rng.spawn`` i for its perturbation
        and for the common random numbers of its J.
    scale : standard deviation of the perturbation of d_k (> 0).
    progress : show a progress bar.
    options : further arguments of :func:`~asoc.belief.trajectory.optimize_belief_trajectory`.

    Returns
    -------
    Sweep

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Examples
    --------
    >>> from asoc.belief import draw_noise, landmark_example
    >>> ex = landmark_example(K=2)
    >>> noise = draw_noise(ex.model, ex.mean0, ex.cov0, 2, 10, np.random.default_rng(0))
    >>> s = perturbation_sweep(ex.model, ex.cost, ex.mean0, ex.cov0, noise, 2, np.random.default_rng(1),
    ...                        n_cost_runs=10)
    >>> s.converged.tolist(), bool(np.ptp(s.costs) < 1e-3 * s.costs.mean())
    ([True, True], True)
    """
    rng = check.generator(rng)
    model = check.instance(model, NonlinearModel, "model")
    cost = _cost_for(cost, model)
    n_members = check.integer(n_members, "n_members", minimum=1)
    scale = check.real_scalar(scale, "scale", low=0, low_open=True)
    progress = check.boolean(progress, "progress")
    simulate(model, cost, mean0, cov0, MeanAffineController(model, AffinePolicy.zero(cost.K, model.n_u, model.n_x)),
             noise)                                                 # checks mean0, cov0 and noise before the runs
    K, n_u, n_x = cost.K, model.n_u, model.n_x

    def mean_cost(policy):
        return float(simulate(model, cost, mean0, cov0, MeanAffineController(model, policy), noise).costs.mean())

    rows = []
    for child in progress_bar(rng.spawn(n_members), progress, desc="perturbed Alg. 2.2"):
        zero = AffinePolicy.zero(K, n_u, n_x)
        start = AffinePolicy(zero.L, scale * child.standard_normal(zero.d.shape))
        res = optimize_belief_trajectory(model, cost, mean0, cov0, policy=start, rng=child, **options)
        J = np.asarray(res.costs)
        rows.append((res.iterations, res.converged, mean_cost(res.policy), float(np.mean(J[1:] > J[0]))))
    it, conv, costs, div = (np.array(c) for c in zip(*rows))
    return Sweep(it, conv.astype(bool), costs, div, mean_cost(AffinePolicy.zero(K, n_u, n_x)))
