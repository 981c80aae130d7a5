"""Corrected bounds of Prop. 3.26 and Thms. 3.31, 3.32: what holds instead, computed independently.

Everything here is written from the printed equations, not from ``asoc.mjls.dynamic``: the
checks of :mod:`asoc_companion.theorems.corrections` compare these computations with the
library's exact costs (Prop. 3.24, Lemma 3.29), so an error on either side shows.

Notation: the controller state x^ and the estimation error e = x - x^. The thesis's
substitutions (3.43) read Xbar = E{e e^T 1(theta = i)}, Xunder = E{x^ x^^T 1(theta = i)};
the printed recursions (3.45)-(3.46) / (3.66)-(3.67) are the exact recursions of these two
blocks with the cross moment E{e x^^T 1(theta = i)} dropped.

The correction rests on (a + b)(a + b)^T <= 2 a a^T + 2 b b^T (as (a - b)(a - b)^T >= 0):
with [x; x^] = [e; 0] + [x^; x^],

    X~ <= 2 [[Xbar + Xunder, Xunder], [Xunder, Xunder]]                              (Prop. 3.26
    corrected)

and with e_{k+1} = (A - K C) e + (A - F + B L - K C) x^ + H w - K J v,
x^_{k+1} = K C e + (F + K C) x^ + K J v, the recursions (3.66)-(3.67) with the two transported
terms doubled bound the blocks from above for every k (induction, the maps are monotone).
"""

import numpy as np

from asoc.mjls import predecessor_sum

__all__ = ["blocks", "moment_bound", "costate_bound", "costate", "forward_bound",
           "optimality_conditions", "split", "bound_3_65", "functional_b4", "difference_3_65_b4"]


_T = lambda S: np.swapaxes(S, -1, -2)
_tr = lambda A, B: float(np.einsum("iab,iba->", A, B))           # sum_i tr[A_i B_i]


def blocks(Z, n):
    """(Z11, Z12, Z22) of a stack of (2n, 2n) matrices."""
    return Z[:, :n, :n], Z[:, :n, n:], Z[:, n:, n:]


def moment_bound(X, factor=2.0):
    """Factor [[Xbar + X2, X2], [X2, X2]] with Xbar = X1 - X12 - X12^T + X2, X2 = X22 (3.43): the
    corrected bound of X~ (factor 2); factor 1 is Prop. 3.26 as printed.
    """
    n = X.shape[-1] // 2
    X1, X12, X2 = blocks(X, n)
    Xbar = X1 - X12 - _T(X12) + X2
    return factor * np.block([[Xbar + X2, X2], [X2, X2]])


def costate_bound(P, factor=2.0, sign=1.0):
    """Factor [[Pbar + P2, -P2], [-P2, P2]] with Pbar = P1 + sign (P12 + P12^T) + P2.

    With sign = +1, z^T (bound / factor) z = x^T Pbar x + e^T P2 e for z = [x; x^], and
    z = [x; x] + [0; -e] gives P~ <= 2 (.) (the corrected bound). sign = -1, factor = 1 is
    Prop. 3.26 as printed (Pbar = P1 - P12 - P12^T + P2).
    """
    n = P.shape[-1] // 2
    P1, P12, P2 = blocks(P, n)
    Pbar = P1 + sign * (P12 + _T(P12)) + P2
    return factor * np.block([[Pbar + P2, -P2], [-P2, P2]])


def costate(At, Qt, T):
    """P~ of P~_i = Q~_i + A~_i^T E_i(P~) A~_i (the multiplier of Prop. 3.25), by a dense solve."""
    M, m, _ = At.shape
    op = np.zeros((M * m * m, M * m * m))
    for i in range(M):
        # vec(A^T Y A) = (A^T (x) A^T) vec(Y)
        kron = np.kron(At[i].T, At[i].T)
        for j in range(M):
            op[i * m * m:(i + 1) * m * m, j * m * m:(j + 1) * m * m] = T[i, j] * kron
    P = np.linalg.solve(np.eye(M * m * m) - op, Qt.reshape(M * m * m)).reshape(M, m, m)
    return 0.5 * (P + _T(P))


def _error_blocks_step(sys, F, K, L, Xbar, Xunder, mu, factor=1.0):
    """One step of (3.66)-(3.67), the two transported terms multiplied by ``factor``.

    factor = 1 is the printed recursion; factor = 2 the corrected one (an upper bound).
    """
    HHt = sys.H @ _T(sys.H)
    KJJK = np.zeros_like(Xbar) if sys.J is None else K @ sys.J @ _T(sys.J) @ K.T
    KC = K @ sys.C
    AKC, G, FKC = sys.A - KC, sys.A - F + sys.B @ L - KC, F + KC
    m = mu[:, None, None]
    Xbar_next = predecessor_sum(sys.T, m * (HHt + KJJK)
                                + factor * (AKC @ Xbar @ _T(AKC) + G @ Xunder @ _T(G)))
    Xunder_next = predecessor_sum(sys.T,
                                  m * KJJK + factor * (KC @ Xbar @ _T(KC) + FKC @ Xunder @ _T(FKC)))
    return Xbar_next, Xunder_next


def _initial_error_blocks(mean0, cov0, mu0, xhat0):
    """Xbar_0 = E{e_0 e_0^T 1(theta_0 = i)}, Xunder_0 = E{x^_0 x^_0^T 1(theta_0 = i)} for a
    constant x^_0.
    """
    dev = mean0 - xhat0
    m = mu0[:, None, None]
    return m * (cov0 + np.einsum("ia,ib->iab", dev, dev)), m * np.outer(xhat0, xhat0)


def forward_bound(sys, F, K, L, mean0, cov0, mu0, xhat0, factor=2.0):
    """Sum over k of sum_i tr[Q~_i factor [[Xbar + Xu, Xu], [Xu, Xu]]] with (3.66)-(3.67)
    (transported terms times ``factor``): with factor 2 an upper bound of the exact cost J_0 (3.56)
    (Thm. 3.31 corrected); with factor 1 the cost of the printed recursions (no bound).
    """
    Xbar, Xunder = _initial_error_blocks(mean0, cov0, mu0, xhat0)
    mu, total = mu0, 0.0
    for k in range(len(F)):
        LRL = L[k].T @ sys.R @ L[k]
        total += factor * (_tr(sys.Q, Xbar + Xunder) + _tr(LRL, Xunder))
        Xbar, Xunder = _error_blocks_step(sys, F[k], K[k], L[k], Xbar, Xunder, mu, factor)
        mu = mu @ sys.T
    return total + factor * _tr(sys.Q, Xbar + Xunder)


# ------------------------------------------------------------------ Thm. 3.32: (B.4) and (3.70)

def optimality_conditions(sys, Xbar, Xunder, EPbar, EPunder, mu):
    """Matrix and vector of (3.70) from (3.50); column-major vec, unknowns [vec F; vec K; vec L]."""
    JJt = np.zeros((sys.M, sys.ny, sys.ny)) if sys.J is None else sys.J @ _T(sys.J)
    S, C, B, A = Xbar + Xunder, sys.C, sys.B, sys.A
    ksum = lambda X, Y: sum(np.kron(x, y) for x, y in zip(X, Y))
    PhiF = ksum(Xunder, EPunder)
    PhiK = ksum(mu[:, None, None] * JJt + C @ S @ _T(C), EPunder)
    PhiL = ksum(Xunder, sys.R + _T(B) @ (EPbar + EPunder) @ B)
    GFK = ksum(Xunder @ _T(C), EPunder)
    GFL = -ksum(Xunder, EPunder @ B)
    GKL = -ksum(C @ Xunder, EPunder @ B)
    vec = lambda X: X.sum(axis=0).ravel(order="F")
    rho = np.concatenate([-vec(EPunder @ A @ Xunder), -vec(EPunder @ A @ S @ _T(C)),
                          vec(_T(B) @ (EPbar + EPunder) @ A @ Xunder)])
    H = np.block([[PhiF, GFK, GFL], [GFK.T, PhiK, GKL], [GFL.T, GKL.T, PhiL]])
    return H, rho


def split(z, sys):
    """(F, K, L) from the unknowns ``z`` = [vec F; vec K; vec L] of (3.70) (column-major vec)."""
    n, ny, nu = sys.nx, sys.ny, sys.nu
    F = z[:n * n].reshape((n, n), order="F")
    K = z[n * n:n * n + n * ny].reshape((n, ny), order="F")
    return F, K, z[n * n + n * ny:].reshape((nu, n), order="F")


def _step_terms(sys, F, K, L, EPbar, EPunder):
    """Pbar_k (3.68), Punder_k (3.69) from E_i(Pbar_{k+1}), E_i(Punder_{k+1})."""
    BL = sys.B @ L
    ABL, G, FBL, LRL = sys.A + BL, sys.A + BL - F - K @ sys.C, F - BL, L.T @ sys.R @ L
    Pbar = sys.Q + LRL + _T(ABL) @ EPbar @ ABL + _T(G) @ EPunder @ G
    return Pbar, LRL + _T(BL) @ EPbar @ BL + _T(FBL) @ EPunder @ FBL


def _noise_term(sys, K, EPbar, EPunder, mu):
    JJt = np.zeros((sys.M, sys.ny, sys.ny)) if sys.J is None else sys.J @ _T(sys.J)
    return float(mu @ (np.einsum("iab,iba->i", EPbar + EPunder, sys.H @ _T(sys.H))
                       + np.einsum("iab,iba->i", EPunder, K @ JJt @ K.T)))


def bound_3_65(sys, F, K, L, Xbar, Xunder, EPbar, EPunder, mu):
    """Jbar_k of (3.65) with Pbar_k, Punder_k from (3.68)-(3.69) (without the
    constant E_i(omega_{k+1})).
    """
    Pbar, Punder = _step_terms(sys, F, K, L, EPbar, EPunder)
    return _tr(Pbar, Xbar + Xunder) + _tr(Punder, Xbar) + _noise_term(sys, K, EPbar, EPunder, mu)


def functional_b4(sys, F, K, L, Xbar, Xunder, EPbar, EPunder, mu, cross=2.0):
    """Jbar_k as the proof expands it in (B.4) (E_i(P_{k+1} + P_{i,k+1}) read as
    E_i(Pbar + Punder)).

    ``cross`` is the factor of the term 2 E_i(Pbar + Punder) B L Xunder A^T (2 as printed; the
    mutant of the corrected Thm. 3.32 drops it to 1).
    """
    A, B, C, E, U = sys.A, sys.B, sys.C, EPbar, EPunder
    S, BL, KC = Xbar + Xunder, B @ L, K @ C
    terms = (_tr(sys.Q, S) + _tr(L.T @ sys.R @ L, Xunder) + _tr(E + U, A @ S @ _T(A))
             - 2 * _tr(_T(KC) @ U @ A, S) + _tr(U, KC @ S @ _T(KC))
             + cross * _tr(E + U, BL @ Xunder @ _T(A))
             - 2 * _tr(U, BL @ Xunder @ _T(KC)) - 2 * _tr(U, F @ Xunder @ _T(A))
             + 2 * _tr(U, F @ Xunder @ _T(KC))
             - 2 * _tr(U, BL @ Xunder @ F.T) + _tr(E + U, BL @ Xunder @ _T(BL))
             + _tr(U, F @ Xunder @ F.T))
    return terms + _noise_term(sys, K, EPbar, EPunder, mu)


def difference_3_65_b4(sys, F, K, L, Xbar, EPbar, EPunder):
    """sum_i tr[(Z12 + Z21 + 2 Z22) Xbar_i] with Z = Q~ + A~^T [[E(Pbar) + E(Pu), -E(Pu)], [-E(Pu),
    E(Pu)]] A~: the amount by which (3.65) exceeds (B.4) (derived by expanding both).
    """
    n = sys.nx
    At = np.block([[sys.A, np.broadcast_to(sys.B @ L, sys.A.shape)],
                   [K @ sys.C, np.broadcast_to(F, sys.A.shape)]])
    Qt = np.zeros((sys.M, 2 * n, 2 * n))
    Qt[:, :n, :n], Qt[:, n:, n:] = sys.Q, L.T @ sys.R @ L
    Z = Qt + _T(At) @ np.block([[EPbar + EPunder, -EPunder], [-EPunder, EPunder]]) @ At
    _, Z12, Z22 = blocks(Z, n)
    return _tr(Z12 + _T(Z12) + 2 * Z22, Xbar)

