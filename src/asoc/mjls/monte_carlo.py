"""Monte Carlo simulation of an MJLS (3.7) in closed loop, vectorised over runs.

All runs advance together: at step k the modes theta_k (N,), states x_k (N, nx) and
controller states are arrays, and the mode-dependent matrices are gathered per run.
Random draws come from the ``rng`` passed in, in a fixed order (initial mode, initial
state, then per step: process noise, measurement noise, next mode), so a seed gives
the same numbers bit for bit.
"""

from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from ..progress import progress_bar
from ..validation import boolean, generator, integer, probability_vector, real_array, semidefinite
from .controllers import as_controller
from .system import check_system

__all__ = ["SimulationResult", "GROUPED_MIN_NX", "simulate"]


@dataclass
class SimulationResult:
    """Per-run costs of (3.3): cost = sum_{k<K} (x'Q x + u'R u) + x_K' Q x_K, and, on request,
    trajectories x (N, horizon + 1, nx), u (N, horizon, nu), theta (N, horizon + 1).

    Examples
    --------
    >>> res = SimulationResult(cost=np.array([10.0, 20.0]), horizon=10)
    >>> res.average_cost
    array([1., 2.])
    """

    cost: np.ndarray
    horizon: int
    x: np.ndarray | None = None
    u: np.ndarray | None = None
    theta: np.ndarray | None = None

    @property
    def average_cost(self):
        """Per-run cost divided by the horizon (the finite-horizon reading of (3.9))."""
        return self.cost / self.horizon


def _initial_states(sys, x0, x0_cov, theta0, n_runs, rng):
    if x0.shape == (sys.nx,):
        mean = np.broadcast_to(x0, (n_runs, sys.nx))
    elif x0.shape == (sys.M, sys.nx):
        mean = x0[theta0]
    else:
        raise ValueError(f"x0: expected shape ({sys.nx},) or ({sys.M}, {sys.nx}), found {x0.shape}")
    if x0_cov is None:
        return mean.copy()
    cov = x0_cov
    if cov.shape == (sys.nx, sys.nx):
        cov = np.broadcast_to(cov, (sys.M, sys.nx, sys.nx))
    roots = np.stack([_psd_sqrt(c, i) for i, c in enumerate(cov)])
    return mean + np.einsum("nab,nb->na", roots[theta0], rng.standard_normal((n_runs, sys.nx)))


def _psd_sqrt(c, i):
    lam, vec = np.linalg.eigh(0.5 * (c + c.T))
    if lam.min() < -1e-10 * max(1.0, abs(lam).max()):
        raise ValueError(f"x0_cov: mode {i + 1} covariance is not positive semidefinite")
    return vec * np.sqrt(np.clip(lam, 0, None))


def _next_mode(theta, r, cumT):
    """theta_{k+1} = #{j < M-1 : r > cumT[theta_k, j]} for uniform r: inverse-CDF sampling of
    the row theta_k of T.
    """
    nxt = np.zeros_like(theta)
    for j in range(cumT.shape[1] - 1):
        nxt += r > cumT[theta, j]
    return nxt


class _ModeStack:
    """Mode-dependent products for all runs at once: one matrix product per quantity for
    all modes (BLAS), then each run's row picked by its mode, instead of gathering an
    (N, n, n) stack of matrices per step.
    """

    def __init__(self, sys):
        self.M, self.nx, self.nu = sys.M, sys.nx, sys.nu
        cat = lambda S: np.concatenate(list(np.swapaxes(S, 1, 2)), axis=1)   # (cols, M*rows)
        self.ABH = cat(np.concatenate([sys.A, sys.B, sys.H], axis=2))
        self.C = cat(sys.C)
        self.J = cat(sys.J) if sys.J is not None else None
        self.Q, self.R = cat(sys.Q), cat(sys.R)

    def rows(self, theta):
        return np.arange(theta.size) * self.M + theta

    def _pick(self, flat, rows):
        # np.take gathers whole rows; ``flat[rows]`` takes numpy's general fancy-index path
        # (15x slower)
        return np.take(flat.reshape(rows.size * self.M, -1), rows, axis=0)

    def output(self, x, rows):
        return self._pick(x @ self.C, rows)

    def measurement_noise(self, v, rows):
        return self._pick(v @ self.J, rows)

    def stage_cost(self, x, u, rows):
        return (np.einsum("na,na->n", self._pick(x @ self.Q, rows), x)
                + np.einsum("na,na->n", self._pick(u @ self.R, rows), u))

    def terminal_cost(self, x, rows):
        return np.einsum("na,na->n", self._pick(x @ self.Q, rows), x)

    def transition(self, x, u, w, rows):
        return self._pick(_stacked_columns(x, u, w) @ self.ABH, rows)


def _stacked_columns(*blocks):
    """``np.concatenate(blocks, axis=1)`` for (N, k) blocks with small k, as the transpose of a
    (sum k, N) array: copying a narrow block into a row stripe is several times faster than into
    a column stripe, and the values are the same.
    """
    out = np.empty((sum(b.shape[1] for b in blocks), blocks[0].shape[0]))
    start = 0
    for b in blocks:
        out[start:start + b.shape[1]] = b.T
        start += b.shape[1]
    return out.T


class _ModeGroups:
    """The same products as :class:`_ModeStack`, computed per mode on the runs in that mode:
    N n^2 instead of M N n^2 operations per step, for large systems (nx >= GROUPED_MIN_NX).
    """

    def __init__(self, sys):
        T = lambda S: np.ascontiguousarray(np.swapaxes(S, 1, 2))
        self.M = sys.M
        self.ABH = T(np.concatenate([sys.A, sys.B, sys.H], axis=2))
        self.C, self.Q, self.R = T(sys.C), sys.Q, sys.R
        self.J = T(sys.J) if sys.J is not None else None

    def rows(self, theta):
        order = np.argsort(theta, kind="stable")
        bounds = np.searchsorted(theta[order], np.arange(self.M + 1))
        return [order[bounds[i]:bounds[i + 1]] for i in range(self.M)]

    def _apply(self, x, mats, groups):
        out = np.empty((x.shape[0], mats.shape[2]))
        for i, idx in enumerate(groups):
            if idx.size:
                out[idx] = x[idx] @ mats[i]
        return out

    def output(self, x, groups):
        return self._apply(x, self.C, groups)

    def measurement_noise(self, v, groups):
        return self._apply(v, self.J, groups)

    def stage_cost(self, x, u, groups):
        return (np.einsum("na,na->n", self._apply(x, self.Q, groups), x)
                + np.einsum("na,na->n", self._apply(u, self.R, groups), u))

    def terminal_cost(self, x, groups):
        return np.einsum("na,na->n", self._apply(x, self.Q, groups), x)

    def transition(self, x, u, w, groups):
        return self._apply(np.concatenate([x, u, w], axis=1), self.ABH, groups)


#: State dimension from which the Monte Carlo multiplies per mode (:class:`_ModeGroups`)
#: instead of by all modes at once (:class:`_ModeStack`): measured crossover on 2 cores.
GROUPED_MIN_NX = 12


def simulate(sys, controller, x0, horizon, n_runs, rng, mode0=None, mu0=None, x0_cov=None,
             trajectories=False, progress=False):
    """Monte Carlo of ``n_runs`` closed-loop runs of ``horizon`` steps, vectorised over runs.

    BLAS is limited to one thread here: the products are small (N x 5 by 5 x 4), and
    threading them costs more than it gains. Every argument, and the controller against the
    system (:meth:`Controller.check`), is checked before the first step.

    Parameters
    ----------
    sys : MJLS
    controller : Controller or a design result
        E.g. :class:`asoc.mjls.StaticGain`, :class:`asoc.mjls.DynamicOutputFeedback`,
        :class:`asoc.mjls.ModeDependentGain`,
        or the result of a design (``static_output_feedback(sys)``, ...), whose
        ``.controller`` is used.
    x0 : array_like, (nx,) or (M, nx)
        Initial state, or per-mode means of a Gaussian mixture (Sec. 3.7).
    horizon : int
        Number of steps, >= 1.
    n_runs : int
        N >= 1 runs.
    rng : numpy.random.Generator
        The only source of random numbers (initial mode, initial state, then per step:
        process noise, measurement noise, next mode).
    mode0 : int, optional
        Fixed initial mode (0-based), or None to draw theta_0 from ``mu0``.
    mu0 : array_like, shape (M,), optional
        Initial mode distribution (default: the stationary distribution).
    x0_cov : array_like, (nx, nx) or (M, nx, nx), optional
        Covariance of x_0 given theta_0.
    trajectories : bool
        Also return x, u and theta of every run.
    progress : bool
        Show a progress bar over the steps.

    Returns
    -------
    SimulationResult
        Per-run costs of (3.3) (``average_cost`` divides by K) and, on request, trajectories.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, ``controller`` not a Controller, ``rng`` not a Generator,
        ``horizon``, ``n_runs`` or ``mode0`` not an integer, a flag not a bool, or an array
        not real.
    ValueError
        If ``horizon`` or ``n_runs`` is < 1, ``mode0`` is out of range, ``mu0``, ``x0``,
        ``x0_cov`` have the wrong shape or are invalid (non-finite, ``x0_cov`` not symmetric
        positive semidefinite), or the controller does not fit the system.

    Examples
    --------
    >>> from asoc.mjls.controllers import StaticGain
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> res = simulate(sys, StaticGain([[-0.4]]), [3.0, 0.0], 50, 200, np.random.default_rng(1))
    >>> res.cost.shape, bool(res.average_cost.mean() < 10)
    ((200,), True)
    """
    check_system(sys)
    controller = as_controller(controller, sys=sys)
    controller.check(sys)
    x0 = real_array(x0, "x0")
    if x0.shape not in ((sys.nx,), (sys.M, sys.nx)):
        raise ValueError(f"x0: expected shape ({sys.nx},) or ({sys.M}, {sys.nx}), "
                         f"found shape {x0.shape}")
    horizon = integer(horizon, "horizon", minimum=1)
    n_runs = integer(n_runs, "n_runs", minimum=1)
    generator(rng, "rng")
    if mode0 is not None:
        mode0 = integer(mode0, "mode0", minimum=0, maximum=sys.M - 1)
    mu0 = sys.mu_inf if mu0 is None else probability_vector(mu0, "mu0", sys.M)
    if x0_cov is not None:
        x0_cov = real_array(x0_cov, "x0_cov")
        if x0_cov.shape not in ((sys.nx, sys.nx), (sys.M, sys.nx, sys.nx)):
            raise ValueError(f"x0_cov: expected shape ({sys.nx}, {sys.nx}) or "
                             f"({sys.M}, {sys.nx}, {sys.nx}), found shape {x0_cov.shape}")
        x0_cov = semidefinite(x0_cov, "x0_cov")
    trajectories, progress = boolean(trajectories, "trajectories"), boolean(progress, "progress")
    with threadpool_limits(limits=1, user_api="blas"):
        return _simulate(sys, controller, x0, horizon, n_runs, rng, mode0, mu0, x0_cov,
                         trajectories, progress)


def _simulate(sys, controller, x0, horizon, n_runs, rng, mode0, mu0, x0_cov, trajectories,
              progress):
    """Simulate ``n_runs`` closed-loop runs of ``horizon`` steps (arguments checked by simulate)."""
    N, K = n_runs, horizon
    if mode0 is not None:
        theta = np.full(N, mode0)
    else:
        theta = rng.choice(sys.M, size=N, p=mu0)
    x = _initial_states(sys, x0, x0_cov, theta, N, rng)
    cumT = np.cumsum(sys.T, axis=1)
    cumT[:, -1] = 1.0
    step = _ModeGroups(sys) if sys.nx >= GROUPED_MIN_NX else _ModeStack(sys)
    state = controller.start(N)
    cost = np.zeros(N)
    if trajectories:
        xs, us = np.empty((N, K + 1, sys.nx)), np.empty((N, K, sys.nu))
        ths = np.empty((N, K + 1), int)
    for k in progress_bar(range(K), progress, desc="Monte Carlo", leave=False):
        rows = step.rows(theta)
        y = step.output(x, rows)
        w = rng.standard_normal((N, sys.nw))
        if sys.J is not None:
            y += step.measurement_noise(rng.standard_normal((N, sys.J.shape[2])), rows)
        u, state = controller.input(k, y, theta, state)
        cost += step.stage_cost(x, u, rows)
        if trajectories:
            xs[:, k], us[:, k], ths[:, k] = x, u, theta
        x = step.transition(x, u, w, rows)
        theta = _next_mode(theta, rng.random(N), cumT)
    cost += step.terminal_cost(x, step.rows(theta))
    if trajectories:
        xs[:, K], ths[:, K] = x, theta
        return SimulationResult(cost, K, xs, us, ths)
    return SimulationResult(cost, K)
