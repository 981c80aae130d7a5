"""Property-based fuzz of the public API of asoc.belief and asoc.gp (issue 15, item 5).

* Malformed input: one argument of a valid call is replaced by a malformed value (NaN,
  infinities, negative or fractional counts, strings, bools, complex numbers, wrong shapes,
  objects of the wrong type). The call either succeeds without NaN in its result (the value
  happened to be admissible) or raises a ValueError or TypeError whose message begins with
  the names of the arguments at fault, as the caller wrote them (``"<name>: expected ...,
  found ..."``); when two arguments do not fit together, either may be named.
* Valid input: finite random inputs of moderate size give results without NaN.

Derandomised (tests/conftest.py loads the ``derandomize=True`` profile): the same examples on
every run and machine.
"""

import dataclasses
import math
import re
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from asoc import belief, gp

# --- valid calls ------------------------------------------------------------------------

EX = belief.landmark_example(K=2)
MODEL, COST, MEAN0, COV0 = EX.model, EX.cost, EX.mean0, EX.cov0
LIN = belief.linear_gaussian_model(
    [[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], 0.3 * np.eye(2), [[1.0, 0.0]], [[0.5]]
)
UKF = belief.UKF(MODEL)
W_POINTS, BETA = belief.sigma_points(MODEL.w.mean, MODEL.w.cov)
V_POINTS, GAMMA = belief.sigma_points(MODEL.v.mean, MODEL.v.cov)
MIX = belief.DiracMixture(belief.sigma_points(MEAN0, COV0)[0])
POLICY = belief.AffinePolicy.zero(2, 2, 2)
REF = belief.reference_trajectory(MODEL, UKF, POLICY, MEAN0, COV0)
NXT = belief.Value(0.0, np.zeros(2), np.eye(2), np.zeros((2, 2)))
STAGE = belief.StageProblem(MODEL, COST, UKF, REF.estimates[0], NXT, W_POINTS, BETA)
EXP = STAGE.expansion(REF.u_bar[0])
NOISE = belief.draw_noise(MODEL, MEAN0, COV0, 2, 3, np.random.default_rng(0))
with warnings.catch_warnings():
    warnings.simplefilter("ignore", RuntimeWarning)
    ILQG = belief.belief_ilqg(MODEL, COST, MEAN0, COV0, max_iterations=3)
X_SET = np.random.default_rng(1).normal(size=(4, 3, 1))
D_TRAIN = gp.mcvmd_matrix(X_SET)
Y_TRAIN = np.array([0.0, 1.0, 0.5, -0.3])
GP_COND = gp.DistributionGP("se").condition(D_TRAIN, Y_TRAIN, 1.0, 1.0, 0.1)
MK_GP = gp.MeanKernelGP(n_restarts=0)
with warnings.catch_warnings():
    warnings.simplefilter("ignore", RuntimeWarning)
    MK_GP.fit(X_SET, Y_TRAIN, np.random.default_rng(0))


def rng():
    return np.random.default_rng(0)


def pdf(x):
    return math.exp(-0.5 * x * x) / math.sqrt(2 * math.pi)


def pdf2(x):
    return math.exp(-0.5 * (x - 1) ** 2) / math.sqrt(2 * math.pi)


def lcd0(m, b):
    return gp.lcd_dirac([0.0], None, m, b)


#: name -> (callable, valid keyword arguments). Every argument is fuzzed in turn.
CALLS = {
    "GaussianNoise": (belief.GaussianNoise, dict(mean=[0.0, 1.0], cov=np.eye(2))),
    "NonlinearModel": (
        belief.NonlinearModel,
        dict(
            a=lambda x, u, w: x + u + w,
            h=lambda x, v: x + v,
            w=belief.GaussianNoise([0.0], [[1.0]]),
            v=belief.GaussianNoise([0.0], [[1.0]]),
            n_x=1,
            n_u=1,
            affine=True,
        ),
    ),
    "QuadraticCost": (
        belief.QuadraticCost,
        dict(Q=np.eye(2), R=np.eye(2), Q_K=np.eye(2), x_target=[0.0, 0.0], K=3),
    ),
    "landmark_example": (
        belief.landmark_example,
        dict(
            K=2,
            landmark=(-3.0, 0.0),
            mean0=(-5.0, 3.0),
            std0=0.2,
            x_target=(0.0, 3.0),
            noise_gain=0.5,
            range_noise=0.1,
            input_weight=0.1,
        ),
    ),
    "linear_gaussian_model": (
        belief.linear_gaussian_model,
        dict(A=np.eye(2), B=np.ones((2, 1)), H=np.eye(2), C=np.ones((1, 2)), J=np.eye(1)),
    ),
    "DiracMixture": (belief.DiracMixture, dict(points=np.zeros((2, 2)), weights=[0.5, 0.5])),
    "sigma_points": (belief.sigma_points, dict(mean=[0.0, 1.0], cov=np.eye(2), kappa=0.5)),
    "next_estimate_covariance": (
        belief.next_estimate_covariance,
        dict(
            mixture=MIX,
            u=[1.0, 0.0],
            model=MODEL,
            w_samples=W_POINTS,
            v_samples=V_POINTS,
            beta=BETA,
            gamma=GAMMA,
        ),
    ),
    "UKF": (belief.UKF, dict(model=MODEL, kappa=0.5)),
    "UKF.step": (UKF.step, dict(estimate=(MEAN0, COV0), u=[0.0, 0.0], y=[2.0])),
    "ParticleFilter": (
        belief.ParticleFilter,
        dict(model=MODEL, n_particles=10, rng=rng(), resample_threshold=0.5),
    ),
    "ekf_step": (belief.ekf_step, dict(model=MODEL, mean=MEAN0, cov=COV0, u=[0.0, 0.0], y=[2.0])),
    "statistical_taylor_expansion": (
        belief.statistical_taylor_expansion,
        dict(
            g=lambda x: float(x @ x),
            mixture=MIX,
            grad=lambda x: 2 * x,
            hess=lambda x: 2 * np.eye(2),
        ),
    ),
    "sigma_point_linearizations": (
        belief.sigma_point_linearizations,
        dict(a=np.sin, da=np.cos, mean=1.0, var=0.5),
    ),
    "statistical_taylor_linearization_error": (
        belief.statistical_taylor_linearization_error,
        dict(x_true=5.7, mean=4.0, var=1.5, reading="regression"),
    ),
    "AffinePolicy": (belief.AffinePolicy, dict(L=np.zeros((2, 1, 2)), d=np.zeros((2, 1)))),
    "AffinePolicy.zero": (belief.AffinePolicy.zero, dict(K=2, n_u=1, n_x=2)),
    "reference_trajectory": (
        belief.reference_trajectory,
        dict(
            model=MODEL, filt=UKF, policy=POLICY, mean0=MEAN0, cov0=COV0, mode="sampled", rng=rng()
        ),
    ),
    "Value": (belief.Value, dict(s=0.0, v=np.zeros(2), V=np.eye(2), S=np.zeros((2, 2)))),
    "terminal_value": (belief.terminal_value, dict(cost=COST, mixture=MIX)),
    "StageProblem": (
        belief.StageProblem,
        dict(
            model=MODEL,
            cost=COST,
            filt=UKF,
            estimate=REF.estimates[0],
            nxt=NXT,
            w_points=W_POINTS,
            beta=BETA,
            covariance_hessian="psd",
            covariance_term=True,
        ),
    ),
    "improved_policy_value": (belief.improved_policy_value, dict(exp=EXP, eps=0.5)),
    "affine_policy_value": (
        belief.affine_policy_value,
        dict(exp=EXP, L=np.zeros((2, 2)), d=np.zeros(2), u_bar=np.zeros(2)),
    ),
    "policy_step": (belief.policy_step, dict(exp=EXP, u_bar=REF.u_bar[0], eps=0.5)),
    "line_search": (
        belief.line_search,
        dict(stage=STAGE, exp=EXP, u_bar=REF.u_bar[0], mean_bar=MEAN0, alpha_min=0.01),
    ),
    "backward_pass": (
        belief.backward_pass,
        dict(
            model=MODEL,
            cost=COST,
            filt=UKF,
            ref=REF,
            policy=POLICY,
            w_points=W_POINTS,
            beta=BETA,
            derivatives="analytic",
            alpha_min=0.01,
            covariance_hessian="psd",
            covariance_term=True,
        ),
    ),
    "optimize_belief_trajectory": (
        belief.optimize_belief_trajectory,
        dict(
            model=MODEL,
            cost=COST,
            mean0=MEAN0,
            cov0=COV0,
            filt=UKF,
            policy=POLICY,
            max_iterations=2,
            rtol=1e-3,
            n_cost_runs=3,
            rng=rng(),
            derivatives="analytic",
            reference_mode="nominal",
            alpha_min=0.01,
            covariance_hessian="psd",
            covariance_term=True,
            progress=False,
        ),
    ),
    "belief_ilqg": (
        belief.belief_ilqg,
        dict(
            model=MODEL,
            cost=COST,
            mean0=MEAN0,
            cov0=COV0,
            u_init=np.zeros((2, 2)),
            max_iterations=2,
            rtol=1e-3,
            eps_min=0.01,
            progress=False,
        ),
    ),
    "optimize_damped": (
        belief.optimize_damped,
        dict(
            model=MODEL,
            cost=COST,
            mean0=MEAN0,
            cov0=COV0,
            filt=UKF,
            policy=POLICY,
            max_iterations=2,
            rtol=1e-3,
            n_cost_runs=3,
            rng=rng(),
            mu_min=1e-3,
            mu_max=1e3,
            factor=4.0,
            derivatives="analytic",
            alpha_min=0.01,
        ),
    ),
    "bend_toward_landmark": (
        belief.bend_toward_landmark,
        dict(
            means=[[-5.0, 3.0], [-2.0, 2.5], [0.0, 3.0]],
            start=[-5.0, 3.0],
            target=[0.0, 3.0],
            landmark=[-3.0, 0.0],
        ),
    ),
    "covariance_aware_optimum": (
        belief.covariance_aware_optimum,
        dict(example=EX, offsets=(0.0,), gtol=1e-3),
    ),
    "belief_vector": (belief.belief_vector, dict(mean=[0.0, 1.0], cov=np.eye(2))),
    "BeliefDynamics": (belief.BeliefDynamics, dict(model=MODEL)),
    "draw_noise": (
        belief.draw_noise,
        dict(model=MODEL, mean0=MEAN0, cov0=COV0, K=2, n_runs=3, rng=rng()),
    ),
    "MeanAffineController": (
        belief.MeanAffineController,
        dict(model=MODEL, policy=POLICY, kappa=0.5),
    ),
    "BeliefAffineController": (belief.BeliefAffineController, dict(model=MODEL, result=ILQG)),
    "simulate": (
        belief.simulate,
        dict(
            model=MODEL,
            cost=COST,
            mean0=MEAN0,
            cov0=COV0,
            controller=belief.MeanAffineController(MODEL, POLICY),
            noise=NOISE,
        ),
    ),
    # gp
    "mcvmd_constant": (gp.mcvmd_constant, dict(b_max=100.0)),
    "mcvmd": (gp.mcvmd, dict(x=[0.0, 1.0], wx=[0.3, 0.7], y=[0.5], wy=None, b_max=100.0)),
    "mcvmd_matrix": (
        gp.mcvmd_matrix,
        dict(
            X=X_SET,
            Y=X_SET[:2],
            WX=None,
            WY=np.full((2, 3), 1 / 3),
            b_max=50.0,
            chunk=2,
            progress=False,
        ),
    ),
    "lcd_dirac": (gp.lcd_dirac, dict(x=[0.0, 1.0], wx=None, m=[[0.0], [1.0]], b=1.0)),
    "lcd_gaussian": (gp.lcd_gaussian, dict(mean=[0.0], cov=[[1.0]], m=[[0.0]], b=[0.5])),
    "mcvmd_quadrature": (
        gp.mcvmd_quadrature,
        dict(lcd1=lcd0, lcd2=lcd0, b_max=2.0, center=0.0, spread=1.0, points=[0.0], n_m=40),
    ),
    "wasserstein_gaussian": (
        gp.wasserstein_gaussian,
        dict(m1=[0.0], C1=[[1.0]], m2=[1.0], C2=[[2.0]]),
    ),
    "omat": (gp.omat, dict(x=[0.0, 1.0], y=[1.0, 2.0], q=2)),
    "omat_matrix": (gp.omat_matrix, dict(X=X_SET, Y=X_SET[:2], q=1.5, progress=False)),
    "ospa": (gp.ospa, dict(x=[0.0], y=[0.0, 1.0], c=2.0, p=2)),
    "ospa_matrix": (
        gp.ospa_matrix,
        dict(X=[[0.0], [0.0, 1.0]], Y=[[1.0, 2.0, 3.0]], c=2.0, p=2, progress=False),
    ),
    "wasserstein_gaussian_matrix": (
        gp.wasserstein_gaussian_matrix,
        dict(means_i=[[0.0], [1.0]], covs_i=[[[1.0]], [[2.0]]], means_j=[[1.0]], covs_j=[[[0.5]]]),
    ),
    "hellinger_gaussian_matrix": (
        gp.hellinger_gaussian_matrix,
        dict(means_i=[[0.0], [1.0]], covs_i=[[[1.0]], [[2.0]]], means_j=[[1.0]], covs_j=[[[0.5]]]),
    ),
    "lq_distance_matrix": (
        gp.lq_distance_matrix,
        dict(heights=[[2.0, 0.0], [1.0, 1.0]], edges=[0.0, 0.5, 1.0], other=[[0.5, 1.5]], q=3),
    ),
    "hellinger_matrix": (
        gp.hellinger_matrix,
        dict(heights=[[2.0, 0.0], [1.0, 1.0]], edges=[0.0, 0.5, 1.0], other=[[0.5, 1.5]]),
    ),
    "jensen_shannon_matrix": (
        gp.jensen_shannon_matrix,
        dict(heights=[[2.0, 0.0], [1.0, 1.0]], edges=[0.0, 0.5, 1.0], other=[[0.5, 1.5]]),
    ),
    "lq_distance": (gp.lq_distance, dict(p1=pdf, p2=pdf2, q=2, lower=-10.0, upper=10.0)),
    "hellinger": (gp.hellinger, dict(p1=pdf, p2=pdf2, lower=-10.0, upper=10.0)),
    "hellinger_gaussian": (gp.hellinger_gaussian, dict(m1=[0.0], C1=[[1.0]], m2=[1.0], C2=[[2.0]])),
    "jensen_shannon": (gp.jensen_shannon, dict(p1=pdf, p2=pdf2, lower=-10.0, upper=10.0)),
    "squared_exponential": (gp.squared_exponential, dict(delta=[0.0, 1.0], l=1.0)),
    "matern": (gp.matern, dict(delta=[0.0, 1.0], l=1.0, nu=1.5)),
    "exponential": (gp.exponential, dict(delta=[0.0, 1.0], l=1.0)),
    "gamma_exponential": (gp.gamma_exponential, dict(delta=[0.0, 1.0], l=1.0, gamma=1.5)),
    "rational_quadratic": (gp.rational_quadratic, dict(delta=[0.0, 1.0], l=1.0, alpha=2.0)),
    "bilinear_product": (
        gp.bilinear_product,
        dict(K_distance=np.ones((2, 1)), means_i=[[1.0], [2.0]], means_j=[[1.0]], Sigma=[[1.0]]),
    ),
    "mean_kernel_dirac": (
        gp.mean_kernel_dirac,
        dict(X=X_SET, Y=X_SET[:2], WX=None, WY=None, alpha=1.0, Lambda=1.0, chunk=2),
    ),
    "mean_kernel_gaussian": (
        gp.mean_kernel_gaussian,
        dict(
            means_i=[[0.0]],
            covs_i=[[[1.0]]],
            means_j=[[1.0]],
            covs_j=[[[0.5]]],
            alpha=1.0,
            Lambda=[[2.0]],
        ),
    ),
    "DistributionGP": (
        gp.DistributionGP,
        dict(
            covariance="matern",
            n_restarts=1,
            bounds={"alpha": (0.1, 10.0), "l": (0.1, 10.0), "sigma_n": (0.01, 1.0)},
            nu=1.5,
        ),
    ),
    "DistributionGP.fit": (
        gp.DistributionGP("se", n_restarts=0).fit,
        dict(D=D_TRAIN, y=Y_TRAIN, rng=rng()),
    ),
    "DistributionGP.condition": (
        gp.DistributionGP("se").condition,
        dict(D=D_TRAIN, y=Y_TRAIN, alpha=1.0, l=1.0, sigma_n=0.1),
    ),
    "DistributionGP.predict": (GP_COND.predict, dict(D_star=D_TRAIN[:2], return_var=True)),
    "DistributionGP.posterior": (
        GP_COND.posterior,
        dict(D_star=D_TRAIN[:2], D_star_star=D_TRAIN[:2, :2]),
    ),
    "DistributionGP.log_marginal_likelihood": (
        GP_COND.log_marginal_likelihood,
        dict(alpha=1.0, l=1.0, sigma_n=0.1),
    ),
    "MeanKernelGP": (gp.MeanKernelGP, dict(n_restarts=0, bounds=None)),
    "MeanKernelGP.fit": (
        gp.MeanKernelGP(n_restarts=0).fit,
        dict(X=X_SET, y=Y_TRAIN, rng=rng(), W=None),
    ),
    "MeanKernelGP.predict": (MK_GP.predict, dict(X_star=X_SET[:2], return_var=True, W_star=None)),
    "mcvmd_standard_normal_dirac": (
        gp.mcvmd_standard_normal_dirac,
        dict(x=[-1.0, 1.0], wx=None, b_max=20.0),
    ),
    "standard_normal_dirac_approximation": (
        gp.standard_normal_dirac_approximation,
        dict(L=3, b_max=100.0),
    ),
    "gaussian_dirac_mixtures": (
        gp.gaussian_dirac_mixtures,
        dict(means=[0.0, 1.0], variances=[1.0, 2.0], L=3, b_max=100.0),
    ),
    "quadratic_function": (gp.quadratic_function, dict(mu=[0.0, 1.0], var=[1.0, 2.0])),
    "modified_rosenbrock": (
        gp.modified_rosenbrock,
        dict(mu=[0.0, 1.0], var=[1.0, 2.0], a=0.1, b=4.0, c=0.1, d=-4.0),
    ),
    "training_gaussians": (gp.training_gaussians, dict(n=3, rng=rng())),
    "evaluation_grid": (gp.evaluation_grid, dict(step=0.5)),
    "error_metrics": (gp.error_metrics, dict(prediction=[1.0, 2.0], truth=[1.0, 3.0])),
    "kernel_study": (
        gp.kernel_study,
        dict(
            n_seeds=1,
            rng=rng(),
            n_train=5,
            grid_step=2.0,
            n_dirac=3,
            b_max=100.0,
            n_restarts=0,
            n_jobs=1,
            progress=False,
        ),
    ),
}

PUBLIC_RESULTS = {
    "BeliefFilter",
    "LandmarkExample",
    "QuadraticExpansion",
    "Expansion",
    "Reference",
    "LineSearch",
    "TrajectoryOptimizationResult",
    "BeliefILQGResult",
    "ClosedLoop",
    "Noise",
    "FitResult",
    "DiracApproximation",
    "COVARIANCES",
    "TABLE_2_1",
    "DampedResult",
    "IndefiniteStep",
    "KernelStudy",
}

BAD = [
    float("nan"),
    float("inf"),
    -float("inf"),
    -1,
    0,
    2.5,
    -0.5,
    "x",
    True,
    None,
    1j,
    [],
    [[float("nan")]],
    np.zeros((2, 3, 4)),
    np.array([1 + 1j, 2]),
    np.full(2, np.nan),
    [1.0, "a"],
    object(),
    {"a": 1},
    10**6,
    -np.eye(2),
    np.array([[1.0, 2.0], [0.0, 1.0]]),
    np.array([0.5, -0.5, 1.0]),
]
CASES = [(name, arg) for name, (_, kwargs) in CALLS.items() for arg in kwargs]
# Sizes of work: 10**6 is a valid value that asks for hours (a million training sets, a million
# worker processes), not a malformed one.
WORK_SIZES = {
    ("kernel_study", arg) for arg in ("n_seeds", "n_train", "n_dirac", "n_restarts", "n_jobs")
}


def test_every_public_function_and_class_is_fuzzed():
    public = {name for pkg in (belief, gp) for name in pkg.__all__}
    fuzzed = {name.split(".")[0] for name in CALLS}
    assert public - fuzzed - PUBLIC_RESULTS == set()


def assert_no_nan(value, where):
    if isinstance(value, np.ndarray) and np.issubdtype(value.dtype, np.number):
        assert not np.any(np.isnan(value)), f"{where}: NaN in the result"
    elif isinstance(value, float):
        assert not math.isnan(value), f"{where}: NaN in the result"
    elif isinstance(value, (tuple, list)):
        for item in value:
            assert_no_nan(item, where)
    elif isinstance(value, dict):
        for item in value.values():
            assert_no_nan(item, where)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            if f.name not in ("model",):
                assert_no_nan(getattr(value, f.name), where)


def call(name, kwargs):
    func = CALLS[name][0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return func(**kwargs)


@pytest.mark.parametrize("name", sorted(CALLS))
def test_valid_calls_run(name):
    assert_no_nan(call(name, dict(CALLS[name][1])), name)


# Defects the fuzz found, each now a named error: a grid step the grid refuses (the message
# named the helper's `step`), an mCvMd width too small for the closed form (it returned 0
# between distinct mixtures, and the GP fit then met an indefinite kernel), no offsets at all.
FOUND_BY_THE_FUZZ = [
    ("kernel_study", "grid_step", 10**6),
    ("kernel_study", "b_max", 2.5),
    ("covariance_aware_optimum", "offsets", []),
]


@pytest.mark.parametrize("name, arg, value", FOUND_BY_THE_FUZZ)
def test_found_defect_is_a_named_error(name, arg, value):
    with pytest.raises(ValueError, match=f"^{arg}: expected .* found"):
        call(name, dict(CALLS[name][1], **{arg: value}))


@settings(max_examples=2500, deadline=None, report_multiple_bugs=False)
@given(st.sampled_from(CASES), st.sampled_from(BAD))
def test_malformed_argument_is_named_or_harmless(case, bad):
    assume(not (case in WORK_SIZES and type(bad) is int and bad == 10**6))
    name, arg = case
    kwargs = dict(CALLS[name][1], **{arg: bad})
    try:
        result = call(name, kwargs)
    except (ValueError, TypeError) as err:
        named = set(re.findall(r"[A-Za-z_]\w*", str(err).split(":")[0]))
        assert named & set(kwargs), (
            f"{name}({arg}={bad!r}): message does not begin with an argument: {err}"
        )
        assert "expected" in str(err) and "found" in str(err), f"{name}({arg}={bad!r}): {err}"
    else:
        assert_no_nan(result, f"{name}({arg}={bad!r})")


# --- finite valid input gives no NaN ----------------------------------------------------

finite = st.floats(-50, 50, allow_nan=False, allow_infinity=False)


def spd(n):
    return arrays(float, (n, n), elements=st.floats(-3, 3)).map(
        lambda A: A @ A.T + 1e-3 * np.eye(n)
    )


@settings(max_examples=60, deadline=None)
@given(arrays(float, st.tuples(st.integers(1, 6), st.integers(1, 3)), elements=finite), st.data())
def test_distances_of_finite_mixtures_are_finite(x, data):
    y = data.draw(arrays(float, (data.draw(st.integers(1, 6)), x.shape[1]), elements=finite))
    wx = data.draw(arrays(float, x.shape[0], elements=st.floats(0.01, 1))).astype(float)
    wx = wx / wx.sum()
    for d in (
        gp.mcvmd(x, wx, y, None),
        gp.ospa(x, y, c=3.0),
        gp.omat(x, x[::-1]),
        gp.lcd_dirac(x, wx, y, 0.7),
        gp.mcvmd_matrix(np.stack([x, x + 1.0])),
    ):
        assert_no_nan(np.asarray(d), "distances")
    assert gp.mcvmd(x, wx, y, None) >= 0


@settings(max_examples=40, deadline=None)
@given(
    st.integers(1, 3).flatmap(
        lambda n: st.tuples(
            arrays(float, n, elements=finite), spd(n), arrays(float, n, elements=finite), spd(n)
        )
    )
)
def test_gaussian_distances_and_kernels_are_finite(args):
    m1, C1, m2, C2 = args
    values = [
        gp.wasserstein_gaussian(m1, C1, m2, C2),
        gp.hellinger_gaussian(m1, C1, m2, C2),
        gp.mean_kernel_gaussian(m1[None], C1[None], m2[None], C2[None], alpha=1.3, Lambda=0.7),
        gp.lcd_gaussian(m1, C1, m2[None], 0.4),
    ]
    for name in gp.COVARIANCES:
        values.append(gp.COVARIANCES[name](np.abs(m1 - m2), 0.8))
    assert_no_nan(values, "gaussian")


@settings(max_examples=40, deadline=None)
@given(
    st.integers(1, 3).flatmap(lambda n: st.tuples(arrays(float, n, elements=finite), spd(n))),
    arrays(float, 1, elements=finite),
    arrays(float, 1, elements=finite),
)
def test_filters_on_finite_estimates_are_finite(estimate, u, y):
    mean, cov = estimate
    n = mean.size
    model = belief.linear_gaussian_model(
        np.eye(n), np.ones((n, 1)), np.eye(n), np.ones((1, n)), [[0.5]]
    )
    values = [
        belief.sigma_points(mean, cov),
        belief.belief_vector(mean, cov),
        belief.ekf_step(model, mean, cov, u, y),
        belief.UKF(model).step((mean, cov), u, y),
        belief.next_estimate_covariance(
            belief.DiracMixture(belief.sigma_points(mean, cov)[0]),
            u,
            model,
            *belief.sigma_points(model.w.mean, model.w.cov)[:1],
            belief.sigma_points(model.v.mean, model.v.cov)[0],
        ),
    ]
    assert_no_nan(values, "filters")


@settings(max_examples=30, deadline=None)
@given(arrays(float, 6, elements=st.floats(-5, 5)), arrays(float, 6, elements=st.floats(0.01, 4)))
def test_gp_on_finite_data_is_finite(mu, var):
    X = gp.gaussian_dirac_mixtures(mu, var, 4)
    y = gp.modified_rosenbrock(mu, var) + gp.quadratic_function(mu, var)
    D = gp.mcvmd_matrix(X)
    model = gp.DistributionGP("se").condition(D, y, alpha=2.0, l=1.5, sigma_n=0.1)
    assert_no_nan(model.predict(D[:2], return_var=True), "gp")
    assert_no_nan(model.posterior(D[:2], D[:2, :2]), "gp")
    assert_no_nan(gp.mean_kernel_dirac(X, alpha=1.0, Lambda=1.0), "gp")
    if np.ptp(y) > 0:
        assert_no_nan(gp.error_metrics(y + 0.1, y), "gp")
