"""Mean-square stability (Sec. 3.3, Corollary 3.2)."""

import numpy as np

from ..validation import real_array, stochastic_matrix
from .operators import spectral_radius
from .system import _stack, check_system


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
    TypeError
        If ``A_stack`` or ``T`` is complex or not numeric.

    Examples
    --------
    >>> ms_operator([[[0.5]], [[2.0]]], [[0.5, 0.5], [0.5, 0.5]])
    array([[0.125, 0.125],
           [2.   , 2.   ]])
    """
    A_stack = _stack(A_stack, "A_stack")
    T = stochastic_matrix(T, "T")
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
    TypeError
        If ``A_stack`` or ``T`` is complex or not numeric.

    Examples
    --------
    Two stable modes whose switching is mean-square unstable (Sec. 3.2):

    >>> from asoc.mjls.examples import SEC32_A, SEC32_T
    >>> round(ms_spectral_radius(SEC32_A, SEC32_T), 4)
    1.4198
    """
    A_stack = _stack(A_stack, "A_stack")
    T = stochastic_matrix(T, "T")
    if T.shape[0] != A_stack.shape[0]:
        raise ValueError(f"T: expected shape ({A_stack.shape[0]}, {A_stack.shape[0]}) for {A_stack.shape[0]} modes, found {T.shape}")
    return spectral_radius(A_stack, T)


def closed_loop(sys, L):
    """Closed-loop matrices A_i + B_i L C_i of (3.10) for a mode-independent gain L.

    Parameters
    ----------
    sys : MJLS
    L : array_like, shape (nu, ny)
        Static output-feedback gain u = L y (3.8).

    Returns
    -------
    numpy.ndarray, shape (M, nx, nx)

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS or ``L`` is not a real array.
    ValueError
        If ``L`` does not have shape (nu, ny) or is not finite.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> closed_loop(sec354_system(1, "C=[1 0]"), [[-0.5]])[0].tolist()
    [[1.2, 1.2], [-0.5, 1.0]]
    """
    check_system(sys)
    L = gain_matrix(L, "L", sys.nu, sys.ny)
    return sys.A + sys.B @ L @ sys.C


def gain_matrix(L, name, nu, ny):
    """A finite real gain of shape (nu, ny); a scalar or a flat array is accepted when nu = ny = 1.

    Examples
    --------
    >>> gain_matrix(-0.5, "L", 1, 1)
    array([[-0.5]])
    """
    L = real_array(L, name)
    if L.size == 1 and nu == ny == 1:
        return L.reshape(1, 1)
    if L.shape != (nu, ny):
        raise ValueError(f"{name}: expected shape ({nu}, {ny}), found shape {L.shape}")
    return L
