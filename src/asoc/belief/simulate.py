"""Closed-loop simulation of (2.1)-(2.2) under a controller, vectorised over runs.

The controller keeps its own estimate (UKF or EKF) and maps it to an input. Random
draws come from one seeded Generator; :func:`draw_noise` gives the same draws to
several controllers (common random numbers), so their costs can be compared run by run.
"""

from dataclasses import dataclass

import numpy as np

from ._validate import check_rng
from .filters import UKF, ekf_step
from .models import GaussianNoise


@dataclass(frozen=True)
class Noise:
    """The random draws of N runs: initial states, process and measurement noises."""

    x0: np.ndarray   # (N, n_x)
    w: np.ndarray    # (N, K, n_w)
    v: np.ndarray    # (N, K, n_v), v[:, k] enters y_{k+1}


def draw_noise(model, mean0, cov0, K: int, n_runs: int, rng) -> Noise:
    """Draw x_0 ~ N(mean0, cov0), w_k ~ p^w, v_{k+1} ~ p^v for ``n_runs`` runs.

    Parameters
    ----------
    model : NonlinearModel
    mean0, cov0 : array_like
        Gaussian initial state.
    K : int
        Horizon.
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
    ValueError
        If ``n_runs`` < 1 or ``rng`` is not a Generator.
    """
    rng = check_rng(rng)
    if not isinstance(n_runs, (int, np.integer)) or n_runs < 1:
        raise ValueError(f"n_runs: expected an integer >= 1, found {n_runs!r}")
    x0 = GaussianNoise(mean0, cov0).sample(rng, n_runs)
    return Noise(x0, model.w.sample(rng, (n_runs, K)), model.v.sample(rng, (n_runs, K)))


class MeanAffineController:
    """u_k = L_k E{x_k} + d_k (eq. 2.18) with the UKF estimate (the proposed controller)."""

    def __init__(self, model, policy, kappa=None):
        self.filter = UKF(model) if kappa is None else UKF(model, kappa)
        self.policy = policy

    def control(self, k, mean, cov):
        return mean @ self.policy.L[k].T + self.policy.d[k]

    def step(self, mean, cov, u, y):
        return self.filter.step((mean, cov), u, y)


class BeliefAffineController:
    """u_k = u_bar_k + L_k (b_k - b_bar_k) with the EKF belief b = (mean, vec sqrt cov) [159]."""

    def __init__(self, model, result):
        self.model, self.result = model, result

    def control(self, k, mean, cov):
        from .vdberg import belief_vector
        r = self.result
        return r.u_bar[k] + (belief_vector(mean, cov) - r.b_bar[k]) @ r.L[k].T

    def step(self, mean, cov, u, y):
        return ekf_step(self.model, mean, cov, u, y)


@dataclass(frozen=True)
class ClosedLoop:
    """Simulated runs: true states x (N, K+1, n), estimates (means, covs), inputs u, costs (N,)."""

    x: np.ndarray
    means: np.ndarray
    covs: np.ndarray
    u: np.ndarray
    costs: np.ndarray


def simulate(model, cost, mean0, cov0, controller, noise: Noise) -> ClosedLoop:
    """Run ``controller`` in closed loop for the draws ``noise``; costs by (2.3)/(2.19).

    Parameters
    ----------
    model : NonlinearModel
    cost : QuadraticCost
    mean0, cov0 : array_like
        Initial estimate given to the controller's filter.
    controller : object
        E.g. :class:`BeliefAffineController` or :class:`MeanAffineController`.
    noise : Noise
        Draws from :func:`draw_noise` (common random numbers across controllers).

    Returns
    -------
    ClosedLoop
        Per-run costs and trajectories.

    Raises
    ------
    ValueError
        If the array shapes are inconsistent (raised by NumPy); nothing else is validated here.
    """
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
    return ClosedLoop(np.stack(xs, 1), np.stack(means, 1), np.stack(covs, 1), np.stack(us, 1), total)
