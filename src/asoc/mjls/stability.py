"""Mean-square stability (Sec. 3.3, Cor. 3.2): the spectral radius rho of the second-moment
operator L with a certified bracket, the stability verdict and the Perron pair of L.

An eigen-solver estimates rho (:mod:`asoc.mjls.spectral_estimate`); the Collatz-Wielandt bounds
around it certify a bracket (:mod:`asoc.mjls.certificate`, which explains them); the verdict
follows the bracket: stable iff its upper end is below 1, unstable iff its lower end is at least 1,
undecided otherwise. Calls run one way: stability -> certificate -> spectral_estimate.

Before any eigen-solve the modes are balanced (:func:`asoc.mjls.spectral_estimate.balance`):
A_i -> D^-1 A_i D with one diagonal D (powers of 2, from ``scipy.linalg.matrix_balance`` of
sum_i |A_i|) and scaled by a power of 2; where the modes' scales differ by more than
2^``mjls.mode_scale_spread``, each mode by its own power of 2 with a similarity of the stack
X_i -> 2^{t_i} X_i that rescales p_ij by 2^{t_i - t_j}. Every factor is a power of 2, so this is
exact in floating point unless an entry under- or overflows; that is checked, and where it
happens the bracket is [0, inf] (not certified), never the bracket of another operator. The
bracket is scaled back outwards where it becomes subnormal.
"""

import enum
import warnings
from dataclasses import dataclass

import numpy as np

from .. import config
from ..threads import single_threaded
from ..validation import real_array
from .certificate import Bracket, certify, narrow
from .closed_loops import controller_closed_loop, is_controller
from .controllers import Controller
from .moment_operator import mode_stack
from .spectral_estimate import balance, check_method, estimate, left_perron_stack
from .system import MJLS

__all__ = ["Verdict", "MeanSquareStability", "ms_spectral_radius", "mean_square_stability",
           "perron_pair"]


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
        How the estimate was obtained: "single_mode", "noda" (many scalar modes), "dense",
        "arnoldi", "arnoldi+dense" or "power".

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
        verdicts = {Verdict.STABLE: True, Verdict.UNSTABLE: False, Verdict.UNDECIDED: None}
        return verdicts[self.verdict]

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


@config.accepts_settings("mjls.bracket_rtol", "mjls.dense_max_radius")
def ms_spectral_radius(A_stack, T=None, *, method="auto", check=True) -> float:
    """Spectral radius rho of the second-moment operator (Cor. 3.2): mean-square stable iff rho < 1.

    Parameters
    ----------
    A_stack : MJLS, array_like of shape (M, n, n), or design result
        As :func:`mean_square_stability`: an MJLS (open loop, or closed by the controller
        ``T``), per-mode (closed-loop) matrices, or a design result (its certified rho).
    T : array_like of shape (M, M), Controller or design result, optional
        Row-stochastic transition matrix with a stack; with an MJLS, None or the controller
        that closes its loop.
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
    result = mean_square_stability(A_stack, T, method=method, check=check)
    width = result.rho_upper - result.rho_lower
    if not width <= config.defaults["mjls.bracket_warn_rtol"] * result.rho_upper:
        warnings.warn(f"the spectral radius {result.rho:.6g} is only known to lie in "
                      f"[{result.rho_lower:.6g}, {result.rho_upper:.6g}] (e.g. a defective or "
                      "nearly reducible spectrum)", RuntimeWarning, stacklevel=2)
    return result.rho


@config.accepts_settings("mjls.bracket_rtol", "mjls.dense_max_radius")
def mean_square_stability(A_stack, T=None, *, method="auto", check=True, start=None):
    """Cor. 3.2 as a certified verdict: rho, its bracket, and stable, unstable or undecided.

    Parameters
    ----------
    A_stack : MJLS, array_like of shape (M, n, n), or design result
        An MJLS: its open loop, or its loop closed by the controller passed as ``T``.
        Per-mode (closed-loop) matrices, e.g. the augmented closed loop of a dynamic controller
        (:func:`asoc.mjls.augmented_closed_loop`), with their ``T``. A design result alone
        (e.g. of :func:`asoc.mjls.static_output_feedback`): the certificate of its closed loop
        that the design computed, ``result.stability`` (``method`` does not apply; pass
        ``(sys, result)`` to compute it again).
    T : array_like of shape (M, M), Controller or design result, optional
        With a stack, its row-stochastic transition matrix. With an MJLS, None (open loop) or
        a time-invariant controller (:class:`asoc.mjls.StaticGain`,
        :class:`asoc.mjls.ModeDependentGain`, :class:`asoc.mjls.DynamicOutputFeedback`) or a
        design result whose closed loop (:func:`asoc.mjls.closed_loops.controller_closed_loop`)
        is certified.
    method : {"auto", "dense", "arnoldi", "power"}
        The estimate: ``"dense"``, the eigenvalues of :func:`asoc.mjls.ms_operator`;
        ``"arnoldi"``, ARPACK on the matrix-free operator (Krylov spaces of
        ``config.defaults["mjls.arnoldi_subspaces"]`` vectors in turn; when none converges,
        dense up to M n^2 = ``mjls.dense_fallback_radius``, else ``"power"``); ``"power"``: the
        shifted cone power method alone. ``"auto"``: p_11 rho(A)^2 for one mode, Noda's
        iteration on the sparse M x M matrix of L for scalar modes from M =
        ``mjls.scalar_sparse_from``, dense up to M n^2 = ``mjls.dense_max_radius``, else Arnoldi.
    check : bool
        Validate the arguments.
    start : array_like of shape (M, n, n), optional
        A positive semidefinite stack near the Perron stack, e.g. the stationary second moments
        of this or a nearby closed loop (their Perron component dominates when rho is near 1 and
        the other eigenvalues are not): where the estimate is Arnoldi's, the power method from it
        is tried first (:func:`asoc.mjls.spectral_estimate.power_estimate`). Only the speed
        depends on it; the bracket is certified either way.

    Returns
    -------
    MeanSquareStability
        ``rho``, ``rho_lower``, ``rho_upper``, ``verdict`` and ``stabilizing``
        (True / False / None).

    Raises
    ------
    ValueError, TypeError
        As :func:`ms_spectral_radius`, and for an unknown ``method``; a TypeError for a
        controller without its system, or a time-variant one; a ValueError for a design result
        without a gain (nothing to certify).

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
    ``|lambda| - 10 s ||E||`` (the eigenvalue's condition number ``s = 1 / |w^H v|`` and the
    backward error ||E|| <= 10 N eps ||K||_F of the QR algorithm, first order), which is tight where
    the Perron stack is singular. Where the bracket is still wider than ``mjls.bracket_warn_rtol``,
    the left Perron stack P gives a residual lower bound and an upper bound at approximate resolvent
    solutions r Z - L(Z) = I with r just above rho, built around the Perron stack
    (:func:`asoc.mjls.certificate.deflated_resolvent_bounds`): Z > 0 even where the Perron stack is
    singular, as in the augmented closed loop of Alg. 3.2 at n = 32, M = 8, whose bracket from the
    Perron stack alone is wider than ``mjls.bracket_warn_rtol`` and with Z narrower
    (tests/asoc/mjls/test_certified.py). This is a first-order bound with a safety factor of 10, not
    interval arithmetic. The bracket is tight where the Perron stack is positive definite or its
    resolvent candidates are; where neither holds (e.g. defective spectra) the bracket can stay
    wide. Where it then straddles 1 with an estimate below 1, the Lyapunov certificate decides a
    margin: X_r = (r I - L)^-1 (I) for r between the estimate and 1 (r = 1: X = L(X) + I, Thm. 3.1),
    with r X_r - L(X_r) >= delta I proven from a residual in extended precision
    (:func:`asoc.mjls.certificate.lyapunov_upper_bound`); otherwise the verdict is undecided rather
    than wrong. A subnormal partial result adds an absolute rounding of n 2^-1022 to the rounding
    term, and the modes are balanced exactly before any of this (module docstring). T is used as
    given (rows summing to 1 within the validation's tolerance, not renormalised): for one mode,
    rho = p_11 rho(A)^2.

    Examples
    --------
    >>> from asoc.mjls.examples import sec32_system
    >>> r = mean_square_stability(sec32_system())
    >>> inside, narrow = r.rho_lower <= r.rho <= r.rho_upper, r.rho_upper - r.rho_lower < 1e-9
    >>> r.verdict, r.stabilizing, bool(inside), bool(narrow)
    (<Verdict.UNSTABLE: 'unstable'>, False, True, True)

    A mode with eigenvalue 1 has rho = 1: undecided, never stable.

    >>> mean_square_stability(np.array([[[1.0]]]), [[1.0]]).stabilizing is None
    True

    A design's closed loop, from the system and the result (or its controller), or from the
    result alone:

    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> res = static_output_feedback(sys)
    >>> mean_square_stability(sys, res).sentence()
    'rho = 0.8178, certified in [0.81776, 0.81776]: stable'
    >>> mean_square_stability(res) == res.stability == mean_square_stability(sys, res.controller)
    True
    >>> mean_square_stability(res.controller)
    Traceback (most recent call last):
    ...
    TypeError: A_stack: a controller's closed loop needs its system: \
mean_square_stability(sys, controller)
    """
    loop = _loop(A_stack, T)
    if isinstance(loop, MeanSquareStability):
        return loop
    A_stack, T = loop
    if check:
        A_stack, T = mode_stack(A_stack, T)
        if start is not None:
            start = real_array(start, "start", shape=A_stack.shape)
    return _certified(A_stack, T, method, start)


def _loop(A_stack, T):
    """(A_stack, T) as given, the closed loop of (sys, controller), or the certificate a design
    result holds.
    """
    if isinstance(A_stack, MJLS) and is_controller(T):
        return controller_closed_loop(A_stack, T, "T")[0], A_stack.T
    if not is_controller(A_stack):
        return A_stack, T
    if T is not None:
        raise TypeError(f"A_stack: expected an MJLS or a stack of matrices, found "
                        f"{type(A_stack).__name__}; a controller or a design result comes second: "
                        f"mean_square_stability(sys, controller)")
    if isinstance(A_stack, Controller) or not hasattr(A_stack, "stability"):
        alone = isinstance(A_stack, Controller)
        what = ("a controller's closed loop needs its system" if alone else
                f"a finite-horizon design ({type(A_stack).__name__}) has a time-variant controller")
        raise TypeError(f"A_stack: {what}: mean_square_stability(sys, controller)")
    if A_stack.stability is None:
        raise ValueError(f"A_stack: the design returned no gain to certify ({A_stack.status}: "
                         f"{A_stack.message})")
    return A_stack.stability


def perron_pair(A, T, method="auto"):
    """Rho of Cor. 3.2 with right and left Perron stacks: L(X) = rho X and L*(P) = rho P, X, P >= 0.

    On a periodic chain (e.g. T = [[0, 1], [1, 0]]) several eigenvalues share the modulus rho;
    the real positive one and its positive semidefinite eigenvectors are returned (Arnoldi on
    L + rho I, where it is strictly dominant); where ARPACK fails, dense eigenvectors up to
    M n^2 = ``mjls.dense_fallback_radius``, else the shifted cone power method. Arguments are
    not validated (float arrays of consistent shapes).

    Returns
    -------
    rho : float
        The estimate of :func:`mean_square_stability`.
    X, P : numpy.ndarray, shape (M, n, n)
        Symmetric positive semidefinite, each scaled to unit Frobenius norm.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[0.9]]]); T = np.array([[0.0, 1.0], [1.0, 0.0]])
    >>> rho, X, P = perron_pair(A, T)
    >>> round(rho, 6), X.ravel().round(4), P.ravel().round(4)
    (0.45, array([0.8742, 0.4856]), array([0.4856, 0.8742]))
    """
    check_method(method)
    balanced = balance(A, T)
    with single_threaded():
        rho, X, solver = _checked_estimate(balanced.A, balanced.W, method)
        P = left_perron_stack(balanced.A, balanced.W, rho, solver)
    with np.errstate(over="ignore"):
        rho = np.ldexp(rho, balanced.g)
    X, P = balanced.to_stack(X), balanced.to_stack(P, adjoint=True)
    return float(rho), X / np.linalg.norm(X), P / np.linalg.norm(P)


def _checked_estimate(A, T, method):
    """(rho, X, solver) of the balanced (A, T): the eigen-solver's estimate where the
    Collatz-Wielandt bounds at its X hold it in a narrow bracket (``mjls.bracket_warn_rtol``),
    else the dense eigenvectors up to M n^2 = ``mjls.dense_fallback_radius`` (near a multiple
    Perron eigenvalue, e.g. at a minimum of rho over gains, X is ill-conditioned and its bounds
    wide), else the certificate's (which tries more Krylov sizes and refines X).
    """
    found = estimate(A, T, method)
    bracket = Bracket(A, T)
    bracket.consider(found.X, config.defaults["mjls.bracket_rtol"])
    if bracket.lower <= found.rho <= bracket.upper and narrow(bracket.lower, bracket.upper):
        return found.rho, found.X, found.method
    M, n, _ = A.shape
    if found.method != "dense" and M * n * n <= config.defaults["mjls.dense_fallback_radius"]:
        found = estimate(A, T, "dense")
        return found.rho, found.X, found.method
    _, _, rho, X, found = certify(A, T, method)
    return rho, X, found.method


def _certified(A, T, method, start=None):
    """MeanSquareStability of (A, T): balance, estimate (from ``start``, where given), bracket,
    scale back.

    Where balancing cannot hold (A, T) exactly (an entry under- or overflows), the estimate is
    returned with the bracket [0, inf]: not certified, never a bound of another operator.
    """
    check_method(method)
    balanced = balance(A, T)
    with np.errstate(over="ignore"):                # 2^g beyond the doubles: inf is right
        unit = float(np.ldexp(1.0, -balanced.g))
        lower, upper, rho, _, estimate = certify(
            balanced.A, balanced.W, method, unit=unit,
            start=None if start is None else balanced.from_stack(start))
        if not balanced.exact:
            lower, upper = 0.0, np.inf
        lower, upper = _scaled(lower, balanced.g, -np.inf), _scaled(upper, balanced.g, np.inf)
        rho = float(np.clip(np.ldexp(rho, balanced.g), lower, upper))
    if upper < 1:
        verdict = Verdict.STABLE
    elif lower >= 1:
        verdict = Verdict.UNSTABLE
    else:
        verdict = Verdict.UNDECIDED
    return MeanSquareStability(rho=rho, rho_lower=lower, rho_upper=upper, verdict=verdict,
                               method=estimate.method)


def _scaled(value, g, direction):
    """2^g value, rounded outwards (towards ``direction``) where it leaves the normal range:
    ldexp is exact except for subnormal results, whose rounding must not cut the bracket.
    """
    result = float(np.ldexp(value, g))
    if result < np.finfo(float).tiny and value != 0:
        result = max(0.0, float(np.nextafter(result, direction)))
    return result
