"""The library beside its peers: python-control, scikit-learn and QuantEcon (the peers page).

With one mode an MJLS is an ordinary linear system: the observed-mode Riccati iteration [38]
must give python-control's ``dlqr``, the coupled Lyapunov solve its ``dlyap``, and Alg. 3.2 the
LQG compensator built from ``dlqr`` and ``dlqe`` (:func:`control_agreement`). On point masses a
:class:`asoc.gp.DistributionGP` is an ordinary GP: it must give what scikit-learn's
``GaussianProcessRegressor`` gives with the same kernel, fixed and fitted
(:func:`sklearn_agreement`). QuantEcon's ``LQMarkov`` solves the observed-mode problem too; it
was run once and its numbers are recorded with its version in
``tests/reference/quantecon_lqmarkov.json`` (QuantEcon is not a dependency), and
:func:`quantecon_comparison` sets them beside the coupled Riccati equations of [38]. The tests
``tests/asoc/mjls/test_peers.py`` and ``tests/asoc/gp/test_peers_sklearn.py`` check the same
agreements independently of this module.
"""

import json
import warnings

import numpy as np
import scipy.optimize

from asoc.gp import DistributionGP, wasserstein_gaussian_matrix
from asoc.mjls import MJLS, dynamic_output_feedback, observed_mode_state_feedback
from asoc.mjls.lyapunov import solve_coupled_lyapunov

from . import paths

__all__ = ["QUANTECON_FILE", "one_mode_plant", "control_agreement", "point_masses",
           "sklearn_agreement", "load_quantecon", "coupled_riccati_residual", "expectation_outside",
           "policy_value", "quantecon_comparison"]


#: QuantEcon's recorded numbers, under the project root.
QUANTECON_FILE = ("tests", "reference", "quantecon_lqmarkov.json")


def _relative(mine, theirs) -> float:
    mine, theirs = np.asarray(mine, float), np.asarray(theirs, float)
    return float(np.abs(mine - theirs).max() / np.abs(theirs).max())


def one_mode_plant(seed=3) -> dict:
    """An open-loop unstable plant (3 states, 2 inputs, 2 noisy outputs) as MJLS keywords.

    Examples
    --------
    >>> plant = one_mode_plant()
    >>> bool(max(abs(np.linalg.eigvals(plant["A"]))) > 1), plant["B"].shape
    (True, (3, 2))
    """
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((3, 3)) / 1.5
    B, C = rng.standard_normal((3, 2)), rng.standard_normal((2, 3))
    H, J = 0.3 * rng.standard_normal((3, 3)), 0.2 * np.eye(2)
    return dict(A=A, B=B, C=C, H=H, J=J, Q=np.eye(3), R=0.5 * np.eye(2))


def control_agreement(plant=None) -> list:
    """Rows (quantity, this library, python-control, largest relative difference) at one mode.

    The LQG compensator is compared by its Markov parameters L F^k K (k < 6), which do not
    depend on its coordinates, and by the closed loop's average cost from ``control.dlyap``.

    Examples
    --------
    >>> rows = control_agreement()
    >>> all(row[3] < 1e-9 for row in rows), len(rows)
    (True, 6)
    """
    import control

    p = one_mode_plant() if plant is None else plant
    A, B, C, H, J, Q, R = (p[k] for k in ("A", "B", "C", "H", "J", "Q", "R"))
    sys, one = MJLS(T=[[1.0]], **p), np.array([[1.0]])
    lq = observed_mode_state_feedback(sys)
    K_lq, S, _ = control.dlqr(A, B, Q, R)
    stable = A / (1.1 * max(abs(np.linalg.eigvals(A))))
    X = solve_coupled_lyapunov(stable[None], one, (H @ H.T)[None]).X[0]
    P = solve_coupled_lyapunov(stable[None], one, Q[None], adjoint=True).X[0]
    alg32 = dynamic_output_feedback(sys)
    K_kf, _, _ = control.dlqe(A, H, C, np.eye(len(A)), J @ J.T)
    F, K, L = A - B @ K_lq - K_kf @ C, K_kf, -K_lq
    markov = [
        (
            alg32.L @ np.linalg.matrix_power(alg32.F, k) @ alg32.K,
            L @ np.linalg.matrix_power(F, k) @ K,
        )
        for k in range(6)
    ]
    A_cl = np.block([[A, B @ L], [K @ C, F]])
    noise = np.block([[H, np.zeros((len(A), J.shape[1]))], [np.zeros_like(H), K @ J]])
    weight = np.block([[Q, np.zeros_like(A)], [np.zeros_like(A), L.T @ R @ L]])
    cost = float(np.trace(weight @ control.dlyap(A_cl, noise @ noise.T)))
    return [
        ("Riccati solution P", "observed_mode_state_feedback", "dlqr", _relative(lq.P[0], S)),
        ("state-feedback gain", "observed_mode_state_feedback", "dlqr", _relative(lq.L[0], -K_lq)),
        (
            "Lyapunov solution",
            "solve_coupled_lyapunov",
            "dlyap",
            _relative(X, control.dlyap(stable, H @ H.T)),
        ),
        (
            "adjoint Lyapunov solution",
            "solve_coupled_lyapunov(adjoint=True)",
            "dlyap",
            _relative(P, control.dlyap(stable.T, Q)),
        ),
        (
            "LQG compensator, L F^k K",
            "dynamic_output_feedback",
            "dlqr + dlqe",
            max(_relative(mine, theirs) for mine, theirs in markov),
        ),
        ("LQG average cost", "dynamic_output_feedback", "dlyap", _relative(alg32.cost, cost)),
    ]


def point_masses(seed=7):
    """25 noisy training points and 10 test points in the plane, and their Dirac distances.

    Returns (X, y, X_star, D, D_star); D is the 2-Wasserstein distance of Gaussians with zero
    covariance, the Euclidean distance of the locations.

    Examples
    --------
    >>> X, y, X_star, D, D_star = point_masses()
    >>> D.shape, D_star.shape, bool(np.allclose(D[0, 1], np.linalg.norm(X[0] - X[1])))
    ((25, 25), (10, 25), True)
    """
    rng = np.random.default_rng(seed)
    X = rng.uniform(-2, 2, (25, 2))
    y = np.sin(X[:, 0]) * np.cos(X[:, 1]) + 0.05 * rng.standard_normal(25)
    X_star = rng.uniform(-2, 2, (10, 2))
    zeros = np.zeros((25, 2, 2))
    D = wasserstein_gaussian_matrix(X, zeros)
    D_star = wasserstein_gaussian_matrix(X_star, np.zeros((10, 2, 2)), X, zeros)
    return X, y, X_star, D, D_star


def _sklearn_kernels():
    from sklearn.gaussian_process.kernels import RBF, Matern, RationalQuadratic

    return {
        "se": ({}, lambda l, b="fixed": RBF(l, b)),
        "matern": ({"nu": 2.5}, lambda l, b="fixed": Matern(l, b, nu=2.5)),
        "exponential": ({}, lambda l, b="fixed": Matern(l, b, nu=0.5)),
        "rational_quadratic": (
            {"alpha_rq": 2.0},
            lambda l, b="fixed": RationalQuadratic(l, 2.0, b, "fixed"),
        ),
    }


def sklearn_agreement(alpha=0.9, l=0.7, sigma_n=0.1, restarts=3) -> list:
    """Rows (covariance, fixed: largest difference of mean, variance and log-likelihood; fitted:
    relative difference of the hyperparameters and of the maximal log-likelihood).

    scikit-learn's diagonal jitter is switched off (``alpha=0``), its white-noise kernel is
    the noise, and it sees the outputs minus their mean (the library's prior mean).

    Examples
    --------
    >>> rows = sklearn_agreement()
    >>> all(row[1] < 1e-13 and row[2] < 1e-4 and row[3] < 1e-7 for row in rows)
    True
    """
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, WhiteKernel

    X, y, X_star, D, D_star = point_masses()
    centred, sy, l0 = y - y.mean(), float(np.std(y)), float(np.median(D[D > 0]))
    bounds = {
        "alpha": (1e-3 * sy, 1e3 * sy),
        "l": (1e-3 * l0, 1e3 * l0),
        "sigma_n": (1e-4 * sy, sy),
    }
    rows = []
    for covariance, (shape, kernel) in _sklearn_kernels().items():
        ours = DistributionGP(covariance, **shape).condition(D, y, alpha, l, sigma_n)
        mean, var = ours.predict(D_star, return_var=True)
        peer = GaussianProcessRegressor(
            ConstantKernel(alpha**2, "fixed") * kernel(l) + WhiteKernel(sigma_n**2, "fixed"),
            optimizer=None,
            alpha=0.0,
        )
        peer_mean, peer_std = peer.fit(X, centred).predict(X_star, return_std=True)
        fixed = max(
            np.abs(mean - peer_mean - y.mean()).max(),
            np.abs(var + sigma_n**2 - peer_std**2).max(),
            abs(
                ours.log_marginal_likelihood(alpha, l, sigma_n)
                - peer.log_marginal_likelihood_value_
            ),
        )
        fit = DistributionGP(covariance, n_restarts=restarts, bounds=bounds, **shape)
        fit = fit.fit(D, y, np.random.default_rng(1)).result
        squared = lambda pair: tuple(np.square(pair))
        peer = GaussianProcessRegressor(
            ConstantKernel(sy**2, squared(bounds["alpha"])) * kernel(l0, bounds["l"])
            + WhiteKernel((sy / 100) ** 2, squared(bounds["sigma_n"])),
            alpha=0.0,
            n_restarts_optimizer=restarts,
            random_state=0,
        )
        with warnings.catch_warnings():  # a noise at its lower bound: the same for both
            warnings.simplefilter("ignore", ConvergenceWarning)
            peer.fit(X, centred)
        amplitude, length, noise = np.exp(peer.kernel_.theta)
        rows.append(
            (
                covariance,
                float(fixed),
                _relative(
                    [fit.alpha, fit.l, fit.sigma_n], [np.sqrt(amplitude), length, np.sqrt(noise)]
                ),
                _relative(fit.log_ml, peer.log_marginal_likelihood_value_),
            )
        )
    return rows


def load_quantecon(root=None) -> dict:
    """QuantEcon's recorded numbers (``tests/reference/quantecon_lqmarkov.json``), arrays as arrays.

    Examples
    --------
    >>> record = load_quantecon()
    >>> record["cases"][0]["name"], record["cases"][0]["P"].ravel().round(5).tolist()
    ('scalar reproducer', [3.64588, 1.16537])
    """
    record = json.loads(paths.project(root).root.joinpath(*QUANTECON_FILE).read_text())
    record["cases"] = [
        {key: value if key == "name" else np.array(value) for key, value in case.items()}
        for case in record["cases"]
    ]
    return record


def coupled_riccati_residual(case, P):
    """X_i minus the right side of the coupled Riccati equations of [38], E_i(X) inside the inverse.

    Examples
    --------
    >>> case = load_quantecon()["cases"][0]
    >>> float(np.abs(coupled_riccati_residual(case, case["P"])).max()) > 0.1
    True
    """
    A, B, Q, R, Pi = (case[k] for k in ("A", "B", "Q", "R", "Pi"))
    E = np.einsum("ij,jab->iab", Pi, P)
    At, Bt = np.swapaxes(A, 1, 2), np.swapaxes(B, 1, 2)
    return P - (At @ E @ A + Q - At @ E @ B @ np.linalg.solve(R + Bt @ E @ B, Bt @ E @ A))


def expectation_outside(case, steps=20000):
    """QuantEcon's recursion, the expectation outside the inverse:
    P_i <- Q_i + sum_j Pi_ij [A'P_j A - A'P_j B (R + B'P_j B)^{-1} B'P_j A].

    Examples
    --------
    >>> case = load_quantecon()["cases"][0]
    >>> bool(np.allclose(expectation_outside(case), case["P"], rtol=1e-8))
    True
    """
    A, B, Q, R, Pi = (case[k] for k in ("A", "B", "Q", "R", "Pi"))
    At, Bt = np.swapaxes(A, 1, 2)[:, None], np.swapaxes(B, 1, 2)[:, None]
    A, B, R = A[:, None], B[:, None], R[:, None]
    P = np.stack([np.eye(A.shape[-1])] * len(Pi))
    for _ in range(steps):
        Pj = P[None]
        per_j = At @ Pj @ A - At @ Pj @ B @ np.linalg.solve(R + Bt @ Pj @ B, Bt @ Pj @ A)
        P = Q + np.einsum("ij,ijab->iab", Pi, per_j)
    return P


def policy_value(case, F):
    """The exact cost-to-go x' P_i x of u = -F_i x (beta = 1):
    P = Q + F'RF + (A - BF)' E(P) (A - BF), a coupled Lyapunov equation.

    Examples
    --------
    >>> case = load_quantecon()["cases"][0]
    >>> policy_value(case, case["F"]).ravel().round(5).tolist()
    [3.86576, 1.17911]
    """
    A_cl = case["A"] - case["B"] @ F
    weight = case["Q"] + np.swapaxes(F, 1, 2) @ case["R"] @ F
    return solve_coupled_lyapunov(A_cl, case["Pi"], weight, adjoint=True).X


def quantecon_comparison(case) -> dict:
    """The observed-mode design [38] of this library beside QuantEcon's recorded P and policy.

    Returns a dict: ``ours`` (P of :func:`asoc.mjls.observed_mode_state_feedback`), ``direct``
    (a root of :func:`coupled_riccati_residual` from P = Q), ``theirs`` (QuantEcon's P),
    ``theirs_recomputed`` (:func:`expectation_outside`), ``their_value`` (the exact value of
    QuantEcon's policy), and the relative gaps ``p_gap`` (theirs against ours), ``value_gap``
    (theirs against the value of their policy) and ``cost_ratio`` (trace sum of their policy's
    value over ours: above 1 when their policy costs more).

    Examples
    --------
    >>> out = quantecon_comparison(load_quantecon()["cases"][0])
    >>> out["ours"].ravel().round(8).tolist(), round(out["p_gap"], 4)
    ([3.8641453, 1.17900908], 0.0565)
    """
    n = case["A"].shape[1]
    sys = MJLS(
        A=case["A"],
        B=case["B"],
        C=np.eye(n),
        H=np.zeros((n, 1)),
        Q=case["Q"],
        R=case["R"],
        T=case["Pi"],
    )
    ours = observed_mode_state_feedback(sys).P
    shape = ours.shape
    direct = scipy.optimize.root(
        lambda p: coupled_riccati_residual(case, p.reshape(shape)).ravel(),
        case["Q"].ravel(),
        tol=1e-14,
    ).x.reshape(shape)
    value = policy_value(case, case["F"])
    trace = lambda P: float(np.trace(P, axis1=1, axis2=2).sum())
    return dict(
        ours=ours,
        direct=direct,
        theirs=case["P"],
        theirs_recomputed=expectation_outside(case),
        their_value=value,
        p_gap=_relative(case["P"], ours),
        direct_gap=_relative(direct, ours),
        value_gap=_relative(case["P"], value),
        cost_ratio=trace(value) / trace(ours),
    )
