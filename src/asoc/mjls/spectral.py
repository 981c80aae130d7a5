"""Mean-square stability (Sec. 3.3, Cor. 3.2): the spectral radius rho of the second-moment
operator L with a certified bracket, the stability verdict and the Perron pair of L.

The estimate of rho comes from an eigen-solver (dense eigenvalues of the Kronecker matrix for
small M n^2, Arnoldi on the matrix-free operator above; rho(A)^2 directly for one mode). It is
never reported alone: L is positive on the cone of positive semidefinite stacks, so for every
stack X > 0 the Collatz-Wielandt bounds

    min_j lambda_min(X_j^{-1/2} L(X)_j X_j^{-1/2}) <= rho <= max_j lambda_max(X_j^{-1/2} L(X)_j X_j^{-1/2})

hold, and they meet at the Perron stack (:mod:`asoc.mjls.certificate`). They are evaluated at
the eigen-solver's eigenvector (made positive semidefinite, shifted into the interior where
needed), at solutions of the resolvent equation r X - L(X) = I for r just above the estimate
(positive definite iff r > rho), and at a few steps of the shifted cone power method
X <- L(X) + rho X, which converges also on periodic chains. Where the Perron stack is singular
(reducible or triangular modes) or badly scaled (periodic chains), the lower end also comes from
first-order eigenvalue perturbation with the left Perron stack. An Arnoldi estimate that is not
inside a narrow bracket (a subdominant eigenvalue) is replaced by the next Krylov space's. The
verdict follows the bracket: stable iff its upper end is below 1, unstable iff its lower end is at
least 1, undecided otherwise.

Before any eigen-solve the modes are balanced, A_i -> D^-1 A_i D with one diagonal D (powers
of 2, from ``scipy.linalg.matrix_balance`` of sum_i |A_i|) and scaled by a power of 2: both are
exact in floating point, leave rho unchanged (up to the known factor) and keep A_i (x) A_i from
overflowing.
"""

import enum
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from .. import config
from ..linalg import sym, transpose
from .certificate import EPS, Bracket, deflated_resolvent_bounds, refine, residual_lower_bound
from .operators import costate_map, kronecker_stack, linear_operator, mode_stack, single_threaded


class Verdict(enum.Enum):
    """Mean-square stability verdict of Cor. 3.2 from the certified bracket of rho.

    Examples
    --------
    >>> Verdict("stable") is Verdict.STABLE
    True
    >>> mean_square_stability(np.array([[[2.0]]]), np.eye(1)).verdict
    <Verdict.UNSTABLE: 'unstable'>
    """

    STABLE = "stable"
    UNSTABLE = "unstable"
    UNDECIDED = "undecided"


@dataclass(frozen=True)
class MeanSquareStability:
    """rho of Cor. 3.2 with its certified bracket and the verdict that follows from it.

    Attributes
    ----------
    rho : float
        The eigen-solver's estimate, always inside [rho_lower, rho_upper].
    rho_lower, rho_upper : float
        Certified bounds rho_lower <= rho(L) <= rho_upper (Collatz-Wielandt, with a margin for
        rounding); rho_upper is inf when no bound could be certified.
    verdict : Verdict
        STABLE iff rho_upper < 1, UNSTABLE iff rho_lower >= 1, else UNDECIDED.
    method : str
        How the estimate was obtained: "single_mode", "dense", "arnoldi", "arnoldi+dense" or
        "power".

    Examples
    --------
    >>> s = mean_square_stability(np.array([[[0.5]]]), np.eye(1))
    >>> round(s.rho, 6), s.stabilizing, s.rho_lower <= s.rho <= s.rho_upper
    (0.25, True, True)
    """

    rho: float
    rho_lower: float
    rho_upper: float
    verdict: Verdict
    method: str

    @property
    def margin(self) -> float:
        """1 - rho (positive: stable)."""
        return 1.0 - self.rho

    @property
    def stable(self) -> bool:
        """True only when the bracket lies below 1."""
        return self.verdict is Verdict.STABLE

    @property
    def stabilizing(self):
        """True (certified stable), False (certified unstable) or None (undecided)."""
        return {Verdict.STABLE: True, Verdict.UNSTABLE: False, Verdict.UNDECIDED: None}[self.verdict]

    @property
    def bracket(self) -> tuple[float, float]:
        """(rho_lower, rho_upper), the certified bracket of rho."""
        return (self.rho_lower, self.rho_upper)

    def sentence(self) -> str:
        """rho, its certified bracket and the verdict in words, for messages.

        Examples
        --------
        >>> mean_square_stability(np.array([[[1.0]]]), np.eye(1)).sentence()
        'rho = 1.0000, certified in [1, 1]: undecided'
        """
        return (f"rho = {self.rho:.4f}, certified in [{self.rho_lower:.6g}, {self.rho_upper:.6g}]: "
                f"{self.verdict.value}")


def ms_spectral_radius(A_stack, T=None, *, method="auto", check=True) -> float:
    """Spectral radius rho of the second-moment operator (Cor. 3.2): mean-square stable iff rho < 1.

    Parameters
    ----------
    A_stack : MJLS or array_like, shape (M, n, n)
        An open-loop MJLS (its A stack and T), or per-mode (closed-loop) matrices, e.g. from
        :func:`asoc.mjls.closed_loop`.
    T : array_like, shape (M, M), optional
        Row-stochastic transition matrix; None with an MJLS.
    method : {"auto", "dense", "arnoldi", "power"}
        As :func:`mean_square_stability`.
    check : bool
        Validate the arguments (False: float arrays of consistent shapes).

    Returns
    -------
    float
        The estimate of rho, inside its certified bracket (:func:`mean_square_stability` returns
        the bracket). A RuntimeWarning says so when the bracket is wider than the relative
        width ``config.defaults["mjls.bracket_warn_rtol"]`` (e.g. for defective spectra).

    Raises
    ------
    ValueError
        If ``A_stack`` is not an (M, n, n) stack of finite matrices, ``T`` is not
        row-stochastic, or their numbers of modes differ.
    TypeError
        If ``A_stack`` or ``T`` is complex or not numeric, or ``T`` is missing.

    Examples
    --------
    Two stable modes whose switching is mean-square unstable (Sec. 3.2), as an MJLS or a stack:

    >>> from asoc.mjls.examples import SEC32_A, SEC32_T, sec32_system
    >>> round(ms_spectral_radius(SEC32_A, SEC32_T), 4), round(ms_spectral_radius(sec32_system()), 4)
    (1.4198, 1.4198)
    """
    if check:
        A_stack, T = mode_stack(A_stack, T)
    result = _certified(A_stack, T, method)
    width = result.rho_upper - result.rho_lower
    if not width <= config.defaults["mjls.bracket_warn_rtol"] * result.rho_upper:
        warnings.warn(f"the spectral radius {result.rho:.6g} is only known to lie in "
                      f"[{result.rho_lower:.6g}, {result.rho_upper:.6g}] (e.g. a defective or nearly "
                      f"reducible spectrum)", RuntimeWarning, stacklevel=2)
    return result.rho


def spectral_radius(A, T, method="auto"):
    """rho of Cor. 3.2 on validated float arrays: :func:`ms_spectral_radius` without checks or warning.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> round(spectral_radius(A, T), 12), round(spectral_radius(A, T, "power"), 9)
    (0.845, 0.845)
    """
    return _certified(A, T, method).rho


def mean_square_stability(A_stack, T=None, *, method="auto", check=True):
    """Cor. 3.2 as a certified verdict: rho with a bracket [rho_lower, rho_upper] and stable, unstable or undecided.

    Parameters
    ----------
    A_stack : MJLS or array_like, shape (M, n, n)
        An open-loop MJLS, or per-mode (closed-loop) matrices, e.g. the augmented closed loop
        of a dynamic controller (:func:`asoc.mjls.augmented_closed_loop`).
    T : array_like, shape (M, M), optional
        Row-stochastic transition matrix; None with an MJLS.
    method : {"auto", "dense", "arnoldi", "power"}
        The estimate: ``"dense"``, the eigenvalues of :func:`asoc.mjls.ms_operator`;
        ``"arnoldi"``, ARPACK on the matrix-free operator (Krylov spaces of
        ``config.defaults["mjls.arnoldi_subspaces"]`` vectors in turn; when none converges,
        dense up to M n^2 = ``mjls.dense_fallback_radius``, else ``"power"``); ``"power"``: the
        shifted cone power method alone. ``"auto"``: rho(A)^2 for one mode, dense up to
        M n^2 = ``mjls.dense_max_radius``, else Arnoldi.
    check : bool
        Validate the arguments.

    Returns
    -------
    MeanSquareStability
        ``rho``, ``rho_lower``, ``rho_upper``, ``verdict`` and ``stabilizing``
        (True / False / None).

    Raises
    ------
    ValueError, TypeError
        As :func:`ms_spectral_radius`, and for an unknown ``method``.

    Notes
    -----
    L is positive on the cone of positive semidefinite stacks. For X > 0, L(X) <= beta X implies
    rho <= beta, and L(X) >= alpha X implies rho >= alpha (the Collatz-Wielandt bounds for
    cone-preserving maps; Costa, Fragoso and Marques, Discrete-Time Markov Jump Linear Systems,
    2005, Ch. 3, for the second-moment operator). With the Cholesky factor X_j = C_j C_j^T, alpha
    and beta are the extreme eigenvalues of C_j^{-1} L(X)_j C_j^{-T} over j. The rounding of L(X)
    (``|dL(X)_j| <= gamma sum_i p_ij |A_i| |X_i| |A_i|^T``, Higham 2002, Sec. 3.5), of the Cholesky
    factor and of the symmetric eigenvalues (backward stable, Higham Ch. 10; Weyl's inequality)
    moves alpha and beta by at most, to first order::

        margin_j = g (sum_i p_ij ||A_i||_F^2 ||X_i||_F + ||L(X)_j||_F
                   + max(|alpha_j|, |beta_j|) ||X_j||_F) / lambda_min(X_j),

    with g = 10 (2 n + M) eps and lambda_min(X_j) = 1 / ||C_j^{-1}||_2^2, bounded by
    1 / ||C_j^{-1}||_F^2 (for the pencil reduced by a Cholesky factor, Golub and Van Loan, Matrix
    Computations, 4th ed., Sec. 8.7.2; the spectral norm itself for the few stacks below); the
    bracket is widened by it. Where the estimate comes from dense eigenvalues, the lower end is also
    ``|lambda| - 10 s ||E||`` (the eigenvalue's condition number ``s = 1 / |w^H v|`` and the backward
    error ||E|| <= 10 N eps ||K||_F of the QR algorithm, first order), which is tight where the
    Perron stack is singular. Where the bracket is still wider than ``mjls.bracket_warn_rtol``, the
    left Perron stack P gives a residual lower bound and an upper bound at approximate resolvent
    solutions r Z - L(Z) = I with r just above rho, built around the Perron stack
    (:func:`asoc.mjls.certificate.deflated_resolvent_bounds`): Z > 0 even where the Perron stack is
    singular, as in the augmented closed loop of Alg. 3.2 at n = 32, M = 8, whose bracket from the
    Perron stack alone is wider than ``mjls.bracket_warn_rtol`` and with Z narrower
    (tests/asoc/mjls/test_certified.py). This is a first-order bound with a safety factor of 10,
    not interval arithmetic. The bracket is tight where the Perron stack is positive definite or its
    resolvent candidates are; where neither holds (e.g. defective spectra) the bracket can stay
    wide, and the verdict is then undecided rather than wrong.

    Examples
    --------
    >>> from asoc.mjls.examples import sec32_system
    >>> r = mean_square_stability(sec32_system())
    >>> r.verdict, r.stabilizing, bool(r.rho_lower <= r.rho <= r.rho_upper), bool(r.rho_upper - r.rho_lower < 1e-9)
    (<Verdict.UNSTABLE: 'unstable'>, False, True, True)

    A mode with eigenvalue 1 has rho = 1: undecided, never stable.

    >>> mean_square_stability(np.array([[[1.0]]]), [[1.0]]).stabilizing is None
    True
    """
    if check:
        A_stack, T = mode_stack(A_stack, T)
    return _certified(A_stack, T, method)


def perron_pair(A, T, method="auto"):
    """rho of Cor. 3.2 with right and left Perron stacks: L(X) = rho X and L*(P) = rho P, X, P >= 0.

    On a periodic chain (e.g. T = [[0, 1], [1, 0]]) several eigenvalues share the modulus rho;
    the real positive one and its positive semidefinite eigenvectors are returned (Arnoldi on
    L + rho I, where it is strictly dominant); where ARPACK fails, dense eigenvectors up to
    M n^2 = ``mjls.dense_fallback_radius``, else the shifted cone power method. Arguments are
    not validated (float arrays of consistent shapes, as :func:`spectral_radius`).

    Returns
    -------
    rho : float
        The estimate of :func:`spectral_radius`.
    X, P : numpy.ndarray, shape (M, n, n)
        Symmetric positive semidefinite, each scaled to unit Frobenius norm.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.9]]]); T = np.array([[0.0, 1.0], [1.0, 0.0]])
    >>> rho, X, P = perron_pair(A, T)
    >>> round(rho, 6), X.ravel().round(4), P.ravel().round(4)
    (0.45, array([0.8742, 0.4856]), array([0.4856, 0.8742]))
    """
    _check_method(method)
    Ab, d, s = _balance(A)
    _, _, rho, X, estimate = _certify(Ab, T, method)
    left = _estimate(Ab, T, estimate.method.split("+")[-1], adjoint=True)
    P = left.X if left.method != "power" else _adjoint_power(Ab, T, rho)
    with np.errstate(over="ignore"):
        rho = (rho * s) * s
    X = d[:, None] * X * d[None, :]
    P = P / d[:, None] / d[None, :]
    return float(rho), X / np.linalg.norm(X), P / np.linalg.norm(P)


def _adjoint_power(A, T, rho):
    """The left Perron stack by the shifted power method P <- L*(P) + rho P (where ARPACK failed)."""
    M, n, _ = A.shape
    P = np.broadcast_to(np.eye(n), (M, n, n)).copy()
    with single_threaded():
        for _ in range(config.defaults["mjls.power_max_steps"]):
            P_new = sym(costate_map(A, T, P)) + rho * P
            P_new /= np.abs(P_new).max()
            if np.abs(P_new - P).max() <= 1e-13:
                return P_new
            P = P_new
    return P


def _left_perron(A, T, rho, method):
    """The left Perron stack P (a second eigen-solve, on L*), for the bounds that need it where the
    Perron stack is singular or badly scaled (periodic chains) and the Collatz-Wielandt bounds at X are
    wide: the residual lower bound rho - 10 s ||E|| (:func:`asoc.mjls.certificate.residual_lower_bound`)
    and the deflated resolvent upper bound (:func:`asoc.mjls.certificate.deflated_resolvent_bounds`)."""
    P = _estimate(A, T, "power" if method == "power" else "arnoldi" if method.startswith("arnoldi") else method,
                  adjoint=True)
    return P.X if P.method != "power" else _adjoint_power(A, T, rho)


def _narrow(lower, upper):
    return upper - lower <= config.defaults["mjls.bracket_warn_rtol"] * upper


def _singular_perron_bounds(A, T, estimate, lower, upper, rho, X):
    """(lower, upper) improved by the bounds from the left Perron stack, when the bracket needs them."""
    needs_lower = lower < rho * (1 - np.sqrt(config.defaults["mjls.bracket_rtol"]))
    if estimate.method == "single_mode" or not (needs_lower or not _narrow(lower, upper)):
        return lower, upper
    P = _left_perron(A, T, rho, estimate.method)
    if needs_lower:
        lower = max(lower, residual_lower_bound(A, T, rho, X, P, upper))
    if not _narrow(lower, upper):
        bracket = Bracket(A, T)
        deflated_resolvent_bounds(bracket, rho, X, P)
        upper = min(upper, max(bracket.upper, lower))
    return lower, upper


# ---------------------------------------------------------------- the estimate

def _check_method(method):
    if method not in ("auto", "dense", "arnoldi", "power"):
        raise ValueError(f"method: expected one of 'auto', 'dense', 'arnoldi', 'power', found {method!r}")


@dataclass(frozen=True)
class _Estimate:
    rho: float          # eigen-solver's rho (nan for the power method)
    X: np.ndarray       # positive semidefinite eigenvector estimate (identity for the power method)
    method: str
    lower: float = 0.0  # first-order perturbation lower bound of rho (dense eigenvalues only)


def _balance(A):
    """D^-1 A_i D / s with one diagonal D and scalar s, both powers of 2 (exact): returns (A', d, s)."""
    M, n, _ = A.shape
    d = np.ones(n)
    if n > 1:
        with np.errstate(invalid="ignore"):                        # scipy casts its unused permutation
            d = np.diag(scipy.linalg.matrix_balance(np.abs(A).sum(axis=0), permute=False)[1]).copy()
    Ab = A / d[:, None] * d[None, :]
    top = float(np.abs(Ab).max())
    s = 1.0 if top == 0.0 or not np.isfinite(top) else float(2.0 ** np.round(np.log2(top)))
    return Ab / s, d, s


def _psd_stack(v, M, n):
    """The positive semidefinite stack nearest the real symmetric part of an eigenvector (phase removed)."""
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


def _estimate(A, T, method, adjoint=False):
    """rho and a PSD eigenvector of L (or L*) from the eigen-solver ``method`` (see mean_square_stability;
    also "single_mode" and "arnoldi+dense", the dense fallback without left eigenvectors)."""
    M, n, _ = A.shape
    dim = M * n * n
    if method == "auto":
        method = "single_mode" if M == 1 else "dense" if dim <= config.defaults["mjls.dense_max_radius"] else "arnoldi"
    if method == "single_mode":
        return _single_mode(A[0], adjoint)
    if method == "arnoldi" and dim > 3:
        estimate = next(_arnoldi(A, T, adjoint), None)
        if estimate is not None:
            return estimate
        method = "arnoldi+dense" if dim <= config.defaults["mjls.dense_fallback_radius"] else "power"
    if method == "power":
        return _Estimate(np.nan, np.broadcast_to(np.eye(n), (M, n, n)).copy(), "power")
    K = kronecker_stack(A[None], T)[0]
    K = K.T if adjoint else K
    if method == "dense":
        lam, left, right = scipy.linalg.eig(K, left=True, right=True)
    else:                                               # the fallback, up to M n^2 = 1024: no left vectors
        lam, right = scipy.linalg.eig(K)
    rho = float(np.max(np.abs(lam)))
    top = np.flatnonzero(np.abs(lam) >= rho * (1 - 1e-8))
    k = top[np.argmax(lam[top].real)]                             # the real Perron eigenvalue
    return _Estimate(rho, _psd_stack(right[:, k], M, n), method,
                     _first_order_lower(K, lam, left, right) if method == "dense" else 0.0)


def _single_mode(A, adjoint):
    """M = 1: rho = rho(A)^2 with eigenvector Re(v v^H) for A v = lambda v (A^T for the adjoint)."""
    A = A.T if adjoint else A
    lam, left, right = scipy.linalg.eig(A, left=True, right=True)
    k = np.argmax(np.abs(lam))
    v = right[:, k]
    lower = _first_order_lower(A, lam, left, right)
    return _Estimate(float(abs(lam[k])) ** 2, _psd_stack(np.outer(v, np.conj(v)), 1, len(A)), "single_mode",
                     lower * lower)


def _first_order_lower(K, lam, left, right):
    """max_k |lambda_k| - s_k ||E||: a computed eigenvalue is exact for K + E with ||E|| <= 10 N eps ||K||_F
    (backward stable QR algorithm), and moves by at most s_k ||E|| to first order, s_k = 1 / |w_k^H v_k|
    its condition number (Wilkinson). Useless (0) for defective eigenvalues, where s_k is huge."""
    with np.errstate(divide="ignore"):
        s = 1.0 / np.abs(np.einsum("ik,ik->k", np.conj(left), right))
    error = 10.0 * len(K) * EPS * np.linalg.norm(K)
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
            yield _Estimate(abs(lam), _psd_stack(V[:, 0], M, n), "arnoldi")
        except scipy.sparse.linalg.ArpackError:
            pass
        if ncv >= dim - 1:
            return


# ---------------------------------------------------------------- the certificate

def _estimates(A, T, method):
    """The eigen-solver's estimates in turn: Arnoldi with each Krylov-space size, then its fallback."""
    M, n, _ = A.shape
    if method == "auto" and M > 1 and M * n * n > config.defaults["mjls.dense_max_radius"]:
        method = "arnoldi"
    if method == "arnoldi" and M * n * n > 3:
        yield from _arnoldi(A, T, False)
        method = "arnoldi+dense" if M * n * n <= config.defaults["mjls.dense_fallback_radius"] else "power"
    yield _estimate(A, T, method)


def _certify(A, T, method):
    """:func:`_certify_estimates` with BLAS on one thread: its work is small products and M small
    eigenproblems, where threads only cost (a stack of 8 eigh of 32 x 32: 0.49 s with threads on a
    loaded 2-core machine, 1 ms without)."""
    with single_threaded():
        return _certify_estimates(A, T, method)


def _certify_estimates(A, T, method):
    """(lower, upper, rho, X, estimate) for the balanced (A, T): the first estimate inside a narrow bracket
    (relative width ``mjls.bracket_warn_rtol``), else the narrowest (a subdominant eigenvalue from a small
    Krylov space fails the test: the bracket holds rho, not it)."""
    best = None
    for estimate in _estimates(A, T, method):
        lower, upper, rho, X = refine(A, T, estimate.X, estimate.rho)
        lower, upper = _singular_perron_bounds(A, T, estimate, lower, upper, rho, X)
        rho = float(np.clip(rho, lower, upper))
        if lower < estimate.lower <= upper:
            lower = estimate.lower
        if best is None or upper - lower < best[1] - best[0]:
            best = lower, upper, rho, X, estimate
        if lower <= estimate.rho <= upper and _narrow(lower, upper):
            break
    return best


def _certified(A, T, method):
    """MeanSquareStability of (A, T): balance, estimate, bracket, scale back."""
    _check_method(method)
    Ab, _, s = _balance(A)
    lower, upper, rho, _, estimate = _certify(Ab, T, method)
    with np.errstate(over="ignore"):
        lower, upper, rho = ((value * s) * s for value in (lower, upper, rho))
    if upper < 1:
        verdict = Verdict.STABLE
    elif lower >= 1:
        verdict = Verdict.UNSTABLE
    else:
        verdict = Verdict.UNDECIDED
    return MeanSquareStability(rho=float(rho), rho_lower=float(lower), rho_upper=float(upper), verdict=verdict,
                               method=estimate.method)


