"""Closed-loop simulation of (2.1)-(2.2) under a controller, vectorised over runs.

The controller keeps its own estimate (UKF or EKF) and maps it to an input
(:class:`~asoc.belief.MeanAffineController`, :class:`~asoc.belief.BeliefAffineController`). Random
draws come from one seeded Generator; :func:`draw_noise` gives the same draws to
several controllers (common random numbers), so their costs can be compared run by run.
"""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from .models import GaussianNoise, NonlinearModel, cost_for

__all__ = ["Noise", "draw_noise", "ClosedLoop", "simulate"]


@dataclass(frozen=True)
class Noise:
    """The random draws of N runs: initial states, process and measurement noises.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=4)
    >>> noise = draw_noise(ex.model, ex.mean0, ex.cov0, 4, 10, np.random.default_rng(0))
    >>> noise.x0.shape, noise.w.shape, noise.v.shape
    ((10, 2), (10, 4, 2), (10, 4, 1))
    """

    x0: np.ndarray   # (N, n_x)
    w: np.ndarray    # (N, K, n_w)
    v: np.ndarray    # (N, K, n_v), v[:, k] enters y_{k+1}


def draw_noise(model, mean0, cov0, K: int, n_runs: int, rng) -> Noise:
    """Draw x_0 ~ N(mean0, cov0), w_k ~ p^w, v_{k+1} ~ p^v for ``n_runs`` runs of (2.1)-(2.2).

    Parameters
    ----------
    model : NonlinearModel
    mean0, cov0 : array_like
        Gaussian initial state, (n_x,) and (n_x, n_x) PSD.
    K : int
        Horizon, >= 1.
    n_runs : int
        Number of runs, >= 1.
    rng : numpy.random.Generator
        The only source of random numbers.

    Returns
    -------
    Noise
        x0 (n_runs, n_x), w (n_runs, K, n_w), v (n_runs, K, n_v).

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type, shape or range.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example()
    >>> draw_noise(ex.model, ex.mean0, ex.cov0, 20, 3, np.random.default_rng(0)).w.shape
    (3, 20, 2)
    """
    model = check.instance(model, NonlinearModel, "model")
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    K = check.integer(K, "K", minimum=1)
    n_runs = check.integer(n_runs, "n_runs", minimum=1)
    return _draw_noise(model, mean0, cov0, K, n_runs, check.generator(rng))


def _draw_noise(model, mean0, cov0, K, n_runs, rng):
    x0 = GaussianNoise(mean0, cov0).sample(rng, n_runs)
    return Noise(x0, model.w.sample(rng, (n_runs, K)), model.v.sample(rng, (n_runs, K)))


@dataclass(frozen=True)
class ClosedLoop:
    """Simulated runs: true states x (N, K+1, n), estimates (means, covs), inputs u, costs (N,).

    Examples
    --------
    >>> from asoc.belief import AffinePolicy, MeanAffineController, landmark_example
    >>> ex = landmark_example(K=2)
    >>> noise = draw_noise(ex.model, ex.mean0, ex.cov0, 2, 5, np.random.default_rng(0))
    >>> controller = MeanAffineController(ex.model, AffinePolicy.zero(2, 2, 2))
    >>> run = simulate(ex.model, ex.cost, ex.mean0, ex.cov0, controller, noise)
    >>> run.x.shape, run.u.shape, run.costs.shape
    ((5, 3, 2), (5, 2, 2), (5,))
    """

    x: np.ndarray
    means: np.ndarray
    covs: np.ndarray
    u: np.ndarray
    costs: np.ndarray


def simulate(model, cost, mean0, cov0, controller, noise: Noise) -> ClosedLoop:
    """Closed loop of (2.1)-(2.2) under ``controller`` for the draws ``noise``, costs (2.3)/(2.19).

    Parameters
    ----------
    model : NonlinearModel
    cost : QuadraticCost
        Its horizon ``K`` must equal the draws' horizon.
    mean0, cov0 : array_like
        Initial estimate given to the controller's filter.
    controller : object
        E.g. :class:`BeliefAffineController` or :class:`MeanAffineController` (methods
        ``control(k, mean, cov)`` and ``step(mean, cov, u, y)``).
    noise : Noise
        Draws from :func:`draw_noise` (common random numbers across controllers).

    Returns
    -------
    ClosedLoop
        Per-run costs and trajectories.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or shape, or the controller's horizon is shorter
        than the draws'.

    Examples
    --------
    >>> from asoc.belief import AffinePolicy, MeanAffineController, landmark_example
    >>> ex = landmark_example(K=3)
    >>> noise = draw_noise(ex.model, ex.mean0, ex.cov0, 3, 100, np.random.default_rng(0))
    >>> zero = MeanAffineController(ex.model, AffinePolicy.zero(3, 2, 2))
    >>> round(float(simulate(ex.model, ex.cost, ex.mean0, ex.cov0, zero, noise).costs.mean()), 1)
    106.3
    """
    model = check.instance(model, NonlinearModel, "model")
    cost = cost_for(cost, model)
    mean0 = check.vector(mean0, "mean0", model.n_x)
    cov0 = check.covariance(cov0, "cov0", model.n_x)
    check.instance(noise, Noise, "noise")
    N, K = noise.w.shape[:2]
    if (noise.x0.shape != (N, model.n_x) or noise.w.shape != (N, K, model.w.dim)
            or noise.v.shape != (N, K, model.v.dim) or K != cost.K):
        raise ValueError(f"noise: expected draws x0 (N, {model.n_x}), "
                         f"w (N, {cost.K}, {model.w.dim}), v (N, {cost.K}, {model.v.dim}), "
                         f"found {noise.x0.shape}, {noise.w.shape}, {noise.v.shape}")
    for method in ("control", "step"):
        if not callable(getattr(controller, method, None)):
            raise TypeError("controller: expected an object with control(k, mean, cov) and "
                            "step(mean, cov, u, y), found "
                            f" {type(controller).__name__}")
    if getattr(controller, "horizon", K) < K:
        raise ValueError(f"controller: expected a horizon >= {K} (the draws'), "
                         f"found {controller.horizon}")
    return _simulate(model, cost, mean0, cov0, controller, noise)


def _simulate(model, cost, mean0, cov0, controller, noise):
    N, K = noise.w.shape[:2]
    x = noise.x0
    mean = np.broadcast_to(np.asarray(mean0, dtype=float), x.shape).copy()
    cov = np.broadcast_to(np.asarray(cov0, dtype=float), x.shape + x.shape[-1:]).copy()
    xs, means, covs, us = [x], [mean], [cov], []
    total = np.zeros(N)
    for k in range(K):
        u = controller.control(k, mean, cov)
        total += cost.stage(x, u)
        x = model.a(x, u, noise.w[:, k])
        y = model.h(x, noise.v[:, k])
        mean, cov = controller.step(mean, cov, u, y)
        xs.append(x), means.append(mean), covs.append(cov), us.append(u)
    total += cost.terminal(x)
    return ClosedLoop(np.stack(xs, 1), np.stack(means, 1), np.stack(covs, 1), np.stack(us, 1),
                      total)
