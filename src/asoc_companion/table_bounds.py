"""Certified evidence that Tables 3.2 and 3.3 cannot come from their printed settings (findings).

Table 3.3 prints *medians* of J/K, so an expected-cost bound says nothing about them by itself.
The argument here is per sample: for one realisation of (x_0, theta_0..K-1, w_0..K-1), every
controller applies some inputs u_0..u_{K-1}, and its cost is at least the minimum of the
deterministic LQ cost over all input sequences, the *clairvoyant* cost (known modes and
disturbances). Pointwise domination orders every quantile, so the median of every controller's
J/K is at least the median of the clairvoyant J/K. That median is estimated by Monte Carlo with
a distribution-free lower confidence bound (an order statistic, binomial tail 1e-6).

Table 3.2: for a linear controller, E{J | x_0} - E{J | 0} = x_0^T Pi x_0 exactly, with Pi from
the closed loop's cost recursion, whatever the noise; and the expected cost at x_0 = 0 is
tr[Gamma_T W] for the noise covariance W, so the ordering of two transition matrices over
every W is decided by the eigenvalues of Gamma_T2 - Gamma_T1.
"""

import numpy as np
import scipy.stats

from asoc.mjls import successor_average

__all__ = ["CONFIDENCE_TAIL", "clairvoyant_costs", "clairvoyant_minimum", "median_lower_bound",
           "table_3_3_bounds", "transient_gap", "noise_weight", "monte_carlo_gap"]


CONFIDENCE_TAIL = 1e-6     # P(the lower bound exceeds the true median) <= this


def _modes(rng, mu0, T, runs, horizon):
    theta = np.empty((horizon, runs), dtype=np.intp)
    theta[0] = rng.choice(len(mu0), size=runs, p=mu0)
    cumulative = np.cumsum(T, axis=1)
    for k in range(1, horizon):
        u = rng.random(runs)
        theta[k] = np.minimum((u[:, None] > cumulative[theta[k - 1]]).sum(axis=1), len(T) - 1)
    return theta


def clairvoyant_costs(sys, mean0, cov0, mu0, horizon, runs, rng, noise_scale=1.0):
    """Per run: the minimum over all input sequences of sum_k (x^T Q x + u^T R u) + x_K^T Q x_K for
    the run's own modes, x_0 and disturbances d_k = noise_scale H_{theta_k} w_k (a lower bound on
    the cost of every controller in that run). Backward recursion V_k(x) = x^T P_k x + 2 p_k^T x +
    c_k, batched over runs.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> J = clairvoyant_costs(sec373_system(1), SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0, 100, 200,
    ...                       np.random.default_rng(0), noise_scale=0.0)
    >>> bool(np.all(J > 0))
    True
    """
    theta = _modes(rng, mu0, sys.T, runs, horizon)
    n = sys.nx
    start = theta[0]
    x0 = mean0[start] + np.einsum("rab,rb->ra",
                                  np.linalg.cholesky(cov0 + 1e-300 * np.eye(n))[start],
                                  rng.standard_normal((runs, n)))
    draws = rng.standard_normal((horizon, runs, sys.nw))
    d = noise_scale * np.einsum("krab,krb->kra", sys.H[theta], draws)
    return clairvoyant_minimum(sys, theta, _final_modes(rng, theta[-1], sys.T), x0, d)


def clairvoyant_minimum(sys, theta, final_mode, x0, d):
    """Min over u_0..u_{K-1} of sum_k (x_k^T Q x_k + u_k^T R u_k) + x_K^T Q x_K with
    x_{k+1} = A x_k + B u_k + d_k, for known modes ``theta`` (K, runs), ``final_mode`` (runs,),
    ``x0`` (runs, n) and disturbances ``d`` (K, runs, n); one value per run.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> float(clairvoyant_minimum(sys, np.zeros((1, 1), dtype=int), np.zeros(1, dtype=int),
    ...                           np.zeros((1, 2)), np.zeros((1, 1, 2)))[0])
    0.0
    """
    P = sys.Q[final_mode]
    runs, n = x0.shape
    p, c = np.zeros((runs, n)), np.zeros(runs)
    for k in range(len(theta) - 1, -1, -1):
        A, B, Q, R = sys.A[theta[k]], sys.B[theta[k]], sys.Q[theta[k]], sys.R[theta[k]]
        BT = np.swapaxes(B, 1, 2)
        S = R + BT @ P @ B
        gain = P @ B @ np.linalg.solve(S, BT)                                       # P B S^-1 B^T
        Pi = P - gain @ P
        pi = p - np.einsum("rab,rb->ra", gain, p)
        Bp = np.einsum("rab,rb->ra", BT, p)
        c = (c + np.einsum("ra,rab,rb->r", d[k], Pi, d[k]) + 2 * np.einsum("ra,ra->r", pi, d[k])
             - np.einsum("ra,ra->r", Bp, np.linalg.solve(S, Bp[..., None])[..., 0]))
        p = np.einsum("rba,rb->ra", A, np.einsum("rab,rb->ra", Pi, d[k]) + pi)
        P = Q + np.swapaxes(A, 1, 2) @ Pi @ A
    return np.einsum("ra,rab,rb->r", x0, P, x0) + 2 * np.einsum("ra,ra->r", p, x0) + c


def _final_modes(rng, last, T):
    """theta_K given theta_{K-1} (the final cost x_K^T Q_{theta_K} x_K)."""
    cumulative = np.cumsum(T, axis=1)
    return np.minimum((rng.random(len(last))[:, None] > cumulative[last]).sum(axis=1), len(T) - 1)


def median_lower_bound(samples, tail=CONFIDENCE_TAIL):
    """A lower confidence bound of the median: the order statistic X_(l) with P(Bin(n, 1/2) <= l -
    1) <= tail, so P(X_(l) > median) <= tail for any continuous distribution.

    Examples
    --------
    >>> x = np.random.default_rng(1).standard_normal(10_000)
    >>> -0.1 < median_lower_bound(x) < 0.0
    True
    """
    x = np.sort(np.asarray(samples))
    n = len(x)
    l = int(scipy.stats.binom.ppf(tail, n, 0.5))            # P(Bin <= l) >= tail: take one below
    while l > 0 and scipy.stats.binom.cdf(l - 1, n, 0.5) > tail:
        l -= 1
    return float(x[max(l - 1, 0)])


def table_3_3_bounds(sys, mean0, cov0, mu0, horizon, runs, rng, noise_scales):
    """Per noise scale: Monte Carlo median of the clairvoyant J/K and its lower confidence bound.

    Examples
    --------
    One scalar mode x' = 0.5 x + u, Q = R = 1, x_0 = 2, one step, no noise: the clairvoyant input
    u = -x_0 / 4 costs x_0^2 (1 + 1/16 + 1/16) = 4.5 in every run:

    >>> from asoc.mjls import MJLS
    >>> one = np.ones((1, 1, 1))
    >>> sys = MJLS(0.5 * one, one, one, one, one, one, [[1.0]])
    >>> table_3_3_bounds(sys, np.array([[2.0]]), np.zeros((1, 1, 1)), np.array([1.0]), 1, 50,
    ...                  np.random.default_rng(0), [0.0])
    [(4.5, 4.5)]
    """
    out = []
    for scale in noise_scales:
        J = clairvoyant_costs(sys, mean0, cov0, mu0, horizon, runs, rng, scale) / horizon
        out.append((float(np.median(J)), median_lower_bound(J)))
    return out


# ------------------------------------------------------------------ Table 3.2

def _closed_loop_cost_to_go(sys, L, horizon):
    """Pi(0), ..., Pi(K) of a mode-dependent state feedback u = L_theta x over K steps (final cost
    Q): Pi_i(k) = Q_i + L_i^T R_i L_i + Acl_i^T E_i(Pi(k+1)) Acl_i, Pi(K) = Q.

    Examples
    --------
    Without feedback (L = 0) on x' = 0.5 x, Q = 1: Pi(K) = 1, Pi(K-1) = 1 + 0.25, Pi(K-2) = 1 + 0.25
    * 1.25:

    >>> from asoc.mjls import MJLS
    >>> one = np.ones((1, 1, 1))
    >>> sys = MJLS(0.5 * one, one, one, one, one, one, [[1.0]])
    >>> [round(float(P[0, 0, 0]), 9) for P in _closed_loop_cost_to_go(sys, np.zeros((1, 1, 1)), 2)]
    [1.3125, 1.25, 1.0]
    """
    Acl = sys.A + sys.B @ L
    stage = sys.Q + np.swapaxes(L, 1, 2) @ sys.R @ L
    Pis = [sys.Q]
    for _ in range(horizon):
        Pis.append(stage + np.swapaxes(Acl, 1, 2) @ successor_average(sys.T, Pis[-1]) @ Acl)
    return Pis[::-1]


def transient_gap(sys, L, x0, mu0, horizon):
    """E{J | x_0} - E{J | x_0 = 0} = sum_i mu0_i x_0^T Pi_i(0) x_0 for u = L_theta x, for any noise.

    Examples
    --------
    The same system from x_0 = 2: x_0^2 Pi(0) = 4 * 1.3125:

    >>> from asoc.mjls import MJLS
    >>> one = np.ones((1, 1, 1))
    >>> sys = MJLS(0.5 * one, one, one, one, one, one, [[1.0]])
    >>> round(transient_gap(sys, np.zeros((1, 1, 1)), np.array([2.0]), np.array([1.0]), 2), 9)
    5.25
    """
    Pi0 = _closed_loop_cost_to_go(sys, L, horizon)[0]
    return float(mu0 @ np.einsum("a,iab,b->i", x0, Pi0, x0))


def noise_weight(sys, L, mu0, horizon):
    """Gamma with E{J | x_0 = 0} / K = tr[Gamma W] for the noise covariance W = H H^T (the same in
    every mode): Gamma = (1 / K) sum_k sum_i mu_k^i E_i(Pi(k + 1)).

    Examples
    --------
    The same system over two steps: Gamma = (Pi(1) + Pi(2)) / 2 = (1.25 + 1) / 2:

    >>> from asoc.mjls import MJLS
    >>> one = np.ones((1, 1, 1))
    >>> sys = MJLS(0.5 * one, one, one, one, one, one, [[1.0]])
    >>> noise_weight(sys, np.zeros((1, 1, 1)), np.array([1.0]), 2).round(9)
    array([[1.125]])
    """
    Pis = _closed_loop_cost_to_go(sys, L, horizon)
    mu, total = np.asarray(mu0, dtype=float), 0.0
    for k in range(horizon):
        total = total + np.einsum("i,iab->ab", mu, successor_average(sys.T, Pis[k + 1]))
        mu = mu @ sys.T
    return total / horizon


def monte_carlo_gap(sys, L, x0, mu0, horizon, runs, rng, noise_scale):
    """Median of J(x_0) minus median of J(0) for u = L_theta x, common modes and noise, H scaled.

    Examples
    --------
    Without noise every run is the deterministic one, so the gap is :func:`transient_gap`'s 5.25:

    >>> from asoc.mjls import MJLS
    >>> one = np.ones((1, 1, 1))
    >>> sys = MJLS(0.5 * one, one, one, one, one, one, [[1.0]])
    >>> round(monte_carlo_gap(sys, np.zeros((1, 1, 1)), np.array([2.0]), np.array([1.0]), 2, 10,
    ...                       np.random.default_rng(0), 0.0), 9)
    5.25
    """
    theta = _modes(rng, mu0, sys.T, runs, horizon + 1)
    draws = rng.standard_normal((horizon, runs, sys.nw))
    w = noise_scale * np.einsum("krab,krb->kra", sys.H[theta[:-1]], draws)
    totals = []
    for start in (np.broadcast_to(x0, (runs, sys.nx)), np.zeros((runs, sys.nx))):
        x, J = np.array(start, dtype=float), np.zeros(runs)
        for k in range(horizon):
            u = np.einsum("rab,rb->ra", L[theta[k]], x)
            J += (np.einsum("ra,rab,rb->r", x, sys.Q[theta[k]], x)
                  + np.einsum("ra,rab,rb->r", u, sys.R[theta[k]], u))
            x = (np.einsum("rab,rb->ra", sys.A[theta[k]], x)
                 + np.einsum("rab,rb->ra", sys.B[theta[k]], u) + w[k])
        totals.append(J + np.einsum("ra,rab,rb->r", x, sys.Q[theta[-1]], x))
    return float(np.median(totals[0]) - np.median(totals[1]))
