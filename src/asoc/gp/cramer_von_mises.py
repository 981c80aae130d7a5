"""Modified Cramer-von Mises distance (Sec. 2.6.3, item 5) by localized cumulative distributions.

Closed form between Dirac mixtures (:func:`mcvmd`, :func:`mcvmd_matrix`), the localized
cumulative distributions of Dirac mixtures and Gaussians (:func:`lcd_dirac`,
:func:`lcd_gaussian`) and the distance from its definition by quadrature
(:func:`mcvmd_quadrature`) for any pair of 1-D distributions. Dirac mixtures are locations
``x`` of shape ``(M, d)`` (a 1-D array is read as ``M`` scalar locations) with weights ``wx``
of shape ``(M,)`` (``None``: equal weights); sets of mixtures are arrays of shape ``(N, L, d)``.
"""

import numpy as np
from scipy import integrate
from scipy.special import xlogy

from .. import config
from .. import validation as check
from ..progress import progress_bar
from . import mixture_checks as v

__all__ = ["EULER_GAMMA", "DEFAULT_B_MAX", "ROUNDING_RTOL", "mcvmd_constant", "mcvmd",
           "mcvmd_matrix", "lcd_dirac",
           "lcd_gaussian", "mcvmd_quadrature"]


EULER_GAMMA = float(np.euler_gamma)
#: The "large constant" b_max of the mCvMd's kernel widths (Sec. 2.6.3, item 5).
DEFAULT_B_MAX = 100.0
ROUNDING_RTOL = 1e-9
"""A closed-form square below 0 by at most this share of its terms' magnitudes is rounding."""


def mcvmd_constant(b_max: float) -> float:
    r"""The constant :math:`c_b` of the mCvMd's closed form at large ``b_max`` (Sec. 2.6.3, 5).

    Integrating the definition, :math:`\int_0^{b_{\max}} w(b) \int (P_1 - P_2)^2\,dm\,db`,
    term by term with the LCD kernel of Sec. 2.6.3 gives
    :math:`c_b = \log(4 b_{\max}^2) - \Gamma + 1` (expansion of
    :math:`\int_0^{S} e^{-a/s} ds = S e^{-a/S} - a E_1(a/S)` for large :math:`S = b_{\max}^2`).
    The thesis prints :math:`c_b = \log(4 b_{\max}^2) - \Gamma`, i.e. the same expression with
    :math:`b_{\max}` replaced by :math:`b_{\max} e^{-1/2}`; since :math:`b_{\max}` is a free
    "large constant", both are the same family of distances. We keep the constant that
    matches the definition (checked against quadrature in the tests).

    Parameters
    ----------
    b_max : float
        Upper limit of the kernel widths, a "large constant".

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If ``b_max`` is not a positive finite number.

    Examples
    --------
    >>> round(mcvmd_constant(100.0), 4)     # log(4 b_max^2) - Gamma + 1
    11.0194
    """
    b_max = v.positive(b_max, "b_max")
    return float(np.log(4.0 * b_max**2) - EULER_GAMMA + 1.0)


def _xlog_sq(a, b):
    """``xlog(|a - b|^2)`` over the last axis, with xlog(0) = 0."""
    sq = np.sum((a - b) ** 2, axis=-1)
    return xlogy(sq, sq)


def mcvmd(x, wx, y, wy, b_max: float = DEFAULT_B_MAX) -> float:
    r"""Modified Cramer-von Mises distance between two Dirac mixtures (Sec. 2.6.3, item 5).

    Closed form for large ``b_max`` ([81], thesis Sec. 2.6.3):
    :math:`d = \big(\tfrac{\pi^{n_x/2}}{8}(D_1 - 2 D_{12} + D_2 + 2 c_b D_m)\big)^{1/2}`
    with :math:`D_1, D_2, D_{12}` the weighted sums of ``xlog`` of squared distances and
    :math:`D_m` the squared distance of the means; :math:`c_b` see :func:`mcvmd_constant`.
    Accepts Dirac/Dirac pairs with any numbers of components and weights.

    Parameters
    ----------
    x : array_like, (M, d) or (M,)
        Locations of the first mixture.
    wx : array_like (M,) or None
        Its weights (non-negative, summing to 1); ``None`` for equal weights.
    y, wy : array_like
        The second mixture, (L, d) and (L,).
    b_max : float
        Upper limit of the kernel widths, a "large constant".

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If locations are empty, non-finite or of different dimensions, weights are negative,
        of the wrong shape or do not sum to 1, or ``b_max`` is too small for the closed form
        (its square negative beyond rounding).

    Examples
    --------
    >>> round(mcvmd([0.0, 1.0], None, [0.5], None), 4)
    0.3919
    >>> mcvmd([0.0, 1.0], [0.5, float("nan")], [0.5], None)
    Traceback (most recent call last):
    ...
    ValueError: wx: expected finite entries, found 1 non-finite
    """
    x, y = v.locations(x, "x"), v.locations(y, "y")
    v.same_dimension(x, y, "x, y")
    wx, wy = v.weights(wx, len(x), "wx"), v.weights(wy, len(y), "wy")
    cb = mcvmd_constant(b_max)
    D1 = wx @ _xlog_sq(x[:, None], x[None]) @ wx
    D2 = wy @ _xlog_sq(y[:, None], y[None]) @ wy
    D12 = wx @ _xlog_sq(x[:, None], y[None]) @ wy
    Dm = float(np.sum((wx @ x - wy @ y) ** 2))
    terms = np.array([D1, -2 * D12, D2, 2 * cb * Dm])
    return float(_root_of_square(np.sum(terms), np.sum(np.abs(terms)), x.shape[1], b_max))


def mcvmd_matrix(X, Y=None, WX=None, WY=None, b_max: float = DEFAULT_B_MAX,
                 chunk: int = 8, progress: bool = False) -> np.ndarray:
    """Pairwise mCvMd between two sets of Dirac mixtures (vectorised :func:`mcvmd`).

    Mixtures of ``X`` are handled in chunks: the weighted sums of ``xlog`` of squared
    distances of a chunk against all of ``Y`` are one vectorised expression. Those sums do not
    depend on ``b_max``: a sequence of values gives the matrices of all of them at the cost of one.

    Parameters
    ----------
    X : array_like, (N, L, d) or (N, L)
        ``N`` mixtures with ``L`` components each.
    Y : array_like, (M, K, d) or (M, K), optional
        Second set; ``None`` means ``X`` (a symmetric matrix with zero diagonal).
    WX, WY : array_like (N, L) / (M, K) or None
        Weights; ``None`` for equal weights.
    b_max : float or sequence of float
        Upper limit of the kernel widths; a sequence gives one matrix per value.
    chunk : int
        Number of mixtures of ``X`` handled per vectorised block (memory ~ chunk*M*L*K).
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    ndarray, (N, M), or (len(b_max), N, M) for a sequence ``b_max``

    Raises
    ------
    ValueError, TypeError
        If the sets are empty, non-finite or of different dimensions, a weight row is
        invalid, or a ``b_max`` is not a positive number or too small for the closed form.

    Examples
    --------
    >>> D = mcvmd_matrix(np.array([[0.0, 1.0], [0.5, 0.5], [2.0, 3.0]]))
    >>> D.round(3).tolist()
    [[0.0, 0.392, 4.014], [0.392, 0.0, 4.073], [4.014, 4.073, 0.0]]
    >>> X = np.array([[0.0, 1.0], [2.0, 3.0]])
    >>> mcvmd_matrix(X, b_max=[10.0, 100.0])[:, 0, 1].round(3).tolist()
    [2.82, 4.014]
    """
    X = v.mixture_set(X, "X")
    WX = v.set_weights(WX, X.shape, "WX")
    symmetric = Y is None
    Y = X if symmetric else v.mixture_set(Y, "Y")
    WY = WX if symmetric else v.set_weights(WY, Y.shape, "WY")
    v.same_dimension(X, Y, "X, Y")
    several = np.ndim(b_max) == 1
    if several and len(b_max) == 0:
        raise ValueError("b_max: expected a positive number or a non-empty sequence of them, "
                         "found an empty sequence")
    constants = [mcvmd_constant(value) for value in (b_max if several else [b_max])]
    chunk = check.integer(chunk, "chunk", minimum=1)
    progress = check.boolean(progress, "progress")
    sums = _mcvmd_sums(X, WX, Y, WY, symmetric, chunk, progress)
    widths = b_max if several else [b_max]
    out = [_combined(sums, cb, X.shape[2], symmetric, b) for cb, b in zip(constants, widths)]
    return np.stack(out) if several else out[0]


def _root_of_square(square, scale, d, b_max):
    """The root of the closed form's (pi^(d/2) / 8) (D1 - 2 D12 + D2 + 2 c_b Dm).

    Rounding below 0 gives 0. A square negative beyond rounding (relative to ``scale``, the
    sum of the terms' magnitudes) means ``b_max`` is too small for the large-``b_max``
    expansion.
    """
    square, scale = np.asarray(square, dtype=float), np.asarray(scale, dtype=float)
    if np.any(square < -ROUNDING_RTOL * scale):
        worst = float(np.min(square / np.maximum(scale, np.finfo(float).tiny)))
        raise ValueError(f"b_max: expected a width large against the distances between the Dirac "
                         f"locations (the closed form holds for large b_max; its square is "
                         f"{worst:.2g} of its terms), found {b_max}")
    return np.sqrt(np.clip(square, 0.0, None) * np.pi ** (d / 2) / 8)


def _combined(sums, cb, d, symmetric, b_max):
    """The mCvMd matrix from the b_max-independent sums of ``_mcvmd_sums`` and the constant c_b."""
    D1, D2, D12, Dm = sums
    terms = (D1[:, None], -2 * D12, D2[None], 2 * cb * Dm)
    scale = sum(np.abs(t) for t in terms)
    out = _root_of_square(sum(terms), scale, d, b_max)
    if symmetric:
        np.fill_diagonal(out, 0.0)
        out = 0.5 * (out + out.T)
    return out


def _mcvmd_sums(X, WX, Y, WY, symmetric, chunk, progress):
    """The weighted sums of :func:`mcvmd_matrix`: D1 (N,), D2 (M,), D12 and Dm (N, M)."""
    D1 = np.einsum("na,nab,nb->n", WX, _xlog_sq(X[:, :, None], X[:, None]), WX)
    D2 = D1 if symmetric else np.einsum("ma,mab,mb->m", WY, _xlog_sq(Y[:, :, None], Y[:, None]), WY)
    mx, my = np.einsum("na,nad->nd", WX, X), np.einsum("ma,mad->md", WY, Y)
    D12, Dm = np.empty((len(X), len(Y))), np.empty((len(X), len(Y)))
    for start in progress_bar(range(0, len(X), chunk), progress, desc="mCvMd", leave=False):
        sl = slice(start, start + chunk)
        xl = _xlog_sq(X[sl, None, :, None], Y[None, :, None, :])          # (c, M, L, K)
        D12[sl] = np.einsum("ca,cmab,mb->cm", WX[sl], xl, WY)
        Dm[sl] = np.sum((mx[sl, None] - my[None]) ** 2, axis=-1)
    return D1, D2, D12, Dm


def lcd_dirac(x, wx, m, b) -> np.ndarray:
    r"""Localized cumulative distribution of a Dirac mixture, :math:`P(\underline m, b)`.

    :math:`P(\underline m, b) =
    \sum_i w_i \exp(-\tfrac12 \|\underline x_i - \underline m\|^2 / b^2)`
    (Sec. 2.6.3, LCD with the radial basis kernel). ``m``: (K, d) evaluation points,
    ``b``: scalar or (K,) widths. Returns (K,).

    Parameters
    ----------
    x : array_like, (M, d) or (M,)
        Dirac locations.
    wx : array_like (M,) or None
        Weights (None: equal).
    m : array_like, (K, d)
        Evaluation points.
    b : float or array_like (K,)
        Kernel widths.

    Returns
    -------
    numpy.ndarray, (K,)

    Raises
    ------
    ValueError, TypeError
        If locations or weights are invalid or the dimensions of ``x`` and ``m`` differ.

    Examples
    --------
    >>> lcd_dirac([0.0, 1.0], None, [[0.0]], 1.0).round(4).tolist()
    [0.8033]
    """
    x = v.locations(x, "x")
    wx = v.weights(wx, len(x), "wx")
    m = v.locations(m, "m")
    v.same_dimension(x, m, "x, m")
    b = v.widths(b, len(m))
    sq = np.sum((m[:, None, :] - x[None]) ** 2, axis=-1)
    return np.exp(-0.5 * sq / b[:, None] ** 2) @ wx


def lcd_gaussian(mean, cov, m, b) -> np.ndarray:
    r"""LCD of a Gaussian :math:`\mathcal N(\underline\mu, \mathbf C)` (closed form).

    :math:`P(\underline m, b) = b^{n}\det(\mathbf C + b^2\mathbf I)^{-1/2}
    \exp(-\tfrac12 (\underline m - \underline\mu)^\top (\mathbf C + b^2 \mathbf I)^{-1}
    (\underline m - \underline\mu))`. ``m``: (K, d), ``b``: scalar or (K,). Returns (K,).

    Parameters
    ----------
    mean : array_like, (d,)
    cov : array_like, (d, d)
        Symmetric positive semidefinite covariance.
    m : array_like, (K, d)
        Evaluation points.
    b : float or array_like (K,)
        Kernel widths.

    Returns
    -------
    numpy.ndarray, (K,)

    Raises
    ------
    ValueError, TypeError
        If ``cov`` is not symmetric PSD or the dimensions do not match.

    Examples
    --------
    >>> lcd_gaussian([0.0], [[1.0]], [[0.0]], 1.0).round(4).tolist()     # b / sqrt(1 + b^2)
    [0.7071]
    """
    mean = check.vector(mean, "mean")
    C = v.covariance(cov, "cov")
    m = v.locations(m, "m")
    if C.shape[0] != len(mean) or m.shape[1] != len(mean):
        raise ValueError(f"mean, cov, m: expected dimension {len(mean)}, "
                         f"found cov {C.shape} and m {m.shape}")
    b = v.widths(b, len(m))
    n = len(mean)
    S = C[None] + b[:, None, None] ** 2 * np.eye(n)[None]
    r = m - mean
    quad = np.einsum("ki,ki->k", r, np.linalg.solve(S, r[..., None])[..., 0])
    return b**n / np.sqrt(np.linalg.det(S)) * np.exp(-0.5 * quad)


def mcvmd_quadrature(lcd1, lcd2, b_max: float = DEFAULT_B_MAX, center: float = 0.0,
                     spread: float = 1.0, points=(), n_m: int = 400) -> float:
    r"""MCvMd from its definition by numerical quadrature (1-D; any pair of distributions).

    :math:`d = (\int_0^{b_{\max}} \int w(b) (P_1(m, b) - P_2(m, b))^2\,dm\,db)^{1/2}` with
    :math:`w(b) = 1` in one dimension (Sec. 2.6.3). ``lcd1``, ``lcd2`` are callables
    ``P(m, b)`` taking ``m`` of shape (K, 1) and a scalar ``b``, e.g. built from
    :func:`lcd_dirac` or :func:`lcd_gaussian`; so this evaluates continuous/continuous,
    continuous/Dirac and Dirac/Dirac pairs alike. The outer integral is adaptive
    (``scipy.integrate.quad``); the inner one is a composite Gauss-Legendre rule over
    ``center +- (spread + 12 b)``, outside of which both LCDs agree to double precision
    when the distributions' mass lies within ``center +- spread``; ``points`` (the Dirac
    locations) get extra panel edges at ``point + k b``, ``|k| <= 8``, so the narrow LCD
    bumps of small ``b`` are resolved.

    Parameters
    ----------
    lcd1, lcd2 : callable
        ``P(m, b)`` of the two distributions.
    b_max : float
        Upper limit of the kernel widths.
    center, spread : float
        Where the distributions' mass lies (center +- spread).
    points : sequence of float
        Dirac locations that need extra panel edges.
    n_m : int
        Gauss-Legendre nodes of the inner integral.

    Returns
    -------
    float

    Raises
    ------
    ValueError, TypeError
        If ``b_max`` is not a positive finite number.

    Examples
    --------
    >>> P = lambda m, b: lcd_dirac([0.0], None, m, b)
    >>> Q = lambda m, b: lcd_dirac([0.3], None, m, b)
    >>> round(mcvmd_quadrature(P, Q, b_max=10.0, spread=2.0, points=[0.0, 0.3]), 3)
    0.593
    """
    check.function(lcd1, "lcd1"), check.function(lcd2, "lcd2")
    b_max = v.positive(b_max, "b_max")
    center = check.real_scalar(center, "center")
    spread = v.positive(spread, "spread")
    points = check.real_array(points, "points").ravel()
    n_m = check.integer(n_m, "n_m", minimum=1)
    t, w = np.polynomial.legendre.leggauss(20)
    panels = max(n_m // 20, 1)

    def inner(b):
        half = spread + 12 * b
        extra = (points[:, None] + b * np.arange(-8, 9)[None]).ravel()
        edges = np.union1d(np.linspace(center - half, center + half, panels + 1),
                           extra[np.abs(extra - center) < half])
        midpoints = 0.5 * (edges[:-1] + edges[1:])
        m = (0.5 * np.diff(edges)[:, None] * t[None] + midpoints[:, None]).ravel()
        wm = (0.5 * np.diff(edges)[:, None] * w[None]).ravel()
        return float(wm @ (lcd1(m[:, None], b) - lcd2(m[:, None], b)) ** 2)

    val = integrate.quad(inner, 0.0, b_max, limit=400, epsabs=config.defaults["gp.quad_epsabs"],
                         epsrel=config.defaults["gp.quad_epsrel"])[0]
    return float(np.sqrt(max(val, 0.0)))
