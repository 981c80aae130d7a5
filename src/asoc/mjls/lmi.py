"""LMI feasibility conditions for static output feedback (Sec. 3.5.2, Theorems 3.9 and 3.12).

Strict inequalities ``> 0`` are imposed as ``>= eps * I`` with ``eps = 1e-6`` (relative to
the problem's unit scale): a solver can only certify non-strict inequalities, and the
margin keeps the recovered G, M invertible. Solved with cvxpy and Clarabel.

Feasibility is decided by the certificate, not by the solver's status string: the returned
matrices are substituted into every constraint, and the LMIs count as satisfied when the
smallest eigenvalue of each (imposed minus its floor) is at least ``-eps / 2``, i.e. each
strict inequality holds with a margin of at least ``eps / 2``, and the equalities hold to
``config.defaults["mjls.lmi_equality_rtol"]``. Whether the recovered gain stabilises is
reported on its own (``rho``, ``stabilizing``): the theorems promise it, so a feasible
certificate with ``rho >= 1`` is either a counterexample or a numerical failure, and the
message says which.
"""

import warnings
from dataclasses import dataclass, field

import cvxpy as cp
import numpy as np

from .. import config
from ..linalg import sym
from ..validation import boolean, real_scalar
from .controllers import ModeDependentGain, StaticGain
from .design_result import CertifiedDesignResult
from .stability import MeanSquareStability, mean_square_stability
from .system import check_system

__all__ = ["EPS", "LMIResult", "certificate", "lmi_result", "performance_output",
           "static_output_lmi", "solve_quietly", "check_solver"]


EPS = 1e-6

#: cvxpy's statuses whose matrices are checked as a certificate (an inaccurate solve may still
#: return matrices that satisfy the LMIs).
_CHECKED = (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)


@dataclass(kw_only=True)
class LMIResult(CertifiedDesignResult):
    """Result of :func:`static_output_lmi` (and of the LMI baseline [52]).

    Attributes
    ----------
    feasible : bool
        Whether the returned matrices satisfy the LMIs (the certificate, checked by
        eigenvalues; see the module's docstring), whatever the solver's status string.
    converged, status, message
        ``"converged"`` when feasible, ``"infeasible"`` when the solver certifies
        infeasibility, ``"inaccurate"`` when the solver stopped short of its accuracy and no
        certificate was verified (:class:`asoc.result.IterativeResult`).
    L : numpy.ndarray or None
        The gain F M^{-1} (nu, ny), or the mode-dependent gains (M, nu, ny); None if not feasible.
    bound : float
        sum_i tr W_i, an upper bound of the H2 cost (3.23); inf if not feasible.
    solver_status : str
        The solver's own status string (e.g. "optimal", "infeasible").
    stability : asoc.mjls.MeanSquareStability or None
        The certificate of the closed loop with L (Cor. 3.2), None without a gain; ``rho``
        (nan without a gain), ``rho_bracket`` and ``stabilizing`` (False without a gain) read
        it (:class:`asoc.mjls.design_result.CertifiedDesignResult`). ``controller`` is a
        :class:`asoc.mjls.StaticGain`, or a :class:`asoc.mjls.ModeDependentGain` for Thm. 3.12.
    margin : float
        Smallest eigenvalue over the constraints, each minus its imposed floor (>= -eps/2 for a
        certificate; nan when the solver returned no matrices).
    equality_residual : float
        Largest ``|M C_i - C_i G|`` relative to the entries' size (nan without matrices).
    variables : dict
        The solver's matrices by name (e.g. "F", "G", "M", "W", "Y", each a list over gains or
        modes), empty when it returned none: the certificate, to re-check or to reuse.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_lmi(sec354_system(1, "state"))
    >>> res.feasible, res.status, res.solver_status, res.stabilizing, bool(res.margin > -5e-7)
    (True, 'converged', 'optimal', True, True)
    """

    feasible: bool
    L: np.ndarray | None
    bound: float
    solver_status: str
    stability: MeanSquareStability | None = None
    margin: float = np.nan
    equality_residual: float = np.nan
    variables: dict = field(default_factory=dict)

    @property
    def controller_type(self):
        """StaticGain for one gain, ModeDependentGain for gains per mode (Thm. 3.12)."""
        return ModeDependentGain if self.L is not None and np.ndim(self.L) == 3 else StaticGain


def certificate(constraints):
    """(margin, equality_residual) of solved cvxpy ``constraints``: the smallest eigenvalue of every
    semidefinite constraint's expression (left minus right side), and the largest equality residual
    relative to max(1, largest entry of its two sides).

    Examples
    --------
    >>> X = cp.Variable((2, 2), symmetric=True)
    >>> cons = [X >> np.eye(2), cp.trace(X) == 3]
    >>> _ = cp.Problem(cp.Minimize(0), cons).solve(solver="CLARABEL")
    >>> margin, residual = certificate(cons)
    >>> bool(margin > -1e-7), bool(residual < 1e-7)
    (True, True)
    """
    margins, residuals = [np.inf], [0.0]
    for con in constraints:
        if isinstance(con, cp.constraints.PSD):
            margins.append(float(np.linalg.eigvalsh(sym(np.atleast_2d(con.expr.value)))[0]))
        elif isinstance(con, cp.constraints.Equality):
            scale = max(1.0, *(float(np.max(np.abs(arg.value))) for arg in con.args))
            residuals.append(float(np.max(np.abs(con.expr.value))) / scale)
    return min(margins), max(residuals)


def lmi_result(solver_status, L=None, bound=np.inf, margin=np.nan, equality_residual=np.nan,
               eps=EPS, variables=None, stability=None):
    """The LMIResult of a solve: feasible iff the matrices satisfy the constraints
    (``margin >= -eps/2``, ``equality_residual <= config.defaults["mjls.lmi_equality_rtol"]``); rho
    reported on its own.
    Without a margin (nan), the solver's status "optimal" stands for the certificate. ``stability``
    is the gain's :func:`asoc.mjls.mean_square_stability` (rho, its certified bracket and
    ``stabilizing``); without it the gain is not certified to stabilise.

    Examples
    --------
    >>> unstable = mean_square_stability(np.array([[[1.1]]]), [[1.0]])
    >>> lmi_result("optimal", np.array([[1.0]]), 2.0, margin=1e-3, equality_residual=0.0,
    ...            stability=unstable).message[:52]
    'the LMIs hold (margin 1.0e-03 >= -5.0e-07), but the '
    >>> lmi_result("infeasible_inaccurate").status
    'inaccurate'
    >>> miss = lmi_result("optimal_inaccurate", np.array([[1.0]]), 2.0, margin=-1e-3,
    ...                   equality_residual=0.0)
    >>> miss.feasible, miss.status, miss.L is None
    (False, 'inaccurate', True)
    """
    rho = np.nan if stability is None else stability.rho
    common = dict(solver_status=solver_status, margin=margin, equality_residual=equality_residual,
                  variables=variables or {})
    verified = (L is not None
                and (solver_status == cp.OPTIMAL if np.isnan(margin) else margin >= -eps / 2)
                and not equality_residual > config.defaults["mjls.lmi_equality_rtol"])
    if not verified:
        status, message = _not_feasible(solver_status, L, margin, equality_residual, eps)
        # no gain, no certificate
        return LMIResult(feasible=False, L=None, bound=np.inf, converged=False, status=status,
                         message=message, **common)
    stabilizing = False if stability is None else stability.stabilizing
    text = f"the LMIs hold (margin {margin:.1e} >= {-eps / 2:.1e})" if not np.isnan(margin) else \
        f"the solver reports {solver_status!r}"
    if stabilizing:
        message = f"{text}; the gain gives rho = {rho:.4f} (mean-square stabilising)"
    else:
        message = (f"{text}, but the recovered gain is not certified to stabilise "
                   f"(rho = {rho:.4f}), which the theorem excludes: a numerical failure of the "
                   "gain's recovery, or a counterexample")
    return LMIResult(feasible=True, L=L, bound=bound, converged=True, status="converged",
                     message=message, stability=stability, **common)


def _not_feasible(solver_status, L, margin, residual, eps):
    """(status, message) of a solve without a verified certificate."""
    if solver_status == cp.INFEASIBLE:
        return "infeasible", ("the solver certifies that the LMIs of the sufficient condition are "
                              "infeasible" + _MAY_EXIST)
    if solver_status in (cp.INFEASIBLE_INACCURATE, cp.OPTIMAL_INACCURATE) or L is not None:
        found = ("" if L is None else f"; its matrices miss the LMIs (margin {margin:.1e}, "
                 f"equality residual {residual:.1e})")
        return "inaccurate", (f"the solver stopped short of its accuracy (status {solver_status!r})"
                              f"{found}: feasibility is undecided; rescale the system or try "
                              "another solver")
    return "infeasible", ("the solver found no solution of the sufficient condition "
                          f"(status {solver_status!r})" + _MAY_EXIST)


_MAY_EXIST = ("; stabilising static gains may still exist (the condition is sufficient only and "
              "depends on the state coordinates, Sec. 3.5.2): exact_static_output_feedback "
              "searches the gains directly")


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


@config.accepts_settings("mjls.lmi_equality_rtol")
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
        cons += [0.5 * (lmi1 + lmi1.T) >> eps * np.eye(2 * nx + nu),
                 0.5 * (lmi2 + lmi2.T) >> eps * np.eye(2 * nx),
                 Y[i] >> eps * np.eye(nx), W[i] >> 0,
                 Mv[g] @ sys.C[i] == sys.C[i] @ G[g]]
    prob = cp.Problem(cp.Minimize(sum(cp.trace(Wi) for Wi in W)), cons)
    status = solve_quietly(prob, solver)
    if status not in _CHECKED:
        return lmi_result(status)
    margin, residual = certificate(cons)
    gains = np.stack([F[g].value @ np.linalg.inv(Mv[g].value) for g in range(n_gains)])
    closed = sys.A + sys.B @ (gains if mode_observed else gains[0]) @ sys.C
    groups = (("F", F), ("G", G), ("M", Mv), ("W", W), ("Y", Y))
    variables = {name: [v.value for v in group] for name, group in groups}
    return lmi_result(status, gains if mode_observed else gains[0], float(prob.value),
                      margin=margin, equality_residual=residual, eps=eps, variables=variables,
                      stability=mean_square_stability(closed, sys.T, check=False))


def solve_quietly(prob, solver):
    """Solve ``prob`` with ``solver``; cvxpy's warnings (e.g. "Solution may be inaccurate") are
    caught, since the result reports the status in its own words. Returns the status string, or
    "solver error: ..." when the solver raised.

    Examples
    --------
    >>> x = cp.Variable()
    >>> solve_quietly(cp.Problem(cp.Minimize(x), [x >= 1]), "CLARABEL")
    'optimal'
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        try:
            prob.solve(solver=solver)
        except cp.SolverError as err:
            return f"solver error: {err}"
    return prob.status


def check_solver(solver, name="solver"):
    """An installed cvxpy solver name.

    Examples
    --------
    >>> check_solver("CLARABEL")
    'CLARABEL'
    """
    if not isinstance(solver, str):
        raise TypeError(f"{name}: expected a cvxpy solver name (str), "
                        f"found {type(solver).__name__}")
    if solver not in cp.installed_solvers():
        raise ValueError(f"{name}: expected one of the installed solvers {cp.installed_solvers()}, "
                         f"found {solver!r}")
    return solver
