"""The second-moment bounds of Prop. 3.26 / Thm. 3.31 that Algorithms 3.2 and 3.3 iterate.

With the controller (3.37), the second moment of x~ = [x; x^] is replaced by the two blocks

    Xbar_i  ~ E{(x - x^)(x - x^)^T 1(theta = i)}   (estimation error, (3.44)),
    Xunder_i ~ E{x^ x^^T 1(theta = i)}              (controller state),

and the Lagrange multiplier by Pbar_i, Punder_i; one step of each recursion is
(3.45)-(3.48) (infinite horizon) or (3.66)-(3.69) (finite horizon).
"""

import numpy as np

from ..linalg import sym, transpose
from ..validation import generator
from .system import predecessor_sum

__all__ = ["bound_moment_step", "bound_costate_step", "initial_bounds", "bound_cost"]


def bound_moment_step(sys, F, K, L, Xbar, Xunder, mu, HHt, JJt):
    """One step of the second-moment bounds, (3.45)-(3.46) / (3.66)-(3.67).

    An inner-loop helper of Algs. 3.2-3.3: its arguments are not validated.

    Returns (Xbar_next, Xunder_next), each (M, nx, nx).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> from asoc.mjls.closed_loops import noise_covariances
    >>> HHt, JJt = noise_covariances(sys)
    >>> Z = np.zeros((2, 2, 2))
    >>> Xbar, Xunder = bound_moment_step(sys, np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)), Z, Z,
    ...                                  sys.mu_inf, HHt, JJt)
    >>> noise = sys.predecessor_sum(sys.mu_inf[:, None, None] * HHt)
    >>> np.allclose(Xbar, noise), np.abs(Xunder).max()
    (True, np.float64(0.0))
    """
    KC = K @ sys.C
    AKC = sys.A - KC
    G = AKC - F + sys.B @ L                       # A_i - F + B_i L - K C_i
    FKC = F + KC
    KJJK = K @ JJt @ K.T
    m = mu[:, None, None]
    Xbar_in = m * (HHt + KJJK) + AKC @ Xbar @ transpose(AKC) + G @ Xunder @ transpose(G)
    Xunder_in = m * KJJK + KC @ Xbar @ transpose(KC) + FKC @ Xunder @ transpose(FKC)
    Xbar_new = predecessor_sum(sys.T, Xbar_in, check=False)
    Xunder_new = predecessor_sum(sys.T, Xunder_in, check=False)
    return sym(Xbar_new), sym(Xunder_new)


def bound_costate_step(sys, F, K, L, EPbar, EPunder):
    """One step of the multiplier bounds, (3.47)-(3.48) / (3.68)-(3.69).

    An inner-loop helper of Algs. 3.2-3.3: its arguments are not validated.

    ``EPbar``, ``EPunder`` are E_i(Pbar), E_i(Punder) of the next step. Returns (Pbar, Punder).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> Z = np.zeros((2, 2, 2))
    >>> Pbar, Punder = bound_costate_step(sys, np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)), Z, Z)
    >>> np.allclose(Pbar, sys.Q), np.abs(Punder).max()
    (True, np.float64(0.0))
    """
    BL = sys.B @ L
    ABL = sys.A + BL
    G = ABL - F - K @ sys.C
    FBL = F - BL
    LRL = L.T @ sys.R @ L
    Pbar = sys.Q + LRL + transpose(ABL) @ EPbar @ ABL + transpose(G) @ EPunder @ G
    Punder = LRL + transpose(BL) @ EPbar @ BL + transpose(FBL) @ EPunder @ FBL
    return sym(Pbar), sym(Punder)


def initial_bounds(sys, init, rng):
    """Step 1 of Alg. 3.2: Xbar, Xunder, Pbar, Punder at init * I (rng None, as the author's
    reference code), or random symmetric positive definite matrices of that scale.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> [float(B[0, 0, 0]) for B in initial_bounds(sec373_system(1), 1e-4, None)]
    [0.0001, 0.0001, 0.0001, 0.0001]
    """
    M, n = sys.M, sys.nx
    if rng is None:
        return [np.broadcast_to(init * np.eye(n), (M, n, n)).copy() for _ in range(4)]
    generator(rng, "rng")
    out = []
    for _ in range(4):
        G = rng.standard_normal((M, n, n))
        out.append(init * (G @ transpose(G) / n + np.eye(n)))
    return out


def bound_cost(sys, L, Xbar, Xunder):
    """sum_i tr[Q_i (Xbar_i + Xunder_i) + L^T R_i L Xunder_i]: the cost of the bounded second
    moment of Prop. 3.26 that Alg. 3.2 minimises (not always an upper bound of the true cost).

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> I = np.broadcast_to(np.eye(2), (2, 2, 2))
    >>> bound_cost(sys, np.zeros((1, 2)), I, I) == 2 * float(np.trace(sys.Q.sum(axis=0)))
    True
    """
    LRL = transpose(L) @ sys.R @ L
    return float(np.einsum("iab,iba->", sys.Q, Xbar + Xunder) + np.einsum("iab,iba->", LRL, Xunder))
