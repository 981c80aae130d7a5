"""Algorithm 2.2 with the exact statistical Hessian and a Levenberg-Marquardt step control.

The thesis asserts R~_k > 0 after Theorem 2.5, but the Hessian of the covariance term
1/2 tr[S_{k+1} C_{k+1}(u)] of (2.13) can make R~_k indefinite, and then (2.17) is not a
descent step. The default of :func:`~asoc.belief.optimize_belief_trajectory` projects that
Hessian onto the PSD cone, which may remove exactly the curvature that rewards a detour.
Here the Hessian stays exact and the step is controlled as in regularised DDP (Tassa, Erez
and Todorov, "Synthesis and stabilization of complex behaviors through online trajectory
optimization", IROS 2012, Sec. II-F; the Levenberg-Marquardt rule): every R_k^i gets
mu I, mu grows (x ``factor``) while some R~_k + mu I is indefinite or the new policy's J does
not decrease, and shrinks (/ ``factor``, to 0 below ``mu_min``) after an accepted step. J is
the same common-random-number Monte Carlo cost as in Alg. 2.2, so the accepted J^[eta] are
non-increasing by construction, and mu = 0 is Alg. 2.2 with the exact Hessian as printed.
"""

import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import validation as check
from .filters import KAPPA, sigma_points
from .models import NonlinearModel, cost_for
from .policy import AffinePolicy, MeanAffineController, policy_for
from .simulate import draw_noise, simulate
from .stage import filter_for
from .trajectory import (
    IndefiniteStep,
    TrajectoryOptimizationResult,
    backward_pass,
    reference_trajectory,
)

__all__ = ["DampedResult", "optimize_damped"]


@dataclass(kw_only=True)
class DampedResult(TrajectoryOptimizationResult):
    """:class:`~asoc.belief.TrajectoryOptimizationResult` of the damped Alg. 2.2.

    ``policies``, ``costs`` and ``iterations`` count accepted steps (J^[eta] non-increasing);
    ``passes`` all backward passes, ``damping`` the mu of each accepted step. Status
    ``converged`` (relative change of J <= rtol), ``no_progress`` (mu exceeded ``mu_max``: no
    damped step decreases J) or ``max_iterations``.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = optimize_damped(ex.model, ex.cost, ex.mean0, ex.cov0, rng=np.random.default_rng(0),
    ...                       n_cost_runs=10)
    >>> res.status, bool(np.all(np.diff(res.costs) <= 0)), res.passes >= res.iterations
    ('converged', True, True)
    """

    passes: int = 0
    damping: list = field(default_factory=list)


def optimize_damped(
    model,
    cost,
    mean0,
    cov0,
    filt=None,
    policy=None,
    max_iterations=60,
    rtol=1e-4,
    n_cost_runs=200,
    rng=None,
    mu_min=1e-3,
    mu_max=1e3,
    factor=4.0,
    derivatives="analytic",
    alpha_min=2.0**-10,
) -> DampedResult:
    """Algorithm 2.2 with the exact covariance Hessian and Levenberg-Marquardt damping of R~_k.

    Parameters
    ----------
    model : NonlinearModel
        The system.
    cost : QuadraticCost
        The cost; its ``K`` is the horizon.
    mean0, cov0 : array_like, (n_x,) and (n_x, n_x)
        The initial estimate p_0^x (Gaussian); ``cov0`` positive semidefinite.
    filt : BeliefFilter, optional
        The filter (default :class:`~asoc.belief.UKF`); its Dirac mixture is the expansion point.
    policy : AffinePolicy, optional
        The initial policy (default L = 0, d = 0).
    max_iterations : int
        Limit on the backward passes (accepted or not), >= 1.
    rtol : float
        Stop when abs(J^[eta+1] - J^[eta]) <= rtol abs(J^[eta]) (Step 9), rtol > 0.
    n_cost_runs : int
        J^[eta] is the mean cost of ``n_cost_runs`` (>= 1) closed-loop runs with common random
        numbers from ``rng``.
    rng : numpy.random.Generator
        The source of those draws.
    mu_min : float
        The smallest non-zero damping, > 0.
    mu_max : float
        The damping beyond which the search stops (``no_progress``), >= ``mu_min``.
    factor : float
        The damping's growth and shrink factor, > 1.
    derivatives : {"analytic", "numdifftools"}
        Model and cost derivatives where available, or numerical ones.
    alpha_min : float
        The constant alpha of Alg. 2.3 below which a step is rejected, in (0, 1]; the line search
        runs inside every damped pass (nominal reference).

    Returns
    -------
    DampedResult

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Warns
    -----
    RuntimeWarning
        If the iteration stops without meeting ``rtol``.
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    mean0, cov0 = check.vector(mean0, "mean0", model.n_x), check.covariance(cov0, "cov0", model.n_x)
    filt = filter_for(filt, model)
    policy = (
        AffinePolicy.zero(cost.K, model.n_u, model.n_x)
        if policy is None
        else policy_for(policy, cost.K, model)
    )
    max_iterations = check.integer(max_iterations, "max_iterations", minimum=1)
    rtol = check.real_scalar(rtol, "rtol", low=0, low_open=True)
    mu_min = check.real_scalar(mu_min, "mu_min", low=0, low_open=True)
    mu_max = check.real_scalar(mu_max, "mu_max", low=mu_min)
    factor = check.real_scalar(factor, "factor", low=1, low_open=True)
    options = {
        "derivatives": check.choice(derivatives, "derivatives", ("analytic", "numdifftools")),
        "alpha_min": check.real_scalar(alpha_min, "alpha_min", low=0, high=1, low_open=True),
        "covariance_hessian": "exact",
    }
    w_points, beta = sigma_points(model.w.mean, model.w.cov, KAPPA)
    noise = draw_noise(
        model,
        mean0,
        cov0,
        cost.K,
        check.integer(n_cost_runs, "n_cost_runs", minimum=1),
        check.generator(rng),
    )

    def J(pol):
        return float(
            simulate(model, cost, mean0, cov0, MeanAffineController(model, pol), noise).costs.mean()
        )

    policies, costs, predicted, damping = [policy], [J(policy)], [], []
    mu, passes, status, ref = 0.0, 0, "max_iterations", None
    while passes < max_iterations:
        ref = ref or reference_trajectory(model, filt, policy, mean0, cov0)
        passes += 1
        try:
            new, value, _, _ = backward_pass(
                model, cost, filt, ref, policy, w_points, beta, damping=mu, **options
            )
            new_cost = J(new)
        except (IndefiniteStep, ValueError):
            new_cost = np.inf
        if not new_cost < costs[-1]:
            mu = max(mu_min, mu * factor)
            if mu > mu_max:
                status = "no_progress"
                break
            continue
        policy, ref = new, None
        (
            policies.append(new),
            costs.append(new_cost),
            predicted.append(value.at(mean0, cov0)),
            damping.append(mu),
        )
        mu = mu / factor if mu / factor >= mu_min else 0.0
        if costs[-2] - costs[-1] <= rtol * abs(costs[-2]):
            status = "converged"
            break
    messages = {
        "converged": f"the relative decrease of J met rtol = {rtol:g} after "
        f"{len(costs) - 1} accepted "
        f"steps ({passes} backward passes)",
        "no_progress": f"no damped step with mu <= mu_max = {mu_max:g} decreased J "
        f"({passes} passes)",
        "max_iterations": f"stopped after max_iterations = {max_iterations} backward passes",
    }
    result = DampedResult(
        policy=policy,
        policies=policies,
        costs=costs,
        predicted=predicted,
        iterations=len(costs) - 1,
        reference=reference_trajectory(model, filt, policy, mean0, cov0),
        converged=status == "converged",
        status=status,
        message=messages[status],
        passes=passes,
        damping=damping,
    )
    if not result.converged:
        warnings.warn(
            f"damped Algorithm 2.2 did not converge: {result.message}", RuntimeWarning, stacklevel=2
        )
    return result
