"""Shared pieces of the Chapter 3 checks: drawing instances, deciding premises, Monte Carlo.

Everything here is verification logic: it draws random instances through
``asoc.mjls.random_mjls``, decides a premise independently of the statement under test
(static output-feedback stabilisability by a search over the gain), or estimates a moment
by simulation with its standard error. The algorithms under test come from ``asoc.mjls``.
"""

import itertools

import numpy as np
import scipy.optimize

from asoc.mjls import closed_loop, ms_spectral_radius, random_mjls

FAMILIES = ("stable", "unstable", "sparse_T", "thesis_like")
Z_SCORE = 6.0         # Monte Carlo tolerance in standard errors (per compared entry; false alarm ~ 2e-9)


def draw_system(rng, *, families=FAMILIES, max_states=3, max_modes=3, siso=False, measurement_noise=0.1):
    """A random MJLS: family, dimensions (nx <= max_states, M <= max_modes) and matrices from ``rng``."""
    family = families[rng.integers(len(families))]
    if family == "thesis_like":
        nx, nu, ny = 2, 1, 1
        M = int(rng.integers(1, max_modes + 1))
    else:
        nx = int(rng.integers(1, max_states + 1))
        nu, ny = (1, 1) if siso else (int(rng.integers(1, 3)), int(rng.integers(1, nx + 1)))
        M = int(rng.integers(1, max_modes + 1))
    concentration = float(rng.choice([0.3, 1.0, 5.0]))
    return random_mjls(rng, nx, nu, ny, M, family=family, concentration=concentration,
                       measurement_noise=measurement_noise)


def size(sys):
    """The numbers that order counterexamples by size (fewest states and modes first)."""
    return {"n_states": sys.nx, "n_modes": sys.M, "n_inputs": sys.nu, "n_outputs": sys.ny}


def system_data(sys):
    """The system's matrices as nested lists (a counterexample is saved as data)."""
    data = {name: np.asarray(getattr(sys, name)).tolist() for name in ("A", "B", "C", "H", "Q", "R", "T")}
    data["J"] = None if sys.J is None else np.asarray(sys.J).tolist()
    return data


def rescaled(sys, factor):
    """The system with A_i, B_i scaled by ``factor`` (closed loops A + B L C scale with it)."""
    return sys.replace(A=factor * sys.A, B=factor * sys.B)


def radius_to(sys, Acl, target):
    """Scale factor c with rho(c Acl) = target (rho of Cor. 3.2 is homogeneous of degree 2)."""
    return float(np.sqrt(target / ms_spectral_radius(Acl, sys.T)))


# ---------------------------------------------------------------- SOF stabilisability (premise)

BOUND_MARGIN = 2.0    # grid_minimum skips a gain whose lower bound of rho exceeds this times the best rho found,
BOUND_FLOOR = 1e-3    # with the best rho taken >= this (near rho = 0 rounding is relatively larger)
BOUND_SEEDS = 16      # gains of smallest lower bound whose rho gives the first estimate of the minimum


def scalar_closed_loops(sys, gains):
    """A_i + L B_i C_i for u = L y with scalar L (SISO), for every L in ``gains``: shape (G, M, n, n)."""
    bc = sys.B[:, :, :1] @ sys.C[:, :1, :]                             # (M, n, n): B_i C_i
    return sys.A[None] + gains[:, None, None, None] * bc[None]


def scalar_gain_radii(sys, gains):
    """rho of Cor. 3.2 for u = L y with scalar L (SISO), for every L in ``gains`` at once."""
    M, n = sys.M, sys.nx
    Acl = scalar_closed_loops(sys, gains)
    kron = np.einsum("giab,gicd->giacbd", Acl, Acl).reshape(len(gains), M, n * n, n * n)
    op = np.einsum("ij,gixy->gjxiy", sys.T, kron).reshape(len(gains), M * n * n, M * n * n)
    return np.max(np.abs(np.linalg.eigvals(op)), axis=1)


def _power_trace(T, Acl, k):
    """tr(M^k) of the matrix M of Cor. 3.2 for each stack of ``Acl`` (G, M, n, n): the sum over the
    closed walks i_0 -> ... -> i_{k-1} -> i_0 of the mode chain of p_{i_0 i_1} ... p_{i_{k-1} i_0}
    tr(Acl_{i_{k-1}} ... Acl_{i_0})^2 (every term >= 0)."""
    total = np.zeros(len(Acl))
    for walk in itertools.product(range(len(T)), repeat=k):
        weight = np.prod([T[walk[t], walk[(t + 1) % k]] for t in range(k)])
        if weight > 0:
            product = Acl[:, walk[0]]
            for mode in walk[1:]:
                product = Acl[:, mode] @ product
            total += weight * np.trace(product, axis1=1, axis2=2) ** 2
    return total


def radius_lower_bounds(sys, gains):
    """Lower bounds of :func:`scalar_gain_radii` without eigenvalues: |tr(M^k)| <= N rho^k for the
    N x N matrix M of Cor. 3.2 (N = M nx^2), the largest of (tr(M^k) / N)^(1/k) over k = 1..M (every
    closed walk of the mode chain is counted once its length is <= M; a bound of 0 skips nothing)."""
    Acl = scalar_closed_loops(sys, gains)
    size = sys.M * sys.nx ** 2
    return np.max([(_power_trace(sys.T, Acl, k) / size) ** (1 / k) for k in range(1, sys.M + 1)], axis=0)


def walk_lower_bounds(sys, gains):
    """Lower bounds of :func:`scalar_gain_radii` from single closed walks of the mode chain. For a closed
    walk i_0 -> ... -> i_{k-1} -> i_0 with probability P and product Pi = Acl_{i_{k-1}} ... Acl_{i_0},
    rho^k >= P rho(Pi)^2: the k-th power of the second-moment map dominates, as positive maps, the map
    X -> P Pi X_{i_0} Pi^T into mode i_0 alone, whose spectral radius is P rho(Pi)^2. Walks of length 1
    (i -> i) and 2 (i -> j -> i); exact for one mode (rho = rho(Acl)^2); the largest bound per gain."""
    Acl = scalar_closed_loops(sys, gains)
    T, M = sys.T, sys.M
    walks = ([(i,) for i in range(M) if T[i, i] > 0]
             + [(i, j) for i in range(M) for j in range(i + 1, M) if T[i, j] * T[j, i] > 0])
    bounds = np.zeros(len(gains))
    for walk in walks:
        product = Acl[:, walk[0]] if len(walk) == 1 else Acl[:, walk[1]] @ Acl[:, walk[0]]
        probability = np.prod([T[walk[t], walk[(t + 1) % len(walk)]] for t in range(len(walk))])
        rho = np.max(np.abs(np.linalg.eigvals(product)), axis=1)
        bounds = np.maximum(bounds, (probability * rho ** 2) ** (1 / len(walk)))
    return bounds


def grid_minimum(sys, gains):
    """Index and value of the first smallest entry of ``scalar_gain_radii(sys, gains)``, with rho computed
    only where it can be the smallest. rho at the BOUND_SEEDS gains of smallest lower bound gives m >= the
    minimum; a gain whose lower bound (:func:`radius_lower_bounds`, then :func:`walk_lower_bounds`)
    exceeds BOUND_MARGIN max(m, BOUND_FLOOR) has a larger rho (the margin covers the rounding of the
    bounds and of the eigenvalues) and is skipped (a seed is not evaluated twice)."""
    bounds = radius_lower_bounds(sys, gains)
    seeds = np.argsort(bounds, kind="stable")[:BOUND_SEEDS]
    radii = np.full(len(gains), np.inf)
    radii[seeds] = scalar_gain_radii(sys, gains[seeds])
    threshold = BOUND_MARGIN * max(radii[seeds].min(), BOUND_FLOOR)
    candidates = np.setdiff1d(np.flatnonzero(bounds <= threshold), seeds)
    candidates = candidates[walk_lower_bounds(sys, gains[candidates]) <= threshold]
    radii[candidates] = scalar_gain_radii(sys, gains[candidates])
    best = int(np.argmin(radii))
    return best, radii[best]


def best_scalar_gain(sys, points=2001):
    """min over scalar L of rho: a grid in L = tan(s), s in (-pi/2, pi/2) (all real gains),
    refined by a bounded scalar search between the grid neighbours of the best point."""
    s = np.linspace(-np.pi / 2, np.pi / 2, points + 2)[1:-1]
    best, rho = grid_minimum(sys, np.tan(s))
    lo, hi = s[max(best - 1, 0)], s[min(best + 1, points - 1)]
    res = scipy.optimize.minimize_scalar(lambda t: scalar_gain_radii(sys, np.array([np.tan(t)]))[0],
                                         bounds=(lo, hi), method="bounded", options={"xatol": 1e-10})
    if res.fun < rho:
        return float(np.tan(res.x)), float(res.fun)
    return float(np.tan(s[best])), float(rho)


def best_gain(sys, rng, starts=20):
    """min over L (nu x ny) of rho: the scalar grid for SISO, else Nelder-Mead from ``starts``
    starts (L = 0 and standard normal draws). Returns (L, rho)."""
    if sys.nu == sys.ny == 1:
        L, rho = best_scalar_gain(sys)
        return np.array([[L]]), rho
    shape = (sys.nu, sys.ny)
    f = lambda v: ms_spectral_radius(closed_loop(sys, v.reshape(shape)), sys.T)
    best = (np.zeros(shape), f(np.zeros(shape).ravel()))
    for k in range(starts):
        x0 = np.zeros(shape).ravel() if k == 0 else rng.standard_normal(shape).ravel()
        res = scipy.optimize.minimize(f, x0, method="Nelder-Mead", options={"xatol": 1e-8, "fatol": 1e-10,
                                                                            "maxiter": 2000})
        if res.fun < best[1]:
            best = (res.x.reshape(shape), float(res.fun))
    return best


# ---------------------------------------------------------------- Monte Carlo

def next_modes(rng, T, theta):
    """theta_{k+1} given theta_k for every run (inverse transform of the rows of T)."""
    cum = np.cumsum(T, axis=1).take(theta, axis=0)
    u = rng.random(len(theta))
    passed = np.zeros(len(theta), dtype=np.intp)
    for column in cum.T:                      # one pass per mode: no reduction over the narrow mode axis
        passed += u > column
    return np.minimum(passed, T.shape[0] - 1)


def initial_modes(rng, mu, n_runs):
    return np.minimum((rng.random(n_runs)[:, None] > np.cumsum(mu)[None]).sum(axis=1), len(mu) - 1)


def mode_rows(theta, n_modes):
    """The runs in each mode, as increasing indices: one grouping shared by the products of a step."""
    return [np.flatnonzero(theta == i) for i in range(n_modes)]


def apply_modes(S, theta, x, rows=None):
    """Rows x_r -> S_{theta_r} x_r for all runs (one matrix product per mode, not a gather).

    ``rows``: :func:`mode_rows` of ``theta`` when several products share it (computed if omitted).
    """
    if rows is None:
        rows = mode_rows(theta, S.shape[0])
    out = np.empty((len(x), S.shape[1]))
    for i, runs in enumerate(rows):
        out[runs] = x.take(runs, axis=0) @ S[i].T
    return out


def moment_estimate(samples):
    """Mean and standard error over the first axis (runs)."""
    return samples.mean(axis=0), samples.std(axis=0, ddof=1) / np.sqrt(len(samples))


def stationary_average(rng, step, stage_cost, state, theta, T, rho, n_runs, steps=100, tail=1e-4):
    """Monte Carlo of the stationary average cost of a mean-square stable loop.

    ``step(state, theta, rng)`` advances all runs, ``stage_cost(state, theta)`` is the cost
    per run. A burn-in of log(tail)/log(rho) steps makes the transient's share below
    ``tail``; then each run averages ``steps`` stage costs. Returns (mean, standard error)
    over the runs (independent) and the burn-in.
    """
    burn = int(np.ceil(np.log(tail) / np.log(max(rho, 1e-3))))
    for _ in range(burn):
        state, theta = step(state, theta, rng), next_modes(rng, T, theta)
    total = np.zeros(n_runs)
    for _ in range(steps):
        total += stage_cost(state, theta)
        state, theta = step(state, theta, rng), next_modes(rng, T, theta)
    mean, se = moment_estimate(total / steps)
    return float(mean), float(se), burn


def random_spd(rng, n, scale=1.0):
    G = rng.standard_normal((n, n))
    return scale * (G @ G.T / n + 0.1 * np.eye(n))


def random_spd_stack(rng, M, n, scale=1.0):
    return np.stack([random_spd(rng, n, scale) for _ in range(M)])


def min_eig(S):
    """Smallest eigenvalue over a stack of symmetric matrices."""
    S = np.asarray(S)
    return float(np.min(np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))))
