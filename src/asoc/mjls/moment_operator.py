"""The second-moment operator L of an MJLS on (M, n, n) stacks, its adjoint and its matrix
(Cor. 3.2, Props. 3.7, 3.23).

The mean-square behaviour of x_{k+1} = A_{theta_k} x_k (+ noise) is governed by the linear map

    L(X)_j = sum_i p_ij A_i X_i A_i^T          (the second-moment recursion (3.29)),

and by its adjoint (the costate or multiplier recursion of Prop. 3.16)

    L*(P)_i = A_i^T E_i(P) A_i,  E_i(P) = sum_j p_ij P_j.

Applying either costs O(M n^3 + M^2 n^2); their Kronecker matrix (Cor. 3.2) costs
O((M n^2)^2) memory and O((M n^2)^3) time to factorise. This module holds the maps, their
matrix and the validation of an open loop (A, T); :mod:`asoc.mjls.stability` the spectral
radius with its certified bracket and :mod:`asoc.mjls.lyapunov` the coupled Lyapunov solves
built on them:

- :func:`second_moment_map`, :func:`costate_map`: the maps on stacks;
- :func:`ms_operator`: their matrix (row-major vec of the stack, one convention for the whole
  library), used for small systems;
- :func:`linear_operator`: the matrix-free map for ARPACK;
- :func:`mode_stack`: the validated (A, T) of an MJLS or of a stack with its T.

L is a positive map (it keeps the cone of positive semidefinite stacks), so rho(L) is an
eigenvalue with a positive semidefinite eigenvector (Krein-Rutman; Costa, Fragoso and
Marques 2005, Ch. 3), and the spectral radius of L on all matrices equals that on symmetric
ones. The iterative methods therefore work on symmetrised stacks.
"""

import threading

import numpy as np
import scipy.sparse.linalg

from .. import config
from ..linalg import sym, transpose
from ..threads import in_parts
from ..validation import real_array, stochastic_matrix
from .system import MJLS

__all__ = ["mode_stack", "second_moment_map", "costate_map", "in_parallel", "mix_modes",
           "ms_operator", "kronecker_stack", "linear_operator", "shifted_map"]


def mode_stack(A_stack, T, name="A_stack"):
    """The validated (A, T) of an open loop: an :class:`~asoc.mjls.MJLS` (its A stack and T; ``T``
    must then be None) or an (M, n, n) stack of finite real matrices with a row-stochastic (M, M)
    ``T``.

    Examples
    --------
    >>> from asoc.mjls.examples import sec32_system
    >>> A, T = mode_stack(sec32_system(), None)
    >>> A.shape, T.shape
    ((2, 2, 2), (2, 2))
    >>> mode_stack(np.eye(2)[None], [[0.5, 0.5], [0.5, 0.5]])
    Traceback (most recent call last):
    ...
    ValueError: T: expected shape (1, 1) for 1 modes (from A_stack), found (2, 2)
    """
    if isinstance(A_stack, MJLS):
        if T is not None:
            raise TypeError(f"T: expected None when {name} is an MJLS (its own T is used), "
                            f"found {type(T).__name__}")
        return A_stack.A, A_stack.T
    if T is None:
        raise TypeError(f"T: expected a transition matrix when {name} is a stack of matrices, "
                        "found None")
    A = real_array(A_stack, name, ndim=3)
    if A.shape[1] != A.shape[2] or A.shape[0] == 0:
        raise ValueError(f"{name}: expected shape (M, n, n) with M >= 1, found {A.shape}")
    T = stochastic_matrix(T, "T")
    if T.shape[0] != A.shape[0]:
        raise ValueError(f"T: expected shape ({A.shape[0]}, {A.shape[0]}) for {A.shape[0]} modes "
                         f"(from {name}), found {T.shape}")
    return A, T


def second_moment_map(A, T, X):
    """L(X)_j = sum_i p_ij A_i X_i A_i^T, the homogeneous part of (3.29) / Prop. 3.23.

    Parameters
    ----------
    A : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    T : numpy.ndarray, shape (M, M)
        Transition matrix, p_ij = P(theta_{k+1} = j | theta_k = i).
    X : numpy.ndarray, shape (M, n, n)
        A stack, e.g. second moments E{x x^T 1(theta = i)}.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)

    Examples
    --------
    >>> A = np.array([[[0.5]], [[2.0]]]); T = np.array([[0.9, 0.1], [0.5, 0.5]])
    >>> second_moment_map(A, T, np.ones((2, 1, 1))).ravel()
    array([2.225, 2.025])
    """
    if not in_parallel(A):
        Y = A @ X @ transpose(A)
        return (T.T @ Y.reshape(len(Y), -1)).reshape(Y.shape)
    return _map_in_parts(A, T, X, adjoint=False)[0].copy()


def costate_map(A, T, P):
    """L*(P)_i = A_i^T E_i(P) A_i, the adjoint of :func:`second_moment_map` (Prop. 3.16).

    <L(X), P> = <X, L*(P)> with <X, P> = sum_i tr(X_i^T P_i).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[2.0]]]); T = np.array([[0.9, 0.1], [0.5, 0.5]])
    >>> costate_map(A, T, np.ones((2, 1, 1))).ravel()
    array([0.25, 4.  ])
    """
    if not in_parallel(A):
        EP = (T @ P.reshape(len(P), -1)).reshape(P.shape)
        return transpose(A) @ EP @ A
    return _map_in_parts(A, T, P, adjoint=True)[0].copy()


_SCRATCH = threading.local()


def _scratch(shape):
    """Four arrays of ``shape`` for this thread's products on threads, kept between calls: a new
    array's pages are mapped when first written, and two threads writing one new array wait for
    each other there (at n = M = 100, an application of L took 32 ms with new arrays, 18 ms with
    these and one copy of the result).
    """
    if getattr(_SCRATCH, "shape", None) != shape:
        _SCRATCH.shape, _SCRATCH.arrays = shape, tuple(np.empty(shape) for _ in range(4))
    return _SCRATCH.arrays


def _symmetric_part(X, out, modes):
    """out[modes] = (X_i + X_i^T) / 2 for the ``modes`` (one mode's matrix stays in cache)."""
    np.add(X[modes], transpose(X[modes]), out=out[modes])
    out[modes] *= 0.5


def _map_in_parts(A, T, X, adjoint, symmetrize=False):
    """L(X) (L*(X) for ``adjoint``) in parts of the modes on threads, and the stack it was applied
    to: sym(X) with ``symmetrize`` (formed mode by mode in the same parts), else X. Both are this
    thread's kept arrays (:func:`_scratch`), overwritten by its next call.
    """
    M = len(A)
    Xs, half, Y, out = _scratch(X.shape)
    Xs = Xs if symmetrize else X
    if adjoint:                        # E(sym X) = sym E(X): mix first, symmetrise per mode
        in_parts(lambda rows: mix_modes(T[rows], X, Y[rows]), M)

        def products(modes):
            E, temporary = Y, half
            if symmetrize:
                _symmetric_part(X, Xs, modes)
                _symmetric_part(Y, half, modes)
                E, temporary = half, Y
            np.matmul(np.matmul(transpose(A[modes]), E[modes], out=temporary[modes]), A[modes],
                      out=out[modes])

        in_parts(products, M)
        return out, Xs

    def products(modes):
        if symmetrize:
            _symmetric_part(X, Xs, modes)
        np.matmul(np.matmul(A[modes], Xs[modes], out=half[modes]), transpose(A[modes]),
                  out=Y[modes])

    in_parts(products, M)
    in_parts(lambda rows: mix_modes(T.T[rows], Y, out[rows]), M)
    return out, Xs


def in_parallel(A):
    """Whether products with the stack A, shape (M, n, n), run in parts of the modes on threads
    (:func:`asoc.threads.in_parts`): from M n^3 = ``mjls.parallel_from`` on. Not validated (a
    float array of shape (M, n, n), as the maps take it).

    Examples
    --------
    >>> in_parallel(np.zeros((2, 3, 3)))
    False
    """
    M, n, _ = A.shape
    return M * n**3 >= config.defaults["mjls.parallel_from"]


def mix_modes(T_rows, X, out):
    """Out = T_rows X: rows of a transition matrix (or of its transpose) times the stack X,
    out_j = sum_i T_rows[j, i] X_i, without a temporary. Not validated, for the inner loops: float
    arrays, T_rows (k, M), X (M, ...) and out (k, ...) C-contiguous.

    Examples
    --------
    >>> out = np.empty((1, 1, 1))
    >>> mix_modes(np.array([[0.25, 0.75]]), np.array([[[4.0]], [[8.0]]]), out)
    >>> out.ravel()
    array([7.])
    """
    np.matmul(T_rows, X.reshape(len(X), -1), out=out.reshape(len(out), -1))


def ms_operator(A_stack, T=None, check=True):
    """The matrix of Cor. 3.2: the second-moment map L on row-major vecs of the stack.

    Block (j, i) is p_ij A_i (x) A_i, i.e. the matrix is (T^T (x) I_{n^2}) diag[A_1 (x) A_1, ...,
    A_M (x) A_M], the product of the same two factors as the thesis's
    M = diag[A_i (x) A_i] (T^T (x) I_{n^2}) in the other order: BC and CB have the same
    eigenvalues, and this order is the matrix of
    :func:`~asoc.mjls.moment_operator.second_moment_map` (its transpose that of
    :func:`~asoc.mjls.moment_operator.costate_map`). vec(A X A^T) = (A (x) A) vec X holds for
    row- and column-major vec alike, so the convention only fixes the order of the blocks.
    Size (M n^2)^2: for small systems only.

    Parameters
    ----------
    A_stack : MJLS or array_like, shape (M, n, n)
        Per-mode (closed-loop) system matrices, or an open-loop MJLS.
    T : array_like, shape (M, M), optional
        Row-stochastic transition matrix (None with an MJLS).
    check : bool
        Validate the arguments (False: float arrays of consistent shapes, for inner loops).

    Returns
    -------
    numpy.ndarray, shape (M n^2, M n^2)

    Raises
    ------
    ValueError
        If ``A_stack`` is not an (M, n, n) stack of finite matrices, ``T`` is not
        row-stochastic, or their numbers of modes differ.
    TypeError
        If ``A_stack`` or ``T`` is complex or not numeric, or ``T`` is missing.

    Examples
    --------
    >>> ms_operator([[[0.5]], [[2.0]]], [[0.5, 0.5], [0.5, 0.5]])
    array([[0.125, 2.   ],
           [0.125, 2.   ]])
    """
    if check:
        A_stack, T = mode_stack(A_stack, T)
    return kronecker_stack(A_stack[None], T)[0]


def kronecker_stack(A, T):
    """:func:`ms_operator` of each closed loop of a stack A, shape (G, M, n, n), unchecked.

    Examples
    --------
    >>> kronecker_stack(np.array([[[[0.5]]], [[[2.0]]]]), np.array([[1.0]])).ravel()
    array([0.25, 4.  ])
    """
    G, M, n, _ = A.shape
    kron = np.einsum("giab,gicd->giacbd", A, A).reshape(G, M, n * n, n * n)
    return np.einsum("ij,gixy->gjxiy", T, kron).reshape(G, M * n * n, M * n * n)


def linear_operator(A, T, adjoint=False, shift=0.0, identity=0.0):
    """L + shift I, or identity I - L, as a LinearOperator on flat symmetrised stacks.

    With ``identity`` non-zero: X -> identity * X - L(X) (I - L for the coupled Lyapunov
    equations); else X -> L(X) + shift * X (``shift`` > 0 makes the Perron eigenvalue
    rho + shift strictly dominant in modulus on periodic chains). ``adjoint``: L* instead of L.

    Examples
    --------
    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> x = np.ones(1)
    >>> linear_operator(A, T, shift=1.0).matvec(x), linear_operator(A, T, identity=1.0).matvec(x)
    (array([1.25]), array([0.75]))
    """
    M, n, _ = A.shape

    def matvec(x):
        return shifted_map(A, T, np.asarray(x).real, adjoint, shift, identity)

    return scipy.sparse.linalg.LinearOperator((M * n * n, M * n * n), matvec=matvec, dtype=float)


def shifted_map(A, T, x, adjoint=False, shift=0.0, identity=0.0, out=None):
    """L(X) + shift X, or identity X - L(X) where ``identity`` is non-zero, for X = sym(x), x a
    flat stack (L* for ``adjoint``): the product of :func:`linear_operator`, into the flat array
    ``out`` where given (else a new one). Not validated, for the inner loops.

    From M n^3 = ``mjls.parallel_from`` on, X is formed mode by mode in the parts of the products
    (:func:`in_parallel`), and the result in one pass.

    Examples
    --------
    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> shifted_map(A, T, np.ones(1), identity=1.0)
    array([0.75])
    """
    M, n, _ = A.shape
    x = x.reshape(M, n, n)
    if in_parallel(A):
        Y, X = _map_in_parts(A, T, x, adjoint, symmetrize=True)
    else:
        X = sym(x)
        Y = (costate_map if adjoint else second_moment_map)(A, T, X)
    out = np.empty(M * n * n) if out is None else out
    result = out.reshape(M, n, n)
    if identity == 1.0:
        np.subtract(X, Y, out=result)
    elif identity:
        np.multiply(X, identity, out=result)
        result -= Y
    elif shift:
        np.add(Y, shift * X, out=result)
    else:
        np.copyto(result, Y)
    return out
