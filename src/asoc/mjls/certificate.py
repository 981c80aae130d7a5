"""The certificate of rho of Cor. 3.2: Collatz-Wielandt bounds of the second-moment operator L
around an eigen-solver's estimate, with a margin for rounding.

L is positive on the cone of positive semidefinite stacks. For X > 0, L(X) <= beta X implies
rho(L) <= beta, and L(X) >= alpha X implies rho(L) >= alpha; with X_j = C_j C_j^T, alpha and beta
are the extreme eigenvalues of C_j^{-1} L(X)_j C_j^{-T} over j. They are evaluated at the
eigen-solver's eigenvector (:mod:`asoc.mjls.spectral_estimate`; made positive semidefinite and
shifted into the interior where needed), at solutions of the resolvent equation r X - L(X) = I
for r just above the estimate (positive definite iff r > rho), and at a few steps of the shifted
cone power method X <- L(X) + rho X, which converges also on periodic chains. Where the Perron
stack is singular (reducible or triangular modes) or badly scaled (periodic chains), the lower
end also comes from first-order eigenvalue perturbation with the left Perron stack, and the upper
end from deflated resolvent stacks. An Arnoldi estimate that is not inside a narrow bracket (a
subdominant eigenvalue) is replaced by the next Krylov space's.

:class:`Bracket` keeps the best bounds found over the stacks it is shown; ``_refine`` shows it
the candidates; :func:`certify` runs the whole certificate on balanced modes.
:func:`asoc.mjls.mean_square_stability` (Notes) gives the margin for rounding. This is the one
explanation of the bounds; the library's other modules point here.
"""

import warnings

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from .. import config
from ..linalg import sym, transpose
from ..threads import single_threaded, stacked_in_parts
from .moment_operator import in_parallel, kronecker_stack, linear_operator, second_moment_map
from .spectral_estimate import estimates, left_perron_stack

__all__ = ["EPS", "TINY", "certified_upper_bound", "Bracket", "deflated_resolvent_bounds",
           "lyapunov_upper_bound", "certify", "narrow"]


EPS = np.finfo(float).eps
#: The smallest normal double: gamma n TINY bounds, with the safety factor 10, the absolute rounding
#: of the (2 n + M) subnormal operations behind an entry of L(X) (each off by at most 2^-1075).
TINY = np.finfo(float).tiny
#: Relative shifts eta (times the largest eigenvalue of X) that move a singular eigenvector
#: estimate into the interior of the cone for the Collatz-Wielandt bounds: the first valid one
#: gives the bounds.
_SHIFTS = (0.0, 1e-12, 1e-9, 1e-6, 1e-3)
#: Relative distances r / rho_hat - 1 of the resolvent equations tried, largest first (while they
#: improve the upper bound): near a defective eigenvalue only the larger ones give a
#: well-conditioned X.
_RESOLVENT_GAPS = (1.0, 0.3, 0.1, 1e-2, 1e-3, 1e-6, 1e-9, 1e-12)
#: Relative gaps r / rho - 1 of :func:`deflated_resolvent_bounds`, largest first.
_DEFLATED_GAPS = (1e-3, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7)


def certified_upper_bound(A, T, X):
    """The Collatz-Wielandt upper bound of rho (Cor. 3.2) at a stack X > 0, rounding included.

    max_j lambda_max(X_j^{-1/2} L(X)_j X_j^{-1/2}) widened as in
    :func:`asoc.mjls.mean_square_stability`; inf when X is not positive definite. For the solution
    of X = L(X) + W with W > 0 it is below 1 iff the closed loop is mean-square stable (Thm. 3.1).
    Arguments are not validated.

    Examples
    --------
    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> X = np.array([[[4 / 3]]])
    >>> round(certified_upper_bound(A, T, X), 9), certified_upper_bound(A, T, -X)
    (0.25, inf)
    """
    bracket = Bracket(A, T)
    bracket.bounds(sym(X), sym(second_moment_map(A, T, sym(X))))
    return bracket.upper


class Bracket:
    """The best Collatz-Wielandt bounds found so far for (A, T).

    Examples
    --------
    A scalar mode with a = 0.5 and no switching has L(X) = 0.25 X, so rho(L) = 0.25 and one
    positive X already gives both bounds:

    >>> A = np.array([[[0.5]]]); T = np.array([[1.0]])
    >>> bracket = Bracket(A, T)
    >>> bracket.lower, bracket.upper
    (0.0, inf)
    >>> X = np.ones((1, 1, 1))
    >>> bracket.bounds(X, second_moment_map(A, T, X))
    >>> round(bracket.lower, 9), round(bracket.upper, 9), bracket.width_reached(1e-9)
    (0.25, 0.25, True)
    """

    def __init__(self, A, T):
        M, n, _ = A.shape
        self.A, self.T = A, T
        self.lower, self.upper, self.margin = 0.0, np.inf, 0.0
        self.gamma = 10.0 * (2 * n + M) * EPS
        self.underflow = n * TINY                   # absolute rounding of subnormal partial results
        self.norm_A2 = np.einsum("iab,iab->i", A, A)
        self.identity = np.broadcast_to(np.eye(n), (M, n, n))
        self.L_identity = None

    def width_reached(self, rtol):
        """The bracket is as narrow as asked, or as rounding allows (margin <= sqrt(rtol) rho)."""
        return bool(np.isfinite(self.upper)
                    and self.upper - self.lower <= rtol * self.upper + 4.0 * self.margin
                    and self.margin <= np.sqrt(rtol) * self.upper)

    def consider(self, X, rtol):
        """Bounds at X (PSD), shifted into the interior as needed; returns L(X)."""
        Y = sym(second_moment_map(self.A, self.T, X))
        top = float(np.abs(X).max())
        for eta in _SHIFTS:
            if eta > 0 and self.L_identity is None:
                self.L_identity = sym(second_moment_map(self.A, self.T, self.identity))
            if eta == 0:
                self.bounds(X, Y)
            else:
                self.bounds(X + eta * top * self.identity, Y + eta * top * self.L_identity)
            if self.width_reached(rtol):
                break
        return Y

    def merge(self, other):
        """Keep the better of each bound of this bracket and ``other``."""
        if other.upper < self.upper:
            self.upper, self.margin = other.upper, other.margin
        self.lower = max(self.lower, other.lower)

    def bounds(self, X, Y, sharp=False):
        """Update the bracket with the bounds at X > 0 and Y = L(X) (none where X is not definite).

        The rounding margin scales with ||C_j^-1||^2 = 1 / lambda_min(X_j): bounded by the Frobenius
        norm (cheap), or with ``sharp`` computed as the spectral norm (M singular value
        decompositions; up to n times smaller where X_j has one small eigenvalue and many large
        ones).
        """
        try:
            extremes = lambda X, Y: _generalized_extremes(X, Y, sharp)
            alpha, beta, inv_norm2 = (stacked_in_parts(extremes, X, Y) if in_parallel(X)
                                      else extremes(X, Y))
        except np.linalg.LinAlgError:
            return
        if not (np.all(np.isfinite(alpha)) and np.all(np.isfinite(beta))):
            return
        norm_X = np.sqrt(np.einsum("iab,iab->i", X, X))
        rounding = (self.T.T @ (self.norm_A2 * norm_X) + np.sqrt(np.einsum("iab,iab->i", Y, Y))
                    + self.underflow)
        margin = self.gamma * (rounding + np.maximum(abs(alpha), abs(beta)) * norm_X) * inv_norm2
        lower, upper = float(np.max([0.0, (alpha - margin).min()])), float((beta + margin).max())
        if upper < self.upper:
            self.upper, self.margin = upper, float(margin.max())
        if lower > self.lower:
            self.lower = lower


def _generalized_extremes(X, Y, sharp):
    """The smallest and largest eigenvalues alpha_i, beta_i of C_i^-1 Y_i C_i^-T (X_i = C_i C_i^T,
    Cholesky; LinAlgError where an X_i is not definite) and ||C_i^-1||^2 (Frobenius, or with
    ``sharp`` spectral), for :meth:`Bracket.bounds`.
    """
    C = np.linalg.cholesky(X)
    with np.errstate(all="ignore"):
        Ci = np.linalg.inv(C)
        lam = np.linalg.eigvalsh(sym(Ci @ Y @ transpose(Ci)))
    inv_norm2 = (np.linalg.norm(Ci, 2, axis=(1, 2)) ** 2 if sharp
                 else np.einsum("iab,iab->i", Ci, Ci))
    return lam[:, 0], lam[:, -1], inv_norm2


def _refine(A, T, X0, rho):
    """(lower, upper, rho, X): Collatz-Wielandt bounds at the eigenvector estimate X0 of rho (nan:
    none, the power method alone), at resolvent solutions (small sizes) and along the shifted cone
    power method; X the last iterate. Call it with BLAS on one thread
    (``asoc.threads.single_threaded``): its work is small products and M small eigenproblems.

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> [round(v, 9) for v in _refine(A, T, np.ones((2, 1, 1)), np.nan)[:3]]
    [0.845, 0.845, 0.845]
    """
    M, n, _ = A.shape
    rtol = config.defaults["mjls.bracket_rtol"]
    bracket = Bracket(A, T)
    Y = bracket.consider(X0, rtol)
    if not np.isfinite(rho):
        X, rho = _power_method(bracket, X0, Y, rtol)
    else:
        small = M * n * n <= config.defaults["mjls.dense_fallback_radius"]
        if not bracket.width_reached(rtol) and small:
            _resolvent_bounds(bracket, rho, rtol)
        X = _power_steps(bracket, X0, Y, rho, rtol)
    return bracket.lower, bracket.upper, float(np.clip(rho, bracket.lower, bracket.upper)), X


def _resolvent_bounds(bracket, rho, rtol):
    """Bounds at solutions of r X - L(X) = I, r from 2 rho down towards rho, while they improve."""
    previous = np.inf
    radii = [max(rho, 1e-300) * (1 + gap) for gap in _RESOLVENT_GAPS]
    for _, X_r in _resolvent_stacks(bracket.A, bracket.T, radii):
        own = Bracket(bracket.A, bracket.T)
        own.consider(X_r, rtol)
        bracket.merge(own)
        if not own.upper < previous:                        # X_r too ill-conditioned from here on
            return
        previous = own.upper


def _power_steps(bracket, X, Y, rho, rtol):
    """Up to ``mjls.bracket_power_steps`` steps X <- L(X) + rho X, while each narrows it by 10 %."""
    width = np.inf
    for _ in range(config.defaults["mjls.bracket_power_steps"]):
        if bracket.width_reached(rtol):
            break
        X = Y + rho * X
        top = np.abs(X).max()
        if not top > 0:                             # L(X) = 0 (nilpotent modes): nothing to scale
            break
        X /= top
        Y = bracket.consider(X, rtol)
        if not bracket.upper - bracket.lower < config.defaults["mjls.bracket_power_shrink"] * width:
            break
        width = bracket.upper - bracket.lower
    return X


def _power_method(bracket, X, Y, rtol):
    """The shifted cone power method alone: X <- L(X) + r X with r = tr L(X) / tr X, its estimate of
    rho, until the bracket is narrow, or X has converged (to ``mjls.power_tol``, e.g. to a singular
    Perron stack, where the bracket stays wide), or L(X) = 0, or ``mjls.power_max_steps``.
    """
    rho = np.inf
    for _ in range(config.defaults["mjls.power_max_steps"]):
        rho = float(np.trace(Y, axis1=1, axis2=2).sum() / np.trace(X, axis1=1, axis2=2).sum())
        if bracket.width_reached(rtol):
            break
        X, previous = Y + rho * X, X
        top = np.abs(X).max()
        if not top > 0:
            return previous, rho
        X /= top
        if np.abs(X - previous).max() <= config.defaults["mjls.power_tol"]:
            break
        Y = bracket.consider(X, rtol)
    return X, rho


def deflated_resolvent_bounds(bracket, rho, X, P):
    """Upper bounds at solutions Z of r Z - L(Z) = I, r just above rho, without a dense solve.

    With the Perron pair (rho, X) and the left Perron stack P, Z = c X + Z_c with
    c = <P, I> / ((r - rho) <P, X>) in closed form, and Z_c the solution of rho Z_c - L(Z_c) = B on
    B = I - (<P, I> / <P, X>) X, which has no Perron component: the iteration Z_c <- (B + L(Z_c)) /
    rho contracts at ``|lambda_2| / rho``. Z > 0 even where X is singular (a Perron stack that does
    not reach every direction, e.g. an unexcited controller block), where the Collatz-Wielandt
    bounds at X, or at X shifted by a multiple of I, stay wide. Z is only a candidate: its bounds
    are computed from L(Z) with the (sharp) rounding margin, so an inexact Z_c costs tightness,
    never validity. The gaps r / rho - 1 go down while the upper bound improves (the margin grows
    like 1 / (r - rho)). Nothing is done for rho = 0 (nilpotent modes: the lower end 0 is exact, and
    no gap is relative to it). Arguments are not validated (the caller,
    :func:`asoc.mjls.mean_square_stability`, has).

    Examples
    --------
    A mode whose Perron stack is singular (the second state is never excited):

    >>> A = np.array([[[0.9, 1.0], [0.0, 0.3]]]); T = np.array([[1.0]])
    >>> X = np.array([[[1.0, 0.0], [0.0, 0.0]]])
    >>> bracket = Bracket(A, T)
    >>> deflated_resolvent_bounds(bracket, 0.81, X, X)
    >>> bool(0.81 <= bracket.upper < 0.81 * (1 + 1e-5))
    True
    """
    inner = float(np.einsum("iab,iab->", P, X))
    if not (rho > 0 and inner > 0):
        return
    weight = float(np.einsum("iab,iab->", P, bracket.identity)) / inner
    B = bracket.identity - weight * X
    Z_c = B / rho
    for _ in range(config.defaults["mjls.deflated_resolvent_steps"]):
        Z_next = (B + second_moment_map(bracket.A, bracket.T, Z_c)) / rho
        change = np.abs(Z_next - Z_c).max()
        converged = change <= config.defaults["mjls.power_tol"] * np.abs(Z_next).max()
        Z_c = Z_next
        if converged:
            break
    previous = np.inf
    for gap in _DEFLATED_GAPS:
        Z = sym(weight / (rho * gap) * X + Z_c)
        own = Bracket(bracket.A, bracket.T)
        own.bounds(Z, sym(second_moment_map(bracket.A, bracket.T, Z)), sharp=True)
        bracket.merge(own)
        # past the best gap: the margin dominates
        if not own.upper < previous:
            return
        previous = own.upper


def _residual_lower_bound(A, T, rho, X, P, upper):
    """Rho - 10 s ||E|| for an eigen-pair (rho, X) of Cor. 3.2's operator and its left Perron P.

    The pair is exact for L + E with ||E|| = ||L(X) - rho X|| / ||X|| (plus the rounding of that
    residual, bounded as in the Collatz-Wielandt margin), and rho moves by at most s ||E|| to first
    order, s = ||X|| ||P|| / <P, X> (Wilkinson). Tight where the Perron stack is singular or badly
    scaled (periodic chains), where the Collatz-Wielandt lower bound is not. 0 when the bound is not
    in (0, upper].

    Examples
    --------
    >>> A = np.array([[[0.9, 0.0], [0.0, 0.5]]]); T = np.array([[1.0]])
    >>> X = np.array([[[1.0, 0.0], [0.0, 0.0]]])
    >>> bool(0.81 - 1e-12 < _residual_lower_bound(A, T, 0.81, X, X, 1.0) <= 0.81)
    True
    """
    M, n, _ = A.shape
    norm_X = np.sqrt(np.einsum("iab,iab->i", X, X))
    rounding = 10.0 * (2 * n + M) * EPS * (T.T @ (np.einsum("iab,iab->i", A, A) * norm_X)
                                           + rho * norm_X + n * TINY)
    residual = np.linalg.norm(second_moment_map(A, T, X) - rho * X)
    # with its own rounding
    error = (residual + np.linalg.norm(rounding)) / np.linalg.norm(X)
    inner = float(np.einsum("iab,iab->", P, X))
    if not inner > 0:
        return 0.0
    bound = rho - 10.0 * np.linalg.norm(X) * np.linalg.norm(P) / inner * error
    return float(bound) if 0 < bound <= upper else 0.0


def _resolvent_stacks(A, T, radii):
    """(r, X) with X the solution of r X - L(X) = I, for each r: X > 0 iff r > rho(L), and then
    L(X) < r X. Dense up to M n^2 = ``mjls.dense_fallback_radius`` (one mode: the Lyapunov solver),
    a sparse LU for scalar modes, else restarted GMRES on the matrix-free operator (an approximate
    X only costs tightness: its bounds are computed from L(X)).
    """
    M, n, _ = A.shape
    dim = M * n * n
    eye = np.broadcast_to(np.eye(n), (M, n, n))
    dense = M > 1 and dim <= config.defaults["mjls.dense_fallback_radius"]
    K = kronecker_stack(A[None], T)[0] if dense else None
    for r in radii:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if M == 1:
                    X = scipy.linalg.solve_discrete_lyapunov(A[0] / np.sqrt(r), np.eye(n) / r)[None]
                elif dense:
                    X = scipy.linalg.solve(r * np.eye(dim) - K, eye.ravel()).reshape(M, n, n)
                elif n == 1:                        # scalar modes: L is a sparse M x M matrix
                    K_r = scipy.sparse.identity(M, format="csc") * r - scipy.sparse.csc_matrix(
                        (T * A[:, 0, 0, None] ** 2).T)
                    X = scipy.sparse.linalg.splu(K_r).solve(np.ones(M)).reshape(M, 1, 1)
                else:
                    restarts = config.defaults["mjls.lyapunov_certificate_restarts"]
                    x, _ = scipy.sparse.linalg.gmres(
                        linear_operator(A, T, identity=r), eye.ravel(), restart=60,
                        maxiter=restarts, rtol=config.defaults["mjls.solve_tolerance"])
                    X = x.reshape(M, n, n)
            except (np.linalg.LinAlgError, ValueError, RuntimeError):   # r is an eigenvalue of L
                continue
        if np.all(np.isfinite(X)):
            yield r, sym(X)


def lyapunov_upper_bound(A, T, rho, unit=1.0):
    """An upper bound of rho from X_r = (r I - L)^-1 (I) for r = rho + f (unit - rho), f from
    ``mjls.lyapunov_certificate_radii``: f = 1 is the Lyapunov certificate X = L(X) + I of Thm. 3.1
    (at unit = 1). If X_r > 0 and r X_r - L(X_r) >= delta I with delta > 0, then
    L(X_r)_j <= (r - delta / lambda_max(X_r,j)) X_r,j: rho <= r - min_j delta / lambda_max(X_r,j).
    The residual r X - L(X) is formed in extended precision (``numpy.longdouble``) with its rounding
    bounded as in :func:`asoc.mjls.mean_square_stability` (first order, safety factor 10, with the
    longdouble's own epsilon: where that is double, the bound is as strict as double allows). Far
    from rho, X_r is well conditioned even where rho's eigenvalue is defective, where the
    Collatz-Wielandt bounds near rho are not; inf where no X_r passes.

    Examples
    --------
    A Jordan block at 0.5 (rho = 0.25) with off-diagonal 100, in a dense basis (1e3 needs the
    extended precision, where numpy.longdouble has it):

    >>> S = np.array([[2.0, 1.0], [1.0, 1.0]]); S_inv = np.array([[1.0, -1.0], [-1.0, 2.0]])
    >>> A = (S @ np.array([[0.5, 100.0], [0.0, 0.5]]) @ S_inv)[None]
    >>> bool(0.25 <= lyapunov_upper_bound(A, np.eye(1), 0.25) < 1)
    True
    """
    radii = [rho + f * (unit - rho) for f in config.defaults["mjls.lyapunov_certificate_radii"]]
    bounds = [_residual_upper_bound(A, T, X, r) for r, X in _resolvent_stacks(A, T, radii)]
    return min(bounds, default=np.inf)


def _residual_upper_bound(A, T, X, r):
    """R - min_j delta_j / lambda_max(X_j) where r X - L(X) >= delta I is proven (inf where not)."""
    M, n, _ = A.shape
    lam_X = np.linalg.eigvalsh(X)
    if not np.all(lam_X[:, 0] > 10.0 * n * EPS * lam_X[:, -1]):
        return np.inf
    wide = np.longdouble
    A_l, X_l = A.astype(wide), X.astype(wide)
    Y = A_l @ X_l @ transpose(A_l)
    R = r * X_l - (T.T.astype(wide) @ Y.reshape(M, -1)).reshape(M, n, n)
    norm_X = np.sqrt(np.einsum("iab,iab->i", X, X))
    rounding = 10.0 * (2 * n + M) * float(np.finfo(wide).eps) * (
        T.T @ (np.einsum("iab,iab->i", A, A) * norm_X) + r * norm_X + n * TINY)
    R = R.astype(float)
    eig_rounding = 10.0 * n * EPS * np.sqrt(np.einsum("iab,iab->i", R, R))
    delta = np.linalg.eigvalsh(sym(R))[:, 0] - rounding - eig_rounding
    if not np.all(delta > 0):
        return np.inf
    return float(np.max(r - delta / lam_X[:, -1]) * (1 + 4 * EPS))


def certify(A, T, method, unit=1.0, start=None):
    """(lower, upper, rho, X, estimate) of the balanced (A, T) (``start``: a stack near the Perron
    stack, :func:`asoc.mjls.spectral_estimate.power_estimate`): ``_certify_estimates`` with BLAS on
    one thread: its work is small products and M small eigenproblems, where threads only cost (a
    stack of 8 eigh of 32 x 32: 0.49 s with threads on a loaded 2-core machine, 1 ms without).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[1.2]]]); T = np.array([[0.5, 0.5], [0.5, 0.5]])
    >>> lower, upper, rho, X, estimate = certify(A, T, "auto")
    >>> bool(lower <= 0.845 <= upper), estimate.method
    (True, 'dense')
    """
    with single_threaded():
        return _certify_estimates(A, T, method, unit, start)


def _certify_estimates(A, T, method, unit, start=None):
    """(lower, upper, rho, X, estimate) for the balanced (A, T): the first estimate inside a narrow
    bracket (relative width ``mjls.bracket_warn_rtol``), else the narrowest (a subdominant
    eigenvalue from a small Krylov space fails the test: the bracket holds rho, not it); the
    estimates start from ``start`` where given (:func:`asoc.mjls.spectral_estimate.estimates`).
    """
    best = None
    for estimate in estimates(A, T, method, start):
        lower, upper, rho, X = _refine(A, T, estimate.X, estimate.rho)
        lower, upper = _singular_perron_bounds(A, T, estimate, lower, upper, rho, X)
        rho = float(np.clip(rho, lower, upper))
        if lower < estimate.lower <= upper:
            lower = estimate.lower
        if lower < unit <= upper and rho < unit:        # the verdict is open: Lyapunov certificate
            upper = max(lower, min(upper, lyapunov_upper_bound(A, T, rho, unit)))
            rho = min(rho, upper)
        if best is None or upper - lower < best[1] - best[0]:
            best = lower, upper, rho, X, estimate
        if lower <= estimate.rho <= upper and narrow(lower, upper):
            break
    return best


def narrow(lower, upper):
    """Whether [lower, upper] is narrow: relative width ``mjls.bracket_warn_rtol`` at most.

    Examples
    --------
    >>> narrow(0.98999, 0.99), narrow(0.9, 0.99)
    (True, False)
    """
    return upper - lower <= config.defaults["mjls.bracket_warn_rtol"] * upper


def _singular_perron_bounds(A, T, estimate, lower, upper, rho, X):
    """(lower, upper) improved by the left Perron stack's bounds where the bracket needs them."""
    needs_lower = lower < rho * (1 - np.sqrt(config.defaults["mjls.bracket_rtol"]))
    if estimate.method == "single_mode" or not (needs_lower or not narrow(lower, upper)):
        return lower, upper
    P = left_perron_stack(A, T, rho, estimate.method)
    if needs_lower:
        lower = max(lower, _residual_lower_bound(A, T, rho, X, P, upper))
    if not narrow(lower, upper):
        bracket = Bracket(A, T)
        deflated_resolvent_bounds(bracket, rho, X, P)
        upper = min(upper, max(bracket.upper, lower))
    return lower, upper
