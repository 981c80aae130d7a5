"""Small linear-algebra helpers shared by the subpackages: transposes and symmetric parts of
stacks, Kronecker sums of two stacks, packing of gains into one vector, the relative change
with one floor rule, and BiCGSTAB on an operator that writes into kept vectors.

Stacks of matrices have shape ``(..., n, m)``; every helper works on the last two axes.
"""

import math

import numpy as np
from scipy.linalg.blas import daxpy, dscal

from . import config
from .validation import function, integer, real_array, real_scalar

__all__ = ["transpose", "sym", "kronecker_sum", "pack", "unpack", "relative_change", "bicgstab"]


def transpose(X):
    """The transpose of every matrix of a stack (the last two axes).

    Examples
    --------
    >>> transpose(np.arange(6.0).reshape(1, 2, 3)).shape
    (1, 3, 2)
    """
    return np.swapaxes(X, -1, -2)


def sym(X):
    """The symmetric part (X + X^T) / 2 of every matrix of a stack.

    Examples
    --------
    >>> sym(np.array([[0.0, 2.0], [0.0, 0.0]]))
    array([[0., 1.],
           [1., 0.]])
    """
    return 0.5 * (X + transpose(X))



def kronecker_sum(X, Y):
    """sum_i X_i (x) Y_i of two stacks, (M, a, b) and (M, c, d), shape (a c, b d): e.g. the matrix
    of L -> sum_i S_i L W_i on column-major vec L for symmetric W_i, in the gain equations
    (3.31) and (3.34) (X = W, Y = S), and the blocks of (3.49).

    One product of the (M, a b) and (M, c d) stacks of entries, rearranged.

    Examples
    --------
    >>> X = np.array([[[1.0, 2.0], [2.0, 3.0]]]); Y = np.array([[[4.0]]])
    >>> kronecker_sum(X, Y)
    array([[ 4.,  8.],
           [ 8., 12.]])
    >>> A, B = np.ones((3, 2, 1)), np.ones((3, 1, 2))
    >>> bool(np.array_equal(kronecker_sum(A, B), 3 * np.kron(A[0], B[0])))
    True
    >>> kronecker_sum(np.ones((2, 1, 1)), np.ones((3, 1, 1)))
    Traceback (most recent call last):
    ...
    ValueError: X, Y: expected stacks (M, a, b) and (M, c, d) of the same M, found shapes
    (2, 1, 1) and (3, 1, 1)
    """
    X, Y = np.asarray(X), np.asarray(Y)
    if X.ndim != 3 or Y.ndim != 3 or len(X) != len(Y):
        raise ValueError(f"X, Y: expected stacks (M, a, b) and (M, c, d) of the same M, found "
                         f"shapes {X.shape} and {Y.shape}")
    M, a, b = X.shape
    _, c, d = Y.shape
    products = X.reshape(M, -1).T @ Y.reshape(M, -1)          # [(a, b), (c, d)]: X_ab Y_cd
    return products.reshape(a, b, c, d).transpose(0, 2, 1, 3).reshape(a * c, b * d)


def pack(*matrices):
    """One vector [vec G_1; vec G_2; ...] of matrices, column-stacking vec (as in (3.49)).

    Examples
    --------
    >>> pack(np.array([[1.0, 2.0], [3.0, 4.0]]), np.zeros((2, 1)), np.ones((1, 2)))
    array([1., 3., 2., 4., 0., 0., 1., 1.])
    """
    return np.concatenate([np.reshape(G, -1, order="F") for G in matrices])


def unpack(z, shapes):
    """The matrices of the given shapes from a vector of :func:`pack`; its inverse.

    Examples
    --------
    >>> F, K, L = unpack(np.arange(8.0), ((2, 2), (2, 1), (1, 2)))
    >>> F.tolist(), K.ravel().tolist(), L.tolist()
    ([[0.0, 2.0], [1.0, 3.0]], [4.0, 5.0], [[6.0, 7.0]])
    """
    out, start = [], 0
    for shape in shapes:
        size = int(np.prod(shape))
        out.append(np.reshape(z[start:start + size], shape, order="F"))
        start += size
    return out


def relative_change(old, new, floor=None, axis=None):
    """||new - old||_F / max(||new||_F, floor): how much an iterate moved, relative to its size.

    Parameters
    ----------
    old, new : array_like
        Iterates; ``old`` may carry leading axes (several old iterates against one new).
    floor : float, optional
        Absolute floor of ||new||: a zero iterate converges instead of dividing by zero
        (default ``config.defaults["linalg.norm_floor"]``).
    axis : int or tuple of int, optional
        The axes the norms run over (default: all, returning a float); the others are kept.

    Examples
    --------
    >>> round(relative_change(np.array([1.0, 0.0]), np.array([1.0, 0.1])), 6)
    0.099504
    >>> relative_change(np.zeros(2), np.zeros(2))
    0.0

    Two old iterates against one new, each row its own norm:

    >>> relative_change(np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([[1.0, 0.0], [0.0, 2.0]]),
    ...                 axis=-1)
    array([0. , 0.5])
    """
    floor = config.defaults["linalg.norm_floor"] if floor is None else floor
    if axis is None:
        d = np.ravel(new) - np.ravel(old)
        n = np.ravel(new)
        return float(np.sqrt(np.vdot(d, d)) / max(np.sqrt(np.vdot(n, n)), floor))
    new = np.asarray(new)
    d = new - np.asarray(old)
    return np.sqrt((d * d).sum(axis=axis)) / np.maximum(np.sqrt((new * new).sum(axis=axis)), floor)


def bicgstab(apply, b, x0, rtol, max_iter):
    """BiCGSTAB (van der Vorst, SIAM J. Sci. Stat. Comput. 13(2), 1992, Alg. "Bi-CGSTAB") for
    K x = b, without preconditioner, on six vectors kept for the whole solve.

    ``apply(x, out)`` writes K x into ``out``; the vector updates are in place (BLAS axpy), so a
    solve of size 10^6 allocates nothing after its start (two threads allocating and freeing
    vectors of 8 MB wait for each other's page mappings).

    Parameters
    ----------
    apply : callable
        (x, out) -> None, out = K x; x and out flat float arrays of the size of b.
    b, x0 : numpy.ndarray
        Right-hand side and start (flat, float).
    rtol : float
        Stop when the recursively updated residual is at most rtol ||b||.
    max_iter : int
        Iteration limit.

    Returns
    -------
    x : numpy.ndarray
    iterations : int
        Iterations started (each one or two products with K); the caller checks the true
        residual, which a breakdown (rho or omega of the recurrence 0) or the limit leaves above
        rtol.

    Examples
    --------
    >>> K = np.array([[4.0, 1.0], [2.0, 3.0]]); b = np.array([1.0, 2.0])
    >>> x, iterations = bicgstab(lambda v, out: np.matmul(K, v, out=out), b, np.zeros(2),
    ...                          1e-12, 10)
    >>> np.allclose(K @ x, b), iterations
    (True, 2)
    >>> bicgstab(lambda v, out: None, b, np.zeros(3), 1e-12, 10)
    Traceback (most recent call last):
    ...
    ValueError: x0: expected shape (2,), found shape (3,)
    """
    apply = function(apply, "apply")
    b = real_array(b, "b", ndim=1, finite=False)        # non-finite: the caller's residual says so
    x = real_array(x0, "x0", shape=b.shape, finite=False).copy()
    rtol = real_scalar(rtol, "rtol", low=0, high=1, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=0)
    if not np.any(b):
        return np.zeros_like(x), 0
    r, v, t = np.empty_like(x), np.zeros_like(x), np.empty_like(x)
    apply(x, r)
    np.subtract(b, r, out=r)
    r_hat, p = r.copy(), r.copy()
    limit = rtol * math.sqrt(np.dot(b, b))
    breakdown = np.finfo(float).eps ** 2
    rho_prev = alpha = omega = 1.0
    for iteration in range(max_iter):
        rho = float(np.dot(r_hat, r))
        if math.sqrt(np.dot(r, r)) <= limit or abs(rho) < breakdown or omega == 0.0:
            return x, iteration
        if iteration:                                   # p = r + beta (p - omega v)
            daxpy(v, p, a=-omega)
            dscal((rho / rho_prev) * (alpha / omega), p)
            daxpy(r, p)
        apply(p, v)
        r_hat_v = float(np.dot(r_hat, v))
        if r_hat_v == 0.0:
            return x, iteration + 1
        alpha = rho / r_hat_v
        daxpy(v, r, a=-alpha)                           # r is now s = r - alpha v
        daxpy(p, x, a=alpha)
        if math.sqrt(np.dot(r, r)) <= limit:
            return x, iteration + 1
        apply(r, t)
        omega = float(np.dot(t, r)) / float(np.dot(t, t))
        daxpy(r, x, a=omega)
        daxpy(t, r, a=-omega)
        rho_prev = rho
    return x, max_iter
