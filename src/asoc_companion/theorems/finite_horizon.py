"""Checks of Sec. 3.7 (finite horizon, Alg. 3.3): the moment form of the cost (Prop. 3.28), the
cost-to-go (Lemma 3.29), the trace inequality (Lemma 3.30), the bound (Thm. 3.31), the conditions
of its minimiser (Thm. 3.32) and Alg. 3.3's monotonicity and convergence (Thm. 3.33).
"""

import numpy as np

from asoc.linalg import transpose
from asoc.mjls import finite_horizon_cost, finite_horizon_dynamic_output_feedback, successor_average
from asoc.mjls.closed_loops import augmented_closed_loop, noise_covariances
from asoc.mjls.finite_horizon import augmented_initial_moment, initial_bounds
from asoc.mjls.moment_bounds import bound_costate_step, bound_moment_step
from asoc.mjls.optimality import optimality_system

from .dynamic_feedback import loop_step, quadratic_form
from .instances import (
    Z_SCORE,
    ModeChain,
    RunModes,
    draw_system,
    gaussian_mixture,
    moment_estimate,
    outcome,
    random_spd_stack,
    sample_mixture,
    trace_sum,
    verdict,
)

__all__ = ["check_3_28", "check_3_29", "check_3_30", "bound_cost", "check_3_31", "summarise_3_31",
           "check_3_32", "check_3_33"]


def _finite_instance(rng, max_states=3, max_modes=3):
    """A random system, horizon 2-8, time-variant gains (F_k, K_k, L_k), a Gaussian-mixture x_0."""
    sys = draw_system(rng, max_states=max_states, max_modes=max_modes)
    horizon = int(rng.integers(2, 9))
    F = 0.5 * rng.standard_normal((horizon, sys.nx, sys.nx))
    K = 0.5 * rng.standard_normal((horizon, sys.nx, sys.ny))
    L = 0.5 * rng.standard_normal((horizon, sys.nu, sys.nx))
    mu0, mean0, cov0 = gaussian_mixture(rng, sys)
    return sys, horizon, F, K, L, mu0, mean0, cov0


def check_3_28(rng, mutant=False):
    """Prop. 3.28: the expected cost (3.56) by the moment recursion (3.57)-(3.58) against Monte
    Carlo. Mutant: the moment form evaluated with the gains in reverse time order.
    """
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    xhat0 = mu0 @ mean0
    order = slice(None, None, -1 if mutant else 1)
    exact = finite_horizon_cost(sys, F[order], K[order], L[order], mean0, cov0, mu0, xhat0)
    n_runs = 10000
    x, theta = sample_mixture(rng, mu0, mean0, cov0, n_runs)
    state, total = (x, np.broadcast_to(xhat0, x.shape).copy()), np.zeros(n_runs)
    step, chain = loop_step(sys), ModeChain(sys.T)
    for k in range(horizon):
        total += (quadratic_form(sys.Q, theta, state[0])
                  + quadratic_form(sys.R, theta, state[1] @ L[k].T))
        state, theta = (step(state, RunModes(theta, sys.M), rng, F[k], K[k], L[k]),
                        chain.next(rng, theta))
    total += quadratic_form(sys.Q, theta, state[0])
    mc, se = moment_estimate(total)
    z = abs(mc - exact) / max(se, 1e-12 * exact)
    return outcome(verdict(z < Z_SCORE), sys, cost_3_57=exact, monte_carlo=float(mc),
                   standard_error=float(se),
                   z=z, horizon=horizon)


def check_3_29(rng, mutant=False):
    """Lemma 3.29: sum_i tr[P~_0^i X~_0^i] + mu_0^i omega_{i,0} by the backward recursion (3.64)
    against the forward sum (3.62). Mutant: the recursion without the noise term omega.
    """
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    xhat0 = mu0 @ mean0
    forward = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0, xhat0)
    n = sys.nx
    P = np.zeros((sys.M, 2 * n, 2 * n))
    P[:, :n, :n] = sys.Q                                               # P~_K = Q~_K
    omega = np.zeros(sys.M)
    for k in range(horizon - 1, -1, -1):
        At, HHt_cl, Qt = augmented_closed_loop(sys, F[k], K[k], L[k])
        EP = successor_average(sys.T, P)
        # tr[H~^T E(P) H~] + E_i(omega)
        omega = np.einsum("iab,iba->i", EP, HHt_cl) + sys.T @ omega
        P = Qt + transpose(At) @ EP @ At
    backward = (trace_sum(P, augmented_initial_moment(mean0, cov0, mu0, xhat0))
                + (0.0 if mutant else float(mu0 @ omega)))
    rel = abs(backward - forward) / forward
    return outcome(verdict(rel < 1e-10), sys, backward=backward, forward=forward,
                   relative_difference=rel)


def check_3_30(rng, mutant=False):
    """Lemma 3.30: X >= A >= 0 and Y >= B >= 0 imply tr[AB] <= tr[XY] (rank-deficient draws
    included, increments X - A, Y - B at a scale log-uniform on [0.01, 1]: near the equality X = A,
    Y = B). Mutant: the hypotheses A, B >= 0 dropped (A, B = psd - 4 psd, mostly negative).
    """
    n = int(rng.integers(1, 5))

    def psd():
        G = rng.standard_normal((n, int(rng.integers(1, n + 1))))
        return G @ G.T

    A, B = (psd() - 4 * psd(), psd() - 4 * psd()) if mutant else (psd(), psd())
    scale = np.exp(rng.uniform(np.log(0.01), 0.0))
    X, Y = A + scale * psd(), B + scale * psd()
    small, large = np.trace(A @ B), np.trace(X @ Y)
    return outcome(verdict(small <= large * (1 + 1e-12) + 1e-12), None, tr_AB=small, tr_XY=large,
                   n_states=n, n_modes=1)


def bound_cost(sys, F, K, L, mean0, cov0, mu0, noise=True):
    """Jbar_0 (3.65) for fixed gains by (3.66)-(3.69) (the library's step functions) and omega
    (``noise=False``: without omega, a mutant).
    """
    horizon = len(F)
    HHt, JJt = noise_covariances(sys)
    _, Xbar, Xunder = initial_bounds(mean0, cov0, mu0)
    mus, X_seq = [mu0], [(Xbar, Xunder)]
    for k in range(horizon):
        X_seq.append(bound_moment_step(sys, F[k], K[k], L[k], *X_seq[-1], mus[-1], HHt, JJt))
        mus.append(mus[-1] @ sys.T)
    Pbar, Punder, omega = sys.Q.copy(), np.zeros_like(sys.Q), np.zeros(sys.M)
    for k in range(horizon - 1, -1, -1):
        EPbar, EPunder = successor_average(sys.T, Pbar), successor_average(sys.T, Punder)
        omega = (np.einsum("iab,iba->i", EPbar + EPunder, HHt)
                 + np.einsum("iab,iba->i", EPunder, K[k] @ JJt @ K[k].T) + sys.T @ omega)
        Pbar, Punder = bound_costate_step(sys, F[k], K[k], L[k], EPbar, EPunder)
    Xbar, Xunder = X_seq[0]
    return trace_sum(Pbar, Xbar + Xunder) + trace_sum(Punder,
                                                      Xbar) + (float(mu0 @ omega) if noise else 0.0)


def check_3_31(rng, mutant=False):
    """Thm. 3.31: J_0 <= Jbar_0 for fixed gains (the exact cost from (3.57)-(3.58)).
    Mutant: Jbar_0 without the noise's share omega.
    """
    sys, horizon, F, K, L, mu0, mean0, cov0 = _finite_instance(rng)
    optimised = bool(rng.random() < 0.5)
    if optimised:                                                     # the gains Alg. 3.3 returns
        run = finite_horizon_dynamic_output_feedback(sys, horizon=horizon, mean0=mean0, cov0=cov0,
                                                     mu0=mu0, init=(F, K, L), max_iter=100,
                                                     warn=False)
        F, K, L = run.F, run.K, run.L
    exact = finite_horizon_cost(sys, F, K, L, mean0, cov0, mu0)
    bound = bound_cost(sys, F, K, L, mean0, cov0, mu0, noise=not mutant)
    return outcome(verdict(exact <= bound * (1 + 1e-9)), sys, exact_cost=exact, bound=bound,
                   relative_excess=(exact - bound) / bound, horizon=horizon,
                   gains_from_alg_3_3=optimised)


def summarise_3_31(outcomes):
    """Thm. 3.31: failures among the instances with Alg. 3.3's gains and with random gains."""
    by = {True: [0, 0], False: [0, 0]}
    for o in outcomes:
        if o.verdict != "not_applicable":
            by[bool(o.numbers.get("gains_from_alg_3_3"))][o.verdict == "fails"] += 1
    return {"alg_3_3_gains": {"instances": sum(by[True]), "fails": by[True][1]},
            "random_gains": {"instances": sum(by[False]), "fails": by[False][1]}}


def check_3_32(rng, mutant=False):
    """Thm. 3.32 at k = 0: with X_0 given and P_1 > 0 (the later gains fixed), Jbar_0 (3.65) with
    (3.68)-(3.69) is a quadratic in (F_0, K_0, L_0); at its minimiser (3.70) must hold, so the
    solution of (3.70) must not be improved by random perturbations.
    Mutant: the solution of (3.70) moved by a random step of 10% of its norm.
    """
    sys = draw_system(rng)
    M, n = sys.M, sys.nx
    # X_0 of a horizon >= 2
    Xbar, Xunder = random_spd_stack(rng, M, n), random_spd_stack(rng, M, n)
    # E_i(P_1), P_1 > 0
    EPbar = successor_average(sys.T, random_spd_stack(rng, M, n))
    EPunder = successor_average(sys.T, random_spd_stack(rng, M, n))
    Eomega, mu = sys.T @ rng.random(M), rng.dirichlet(np.ones(M))
    HHt, JJt = noise_covariances(sys)
    shapes = [(n, n), (n, sys.ny), (sys.nu, n)]
    sizes = np.cumsum([0] + [a * b for a, b in shapes])

    def unpack(z):
        return [z[sizes[j]:sizes[j + 1]].reshape(shapes[j], order="F") for j in range(3)]

    def bound(z):
        F, K, L = unpack(z)
        Pbar, Punder = bound_costate_step(sys, F, K, L, EPbar, EPunder)
        omega = (np.einsum("iab,iba->i", EPbar + EPunder, HHt)
                 + np.einsum("iab,iba->i", EPunder, K @ JJt @ K.T) + Eomega)
        return trace_sum(Pbar, Xbar + Xunder) + trace_sum(Punder, Xbar) + float(mu @ omega)

    H, rho = optimality_system(sys, Xbar, Xunder, EPbar, EPunder, mu, JJt)
    z = np.linalg.lstsq(H, -rho, rcond=None)[0]
    if mutant:
        step = rng.standard_normal(z.size)
        z = z + 0.1 * max(np.linalg.norm(z), 1.0) * step / np.linalg.norm(step)
    best = bound(z)
    drops = [best - bound(z + scale * rng.standard_normal(z.size))
             for scale in (1e-3, 1e-1, 1.0) for _ in range(5)]
    worst = max(drops) / abs(best)
    return outcome(verdict(worst <= 1e-9), sys, bound_at_solution=best, largest_relative_drop=worst)


def check_3_33(rng, mutant=False):
    """Thm. 3.33: Alg. 3.3 gives non-increasing Jbar_0 and its parameters converge
    (20 further iterations after the stop change them by < 1e-4 relative).
    Mutant: Alg. 3.3 stopped after 2 iterations.
    """
    sys, horizon, _, _, _, mu0, mean0, cov0 = _finite_instance(rng, max_states=2, max_modes=2)
    seed = int(rng.integers(2**32))
    kwargs = dict(horizon=horizon, mean0=mean0, cov0=cov0, mu0=mu0, warn=False)
    run = finite_horizon_dynamic_output_feedback(sys, init=np.random.default_rng(seed),
                                                 max_iter=2 if mutant else 300,
                                                 **kwargs)
    bounds = run.cost_bounds
    increases = np.diff(bounds) / np.maximum(1.0, np.abs(bounds[1:]))
    largest_increase = float(increases.max()) if increases.size else 0.0
    numbers = dict(iterations=run.iterations, converged=run.converged,
                   largest_relative_increase=largest_increase,
                   first_bound=float(bounds[0]), last_bound=float(bounds[-1]), horizon=horizon)
    if not run.converged:
        return outcome("fails", sys, **numbers)
    more = finite_horizon_dynamic_output_feedback(sys, init=np.random.default_rng(seed),
                                                  max_iter=run.iterations + 20,
                                                  tol=1e-300, **kwargs)
    theta = lambda r: np.concatenate([r.F.ravel(), r.K.ravel(), r.L.ravel()])
    change = float(np.linalg.norm(theta(more) - theta(run))
                   / max(np.linalg.norm(theta(run)), 1e-12))
    return outcome(verdict(largest_increase <= 1e-8 and change < 1e-4), sys,
                   parameter_change_after_20=change, **numbers)
