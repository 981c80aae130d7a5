"""The Markov jump linear system (3.7) and its mode-chain helpers (Secs. 3.2, 3.5.1, 3.6.1).

    x_{k+1} = A_{theta_k} x_k + B_{theta_k} u_k + H_{theta_k} w_k,
    y_k     = C_{theta_k} x_k + J_{theta_k} v_k,

with w_k, v_k zero-mean, identity covariance, and a Markov chain theta_k with transition
matrix T = (p_ij), p_ij = P(theta_{k+1} = j | theta_k = i).
"""

from dataclasses import dataclass

import numpy as np


def _stack(value, name, M=None, shape2=None):
    """Stack a list of 2-D arrays (or one 2-D array for all modes) into (M, r, c).

    A list counts as per-mode matrices when each element is 2-D; ``[[1, 0]]`` is one matrix.
    """
    if isinstance(value, (list, tuple)) and value and all(np.ndim(v) >= 2 for v in value):
        mats = [np.atleast_2d(np.asarray(v, dtype=float)) for v in value]
        if len({m.shape for m in mats}) > 1:
            raise ValueError(f"{name}: all modes need one shape, found {[m.shape for m in mats]}")
        arr = np.stack(mats) if mats else np.zeros((0, 0, 0))
    else:
        arr = np.asarray(value, dtype=float)
        if arr.ndim < 2:
            arr = np.atleast_2d(arr)
        if arr.ndim == 2:
            if M is None:
                raise ValueError(f"{name}: give a list or an (M, r, c) array")
            arr = np.broadcast_to(arr, (M,) + arr.shape).copy()
    if arr.ndim != 3:
        raise ValueError(f"{name}: expected shape (M, r, c), found {arr.shape}")
    if M is not None and arr.shape[0] != M:
        raise ValueError(f"{name}: expected {M} modes, found {arr.shape[0]}")
    if shape2 is not None:
        for axis, want in enumerate(shape2):
            if want is not None and arr.shape[1 + axis] != want:
                exp = tuple("*" if w is None else w for w in shape2)
                raise ValueError(f"{name}: expected shape (M, {exp[0]}, {exp[1]}) = "
                                 f"({M}, {exp[0]}, {exp[1]}), found {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: found non-finite entries")
    return arr


def check_transition_matrix(T, name="T"):
    """Validate a row-stochastic matrix; return it as an array."""
    T = np.asarray(T, dtype=float)
    if T.ndim != 2 or T.shape[0] != T.shape[1]:
        raise ValueError(f"{name}: expected a square (M, M) matrix, found shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError(f"{name}: found non-finite entries")
    for i, row in enumerate(T):
        if np.any(row < 0) or abs(row.sum() - 1) > 1e-10:
            raise ValueError(f"{name}: row {i} must be non-negative and sum to 1, found {row}")
    return T


def check_distribution(mu, M, name="mu0"):
    """Validate a probability vector of length M."""
    mu = np.asarray(mu, dtype=float)
    if mu.shape != (M,):
        raise ValueError(f"{name}: expected shape ({M},), found {mu.shape}")
    if not np.all(np.isfinite(mu)) or np.any(mu < 0) or abs(mu.sum() - 1) > 1e-10:
        raise ValueError(f"{name}: must be non-negative and sum to 1, found {mu}")
    return mu


def check_psd(S, name, definite=False, tol=1e-10):
    """Validate a stack (M, n, n) of symmetric positive (semi)definite matrices."""
    for i, Si in enumerate(S):
        if not np.allclose(Si, Si.T, atol=1e-10 * max(1.0, np.abs(Si).max())):
            raise ValueError(f"{name}: mode {i + 1} matrix is not symmetric")
        lam = np.linalg.eigvalsh(Si).min()
        if definite and lam <= tol:
            raise ValueError(f"{name}: mode {i + 1} matrix must be positive definite, "
                             f"smallest eigenvalue {lam:.3g}")
        if not definite and lam < -tol * max(1.0, np.abs(Si).max()):
            raise ValueError(f"{name}: mode {i + 1} matrix must be positive semidefinite, "
                             f"smallest eigenvalue {lam:.3g}")
    return S


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
    """
    T = check_transition_matrix(T)
    M = T.shape[0]
    lhs = np.vstack([T.T - np.eye(M), np.ones((1, M))])
    rhs = np.concatenate([np.zeros(M), [1.0]])
    mu, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    return np.clip(mu, 0.0, None) / np.clip(mu, 0.0, None).sum()


def successor_average(T, P):
    """E_i(P) = sum_j p_ij P_j (Prop. 3.16), for a stack P of shape (M, ...).

    Parameters
    ----------
    T : numpy.ndarray, shape (M, M)
        Transition matrix (not validated here: this helper runs inside the iterations).
    P : numpy.ndarray, shape (M, ...)
        One array per mode, e.g. the multipliers P^j of Prop. 3.16.

    Returns
    -------
    numpy.ndarray, shape (M, ...)
        The expected next-mode value E_i(P) for every mode i.

    Raises
    ------
    ValueError
        If ``T`` and the stack have different numbers of modes (raised by ``numpy.einsum``).
    """
    return np.einsum("ij,j...->i...", T, P)


def predecessor_sum(T, Y):
    """D_i(Y) = sum_j p_ji Y_j (Lemma 3.8), for a stack Y of shape (M, ...).

    Parameters
    ----------
    T : numpy.ndarray, shape (M, M)
        Transition matrix (not validated here).
    Y : numpy.ndarray, shape (M, ...)
        One array per mode, e.g. the second moments X^j of (3.29).

    Returns
    -------
    numpy.ndarray, shape (M, ...)
        D_i(Y), the probability-weighted sum over the predecessor modes j of i.

    Raises
    ------
    ValueError
        If ``T`` and the stack have different numbers of modes (raised by ``numpy.einsum``).
    """
    return np.einsum("ji,j...->i...", T, Y)


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
        Row-stochastic transition matrix, p_ij = P(theta_{k+1} = j | theta_k = i).
    J : array_like, (M, ny, nv), optional
        Measurement-noise matrices of y = C x + J v (Sec. 3.6); None means y = C x.

    Attributes
    ----------
    M, nx, nu, ny, nw : int
        Number of modes and dimensions.

    Raises
    ------
    ValueError
        Naming the argument, when a shape does not fit, an entry is not finite, ``T`` is not
        row-stochastic, ``Q`` is not symmetric positive semidefinite or ``R`` not positive
        definite.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    H: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    T: np.ndarray
    J: np.ndarray | None = None

    def __init__(self, A, B, C, H, Q, R, T, J=None):
        T = check_transition_matrix(T)
        M = T.shape[0]
        A = _stack(A, "A", M)
        nx = A.shape[1]
        if A.shape[2] != nx:
            raise ValueError(f"A: expected square (M, nx, nx), found {A.shape}")
        B = _stack(B, "B", M, (nx, None))
        C = _stack(C, "C", M, (None, nx))
        H = _stack(H, "H", M, (nx, None))
        Q = check_psd(_stack(Q, "Q", M, (nx, nx)), "Q")
        R = check_psd(_stack(R, "R", M, (B.shape[2], B.shape[2])), "R", definite=True)
        if J is not None:
            J = _stack(J, "J", M, (C.shape[1], None))
        for name, value in dict(A=A, B=B, C=C, H=H, Q=Q, R=R, T=T, J=J).items():
            object.__setattr__(self, name, value)

    @property
    def M(self) -> int:
        """Number of modes."""
        return self.T.shape[0]

    @property
    def nx(self) -> int:
        return self.A.shape[1]

    @property
    def nu(self) -> int:
        return self.B.shape[2]

    @property
    def ny(self) -> int:
        return self.C.shape[1]

    @property
    def nw(self) -> int:
        return self.H.shape[2]

    @property
    def mu_inf(self) -> np.ndarray:
        """Stationary mode distribution lim P(theta_k = i)."""
        return stationary_distribution(self.T)

    def successor_average(self, P):
        """E_i(P) = sum_j p_ij P_j."""
        return successor_average(self.T, P)

    def predecessor_sum(self, Y):
        """D_i(Y) = sum_j p_ji Y_j."""
        return predecessor_sum(self.T, Y)

    def replace(self, **changes) -> "MJLS":
        """A copy with some matrices replaced, e.g. ``sys.replace(T=T2, C=C2)``."""
        fields = dict(A=self.A, B=self.B, C=self.C, H=self.H, Q=self.Q, R=self.R, T=self.T, J=self.J)
        fields.update(changes)
        return MJLS(**fields)
