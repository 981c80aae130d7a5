"""Optimal-transport distances (Sec. 2.6.3, item 4): Gaussian Wasserstein-2, OMAT (2.23), OSPA.

Wasserstein-2 has a closed form between Gaussians (:func:`wasserstein_gaussian`,
:func:`wasserstein_gaussian_matrix`); between equally weighted Dirac mixtures it is the OMAT
distance (:func:`omat`, :func:`omat_matrix`), a linear assignment problem, and the OSPA
metric (:func:`ospa`, :func:`ospa_matrix`) extends it to different numbers of components.
"""

import numpy as np
from scipy.optimize import linear_sum_assignment

from .. import validation as check
from ..progress import progress_bar
from . import mixture_checks as v

__all__ = ["wasserstein_gaussian", "wasserstein_gaussian_matrix", "omat", "omat_matrix", "ospa",
           "ospa_matrix"]


def _sqrtm_psd(C):
    """Principal square root of a (stack of) symmetric PSD matrices."""
    lam, U = np.linalg.eigh(C)
    return (U * np.sqrt(np.clip(lam, 0.0, None))[..., None, :]) @ np.swapaxes(U, -1, -2)


def wasserstein_gaussian(m1, C1, m2, C2) -> float:
    r"""Wasserstein-2 distance between two Gaussians (closed form [75], Sec. 2.6.3, item 4).

    :math:`d_2^2 = \|\underline\mu_1 - \underline\mu_2\|^2 + \mathrm{tr}\,\mathbf C_1 +
    \mathrm{tr}\,\mathbf C_2 -
    2\,\mathrm{tr}\sqrt{\sqrt{\mathbf C_1}\mathbf C_2\sqrt{\mathbf C_1}}`.
    Continuous/continuous (Gaussian) pairs only.

    Parameters
    ----------
    m1 : array_like, (d,)
        Mean of the first Gaussian.
    C1 : array_like, (d, d)
        Its covariance, symmetric positive semidefinite.
    m2 : array_like, (d,)
        Mean of the second Gaussian.
    C2 : array_like, (d, d)
        Its covariance, symmetric positive semidefinite.

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If a covariance is not symmetric PSD or the dimensions do not match.

    Examples
    --------
    >>> wasserstein_gaussian([0.0], [[1.0]], [3.0], [[4.0]])     # sqrt(3^2 + (2 - 1)^2)
    3.1622776601683795
    """
    m1, m2 = check.vector(m1, "m1"), check.vector(m2, "m2")
    C1, C2 = v.covariance(C1, "C1"), v.covariance(C2, "C2")
    if not (m1.shape == m2.shape and C1.shape == C2.shape == (len(m1), len(m1))):
        raise ValueError(f"m1, C1, m2, C2: expected matching dimensions, found means "
                         f"{m1.shape}, {m2.shape} and covariances {C1.shape}, {C2.shape}")
    S1 = _sqrtm_psd(C1)
    cross = _sqrtm_psd(S1 @ C2 @ S1)
    d2 = np.sum((m1 - m2) ** 2) + np.trace(C1) + np.trace(C2) - 2 * np.trace(cross)
    return float(np.sqrt(max(d2, 0.0)))


def wasserstein_gaussian_matrix(means_i, covs_i, means_j=None, covs_j=None) -> np.ndarray:
    r"""Pairwise Wasserstein-2 distances between sets of Gaussians (:func:`wasserstein_gaussian`).

    Parameters
    ----------
    means_i, covs_i : array_like, (N, d) and (N, d, d)
        Means and symmetric PSD covariances (for d = 1 also (N,) and (N,)).
    means_j, covs_j : array_like, (M, d) and (M, d, d), optional
        The second set; ``None``: the first (a symmetric matrix with zero diagonal).

    Returns
    -------
    numpy.ndarray, (N, M)

    Raises
    ------
    ValueError, TypeError
        If a covariance is not symmetric PSD or the shapes do not match.

    Examples
    --------
    >>> wasserstein_gaussian_matrix([0.0, 3.0], [1.0, 4.0]).round(4).tolist()
    [[0.0, 3.1623], [3.1623, 0.0]]
    """
    mi, Ci = v.gaussian_set(means_i, covs_i, "means_i", "covs_i")
    symmetric = means_j is None and covs_j is None
    mj, Cj = (mi, Ci) if symmetric else v.gaussian_set(means_j, covs_j, "means_j", "covs_j")
    if mj.shape[1] != mi.shape[1]:
        raise ValueError("means_i, means_j: expected Gaussians of the same dimension, "
                         f"found {mi.shape[1]} and {mj.shape[1]}")
    Si = _sqrtm_psd(Ci)
    cross = np.linalg.eigvalsh(Si[:, None] @ Cj[None] @ Si[:, None])               # (N, M, d)
    d2 = (np.sum((mi[:, None] - mj[None]) ** 2, axis=-1) + np.trace(Ci, axis1=1, axis2=2)[:, None]
          + np.trace(Cj, axis1=1, axis2=2)[None]
          - 2 * np.sqrt(np.clip(cross, 0.0, None)).sum(axis=-1))
    out = np.sqrt(np.clip(d2, 0.0, None))
    if symmetric:
        np.fill_diagonal(out, 0.0)
        out = 0.5 * (out + out.T)
    return out


def _omat_cost(x, y, q):
    return np.sum((x[:, None, :] - y[None, :, :]) ** 2, axis=-1) ** (q / 2)


def omat(x, y, q: float = 2) -> float:
    r"""OMAT distance between two equally weighted Dirac mixtures, eq. (2.23).

    :math:`d_q = \min_{\pi} (\tfrac1m \sum_i d_e(\underline x_i, \underline y_{\pi,i})^q)^{1/q}`,
    solved exactly as a linear assignment problem ([100];
    ``scipy.optimize.linear_sum_assignment``). Dirac/Dirac pairs with the same number
    of equally weighted components; use :func:`ospa` for different numbers.

    Parameters
    ----------
    x, y : array_like, (m, d) or (m,)
        Locations of the two mixtures (same number of components).
    q : float
        Order, 1 <= q <= 100.

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If the mixtures are invalid, of different dimensions or sizes, or ``q`` outside [1, 100].

    Examples
    --------
    >>> round(omat([0.0, 1.0], [1.1, 0.1]), 6)     # the assignment pairs 0 with 0.1 and 1 with 1.1
    0.1
    """
    x, y = v.locations(x, "x"), v.locations(y, "y")
    v.same_dimension(x, y, "x, y")
    q = v.order(q, "q")
    if len(x) != len(y):
        raise ValueError(f"x, y: expected the same number of components (OMAT), found {len(x)} and "
                         f"{len(y)} (use ospa)")
    cost = _omat_cost(x, y, q)
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].mean() ** (1 / q))


def omat_matrix(X, Y=None, q: float = 2, progress: bool = False) -> np.ndarray:
    """Pairwise OMAT distances between two sets of equally weighted mixtures, (N, M).

    The cost matrices are built vectorised per row; each pair is one linear assignment. For
    scalar locations (d = 1) and ``q > 1`` the monotone matching, sorted to sorted, is the
    optimal assignment of the strictly convex costs :math:`|x - y|^q` (unique for distinct
    locations; e.g. Villani, "Topics in Optimal Transportation", 2003, Sec. 2.2) and replaces
    the linear assignments.
    ``Y=None`` computes the symmetric matrix of ``X`` with itself (upper triangle only).

    Parameters
    ----------
    X : array_like, (N, m, d) or (N, m)
    Y : array_like, (M, m, d) or (M, m), optional
        None: ``X`` with itself.
    q : float
        Order, 1 <= q <= 100.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    numpy.ndarray, (N, M)

    Raises
    ------
    ValueError, TypeError
        If the sets are invalid, of different dimensions or numbers of components, or ``q``
        outside [1, 100].

    Examples
    --------
    >>> omat_matrix(np.array([[0.0, 1.0], [0.0, 2.0]])).tolist()
    [[0.0, 0.7071067811865476], [0.7071067811865476, 0.0]]
    """
    X = v.mixture_set(X, "X")
    symmetric = Y is None
    Y = X if symmetric else v.mixture_set(Y, "Y")
    v.same_dimension(X, Y, "X, Y")
    q = v.order(q, "q")
    progress = check.boolean(progress, "progress")
    if X.shape[1] != Y.shape[1]:
        raise ValueError(f"X, Y: expected the same number of components (OMAT), found {X.shape[1]} "
                         f"and {Y.shape[1]}")
    rows = progress_bar(range(len(X)), progress, desc="OMAT", leave=False)
    if X.shape[2] == 1 and q > 1:
        out = _mean_sorted_matching_costs(X[..., 0], Y[..., 0], q, symmetric, rows)
    else:
        out = _mean_optimal_assignment_costs(X, Y, q, symmetric, rows)
    out = out ** (1 / q)
    return out + out.T if symmetric else out


def _mean_optimal_assignment_costs(X, Y, q, symmetric, rows):
    """Mean cost (N, M) of the optimal assignment of every pair (upper triangle if symmetric)."""
    out = np.zeros((len(X), len(Y)))
    for i in rows:
        j0 = i + 1 if symmetric else 0
        costs = np.sum((X[i][None, :, None, :] - Y[j0:, None, :, :]) ** 2, axis=-1) ** (q / 2)
        out[i, j0:] = _mean_assignment_costs(costs)
    return out


def _mean_sorted_matching_costs(x, y, q, symmetric, rows):
    """``_mean_optimal_assignment_costs`` of scalar locations ``x`` (N, m), ``y`` (M, m) by sorting:
    each location is matched with the location of the same rank in its partner.
    """
    x_sorted, y_sorted = np.sort(x, axis=1), np.sort(y, axis=1)
    out = np.zeros((len(x), len(y)))
    for i in rows:
        j0 = i + 1 if symmetric else 0
        out[i, j0:] = (np.abs(x_sorted[i] - y_sorted[j0:]) ** q).mean(axis=-1)
    return out


def _mean_assignment_costs(costs):
    """The mean cost of the optimal assignment of each square cost matrix of ``costs`` (K, m, m)."""
    K, m = costs.shape[:2]
    cols = np.array([linear_sum_assignment(cost)[1] for cost in costs], dtype=np.intp).reshape(K, m)
    return costs[np.arange(K)[:, None], np.arange(m), cols].mean(axis=-1)


def ospa(x, y, c: float, p: float = 2) -> float:
    r"""OSPA metric of Schuhmacher, Vo and Vo [139] for different numbers of components.

    For :math:`m \le n` components, :math:`d = (\tfrac1n(\min_\pi \sum_{i=1}^m
    d^{(c)}(\underline x_i, \underline y_{\pi(i)})^p + c^p (n - m)))^{1/p}` with the cut-off
    distance :math:`d^{(c)} = \min(c, d_e)`. Equal numbers and ``c`` larger than every
    distance give the OMAT distance (2.23). Dirac/Dirac pairs, equally weighted.

    Parameters
    ----------
    x, y : array_like, (m, d) and (n, d)
        Locations (equally weighted).
    c : float
        Cut-off distance, > 0.
    p : float
        Order, 1 <= p <= 100.

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If the mixtures are invalid or of different dimensions, ``c`` <= 0 or ``p`` outside
        [1, 100].

    Examples
    --------
    >>> ospa([0.0], [0.0, 5.0], c=2.0)     # one unmatched component at the cut-off
    1.4142135623730951
    """
    x, y = v.locations(x, "x"), v.locations(y, "y")
    v.same_dimension(x, y, "x, y")
    c, p = v.positive(c, "c"), v.order(p, "p")
    return _ospa(x, y, c, p)


def _ospa(x, y, c, p):
    if len(x) > len(y):
        x, y = y, x
    m, n = len(x), len(y)
    cost = np.minimum(np.sqrt(np.sum((x[:, None] - y[None]) ** 2, axis=-1)), c) ** p
    rows, cols = linear_sum_assignment(cost)
    return float(((cost[rows, cols].sum() + c**p * (n - m)) / n) ** (1 / p))


def ospa_matrix(X, Y=None, c: float = 1.0, p: float = 2, progress: bool = False) -> np.ndarray:
    """Pairwise OSPA distances (:func:`ospa`) between sets of equally weighted mixtures, any sizes.

    Parameters
    ----------
    X : sequence of array_like, each (m_i, d) or (m_i,)
        Locations of the mixtures (their numbers of components may differ).
    Y : sequence of array_like, optional
        The second set; ``None``: ``X`` (a symmetric matrix with zero diagonal, upper
        triangle computed).
    c : float
        Cut-off distance, > 0.
    p : float
        Order, 1 <= p <= 100.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    numpy.ndarray, (len(X), len(Y))

    Raises
    ------
    ValueError, TypeError
        If a mixture is invalid, the dimensions differ, ``c`` <= 0 or ``p`` outside [1, 100].

    Examples
    --------
    >>> ospa_matrix([[0.0], [0.0, 5.0], [1.0]], c=2.0).round(4).tolist()
    [[0.0, 1.4142, 1.0], [1.4142, 0.0, 1.5811], [1.0, 1.5811, 0.0]]
    """
    check.instance(X, (list, tuple, np.ndarray), "X", "a sequence of mixtures")
    symmetric = Y is None
    if not symmetric:
        check.instance(Y, (list, tuple, np.ndarray), "Y", "a sequence of mixtures")
    xs = [v.locations(x, f"X[{i}]") for i, x in enumerate(X)]
    ys = xs if symmetric else [v.locations(y, f"Y[{j}]") for j, y in enumerate(Y)]
    if not xs or not ys:
        raise ValueError("X, Y: expected non-empty sequences of mixtures, "
                         f"found {len(xs)} and {len(ys)}")
    for j, y in enumerate(ys):
        v.same_dimension(xs[0], y, f"X[0], {'X' if symmetric else 'Y'}[{j}]")
    c, p = v.positive(c, "c"), v.order(p, "p")
    progress = check.boolean(progress, "progress")
    out = np.zeros((len(xs), len(ys)))
    for i in progress_bar(range(len(xs)), progress, desc="OSPA", leave=False):
        for j in range(i + 1 if symmetric else 0, len(ys)):
            out[i, j] = _ospa(xs[i], ys[j], c, p)
    return out + out.T if symmetric else out
