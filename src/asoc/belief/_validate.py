"""Input checks of asoc.belief: ValueError naming the argument, the expected and the found value."""

import numpy as np

SYM_TOL = 1e-9
WEIGHT_TOL = 1e-8


def check_vector(x, name):
    x = np.atleast_1d(np.asarray(x, dtype=float))
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"{name}: expected a non-empty vector, found shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: expected finite entries, found {x}")
    return x


def _square(M, name, n):
    M = np.atleast_2d(np.asarray(M, dtype=float))
    if M.ndim != 2 or M.shape[0] != M.shape[1] or (n is not None and M.shape[0] != n):
        want = f"({n}, {n})" if n is not None else "(n, n)"
        raise ValueError(f"{name}: expected a square matrix of shape {want}, found shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ValueError(f"{name}: expected finite entries, found non-finite entries")
    scale = max(1.0, np.abs(M).max())
    if np.abs(M - M.T).max() > SYM_TOL * scale:
        raise ValueError(f"{name}: expected a symmetric matrix, found asymmetry {np.abs(M - M.T).max():.3g}")
    return 0.5 * (M + M.T)


def check_psd(M, name, n=None):
    """A symmetric positive semi-definite matrix (covariances, Q)."""
    M = _square(M, name, n)
    lam = np.linalg.eigvalsh(M).min()
    if lam < -SYM_TOL * max(1.0, np.abs(M).max()):
        raise ValueError(f"{name}: expected a positive semi-definite matrix, found minimal eigenvalue {lam:.3g}")
    return M


def check_pd(M, name, n=None):
    """A symmetric positive definite matrix (R, Assumption 2.3)."""
    M = _square(M, name, n)
    lam = np.linalg.eigvalsh(M).min()
    if lam <= 0:
        raise ValueError(f"{name}: expected a positive definite matrix, found minimal eigenvalue {lam:.3g}")
    return M


def check_weights(w, m, name):
    """Mixture weights (eq. 2.5): shape (m,), non-negative, summing to one."""
    w = np.asarray(w, dtype=float)
    if w.shape != (m,):
        raise ValueError(f"{name}: expected shape ({m},), found shape {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError(f"{name}: expected non-negative finite weights, found minimum {np.min(w):.3g}")
    if abs(w.sum() - 1.0) > WEIGHT_TOL:
        raise ValueError(f"{name}: expected weights summing to 1, found sum {w.sum():.10g}")
    return w


def check_rng(rng, name="rng"):
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"{name}: expected a seeded numpy.random.Generator, found {type(rng).__name__}")
    return rng
