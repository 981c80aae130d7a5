"""LMI feasibility conditions for static output feedback (Sec. 3.5.2, Theorems 3.9 and 3.12).

Strict inequalities ``> 0`` are imposed as ``>= eps * I`` with ``eps = 1e-6`` (relative to
the problem's unit scale): a solver can only certify non-strict inequalities, and the
margin keeps the recovered G, M invertible. Solved with cvxpy and Clarabel.
"""

from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from ..result import IterativeResult
from ..validation import boolean, real_scalar
from .spectral import ms_spectral_radius
from .system import check_system

EPS = 1e-6


@dataclass(kw_only=True)
class LMIResult(IterativeResult):
    """Result of :func:`static_output_lmi` (and of the LMI baseline [52]).

    Attributes
    ----------
    feasible : bool
        Whether the solver found a solution of the LMIs (status optimal) AND the recovered
        gain mean-square stabilises the MJLS (rho < 1, Cor. 3.2, checked here: the theorems
        guarantee it, so a failure means the solution is numerically unreliable).
    converged, status, message
        ``"converged"`` when feasible, else ``"infeasible"``; the message says which test
        failed (:class:`asoc.result.IterativeResult`).
    L : numpy.ndarray or None
        The gain F M^{-1} (nu, ny), or the mode-dependent gains (M, nu, ny); None if infeasible.
    bound : float
        sum_i tr W_i, an upper bound of the H2 cost (3.23); inf if infeasible.
    solver_status : str
        The solver's own status string (e.g. "optimal", "infeasible").
    rho : float
        Mean-square spectral radius of the closed loop with L (nan without a gain).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_lmi(sec354_system(1, "state"))
    >>> res.feasible, res.status, res.solver_status, bool(res.rho < 1)
    (True, 'converged', 'optimal', True)
    """

    feasible: bool
    L: np.ndarray | None
    bound: float
    solver_status: str
    rho: float = np.nan


def lmi_result(solver_status, L=None, bound=np.inf, rho=np.nan):
    """The LMIResult of a solve: feasible iff the solver's status is optimal and rho < 1.

    Examples
    --------
    >>> lmi_result("optimal", np.array([[1.0]]), 2.0, rho=1.2).message[:40]
    "the solver reports 'optimal', but the re"
    """
    if L is None:
        return LMIResult(feasible=False, L=None, bound=np.inf, solver_status=solver_status, rho=rho,
                         converged=False, status="infeasible",
                         message=f"the solver found no solution (status {solver_status!r})")
    if not rho < 1:
        return LMIResult(feasible=False, L=None, bound=np.inf, solver_status=solver_status, rho=rho,
                         converged=False, status="infeasible",
                         message=f"the solver reports {solver_status!r}, but the recovered gain does not "
                                 f"stabilise the MJLS (rho = {rho:.4f} >= 1): numerically unreliable")
    return LMIResult(feasible=True, L=L, bound=bound, solver_status=solver_status, rho=rho,
                     converged=True, status="converged",
                     message=f"feasible (solver status {solver_status!r}); the gain gives rho = {rho:.4f}")


def performance_output(sys):
    """D_i = [Q_i^{1/2}; 0], E_i = [0; R_i^{1/2}] of (3.12), by Cholesky (PSD-safe for Q).

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> D, E = performance_output(sec354_system(1))
    >>> D.shape, E[0].ravel().tolist()
    ((2, 3, 2), [0.0, 0.0, 1.0])
    """
    nx, nu = sys.nx, sys.nu
    D = np.zeros((sys.M, nx + nu, nx))
    E = np.zeros((sys.M, nx + nu, nu))
    for i in range(sys.M):
        lam, vec = np.linalg.eigh(sys.Q[i])
        D[i, :nx] = (vec * np.sqrt(np.clip(lam, 0, None))) @ vec.T
        E[i, nx:] = np.linalg.cholesky(sys.R[i]).T
    return D, E


def _sym(X):
    return 0.5 * (X + X.T)


def static_output_lmi(sys, mode_observed=False, eps=EPS, solver="CLARABEL"):
    """Theorem 3.9 (one gain, mode not observed) or Theorem 3.12 (gains L_i, mode observed).

    Minimises sum_i tr W_i subject to the LMIs of the theorem and M C_i = C_i G (Crusius and
    Trofino's constraint); feasibility implies a mean-square stabilising gain L = F M^{-1}.
    Strict inequalities are imposed with the margin ``eps``.

    Parameters
    ----------
    sys : MJLS
    mode_observed : bool
        False: Theorem 3.9 (one gain); True: Theorem 3.12 (one gain per mode).
    eps : float
        Margin of the strict inequalities (>= eps I).
    solver : str
        cvxpy solver name.

    Returns
    -------
    LMIResult
        Infeasibility and solver errors are reported in the result (``feasible=False`` and
        the status), not raised.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, ``mode_observed`` not a bool or ``solver`` not a string.
    ValueError
        If ``eps`` is not a finite positive number or ``solver`` is not an installed cvxpy
        solver.
    numpy.linalg.LinAlgError
        Only if the solver returns a numerically singular M despite the margin M >= eps I
        (infeasibility and solver errors are reported in the result, not raised).

    Examples
    --------
    Theorem 3.9 for the example of Sec. 3.5.4 with C = [1 0] (infeasible, as the thesis says):

    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_lmi(sec354_system(1, "C=[1 0]"))
    >>> res.feasible, res.status, res.solver_status
    (False, 'infeasible', 'infeasible')
    """
    check_system(sys)
    mode_observed = boolean(mode_observed, "mode_observed")
    eps = real_scalar(eps, "eps", low=0, low_open=True)
    check_solver(solver)
    M_, nx, nu, ny = sys.M, sys.nx, sys.nu, sys.ny
    mu = sys.mu_inf
    D, E = performance_output(sys)
    HHt = sys.H @ np.swapaxes(sys.H, 1, 2)
    n_gains = M_ if mode_observed else 1
    F = [cp.Variable((nu, ny)) for _ in range(n_gains)]
    G = [cp.Variable((nx, nx), symmetric=True) for _ in range(n_gains)]
    Mv = [cp.Variable((ny, ny), symmetric=True) for _ in range(n_gains)]
    W = [cp.Variable((nx + nu, nx + nu), symmetric=True) for _ in range(M_)]
    Y = [cp.Variable((nx, nx), symmetric=True) for _ in range(M_)]
    cons = []
    for g in range(n_gains):
        cons += [G[g] >> eps * np.eye(nx), Mv[g] >> eps * np.eye(ny)]
    for i in range(M_):
        g = i if mode_observed else 0
        DY = sum(sys.T[j, i] * Y[j] for j in range(M_))
        corner = G[g] + G[g].T - DY
        top = D[i] @ G[g] + E[i] @ F[g] @ sys.C[i]
        mid = sys.A[i] @ G[g] + sys.B[i] @ F[g] @ sys.C[i]
        lmi1 = cp.bmat([[W[i], top], [top.T, corner]])
        lmi2 = cp.bmat([[Y[i] - mu[i] * HHt[i], mid], [mid.T, corner]])
        cons += [_sym(lmi1) >> eps * np.eye(2 * nx + nu), _sym(lmi2) >> eps * np.eye(2 * nx),
                 Y[i] >> eps * np.eye(nx), W[i] >> 0,
                 Mv[g] @ sys.C[i] == sys.C[i] @ G[g]]
    prob = cp.Problem(cp.Minimize(sum(cp.trace(Wi) for Wi in W)), cons)
    try:
        prob.solve(solver=solver)
    except cp.SolverError as err:
        return lmi_result(f"solver error: {err}")
    if prob.status != cp.OPTIMAL:
        return lmi_result(prob.status)
    gains = np.stack([F[g].value @ np.linalg.inv(Mv[g].value) for g in range(n_gains)])
    closed = sys.A + sys.B @ (gains if mode_observed else gains[0]) @ sys.C
    return lmi_result(prob.status, gains if mode_observed else gains[0], float(prob.value),
                      ms_spectral_radius(closed, sys.T))


def check_solver(solver, name="solver"):
    """An installed cvxpy solver name.

    Examples
    --------
    >>> check_solver("CLARABEL")
    'CLARABEL'
    """
    if not isinstance(solver, str):
        raise TypeError(f"{name}: expected a cvxpy solver name (str), found {type(solver).__name__}")
    if solver not in cp.installed_solvers():
        raise ValueError(f"{name}: expected one of the installed solvers {cp.installed_solvers()}, found {solver!r}")
    return solver
