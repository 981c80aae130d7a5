"""Mean-square stability (Sec. 3.3, Corollary 3.2)."""

import numpy as np

from .operators import closed_loop, spectral_radius  # noqa: F401  (closed_loop: re-exported)
from .system import check_transition_matrix, _stack


def _checked(A_stack, T):
    """A_stack as an (M, n, n) array and T as a row-stochastic (M, M) matrix."""
    A_stack = _stack(A_stack, "A_stack")
    T = check_transition_matrix(T)
    if T.shape[0] != A_stack.shape[0]:
        raise ValueError(f"T: expected shape ({A_stack.shape[0]}, {A_stack.shape[0]}) for "
                         f"{A_stack.shape[0]} modes, found {T.shape}")
    return A_stack, T


def ms_operator(A_stack, T):
    """The matrix M = diag[A_1 (x) A_1, ..., A_M (x) A_M] (T^T (x) I_{n^2}) of Corollary 3.2.

    Parameters
    ----------
    A_stack : array_like, shape (M, n, n)
        Per-mode (closed-loop) system matrices.
    T : array_like, shape (M, M)
        Row-stochastic transition matrix.

    Returns
    -------
    numpy.ndarray, shape (M n^2, M n^2)
        The mean-square operator whose spectral radius decides stability.

    Raises
    ------
    ValueError
        If ``A_stack`` is not an (M, n, n) stack of finite matrices, ``T`` is not
        row-stochastic, or their numbers of modes differ.
    """
    A_stack = _stack(A_stack, "A_stack")
    T = check_transition_matrix(T)
    M, n, _ = A_stack.shape
    if T.shape[0] != M:
        raise ValueError(f"T: expected shape ({M}, {M}) for {M} modes, found {T.shape}")
    n2 = n * n
    blocks = np.zeros((M * n2, M * n2))
    for i in range(M):
        blocks[i * n2:(i + 1) * n2, i * n2:(i + 1) * n2] = np.kron(A_stack[i], A_stack[i])
    return blocks @ np.kron(T.T, np.eye(n2))


def ms_spectral_radius(A_stack, T) -> float:
    """Spectral radius of M (Corollary 3.2); the MJLS is mean-square stable iff it is < 1.

    Parameters
    ----------
    A_stack : array_like, shape (M, n, n)
        Per-mode (closed-loop) system matrices, e.g. from :func:`closed_loop`.
    T : array_like, shape (M, M)
        Row-stochastic transition matrix.

    Returns
    -------
    float
        rho(M) of :func:`ms_operator`, computed without forming it above a small size
        (:func:`asoc.mjls.operators.spectral_radius`).

    Raises
    ------
    ValueError
        As :func:`ms_operator`, e.g. for non-finite matrices.
    """
    return spectral_radius(*_checked(A_stack, T))
