"""The baselines of Table 3.2 against formulations outside their own code.

The papers' full texts were not available (the search tool found the abstract of [165], not its
example's numbers), so each baseline is checked on small instances against an independent
formulation of what it claims to compute:

* [52] (``do_val_h2_state_feedback``): with one mode the H2 state-feedback optimum is the LQ
  gain of the discrete algebraic Riccati equation (scipy's ``solve_discrete_are``), cost
  tr(P H H^T); with two modes the LMI optimum bounds the exact H2 cost of its gain from above,
  the cost from the coupled Lyapunov equations solved as one Kronecker linear system;
* [165] and [163] (``time_variant_feedback``): the finite-horizon cost (3.3) of a gain sequence
  by enumerating every mode path (a formulation without the coupled moment recursions), and its
  optimum over all gain sequences by brute force: a grid over every gain entry, the best grid
  points polished by Nelder-Mead.
"""

import itertools

import numpy as np
import scipy.linalg
import scipy.optimize

from asoc.mjls import MJLS
from asoc.mjls.baselines import do_val_h2_state_feedback, time_variant_feedback

__all__ = ["GRID", "POLISHED", "MAX_DRAWS", "random_instance", "exact_h2_cost", "check_52",
           "path_cost", "brute_force_optimum", "check_time_variant", "baseline_checks"]


GRID = np.linspace(-2.5, 2.5, 11)  # brute-force grid of every gain entry
POLISHED = 4  # best grid points polished by Nelder-Mead
MAX_DRAWS = 20  # two-mode draws tried for one with feasible LMIs ([52])


def random_instance(rng, n_modes, n_outputs, state_feedback=False):
    """A small random MJLS (two states, one input) for the checks; C = I for state feedback.

    Examples
    --------
    >>> sys = random_instance(np.random.default_rng(0), 2, 1)
    >>> sys.M, sys.nx, sys.nu, sys.ny
    (2, 2, 1, 1)
    """
    nx = 2
    A = 0.7 * rng.standard_normal((n_modes, nx, nx))
    B = rng.standard_normal((n_modes, nx, 1))
    C = (
        np.tile(np.eye(nx), (n_modes, 1, 1))
        if state_feedback
        else rng.standard_normal((n_modes, n_outputs, nx))
    )
    T = rng.dirichlet(np.ones(n_modes), size=n_modes)
    return MJLS(
        A=A,
        B=B,
        C=C,
        H=0.3 * np.tile(np.eye(nx), (n_modes, 1, 1)),
        Q=np.tile(np.eye(nx), (n_modes, 1, 1)),
        R=np.ones((n_modes, 1, 1)),
        T=T,
    )


def exact_h2_cost(sys, K):
    """sum_i tr[(Q_i + K^T R_i K) X_i] of u = K x (the H2 cost (3.9) of [52]'s gain).

    X solves X_j = sum_i p_ij (Acl_i X_i Acl_i^T + mu_i H_i H_i^T) as one linear system
    (Kronecker products); inf when the closed loop is not mean-square stable.

    Examples
    --------
    One mode, x+ = 0.5 x + w: X = 1 / (1 - 0.25), cost 4/3 with K = 0:

    >>> one = [[[1.0]]]
    >>> sys = MJLS(A=[[[0.5]]], B=one, C=one, H=one, Q=one, R=one, T=[[1.0]])
    >>> round(exact_h2_cost(sys, np.zeros((1, 1))), 6)
    1.333333
    """
    M, n = sys.M, sys.nx
    Acl = sys.A + sys.B @ K
    ops = np.zeros((M * n * n, M * n * n))
    for i, j in itertools.product(range(M), range(M)):
        ops[j * n * n : (j + 1) * n * n, i * n * n : (i + 1) * n * n] = sys.T[i, j] * np.kron(
            Acl[i], Acl[i]
        )
    if np.max(np.abs(np.linalg.eigvals(ops))) >= 1:
        return np.inf
    noise = np.concatenate(
        [
            sum(sys.T[i, j] * sys.mu_inf[i] * (sys.H[i] @ sys.H[i].T) for i in range(M)).ravel()
            for j in range(M)
        ]
    )
    X = np.linalg.solve(np.eye(M * n * n) - ops, noise).reshape(M, n, n)
    return float(sum(np.trace((sys.Q[i] + K.T @ sys.R[i] @ K) @ X[i]) for i in range(M)))


def check_52(rng, n_instances=4):
    """[52] against the Riccati optimum (one mode) and the exact H2 cost of its gain (two modes).

    Returns
    -------
    dict
        ``against``, ``max_rel_diff`` (one mode: the larger of the relative cost and gain
        differences to the DARE solution), ``bound_holds`` and ``max_bound_slack`` (two modes:
        the LMI optimum over the exact cost of its gain, minus one).

    Examples
    --------
    >>> out = check_52(np.random.default_rng(1), n_instances=1)
    >>> out["max_rel_diff"] < 1e-3, out["bound_holds"]
    (True, True)
    """
    diffs, slacks = [], []
    for _ in range(n_instances):
        one = random_instance(rng, 1, 2, state_feedback=True)
        res = do_val_h2_state_feedback(one)
        P = scipy.linalg.solve_discrete_are(one.A[0], one.B[0], one.Q[0], one.R[0])
        K_dare = -np.linalg.solve(one.R[0] + one.B[0].T @ P @ one.B[0], one.B[0].T @ P @ one.A[0])
        J_dare = float(np.trace(P @ one.H[0] @ one.H[0].T))
        diffs += [
            abs(res.bound / J_dare - 1),
            np.linalg.norm(res.L - K_dare) / np.linalg.norm(K_dare),
        ]
        for _ in range(MAX_DRAWS):  # a two-mode system on which the LMIs are feasible
            two = random_instance(rng, 2, 2, state_feedback=True)
            res2 = do_val_h2_state_feedback(two)
            if res2.feasible:
                slacks.append(res2.bound / exact_h2_cost(two, res2.L) - 1)
                break
    if not slacks:
        raise RuntimeError(f"check_52: no two-mode draw with feasible LMIs in {MAX_DRAWS} tries")
    return {
        "against": "one mode: the DARE optimum (scipy solve_discrete_are); "
        "two modes: the exact H2 cost of the gain (coupled Lyapunov equations, Kronecker solve), "
        "which the LMI optimum bounds",
        "max_rel_diff": float(max(diffs)),
        "bound_holds": bool(min(slacks) >= -1e-6),
        "max_bound_slack": float(max(slacks)),
        "two_mode_systems": len(slacks),
    }


def path_cost(sys, gains, x0, mu0):
    """The cost (3.3) of u_k = G_k y_k from the known x_0, by enumerating every mode path.

    ``gains`` has shape (n, K, nu, ny): n gain sequences, evaluated at once. Each path
    theta_0..theta_K has probability mu0[theta_0] prod T[theta_k, theta_k+1]; along it the second
    moment runs S_{k+1} = Acl S_k Acl^T + H H^T and the cost adds tr[(Q + C^T G^T R G C) S_k],
    then tr[Q_{theta_K} S_K].

    Examples
    --------
    One mode, x+ = x + u, u = -x: the cost is x_0^2 (1 + 1) + 0 = 2 from x_0 = 1:

    >>> one = [[[1.0]]]
    >>> sys = MJLS(A=one, B=one, C=one, H=[[[0.0]]], Q=one, R=one, T=[[1.0]])
    >>> path_cost(sys, -np.ones((1, 1, 1, 1)), np.array([1.0]), np.array([1.0])).tolist()
    [2.0]
    """
    n, K = gains.shape[:2]
    total = np.zeros(n)
    for path in itertools.product(range(sys.M), repeat=K + 1):
        p = mu0[path[0]] * np.prod([sys.T[a, b] for a, b in zip(path[:-1], path[1:])])
        if p == 0:
            continue
        S = np.broadcast_to(np.outer(x0, x0), (n, sys.nx, sys.nx))
        cost = np.zeros(n)
        for k, i in enumerate(path[:-1]):
            GC = gains[:, k] @ sys.C[i]
            Acl = sys.A[i] + sys.B[i] @ GC
            weight = sys.Q[i] + np.swapaxes(GC, 1, 2) @ sys.R[i] @ GC
            cost += np.einsum("nab,nba->n", weight, S)
            S = Acl @ S @ np.swapaxes(Acl, 1, 2) + sys.H[i] @ sys.H[i].T
        total += p * (cost + np.einsum("ab,nba->n", sys.Q[path[-1]], S))
    return total


def brute_force_optimum(sys, horizon, x0, mu0):
    """The minimum of :func:`path_cost` over all gain sequences: the grid ``GRID`` over every entry,
    the ``POLISHED`` best points refined by Nelder-Mead. Returns (cost, gains).
    """
    shape = (horizon, sys.nu, sys.ny)
    grid = np.array(list(itertools.product(GRID, repeat=int(np.prod(shape))))).reshape(
        (-1,) + shape
    )
    costs = np.concatenate(
        [path_cost(sys, chunk, x0, mu0) for chunk in np.array_split(grid, 1 + len(grid) // 20000)]
    )
    best = []
    for start in grid[np.argsort(costs)[:POLISHED]]:
        res = scipy.optimize.minimize(
            lambda g: path_cost(sys, g.reshape((1,) + shape), x0, mu0)[0],
            start.ravel(),
            method="Nelder-Mead",
            options={"xatol": 1e-9, "fatol": 1e-12, "maxiter": 20000},
        )
        best.append((res.fun, res.x.reshape(shape)))
    return min(best, key=lambda b: b[0])


def check_time_variant(rng, state_feedback, n_instances=3, horizon=2):
    """[165] (state feedback) or [163] (one output) against the brute-force optimum.

    Returns
    -------
    dict
        ``against``, ``max_rel_diff`` (the variational method's cost over the brute-force optimum,
        minus one, largest over the instances; negative when the variational method is better than
        the polished grid), ``max_cost_formula_diff`` (its own cost against the path enumeration of
        its gains).

    Examples
    --------
    >>> out = check_time_variant(np.random.default_rng(2), state_feedback=False, n_instances=1)
    >>> abs(out["max_rel_diff"]) < 1e-6, out["max_cost_formula_diff"] < 1e-10
    (True, True)
    """
    rel, formula = [], []
    for _ in range(n_instances):
        sys = random_instance(rng, 2, 1, state_feedback=state_feedback)
        x0, mu0 = 2.0 * rng.standard_normal(sys.nx), sys.mu_inf
        res = time_variant_feedback(sys, horizon, x0, mu0=mu0, warn=False)
        J_var = path_cost(sys, res.G[None], x0, mu0)[0]
        J_opt, _ = brute_force_optimum(sys, horizon, x0, mu0)
        rel.append(J_var / J_opt - 1)
        formula.append(abs(res.costs[-1] / J_var - 1))
    return {
        "against": "brute-force optimum over all gain sequences (grid and Nelder-Mead, "
        f"horizon {horizon}) of the cost by mode-path enumeration, on random two-mode systems",
        "max_rel_diff": float(max(rel, key=abs)),
        "max_cost_formula_diff": float(max(formula)),
    }


def baseline_checks(seed_sequence, n_instances=3):
    """``{"52": ..., "165": ..., "163": ...}``: each baseline against its independent check.

    Examples
    --------
    >>> checks = baseline_checks(np.random.SeedSequence(0), n_instances=1)
    >>> sorted(checks), all(abs(c["max_rel_diff"]) < 1e-3 for c in checks.values())
    (['163', '165', '52'], True)
    """
    rngs = [np.random.default_rng(s) for s in seed_sequence.spawn(3)]
    return {
        "52": check_52(rngs[0], n_instances),
        "165": check_time_variant(rngs[1], state_feedback=True, n_instances=n_instances),
        "163": check_time_variant(rngs[2], state_feedback=False, n_instances=n_instances),
    }
