"""LMI feasibility conditions for static output feedback (Sec. 3.5.2, Theorems 3.9 and 3.12).

Strict inequalities ``> 0`` are imposed as ``>= eps * I`` with ``eps = 1e-6`` (relative to
the problem's unit scale): a solver can only certify non-strict inequalities, and the
margin keeps the recovered G, M invertible. Solved with cvxpy and Clarabel.
"""

from dataclasses import dataclass

import cvxpy as cp
import numpy as np

EPS = 1e-6


@dataclass
class LMIResult:
    """Result of :func:`static_output_lmi`.

    Attributes
    ----------
    feasible : bool
        Whether the solver found a solution of the LMIs (status optimal).
    L : numpy.ndarray or None
        The gain F M^{-1} (nu, ny), or the mode-dependent gains (M, nu, ny); None if infeasible.
    bound : float
        sum_i tr W_i, an upper bound of the H2 cost (3.23); inf if infeasible.
    status : str
        The solver's status string.
    """

    feasible: bool
    L: np.ndarray | None
    bound: float
    status: str


def performance_output(sys):
    """D_i = [Q_i^{1/2}; 0], E_i = [0; R_i^{1/2}] of (3.12), by Cholesky (PSD-safe for Q)."""
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
    numpy.linalg.LinAlgError
        Only if the solver returns a numerically singular M despite the margin M >= eps I
        (infeasibility and solver errors are reported in the result, not raised).
    """
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
        return LMIResult(False, None, np.inf, f"solver error: {err}")
    feasible = prob.status == cp.OPTIMAL
    if not feasible:
        return LMIResult(False, None, np.inf, prob.status)
    gains = np.stack([F[g].value @ np.linalg.inv(Mv[g].value) for g in range(n_gains)])
    return LMIResult(True, gains if mode_observed else gains[0], float(prob.value), prob.status)
