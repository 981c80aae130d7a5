"""An independent covariance-aware planner for the example of Sec. 2.5.3, and the bend of a path.

Sec. 2.5.3 says that both controllers "deviate towards the landmark" because the cost
(2.20), written in the mean and covariance of a Gaussian estimate, rewards localisation.
Whether the *model* rewards such a detour can be decided without Alg. 2.2: propagate an
EKF belief along an open-loop input sequence (nominal means, covariances by the EKF
Riccati step with the state-dependent range noise) and minimise (2.20) over the whole
sequence with a quasi-Newton method from several starts. Nothing here uses the companion's
filters, models or Alg. 2.2: only the printed model, written out below.
"""

import numpy as np
from scipy.optimize import minimize

from .. import validation as check
from .models import LandmarkExample

__all__ = ["bend_toward_landmark", "ekf_belief_plan", "belief_cost", "covariance_aware_optimum"]


def bend_toward_landmark(means, start, target, landmark) -> float:
    """Largest signed distance of a path from the line start-target, toward the landmark (Fig. 2.3).

    Positive on the landmark's side of the line. For Sec. 2.5.3 (start [-5, 3], target [0, 3],
    landmark [-3, 0]) this is max_k (3 - x_2).

    Parameters
    ----------
    means : array_like, (N, 2)
        The path (e.g. the means of a planned belief trajectory).
    start, target, landmark : array_like, (2,)

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If a point is not a finite 2-vector, start equals target or the landmark lies on the line.

    Examples
    --------
    >>> round(bend_toward_landmark([[-5, 3], [-3, 2.1], [0, 3]], [-5, 3], [0, 3], [-3, 0]), 9)
    0.9
    """
    path = check.real_array(means, "means", shape=(None, 2))
    start, target = check.vector(start, "start", 2), check.vector(target, "target", 2)
    landmark = check.vector(landmark, "landmark", 2)
    direction = target - start
    if not np.linalg.norm(direction) > 0:
        raise ValueError("start, target: expected two different points")
    normal = np.array([-direction[1], direction[0]]) / np.linalg.norm(direction)
    side = float(normal @ (landmark - start))
    if side == 0.0:
        raise ValueError("landmark: lies on the line from start to target, no side to bend toward")
    return float(np.max((path - start) @ (np.sign(side) * normal)))


def ekf_belief_plan(u, example: LandmarkExample, noise_gain=0.5, range_noise=0.1):
    """Nominal EKF belief (means, covariances) of Sec. 2.5.3 along the open-loop inputs ``u``.

    mu_{k+1} = mu_k + u_k (the expected innovation is zero), P = C_k + g^2 I,
    C_{k+1} = P - P h h^T P / (h^T P h + r^2 ||mu_{k+1} - x^||^2), h the unit vector from the
    landmark x^ to mu_{k+1}: the EKF of y = ||x - x^|| + v, v ~ N(0, r^2 ||x - x^||^2).

    Parameters
    ----------
    u : array_like, (..., K, 2)
        One or a batch of input sequences.
    example : LandmarkExample
        Start, prior and landmark (:func:`~asoc.belief.landmark_example`).
    noise_gain, range_noise : float
        g (0.5) and r (0.1) as printed.

    Returns
    -------
    means : numpy.ndarray, (..., K + 1, 2)
    covs : numpy.ndarray, (..., K + 1, 2, 2)

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> means, covs = ekf_belief_plan(np.ones((1, 2)), landmark_example(K=1))
    >>> means[-1].tolist(), round(float(np.trace(covs[-1])), 4)
    ([-4.0, 4.0], 0.3972)
    """
    u = check.real_array(u, "u")
    if u.ndim < 2 or u.shape[-1] != 2:
        raise ValueError(f"u: expected input sequences of shape (..., K, 2), found {u.shape}")
    example = check.instance(example, LandmarkExample, "example")
    batch = u.shape[:-2]
    mean = np.broadcast_to(np.asarray(example.mean0, dtype=float), batch + (2,))
    cov = np.broadcast_to(np.asarray(example.cov0, dtype=float), batch + (2, 2))
    means, covs = [mean], [cov]
    for k in range(u.shape[-2]):
        mean = mean + u[..., k, :]
        P = cov + noise_gain**2 * np.eye(2)
        offset = mean - example.landmark
        dist = np.linalg.norm(offset, axis=-1)
        h = offset / dist[..., None]
        Ph = np.einsum("...ij,...j->...i", P, h)
        denominator = np.einsum("...i,...i->...", h, Ph) + (range_noise * dist) ** 2
        cov = P - Ph[..., :, None] * Ph[..., None, :] / denominator[..., None, None]
        means.append(mean), covs.append(cov)
    return np.stack(means, axis=-2), np.stack(covs, axis=-3)


def belief_cost(u, example: LandmarkExample, covariance=True, **noise):
    """Cost (2.20) of the nominal EKF belief along ``u`` (K, 2) or a batch (..., K, 2).

    sum_{k<K} (||mu_k - x_T||^2 + tr C_k + 0.1 ||u_k||^2) + ||mu_K - x_T||^2 + tr C_K with the
    weights of ``example.cost``; ``covariance=False`` drops the tr C_k terms.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> ex = landmark_example(K=1)
    >>> round(float(belief_cost(np.array([[5.0, 0.0]]), ex, covariance=False)), 6)  # 25 + 2.5
    27.5
    """
    u = check.real_array(u, "u")
    means, covs = ekf_belief_plan(u, example, **noise)
    c = example.cost
    err = means - c.x_target
    total = (
        np.einsum("...ki,ij,...kj->...", err[..., :-1, :], c.Q, err[..., :-1, :])
        + np.einsum("...i,ij,...j->...", err[..., -1, :], c.Q_K, err[..., -1, :])
        + np.einsum("...ki,ij,...kj->...", u, c.R, u)
    )
    if covariance:
        total = (
            total
            + np.einsum("ij,...kji->...", c.Q, covs[..., :-1, :, :])
            + np.einsum("ij,...ji->...", c.Q_K, covs[..., -1, :, :])
        )
    return total


def _cost_and_gradient(z, example, covariance, noise, step=1e-6):
    """(2.20) of the flat input sequence z and its central-difference gradient, in one batch."""
    K = z.size // 2
    probes = z + np.concatenate(
        [step * np.eye(z.size), -step * np.eye(z.size), np.zeros((1, z.size))]
    )
    values = belief_cost(probes.reshape(-1, K, 2), example, covariance, **noise)
    return float(values[-1]), (values[: z.size] - values[z.size : -1]) / (2 * step)


def covariance_aware_optimum(
    example: LandmarkExample, offsets=(0.0, -0.5, -1.0, -2.0, 1.0), gtol=1e-6, **noise
) -> dict:
    """Minimise (2.20) over the whole input sequence, EKF belief, BFGS from several starts.

    Starts: the certainty-equivalent plan (minimiser of (2.20) without the tr C_k terms, the
    straight line) and that plan with its middle input shifted sideways by each of
    ``offsets`` (and back at the next step), so detours on both sides are tried.

    Parameters
    ----------
    example : LandmarkExample
        The model, cost and initial belief of Sec. 2.5.3.
    offsets : array_like, (m,)
        Sideways shifts of the middle input of the straight plan, one start each (finite, at
        least one).
    gtol : float
        BFGS's gradient tolerance, > 0.
    **noise
        ``noise_gain`` and ``range_noise`` of ``ekf_belief_plan``.

    Returns
    -------
    dict
        ``u`` (K, 2), ``means``, ``covs`` of the best optimum, ``cost`` (2.20) there,
        ``cost_straight`` (2.20) of the certainty-equivalent plan, ``bend`` and
        ``bend_straight`` (:func:`bend_toward_landmark`), ``gradient_norm`` at the optimum and
        ``costs`` of every start's optimum.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> res = covariance_aware_optimum(landmark_example(K=4), offsets=(0.0,))
    >>> bool(res["cost"] <= res["cost_straight"]), res["u"].shape
    (True, (4, 2))
    """
    example = check.instance(example, LandmarkExample, "example")
    offsets = check.real_array(offsets, "offsets", ndim=1)
    if offsets.size == 0:
        raise ValueError("offsets: expected at least one shift (one start each), found none")
    gtol = check.real_scalar(gtol, "gtol", low=0, low_open=True)
    K = example.cost.K
    zero = np.zeros(2 * K)
    straight = minimize(
        _cost_and_gradient,
        zero,
        args=(example, False, noise),
        jac=True,
        method="BFGS",
        options={"gtol": gtol},
    ).x
    starts = []
    for offset in offsets:
        start = straight.reshape(K, 2).copy()
        start[K // 2, 1] += offset
        if K // 2 + 1 < K:
            start[K // 2 + 1, 1] -= offset
        starts.append(start.ravel())
    runs = [
        minimize(
            _cost_and_gradient,
            s,
            args=(example, True, noise),
            jac=True,
            method="BFGS",
            options={"gtol": gtol},
        )
        for s in starts
    ]
    best = min(runs, key=lambda r: r.fun)
    u = best.x.reshape(K, 2)
    means, covs = ekf_belief_plan(u, example, **noise)
    line = (example.mean0, example.cost.x_target, example.landmark)
    return {
        "u": u,
        "means": means,
        "covs": covs,
        "cost": float(best.fun),
        "cost_straight": float(belief_cost(straight.reshape(K, 2), example, True, **noise)),
        "bend": bend_toward_landmark(means, *line),
        "bend_straight": bend_toward_landmark(
            ekf_belief_plan(straight.reshape(K, 2), example, **noise)[0], *line
        ),
        "gradient_norm": float(np.max(np.abs(best.jac))),
        "costs": [float(r.fun) for r in runs],
    }
