"""Baseline [38]: optimal state feedback with observed mode (coupled algebraic Riccati equations).

O. L. V. Costa, M. D. Fragoso, R. P. Marques, *Discrete-Time Markov Jump Linear Systems*,
Springer 2005, Ch. 4 (control CARE, eq. (4.12)-(4.14)) and Sec. 4.4 (the H2/LQ problem
with noise): the mode-dependent gains

    F_i = -(R_i + B_i^T E_i(X) B_i)^{-1} B_i^T E_i(X) A_i,
    X_i = A_i^T E_i(X) A_i + Q_i - A_i^T E_i(X) B_i (R_i + B_i^T E_i(X) B_i)^{-1} B_i^T E_i(X) A_i,

with E_i(X) = sum_j p_ij X_j. The CARE is solved by the Riccati iteration started at
X = 0 (the coupled Riccati difference equation run backwards until it is stationary),
which converges to the mean-square stabilising solution when the MJLS is
mean-square stabilisable and detectable (Costa et al., Sec. 4.2 and App. A).
"""

import time
import warnings
from dataclasses import dataclass

import numpy as np

from ..result import Status
from ..validation import boolean, integer, real_scalar
from .controllers import ModeDependentGain
from .design_result import CertifiedDesignResult
from .stability import mean_square_stability
from .system import check_system

__all__ = ["DIVERGED", "ObservedModeResult", "riccati_step", "observed_mode_state_feedback"]


DIVERGED = 1e100     # the Riccati iteration diverges once |P| exceeds this (as Alg. 3.2's bounds)


@dataclass(kw_only=True)
class ObservedModeResult(CertifiedDesignResult):
    """Result of :func:`observed_mode_state_feedback`.

    Attributes
    ----------
    L : numpy.ndarray, shape (M, nu, nx)
        Mode-dependent state-feedback gains.
    P : numpy.ndarray, shape (M, nx, nx)
        Solution of the coupled algebraic Riccati equations.
    stability : asoc.mjls.MeanSquareStability or None
        The closed loop's certificate (Cor. 3.2), None when the last Riccati step failed;
        ``rho``, ``rho_bracket`` and ``stabilizing`` read it
        (:class:`asoc.mjls.design_result.CertifiedDesignResult`). ``controller`` is
        u = L_theta x as a :class:`asoc.mjls.ModeDependentGain` (it observes the mode; the
        state is the output of the systems this design is for, C = I).
    converged, status, message
        Why the Riccati iteration stopped: ``"converged"``, ``"max_iterations"``,
        ``"diverged"`` (an entry of P beyond 1e100 in magnitude) or ``"linalg_error"``
        (R_i + B_i^T E_i(P) B_i singular).
    iterations : int
    seconds : float

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = observed_mode_state_feedback(sec354_system(1, "state"), max_iter=5, warn=False)
    >>> res.status, res.iterations
    ('max_iterations', 5)
    """

    controller_type = ModeDependentGain

    L: np.ndarray
    P: np.ndarray
    iterations: int
    seconds: float


def riccati_step(sys, P):
    """One step of the coupled Riccati difference equation; returns (L, P_new).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> L, P = riccati_step(sec354_system(1, "state"), np.zeros((2, 2, 2)))
    >>> L.shape, float(P[0, 0, 0])
    ((2, 1, 2), 1.0)
    """
    check_system(sys)
    EP = sys.successor_average(P)
    BT = np.swapaxes(sys.B, 1, 2)
    S = sys.R + BT @ EP @ sys.B
    L = -np.linalg.solve(S, BT @ EP @ sys.A)
    Acl = sys.A + sys.B @ L
    P_new = np.swapaxes(Acl, 1, 2) @ EP @ Acl + sys.Q + np.swapaxes(L, 1, 2) @ sys.R @ L
    return L, 0.5 * (P_new + np.swapaxes(P_new, 1, 2))


def observed_mode_state_feedback(sys, tol=1e-12, max_iter=100000, warn=True):
    """[38]: optimal time-invariant state feedback u_k = L_{theta_k} x_k with observed mode.

    Solves the coupled algebraic Riccati equations (Costa, Fragoso, Marques 2005, Ch. 4) by
    the Riccati iteration from P = 0. Its cost is a lower bound for every controller that
    sees less (the output only, or not the mode).

    Parameters
    ----------
    sys : MJLS
    tol : float
        Stop when the largest change of P, relative to 1 + max abs(P), is below tol.
    max_iter : int
        Iteration limit.
    warn : bool
        Warn (RuntimeWarning) on non-convergence or a non-stabilising result.

    Returns
    -------
    ObservedModeResult
        When the iteration diverges (max abs(P) > 1e100: the MJLS is not mean-square
        stabilisable even with observed mode), converged is False and L, P, rho are those
        of the last iterate; it warns.

    Raises
    ------
    TypeError
        if sys is not an MJLS, max_iter is not an integer or warn not a bool.
    ValueError
        if tol is not a finite positive number or max_iter < 1.

    Examples
    --------
    State feedback with observed mode on the example of Sec. 3.5.4 (Table 3.2, [38]):

    >>> from asoc.mjls.examples import sec354_system
    >>> res = observed_mode_state_feedback(sec354_system(1, "state"))
    >>> res.status, res.stabilizing, res.L.shape
    ('converged', True, (2, 1, 2))
    """
    check_system(sys)
    tol = real_scalar(tol, "tol", low=0, low_open=True)
    max_iter = integer(max_iter, "max_iter", minimum=1)
    warn = boolean(warn, "warn")
    start = time.perf_counter()
    P = np.zeros((sys.M, sys.nx, sys.nx))
    status, delta = Status.MAX_ITERATIONS, np.inf
    it = 0
    for it in range(1, max_iter + 1):
        try:
            L, P_new = riccati_step(sys, P)
        except np.linalg.LinAlgError:
            status = Status.LINALG_ERROR
            break
        if not np.abs(P_new).max() <= DIVERGED:
            status = Status.DIVERGED
            break
        delta = np.abs(P_new - P).max() / (1 + np.abs(P_new).max())
        P = P_new
        if delta < tol:
            status = Status.CONVERGED
            break
    try:
        L, _ = riccati_step(sys, P)
        stability = mean_square_stability(sys.A + sys.B @ L, sys.T)
    except np.linalg.LinAlgError:
        L, stability = np.full((sys.M, sys.nu, sys.nx), np.nan), None
    rho, stabilizing = ((np.inf, False) if stability is None else
                        (stability.rho, stability.stabilizing))
    message = {"converged": f"converged after {it} steps "
                            f"(relative change {delta:.2g} < tol = {tol:.2g})",
               "max_iterations": f"did not converge in {it} steps "
                                 f"(relative change {delta:.2g} >= tol = {tol:.2g})",
               "diverged": f"diverges (max |P| > {DIVERGED:.0e} after {it} steps): the MJLS is "
                           "not mean-square stabilisable even with observed mode",
               "linalg_error": f"stopped at step {it}: R_i + B_i^T E_i(P) B_i is singular"}[status]
    if warn and status is not Status.CONVERGED:
        warnings.warn(f"coupled Riccati iteration {message}", RuntimeWarning, stacklevel=2)
    elif warn and not stabilizing:
        warnings.warn(f"CARE gains are not certified to stabilise the MJLS (rho = {rho:.4f})",
                      RuntimeWarning, stacklevel=2)
    return ObservedModeResult(L=L, P=P, stability=stability, converged=status is Status.CONVERGED,
                              status=status, message=message, iterations=it,
                              seconds=time.perf_counter() - start)
