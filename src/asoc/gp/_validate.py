"""Input checks shared by the distances, kernels and GPs (ValueError naming the argument)."""

import numpy as np

WEIGHT_TOL = 1e-8


def locations(x, name: str) -> np.ndarray:
    """Dirac locations as an ``(M, d)`` float array; a 1-D array is read as ``M`` scalars."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2:
        raise ValueError(f"{name}: expected locations of shape (M, d), found shape {x.shape}")
    if x.shape[0] == 0:
        raise ValueError(f"{name}: expected a non-empty mixture, found 0 components")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: expected finite locations, found non-finite entries")
    return x


def weights(w, m: int, name: str) -> np.ndarray:
    """Mixture weights: ``None`` means equal weights; otherwise non-negative, summing to 1."""
    if w is None:
        return np.full(m, 1.0 / m)
    w = np.asarray(w, dtype=float)
    if w.shape != (m,):
        raise ValueError(f"{name}: expected shape ({m},), found shape {w.shape}")
    if np.any(w < 0):
        raise ValueError(f"{name}: expected non-negative weights, found minimum {w.min():.3g}")
    if abs(w.sum() - 1.0) > WEIGHT_TOL:
        raise ValueError(f"{name}: expected weights summing to 1, found sum {w.sum():.10g}")
    return w


def same_dimension(x, y, names: str):
    if x.shape[-1] != y.shape[-1]:
        raise ValueError(f"{names}: expected mixtures of the same dimension, "
                         f"found {x.shape[-1]} and {y.shape[-1]}")


def mixture_set(X, name: str) -> np.ndarray:
    """A set of equally sized mixtures as ``(N, L, d)``; ``(N, L)`` is read as scalar locations."""
    X = np.asarray(X, dtype=float)
    if X.ndim == 2:
        X = X[:, :, None]
    if X.ndim != 3 or 0 in X.shape:
        raise ValueError(f"{name}: expected a non-empty array of shape (N, L, d), found shape {X.shape}")
    if not np.all(np.isfinite(X)):
        raise ValueError(f"{name}: expected finite locations, found non-finite entries")
    return X


def set_weights(W, shape, name: str) -> np.ndarray:
    """Weights of a mixture set, ``(N, L)``; ``None`` means equal weights."""
    n, m = shape[:2]
    if W is None:
        return np.full((n, m), 1.0 / m)
    W = np.asarray(W, dtype=float)
    if W.shape != (n, m):
        raise ValueError(f"{name}: expected shape ({n}, {m}), found shape {W.shape}")
    if np.any(W < 0):
        raise ValueError(f"{name}: expected non-negative weights, found minimum {W.min():.3g}")
    sums = W.sum(axis=1)
    if np.any(np.abs(sums - 1.0) > WEIGHT_TOL):
        bad = sums[np.argmax(np.abs(sums - 1.0))]
        raise ValueError(f"{name}: expected each row of weights to sum to 1, found a sum {bad:.10g}")
    return W


def covariance(C, name: str) -> np.ndarray:
    """A symmetric positive semi-definite covariance as an ``(n, n)`` array (scalars allowed)."""
    C = np.atleast_2d(np.asarray(C, dtype=float))
    if C.ndim != 2 or C.shape[0] != C.shape[1]:
        raise ValueError(f"{name}: expected a square matrix, found shape {C.shape}")
    if not np.allclose(C, C.T, rtol=1e-10, atol=1e-12):
        raise ValueError(f"{name}: expected a symmetric matrix, found asymmetry "
                         f"{np.max(np.abs(C - C.T)):.3g}")
    lam_min = np.linalg.eigvalsh(C).min()
    if lam_min < -1e-10 * max(1.0, np.abs(C).max()):
        raise ValueError(f"{name}: expected a positive semi-definite matrix, "
                         f"found smallest eigenvalue {lam_min:.3g}")
    return C


def positive(value, name: str) -> float:
    value = float(value)
    if not value > 0 or not np.isfinite(value):
        raise ValueError(f"{name}: expected a positive finite number, found {value!r}")
    return value


def at_least_one(value, name: str) -> float:
    value = float(value)
    if not value >= 1 or not np.isfinite(value):
        raise ValueError(f"{name}: expected a finite number >= 1, found {value!r}")
    return value
