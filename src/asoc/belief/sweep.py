"""Alg. 2.2 over rounding-level perturbations: distributions instead of single chaotic runs.

With the exact Hessian of the covariance term (or the Levenberg-Marquardt shift) the
iterates of Alg. 2.2 depend on the last bits of the arithmetic: the same run gives 13
iterations with one BLAS kernel and 26 with another. :func:`perturbation_sweep` therefore
runs Alg. 2.2 from ``n_members`` initial policies L_k = 0, d_k = delta (delta ~ N(0,
``scale``^2 I), far below any modelling accuracy but far above rounding, so that the
spread it causes dominates the machine's), each with its own common random numbers for
J, and reports the spread of what a single run would show.
"""

import warnings
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from .damped import optimize_damped
from .models import NonlinearModel, cost_for
from .planning import bend_toward_landmark
from .policy import AffinePolicy, MeanAffineController
from .simulate import simulate
from .trajectory import optimize_belief_trajectory
from .ukf import UKF

__all__ = ["Sweep", "distribution", "perturbation_sweep"]


@dataclass(frozen=True)
class Sweep:
    """Per member: ``iterations``, ``converged``, ``costs`` (mean cost (2.19) of the final policy on
    the evaluation draws), ``diverged_iterates`` (fraction of iterates eta >= 1 with
    J^[eta] > J^[0]); ``baseline`` the mean cost of the zero policy on the evaluation draws;
    ``bends`` the bend of the final reference toward the landmark
    (:func:`~asoc.belief.planning.bend_toward_landmark`, NaN without a landmark); ``increases`` the
    largest relative increase of J^[eta] between iterations (<= 0 when J never rose).

    Examples
    --------
    >>> s = Sweep(np.array([3, 5]), np.array([True, True]), np.array([1.0, 9.0]), np.zeros(2), 5.0,
    ...           np.zeros(2), np.zeros(2))
    >>> s.diverged.tolist()
    [False, True]
    """

    iterations: np.ndarray
    converged: np.ndarray
    costs: np.ndarray
    diverged_iterates: np.ndarray
    baseline: float
    bends: np.ndarray
    increases: np.ndarray

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
    return {"value": median, "median": median, "range": [float(x.min()), float(x.max())],
            "n": int(x.size)}


def perturbation_sweep(model, cost, mean0, cov0, noise, n_members, rng, scale=1e-9, progress=False,
                       n_jobs=1, landmark=None, **options) -> Sweep:
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
    n_jobs : worker processes for the members (joblib's convention: -1 all cores); 1 runs them
        in this process. The result does not depend on it.
    landmark : array_like (2,), optional
        For ``bends``: the landmark of Sec. 2.5.3 (the line runs from ``mean0`` to the target).
    options : further arguments of :func:`~asoc.belief.trajectory.optimize_belief_trajectory`;
        ``step_control="levenberg-marquardt"`` runs :func:`~asoc.belief.damped.optimize_damped`
        (exact Hessian) with the remaining options instead.

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
    >>> s = perturbation_sweep(ex.model, ex.cost, ex.mean0, ex.cov0, noise, 2,
    ...                        np.random.default_rng(1), n_cost_runs=10)
    >>> s.converged.tolist(), bool(np.ptp(s.costs) < 1e-3 * s.costs.mean())
    ([True, True], True)
    """
    rng = check.generator(rng)
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    n_members = check.integer(n_members, "n_members", minimum=1)
    scale = check.real_scalar(scale, "scale", low=0, low_open=True)
    progress = check.boolean(progress, "progress")
    n_jobs = check.process_count(n_jobs, "n_jobs")
    zero = AffinePolicy.zero(cost.K, model.n_u, model.n_x)
    # checks mean0, cov0 and noise before the runs
    simulate(model, cost, mean0, cov0, MeanAffineController(model, zero), noise)

    children = rng.spawn(n_members)
    options = {**options,
               "landmark": None if landmark is None else check.vector(landmark, "landmark", 2)}
    if n_jobs == 1:
        outputs = [_member(model, cost, mean0, cov0, noise, child, scale, options)
                   for child in progress_bar(children, progress, desc="perturbed Alg. 2.2")]
    else:
        outputs = _members_in_parallel(model, cost, mean0, cov0, noise, children, scale, options,
                                       n_jobs, progress)
    rows = _reissued(outputs)
    it, conv, costs, div, bends, increases = (np.array(c) for c in zip(*rows))
    return Sweep(it, conv.astype(bool), costs, div,
                 _mean_cost(model, cost, mean0, cov0, noise, zero), bends, increases)


def _mean_cost(model, cost, mean0, cov0, noise, policy) -> float:
    run = simulate(model, cost, mean0, cov0, MeanAffineController(model, policy), noise)
    return float(run.costs.mean())


def _member(model, cost, mean0, cov0, noise, child, scale, options):
    """One member of the sweep: (iterations, converged, mean cost, share of diverged iterates) and
    the warnings it raised (recorded, since a worker process's warnings would not reach the caller).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        zero = AffinePolicy.zero(cost.K, model.n_u, model.n_x)
        start = AffinePolicy(zero.L, scale * child.standard_normal(zero.d.shape))
        options = dict(options)
        landmark = options.pop("landmark")
        if options.pop("step_control", None) == "levenberg-marquardt":
            options.pop("covariance_hessian", None)
            res = optimize_damped(model, cost, mean0, cov0, policy=start, rng=child, **options)
        else:
            res = optimize_belief_trajectory(model, cost, mean0, cov0, policy=start, rng=child,
                                             **options)
        J = np.asarray(res.costs)
        means = (None if res.reference is None
                 else [UKF.mean(e) for e in res.reference.estimates])
        bend = (np.nan if landmark is None or means is None
                else bend_toward_landmark(means, mean0, cost.x_target, landmark))
        mean_cost = _mean_cost(model, cost, mean0, cov0, noise, res.policy)
        row = (res.iterations, res.converged, mean_cost, float(np.mean(J[1:] > J[0])), bend,
               float(np.max(np.diff(J) / J[:-1])) if J.size > 1 else 0.0)
    return row, [(w.message, w.category) for w in caught]


def _reissued(member_outputs):
    """The members' rows, their warnings re-issued here in member order (the caller's filters)."""
    rows = []
    for row, caught in member_outputs:
        for message, category in caught:
            warnings.warn(message, category, stacklevel=3)
        rows.append(row)
    return rows


def _members_in_parallel(model, cost, mean0, cov0, noise, children, scale, options, n_jobs,
                         progress):
    """The members on ``n_jobs`` worker processes (joblib/loky, which pickles the model's local
    functions); each member's generator travels with it, so the rows equal the serial ones.
    """
    try:
        import joblib
    except ImportError as err:                                   # the optional extra asoc[studies]
        raise ImportError("n_jobs != 1 needs joblib: pip install 'asoc[studies]'") from err
    tasks = (joblib.delayed(_member)(model, cost, mean0, cov0, noise, child, scale, options)
             for child in children)
    rows = joblib.Parallel(n_jobs=n_jobs, return_as="generator")(tasks)
    return list(progress_bar(rows, progress, desc="perturbed Alg. 2.2", total=len(children)))
