"""Small linear-algebra helpers shared by the subpackages: transposes and symmetric parts of
stacks, Kronecker sums of two stacks, packing of gains into one vector, and the relative change
with one floor rule.

Stacks of matrices have shape ``(..., n, m)``; every helper works on the last two axes.
"""

import numpy as np

from . import config

__all__ = ["transpose", "sym", "kronecker_sum", "pack", "unpack", "relative_change"]


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
