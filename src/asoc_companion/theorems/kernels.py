"""Sec. 2.6.3: every covariance function of Table 2.1 over an admissible distance gives a valid GP?

A Gaussian kernel of a distance is positive definite for all length scales only if the squared
distance is conditionally negative definite, i.e. the distance embeds isometrically in a Hilbert
space (Schoenberg 1938; Feragen, Lauze and Hauberg, CVPR 2015). The check searches adversarially
for a configuration of distributions whose Gram matrix has a negative eigenvalue, with the
library's distances and covariances (``asoc.gp``) throughout:

* the objective of a configuration is the smallest lambda_min / lambda_max of its Gram matrix
  over a grid of length scales (one stacked eigenvalue call);
* the search moves one distribution at a time (a Gaussian step in its parameters, accepted when
  the objective drops; the step grows on success and shrinks on failure), so a move recomputes
  one row of the distance matrix, N - 1 library calls;
* a failure is certified on the best configuration: the library's Gram matrix has an eigenvalue
  below -tolerance by LAPACK's ``syevd`` (numpy), ``syevr`` (scipy) and the Rayleigh quotient
  of its eigenvector in exact rational arithmetic. The tolerance bounds, by Weyl's inequality,
  what the distances' errors can move an eigenvalue; the errors of the quadrature distances
  (Jensen-Shannon, L_q) are estimated by computing them a second time over a wider interval.

A search can miss a counterexample, so "holds" says only that none was found, and the share of
failing instances is the search's yield, not a failure rate of the claim.
"""

import json
from fractions import Fraction

import numpy as np
from scipy.linalg import eigh as scipy_eigh
from scipy.optimize import minimize_scalar

from asoc import gp

from .statement import Outcome

__all__ = ["EPS", "BOX", "STOP", "LOG_SCALES", "MOVES", "STALL", "FAMILIES", "COVARIANCE_NAMES",
           "MUTANT_COVARIANCE", "random_covariance", "covariance", "distance_matrix",
           "gram_certificate", "check_kernels_sec_2_6_3", "search_counterexample",
           "replay_kernel_counterexample", "distance_label", "DISTANCE_LABELS", "summarise_kernels"]


EPS = float(np.finfo(float).eps)
BOX = 5.0                     # positions within +-BOX (the range of the thesis's examples)
STOP = -1e-4                  # the search stops at lambda_min / lambda_max below this
LOG_SCALES = np.linspace(-3.0, 3.0, 61)     # length scale = exp(x) median distance, x on this grid
#: Moves per instance: about 1 s of library calls per instance on one core (a move of the
#: quadrature distances costs N - 1 integrations of about 1-3 ms).
MOVES = {"mcvmd": 300, "omat": 300, "ospa": 300, "wasserstein_gaussian": 300, "hellinger": 300,
         "jensen_shannon": 40, "lq": 80}
# moves without progress before the search restarts from a new configuration
STALL = 60
FAMILIES = tuple(MOVES)
COVARIANCE_NAMES = ("se", "matern", "exponential", "gamma_exponential", "rational_quadratic")
# exp(-(d/l)^4): not positive definite even on the real line
MUTANT_COVARIANCE = "quartic_exponential"


def random_covariance(rng):
    """A Table 2.1 covariance (named as in ``asoc.gp.COVARIANCES``) and a random shape parameter."""
    name = COVARIANCE_NAMES[int(rng.integers(len(COVARIANCE_NAMES)))]
    shape = {"matern": {"nu": float(rng.choice([0.5, 1.5, 2.5]))},
             "gamma_exponential": {"gamma": float(rng.uniform(0.5, 2.0))},
             "rational_quadratic": {"alpha_rq": float(rng.uniform(0.5, 5.0))}}.get(name, {})
    return name, shape


def covariance(name, shape, D, l):
    """The library's covariance ``name`` of Table 2.1 at distances ``D`` and length scale ``l``
    (or the mutant's exp(-(D/l)^4)).
    """
    if name == MUTANT_COVARIANCE:
        return np.exp(-(np.asarray(D) / l) ** 4)
    params = {("alpha" if key == "alpha_rq" else key): value for key, value in shape.items()}
    return gp.COVARIANCES[name](D, l, **params)


def _random_layout(rng, family):
    N = int(rng.integers(4, 8))
    layout = {"N": N}
    if family in ("mcvmd", "omat"):
        layout["points"] = int(rng.integers(2, 5)) if family == "mcvmd" else int(rng.integers(2, 4))
    elif family == "ospa":
        layout["sizes"] = [int(s) for s in rng.integers(1, 4, size=N)]
        layout["c"] = float(rng.uniform(1.0, 10.0))
    elif family == "hellinger":
        layout["exponent"] = "printed" if rng.random() < 0.75 else "usual"
    elif family in ("jensen_shannon", "lq"):
        layout["bins"] = int(rng.choice([4, 8]))
        if family == "lq":
            layout["q"] = int(rng.choice([1, 2, 3]))
    return layout


def _parameter_count(family, layout, i):
    """Unconstrained parameters of distribution ``i``."""
    return {"mcvmd": 2 * layout.get("points", 0), "omat": 2 * layout.get("points", 0),
            "ospa": 2 * layout.get("sizes", [0] * (i + 1))[i], "wasserstein_gaussian": 5,
            "hellinger": 2,
            }.get(family, layout.get("bins", 0))


def _decode(family, theta):
    """The distribution (JSON-able) encoded by the unconstrained parameters ``theta``."""
    if family in ("mcvmd", "omat", "ospa"):
        return (BOX * np.tanh(theta)).reshape(-1, 2).tolist()
    if family == "wasserstein_gaussian":
        s = np.tanh(theta)
        chol = np.array([[np.exp(1.5 * s[2]), 0.0], [2 * s[3], np.exp(1.5 * s[4])]])
        return [(BOX * s[:2]).tolist(), (chol @ chol.T).tolist()]
    if family == "hellinger":
        t = np.tanh(theta)
        return [float(BOX * t[0]), float(np.exp(2 * t[1]))]              # mean, standard deviation
    e = np.exp(theta - theta.max())
    # bin probabilities on [0, 1]
    return (e / e.sum()).tolist()


def _step_density(weights):
    """Piecewise-constant density on [0, 1] with len(weights) equal bins."""
    w = np.asarray(weights, dtype=float)
    B = len(w)
    return lambda x: B * w[min(int(x * B), B - 1)] if 0.0 <= x <= 1.0 else 0.0


def _pair_distance(family, config, a, b, interval=(0.0, 1.0)):
    """The library's distance of Sec. 2.6.3 between two distributions of a configuration
    (``interval``: the integration limits of the quadrature distances).

    Examples
    --------
    >>> h = _pair_distance("hellinger", {"exponent": "usual"}, [0.0, 1.0], [1.0, 1.0])
    >>> round(h, 4), round(_pair_distance("hellinger", {"exponent": "printed"}, [0.0, 1.0], [1.0,
    ...     1.0]), 6)
    (0.3428, 0.013807)
    """
    if family == "mcvmd":
        return float(gp.mcvmd_matrix(np.array([a]), np.array([b]))[0, 0])
    if family == "omat":
        return float(gp.omat_matrix(np.array([a]), np.array([b]), q=2)[0, 0])
    if family == "ospa":
        return gp.ospa(np.array(a), np.array(b), c=config["c"], p=2)
    if family == "wasserstein_gaussian":
        return gp.wasserstein_gaussian(a[0], a[1], b[0], b[1])
    if family == "hellinger":
        h = gp.hellinger_gaussian([a[0]], [[a[1] ** 2]], [b[0]], [[b[1] ** 2]])
        # thesis: (1 - BC)^2 = (h^2)^2
        return h ** 4 if config["exponent"] == "printed" else h
    if family == "jensen_shannon":
        return gp.jensen_shannon(_step_density(a), _step_density(b), *interval)
    return gp.lq_distance(_step_density(a), _step_density(b), config["q"], *interval)


def distance_matrix(family, config, interval=(0.0, 1.0)):
    """The library's distances between all distributions of ``config["items"]``."""
    items = config["items"]
    D = np.zeros((len(items), len(items)))
    for i in range(len(items)):
        for j in range(i + 1, len(items)):
            D[i, j] = D[j, i] = _pair_distance(family, config, items[i], items[j], interval)
    return D


def _median_distance(D):
    return float(np.median(D[np.triu_indices(len(D), 1)]))


def _objective(D, name, shape):
    """(smallest lambda_min / lambda_max over the grid of length scales, its log factor)."""
    median = _median_distance(D)
    if not median > 0:
        # all distributions coincide: nothing to learn
        return 1.0, 0.0
    scales = median * np.exp(LOG_SCALES)
    lam = np.linalg.eigvalsh(covariance(name, shape, D[None] / scales[:, None, None], 1.0))
    ratios = lam[:, 0] / lam[:, -1]
    best = int(np.argmin(ratios))
    return float(ratios[best]), float(LOG_SCALES[best])


def _search(rng, family, layout, config, name, shape):
    """Adversarial search, one distribution at a time: theta, value, log factor, moves, restarts."""
    N = layout["N"]
    start = lambda: [rng.normal(size=_parameter_count(family, layout, i)) for i in range(N)]
    theta = start()
    D = distance_matrix(family, {**config, "items": [_decode(family, t) for t in theta]})
    value, log_factor = _objective(D, name, shape)
    best = (value, [t.copy() for t in theta], log_factor)
    sigma, stall, restarts, moves = 0.5, 0, 0, 0
    for moves in range(1, MOVES[family] + 1):
        if best[0] < STOP:
            break
        if stall >= STALL:
            theta, restarts, stall, sigma = start(), restarts + 1, 0, 0.5
            D = distance_matrix(family, {**config, "items": [_decode(family, t) for t in theta]})
            value, log_factor = _objective(D, name, shape)
        i = int(rng.integers(N))
        trial = theta[i] + sigma * rng.standard_normal(theta[i].shape)
        moved = _decode(family, trial)
        row = [0.0 if j == i else _pair_distance(family, config, moved, _decode(family, theta[j]))
               for j in range(N)]
        D_trial = D.copy()
        D_trial[i, :] = D_trial[:, i] = row
        trial_value, trial_factor = _objective(D_trial, name, shape)
        if trial_value < value:
            theta[i], D, value, log_factor = trial, D_trial, trial_value, trial_factor
            sigma, stall = min(2.0 * sigma, 2.0), 0
            if value < best[0]:
                best = (value, [t.copy() for t in theta], log_factor)
        else:
            sigma, stall = max(0.8 * sigma, 0.01), stall + 1
    return best[1], best[0], best[2], moves, restarts


def _exact_quadratic_form(K, a):
    """a^T K a / a^T a in exact rational arithmetic of the double-precision entries."""
    Kf = [[Fraction(float(x)) for x in row] for row in K]
    af = [Fraction(float(x)) for x in a]
    num = sum(af[i] * Kf[i][j] * af[j] for i in range(len(af)) for j in range(len(af)))
    return float(num / sum(x * x for x in af))


def gram_certificate(family, config, name, shape, l):
    """Library Gram matrix of a configuration and the evidence that it is (not) PSD.

    Returns the smallest eigenvalue (LAPACK syevd through numpy and syevr through scipy), the
    Rayleigh quotient of its eigenvector in exact rational arithmetic, and the tolerance
    N (max |kappa'(D)| delta_D + 16 eps): by Weyl's inequality, errors delta_D of the distances
    cannot move an eigenvalue of the unit-diagonal Gram matrix by more. delta_D is 64 eps max D,
    plus, for the quadrature distances, their change when integrated over [-1, 2] instead of [0, 1].

    Examples
    --------
    Three 1-D Gaussians N(0, 1), N(1, 1), N(2, 1) under the Hellinger expression as printed:

    >>> config = {"items": [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]], "exponent": "printed"}
    >>> cert = gram_certificate("hellinger", config, "se", {}, 0.03)
    >>> round(cert["lambda_min"], 3), cert["rayleigh_exact"] < -cert["tolerance"]
    (-0.272, True)
    """
    if family not in FAMILIES:
        raise ValueError(f"family: expected one of {FAMILIES}, found {family!r}")
    D = distance_matrix(family, config)
    N = len(D)
    K = covariance(name, shape, D, l)
    lam, U = np.linalg.eigh(K)
    lam_scipy = float(scipy_eigh(K, eigvals_only=True, driver="evr")[0])
    rayleigh = _exact_quadratic_form(K, U[:, 0])
    delta_D = 64 * EPS * float(D.max())
    if family in ("jensen_shannon", "lq"):
        delta_D += float(np.abs(D - distance_matrix(family, config, (-1.0, 2.0))).max())
    off = D[np.triu_indices(N, 1)]
    h = 1e-6
    slope = np.abs(covariance(name, shape, off * (1 + h), l)
                   - covariance(name, shape, off * (1 - h), l)) \
        / (2 * h * np.maximum(off, 1e-300))
    slope = float(np.nanmax(np.where(off > 0, slope, 0.0))) if off.size else 0.0
    tol = N * (slope * delta_D + 16 * EPS)
    return {"lambda_min": float(lam[0]), "lambda_min_scipy_evr": lam_scipy,
            "lambda_max": float(lam[-1]),
            "rayleigh_exact": rayleigh, "tolerance": float(tol), "delta_D": delta_D,
            "max_kernel_slope": slope}


def check_kernels_sec_2_6_3(rng: np.random.Generator, mutant=False) -> Outcome:
    """Sec. 2.6.3: a covariance of Table 2.1 over a distance of Sec. 2.6.3 gives a PSD Gram matrix.

    The instance draws a distance (mCvMd and OMAT between 2-D Dirac mixtures, OSPA between 2-D
    point sets of 1-3 points, Wasserstein-2 between 2-D Gaussians, Hellinger between 1-D
    Gaussians with the printed exponent (1 - BC)^2 or, in a quarter of the instances, the usual
    sqrt(1 - BC), the Jensen-Shannon divergence and L_q (q = 1, 2, 3) between piecewise-constant
    densities on [0, 1]), a covariance of Table 2.1 with its shape parameter and 4-7
    distributions, and searches (:func:`search_counterexample`). Mutant: the covariance
    exp(-(d/l)^4) in place of Table 2.1's.
    """
    family = FAMILIES[int(rng.integers(len(FAMILIES)))]
    name, shape = random_covariance(rng)
    if mutant:
        name, shape = MUTANT_COVARIANCE, {}
    return search_counterexample(rng, family, name, shape)


def search_counterexample(rng: np.random.Generator, family: str, name: str, shape: dict,
                          **fixed) -> Outcome:
    """The adversarial search of :func:`check_kernels_sec_2_6_3` for one distance and covariance.

    ``family`` is one of ``FAMILIES``; ``name``/``shape`` a covariance of Table 2.1 (names as
    in ``asoc.gp.COVARIANCES``); ``fixed`` overrides entries of the random layout (e.g.
    ``q=2``, ``exponent="usual"``, ``N=5``).
    """
    if family not in FAMILIES:
        raise ValueError(f"family: expected one of {FAMILIES}, found {family!r}")
    if name not in (*COVARIANCE_NAMES, MUTANT_COVARIANCE):
        raise ValueError(f"name: expected one of {COVARIANCE_NAMES}, found {name!r}")
    layout = {**_random_layout(rng, family), **fixed}
    config = {key: layout[key] for key in ("c", "exponent", "q") if key in layout}
    theta, value, log_factor, moves, restarts = _search(rng, family, layout, config, name, shape)
    config["items"] = [_decode(family, t) for t in theta]
    D = distance_matrix(family, config)
    refined = minimize_scalar(lambda x: _objective_at(D, name, shape, x), bounds=(log_factor - 0.1,
                                                                                  log_factor + 0.1),
                              method="bounded")
    l = float(np.exp(refined.x if refined.fun < value else log_factor) * _median_distance(D))
    cert = gram_certificate(family, config, name, shape, l) if l > 0 else \
        {"lambda_min": 1.0, "lambda_min_scipy_evr": 1.0, "rayleigh_exact": 1.0, "tolerance": 0.0}
    negative = (cert["lambda_min"] < -cert["tolerance"]
                and cert["lambda_min_scipy_evr"] < -cert["tolerance"]
                and cert["rayleigh_exact"] < -cert["tolerance"])
    numbers = {"distance": family, "covariance": name, "shape": json.dumps(shape),
               "distributions": layout["N"],
               "length_scale": l, "search_lambda_ratio": value, "moves": moves,
               "restarts": restarts, **cert,
               "configuration": json.dumps(config)}
    for key in ("exponent", "q", "points", "bins"):
        if key in layout:
            numbers[key] = layout[key]
    return Outcome("fails" if negative else "holds", numbers)


def _objective_at(D, name, shape, log_factor):
    lam = np.linalg.eigvalsh(covariance(name, shape, D,
                                        float(np.exp(log_factor) * _median_distance(D))))
    return float(lam[0] / lam[-1])


def replay_kernel_counterexample(numbers: dict) -> dict:
    """Re-evaluate a recorded kernel counterexample from its outcome numbers alone (no search).

    Examples
    --------
    >>> config = {"items": [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]], "exponent": "printed"}
    >>> numbers = {"distance": "hellinger", "configuration": json.dumps(config), "covariance": "se",
    ...            "shape": "{}", "length_scale": 0.03}
    >>> round(replay_kernel_counterexample(numbers)["lambda_min"], 3)
    -0.272
    """
    return gram_certificate(numbers["distance"], json.loads(numbers["configuration"]),
                            numbers["covariance"],
                            json.loads(numbers["shape"]), numbers["length_scale"])


def distance_label(numbers: dict) -> str:
    """The distance of a kernel instance as summarised: family, Hellinger exponent, L_q order."""
    label = numbers["distance"]
    if "exponent" in numbers:
        label += "_" + numbers["exponent"]
    if "q" in numbers:
        label += f"_{numbers['q']}"
    return label


DISTANCE_LABELS = ("mcvmd", "omat", "ospa", "wasserstein_gaussian", "hellinger_printed",
                   "hellinger_usual",
                   "jensen_shannon", "lq_1", "lq_2", "lq_3")


def summarise_kernels(outcomes) -> dict:
    """Instances and failures per distance and per covariance of the Sec. 2.6.3 check."""
    by_distance = {label: {"instances": 0, "fails": 0} for label in DISTANCE_LABELS}
    by_covariance = {name: {"instances": 0, "fails": 0} for name in COVARIANCE_NAMES}
    for outcome in outcomes:
        for table, label in ((by_distance, distance_label(outcome.numbers)),
                             (by_covariance, outcome.numbers["covariance"])):
            table[label]["instances"] += 1
            table[label]["fails"] += outcome.verdict == "fails"
    return {"by_distance": by_distance, "by_covariance": by_covariance}
