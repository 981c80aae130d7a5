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

from ..progress import progress_bar
from ._validate import check_rng
from .simulate import MeanAffineController, simulate
from .trajectory import AffinePolicy, algorithm_2_2


@dataclass(frozen=True)
class Sweep:
    """Per member: ``iterations``, ``converged``, ``costs`` (mean cost (2.19) of the final policy
    on the evaluation draws), ``diverged_iterates`` (fraction of iterates eta >= 1 with J^[eta] >
    J^[0]); ``baseline`` the mean cost of the zero policy on the evaluation draws."""

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
    """Median (also as ``value``, the number the ledger shows), range [min, max] and count n."""
    x = np.asarray(samples, dtype=float).ravel()
    if x.size == 0:
        raise ValueError("samples: need at least one sample, found none")
    median = float(np.median(x))
    return {"value": median, "median": median, "range": [float(x.min()), float(x.max())], "n": int(x.size)}


def perturbation_sweep(model, cost, mean0, cov0, noise, n_members, rng, scale=1e-9, progress=False,
                       **alg22) -> Sweep:
    """Algorithm 2.2 from ``n_members`` perturbed zero policies; costs on the draws ``noise``.

    Parameters
    ----------
    noise : :class:`~asoc.belief.simulate.Noise`, the common evaluation draws of every member.
    n_members : number of perturbed runs (>= 1).
    rng : seeded Generator; member i gets the child ``rng.spawn`` i for its perturbation
        and for the common random numbers of its J.
    scale : standard deviation of the perturbation of d_k (> 0).
    alg22 : further arguments of :func:`~asoc.belief.trajectory.algorithm_2_2`.
    """
    rng = check_rng(rng)
    if not isinstance(n_members, (int, np.integer)) or n_members < 1:
        raise ValueError(f"n_members: expected an integer >= 1, found {n_members!r}")
    if not scale > 0:
        raise ValueError(f"scale: expected > 0, found {scale!r}")
    K, n_u, n_x = cost.K, model.n_u, model.n_x

    def mean_cost(policy):
        return float(simulate(model, cost, mean0, cov0, MeanAffineController(model, policy), noise).costs.mean())

    rows = []
    for child in progress_bar(rng.spawn(n_members), progress, desc="perturbed Alg. 2.2"):
        zero = AffinePolicy.zero(K, n_u, n_x)
        start = AffinePolicy(zero.L, scale * child.standard_normal(zero.d.shape))
        res = algorithm_2_2(model, cost, mean0, cov0, policy=start, rng=child, **alg22)
        J = np.asarray(res.costs)
        rows.append((res.iterations, res.converged, mean_cost(res.policy), float(np.mean(J[1:] > J[0]))))
    it, conv, costs, div = (np.array(c) for c in zip(*rows))
    return Sweep(it, conv.astype(bool), costs, div, mean_cost(AffinePolicy.zero(K, n_u, n_x)))
