"""Alg. 3.1 as printed, in plain NumPy: the reference the benchmarks compare the library with.

Not part of the library (which holds one implementation of each algorithm): it is the
straightforward transcription a reader would write from the thesis, kept here to measure
what the library's moment updates gain.
"""

import numpy as np

from asoc.mjls import closed_loop
from asoc.mjls.static import gain_from_moments
from asoc.mjls.system import predecessor_sum, successor_average


def thesis_iteration(sys, tol=1e-10, max_iter=20000, init=1e-4):
    """Alg. 3.1, eqs. (3.34)-(3.35), as printed: X^i = P^i = init I; L from (3.34); one step of
    each recursion (3.35); stop when L changes by less than tol (relative). Returns L."""
    X = np.broadcast_to(init * np.eye(sys.nx), (sys.M, sys.nx, sys.nx)).copy()
    P = X.copy()
    muHHt = sys.mu_inf[:, None, None] * (sys.H @ np.swapaxes(sys.H, 1, 2))
    L = np.zeros((sys.nu, sys.ny))
    for _ in range(max_iter):
        L_new = gain_from_moments(sys, X, P)
        Acl = closed_loop(sys, L_new)
        LC = L_new @ sys.C
        X, P = (
            predecessor_sum(sys.T, Acl @ X @ np.swapaxes(Acl, 1, 2) + muHHt),
            sys.Q
            + np.swapaxes(LC, 1, 2) @ sys.R @ LC
            + np.swapaxes(Acl, 1, 2) @ successor_average(sys.T, P) @ Acl,
        )
        done = np.linalg.norm(L_new - L) <= tol * np.linalg.norm(L_new)
        L = L_new
        if done:
            break
    return L
