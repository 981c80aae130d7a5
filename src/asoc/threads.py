"""BLAS thread control for the library's iterative methods.

The iterative methods of :mod:`asoc.mjls` work on n x n products and vectors of length M n^2, where
BLAS threads cost more than they gain; they run inside :func:`single_threaded`.
"""

from threadpoolctl import ThreadpoolController

__all__ = ["single_threaded"]


_THREADS = ThreadpoolController()


def single_threaded():
    """A context in which BLAS runs on one thread: the iterative methods work on n x n products
    and vectors of length M n^2, where threads cost more than they gain (10x slower at n = 64,
    M = 8 on a loaded 2-core machine).

    Examples
    --------
    >>> from threadpoolctl import threadpool_info
    >>> with single_threaded():
    ...     print({lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"})
    {1}
    """
    return _THREADS.limit(limits=1, user_api="blas")
