"""Shared pieces of the Chapter 3 checks: drawing instances, deciding premises, Monte Carlo.

Everything here is verification logic: it draws random instances through
``asoc.mjls.random_mjls``, decides a premise independently of the statement under test
(static output-feedback stabilisability by a search over the gain), or estimates a moment
by simulation with its standard error. The algorithms under test come from ``asoc.mjls``.
"""

import functools
import itertools

import numpy as np
import scipy.optimize

from asoc.linalg import sym, transpose
from asoc.mjls import closed_loop, ms_spectral_radius, random_mjls

from .statement import Outcome

__all__ = ["FAMILIES", "Z_SCORE", "draw_system", "size", "rescaled", "BOUND_MARGIN", "BOUND_FLOOR",
           "BOUND_SEEDS", "scalar_gain_radii", "radius_lower_bounds", "walk_lower_bounds",
           "grid_minimum", "best_scalar_gain", "best_gain", "ModeChain", "initial_modes",
           "RunModes", "ModeOperator", "moment_estimate", "indicator_moment_estimate",
           "stationary_average", "random_spd", "random_spd_stack", "min_eig", "trace_sum",
           "verdict", "outcome", "stabilised", "gaussian_mixture", "sample_mixture", "z_scores",
           "norm_scale"]


FAMILIES = ("stable", "unstable", "sparse_T", "thesis_like")
# Monte Carlo tolerance in standard errors (per compared entry; false alarm ~ 2e-9)
Z_SCORE = 6.0


def draw_system(rng, *, families=FAMILIES, max_states=3, max_modes=3, siso=False,
                measurement_noise=0.1):
    """A random MJLS from ``rng``: family, sizes (nx <= max_states, M <= max_modes), matrices."""
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


def _system_data(sys):
    """The system's matrices as nested lists (a counterexample is saved as data)."""
    data = {name: np.asarray(getattr(sys, name)).tolist() for name in ("A", "B", "C", "H", "Q", "R",
                                                                       "T")}
    data["J"] = None if sys.J is None else np.asarray(sys.J).tolist()
    return data


def rescaled(sys, factor):
    """The system with A_i, B_i scaled by ``factor`` (closed loops A + B L C scale with it)."""
    return sys.replace(A=factor * sys.A, B=factor * sys.B)


def _radius_to(sys, Acl, target):
    """Scale factor c with rho(c Acl) = target (rho of Cor. 3.2 is homogeneous of degree 2)."""
    return float(np.sqrt(target / ms_spectral_radius(Acl, sys.T)))


# ---------------------------------------------------------------- SOF stabilisability (premise)

# grid_minimum skips a gain whose lower bound of rho exceeds this times the best rho found,
BOUND_MARGIN = 2.0
BOUND_FLOOR = 1e-3    # with the best rho taken >= this (near rho = 0 rounding is relatively larger)
# gains of smallest lower bound whose rho gives the first estimate of the minimum
BOUND_SEEDS = 16


def _scalar_closed_loops(sys, gains):
    """A_i + L B_i C_i (u = L y, scalar L: SISO) for every L in ``gains``, shape (G, M, n, n)."""
    bc = sys.B[:, :, :1] @ sys.C[:, :1, :]                             # (M, n, n): B_i C_i
    return sys.A[None] + gains[:, None, None, None] * bc[None]


def scalar_gain_radii(sys, gains):
    """Rho of Cor. 3.2 for u = L y with scalar L (SISO), for every L in ``gains`` at once."""
    M, n = sys.M, sys.nx
    Acl = _scalar_closed_loops(sys, gains)
    kron = np.einsum("giab,gicd->giacbd", Acl, Acl).reshape(len(gains), M, n * n, n * n)
    op = np.einsum("ij,gixy->gjxiy", sys.T, kron).reshape(len(gains), M * n * n, M * n * n)
    return np.max(np.abs(np.linalg.eigvals(op)), axis=1)


def _power_trace(T, Acl, k):
    """tr(M^k) of the matrix M of Cor. 3.2 for each stack of ``Acl`` (G, M, n, n): the sum over the
    closed walks i_0 -> ... -> i_{k-1} -> i_0 of the mode chain of p_{i_0 i_1} ... p_{i_{k-1} i_0}
    tr(Acl_{i_{k-1}} ... Acl_{i_0})^2 (every term >= 0).
    """
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
    closed walk of the mode chain is counted once its length is <= M; a bound of 0 skips nothing).
    """
    Acl = _scalar_closed_loops(sys, gains)
    size = sys.M * sys.nx ** 2
    return np.max([(_power_trace(sys.T, Acl, k) / size) ** (1 / k) for k in range(1, sys.M + 1)],
                  axis=0)


def walk_lower_bounds(sys, gains):
    """Lower bounds of :func:`scalar_gain_radii` from single closed walks of the mode chain. For a
    closed walk i_0 -> ... -> i_{k-1} -> i_0 with probability P and product Pi = Acl_{i_{k-1}} ...
    Acl_{i_0}, rho^k >= P rho(Pi)^2: the k-th power of the second-moment map dominates, as positive
    maps, the map X -> P Pi X_{i_0} Pi^T into mode i_0 alone, whose spectral radius is P rho(Pi)^2.
    Walks of length 1 (i -> i) and 2 (i -> j -> i); exact for one mode (rho = rho(Acl)^2); the
    largest bound per gain.

    Examples
    --------
    >>> sys, gains = draw_system(np.random.default_rng(1), siso=True), np.linspace(-2.0, 2.0, 9)
    >>> bool(np.all(walk_lower_bounds(sys, gains) <= scalar_gain_radii(sys, gains) * (1 + 1e-12)))
    True
    """
    Acl = _scalar_closed_loops(sys, gains)
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
    """Index and value of the first smallest entry of ``scalar_gain_radii(sys, gains)``, with rho
    computed only where it can be the smallest. rho at the BOUND_SEEDS gains of smallest lower bound
    gives m >= the minimum; a gain whose lower bound (:func:`radius_lower_bounds`, then
    :func:`walk_lower_bounds`) exceeds BOUND_MARGIN max(m, BOUND_FLOOR) has a larger rho (the margin
    covers the rounding of the bounds and of the eigenvalues) and is skipped (a seed is not
    evaluated twice).
    """
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
    """Min over scalar L of rho: a grid in L = tan(s), s in (-pi/2, pi/2) (all real gains),
    refined by a bounded scalar search between the grid neighbours of the best point.
    """
    s = np.linspace(-np.pi / 2, np.pi / 2, points + 2)[1:-1]
    best, rho = grid_minimum(sys, np.tan(s))
    lo, hi = s[max(best - 1, 0)], s[min(best + 1, points - 1)]
    res = scipy.optimize.minimize_scalar(lambda t: scalar_gain_radii(sys, np.array([np.tan(t)]))[0],
                                         bounds=(lo, hi), method="bounded",
                                         options={"xatol": 1e-10})
    if res.fun < rho:
        return float(np.tan(res.x)), float(res.fun)
    return float(np.tan(s[best])), float(rho)


def best_gain(sys, rng, starts=20):
    """Min over L (nu x ny) of rho: the scalar grid for SISO, else Nelder-Mead from ``starts``
    starts (L = 0 and standard normal draws). Returns (L, rho).
    """
    if sys.nu == sys.ny == 1:
        L, rho = best_scalar_gain(sys)
        return np.array([[L]]), rho
    shape = (sys.nu, sys.ny)
    f = lambda v: ms_spectral_radius(closed_loop(sys, v.reshape(shape)), sys.T)
    best = (np.zeros(shape), f(np.zeros(shape).ravel()))
    for k in range(starts):
        x0 = np.zeros(shape).ravel() if k == 0 else rng.standard_normal(shape).ravel()
        res = scipy.optimize.minimize(f, x0, method="Nelder-Mead", options={"xatol": 1e-8,
                                                                            "fatol": 1e-10,
                                                                            "maxiter": 2000})
        if res.fun < best[1]:
            best = (res.x.reshape(shape), float(res.fun))
    return best


# ---------------------------------------------------------------- Monte Carlo

class ModeChain:
    """The runs' mode chain: theta_{k+1} given theta_k by inverse transform of the rows of T.

    The cumulative sums of T's rows are computed once. The next mode is the number of
    cumulative sums of the row of theta_k below a uniform draw u, at most M - 1; the sums do
    not decrease, so the row's last sum (about 1) is below u only when all are: it is not needed.

    Parameters
    ----------
    T : ndarray, shape (M, M)
        Transition matrix (rows sum to 1, entries >= 0: the cumulative sums do not decrease).

    Examples
    --------
    >>> chain = ModeChain(np.array([[0.9, 0.1], [0.0, 1.0]]))
    >>> chain.next(np.random.default_rng(0), np.array([0, 1, 1]))
    array([0, 1, 1])
    """

    def __init__(self, T):
        T = np.asarray(T, dtype=float)
        if T.ndim != 2 or T.shape[0] != T.shape[1]:
            raise ValueError("T: expected a square transition matrix (M, M), found shape "
                             f"{T.shape}")
        # row j: sum_{l <= j} p_il
        self.thresholds = np.ascontiguousarray(np.cumsum(T, axis=1)[:, :-1].T)

    def next(self, rng, theta):
        """theta_{k+1} for every run (one uniform draw per run, ``rng.random(len(theta))``)."""
        u = rng.random(len(theta))
        if len(self.thresholds) == 0:
            return np.zeros(len(theta), dtype=np.intp)
        passed = (u > self.thresholds[0].take(theta)).astype(np.intp)
        # one pass per mode: no reduction over the narrow mode axis
        for column in self.thresholds[1:]:
            passed += u > column.take(theta)
        return passed


def initial_modes(rng, mu, n_runs):
    """theta_0 ~ ``mu`` for each of ``n_runs`` runs (one uniform draw per run)."""
    return np.minimum((rng.random(n_runs)[:, None] > np.cumsum(mu)[None]).sum(axis=1), len(mu) - 1)


@functools.lru_cache(maxsize=16)
def _run_offsets(runs, step):
    """0, step, 2 step, ... for ``runs`` runs (read-only: shared by the steps of a simulation)."""
    offsets = np.arange(runs) * step
    offsets.flags.writeable = False
    return offsets


class RunModes:
    """The modes theta of all runs at one step, indexed for :class:`ModeOperator`: made once per
    step and shared by every product of the step.

    Attributes
    ----------
    theta : ndarray of int, shape (runs,)
        The mode of each run.
    n_modes : int
        The number of modes M.

    Examples
    --------
    >>> RunModes(np.array([1, 0, 1]), 2).run_major       # rows r M + theta_r
    array([1, 2, 5])
    """

    def __init__(self, theta, n_modes):
        self.theta, self.n_modes = theta, n_modes
        self._run_major = None

    @property
    def run_major(self):
        """Row r M + theta_r of the (runs M, m) products of every run by every mode: run r's own."""
        if self._run_major is None:
            self._run_major = _run_offsets(len(self.theta), self.n_modes) + self.theta
        return self._run_major


class ModeOperator:
    """Rows x_r -> S_{theta_r} x_r for all runs, with one matrix product per operator: x times
    [S_1^T ... S_M^T], then each run's own block of m columns.

    This computes M times the products that one matmul per mode over its runs computes, but in
    one BLAS call instead of M gathers, products and scatters on arrays of a few columns (the
    same dot products, equal to rounding).

    Parameters
    ----------
    S : ndarray, shape (M, m, n)
        One matrix per mode.

    Examples
    --------
    >>> S = np.array([[[1.0, 2.0]], [[0.0, 3.0]]])
    >>> x = np.array([[1.0, 1.0], [2.0, 0.0], [1.0, -1.0]])
    >>> ModeOperator(S)(x, RunModes(np.array([0, 1, 0]), 2))
    array([[ 3.],
           [ 0.],
           [-1.]])
    """

    def __init__(self, S):
        S = np.asarray(S, dtype=float)
        if S.ndim != 3:
            raise ValueError("S: expected one matrix per mode, shape (M, m, n), found shape "
                             f"{S.shape}")
        n_modes, self.m, n = S.shape
        self.stacked = np.ascontiguousarray(S.transpose(2, 0, 1).reshape(n, n_modes * self.m))

    def __call__(self, x, modes):
        """S_{theta_r} x_r per row of ``x`` (runs, n); ``modes``: the runs' :class:`RunModes`."""
        return (x @ self.stacked).reshape(-1, self.m).take(modes.run_major, axis=0)


def moment_estimate(samples):
    """Mean and standard error over the first axis (runs)."""
    return samples.mean(axis=0), samples.std(axis=0, ddof=1) / np.sqrt(len(samples))


def indicator_moment_estimate(x, theta, n_modes):
    """Mean and standard error over the runs of x_r x_r^T 1(theta_r = i), each of shape (M, n, n).

    Examples
    --------
    >>> x, theta = np.array([[1.0, 0.5], [2.0, -1.0], [3.0, 0.0]]), np.array([0, 1, 0])
    >>> mean, se = indicator_moment_estimate(x, theta, 2)
    >>> # mode 0: x x^T of runs 0 and 2; mode 1: of run 1
    >>> (3 * mean).round(12).tolist()
    [[[10.0, 0.5], [0.5, 0.25]], [[4.0, -2.0], [-2.0, 1.0]]]
    """
    samples = np.zeros((len(x), n_modes, x.shape[1], x.shape[1]))
    samples[np.arange(len(x)), theta] = np.einsum("ra,rb->rab", x, x)
    return moment_estimate(samples)


def stationary_average(rng, step, stage_cost, state, theta, T, rho, n_runs, steps=100, tail=1e-4):
    """Monte Carlo of the stationary average cost of a mean-square stable loop.

    ``step(state, modes, rng)`` advances all runs, ``stage_cost(state, modes)`` is the cost
    per run, with ``modes`` the :class:`RunModes` of the step (the modes start at ``theta``
    and follow :class:`ModeChain` of ``T``). A burn-in of log(tail)/log(rho) steps makes the
    transient's share below ``tail``; then each run averages ``steps`` stage costs. Returns
    (mean, standard error) over the runs (independent) and the burn-in.
    """
    burn = int(np.ceil(np.log(tail) / np.log(max(rho, 1e-3))))
    chain, n_modes = ModeChain(T), len(T)
    for _ in range(burn):
        state, theta = step(state, RunModes(theta, n_modes), rng), chain.next(rng, theta)
    total = np.zeros(n_runs)
    for _ in range(steps):
        modes = RunModes(theta, n_modes)
        total += stage_cost(state, modes)
        state, theta = step(state, modes, rng), chain.next(rng, theta)
    mean, se = moment_estimate(total / steps)
    return float(mean), float(se), burn


def random_spd(rng, n, scale=1.0):
    """A random SPD n x n matrix ``scale`` (G G^T / n + 0.1 I), G standard normal."""
    G = rng.standard_normal((n, n))
    return scale * (G @ G.T / n + 0.1 * np.eye(n))


def random_spd_stack(rng, M, n, scale=1.0):
    """``M`` independent :func:`random_spd` matrices, stacked (M, n, n)."""
    return np.stack([random_spd(rng, n, scale) for _ in range(M)])


def min_eig(S):
    """Smallest eigenvalue over a stack of symmetric matrices."""
    return float(np.min(np.linalg.eigvalsh(sym(np.asarray(S)))))


def trace_sum(A, B):
    """sum_i tr[A_i B_i] over a stack (or tr[A B] of two matrices).

    Examples
    --------
    >>> trace_sum(np.stack([np.eye(2), 2 * np.eye(2)]), np.stack([np.eye(2)] * 2))
    6.0
    """
    return float(np.sum(A * transpose(B)))


def verdict(ok):
    """Return "holds" if ``ok`` else "fails"."""
    return "holds" if ok else "fails"


def outcome(verdict, sys=None, **numbers):
    """An Outcome with plain numbers; a failing instance also carries its system as data.

    Examples
    --------
    >>> outcome("holds", None, gap=np.float64(0.5), ok=np.bool_(True)).numbers
    {'gap': 0.5, 'ok': True}
    """
    plain = lambda v: (v.tolist() if isinstance(v, np.ndarray)
                       else float(v) if isinstance(v, np.floating)
                       else bool(v) if isinstance(v, np.bool_) else v)
    clean = {k: plain(v) for k, v in numbers.items()}
    if sys is not None:
        clean.update(size(sys))
        if verdict == "fails":
            clean["system"] = _system_data(sys)
    return Outcome(verdict, clean)


def stabilised(rng, sys, gain_fn, low=0.2, high=0.85):
    """Rescale A_i, B_i so the closed loop of ``gain_fn(sys)`` has rho uniform in [low, high]."""
    target = rng.uniform(low, high)
    factor = _radius_to(sys, gain_fn(sys), target)
    return rescaled(sys, factor), target


# ---------------------------------------------------------------- Gaussian-mixture initial states

def gaussian_mixture(rng, sys):
    """A random Gaussian mixture of x_0: weights mu_0, means (M, n), covariances (M, n, n)."""
    mu0 = rng.dirichlet(np.ones(sys.M))
    mean0 = rng.standard_normal((sys.M, sys.nx))
    cov0 = random_spd_stack(rng, sys.M, sys.nx, 0.2)
    return mu0, mean0, cov0


def sample_mixture(rng, mu0, mean0, cov0, n_runs):
    """``n_runs`` draws (x_0, theta_0) of the mixture."""
    theta = initial_modes(rng, mu0, n_runs)
    chol = ModeOperator(np.linalg.cholesky(cov0))
    draws = rng.standard_normal((n_runs, mean0.shape[1]))
    x = mean0[theta] + chol(draws, RunModes(theta, len(mu0)))
    return x, theta


def z_scores(x, theta, exact, mu, min_hits=100):
    """Largest |Monte Carlo - exact| / standard error, the Monte Carlo of E{x x^T 1(theta = i)} over
    the runs (x, theta), over the entries of the modes with at least ``min_hits`` expected visits
    (rarer modes have too few samples for a normal standard error).
    """
    mean, se = indicator_moment_estimate(x, theta, len(mu))
    seen = mu * len(x) >= min_hits
    if not seen.any():
        return 0.0
    scale = 1e-12 * (1 + np.abs(exact).max())
    return float(np.max(np.abs(mean - exact)[seen] / np.maximum(se, scale)[seen]))


def norm_scale(rng, Acl):
    """Factor making max_i ||Acl_i||_2 uniform on [0.5, 1.5]. A Monte Carlo estimate of a moment is
    only trustworthy when no rare mode path carries it: with ||Acl_i|| = 3, a path staying in mode i
    multiplies x x^T by 9 per step, and a few samples decide the mean (the standard error then
    misleads).
    """
    return float(rng.uniform(0.5, 1.5) / np.max(np.linalg.norm(Acl, ord=2, axis=(1, 2))))
