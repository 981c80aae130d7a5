"""The finite-horizon model of Sec. 3.7: the time-variant MJLS (3.54) step by step.

:class:`Stages` holds one MJLS per step k = 0..K-1, the terminal weight Q_K and the noise
covariances per step; :func:`mode_distributions` gives mu_k = P(theta_k = i); and
:func:`check_initial_state` validates the Gaussian-mixture initial state (x_0 given
theta_0 = i has mean ``mean0[i]`` and covariance ``cov0[i]``, theta_0 has distribution
``mu0``). Alg. 3.3 (:mod:`.finite_horizon`), the exact-cost design
(:mod:`.exact_cost_design`) and the mode-observing baseline (:mod:`.observed_mode_lqg`)
share them.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..validation import integer, probability_vector, real_array, semidefinite
from .closed_loops import noise_covariances
from .system import MJLS

__all__ = ["Stages", "StackedStages", "stages", "check_initial_state", "mode_distributions"]


@dataclass(frozen=True)
class Stages:
    """The time-variant MJLS (3.54) over a horizon: one MJLS per step k = 0..K-1 and the
    terminal weight Q_K (M, nx, nx); noise covariances HHt, JJt per step.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> st = stages(sys, 4)
    >>> st.horizon, len(st.HHt)
    (4, 4)
    """

    systems: tuple
    Q_final: np.ndarray
    HHt: tuple
    JJt: tuple

    @property
    def horizon(self):
        """The number of steps K."""
        return len(self.systems)

    @cached_property
    def stacked(self) -> "StackedStages":
        """The matrices of all steps stacked over k, computed once (:class:`StackedStages`).

        Examples
        --------
        >>> from asoc.mjls.examples import sec373_system
        >>> st = stages(sec373_system(1), 4)
        >>> st.stacked.A.shape, st.stacked.HHt.shape, st.stacked is st.stacked
        ((4, 2, 2, 2), (4, 2, 2, 2), True)
        """
        stacked = {name: np.stack([getattr(s, name) for s in self.systems]) for name in "ABCQRT"}
        return StackedStages(**stacked, HHt=np.stack(self.HHt), JJt=np.stack(self.JJt))


@dataclass(frozen=True)
class StackedStages:
    """The matrices of the time-variant MJLS (3.54) stacked over the steps k = 0..K-1.

    Attributes
    ----------
    A, B, C, Q, R : numpy.ndarray, shape (horizon, M, ., .)
    T : numpy.ndarray, shape (horizon, M, M)
    HHt, JJt : numpy.ndarray, shape (horizon, M, ., .)
        The noise covariances H_i H_i^T and J_i J_i^T per step.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    T: np.ndarray
    HHt: np.ndarray
    JJt: np.ndarray


def stages(sys, horizon):
    """Normalise ``sys`` (an MJLS, or a sequence of ``horizon`` or ``horizon + 1`` MJLS for
    the time-variant model (3.54); a last extra entry only supplies Q_K) into :class:`Stages`.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> st = stages([sys, sys, sys.replace(Q=2 * np.eye(2))], 2)
    >>> st.horizon, float(st.Q_final[0, 0, 0])
    (2, 2.0)
    """
    horizon = integer(horizon, "horizon", minimum=1)
    if isinstance(sys, MJLS):
        systems = (sys,) * horizon
        Q_final = sys.Q
    else:
        if not isinstance(sys, (list, tuple)):
            raise TypeError("sys: expected an MJLS or a sequence of MJLS, found "
                            f"{type(sys).__name__}")
        systems = tuple(sys)
        lengths = (horizon, horizon + 1)
        if len(systems) not in lengths or not all(isinstance(s, MJLS) for s in systems):
            raise ValueError(f"sys: expected an MJLS or a sequence of {horizon} or {horizon + 1} "
                             f"MJLS, found {type(sys).__name__} of length {len(systems)}")
        ref = systems[0]
        for k, s in enumerate(systems):
            if (s.M, s.nx, s.nu, s.ny) != (ref.M, ref.nx, ref.nu, ref.ny):
                raise ValueError(f"sys: step {k} has (M, nx, nu, ny) = {(s.M, s.nx, s.nu, s.ny)}, "
                                 f"step 0 has {(ref.M, ref.nx, ref.nu, ref.ny)}")
        Q_final = systems[-1].Q
        systems = systems[:horizon]
    cache = {}
    for s in systems:
        if id(s) not in cache:
            cache[id(s)] = noise_covariances(s)
    HHt = tuple(cache[id(s)][0] for s in systems)
    JJt = tuple(cache[id(s)][1] for s in systems)
    return Stages(systems, Q_final, HHt, JJt)


def check_initial_state(M, nx, mean0, cov0, mu0):
    """Validate the Gaussian-mixture initial state; return (mean0, cov0, mu0) as arrays.

    Examples
    --------
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> mean0, cov0, mu0 = check_initial_state(2, 2, SEC373_MEAN0[1], SEC373_COV0, [1, 0])
    >>> mu0
    array([1., 0.])
    """
    mu0 = probability_vector(mu0, "mu0", M)
    mean0 = real_array(mean0, "mean0", shape=(M, nx))
    cov0 = semidefinite(real_array(cov0, "cov0", shape=(M, nx, nx)), "cov0")
    return mean0, cov0, mu0


def mode_distributions(st, mu0):
    """mu_k = mu_0 T_0 ... T_{k-1} for k = 0..horizon, shape (horizon + 1, M).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> mode_distributions(stages(sys, 2), np.array([1.0, 0.0])).round(3).tolist()
    [[1.0, 0.0], [0.7, 0.3], [0.67, 0.33]]
    """
    mu = np.empty((st.horizon + 1, len(mu0)))
    mu[0] = mu0
    for k, s in enumerate(st.systems):
        mu[k + 1] = mu[k] @ s.T
    return mu
