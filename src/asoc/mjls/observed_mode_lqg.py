"""Baseline [38] of Table 3.3: finite-horizon output feedback WITH mode observation.

O. L. V. Costa, M. D. Fragoso, R. P. Marques, *Discrete-Time Markov Jump Linear Systems*,
Springer 2005 ([38] of the thesis). With theta_k observed, the quadratic problem with
partial state information separates (their Ch. 5, finite-horizon case with the Markov
jump filter; also Dolgov & Hanebeck, arXiv:1507.00304, Sec. 1: "mode availability
guarantees that the separation between control and estimation holds"):

* control: the mode-dependent LQ gains of the coupled Riccati difference equations
  (their Ch. 4, finite horizon),

      X_i(K) = Q_i,   S_i(k) = R_i + B_i^T E_i(X(k+1)) B_i,
      F_i(k) = -S_i(k)^{-1} B_i^T E_i(X(k+1)) A_i,
      X_i(k) = Q_i + A_i^T E_i(X(k+1)) (A_i + B_i F_i(k)),

* estimation: the Markov jump filter, the best linear estimator whose gain depends on
  the current mode and time only (their Ch. 5), in predictor form so that u_k uses
  y_0..y_{k-1} as the controllers (3.37)/(3.55) do:

      x^_{k+1} = A_i x^_k + B_i u_k + M_i(k) (y_k - C_i x^_k),   i = theta_k,
      M_i(k) = A_i Y_i(k) C_i^T (C_i Y_i(k) C_i^T + pi_i(k) J_i J_i^T)^+,
      Y_j(k+1) = sum_i p_ij [A_i Y_i(k) A_i^T - M_i(k) C_i Y_i(k) A_i^T + pi_i(k) H_i H_i^T],

  with Y_i(k) = E{(x_k - x^_k)(x_k - x^_k)^T 1(theta_k = i)} and pi_i(k) = P(theta_k = i).
  Y_j(k+1) is minimal in the positive semidefinite order because M_i(k) enters only the
  i-th summand (A_i - M C_i) Y_i (A_i - M C_i)^T + pi_i M J_i J_i^T M^T, which M_i(k)
  minimises (completion of squares); the estimation error does not depend on u.

u_k = F_{theta_k}(k) x^_k. The filter starts at x^_0 = E{x_0} with
Y_i(0) = mu0_i (cov0[i] + (mean0[i] - x^_0)(mean0[i] - x^_0)^T).
"""

from dataclasses import dataclass, field

import numpy as np

from ..linalg import transpose
from ..validation import real_array
from .controllers import Controller
from .finite_horizon import augmented_cost, augmented_initial_moment
from .finite_horizon_model import check_initial_state, mode_distributions, stages
from .system import check_system

__all__ = ["ModeObservedResult", "ModeObservedLQG", "mode_observed_lqg"]


@dataclass
class ModeObservedResult:
    """Result of :func:`mode_observed_lqg`.

    Attributes
    ----------
    F : numpy.ndarray, shape (horizon, M, nu, nx)
        LQ gains.
    Mf : numpy.ndarray, shape (horizon, M, nx, ny)
        Markov jump filter gains.
    X : numpy.ndarray, shape (horizon + 1, M, nx, nx)
        Control Riccati solutions.
    Y : numpy.ndarray, shape (horizon + 1, M, nx, nx)
        Filter error moments.
    xhat0 : numpy.ndarray, shape (nx,)
    cost : float
        The exact expected cost (3.56) of the closed loop (augmented second-moment recursion).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.examples import SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = mode_observed_lqg(sys, 4, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0)
    >>> res.X.shape, res.Y.shape, res.xhat0.tolist()
    ((5, 2, 2, 2), (5, 2, 2, 2), [5.0, 0.0])
    """

    F: np.ndarray
    Mf: np.ndarray
    X: np.ndarray = field(repr=False)
    Y: np.ndarray = field(repr=False)
    xhat0: np.ndarray = None
    cost: float = np.nan

    def controller(self, sys):
        """The controller for :func:`asoc.mjls.simulate` (it reads theta_k)."""
        return ModeObservedLQG(sys, self.F, self.Mf, self.xhat0)


class ModeObservedLQG(Controller):
    """u_k = F_{theta_k}(k) x^_k with the Markov jump filter x^ (needs the mode, [38]).

    Parameters
    ----------
    sys : MJLS
    F, Mf : array_like
        Gains of :class:`ModeObservedResult`.
    xhat0 : array_like, shape (nx,)
        Filter initial state.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> sys = sec373_system(1)
    >>> res = mode_observed_lqg(sys, 5, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0)
    >>> controller = res.controller(sys)
    >>> controller.observes_mode, controller.start(3).shape, controller
    (True, (3, 2), ModeObservedLQG(horizon=5, M=2, nx=2, ny=1, nu=1))
    """

    observes_mode = True

    def __init__(self, sys, F, Mf, xhat0):
        check_system(sys)
        self.A, self.B, self.C = sys.A, sys.B, sys.C
        self.F = real_array(F, "F", ndim=4)
        horizon = self.F.shape[0]
        self.F = real_array(F, "F", shape=(horizon, sys.M, sys.nu, sys.nx))
        self.Mf = real_array(Mf, "Mf", shape=(horizon, sys.M, sys.nx, sys.ny))
        self.xhat0 = real_array(xhat0, "xhat0", shape=(sys.nx,))
        self._dims = (sys.M, sys.nx, sys.nu, sys.ny)

    def check(self, sys):
        """Raise a ValueError when ``sys`` has other (M, nx, nu, ny) than the design's system."""
        if (sys.M, sys.nx, sys.nu, sys.ny) != self._dims:
            raise ValueError(f"controller: built for (M, nx, nu, ny) = {self._dims}, found "
                             f"{(sys.M, sys.nx, sys.nu, sys.ny)}")

    def start(self, n_runs):
        """The filter's initial estimate x^_0 for each of ``n_runs`` runs, shape (n_runs, nx)."""
        return np.broadcast_to(self.xhat0, (n_runs, self.xhat0.size)).copy()

    def input(self, k, y, theta, xhat):
        """``(u, xhat)`` at step k: u_k = F_theta(k) x^_k and the Markov jump filter's x^_{k+1}."""
        k = min(k, len(self.F) - 1)
        u = np.einsum("nab,nb->na", self.F[k][theta], xhat)
        innovation = y - np.einsum("nab,nb->na", self.C[theta], xhat)
        xhat = (np.einsum("nab,nb->na", self.A[theta], xhat)
                + np.einsum("nab,nb->na", self.B[theta], u)
                + np.einsum("nab,nb->na", self.Mf[k][theta], innovation))
        return u, xhat

    def _sizes(self):
        return dict(zip(("horizon", "M", "nx", "ny", "nu"), (len(self.F), *self._dims[:2],
                                                             self._dims[3], self._dims[2])))


def _control_riccati(st):
    """Coupled Riccati difference equations of the LQ problem with observed mode ([38], Ch. 4).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.finite_horizon_model import stages
    >>> F, X = _control_riccati(stages(sys, 3))
    >>> F.shape, np.allclose(X[-1], sys.Q)
    ((3, 2, 1, 2), True)
    """
    K_ = st.horizon
    s0 = st.systems[0]
    X = np.empty((K_ + 1, s0.M, s0.nx, s0.nx))
    F = np.empty((K_, s0.M, s0.nu, s0.nx))
    X[K_] = st.Q_final
    for k in range(K_ - 1, -1, -1):
        s = st.systems[k]
        EX = s.successor_average(X[k + 1])
        BtEX = transpose(s.B) @ EX
        F[k] = -np.linalg.solve(s.R + BtEX @ s.B, BtEX @ s.A)
        Xk = s.Q + transpose(s.A) @ EX @ (s.A + s.B @ F[k])
        X[k] = 0.5 * (Xk + transpose(Xk))
    return F, X


def _markov_jump_filter(st, Y0, mu):
    """Gains M_i(k) and error moments Y_i(k) of the Markov jump filter ([38], Ch. 5).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.finite_horizon_model import mode_distributions, stages
    >>> st = stages(sys, 3)
    >>> Mf, Y = _markov_jump_filter(st, 0.01 * np.broadcast_to(np.eye(2), (2, 2, 2)),
    ...                             mode_distributions(st, sys.mu_inf))
    >>> Mf.shape, Y.shape
    ((3, 2, 2, 1), (4, 2, 2, 2))
    """
    K_ = st.horizon
    s0 = st.systems[0]
    Y = np.empty((K_ + 1, s0.M, s0.nx, s0.nx))
    Mf = np.empty((K_, s0.M, s0.nx, s0.ny))
    Y[0] = Y0
    for k, s in enumerate(st.systems):
        CY = s.C @ Y[k]
        Sigma = CY @ transpose(s.C) + mu[k][:, None, None] * st.JJt[k]
        Mf[k] = s.A @ transpose(CY) @ np.linalg.pinv(Sigma, hermitian=True)
        inner = (s.A @ Y[k] @ transpose(s.A) - Mf[k] @ CY @ transpose(s.A)
                 + mu[k][:, None, None] * st.HHt[k])
        Yn = s.predecessor_sum(inner)
        Y[k + 1] = 0.5 * (Yn + transpose(Yn))
    return Mf, Y


def mode_observed_lqg(sys, horizon, mean0, cov0, mu0):
    """The optimal finite-horizon output-feedback controller with observed mode ([38]).

    Mode-dependent LQ gains from the coupled Riccati difference equations and the Markov
    jump filter (Costa, Fragoso, Marques 2005, Chs. 4-5): the benchmark of Table 3.3. Its
    cost is not a proven lower bound for controllers that do not observe the mode, since the
    filter gain depends on the current mode only, not on the whole mode history.

    Parameters
    ----------
    sys : MJLS or sequence of MJLS
        As in :func:`finite_horizon_dynamic_output_feedback` (3.54).
    horizon : int
        Number of steps, >= 1.
    mean0, cov0 : array_like, shapes (M, nx) and (M, nx, nx)
        Mode-conditional mean and covariance of x_0.
    mu0 : array_like, shape (M,)
        Distribution of theta_0.

    Returns
    -------
    ModeObservedResult
        Gains, filter, and the exact expected cost; ``.controller(sys)`` simulates it.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS (sequence), ``horizon`` not an integer or an array not real.
    ValueError
        If ``horizon``, ``sys`` or the initial state is invalid.

    Examples
    --------
    Table 3.3's benchmark on the example of Sec. 3.7.3 over 20 steps:

    >>> from asoc.mjls.examples import sec373_system, SEC373_MEAN0, SEC373_COV0, SEC373_MU0
    >>> res = mode_observed_lqg(sec373_system(1), 20, SEC373_MEAN0[1], SEC373_COV0, SEC373_MU0)
    >>> res.F.shape, res.Mf.shape, round(res.cost, 2)
    ((20, 2, 1, 2), (20, 2, 2, 1), 170.71)
    """
    st = stages(sys, horizon)
    s0 = st.systems[0]
    mean0, cov0, mu0 = check_initial_state(s0.M, s0.nx, mean0, cov0, mu0)
    mu = mode_distributions(st, mu0)
    xhat0 = mu0 @ mean0
    dev = mean0 - xhat0
    Y0 = mu0[:, None, None] * (cov0 + np.einsum("ia,ib->iab", dev, dev))
    F, X = _control_riccati(st)
    Mf, Y = _markov_jump_filter(st, Y0, mu)
    cost = _closed_loop_cost(st, F, Mf, mean0, cov0, mu0, xhat0)
    return ModeObservedResult(F=F, Mf=Mf, X=X, Y=Y, xhat0=xhat0, cost=cost)


def _closed_loop_cost(st, F, Mf, mean0, cov0, mu0, xhat0):
    """Exact expected cost (3.56) of [x; x^] with x^+ = M C x + (A + B F - M C) x^ + M J v."""
    nx = st.systems[0].nx
    Acl, HHcl, Qcl = [], [], []
    for k, s in enumerate(st.systems):
        A = np.zeros((s.M, 2 * nx, 2 * nx))
        BF, MC = s.B @ F[k], Mf[k] @ s.C
        A[:, :nx, :nx], A[:, :nx, nx:] = s.A, BF
        A[:, nx:, :nx], A[:, nx:, nx:] = MC, s.A + BF - MC
        HH = np.zeros_like(A)
        HH[:, :nx, :nx], HH[:, nx:, nx:] = st.HHt[k], Mf[k] @ st.JJt[k] @ transpose(Mf[k])
        Q = np.zeros_like(A)
        Q[:, :nx, :nx], Q[:, nx:, nx:] = s.Q, transpose(F[k]) @ s.R @ F[k]
        Acl.append(A), HHcl.append(HH), Qcl.append(Q)
    Q_final = np.zeros_like(Acl[0])
    Q_final[:, :nx, :nx] = st.Q_final
    X0 = augmented_initial_moment(mean0, cov0, mu0, xhat0)
    return augmented_cost(Acl, HHcl, Qcl, Q_final, [s.T for s in st.systems], X0, mu0)
