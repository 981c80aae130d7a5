"""Gaussian process regression whose inputs are probability distributions (Sec. 2.6).

:class:`DistributionGP` is the thesis's framework (Sec. 2.6.3): a stationary covariance
of Table 2.1 evaluated at a distance :math:`D(d_i, d_j)` between the input distributions.
The distances do not depend on the hyperparameters, so they are computed once and the
fit only re-evaluates an elementwise function of a fixed matrix.

:class:`MeanKernelGP` is the baseline of Dallaire, Besse and Chaib-draa [42] ("Learning
Gaussian Process Models from Uncertain Data", ICONIP 2009): the SE kernel averaged over
both input distributions, eq. (2.22), whose hyperparameters are found, as in [42], by
maximising the log marginal likelihood with the expected kernel matrix recomputed at
every step of the optimiser (the SE length scale sits inside the average).

Both share the same estimator (Sec. 2.6.1): hyperparameters
:math:`\\underline\\theta = (\\alpha, l, \\sigma_n)` maximise the log marginal likelihood
:math:`\\log p(\\underline y | \\mathbf X) = -\\tfrac12 \\underline r^\\top \\Sigma_y^{-1}
\\underline r - \\tfrac12 \\log|\\Sigma_y| - \\tfrac M2 \\log 2\\pi`,
:math:`\\underline r = \\underline y - \\underline m(\\mathbf X)`,
:math:`\\Sigma_y = \\alpha^2 K_l + \\sigma_n^2 \\mathbf I` (L-BFGS-B in log-parameters with the
analytic gradient, one start at a data-based guess plus seeded random restarts), and the
prediction is Proposition 2.7, both via one Cholesky factorisation of :math:`\\Sigma_y`.
The prior mean is the constant :math:`m = \\bar y` (the sample mean of the training
outputs), a reading: the thesis leaves :math:`m` open.
"""

import warnings
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import LinAlgError, cho_factor, cho_solve
from scipy.optimize import minimize

from .. import config
from .. import validation as check
from ..result import IterativeResult
from . import mixture_checks as v
from .kernels import COVARIANCES, mean_kernel_dirac

__all__ = ["PARAMS", "ALPHA_CAP", "NOISE_FLOOR", "POLISH_RESTARTS", "LOG_ML_TIE", "FitResult",
           "DistributionGP", "MeanKernelGP", "EXP_ZERO_BELOW"]


PARAMS = ("alpha", "l", "sigma_n")
#: Default bounds of alpha (upper) and sigma_n (lower) relative to std(y): together they keep
#: cond(Sigma_y) <= M (ALPHA_CAP / NOISE_FLOOR)^2 = M 1e10, where the likelihood and its analytic
#: gradient are accurate to far better than gp.gradient_tol. With the earlier bounds (1e3, 1e-4)
#: the OMAT fits of Sec. 2.6.4, whose likelihood grows without bound along alpha, l -> infinity
#: (OMAT is Euclidean in (mu, sigma) there and v_1 a polynomial), ran into cond ~ 1e18 with alpha
#: at its bound, where the jittered Cholesky no longer matches the gradient: they stopped
#: without converging.
ALPHA_CAP = 1e2
NOISE_FLOOR = 1e-3
#: Polishing restarts of L-BFGS-B from its own end point when the projected gradient is above the
#: tolerance (a fresh start discards the curvature pairs that stalled the line search).
POLISH_RESTARTS = 3
#: Log-likelihood difference below which two starts' optima are not told apart (a likelihood
#: ratio of 1.001): among such near-best optima a converged one is preferred to an unconverged
#: one whose gradient the conditioning of Sigma_y does not let L-BFGS-B reduce further.
LOG_ML_TIE = 1e-3


@dataclass(kw_only=True)
class FitResult(IterativeResult):
    """Outcome of the hyperparameter estimation (Sec. 2.6.1): the best start's optimum, and why.

    ``converged`` when the projected gradient of the log marginal likelihood in
    log-parameters is below ``config.defaults["gp.gradient_tol"]`` at the chosen start (the best
    one, or a converged one within ``LOG_ML_TIE`` of it; status ``converged``);
    otherwise ``max_iterations`` or ``no_progress`` (L-BFGS-B stopped earlier).

    Examples
    --------
    >>> x = np.linspace(-2, 2, 8)
    >>> D = np.abs(x[:, None] - x[None])
    >>> gp = DistributionGP("se", n_restarts=1).fit(D, np.sin(x), np.random.default_rng(0))
    >>> from asoc import config
    >>> gp.result.status, gp.result.gradient_norm < config.defaults["gp.gradient_tol"]
    ('converged', True)
    """

    alpha: float            #: signal standard deviation (kernel amplitude alpha^2)
    l: float                #: length scale
    sigma_n: float          #: noise standard deviation
    log_ml: float           #: log marginal likelihood at the optimum
    iterations: int         #: iterations of the best start
    #: largest projected gradient component (log-parameters) at the optimum
    gradient_norm: float = 0.0
    starts: list = field(default_factory=list)  #: (start, optimum, log_ml, converged) per start


def _cholesky(Ky):
    """Cholesky factor of ``Ky``, adding the smallest sufficient diagonal jitter."""
    scale = np.mean(np.diag(Ky))
    for jitter in (0.0, 1e-12, 1e-10, 1e-8, 1e-6):
        try:
            jittered = Ky if jitter == 0.0 else Ky + jitter * scale * np.eye(len(Ky))
            return cho_factor(jittered, lower=True)
        except LinAlgError:
            continue
    raise LinAlgError("Sigma_y is not positive definite even with jitter 1e-6 * mean(diag)")


def _projected_gradient(res, log_b) -> float:
    """Largest component of the gradient projected onto the box ``log_b`` (0 at an active bound).

    On the flat ridges of the likelihood (alpha and l growing together) L-BFGS-B often
    ends with an abnormal line search at a point whose projected gradient is negligible;
    the library's criterion is this gradient, never the optimiser's status.
    """
    g = np.array(res.jac, dtype=float)
    at_lo, at_hi = res.x <= log_b[:, 0] + 1e-9, res.x >= log_b[:, 1] - 1e-9
    g[(at_lo & (g > 0)) | (at_hi & (g < 0))] = 0.0
    return float(np.max(np.abs(g)))


def _status(gradient, iterations, tolerance, max_iterations):
    if gradient <= tolerance:
        return "converged", (f"projected gradient {gradient:.2g} <= {tolerance:g} "
                             f"after {iterations} iterations")
    if iterations >= max_iterations:
        return "max_iterations", (f"stopped after {iterations} iterations "
                                  f"with projected gradient {gradient:.2g}")
    return "no_progress", (f"L-BFGS-B stopped after {iterations} iterations with projected "
                           f"gradient {gradient:.2g} > {tolerance:g}")


class _LikelihoodGP:
    """Shared estimator: subclasses provide the unit-variance kernel and its l-derivative."""

    def __init__(self, n_restarts: int = 4, bounds=None):
        self.n_restarts = check.integer(n_restarts, "n_restarts", minimum=0)
        self.bounds = None if bounds is None else _bounds(bounds)
        self.result = None
        self._reset_kernels()

    # -- subclasses ----------------------------------------------------------------------
    def _unit_kernel(self, l, grad=False):
        """Training kernel with alpha = 1 and, if ``grad``, its derivative w.r.t. log l."""
        raise NotImplementedError

    # -- kernels of recent length scales ---------------------------------------------------
    def _reset_kernels(self):
        """Forget the remembered kernels (new training data)."""
        self._kernels = OrderedDict()

    def _kernel(self, l, grad=False):
        """:meth:`_unit_kernel` (read-only arrays), remembered for the recent length scales.

        The same arrays for the same value of ``l``: an entry without the derivative serves
        ``grad=False`` only. The least recently used entries go beyond
        ``config.defaults["gp.kernel_cache_bytes"]``.
        """
        budget = config.defaults["gp.kernel_cache_bytes"]
        key = float(l)
        entry = self._kernels.get(key)
        if entry is None or (grad and entry[1] is None):
            kernels = self._unit_kernel(l, grad=grad)
            entry = self._kernels[key] = tuple(_read_only(K) for K in kernels)
        self._kernels.move_to_end(key)
        while len(self._kernels) > 1 and sum(K.nbytes for pair in self._kernels.values()
                                             for K in pair if K is not None) > budget:
            self._kernels.popitem(last=False)
        return entry

    def _length_scale_guess(self) -> float:
        raise NotImplementedError

    # -- estimation ------------------------------------------------------------------------
    def _set_outputs(self, y):
        y = check.real_array(y, "y", ndim=1)
        if y.size < 2:
            raise ValueError(f"y: expected at least two finite outputs, found {y.size} values")
        self.y, self.m = y, float(y.mean())
        return y

    def _default_bounds(self):
        sy = float(np.std(self.y)) or 1.0
        l0 = self._length_scale_guess()
        return {"alpha": (1e-3 * sy, ALPHA_CAP * sy), "l": (1e-3 * l0, 1e3 * l0),
                "sigma_n": (NOISE_FLOOR * sy, 1.0 * sy)}

    def neg_log_ml(self, log_theta, grad=True):
        """Negative log marginal likelihood (Sec. 2.6.1) and gradient at log(alpha, l, sigma_n)."""
        self._fitted_data()
        log_theta = check.real_array(log_theta, "log_theta", shape=(3,))
        return self._neg_log_ml(log_theta, check.boolean(grad, "grad"))

    def _fitted_data(self):
        if not hasattr(self, "y"):
            raise RuntimeError("call fit() or condition() first: "
                               "the likelihood needs training data")

    def _neg_log_ml(self, log_theta, grad=True):
        alpha, l, sn = np.exp(log_theta)
        Ku, dKu = self._kernel(l, grad=grad)
        # + sn^2 I in place: off the diagonal x + 0 = x (x >= +0)
        Ky = alpha**2 * Ku
        Ky.flat[::len(Ky) + 1] += sn**2
        try:
            cf = _cholesky(Ky)
        except LinAlgError:
            return (1e25, np.zeros(3)) if grad else 1e25
        r = self.y - self.m
        a = cho_solve(cf, r)
        nll = 0.5 * r @ a + np.sum(np.log(np.diag(cf[0]))) + 0.5 * len(r) * np.log(2 * np.pi)
        if not grad:
            return nll
        Kinv = cho_solve(cf, np.eye(len(r)))
        W = np.outer(a, a) - Kinv                      # d nll / d theta = -1/2 tr(W dK)
        g = -0.5 * np.array([np.sum(W * (2 * alpha**2 * Ku)),
                             np.sum(W * (alpha**2 * dKu)),
                             np.sum(W * (2 * sn**2 * np.eye(len(r))))])
        return nll, g

    def log_marginal_likelihood(self, alpha, l, sigma_n) -> float:
        """Log marginal likelihood log p(y | X) at given hyperparameters (likelihood surfaces)."""
        self._fitted_data()
        named = ((alpha, "alpha"), (l, "l"), (sigma_n, "sigma_n"))
        theta = [v.positive(value, name) for value, name in named]
        return -self._neg_log_ml(np.log(theta), grad=False)

    def _optimise(self, rng: np.random.Generator):
        rng = check.generator(rng)
        bounds = self.bounds or self._default_bounds()
        log_b = np.log([bounds[n] for n in PARAMS])
        sy = float(np.std(self.y)) or 1.0
        guess = np.log(np.clip([sy, self._length_scale_guess(), 1e-2 * sy],
                               [b[0] for b in np.exp(log_b)], [b[1] for b in np.exp(log_b)]))
        starts = [guess] + [rng.uniform(log_b[:, 0], log_b[:, 1]) for _ in range(self.n_restarts)]
        tolerance = config.defaults["gp.gradient_tol"]
        max_iterations = config.defaults["gp.max_iterations"]
        runs = []
        for x0 in starts:
            res, iterations = self._minimise(x0, log_b, max_iterations), 0
            iterations += int(res.nit)
            for _ in range(POLISH_RESTARTS):
                if _projected_gradient(res, log_b) <= tolerance or iterations >= max_iterations:
                    break
                res = self._minimise(res.x, log_b, max_iterations - iterations)
                iterations += int(res.nit)
            gradient = _projected_gradient(res, log_b)
            runs.append((np.exp(x0), np.exp(res.x), -float(res.fun), gradient <= tolerance,
                         iterations, gradient))
        best = max(runs, key=lambda run: run[2])
        tied = [run for run in runs if run[3] and run[2] >= best[2] - LOG_ML_TIE]
        best = max(tied, key=lambda run: run[2]) if tied else best
        alpha, l, sn = best[1]
        status, message = _status(best[5], best[4], tolerance, max_iterations)
        self.result = FitResult(alpha=float(alpha), l=float(l), sigma_n=float(sn), log_ml=best[2],
                                iterations=best[4], gradient_norm=best[5],
                                starts=[run[:4] for run in runs],
                                converged=status == "converged", status=status, message=message)
        if not self.result.converged:
            warnings.warn(f"{type(self).__name__}.fit: the best start did not converge: {message}",
                          RuntimeWarning)
        return self.result

    def _minimise(self, x0, log_b, max_iterations):
        """One L-BFGS-B run of the negative log marginal likelihood from ``x0`` (log-parameters)."""
        return minimize(self._neg_log_ml, x0, jac=True, method="L-BFGS-B", bounds=log_b,
                        options={"maxiter": max(1, max_iterations)})

    def _factor(self):
        r = self.result
        Ku, _ = self._kernel(r.l)
        # the fit's others: memory
        self._kernels = OrderedDict([(float(r.l), self._kernels[float(r.l)])])
        self._cf = _cholesky(r.alpha**2 * Ku + r.sigma_n**2 * np.eye(len(Ku)))
        self._a = cho_solve(self._cf, self.y - self.m)

    def _fitted(self):
        if self.result is None:
            raise RuntimeError("call fit() or condition() before predict()")

    def _predict(self, K_cross_unit, k_self_unit, return_var):
        """Proposition 2.7 from the unit cross kernel (N, M) and unit self-covariances (N,)."""
        a2 = self.result.alpha**2
        Ks = a2 * K_cross_unit
        mean = self.m + Ks @ self._a
        if not return_var:
            return mean
        V = cho_solve(self._cf, Ks.T)
        var = a2 * k_self_unit - np.einsum("nm,mn->n", Ks, V)
        return mean, np.clip(var, 0.0, None)


class DistributionGP(_LikelihoodGP):
    """GP regression with a covariance of a distance between input distributions (Sec. 2.6.3).

    :math:`k(d_i, d_j) = \\alpha^2 \\kappa(D(d_i, d_j); l)` with :math:`\\kappa` one of
    Table 2.1 (``covariance`` in ``"se"``, ``"matern"``, ``"exponential"``,
    ``"gamma_exponential"``, ``"rational_quadratic"``; their shape parameters ``nu``,
    ``gamma``, ``alpha_rq`` are fixed, not estimated). Works with any distance: pass the
    matrices computed once, e.g. by :func:`asoc.gp.mcvmd_matrix` or :func:`asoc.gp.omat_matrix`.

    Parameters
    ----------
    covariance : str
    n_restarts : int
        Random restarts of the likelihood maximisation besides the data-based guess.
    bounds : dict, optional
        ``{"alpha": (lo, hi), "l": (lo, hi), "sigma_n": (lo, hi)}``; default: alpha in
        [1e-3, 1e2] std(y), l in [1e-3, 1e3] median distance, sigma_n in [1e-3, 1] std(y)
        (``ALPHA_CAP`` and ``NOISE_FLOOR`` keep :math:`\\Sigma_y` well conditioned, cond <~ M 1e10,
        for noiseless data).
    **shape : float
        ``nu`` (Matern), ``gamma`` (gamma-exponential), ``alpha_rq`` (rational quadratic).

    Examples
    --------
    >>> x = np.linspace(-3, 3, 12)                        # inputs: Dirac distributions at x
    >>> D = np.abs(x[:, None] - x[None])
    >>> gp = DistributionGP("se", n_restarts=1).fit(D, np.sin(x), np.random.default_rng(0))
    >>> mean, var = gp.predict(np.abs(np.array([[0.5]]) - x[None]), return_var=True)
    >>> round(float(mean[0]), 3), bool(var[0] < 1e-3)     # sin(0.5) = 0.479
    (0.479, True)
    """

    def __init__(self, covariance: str = "se", n_restarts: int = 4, bounds=None, **shape):
        check.choice(covariance, "covariance", COVARIANCES)
        allowed = {"matern": {"nu"}, "gamma_exponential": {"gamma"},
                   "rational_quadratic": {"alpha_rq"}}.get(covariance, set())
        if set(shape) - allowed:
            extra = ", ".join(sorted(set(shape) - allowed))
            raise TypeError(f"{extra}: expected the shape parameters of {covariance!r}, "
                            f"{sorted(allowed) or 'none'}, found {sorted(shape)}")
        super().__init__(n_restarts, bounds)
        self.covariance = covariance
        fn = COVARIANCES[covariance]
        if "alpha_rq" in shape:
            shape = {"alpha": v.positive(shape["alpha_rq"], "alpha_rq")}
        if "nu" in shape:
            shape["nu"] = v.positive(shape["nu"], "nu")
        if "gamma" in shape:
            shape["gamma"] = check.real_scalar(shape["gamma"], "gamma", low=0, high=2,
                                               low_open=True)
        self._kappa = lambda D, l: fn(D, l, **shape)
        # the training distances are checked by fit, the optimiser's l = exp(log l) is positive
        self._kappa_training = lambda l: fn(self.D, float(l), check=False, **shape)

    def _length_scale_guess(self):
        off = self.D[~np.eye(len(self.D), dtype=bool)]
        return float(np.median(off[off > 0])) if np.any(off > 0) else 1.0

    def _unit_kernel(self, l, grad=False):
        K = self._kappa_training(l)
        if not grad:
            return K, None
        if self.covariance == "se":
            return K, K * (self.D / l) ** 2
        h = 1e-6                                       # central difference in log l
        difference = self._kappa_training(l * np.exp(h)) - self._kappa_training(l * np.exp(-h))
        return K, difference / (2 * h)

    @config.accepts_settings("gp.gradient_tol", "gp.max_iterations")
    def fit(self, D, y, rng: np.random.Generator):
        """Estimate the hyperparameters from distances ``D`` (M, M) and outputs ``y`` (M,)."""
        check.generator(rng)
        self._check_training(D, y)
        self._optimise(rng)
        self._factor()
        return self

    def _check_training(self, D, y):
        D = v.distances(D, "D")
        if D.ndim != 2 or D.shape[0] != D.shape[1]:
            raise ValueError(f"D: expected a square distance matrix, found shape {D.shape}")
        if not np.allclose(D, D.T) or np.any(np.diag(D) != 0):
            raise ValueError("D: expected a symmetric distance matrix with zero diagonal, found "
                             f"asymmetry {np.abs(D - D.T).max():.3g} and largest diagonal entry "
                             f"{np.abs(np.diag(D)).max():.3g}")
        y = self._set_outputs(y)
        if len(y) != len(D):
            raise ValueError(f"y: expected {len(D)} outputs (one per training input), "
                             f"found {len(y)}")
        self.D = D
        self._reset_kernels()

    def condition(self, D, y, alpha: float, l: float, sigma_n: float):
        """Condition on training data with given hyperparameters (no estimation)."""
        self._check_training(D, y)
        alpha, l, sigma_n = (v.positive(value, name) for value, name in ((alpha, "alpha"), (l, "l"),
                                                                          (sigma_n, "sigma_n")))
        log_ml = -self._neg_log_ml(np.log([alpha, l, sigma_n]), grad=False)
        self.result = FitResult(alpha=alpha, l=l, sigma_n=sigma_n, log_ml=float(log_ml),
                                iterations=0, converged=True, status="converged",
                                message="conditioned on given hyperparameters (no estimation)")
        self._factor()
        return self

    def posterior(self, D_star, D_star_star):
        """Joint predictive mean (N,) and covariance (N, N) of the latent function values.

        ``D_star`` (N, M): distances test-training; ``D_star_star`` (N, N): test-test.
        """
        mean = self.predict(D_star)
        D_star = np.atleast_2d(v.distances(D_star, "D_star"))
        D_ss = v.distances(D_star_star, "D_star_star")
        if D_ss.shape != (len(D_star), len(D_star)):
            raise ValueError(f"D_star_star: expected shape {(len(D_star),) * 2}, "
                             f"found {D_ss.shape}")
        Ks = self.result.alpha**2 * self._kappa(D_star, self.result.l)
        prior = self.result.alpha**2 * self._kappa(D_ss, self.result.l)
        cov = prior - Ks @ cho_solve(self._cf, Ks.T)
        return mean, 0.5 * (cov + cov.T)

    def predict(self, D_star, return_var: bool = False):
        """Predictive mean (and variance) at test inputs from distances ``D_star`` (N, M)."""
        self._fitted()
        D_star = np.atleast_2d(v.distances(D_star, "D_star"))
        if D_star.ndim != 2 or D_star.shape[1] != len(self.y):
            raise ValueError("D_star: expected non-negative distances of shape "
                             f"(N, {len(self.y)}), found shape {D_star.shape}")
        return_var = check.boolean(return_var, "return_var")
        return self._predict(self._kappa(D_star, self.result.l), np.ones(len(D_star)), return_var)


class MeanKernelGP(_LikelihoodGP):
    """Mean-kernel GP of Dallaire et al. [42]: SE kernel averaged over the inputs, eq. (2.22).

    Inputs are Dirac mixtures ``X`` (M, L, d) with weights ``W`` (M, L) (``None``: equal),
    e.g. the deterministic samples of Gaussians; :math:`k(d_i, d_j) = \\alpha^2 \\sum_{a,b}
    w_{i,a} w_{j,b} \\exp(-\\|\\underline x_{i,a} - \\underline x_{j,b}\\|^2 / (2 l^2))`
    (isotropic :math:`\\mathbf\\Lambda = l^2 \\mathbf I`). Eq. (2.22) is applied to every pair,
    the diagonal included (the average of the kernel over two independent copies of the
    input), which keeps the kernel a valid covariance on distributions. For Gaussian inputs
    the closed form is :func:`asoc.gp.mean_kernel_gaussian`. The expected kernel matrix is
    recomputed from the component distances at every likelihood evaluation, as in [42].

    Examples
    --------
    >>> from asoc.gp import gaussian_dirac_mixtures
    >>> mu = np.linspace(-2, 2, 10)
    >>> X = gaussian_dirac_mixtures(mu, np.full(10, 0.1), L=5)
    >>> gp = MeanKernelGP(n_restarts=1).fit(X, np.sin(mu), np.random.default_rng(0))
    >>> gp.result.status, round(float(gp.predict(gaussian_dirac_mixtures([1.0], [0.1], L=5))[0]), 2)
    ('converged', 0.84)
    """

    def _length_scale_guess(self):
        means = np.einsum("ma,mad->md", self.W, self.X)
        sq = np.sum((means[:, None] - means[None]) ** 2, axis=-1)
        off = sq[~np.eye(len(sq), dtype=bool)]
        return float(np.sqrt(np.median(off[off > 0]))) if np.any(off > 0) else 1.0

    def _unit_kernel(self, l, grad=False):
        # eq. (2.22) block row by block row, from the diagonal block on (the kernel is symmetric:
        # half the exponentials), and its derivative in log l,
        # sum_ab w_ia w_jb exp(-sq / (2 l^2)) sq / l^2
        M, l2 = len(self.W), l**2
        K = np.empty((M, M))
        dK = np.empty((M, M)) if grad else None
        for rows, sq, lowest in self._blocks:
            E = np.divide(sq, -2.0 * l2, out=_view(self._buffer, sq.shape))
            _exp_in_place(E, lowest / l2)
            _expected_kernel_rows(E, self.W, rows, K)
            if grad:
                dE = np.multiply(E, sq, out=E)
                dE /= l2
                _expected_kernel_rows(dE, self.W, rows, dK)
        return K, dK

    @config.accepts_settings("gp.gradient_tol", "gp.max_iterations")
    def fit(self, X, y, rng: np.random.Generator, W=None):
        """Estimate the hyperparameters from training mixtures ``X`` (M, L, d)."""
        check.generator(rng)
        self.X = v.mixture_set(X, "X")
        self.W = v.set_weights(W, self.X.shape, "W")
        y = self._set_outputs(y)
        if len(y) != len(self.X):
            raise ValueError(f"y: expected {len(self.X)} outputs (one per training input), "
                             f"found {len(y)}")
        self._prepare_kernel()
        self._optimise(rng)
        self._factor()
        return self

    def _prepare_kernel(self):
        """Squared component distances per block row and a work buffer for :meth:`_unit_kernel`.

        Block row ``rows`` holds |x_ia - x_jb|^2 as [i, a, j, b] for the mixtures i of ``rows``
        and j from ``rows.start`` on, with its smallest exponent -max(sq) / 2.
        """
        # [i, a, j, b]
        sq = np.sum((self.X[:, :, None, None, :] - self.X[None, None]) ** 2, axis=-1)
        rows_per_block = config.defaults["gp.mean_kernel_block_rows"]
        self._blocks = []
        for start in range(0, len(self.X), rows_per_block):
            rows = slice(start, start + rows_per_block)
            block = np.ascontiguousarray(sq[rows, :, start:])
            self._blocks.append((rows, block, -0.5 * block.max()))
        self._buffer = np.empty(max(block.size for _, block, _ in self._blocks))
        self._reset_kernels()

    def predict(self, X_star, return_var: bool = False, W_star=None):
        """Predictive mean (and variance) at test mixtures ``X_star`` (N, L', d)."""
        self._fitted()
        X_star = v.mixture_set(X_star, "X_star")
        v.same_dimension(X_star, self.X, "X_star, X")
        W_star = v.set_weights(W_star, X_star.shape, "W_star")
        return_var = check.boolean(return_var, "return_var")
        Lam = self.result.l**2
        K_cross = mean_kernel_dirac(X_star, self.X, W_star, self.W, alpha=1.0, Lambda=Lam)
        sq_self = np.sum((X_star[:, :, None] - X_star[:, None]) ** 2, axis=-1)
        k_self = np.einsum("na,nab,nb->n", W_star, np.exp(-0.5 * sq_self / Lam), W_star)
        return self._predict(K_cross, k_self, return_var)


#: exp(x) rounds to +0 below this exponent (exp(-745.14) < 2^-1075, half the smallest subnormal).
EXP_ZERO_BELOW = -746.0


def _exp_in_place(E, lowest):
    """``np.exp(E, out=E)``; exponents below :data:`EXP_ZERO_BELOW` give 0 without calling exp.

    ``lowest``: the smallest entry of ``E`` (or less). The exponential of those exponents,
    +0, takes libm's slow underflow path, several times the cost of the others; short length
    scales make many of them.
    """
    if lowest >= EXP_ZERO_BELOW:
        np.exp(E, out=E)
        return
    vanishing = E < EXP_ZERO_BELOW
    np.exp(E, out=E, where=~vanishing)
    E[vanishing] = 0.0


def _view(buffer, shape):
    """A C-contiguous array of ``shape`` on the start of the flat ``buffer``."""
    return buffer[:int(np.prod(shape))].reshape(shape)


def _expected_kernel_rows(V, W, rows, out):
    """Rows ``rows`` of eq. (2.22) from the diagonal block on, and their mirror below, into ``out``.

    ``V[i, a, j, b]`` (B, L, M - rows.start, L) holds the component kernel of mixture ``i`` of
    ``rows`` (component a) and mixture ``rows.start + j`` (component b); ``W`` the weights (M, L).
    """
    start = rows.start
    block = np.einsum("ia,iajb,jb->ij", W[rows], V, W[start:], optimize=True)
    out[rows, start:] = block
    out[start + block.shape[0]:, rows] = block[:, block.shape[0]:].T


def _read_only(K):
    """``K`` (an array or None) flagged read-only: remembered kernels are shared."""
    if K is not None:
        K.flags.writeable = False
    return K


def _bounds(bounds):
    """``{"alpha": (lo, hi), "l": (lo, hi), "sigma_n": (lo, hi)}`` with 0 < lo < hi finite."""
    check.instance(bounds, dict, "bounds",
                   "a dict {'alpha': (lo, hi), 'l': (lo, hi), 'sigma_n': (lo, hi)}")
    if set(bounds) != set(PARAMS):
        raise ValueError(f"bounds: expected the keys {list(PARAMS)}, found {sorted(bounds)}")
    out = {}
    for name in PARAMS:
        pair = check.real_array(bounds[name], f"bounds[{name!r}]", shape=(2,))
        if not 0 < pair[0] < pair[1]:
            raise ValueError(f"bounds[{name!r}]: expected 0 < low < high, "
                             f"found ({pair[0]}, {pair[1]})")
        out[name] = (float(pair[0]), float(pair[1]))
    return out
