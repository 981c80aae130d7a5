"""Belief-space trajectory optimisation by statistical Taylor expansion (Sec. 2.5.2).

Algorithm 2.1 (reference trajectory), the backward pass of Algorithm 2.2 (Theorems 2.4,
2.5 and Algorithm 2.3 along the reference, from :mod:`asoc.belief.stage` and
:mod:`asoc.belief.improvement`) and the iteration of Algorithm 2.2 for the affine policy
u_k = L_k E{x_k} + d_k (2.18).
"""

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from ..result import IterativeResult
from .filters import KAPPA, sigma_points
from .improvement import affine_policy_value, improved_policy_value, line_search, policy_step
from .models import NonlinearModel, cost_for
from .policy import AffinePolicy, MeanAffineController, policy_for
from .simulate import draw_noise, simulate
from .stage import COVARIANCE_HESSIANS, StageProblem, filter_for, terminal_value

__all__ = ["Reference", "reference_trajectory", "TrajectoryOptimizationResult", "backward_pass",
           "IndefiniteStep", "optimize_belief_trajectory"]


@dataclass(frozen=True)
class Reference:
    """Reference trajectory {p_bar_{0:K}, u_bar_{0:K-1}} of Algorithm 2.1.

    Examples
    --------
    >>> ref = Reference([(np.zeros(1), np.eye(1))] * 2, np.zeros((1, 1)))
    >>> len(ref.estimates), ref.u_bar.shape
    (2, (1, 1))
    """

    estimates: list
    u_bar: np.ndarray

    def __post_init__(self):
        u_bar = check.real_array(self.u_bar, "u_bar", ndim=2)
        check.instance(self.estimates, (list, tuple), "estimates", "a list of estimates")
        if len(self.estimates) != u_bar.shape[0] + 1:
            raise ValueError(f"estimates: expected {u_bar.shape[0] + 1} estimates "
                             f"(one more than inputs), found {len(self.estimates)}")
        object.__setattr__(self, "u_bar", u_bar)


def reference_trajectory(model, filt, policy: AffinePolicy, mean0, cov0, mode="nominal",
                         rng=None) -> Reference:
    """Algorithm 2.1: simulate the reference estimates under ``policy``.

    ``mode="nominal"`` uses the means E{x_k}, E{w_k}, E{v_k} (the variant the thesis
    mentions after Alg. 2.1); ``mode="sampled"`` draws one sample of each from ``rng``.

    Parameters
    ----------
    model : NonlinearModel
    filt : BeliefFilter
        E.g. :class:`~asoc.belief.UKF` or :class:`~asoc.belief.ParticleFilter` (any
        :class:`~asoc.belief.BeliefFilter`).
    policy : AffinePolicy
    mean0, cov0 : array_like
        Initial estimate, (n_x,) and (n_x, n_x) positive semi-definite.
    mode : {"nominal", "sampled"}
    rng : numpy.random.Generator, optional
        Needed for ``mode="sampled"``.

    Returns
    -------
    Reference

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, ``mode`` is unknown, or ``rng`` is
        not a Generator when sampling.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> from asoc.belief import UKF
    >>> ref = reference_trajectory(ex.model, UKF(ex.model), AffinePolicy.zero(3, 2, 2), ex.mean0,
    ...                            ex.cov0)
    >>> len(ref.estimates), ref.u_bar.shape
    (4, (3, 2))
    """
    model = check.instance(model, NonlinearModel, "model")
    filt = filter_for(filt, model)
    policy = policy_for(policy, check.instance(policy, AffinePolicy, "policy").L.shape[0], model)
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    mode = check.choice(mode, "mode", ("nominal", "sampled"))
    if mode == "sampled":
        rng = check.generator(rng)
    return _reference_trajectory(model, filt, policy, mean0, cov0, mode, rng)


def _reference_trajectory(model, filt, policy, mean0, cov0, mode, rng):
    est = filt.initial(mean0, cov0)
    estimates, u_bar = [est], []
    for k in range(policy.L.shape[0]):
        u = policy(k, filt.mean(est))
        if mode == "nominal":
            x, w, v = filt.mean(est), model.w.mean, model.v.mean
        else:
            mix = filt.mixture(est)
            x = mix.points[rng.choice(mix.weights.size, p=mix.weights)]
            w, v = model.w.sample(rng), model.v.sample(rng)
        y = model.h(model.a(x, u, w), v)
        est = filt.step(est, u, y)
        estimates.append(est), u_bar.append(u)
    return Reference(estimates, np.array(u_bar))


@dataclass(kw_only=True)
class TrajectoryOptimizationResult(IterativeResult):
    """Result of Algorithm 2.2 (belief-space trajectory optimisation, statistical Taylor expansion).

    ``policy`` the final affine policy; ``policies`` the policy of every iteration
    (policies[0] the initial one); ``costs`` J of each policy in ``policies`` (Monte Carlo
    with common random numbers); ``predicted`` the value approximation V_0(p_0) of each
    new policy; ``eps`` the line-search steps (iterations x K); ``rejected`` how many time
    steps kept their policy; ``iterations``; ``reference`` the last reference trajectory;
    ``converged``, ``status`` and ``message`` say why the iteration stopped (``converged``:
    the relative change of J met ``rtol``; ``max_iterations``; ``diverged``: J became
    non-finite; ``linalg_error``: a linear-algebra step failed).

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = optimize_belief_trajectory(ex.model, ex.cost, ex.mean0, ex.cov0,
    ...                                  rng=np.random.default_rng(0), n_cost_runs=10)
    >>> res.status, res.iterations, round(res.costs[-1], 2) < round(res.costs[0], 2)
    ('converged', 2, True)
    """

    policy: AffinePolicy
    policies: list
    costs: list
    predicted: list = field(default_factory=list)
    eps: list = field(default_factory=list)
    rejected: list = field(default_factory=list)
    iterations: int = 0
    reference: Reference | None = None


def backward_pass(model, cost, filt, ref: Reference, policy: AffinePolicy, w_points, beta,
                  derivatives="analytic", alpha_min=2.0 ** -10, covariance_hessian="psd",
                  covariance_term=True, damping=None):
    """Steps 3-8 of Algorithm 2.2 along ``ref``; returns (new policy, V_0, eps, rejected).

    Parameters
    ----------
    model, cost : NonlinearModel and QuadraticCost
    filt : BeliefFilter
        Its Dirac mixture is the expansion point (:class:`~asoc.belief.BeliefFilter`).
    ref : Reference
        The reference trajectory (Alg. 2.1).
    policy : AffinePolicy
        The current policy.
    w_points, beta : array_like, (R, n_w) and (R,)
        Process-noise points and weights.
    derivatives : {"analytic", "numdifftools"}
    alpha_min : float
        Line-search threshold of Alg. 2.3, in (0, 1].
    covariance_hessian : {"psd", "exact", "shift"}
    covariance_term : bool
        False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.
    damping : float, optional
        Levenberg-Marquardt damping mu >= 0 added to every R_k^i; then an indefinite
        R~_k + mu I raises :class:`IndefiniteStep` instead of keeping the old policy.

    Returns
    -------
    policy : AffinePolicy
    V0 : Value
    eps : numpy.ndarray
    rejected : int

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or an option is unknown.

    Examples
    --------
    >>> from asoc.belief import UKF, landmark_example, sigma_points
    >>> ex = landmark_example(K=2)
    >>> filt, policy = UKF(ex.model), AffinePolicy.zero(2, 2, 2)
    >>> ref = reference_trajectory(ex.model, filt, policy, ex.mean0, ex.cov0)
    >>> w, beta = sigma_points(ex.model.w.mean, ex.model.w.cov)
    >>> new, V0, eps, rejected = backward_pass(ex.model, ex.cost, filt, ref, policy, w, beta)
    >>> eps.tolist(), rejected, new.d.round(2).tolist()
    ([1.0, 1.0], 0, [[0.0, 2.73], [0.0, 2.73]])
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    filt = filter_for(filt, model)
    check.instance(ref, Reference, "ref")
    K = ref.u_bar.shape[0]
    if K != cost.K or len(ref.estimates) != K + 1:
        raise ValueError(f"ref: expected a reference of horizon cost.K = {cost.K}, "
                         f"found {K} inputs and {len(ref.estimates)} estimates")
    policy = policy_for(policy, K, model)
    w_points = check.real_array(w_points, "w_points", shape=(None, model.w.dim))
    beta = check.probability_vector(beta, "beta", w_points.shape[0])
    if damping is not None:
        damping = check.real_scalar(damping, "damping", low=0)
    return _backward_pass(model, cost, filt, ref, policy, w_points, beta, *_options(
        derivatives, alpha_min, covariance_hessian, covariance_term), damping=damping)


def _options(derivatives, alpha_min, covariance_hessian, covariance_term):
    return (check.choice(derivatives, "derivatives", ("analytic", "numdifftools")),
            check.real_scalar(alpha_min, "alpha_min", low=0, high=1, low_open=True),
            check.choice(covariance_hessian, "covariance_hessian", COVARIANCE_HESSIANS),
            check.boolean(covariance_term, "covariance_term"))


class IndefiniteStep(np.linalg.LinAlgError):
    """R~_k + mu I is not positive definite at some step of a damped backward pass."""


def _backward_pass(model, cost, filt, ref, policy, w_points, beta, derivatives, alpha_min,
                   covariance_hessian, covariance_term, damping=None):
    """Steps 3-8 of Alg. 2.2; ``damping`` mu adds mu I to every R_k^i (so to R~_k) and raises
    :class:`IndefiniteStep` where R~_k + mu I is still indefinite (the damped variant).
    """
    K = ref.u_bar.shape[0]
    value = terminal_value(cost, filt.mixture(ref.estimates[K]))
    L_new, d_new = policy.L.copy(), policy.d.copy()
    eps_k, rejected = np.zeros(K), 0
    for k in range(K - 1, -1, -1):
        stage = StageProblem(model, cost, filt, ref.estimates[k], value, w_points, beta,
                             covariance_hessian, covariance_term)
        exp = stage.expansion(ref.u_bar[k], derivatives)
        if damping is not None:
            exp = replace(exp, R=exp.R + damping * np.eye(exp.R.shape[-1]))
        lam = np.linalg.eigvalsh(exp.tilde[3]).min()
        if not lam > 0 and damping is not None:
            raise IndefiniteStep(f"R~_{k} + {damping:g} I is indefinite "
                                 f"(minimal eigenvalue {lam:.3g})")
        if not lam > 0:
            warnings.warn(f"Assumption 2.3 fails at k={k}: R~_k is not positive definite "
                          f"(minimal eigenvalue {lam:.3g}); keeping the policy", RuntimeWarning,
                          stacklevel=3)
            accepted, eps = False, 0.0
        else:
            ls = line_search(stage, exp, ref.u_bar[k], filt.mean(ref.estimates[k]), alpha_min)
            accepted, eps = ls.accepted, ls.eps
        if accepted:
            L_new[k], d_new[k] = policy_step(exp, ref.u_bar[k], eps)
            value = improved_policy_value(exp, eps)
        else:
            rejected += 1
            value = affine_policy_value(exp, policy.L[k], policy.d[k], ref.u_bar[k])
        eps_k[k] = eps if accepted else 0.0
    return AffinePolicy(L_new, d_new), value, eps_k, rejected


def optimize_belief_trajectory(model, cost, mean0, cov0, filt=None, policy=None, max_iterations=50,
                               rtol=1e-4, n_cost_runs=200, rng=None, derivatives="analytic",
                               reference_mode="nominal", alpha_min=2.0 ** -10,
                               covariance_hessian="psd", covariance_term=True,
                               progress=False) -> TrajectoryOptimizationResult:
    """Algorithm 2.2: belief-space trajectory optimisation by statistical Taylor expansion.

    Iterates the reference trajectory (Alg. 2.1) and the backward pass (Thms. 2.4-2.5,
    line search Alg. 2.3) for the affine policy u_k = L_k E{x_k} + d_k (2.18).

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
        Iteration limit, >= 1.
    rtol : float
        Stop when abs(J^[eta+1] - J^[eta]) <= rtol abs(J^[eta]) (Step 9), rtol > 0.
    n_cost_runs : int
        J^[eta] is the mean cost of ``n_cost_runs`` (>= 1) closed-loop runs whose random draws
        are the same in every iteration (common random numbers from ``rng``).
    rng : numpy.random.Generator
        The source of those draws (and of the sampled reference).
    derivatives : {"analytic", "numdifftools"}
        Model and cost derivatives where available, or numerical ones.
    reference_mode : {"nominal", "sampled"}
        The reference of Alg. 2.1; "sampled" draws from ``rng``.
    alpha_min : float
        The constant alpha of Alg. 2.3 below which a step is rejected, in (0, 1].
    covariance_hessian : {"psd", "exact", "shift"}
        The covariance term's Hessian (default "psd"), see ``StageProblem._covariance_hessian``.
    covariance_term : bool
        False drops 1/2 tr[S_{k+1} C_{k+1}(u)] from phi_k (2.13): no dual effect.
    progress : bool
        Show a progress bar.

    Returns
    -------
    TrajectoryOptimizationResult
        The policy, the policies and costs per iteration, line-search steps, and why it stopped.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Warns
    -----
    RuntimeWarning
        If the iteration stops without meeting ``rtol``.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=3)
    >>> res = optimize_belief_trajectory(ex.model, ex.cost, ex.mean0, ex.cov0,
    ...                                  rng=np.random.default_rng(0), n_cost_runs=10)
    >>> res.converged, res.iterations, res.policy.L.shape
    (True, 2, (3, 2, 2))
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    K = cost.K
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    filt = filter_for(filt, model)
    policy = (AffinePolicy.zero(K, model.n_u, model.n_x) if policy is None
              else policy_for(policy, K, model))
    max_iterations = check.integer(max_iterations, "max_iterations", minimum=1)
    rtol = check.real_scalar(rtol, "rtol", low=0, low_open=True)
    n_cost_runs = check.integer(n_cost_runs, "n_cost_runs", minimum=1)
    rng = check.generator(rng)
    reference_mode = check.choice(reference_mode, "reference_mode", ("nominal", "sampled"))
    options = _options(derivatives, alpha_min, covariance_hessian, covariance_term)
    progress = check.boolean(progress, "progress")
    w_points, beta = sigma_points(model.w.mean, model.w.cov, KAPPA)
    noise = draw_noise(model, mean0, cov0, K, n_cost_runs, rng)

    def J(pol):
        run = simulate(model, cost, mean0, cov0, MeanAffineController(model, pol), noise)
        return float(run.costs.mean())

    policies, costs, predicted, eps_all, rejected_all = [policy], [J(policy)], [], [], []
    status, ref, error = "max_iterations", None, None
    for _ in progress_bar(range(max_iterations), progress, desc="Alg. 2.2"):
        try:
            ref = _reference_trajectory(model, filt, policy, mean0, cov0, reference_mode, rng)
            policy, value, eps, rejected = _backward_pass(model, cost, filt, ref, policy, w_points,
                                                          beta, *options)
        except np.linalg.LinAlgError as err:
            status, error = "linalg_error", err
            break
        except ValueError as err:
            # the inputs are checked: a non-finite intermediate (value, policy)
            status, error = "diverged", err
            break
        policies.append(policy), costs.append(J(policy))
        eps_all.append(eps), rejected_all.append(rejected)
        predicted.append(value.at(mean0, cov0))
        if not np.isfinite(costs[-1]):
            status = "diverged"
            break
        if abs(costs[-1] - costs[-2]) <= rtol * abs(costs[-2]):
            status = "converged"
            break
    iterations = len(costs) - 1
    messages = {
        "converged": lambda: f"the relative change of J, {_change(costs):.3g}, met rtol = {rtol:g} "
                             f"after {iterations} iterations",
        "max_iterations": lambda: f"stopped after max_iterations = {max_iterations} with relative "
                                  f"change of J {_change(costs):.3g} > rtol = {rtol:g}",
        "diverged": lambda: (f"J became non-finite ({costs[-1]}) at iteration {iterations}"
                             if error is None else
                             f"an iterate became non-finite at iteration {iterations + 1}: "
                             f"{error}"),
        "linalg_error": lambda: (f"a linear-algebra step failed at iteration {iterations + 1}: "
                                 f"{error}"),
    }
    result = TrajectoryOptimizationResult(
        policy=policy, policies=policies, costs=costs, predicted=predicted, eps=eps_all,
        rejected=rejected_all, iterations=iterations, reference=ref,
        converged=status == "converged", status=status, message=messages[status]())
    if not result.converged:
        warnings.warn(f"Algorithm 2.2 did not converge: {result.message}", RuntimeWarning,
                      stacklevel=2)
    return result


def _change(costs):
    if len(costs) > 1 and costs[-2] != 0:
        return abs(costs[-1] - costs[-2]) / abs(costs[-2])
    return float("inf")
