"""Checks of Sec. 3.3-3.4: mean-square stability (Thm. 3.1, Cor. 3.2) and the step of Prop. 3.5.

Mean-square stability is decided from its definition, independently of the printed matrices:
the second moments X_k^j = E{x_k x_k^T 1(theta_k = j)} of x_{k+1} = A_{theta_k} x_k follow the
linear map X -> (sum_i p_ij A_i X_i A_i^T)_j, and E{|x_k|^2} -> 0 for every initial condition
exactly when that map's spectral radius is below 1 (Costa, Fragoso and Marques 2005, Thm. 3.9).
:func:`moment_map_radius` builds the map's matrix column by column from its action on the
basis matrices (no Kronecker algebra, no library operator) and takes its eigenvalues densely.
"""

import numpy as np
import scipy.optimize

from asoc.linalg import transpose
from asoc.mjls import ms_spectral_radius, successor_average
from asoc.mjls.moment_operator import ms_operator

from .instances import draw_system, min_eig, outcome, random_spd, random_spd_stack, verdict

__all__ = ["DECISIVE", "moment_map_matrix", "moment_map_radius", "BOUNDARY_SHARE", "near_cycle",
           "boundary_system", "check_3_1", "check_3_2", "check_3_5"]


DECISIVE = 1e-9       # |rho - 1| below this leaves mean-square stability undecided by rounding


def moment_map_matrix(A, T):
    """The matrix of X -> (sum_i p_ij A_i X_i A_i^T)_j on the stacked entries of (X_1, ..., X_M),
    column k the image of the k-th basis matrix.

    Examples
    --------
    >>> moment_map_matrix(np.array([[[0.5]], [[2.0]]]), np.array([[0.5, 0.5], [0.0, 1.0]]))
    array([[0.125, 0.   ],
           [0.125, 4.   ]])
    """
    M, n, _ = A.shape
    basis = np.eye(M * n * n).reshape(M * n * n, M, n, n)
    images = np.einsum("ij,iab,Nibc,idc->Njad", T, A, basis, A)
    return images.reshape(M * n * n, M * n * n).T


def moment_map_radius(A, T):
    """Spectral radius of :func:`moment_map_matrix` (dense eigenvalues).

    Examples
    --------
    >>> A = np.array([[[0.5]], [[2.0]]])
    >>> round(moment_map_radius(A, np.array([[0.5, 0.5], [0.5, 0.5]])), 6)     # (0.25 + 4) / 2
    2.125
    """
    return float(np.max(np.abs(np.linalg.eigvals(moment_map_matrix(A, T)))))


BOUNDARY_SHARE = 0.5  # share of the checks' draws from boundary_system (all of the mutants')


def near_cycle(rng, M, reverse=False):
    """A random asymmetric transition matrix: one random M-cycle of the modes (run backwards when
    ``reverse``), mixed with Dirichlet(1) rows at a weight uniform on [0, 0.3] (T^T is far from
    T).
    """
    order = rng.permutation(M)
    cycle = np.zeros((M, M))
    cycle[order, np.roll(order, -1)] = 1.0                      # order[k] -> order[k + 1]
    weight = rng.uniform(0.0, 0.3)
    mixed = rng.dirichlet(np.ones(M), size=M)
    return [(1 - weight) * C + weight * mixed for C in (cycle, cycle.T)][::-1 if reverse else 1]


def boundary_system(rng, radius_of, against=None):
    """Mode matrices A_i (3 modes, 2-3 states, standard normal) and a :func:`near_cycle` T, with A
    scaled so that ``radius_of(A, T)`` (homogeneous of degree 2 in A) is log-uniform on [0.97, 1):
    the draws where a statement about mean-square stability is decided by small differences of
    spectra. With ``against`` (a mutant's radius), the cycle runs in the direction in which
    ``against`` understates the library's ``ms_spectral_radius`` more (reversing the cycle is what
    transposing T does, so in a family symmetric under reversal the mutant's premise errs on the
    safe side in half the draws).
    """
    M, n = 3, int(rng.integers(2, 4))
    A, candidates = rng.standard_normal((M, n, n)), near_cycle(rng, M)
    T = candidates[0] if against is None else max(
        candidates, key=lambda T: ms_spectral_radius(A, T) / against(A, T))
    target = np.exp(rng.uniform(np.log(0.97), 0.0))
    return A * np.sqrt(target / radius_of(A, T)), T


def _coupled_lyapunov_solutions(A, T, S):
    """Q of the two forms of Thm. 3.1 for S: A_i^T E_i(Q) A_i - Q_i = -S_i and
    D_j(A Q A^T) - Q_j = -S_j.
    """
    M, n, _ = A.shape
    op = ms_operator(A, T, check=False)
    eye = np.eye(M * n * n)
    return (np.linalg.solve(eye - op.T, S.ravel()).reshape(M, n, n),
            np.linalg.solve(eye - op, S.ravel()).reshape(M, n, n))


def check_3_1(rng, mutant=False):
    """Thm. 3.1: PD solutions Q of the coupled Lyapunov equations (either form) for PD S imply MSS.
    Half the draws (all of the mutant's) come from :func:`boundary_system`, scaled at the premise's
    own boundary. Mutant: the equations solved with T^T in place of T (nx >= 2, a 3-cycle T: with nx
    = 1 or M = 2 the two spectra coincide).
    """
    premise_T = (lambda T: T.T) if mutant else (lambda T: T)
    premise_radius = lambda A, T: moment_map_radius(A, premise_T(T))
    if mutant or rng.random() < BOUNDARY_SHARE:
        A, T = boundary_system(rng, premise_radius, against=premise_radius if mutant else None)
        sys = None
    else:
        sys = draw_system(rng)
        A, T = sys.A, sys.T
    S = random_spd_stack(rng, *A.shape[:2])
    try:
        Q_first, Q_second = _coupled_lyapunov_solutions(A, premise_T(T), S)
    except np.linalg.LinAlgError:
        return outcome("not_applicable", sys, reason="singular coupled Lyapunov operator")
    eig_first, eig_second = min_eig(Q_first), min_eig(Q_second)
    rho = moment_map_radius(A, T)
    numbers = dict(min_eig_Q_first_form=eig_first, min_eig_Q_second_form=eig_second,
                   moment_map_radius=rho, **({} if sys is not None else dict(A=A, T=T)))
    if not (eig_first > 0 or eig_second > 0) or abs(rho - 1) < DECISIVE:
        return outcome("not_applicable", sys, **numbers)
    return outcome(verdict(rho < 1), sys, **numbers)


def _printed_matrix(A, T):
    """The matrix of Cor. 3.2 as printed: diag[A_1 (x) A_1, ..., A_M (x) A_M] (T^T (x) I_{n^2}).

    Examples
    --------
    >>> _printed_matrix(np.array([[[2.0]]]), np.array([[1.0]]))
    array([[4.]])
    """
    M, n, _ = A.shape
    blocks = np.zeros((M * n * n, M * n * n))
    for i in range(M):
        blocks[i * n * n:(i + 1) * n * n, i * n * n:(i + 1) * n * n] = np.kron(A[i], A[i])
    return blocks @ np.kron(T.T, np.eye(n * n))


def check_3_2(rng, mutant=False):
    """Cor. 3.2 with the text's remark ([112]: also necessary): rho(M) < 1 of the printed M iff MSS,
    decided by :func:`moment_map_radius`. Half the draws (all of the mutant's) come from
    :func:`boundary_system`, scaled at the printed matrix's boundary. Mutant: M built with T^T.
    """
    radius = lambda matrix: float(np.max(np.abs(np.linalg.eigvals(matrix))))
    printed = lambda A, T: radius(_printed_matrix(A, T.T if mutant else T))
    if mutant or rng.random() < BOUNDARY_SHARE:
        A, T = boundary_system(rng, printed, against=printed if mutant else None)
        sys, data = None, dict(A=A, T=T)
    else:
        sys = draw_system(rng)
        A, T, data = sys.A, sys.T, dict(rho_library=ms_spectral_radius(sys.A, sys.T))
    rho, rho_map = printed(A, T), moment_map_radius(A, T)
    numbers = dict(rho_printed=rho, moment_map_radius=rho_map, **data)
    if abs(rho - 1) < DECISIVE or abs(rho_map - 1) < DECISIVE:
        return outcome("not_applicable", sys, **numbers)
    return outcome(verdict((rho < 1) == (rho_map < 1)), sys, **numbers)


def check_3_5(rng, mutant=False):
    """Prop. 3.5 at step K-1: J*_{K-1} = x^T Psi x + Delta, against a numerical minimisation over u.
    Mutant: the closed form without Delta (the noise's cost dropped).
    """
    sys = draw_system(rng, max_states=2)
    A, B, Q, R, T, M = sys.A, sys.B, sys.Q, sys.R, sys.T, sys.M
    W = random_spd(rng, sys.nx, 0.1)                               # covariance of w_k (3.2)
    belief = rng.dirichlet(np.ones(M))                             # p(theta_{K-1} | I_{K-1})
    x = rng.standard_normal(sys.nx) * 2
    # E{Q_{theta_K} | theta_{K-1} = i}
    EQ = successor_average(T, Q)

    def expected_cost(u):
        nxt = A @ x + B @ u
        return float(belief @ (np.einsum("a,iab,b->i", x, Q, x) + np.einsum("a,iab,b->i", u, R, u)
                               + np.einsum("ia,iab,ib->i", nxt, EQ, nxt)
                               + np.einsum("iab,ba->i", EQ, W)))

    res = scipy.optimize.minimize(expected_cost, np.zeros(sys.nu), method="BFGS",
                                  options={"gtol": 1e-12})
    Ew = lambda S: np.einsum("i,i...->...", belief, S)
    At, Bt = transpose(A), transpose(B)
    psi = (Ew(Q + At @ EQ @ A)
           - Ew(At @ EQ @ B) @ np.linalg.solve(Ew(R + Bt @ EQ @ B), Ew(Bt @ EQ @ A)))
    delta = 0.0 if mutant else float(belief @ np.einsum("iab,ba->i", EQ, W))
    closed = float(x @ psi @ x + delta)
    rel = abs(closed - res.fun) / max(abs(res.fun), 1e-12)
    return outcome(verdict(rel < 1e-7), sys, closed_form=closed, minimised=res.fun,
                   relative_difference=rel, delta=delta)
