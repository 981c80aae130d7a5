"""Sec. 2.6.4 over seeds: the three GPs on independently drawn training sets.

The thesis draws one set of 200 training Gaussians and reads the kernel orderings off one
pair of error plots (Figs. 2.9-2.10). :func:`kernel_study` repeats the whole experiment for
independent training sets (one seed each: 200 means and variances drawn uniformly, their
deterministic Dirac approximations [82], the three GPs fitted by maximum likelihood) and
returns the per-seed errors on a common test grid, so that each ordering the text states can
be decided by a paired statistic over the seeds (:func:`asoc.stats.decide_claim`).
"""

import warnings
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..progress import progress_bar
from .cramer_von_mises import mcvmd_matrix
from .experiment import (
    GRID_STEP_RANGE,
    error_metrics,
    evaluation_grid,
    modified_rosenbrock,
    quadratic_function,
    training_gaussians,
)
from .regression import DistributionGP, MeanKernelGP
from .sampling import gaussian_dirac_mixtures
from .transport import omat_matrix

__all__ = ["GPS", "FUNCTIONS", "KernelStudy", "kernel_study"]


GPS = ("mcvmd", "omat", "mean_kernel")
FUNCTIONS = {"v1": quadratic_function, "v2": modified_rosenbrock}


@dataclass(frozen=True)
class KernelStudy:
    """Per seed (rows) the error metrics of each GP on each function.

    ``rmse``, ``nrmse`` (RMSE / range of the true values) and ``r2`` map ``(function, gp)``
    (e.g. ``("v1", "omat")``) to arrays (n_seeds,); ``unconverged`` counts the fits whose
    likelihood maximisation stopped above its gradient tolerance, ``n_fits`` all fits.

    Examples
    --------
    >>> s = KernelStudy({("v1", "omat"): np.ones(2)}, {}, {}, 0, 2)
    >>> s.n_seeds
    2
    """

    rmse: dict
    nrmse: dict
    r2: dict
    unconverged: int
    n_fits: int

    @property
    def n_seeds(self) -> int:
        """Number of seeds (training sets)."""
        return len(next(iter(self.rmse.values())))


def kernel_study(
    n_seeds,
    rng,
    n_train=200,
    grid_step=0.5,
    n_dirac=10,
    b_max=100.0,
    n_restarts=0,
    n_jobs=1,
    progress=False,
) -> KernelStudy:
    """Sec. 2.6.4 for ``n_seeds`` independent training sets; errors on the grid of ``grid_step``.

    Parameters
    ----------
    n_seeds : int
        Number of training sets (>= 1); seed i uses the child ``rng.spawn`` i.
    rng : numpy.random.Generator
        The source of the training sets and of the restarts.
    n_train : int
        Training inputs per set (200 in the thesis), >= 3.
    grid_step : float
        Step of the test grid in mean and variance (0.1 in the thesis; coarser for speed), in
        [1e-3, 10] (``GRID_STEP_RANGE`` of ``asoc.gp.experiment``).
    n_dirac : int
        Dirac components per input distribution (10 in the thesis).
    b_max : float
        The mCvMd's largest kernel width (our reading of the thesis: 100).
    n_restarts : int
        Random restarts of each likelihood maximisation besides the data-based start.
    n_jobs : int
        Worker processes (joblib; -1 all cores); the result does not depend on it.
    progress : bool
        Show a progress bar.

    Returns
    -------
    KernelStudy
        The errors per seed, test function and GP, and the fits that did not converge.

    Raises
    ------
    ValueError, TypeError
        If an argument has the wrong type or range.

    Examples
    --------
    >>> s = kernel_study(2, np.random.default_rng(0), n_train=20, grid_step=1.0)
    >>> s.n_seeds, s.n_fits, sorted(s.rmse)[0]
    (2, 12, ('v1', 'mcvmd'))
    """
    n_seeds = check.integer(n_seeds, "n_seeds", minimum=1)
    rng = check.generator(rng)
    n_train = check.integer(n_train, "n_train", minimum=3)
    grid_step = check.real_scalar(grid_step, "grid_step", low=GRID_STEP_RANGE[0],
                                  high=GRID_STEP_RANGE[1])
    n_jobs = check.process_count(n_jobs, "n_jobs")
    progress = check.boolean(progress, "progress")
    settings = (
        n_train,
        grid_step,
        check.integer(n_dirac, "n_dirac", minimum=1),
        check.real_scalar(b_max, "b_max", low=0, low_open=True),
        check.integer(n_restarts, "n_restarts", minimum=0),
    )
    children = rng.spawn(n_seeds)
    if n_jobs == 1:
        rows = [
            _seed(child, *settings)
            for child in progress_bar(children, progress, desc="training sets")
        ]
    else:
        import joblib

        tasks = (joblib.delayed(_seed)(child, *settings) for child in children)
        rows = list(
            progress_bar(
                joblib.Parallel(n_jobs=n_jobs, return_as="generator")(tasks),
                progress,
                desc="training sets",
                total=n_seeds,
            )
        )
    metrics = {
        name: {key: np.array([row[0][key][name] for row in rows]) for key in rows[0][0]}
        for name in ("rmse", "nrmse", "r2")
    }
    return KernelStudy(
        metrics["rmse"],
        metrics["nrmse"],
        metrics["r2"],
        int(sum(row[1] for row in rows)),
        int(sum(row[2] for row in rows)),
    )


def _seed(rng, n_train, grid_step, n_dirac, b_max, n_restarts):
    """One training set: ({(function, gp): metrics}, unconverged fits, fits)."""
    mu_tr, var_tr = training_gaussians(n_train, rng)
    mu_axis, var_axis = evaluation_grid(grid_step)
    MU, VAR = (a.ravel() for a in np.meshgrid(mu_axis, var_axis))
    X_tr, X_te = (
        gaussian_dirac_mixtures(mu_tr, var_tr, n_dirac, b_max),
        gaussian_dirac_mixtures(MU, VAR, n_dirac, b_max),
    )
    inputs = {
        "mcvmd": (mcvmd_matrix(X_tr, b_max=b_max), mcvmd_matrix(X_te, X_tr, b_max=b_max)),
        "omat": (omat_matrix(X_tr), omat_matrix(X_te, X_tr)),
        "mean_kernel": (X_tr, X_te),
    }
    out, unconverged, fits = {}, 0, 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # counted below, reported by the caller
        for fname, f in FUNCTIONS.items():
            y_tr, y_te = f(mu_tr, var_tr), f(MU, VAR)
            for name, (train, test) in inputs.items():
                model = (
                    MeanKernelGP(n_restarts=n_restarts)
                    if name == "mean_kernel"
                    else DistributionGP("se", n_restarts=n_restarts)
                )
                model.fit(train, y_tr, rng)
                out[fname, name] = error_metrics(model.predict(test), y_te)
                unconverged += not model.result.converged
                fits += 1
    return out, unconverged, fits
