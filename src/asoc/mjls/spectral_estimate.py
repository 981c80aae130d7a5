"""The estimate of the spectral radius rho of the second-moment operator L (Cor. 3.2): an
eigen-solver's rho and its positive semidefinite eigenvector, the input of the certificate.

The methods (:data:`METHODS`, one table resolved by ``_resolve_method``): rho(A)^2 directly for
one mode (``"single_mode"``); the dense eigenvalues of the Kronecker matrix for small M n^2
(``"dense"``); ARPACK on the matrix-free operator above (``"arnoldi"``, falling back to dense
eigenvalues up to M n^2 = ``mjls.dense_fallback_radius``, ``"arnoldi+dense"``, else to the
shifted cone power method, ``"power"``); for many scalar modes (n = 1), where L is a sparse
nonnegative M x M matrix, Noda's inverse iteration (``"noda"``).
An estimate is never reported alone: :mod:`asoc.mjls.certificate` brackets rho around it and
:mod:`asoc.mjls.stability` gives the verdict. Calls run one way: stability -> certificate ->
spectral_estimate.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from .. import config
from ..linalg import sym, transpose
from ..threads import single_threaded, stacked_in_parts
from .moment_operator import (
    costate_map,
    in_parallel,
    kronecker_stack,
    linear_operator,
    second_moment_map,
)

__all__ = ["METHODS", "Estimate", "check_method", "left_perron_stack", "Balanced", "balance",
           "power_estimate",
           "estimates", "estimate"]


_EPS = np.finfo(float).eps
#: The methods a caller may name; "single_mode" and "arnoldi+dense" are what they resolve to.
METHODS = ("auto", "dense", "arnoldi", "power")


@dataclass(frozen=True)
class Estimate:
    """An eigen-solver's estimate of rho with a positive semidefinite eigenvector stack.

    Attributes
    ----------
    rho : float
        The eigen-solver's rho (nan for the power method).
    X : numpy.ndarray, shape (M, n, n)
        Positive semidefinite eigenvector estimate (the identity stack for the power method).
    method : str
        "single_mode", "noda", "dense", "arnoldi", "arnoldi+dense" or "power".
    lower : float
        First-order perturbation lower bound of rho (dense eigenvalues only, else 0).

    Examples
    --------
    >>> Estimate(0.25, np.ones((1, 1, 1)), "single_mode").lower
    0.0
    """

    rho: float
    X: np.ndarray
    method: str
    lower: float = 0.0


def check_method(method):
    """Reject a ``method`` that is not one of :data:`METHODS`.

    Examples
    --------
    >>> check_method("qr")
    Traceback (most recent call last):
    ...
    ValueError: method: expected one of 'auto', 'dense', 'arnoldi', 'power', found 'qr'
    """
    if method not in METHODS:
        raise ValueError(f"method: expected one of {', '.join(map(repr, METHODS))}, "
                         f"found {method!r}")


def _resolve_method(method, M, n):
    """The eigen-solver that ``method`` means for M modes of size n: the one resolution table.

    ``"auto"`` is "single_mode" for one mode, "noda" for scalar modes (n = 1) from
    M = ``mjls.scalar_sparse_from`` on, "dense" up to M n^2 = ``mjls.dense_max_radius``, else
    "arnoldi"; "arnoldi" on M n^2 <= 3 is "dense"; every other name stands for itself.

    Examples
    --------
    >>> [_resolve_method("auto", M, n) for M, n in ((1, 3), (2, 3), (100, 100))]
    ['single_mode', 'dense', 'arnoldi']
    >>> _resolve_method("auto", 1000, 1)
    'noda'
    """
    if method == "auto":
        if M == 1:
            return "single_mode"
        if n == 1 and M >= config.defaults["mjls.scalar_sparse_from"]:
            return "noda"
        return "dense" if M * n * n <= config.defaults["mjls.dense_max_radius"] else "arnoldi"
    return "dense" if method == "arnoldi" and M * n * n <= 3 else method


def _fallback_method(dim):
    """Where no Krylov space converges: dense eigenvalues up to
    M n^2 = ``mjls.dense_fallback_radius`` ("arnoldi+dense"), else the shifted cone power method
    ("power").

    Examples
    --------
    >>> _fallback_method(16), _fallback_method(10**6)
    ('arnoldi+dense', 'power')
    """
    return "arnoldi+dense" if dim <= config.defaults["mjls.dense_fallback_radius"] else "power"


def _adjoint_method(method):
    """The eigen-solver for the left Perron stack, given the one that found the right one: the
    same, with the dense fallback run with left eigenvectors ("arnoldi+dense" -> "dense").

    Examples
    --------
    >>> _adjoint_method("arnoldi+dense"), _adjoint_method("arnoldi")
    ('dense', 'arnoldi')
    """
    return "dense" if method == "arnoldi+dense" else method


def left_perron_stack(A, T, rho, method):
    """The left Perron stack P, L*(P) = rho P, by the eigen-solver matching ``method`` (the right
    stack's), or the shifted power method P <- L*(P) + rho P where that is the power method.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.9]]]); T = np.array([[0.0, 1.0], [1.0, 0.0]])
    >>> P = left_perron_stack(A, T, 0.45, "dense")
    >>> (P.ravel() / np.linalg.norm(P)).round(4)
    array([0.4856, 0.8742])
    """
    left = estimate(A, T, _adjoint_method(method), adjoint=True)
    return left.X if left.method != "power" else _adjoint_power(A, T, rho)


@dataclass(frozen=True)
class Balanced:
    """Modes and weights similar to (A, T) up to a power of 2: rho(L_{A,T}) = 2^g rho(L_{A', W}).

    With one diagonal D (powers of 2, ``scipy.linalg.matrix_balance`` of ``sum_i abs(A_i)``), mode
    exponents e_i and similarity exponents t_i,
    A_i = 2^{e_i} D A'_i D^-1 and W_ij = p_ij 2^{2 e_i + t_i - t_j - g}, because the similarity
    X_i -> 2^{t_i} D X_i D of the stack turns L(X)_j = sum_i p_ij A_i X_i A_i^T into
    2^g sum_i W_ij A'_i X_i A'_i^T. Every factor is a power of 2, so the map is exact unless an
    entry leaves the range of doubles: ``exact`` says whether (A', W) reproduce (A, T) exactly.

    Attributes
    ----------
    A, W : numpy.ndarray
        The balanced modes (largest entry of each about 1) and weights (not row-stochastic).
    d : numpy.ndarray, shape (n,)
        The diagonal of D.
    t : numpy.ndarray, shape (M,)
        The similarity exponents t_i of the modes.
    g : int
        rho(L_{A,T}) = 2^g rho(L_{A', W}).
    exact : bool
        (A', W) hold (A, T) without underflow: bounds on them are bounds of (A, T).
    """

    A: np.ndarray
    W: np.ndarray
    d: np.ndarray
    t: np.ndarray
    g: int
    exact: bool

    def to_stack(self, X, adjoint=False):
        """The stack X_i -> 2^{t_i} D X_i D of (A, T) (adjoint: P_i -> 2^{-t_i} D^-1 P_i D^-1)."""
        d = 1.0 / self.d if adjoint else self.d
        t = -self.t if adjoint else self.t
        return np.ldexp(X * d[:, None] * d[None, :], t[:, None, None])

    def from_stack(self, X):
        """The stack of (A', W) of a stack X of (A, T): the inverse of :meth:`to_stack`, scaled to
        largest entry 1 (where it is not zero).
        """
        Y = np.ldexp(X / (self.d[:, None] * self.d[None, :]), -self.t[:, None, None])
        top = np.abs(Y).max()
        return Y / top if top > 0 and np.isfinite(top) else Y


def balance(A, T):
    """(A, T) balanced exactly (:class:`Balanced`): one common diagonal D and one power of 2 for all
    modes, or, where the modes' scales differ by more than 2^``mjls.mode_scale_spread``, a power
    of 2 per mode and a per-mode similarity that balances the weights (Osborne's iteration on
    log2 W).

    Examples
    --------
    >>> b = balance(np.array([[[8.0, 64.0], [0.0, 4.0]]]), np.eye(1))
    >>> b.d.tolist(), b.g, bool(np.abs(b.A).max() <= 2.0), b.W.tolist(), b.exact
    ([4.0, 0.5], 6, True, [[1.0]], True)

    Scalar modes a_1 = 1e80, a_2 = 1e-80 on a 2-cycle: L is [[0, a_2^2], [a_1^2, 0]] with
    rho = ``abs(a_1 a_2)``; balanced, both weights are about ``abs(a_1 a_2) / 2^g``:

    >>> b = balance(np.array([[[1e80]], [[1e-80]]]), np.array([[0.0, 1.0], [1.0, 0.0]]))
    >>> bool(np.all(b.W.sum(axis=1) > 0.25) and np.all(b.W.sum(axis=1) < 4)), b.exact
    (True, True)
    """
    M, n, _ = A.shape
    d = np.ones(n)
    if n > 1:
        # scipy casts its unused permutation
        with np.errstate(invalid="ignore"):
            d = np.diag(scipy.linalg.matrix_balance(np.abs(A).sum(axis=0), permute=False)[1]).copy()
    Ad = A * (d[None, :] / d[:, None])                  # one product by a power of 2 per entry
    with np.errstate(divide="ignore"):
        e = np.round(np.log2(np.abs(Ad).max(axis=(1, 2))))
    live = np.isfinite(e)
    t = np.zeros(M, dtype=int)
    if live.any() and np.ptp(e[live]) > config.defaults["mjls.mode_scale_spread"]:
        e = np.where(live, e, np.median(e[live])).astype(int)
        t = _osborne_exponents(T, e)
        with np.errstate(divide="ignore"):
            exponents = np.where(T > 0, 2 * e[:, None] + t[:, None] - t[None, :], 0)
            g = int(np.max(np.where(T > 0, np.floor(np.log2(T)) + exponents, -np.inf)))
        W = np.ldexp(T, exponents - g)
        exact = _normal(W, T)
    else:
        top = float(np.abs(Ad).max())
        e = np.full(M, 0 if top == 0.0 or not np.isfinite(top) else int(np.round(np.log2(top))))
        W, g, exact = T, 2 * int(e[0]), True
    Ab = np.ldexp(Ad, -e[:, None, None])
    exact = exact and _normal(Ad, A) and _normal(Ab, A)
    return Balanced(Ab, W, d, t, g, exact)


def _normal(scaled, A):
    """A product by a power of 2 is exact iff it neither overflows nor lands below the normal range:
    every entry finite, and every nonzero entry of A still nonzero and at least the smallest normal.
    """
    live = A != 0
    magnitude = np.abs(scaled)
    return bool(np.all(np.isfinite(scaled)) and np.all(magnitude[live] >= np.finfo(float).tiny))


def _osborne_exponents(T, e):
    """Integer t balancing the weights w_ij = log2 p_ij + 2 e_i + t_i - t_j (i != j): Osborne's
    iteration equates, mode by mode, the log-sums of each mode's outgoing and incoming weights
    (exact in the log domain: no weight is formed before it is balanced).
    """
    M = len(T)
    with np.errstate(divide="ignore"):
        w = np.log2(T) + 2.0 * e[:, None]
    np.fill_diagonal(w, -np.inf)
    t = np.zeros(M)
    for _ in range(config.defaults["mjls.mode_balance_sweeps"]):
        moved = False
        for k in range(M):
            out = w[k] + t[k] - t
            into = w[:, k] + t - t[k]
            if np.isneginf(out.max()) or np.isneginf(into.max()):
                continue
            step = np.round((_log2_sum(into) - _log2_sum(out)) / 2)
            if step != 0:
                t[k] += step
                moved = True
        if not moved:
            break
    return t.astype(int)


def _log2_sum(x):
    top = x.max()
    return top + np.log2(np.exp2(x - top).sum())


def _psd_stack(v, M, n):
    """The positive semidefinite stack nearest the real symmetric part of an eigenvector, unphased.

    Examples
    --------
    >>> _psd_stack(np.array([1.0, 0.0, 0.0, -1e-3]), 1, 2).round(6).tolist()
    [[[1.0, 0.0], [0.0, 0.0]]]
    """
    Z = np.asarray(v).reshape(M, n, n)
    z = Z.ravel()
    big = z[np.argmax(np.abs(z))]
    Z = sym((Z * (np.conj(big) / abs(big))).real) if abs(big) > 0 else np.zeros((M, n, n))
    if np.trace(Z, axis1=1, axis2=2).sum() < 0:
        Z = -Z
    Z = stacked_in_parts(_nearest_psd, Z) if in_parallel(Z) else _nearest_psd(Z)
    top = np.abs(Z).max()
    return sym(Z) / top if top > 0 else np.broadcast_to(np.eye(n), (M, n, n)).copy()


def _nearest_psd(Z):
    """The nearest positive semidefinite matrix of each symmetric Z_i: its negative eigenvalues
    set to 0.
    """
    w, U = np.linalg.eigh(Z)
    return (U * np.clip(w, 0.0, None)[:, None, :]) @ transpose(U)


def estimates(A, T, method, start=None):
    """The eigen-solver's estimates in turn: Arnoldi with each Krylov-space size, then its fallback;
    for Arnoldi with a ``start`` near the Perron stack, first the power method from it
    (:func:`power_estimate`) where it converges.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> [e.method for e in estimates(A, T, "power")]
    ['power']
    """
    M, n, _ = A.shape
    method = _resolve_method(method, M, n)
    if method == "arnoldi" and M * n * n > 3:
        found = None if start is None else power_estimate(A, T, start)
        if found is not None:
            yield found
        yield from _arnoldi(A, T, False)
        method = _fallback_method(M * n * n)
    yield estimate(A, T, method)


def estimate(A, T, method, adjoint=False):
    """Rho and a PSD eigenvector of L (or L*) from the eigen-solver ``method`` (a name of
    :data:`METHODS`, or one that ``_resolve_method`` returns).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> e = estimate(A, T, "auto")
    >>> round(e.rho, 12), e.method
    (0.845, 'dense')
    """
    M, n, _ = A.shape
    dim = M * n * n
    method = _resolve_method(method, M, n)
    if method == "single_mode":
        return _single_mode(A[0], T[0, 0], adjoint)
    if method == "noda":
        return _noda(A[:, 0, 0], T, adjoint)
    if method == "arnoldi" and dim > 3:
        estimate = next(_arnoldi(A, T, adjoint), None)
        if estimate is not None:
            return estimate
        method = _fallback_method(dim)
    if method == "power":
        return Estimate(np.nan, np.broadcast_to(np.eye(n), (M, n, n)).copy(), "power")
    K = kronecker_stack(A[None], T)[0]
    K = K.T if adjoint else K
    if method == "dense":
        lam, left, right = scipy.linalg.eig(K, left=True, right=True)
    else:
        # the fallback, up to M n^2 = 1024: no left vectors
        lam, right = scipy.linalg.eig(K)
    rho = float(np.max(np.abs(lam)))
    top = np.flatnonzero(np.abs(lam) >= rho * (1 - config.defaults["mjls.perron_tie_rtol"]))
    k = top[np.argmax(lam[top].real)]                             # the real Perron eigenvalue
    return Estimate(rho, _psd_stack(right[:, k], M, n), method,
                     _first_order_lower(K, lam, left, right) if method == "dense" else 0.0)


def power_estimate(A, T, start, tol=1e-10):
    """Rho and its eigenvector stack by the power method ``X <- L(X) / max|L(X)|`` from ``start``, a
    stack near the Perron stack (e.g. the stationary second moments of the same or a nearby
    closed loop, X = sum_k L^k(N), whose Perron component dominates when rho is near 1 and the
    other eigenvalues are not): None where the largest change of an entry does not fall to
    ``tol`` within ``mjls.start_power_steps`` steps, or its rate says it would not.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> found = power_estimate(A, T, np.ones((2, 1, 1)))
    >>> round(found.rho, 9), found.method
    (0.845, 'power')
    """
    steps = config.defaults["mjls.start_power_steps"]
    top = np.abs(start).max()
    if not (top > 0 and np.isfinite(top)):
        return None
    X, previous = start / top, np.inf
    for step in range(steps):
        Y = sym(second_moment_map(A, T, X))
        rho = float(np.abs(Y).max())
        if not (rho > 0 and np.isfinite(rho)):
            return None
        Y /= rho
        change = float(np.abs(Y - X).max())
        X = Y
        if change <= tol:
            return Estimate(rho, X, "power")
        rate = change / previous
        if step >= 2 and (rate >= 1 or np.log(tol / change) / np.log(rate) > steps - step - 1):
            return None
        previous = change
    return None


def _single_mode(A, p, adjoint):
    """M = 1: rho = p rho(A)^2 with eigenvector Re(v v^H) for A v = lambda v (A^T for the adjoint);
    p = T[0, 0] as given (1 up to the row-sum tolerance of the validation: used, not rounded).
    """
    A = A.T if adjoint else A
    lam, left, right = scipy.linalg.eig(A, left=True, right=True)
    k = np.argmax(np.abs(lam))
    v = right[:, k]
    lower = _first_order_lower(A, lam, left, right)
    return Estimate(p * float(abs(lam[k])) ** 2, _psd_stack(np.outer(v, np.conj(v)), 1, len(A)),
                    "single_mode", p * lower * lower)


def _noda(a, T, adjoint):
    """Scalar modes: L is the nonnegative M x M matrix K = (diag(a^2) T)^T (its transpose for L*).
    Noda's inverse iteration x <- (r I - K)^-1 x with r = max_j (K x)_j / x_j, the Collatz-Wielandt
    upper bound, which stays >= rho and falls to it superlinearly, also on periodic chains (Noda,
    Numer. Math. 17, 1971); x stays positive because (r I - K)^-1 >= I / r. One sparse LU a step.
    """
    K = scipy.sparse.csr_matrix((T * (a * a)[:, None]) if adjoint else (T * (a * a)[:, None]).T)
    x = np.ones(len(a))
    eye = scipy.sparse.identity(len(a), format="csc")
    rtol = config.defaults["mjls.bracket_rtol"]
    upper = np.inf
    for _ in range(config.defaults["mjls.noda_max_steps"]):
        ratio = K @ x / x
        if not ratio.max() < upper:                            # stalled (rounding)
            break
        upper = float(ratio.max())
        if upper - ratio.min() <= rtol * upper or upper == 0.0:
            break
        try:
            shift = upper * (1 + 4 * _EPS)          # above rho also where upper is (reducible K)
            z = scipy.sparse.linalg.splu((shift * eye - K).tocsc()).solve(x)
        except RuntimeError:                        # shift rounds to an eigenvalue: x is Perron's
            break
        if not np.all(z > 0) or not np.all(np.isfinite(z)):
            break
        x = z / z.max()
    return Estimate(upper, x[:, None, None], "noda")


def _first_order_lower(K, lam, left, right):
    """max_k |lambda_k| - s_k ||E||: a computed eigenvalue is exact for K + E with
    ||E|| <= 10 N eps ||K||_F (backward stable QR algorithm), and moves by at most s_k ||E|| to
    first order, s_k = 1 / |w_k^H v_k| its condition number (Wilkinson). Useless (0) for defective
    eigenvalues, where s_k is huge.
    """
    with np.errstate(divide="ignore"):
        s = 1.0 / np.abs(np.einsum("ik,ik->k", np.conj(left), right))
    error = 10.0 * len(K) * _EPS * np.linalg.norm(K)
    bounds = np.abs(lam) - 10.0 * s * error                     # a further factor 10 for safety
    return float(max(0.0, np.max(bounds)))


def _arnoldi(A, T, adjoint):
    """Estimates by ARPACK on L (or L*), one per Krylov-space size of ``mjls.arnoldi_subspaces``
    (after ``mjls.arnoldi_lean_subspace``, to ``mjls.arnoldi_lean_tol``, from M n^2 =
    ``mjls.arnoldi_lean_from`` on) that converges: the largest-modulus eigenvalue; when it is not
    real positive (periodic chains), again on L + |lambda| I, where the Perron eigenvalue is
    strictly dominant.
    """
    M, n, _ = A.shape
    dim = M * n * n
    v0 = np.broadcast_to(np.eye(n), (M, n, n)).ravel()
    lean = config.defaults["mjls.arnoldi_lean_subspace"]
    lean = (lean,) if dim >= config.defaults["mjls.arnoldi_lean_from"] else ()
    for ncv in lean + tuple(config.defaults["mjls.arnoldi_subspaces"]):
        tol = config.defaults["mjls.arnoldi_lean_tol" if lean and ncv == lean[0] else
                              "mjls.arnoldi_tol"]
        shift = 0.0
        try:
            with single_threaded():
                for _ in range(2):
                    lam, V = scipy.sparse.linalg.eigs(
                        linear_operator(A, T, adjoint, shift=shift), k=1, which="LM", v0=v0,
                        tol=tol, ncv=min(dim - 1, ncv),
                        maxiter=max(1000, dim))
                    lam = complex(lam[0]) - shift
                    real = abs(lam.imag) <= config.defaults["mjls.arnoldi_real_rtol"] * abs(lam)
                    if real and lam.real >= 0:
                        break
                    shift = abs(lam)
            yield Estimate(abs(lam), _psd_stack(V[:, 0], M, n), "arnoldi")
        except scipy.sparse.linalg.ArpackError:
            pass
        if ncv >= dim - 1:
            return


def _adjoint_power(A, T, rho):
    """The left Perron stack by the shifted power method P <- L*(P) + rho P (if ARPACK failed)."""
    M, n, _ = A.shape
    P = np.broadcast_to(np.eye(n), (M, n, n)).copy()
    with single_threaded():
        for _ in range(config.defaults["mjls.power_max_steps"]):
            P_new = sym(costate_map(A, T, P)) + rho * P
            P_new /= np.abs(P_new).max()
            if np.abs(P_new - P).max() <= config.defaults["mjls.power_tol"]:
                return P_new
            P = P_new
    return P
