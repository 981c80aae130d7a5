"""BLAS thread control and task parallelism for the library's iterative methods.

The iterative methods of :mod:`asoc.mjls` work on n x n products and vectors of length M n^2, where
BLAS threads cost more than they gain; they run inside :func:`single_threaded`. Where two
independent computations of that kind meet (the two moment equations of one gain, the two
recursions of (3.35)), :func:`concurrently` runs them on threads of their own, each with
single-threaded BLAS: numpy releases the interpreter lock in its products, and at n = M = 100
one application of L and one of L* take 26 ms together instead of 50 ms one after the other, or
44 ms with two BLAS threads (2-core machine).
"""

import contextlib
import contextvars
import os
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from threadpoolctl import ThreadpoolController

from .validation import integer

__all__ = ["single_threaded", "concurrently", "worker_count", "parts", "in_parts",
           "stacked_in_parts"]


_LOCK = threading.Lock()
# the open single_threaded() contexts of all threads, the limiter that restores BLAS after them,
# and the controller with the number of modules loaded when it was made
_OPEN = {"count": 0, "limiter": None}
_POOL = {}


@contextlib.contextmanager
def single_threaded():
    """A context in which BLAS runs on one thread: the iterative methods work on n x n products
    and vectors of length M n^2, where threads cost more than they gain (10x slower at n = 64,
    M = 8 on a loaded 2-core machine).

    The limit is process-wide. Contexts may overlap across threads (:func:`concurrently`): the
    first to open sets it, the last to close restores the earlier number of threads.

    Examples
    --------
    >>> from threadpoolctl import threadpool_info
    >>> with single_threaded():
    ...     print({lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"})
    {1}
    """
    with _LOCK:
        if _OPEN["count"] == 0:
            _OPEN["limiter"] = _controller().limit(limits=1, user_api="blas")
        _OPEN["count"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _OPEN["count"] -= 1
            if _OPEN["count"] == 0:
                _OPEN["limiter"].restore_original_limits()


def _controller():
    """The thread-pool controller of the BLAS libraries loaded now. A controller misses the
    libraries loaded after it was made (scipy brings its own OpenBLAS, which ARPACK uses), so it
    is made again whenever modules were imported since (making one takes about 1 ms).
    """
    if _OPEN.get("modules") != len(sys.modules):
        _OPEN["controller"], _OPEN["modules"] = ThreadpoolController(), len(sys.modules)
    return _OPEN["controller"]


def worker_count():
    """The threads :func:`concurrently` may use: the cores this process may run on.

    Examples
    --------
    >>> worker_count() >= 1
    True
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - platforms without sched_getaffinity
        return os.cpu_count() or 1


def parts(count):
    """Slices that cut range(count) into :func:`worker_count` contiguous parts of nearly equal
    length (fewer where count is smaller), for :func:`concurrently` over a stack.

    Examples
    --------
    >>> [(p.start, p.stop) for p in parts(5)] == [(5 * k // worker_count(), 5 * (k + 1) //
    ...     worker_count()) for k in range(min(5, worker_count()))]
    True
    """
    count = integer(count, "count", minimum=0)
    return _split(count, max(1, min(count, worker_count())))


def concurrently(*calls):
    """The results of the argument-free callables ``calls``, in order, computed on up to
    :func:`worker_count` threads with single-threaded BLAS.

    Each call runs in a copy of the caller's context, so per-call settings
    (:func:`asoc.config.accepts_settings`) hold in it. The first call runs on the calling thread,
    with its share of the calls (contiguous groups, one per thread); a group is handed only to a
    worker reserved for it, and where none is free the calls run on the calling thread, so no
    thread ever waits for a queued call (calls made from inside a call take a worker when one
    has become free, e.g. when the other of two solves has finished).
    An exception of a call is raised once every call has finished. Results are those of the calls
    run alone: each call's arithmetic is the same whichever thread runs it.

    Raises
    ------
    TypeError
        If a call is not callable (named by its position, ``calls[k]``).

    Examples
    --------
    >>> import numpy as np
    >>> A = np.arange(4.0).reshape(2, 2)
    >>> left, right = concurrently(lambda: A @ A, lambda: A.T @ A)
    >>> left.tolist(), right.tolist()
    ([[2.0, 3.0], [6.0, 11.0]], [[4.0, 6.0], [6.0, 10.0]])
    >>> concurrently(lambda: 1, 2)
    Traceback (most recent call last):
    ...
    TypeError: calls[1]: expected an argument-free callable, found int
    """
    for k, call in enumerate(calls):
        if not callable(call):
            raise TypeError(f"calls[{k}]: expected an argument-free callable, found "
                            f"{type(call).__name__}")
    with single_threaded():
        pool = _pool(worker_count() - 1) if len(calls) > 1 and worker_count() > 1 else None
        handed = pool.reserve(len(calls) - 1) if pool is not None else 0
        if handed == 0:
            return [call() for call in calls]
        # contiguous groups of calls, the first on this thread, one on each reserved worker
        groups = [[(contextvars.copy_context(), call) for call in calls[part]]
                  for part in _split(len(calls), handed + 1)]
        futures = [pool.submit(_run_group, group) for group in groups[1:]]
        try:
            here = _run_group(groups[0])
        finally:
            rest = [future.exception() for future in futures]   # waits for every call
        for error in rest:
            if error is not None:
                raise error
        return here + [result for future in futures for result in future.result()]


def _run_group(group):
    """The results of the (context, call) pairs of a group, each call run in its context."""
    return [context.run(call) for context, call in group]


def _split(count, pieces):
    """Slices cutting range(count) into ``pieces`` contiguous parts of nearly equal length."""
    return [slice(count * k // pieces, count * (k + 1) // pieces) for k in range(pieces)]


def in_parts(task, count):
    """task(part) for the :func:`parts` of range(count), concurrently (:func:`concurrently`).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.zeros(6)
    >>> def fill(part):
    ...     x[part] = np.arange(6)[part] ** 2
    >>> in_parts(fill, 6)
    >>> x.tolist()
    [0.0, 1.0, 4.0, 9.0, 16.0, 25.0]
    >>> in_parts(fill, -1)
    Traceback (most recent call last):
    ...
    ValueError: count: expected an integer >= 0, found -1
    """
    if not callable(task):
        raise TypeError(f"task: expected a callable of one slice, found {type(task).__name__}")
    concurrently(*(lambda part=part: task(part) for part in parts(count)))


def stacked_in_parts(function, *stacks):
    """``function(*stacks)`` for a function that works matrix by matrix along the leading axis (e.g.
    M eigendecompositions), computed in the :func:`parts` of that axis concurrently
    (:func:`concurrently`) and joined: an array, or a tuple of arrays where the function returns
    a tuple.

    Examples
    --------
    >>> import numpy as np
    >>> X = np.arange(8.0).reshape(2, 2, 2)
    >>> stacked_in_parts(lambda S: S.sum(axis=(1, 2)), X).tolist()
    [6.0, 22.0]
    >>> stacked_in_parts(len, X)
    Traceback (most recent call last):
    ...
    TypeError: function: expected a function of the stacks' parts returning arrays, found int
    """
    if not callable(function):
        raise TypeError(f"function: expected a callable, found {type(function).__name__}")
    lengths = {len(stack) if hasattr(stack, "__len__") else None for stack in stacks}
    if len(lengths) != 1 or None in lengths:
        raise ValueError(f"stacks: expected one or more arrays of one length along the leading "
                         f"axis, found lengths {sorted(lengths, key=str)}")
    pieces = concurrently(*(lambda part=part: function(*(stack[part] for stack in stacks))
                            for part in parts(len(stacks[0]))))
    if isinstance(pieces[0], tuple):
        return tuple(np.concatenate(joined) for joined in zip(*pieces))
    if not isinstance(pieces[0], np.ndarray):
        raise TypeError("function: expected a function of the stacks' parts returning arrays, "
                        f"found {type(pieces[0]).__name__}")
    return np.concatenate(pieces)


class _Pool:
    """A thread pool whose workers are reserved before a call is handed to them (:meth:`reserve`),
    so that a call never waits in its queue behind another: nested calls cannot deadlock.
    """

    def __init__(self, workers):
        self.executor = ThreadPoolExecutor(workers, thread_name_prefix="asoc")
        self.free = workers

    def reserve(self, wanted):
        """The number of workers (at most ``wanted``) now reserved for the caller's calls."""
        with _LOCK:
            taken = min(wanted, self.free)
            self.free -= taken
        return taken

    def submit(self, run, calls):
        """run(calls) on a reserved worker, which is free again once it has returned."""
        return self.executor.submit(self._release_after, run, calls)

    def _release_after(self, run, calls):
        try:
            return run(calls)
        finally:
            with _LOCK:
                self.free += 1


def _pool(workers):
    """The pool of ``workers`` threads, made once per size (and again after a fork)."""
    key = (os.getpid(), workers)
    with _LOCK:
        if key not in _POOL:
            _POOL[key] = _Pool(workers)
        return _POOL[key]
