"""The estimate of the spectral radius rho of the second-moment operator L (Cor. 3.2): an
eigen-solver's rho and its positive semidefinite eigenvector, the input of the certificate.

The methods (:data:`METHODS`, one table resolved by :func:`resolve_method`): rho(A)^2 directly for
one mode (``"single_mode"``); the dense eigenvalues of the Kronecker matrix for small M n^2
(``"dense"``); ARPACK on the matrix-free operator above (``"arnoldi"``, falling back to dense
eigenvalues up to M n^2 = ``mjls.dense_fallback_radius``, ``"arnoldi+dense"``, else to the
shifted cone power method, ``"power"``). An estimate is never reported alone:
:mod:`asoc.mjls.certificate` brackets rho around it and :mod:`asoc.mjls.stability` gives the verdict.
Calls run one way: stability -> certificate -> spectral_estimate.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from .. import config
from ..linalg import sym, transpose
from ..threads import single_threaded
from .moment_operator import costate_map, kronecker_stack, linear_operator

__all__ = ["METHODS", "Estimate", "check_method", "resolve_method", "fallback_method",
           "adjoint_method", "left_perron_stack", "balance", "psd_stack", "estimates", "estimate"]


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
        "single_mode", "dense", "arnoldi", "arnoldi+dense" or "power".
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
        raise ValueError(f"method: expected one of {', '.join(map(repr, METHODS))}, found {method!r}")


def resolve_method(method, M, n):
    """The eigen-solver that ``method`` means for M modes of size n: the one resolution table.

    ``"auto"`` is "single_mode" for one mode, "dense" up to M n^2 = ``mjls.dense_max_radius``,
    else "arnoldi"; "arnoldi" on M n^2 <= 3 is "dense"; every other name stands for itself.

    Examples
    --------
    >>> resolve_method("auto", 1, 3), resolve_method("auto", 2, 3), resolve_method("auto", 100, 100)
    ('single_mode', 'dense', 'arnoldi')
    """
    if method == "auto":
        if M == 1:
            return "single_mode"
        return "dense" if M * n * n <= config.defaults["mjls.dense_max_radius"] else "arnoldi"
    return "dense" if method == "arnoldi" and M * n * n <= 3 else method


def fallback_method(dim):
    """Where no Krylov space converges: dense eigenvalues up to M n^2 = ``mjls.dense_fallback_radius``
    ("arnoldi+dense"), else the shifted cone power method ("power").

    Examples
    --------
    >>> fallback_method(16), fallback_method(10**6)
    ('arnoldi+dense', 'power')
    """
    return "arnoldi+dense" if dim <= config.defaults["mjls.dense_fallback_radius"] else "power"


def adjoint_method(method):
    """The eigen-solver for the left Perron stack, given the one that found the right one: the
    same, with the dense fallback run with left eigenvectors ("arnoldi+dense" -> "dense").

    Examples
    --------
    >>> adjoint_method("arnoldi+dense"), adjoint_method("arnoldi")
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
    left = estimate(A, T, adjoint_method(method), adjoint=True)
    return left.X if left.method != "power" else _adjoint_power(A, T, rho)


def balance(A):
    """D^-1 A_i D / s with one diagonal D and scalar s, both powers of 2 (exact): returns (A', d, s).

    Examples
    --------
    >>> Ab, d, s = balance(np.array([[[8.0, 64.0], [0.0, 4.0]]]))
    >>> d.tolist(), s, bool(np.abs(Ab).max() <= 2.0)
    ([4.0, 0.5], 8.0, True)
    """
    M, n, _ = A.shape
    d = np.ones(n)
    if n > 1:
        with np.errstate(invalid="ignore"):                        # scipy casts its unused permutation
            d = np.diag(scipy.linalg.matrix_balance(np.abs(A).sum(axis=0), permute=False)[1]).copy()
    Ab = A / d[:, None] * d[None, :]
    top = float(np.abs(Ab).max())
    s = 1.0 if top == 0.0 or not np.isfinite(top) else float(2.0 ** np.round(np.log2(top)))
    return Ab / s, d, s


def psd_stack(v, M, n):
    """The positive semidefinite stack nearest the real symmetric part of an eigenvector (phase removed).

    Examples
    --------
    >>> psd_stack(np.array([1.0, 0.0, 0.0, -1e-3]), 1, 2).round(6).tolist()
    [[[1.0, 0.0], [0.0, 0.0]]]
    """
    Z = np.asarray(v).reshape(M, n, n)
    z = Z.ravel()
    big = z[np.argmax(np.abs(z))]
    Z = sym((Z * (np.conj(big) / abs(big))).real) if abs(big) > 0 else np.zeros((M, n, n))
    if np.trace(Z, axis1=1, axis2=2).sum() < 0:
        Z = -Z
    w, U = np.linalg.eigh(Z)
    Z = (U * np.clip(w, 0.0, None)[:, None, :]) @ transpose(U)
    top = np.abs(Z).max()
    return sym(Z) / top if top > 0 else np.broadcast_to(np.eye(n), (M, n, n)).copy()


def estimates(A, T, method):
    """The eigen-solver's estimates in turn: Arnoldi with each Krylov-space size, then its fallback.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> [e.method for e in estimates(A, T, "power")]
    ['power']
    """
    M, n, _ = A.shape
    method = resolve_method(method, M, n)
    if method == "arnoldi" and M * n * n > 3:
        yield from _arnoldi(A, T, False)
        method = fallback_method(M * n * n)
    yield estimate(A, T, method)


def estimate(A, T, method, adjoint=False):
    """rho and a PSD eigenvector of L (or L*) from the eigen-solver ``method`` (a name of
    :data:`METHODS`, or one that :func:`resolve_method` returns).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> e = estimate(A, T, "auto")
    >>> round(e.rho, 12), e.method
    (0.845, 'dense')
    """
    M, n, _ = A.shape
    dim = M * n * n
    method = resolve_method(method, M, n)
    if method == "single_mode":
        return _single_mode(A[0], adjoint)
    if method == "arnoldi" and dim > 3:
        estimate = next(_arnoldi(A, T, adjoint), None)
        if estimate is not None:
            return estimate
        method = fallback_method(dim)
    if method == "power":
        return Estimate(np.nan, np.broadcast_to(np.eye(n), (M, n, n)).copy(), "power")
    K = kronecker_stack(A[None], T)[0]
    K = K.T if adjoint else K
    if method == "dense":
        lam, left, right = scipy.linalg.eig(K, left=True, right=True)
    else:                                               # the fallback, up to M n^2 = 1024: no left vectors
        lam, right = scipy.linalg.eig(K)
    rho = float(np.max(np.abs(lam)))
    top = np.flatnonzero(np.abs(lam) >= rho * (1 - 1e-8))
    k = top[np.argmax(lam[top].real)]                             # the real Perron eigenvalue
    return Estimate(rho, psd_stack(right[:, k], M, n), method,
                     _first_order_lower(K, lam, left, right) if method == "dense" else 0.0)


def _single_mode(A, adjoint):
    """M = 1: rho = rho(A)^2 with eigenvector Re(v v^H) for A v = lambda v (A^T for the adjoint)."""
    A = A.T if adjoint else A
    lam, left, right = scipy.linalg.eig(A, left=True, right=True)
    k = np.argmax(np.abs(lam))
    v = right[:, k]
    lower = _first_order_lower(A, lam, left, right)
    return Estimate(float(abs(lam[k])) ** 2, psd_stack(np.outer(v, np.conj(v)), 1, len(A)), "single_mode",
                     lower * lower)


def _first_order_lower(K, lam, left, right):
    """max_k |lambda_k| - s_k ||E||: a computed eigenvalue is exact for K + E with ||E|| <= 10 N eps ||K||_F
    (backward stable QR algorithm), and moves by at most s_k ||E|| to first order, s_k = 1 / |w_k^H v_k|
    its condition number (Wilkinson). Useless (0) for defective eigenvalues, where s_k is huge."""
    with np.errstate(divide="ignore"):
        s = 1.0 / np.abs(np.einsum("ik,ik->k", np.conj(left), right))
    error = 10.0 * len(K) * _EPS * np.linalg.norm(K)
    bounds = np.abs(lam) - 10.0 * s * error                     # a further factor 10 for safety
    return float(max(0.0, np.max(bounds)))


def _arnoldi(A, T, adjoint):
    """Estimates by ARPACK on L (or L*), one per Krylov-space size of ``mjls.arnoldi_subspaces`` (after 20
    from M n^2 = ``mjls.arnoldi_lean_from`` on) that converges: the largest-modulus eigenvalue; when it is not real positive (periodic chains), again on
    L + |lambda| I, where the Perron eigenvalue is strictly dominant."""
    M, n, _ = A.shape
    dim = M * n * n
    v0 = np.broadcast_to(np.eye(n), (M, n, n)).ravel()
    lean = (20,) if dim >= config.defaults["mjls.arnoldi_lean_from"] else ()
    for ncv in lean + tuple(config.defaults["mjls.arnoldi_subspaces"]):
        shift = 0.0
        try:
            with single_threaded():
                for _ in range(2):
                    lam, V = scipy.sparse.linalg.eigs(linear_operator(A, T, adjoint, shift=shift), k=1, which="LM",
                                                      tol=1e-14, ncv=min(dim - 1, ncv), maxiter=max(1000, dim), v0=v0)
                    lam = complex(lam[0]) - shift
                    if abs(lam.imag) <= 1e-8 * abs(lam) and lam.real >= 0:
                        break
                    shift = abs(lam)
            yield Estimate(abs(lam), psd_stack(V[:, 0], M, n), "arnoldi")
        except scipy.sparse.linalg.ArpackError:
            pass
        if ncv >= dim - 1:
            return


def _adjoint_power(A, T, rho):
    """The left Perron stack by the shifted power method P <- L*(P) + rho P (where ARPACK failed)."""
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
