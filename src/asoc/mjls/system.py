"""The Markov jump linear system (3.7) and its mode-chain helpers (Secs. 3.2, 3.5.1, 3.6.1).

    x_{k+1} = A_{theta_k} x_k + B_{theta_k} u_k + H_{theta_k} w_k,
    y_k     = C_{theta_k} x_k + J_{theta_k} v_k,

with w_k, v_k zero-mean, identity covariance, and a Markov chain theta_k with transition
matrix T = (p_ij), p_ij = P(theta_{k+1} = j | theta_k = i).
"""

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components

from .. import config
from ..validation import (
    probability_vector,
    real_array,
    real_scalar,
    semidefinite,
    stochastic_matrix,
)

__all__ = ["check_system", "stationary_distribution", "successor_average", "predecessor_sum",
           "MJLS", "import_control"]


def _stack(value, name, M=None, shape2=None, source=""):
    """Stack a list of 2-D arrays (or one 2-D array for all modes) into (M, r, c).

    A list counts as per-mode matrices when each element is 2-D; ``[[1, 0]]`` is one matrix.
    Complex, non-numeric and non-finite entries are rejected (naming ``name``); ``source``
    says where the expected sizes come from (e.g. "nx from A").
    """
    if isinstance(value, (list, tuple)) and value and all(np.ndim(v) >= 2 for v in value):
        mats = [np.atleast_2d(real_array(v, f"{name}[{i}]", finite=False))
                for i, v in enumerate(value)]
        if len({m.shape for m in mats}) > 1:
            raise ValueError(f"{name}: expected one shape for all modes, "
                             f"found {[m.shape for m in mats]}")
        arr = np.stack(mats)
    else:
        arr = real_array(value, name, finite=False)
        if arr.ndim < 2:
            arr = np.atleast_2d(arr)
        if arr.ndim == 2:
            if M is None:
                raise ValueError(f"{name}: expected a list of matrices or an (M, r, c) array, "
                                 f"found shape {arr.shape}")
            arr = np.broadcast_to(arr, (M,) + arr.shape).copy()
    if arr.ndim != 3:
        raise ValueError(f"{name}: expected shape (M, r, c), found {arr.shape}")
    if M is not None and arr.shape[0] != M:
        raise ValueError(f"{name}: expected {M} modes, found {arr.shape[0]}")
    if shape2 is not None:
        for axis, want in enumerate(shape2):
            if want is not None and arr.shape[1 + axis] != want:
                exp = tuple("*" if w is None else w for w in shape2)
                raise ValueError(f"{name}: expected shape ({M}, {exp[0]}, {exp[1]})"
                                 f"{f' ({source})' if source else ''}, found {arr.shape}")
    if not np.all(np.isfinite(arr)):
        n_bad = int(np.size(arr) - np.isfinite(arr).sum())
        raise ValueError(f"{name}: expected finite entries, found {n_bad} non-finite")
    return arr


def check_system(sys, name="sys"):
    """Check that ``sys`` is an :class:`MJLS`; return it.

    Examples
    --------
    >>> check_system("not a system")
    Traceback (most recent call last):
    ...
    TypeError: sys: expected an MJLS (asoc.mjls.MJLS), found str
    """
    if not isinstance(sys, MJLS):
        raise TypeError(f"{name}: expected an MJLS (asoc.mjls.MJLS), found {type(sys).__name__}")
    return sys


def _closed_classes(T):
    """The number of closed communicating classes of the chain T (1 iff mu_inf is unique).

    Examples
    --------
    >>> _closed_classes(np.eye(2)), _closed_classes([[0.9, 0.1], [0.2, 0.8]])
    (2, 1)
    """
    T = stochastic_matrix(T, "T")
    n_classes, label = connected_components(T > 0, directed=True, connection="strong")
    leaves = np.ones(n_classes, dtype=bool)
    rows, cols = np.nonzero(T > 0)
    leaves[label[rows][label[rows] != label[cols]]] = False
    return int(leaves.sum())


def stationary_distribution(T):
    """Limit distribution mu_inf with mu_inf^T T = mu_inf^T (footnote 5, Sec. 3.5.2).

    Parameters
    ----------
    T : array_like, shape (M, M)
        Row-stochastic transition matrix, p_ij = P(theta_{k+1} = j | theta_k = i).

    Returns
    -------
    numpy.ndarray, shape (M,)
        The stationary distribution (least-squares solution of mu^T (T - I) = 0,
        sum mu = 1, clipped to be non-negative and renormalised).

    Raises
    ------
    ValueError
        If ``T`` is not square, not finite, or a row is negative or does not sum to 1.
    TypeError
        If ``T`` is complex or not numeric.

    Warns
    -----
    RuntimeWarning
        When T has several closed classes (e.g. T = I): the stationary distribution is not
        unique and the one returned is only one of many; pass the intended one as
        ``MJLS(..., mu_inf=...)``.

    Examples
    --------
    >>> stationary_distribution([[0.9, 0.1], [0.2, 0.8]]).round(4)
    array([0.6667, 0.3333])
    """
    T = stochastic_matrix(T, "T")
    _warn_if_not_unique(T, stacklevel=3)
    return _least_squares_stationary(T)


def _warn_if_not_unique(T, stacklevel):
    n_closed = _closed_classes(T)
    if n_closed > 1:
        warnings.warn(f"T: the chain has {n_closed} closed classes, so its stationary distribution "
                      "is not unique; pass the intended one as MJLS(..., mu_inf=...)",
                      RuntimeWarning, stacklevel=stacklevel)


def _least_squares_stationary(T):
    M = T.shape[0]
    lhs = np.vstack([T.T - np.eye(M), np.ones((1, M))])
    rhs = np.concatenate([np.zeros(M), [1.0]])
    mu, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    return np.clip(mu, 0.0, None) / np.clip(mu, 0.0, None).sum()


def successor_average(T, P, check=True):
    """E_i(P) = sum_j p_ij P_j (Prop. 3.16), for a stack P of shape (M, ...).

    Parameters
    ----------
    T : array_like, shape (M, M)
        Transition matrix.
    P : array_like, shape (M, ...)
        One array per mode, e.g. the multipliers P^j of Prop. 3.16.
    check : bool
        Validate ``T`` and ``P`` (default); False skips it, for the library's iterations, which
        pass arrays they have checked once.

    Returns
    -------
    numpy.ndarray, shape (M, ...)
        The expected next-mode value E_i(P) for every mode i.

    Raises
    ------
    ValueError
        If ``T`` is not a transition matrix, or ``P`` not a stack of as many arrays as ``T``
        has modes.
    TypeError
        If ``T`` or ``P`` is not a real array.

    Examples
    --------
    >>> successor_average(np.array([[0.5, 0.5], [0.0, 1.0]]), np.array([2.0, 4.0]))
    array([3., 4.])
    >>> successor_average([[1.0]], np.ones(2))
    Traceback (most recent call last):
    ...
    ValueError: P: expected a stack of 1 array(s), one per mode of T, found shape (2,)
    """
    if check:
        T, P = _transition_and_stack(T, P, "P")
    return np.einsum("ij,j...->i...", T, P)


def predecessor_sum(T, Y, check=True):
    """D_i(Y) = sum_j p_ji Y_j (Lemma 3.8), for a stack Y of shape (M, ...).

    Parameters
    ----------
    T : array_like, shape (M, M)
        Transition matrix.
    Y : array_like, shape (M, ...)
        One array per mode, e.g. the second moments X^j of (3.29).
    check : bool
        Validate ``T`` and ``Y`` (default); False skips it, for the library's iterations.

    Returns
    -------
    numpy.ndarray, shape (M, ...)
        D_i(Y), the probability-weighted sum over the predecessor modes j of i.

    Raises
    ------
    ValueError
        If ``T`` is not a transition matrix, or ``Y`` not a stack of as many arrays as ``T``
        has modes.
    TypeError
        If ``T`` or ``Y`` is not a real array.

    Examples
    --------
    >>> predecessor_sum(np.array([[0.5, 0.5], [0.0, 1.0]]), np.array([2.0, 4.0]))
    array([1., 5.])
    >>> predecessor_sum("T", np.ones(2))
    Traceback (most recent call last):
    ...
    TypeError: T: expected a real array, found dtype <U1
    """
    if check:
        T, Y = _transition_and_stack(T, Y, "Y")
    return np.einsum("ji,j...->i...", T, Y)


def _transition_and_stack(T, stack, name):
    T = stochastic_matrix(T, "T")
    stack = real_array(stack, name, finite=False)
    if stack.ndim < 1 or stack.shape[0] != len(T):
        raise ValueError(f"{name}: expected a stack of {len(T)} array(s), one per mode of T, "
                         f"found shape {stack.shape}")
    return T, stack


def _sampling_time(dt, name="dt"):
    """None (unspecified), True (discrete, period unspecified, as python-control) or dt > 0."""
    if dt is None or dt is True:
        return dt
    return real_scalar(dt, name, low=0, low_open=True)


@dataclass(frozen=True, eq=False)
class MJLS:
    """Markov jump linear system (3.7) with cost matrices Q_i, R_i (cost (3.9)).

    x_{k+1} = A_i x_k + B_i u_k + H_i w_k, y_k = C_i x_k + J_i v_k with i = theta_k, w_k and
    v_k standard normal, theta_k a Markov chain with transition matrix T.

    Parameters
    ----------
    A : list of 2-D array_like, or array_like (M, nx, nx)
        Per-mode system matrices; a single 2-D array is used for every mode (also below).
    B : list of 2-D array_like, or array_like (M, nx, nu)
        Input matrices.
    C : list of 2-D array_like, or array_like (M, ny, nx)
        Output matrices.
    H : list of 2-D array_like, or array_like (M, nx, nw)
        Process-noise matrices.
    Q : array_like, (M, nx, nx) or (nx, nx)
        Symmetric positive semidefinite state weights.
    R : array_like, (M, nu, nu) or (nu, nu)
        Symmetric positive definite input weights.
    T : array_like, shape (M, M)
        Row-stochastic transition matrix, p_ij = P(theta_{k+1} = j | theta_k = i), M >= 1.
    J : array_like, (M, ny, nv), optional
        Measurement-noise matrices of y = C x + J v (Sec. 3.6); None means y = C x.
    mu_inf : array_like, shape (M,), optional
        The stationary mode distribution used by the average-cost designs. Default: computed
        from T (:func:`stationary_distribution`); give it when T has several closed classes
        (e.g. T = I), where it is not unique. Must satisfy mu_inf T = mu_inf.
    dt : float or True, optional
        Sampling time (for :meth:`to_statespace`); True: discrete time, period unspecified.

    Attributes
    ----------
    M, nx, nu, ny, nw : int
        Number of modes and dimensions.

    Raises
    ------
    ValueError
        Naming the argument, when a shape does not fit, an entry is not finite, ``T`` is not
        row-stochastic, ``Q`` is not symmetric positive semidefinite or ``R`` not positive
        definite, or ``mu_inf`` is not a stationary distribution of ``T``.
    TypeError
        If a matrix is complex or not numeric.

    Examples
    --------
    >>> sys = MJLS(A=[[[1.2]], [[0.5]]], B=[[1.0]], C=[[1.0]], H=[[0.1]], Q=[[1.0]], R=[[1.0]],
    ...            T=[[0.9, 0.1], [0.3, 0.7]])
    >>> sys.M, sys.nx, sys.nu, sys.ny, sys.mu_inf.round(3)
    (2, 1, 1, 1, array([0.75, 0.25]))
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    H: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    T: np.ndarray
    J: np.ndarray | None = None
    mu_inf: np.ndarray | None = None
    dt: float | bool | None = None

    def __init__(self, A, B, C, H, Q, R, T, J=None, mu_inf=None, dt=None):
        T = stochastic_matrix(T, "T")
        M = T.shape[0]
        A = _stack(A, "A", M)
        nx = A.shape[1]
        if A.shape[2] != nx:
            raise ValueError(f"A: expected square (M, nx, nx), found {A.shape}")
        from_A = f"nx = {nx} from A"
        B = _stack(B, "B", M, (nx, None), from_A)
        C = _stack(C, "C", M, (None, nx), from_A)
        H = _stack(H, "H", M, (nx, None), from_A)
        Q = semidefinite(_stack(Q, "Q", M, (nx, nx), from_A), "Q")
        nu = B.shape[2]
        R = semidefinite(_stack(R, "R", M, (nu, nu), f"nu = {nu} from B"), "R", definite=True)
        if J is not None:
            J = _stack(J, "J", M, (C.shape[1], None), f"ny = {C.shape[1]} from C")
        if mu_inf is None:
            _warn_if_not_unique(T, stacklevel=3)
            mu_inf = _least_squares_stationary(T)
        else:
            mu_inf = probability_vector(mu_inf, "mu_inf", M)
            gap = np.abs(mu_inf @ T - mu_inf).max()
            if gap > config.defaults["mjls.stationary_atol"]:
                raise ValueError("mu_inf: expected a stationary distribution of T "
                                 "(mu_inf T = mu_inf), "
                                 f"found max |mu_inf T - mu_inf| = {gap:.3g}")
        dt = _sampling_time(dt)
        fields = dict(A=A, B=B, C=C, H=H, Q=Q, R=R, T=T, J=J, mu_inf=mu_inf, dt=dt)
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    @property
    def M(self) -> int:
        """Number of modes."""
        return self.T.shape[0]

    @property
    def nx(self) -> int:
        """State dimension."""
        return self.A.shape[1]

    @property
    def nu(self) -> int:
        """Input dimension."""
        return self.B.shape[2]

    @property
    def ny(self) -> int:
        """Output dimension."""
        return self.C.shape[1]

    @property
    def nw(self) -> int:
        """Process-noise dimension."""
        return self.H.shape[2]

    def successor_average(self, P):
        """E_i(P) = sum_j p_ij P_j (:func:`successor_average`)."""
        return successor_average(self.T, P, check=False)

    def predecessor_sum(self, Y):
        """D_i(Y) = sum_j p_ji Y_j (:func:`predecessor_sum`)."""
        return predecessor_sum(self.T, Y, check=False)

    def replace(self, **changes) -> "MJLS":
        """A copy with some matrices replaced, e.g. ``sys.replace(T=T2, C=C2)``.

        A new ``T`` drops the old ``mu_inf`` (recomputed unless given).

        Examples
        --------
        >>> sys = MJLS(A=[[[1.2]], [[0.5]]], B=[[1.0]], C=[[1.0]], H=[[0.1]], Q=[[1.0]],
        ...            R=[[1.0]], T=[[0.9, 0.1], [0.3, 0.7]])
        >>> sys.replace(T=[[0.5, 0.5], [0.5, 0.5]]).mu_inf
        array([0.5, 0.5])
        """
        fields = dict(A=self.A, B=self.B, C=self.C, H=self.H, Q=self.Q, R=self.R, T=self.T,
                      J=self.J, mu_inf=None if "T" in changes else self.mu_inf, dt=self.dt)
        unknown = set(changes) - set(fields)
        if unknown:
            raise TypeError(f"replace: expected keywords among {sorted(fields)}, "
                            f"found {sorted(unknown)}")
        fields.update(changes)
        return MJLS(**fields)

    @classmethod
    def from_statespace(cls, systems, T, *, Q=None, R=None, H=None, J=None, dt=None,
                        mu_inf=None) -> "MJLS":
        """The MJLS (3.7) whose mode i is the discrete-time ``control.StateSpace`` ``systems[i]``.

        The model (3.7) has no feedthrough (y = C x + J v), so every D must be zero: a
        nonzero D is rejected. The noise and cost matrices are not part of a StateSpace and
        are given as keywords, as in :class:`MJLS`; for an analysis (stability, simulation
        without a design) they may be left out and default to Q = I, R = I and H = I: unit
        weights on every state and input, unit process noise on every state.

        Parameters
        ----------
        systems : sequence of control.StateSpace
            M discrete-time systems (A_i, B_i, C_i, D_i = 0) of equal sizes and sampling time.
        T : array_like, shape (M, M)
            Transition matrix.
        Q, R, H : array_like, optional
            As for :class:`MJLS`; default the identity of size nx, nu, nx.
        J, mu_inf
            As for :class:`MJLS`.
        dt : float, optional
            The sampling time the systems must have; default: theirs.

        Returns
        -------
        MJLS
            With ``dt`` the systems' common sampling time (True if unspecified).

        Raises
        ------
        ImportError
            If python-control is not installed (``pip install asoc[control]``).
        TypeError
            If an entry of ``systems`` is not a ``control.StateSpace``.
        ValueError
            If ``systems`` does not hold M systems, one is continuous-time (dt = 0), the
            sampling times differ from each other or from ``dt``, the sizes differ, or a D is
            nonzero.

        Examples
        --------
        >>> import control
        >>> modes = [control.ss([[1.2]], [[1.0]], [[1.0]], [[0.0]], 0.1),
        ...          control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1)]
        >>> sys = MJLS.from_statespace(modes, [[0.9, 0.1], [0.3, 0.7]], Q=[[1.0]], R=[[1.0]],
        ...                            H=[[0.1]])
        >>> sys.M, sys.dt, float(sys.A[0, 0, 0])
        (2, 0.1, 1.2)

        For a stability check the weights may be left out:

        >>> from asoc.mjls import ms_spectral_radius
        >>> plain = MJLS.from_statespace(modes, [[0.9, 0.1], [0.3, 0.7]])
        >>> plain.Q.ravel().tolist(), round(ms_spectral_radius(plain.A, plain.T), 4)
        ([1.0, 1.0], 1.3056)
        """
        control = import_control()
        T = stochastic_matrix(T, "T")
        if isinstance(systems, control.StateSpace) or not isinstance(systems, (list, tuple)):
            raise TypeError(f"systems: expected a list of {T.shape[0]} control.StateSpace, "
                            f"found {type(systems).__name__}")
        if len(systems) != T.shape[0]:
            raise ValueError(f"systems: expected {T.shape[0]} systems (one per mode of T), "
                             f"found {len(systems)}")
        for i, s in enumerate(systems):
            if not isinstance(s, control.StateSpace):
                raise TypeError(f"systems[{i}]: expected a control.StateSpace, "
                                f"found {type(s).__name__}")
            if s.dt is None or (s.dt is not True and s.dt == 0):
                raise ValueError(f"systems[{i}]: expected a discrete-time system (dt > 0 or True), "
                                 f"found continuous-time dt = {s.dt}; "
                                 "discretise it, e.g. control.c2d")
        periods = {s.dt for s in systems if s.dt is not True}
        if len(periods) > 1:
            raise ValueError(f"systems: expected one sampling time, found {sorted(periods)}")
        found = periods.pop() if periods else True
        if dt is not None:
            dt = _sampling_time(dt)
            rtol = config.defaults["mjls.sampling_time_rtol"]
            if found is not True and dt is not True and not np.isclose(found, dt, rtol=rtol,
                                                                       atol=0):
                raise ValueError(f"dt: expected the systems' sampling time {found}, found {dt}")
            found = dt if found is True else found
        sizes = [(s.nstates, s.ninputs, s.noutputs) for s in systems]
        if len(set(sizes)) > 1:
            raise ValueError("systems: expected equal sizes (nstates, ninputs, noutputs), "
                             f"found {sizes}")
        for i, s in enumerate(systems):
            if np.any(np.asarray(s.D) != 0):
                raise ValueError(f"systems[{i}]: expected D = 0 "
                                 "(the MJLS (3.7) has no feedthrough), "
                                 f"found max |D| = {np.abs(s.D).max():.3g}")
        nx, nu, _ = sizes[0]
        return cls(A=[np.asarray(s.A, float) for s in systems],
                   B=[np.asarray(s.B, float) for s in systems],
                   C=[np.asarray(s.C, float) for s in systems], H=np.eye(nx) if H is None else H,
                   Q=np.eye(nx) if Q is None else Q, R=np.eye(nu) if R is None else R, T=T, J=J,
                   mu_inf=mu_inf, dt=found)

    def to_statespace(self, dt=None) -> list:
        """The M modes as discrete-time ``control.StateSpace`` (A_i, B_i, C_i, 0).

        Noise (H, J), costs (Q, R) and T are not part of a StateSpace and are dropped.

        Parameters
        ----------
        dt : float or True, optional
            Sampling time; default the system's ``dt`` (True, unspecified, if it has none).
            A ``dt`` that contradicts the system's is a ValueError.

        Returns
        -------
        list of control.StateSpace

        Raises
        ------
        ImportError
            If python-control is not installed.
        ValueError
            If ``dt`` is not positive, or differs from the system's sampling time.

        Examples
        --------
        >>> sys = MJLS(A=[[[1.2]], [[0.5]]], B=[[1.0]], C=[[1.0]], H=[[0.1]], Q=[[1.0]],
        ...            R=[[1.0]], T=[[0.9, 0.1], [0.3, 0.7]])
        >>> modes = sys.to_statespace(dt=0.1)
        >>> len(modes), modes[1].dt, float(modes[1].A[0, 0])
        (2, 0.1, 0.5)
        """
        control = import_control()
        if dt is None:
            dt = True if self.dt is None else self.dt
        dt = _sampling_time(dt)
        if dt is None:
            dt = True
        fixed = self.dt is not None and self.dt is not True
        rtol = config.defaults["mjls.sampling_time_rtol"]
        if fixed and dt is not True and not np.isclose(dt, self.dt, rtol=rtol, atol=0):
            raise ValueError(f"dt: expected the system's sampling time {self.dt}, found {dt}")
        return [control.ss(self.A[i], self.B[i], self.C[i], np.zeros((self.ny, self.nu)), dt)
                for i in range(self.M)]


def import_control():
    """The python-control module, or an ImportError saying how to install it (``asoc[control]``)."""
    try:
        import control
    except ImportError as err:
        raise ImportError("python-control is needed for the StateSpace interop: "
                          "pip install 'asoc[control]' (or pip install control)") from err
    return control
