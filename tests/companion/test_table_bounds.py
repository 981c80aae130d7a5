"""The certified evidence on Tables 3.2 and 3.3: the clairvoyant per-sample bound, the median's
lower
confidence bound, the noise-independent transient and the noise weight of the expected cost."""

import numpy as np
import pytest

from asoc.mjls import observed_mode_state_feedback
from asoc.mjls.examples import SEC373_COV0, SEC373_MEAN0, SEC373_MU0, sec354_system, sec373_system
from asoc_companion import table_bounds as tb


def _cost(sys, theta, final_mode, x0, d, u):
    x, J = x0.copy(), 0.0
    for k, i in enumerate(theta):
        J += x @ sys.Q[i] @ x + u[k] @ sys.R[i] @ u[k]
        x = sys.A[i] @ x + sys.B[i] @ u[k] + d[k]
    return J + x @ sys.Q[final_mode] @ x


def test_clairvoyant_minimum_is_the_least_squares_minimum_and_below_other_inputs():
    sys, rng = sec373_system(1), np.random.default_rng(4)
    K = 6
    theta, final = rng.integers(0, 2, K), int(rng.integers(0, 2))
    x0, d = rng.standard_normal(2), 0.3 * rng.standard_normal((K, 2))
    value = tb.clairvoyant_minimum(sys, theta[:, None], np.array([final]), x0[None], d[:, None, :])[
        0
    ]
    # the cost is quadratic in u: minimise it by least squares on its exact gradient and Hessian
    f = lambda u: _cost(sys, theta, final, x0, d, u.reshape(K, 1))
    e, base = np.eye(K), f(np.zeros(K))
    grad = np.array([(f(e[j]) - f(-e[j])) / 2 for j in range(K)])
    hess = np.array(
        [[(f(e[a] + e[b]) - f(e[a]) - f(e[b]) + base) for b in range(K)] for a in range(K)]
    )
    u_star = np.linalg.solve(hess, -grad)
    assert value == pytest.approx(f(u_star), rel=1e-9)
    assert all(value <= f(u_star + 0.1 * rng.standard_normal(K)) for _ in range(5))


def test_median_lower_bound_covers():
    misses = sum(
        tb.median_lower_bound(np.random.default_rng(s).exponential(size=500), tail=0.05) > np.log(2)
        for s in range(200)
    )
    assert misses <= 25  # P(miss) <= 0.05: 10 expected, 25 is ~5 sigma


def test_transient_gap_is_the_noise_free_cost_and_noise_weight_the_noise_cost():
    sys = sec354_system(1, "state")
    L = observed_mode_state_feedback(sys).L
    x0, mu0, K = np.array([3.0, 0.0]), np.array([0.3, 0.7]), 30
    # noise-free expected cost from x0 by the second-moment recursion
    X, mu, total = mu0[:, None, None] * np.outer(x0, x0), mu0.copy(), 0.0
    Acl, stage = sys.A + sys.B @ L, sys.Q + np.swapaxes(L, 1, 2) @ sys.R @ L
    W = sys.H[0] @ sys.H[0].T
    Xn = np.zeros_like(X)
    noise_total = 0.0
    for _ in range(K):
        total += np.einsum("iab,iba->", stage, X)
        noise_total += np.einsum("iab,iba->", stage, Xn)
        X = np.einsum("ij,iab->jab", sys.T, Acl @ X @ np.swapaxes(Acl, 1, 2))
        Xn = np.einsum(
            "ij,iab->jab", sys.T, Acl @ Xn @ np.swapaxes(Acl, 1, 2) + mu[:, None, None] * W
        )
        mu = mu @ sys.T
    total += np.einsum("iab,iba->", sys.Q, X)
    noise_total += np.einsum("iab,iba->", sys.Q, Xn)
    assert tb.transient_gap(sys, L, x0, mu0, K) == pytest.approx(total, rel=1e-10)
    assert K * np.trace(tb.noise_weight(sys, L, mu0, K) @ W) == pytest.approx(
        noise_total, rel=1e-10
    )


def test_clairvoyant_median_exceeds_the_printed_table_3_3_column():
    J = (
        tb.clairvoyant_costs(
            sec373_system(1),
            SEC373_MEAN0[1],
            SEC373_COV0,
            SEC373_MU0,
            100,
            2000,
            np.random.default_rng(0),
        )
        / 100
    )
    assert tb.median_lower_bound(J) > 0.7587  # the largest printed xi_0[1] entry
