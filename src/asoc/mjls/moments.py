"""Second moments X_k^i = E{x_k x_k^T 1(theta_k = i)} (3.28) and the H2 cost (Prop. 3.7)."""

import numpy as np

from ..linalg import transpose
from ..validation import integer, probability_vector, real_array, semidefinite, stochastic_matrix
from .closed_loops import controller_closed_loop, gain_matrix, is_controller
from .lyapunov import solve_coupled_lyapunov
from .moment_operator import second_moment_map
from .stability import MeanSquareStability, mean_square_stability
from .system import MJLS, check_system, predecessor_sum

__all__ = ["second_moment_step", "second_moments", "steady_state_second_moment",
           "certified_second_moment", "h2_cost"]


_NO_MOMENT = object()


def _moment_arguments(Acl, HHt, T, mu, X=_NO_MOMENT, X_name="X", mu_name="mu"):
    """Validated closed loop and noise (M, n, n), T (M, M), mu (M,) and optional X (M, n, n)."""
    Acl = real_array(Acl, "Acl", ndim=3)
    M, n, _ = Acl.shape
    Acl = real_array(Acl, "Acl", shape=(M, n, n))
    why = f"(M = {M}, n = {n} from Acl)"
    HHt = real_array(HHt, "HHt")
    if HHt.shape != (M, n, n):
        raise ValueError(f"HHt: expected shape ({M}, {n}, {n}) {why}, found shape {HHt.shape}")
    T = real_array(T, "T")
    if T.shape != (M, M):
        raise ValueError(f"T: expected shape ({M}, {M}) {why}, found shape {T.shape}")
    T = stochastic_matrix(T, "T", M)
    mu = real_array(mu, mu_name)
    if mu.shape != (M,):
        raise ValueError(f"{mu_name}: expected shape ({M},) {why}, found shape {mu.shape}")
    mu = probability_vector(mu, mu_name, M)
    semidefinite(HHt, "HHt")
    if X is not _NO_MOMENT:
        X = real_array(X, X_name)
        if X.shape != (M, n, n):
            raise ValueError(f"{X_name}: expected shape ({M}, {n}, {n}) {why}, "
                             f"found shape {X.shape}")
        semidefinite(X, X_name)
    return Acl, HHt, T, mu, X


def second_moment_step(Acl, HHt, T, X, mu):
    """One step of (3.29): X_{k+1}^j = sum_i p_ij [Acl_i X^i Acl_i^T + mu^i H_i H_i^T].

    Parameters
    ----------
    Acl : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices.
    HHt : numpy.ndarray, shape (M, n, n)
        Noise covariances H_i H_i^T.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    X : numpy.ndarray, shape (M, n, n)
        Second moments X_k^i = E{x_k x_k^T 1(theta_k = i)} (3.28).
    mu : numpy.ndarray, shape (M,)
        Mode distribution at step k.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)
        X_{k+1}.

    Raises
    ------
    TypeError, ValueError
        Naming the argument, if an array is not real, not finite, of inconsistent shape, T
        not stochastic or mu not a distribution.

    Examples
    --------
    >>> step = second_moment_step(np.array([[[0.5]]]), np.array([[[1.0]]]), [[1.0]],
    ...                           np.array([[[4.0]]]), [1.0])
    >>> step
    array([[[2.]]])
    """
    Acl, HHt, T, mu, X = _moment_arguments(Acl, HHt, T, mu, X)
    return second_moment_map(Acl, T, X) + predecessor_sum(T, mu[:, None, None] * HHt, check=False)


def second_moments(Acl, HHt, T, X0, mu0, horizon):
    """X_k^i for k = 0..horizon by (3.29), with mode distributions mu_k = mu_0 T^k.

    Parameters
    ----------
    Acl, HHt : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices and noise covariances H_i H_i^T.
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    X0 : numpy.ndarray, shape (M, n, n)
        Initial second moments.
    mu0 : numpy.ndarray, shape (M,)
        Initial mode distribution.
    horizon : int
        Number of steps K.

    Returns
    -------
    X : numpy.ndarray, shape (horizon + 1, M, n, n)
    mu : numpy.ndarray, shape (horizon + 1, M)

    Raises
    ------
    TypeError, ValueError
        As :func:`second_moment_step`, and for a horizon that is not an integer >= 0.

    Examples
    --------
    >>> X, mu = second_moments(np.array([[[0.5]]]), np.array([[[1.0]]]), [[1.0]],
    ...                        np.zeros((1, 1, 1)), [1.0], 2)
    >>> X.ravel()
    array([0.  , 1.  , 1.25])
    """
    Acl, HHt, T, mu0, X0 = _moment_arguments(Acl, HHt, T, mu0, X0, "X0", "mu0")
    horizon = integer(horizon, "horizon", minimum=0)
    X = np.empty((horizon + 1,) + np.shape(X0))
    mu = np.empty((horizon + 1, len(mu0)))
    X[0], mu[0] = X0, mu0
    for k in range(horizon):
        mu[k + 1] = mu[k] @ T
    # predecessor_sum for every k
    noise = np.einsum("ji,kj...->ki...", T, mu[:-1, :, None, None] * HHt)
    Aclt, Tt, M = np.swapaxes(Acl, 1, 2), T.T, len(T)
    # (3.29) on the validated arguments: second_moment_map written out
    for k in range(horizon):
        Y = Acl @ X[k] @ Aclt
        np.matmul(Tt, Y.reshape(M, -1), out=X[k + 1].reshape(M, -1))
        X[k + 1] += noise[k]
    return X, mu


def steady_state_second_moment(Acl, HHt, T=None, mu_inf=None):
    """X_inf^i solving the coupled Lyapunov equations of Prop. 3.7 / (3.32) directly.

    Vectorised: vec X^j = sum_i p_ij [(Acl_i (x) Acl_i) vec X^i + mu_i vec(H_i H_i^T)], solved
    by :func:`asoc.mjls.lyapunov.solve_coupled_lyapunov` (dense LU for small M n^2, else
    BiCGSTAB on the operator to a relative residual of 1e-12). A stationary moment exists
    only when the closed loop is mean-square stable (Cor. 3.2): that is certified first
    (:func:`asoc.mjls.mean_square_stability`), and the solution's residual is checked.

    Parameters
    ----------
    Acl, HHt : numpy.ndarray, shape (M, n, n)
        Closed-loop matrices and noise covariances; or an MJLS and a time-invariant controller
        or design result, whose closed loop and noise
        (:func:`asoc.mjls.closed_loops.controller_closed_loop`) are used with the system's T
        and mu_inf (then ``T`` and ``mu_inf`` are omitted). For a dynamic controller the
        moments are those of x~ = [x; x^] (Prop. 3.23).
    T : numpy.ndarray, shape (M, M)
        Transition matrix.
    mu_inf : numpy.ndarray, shape (M,)
        Stationary mode distribution.

    Returns
    -------
    numpy.ndarray, shape (M, n, n)
        The stationary second moments (symmetrised).

    Raises
    ------
    TypeError, ValueError
        As :func:`second_moment_step` (``mu_inf`` a distribution), and for a controller that is
        not time-invariant or does not fit the MJLS.
    numpy.linalg.LinAlgError
        If mean-square stability is not certified (rho >= 1, or its bracket straddles 1, e.g.
        rho = 1 exactly: I - M is singular), or the solution misses the residual
        ``config.defaults["mjls.solve_residual_max"]``.

    Examples
    --------
    x+ = 0.5 x + w has stationary variance 1 / (1 - 0.25):

    >>> A, HHt = np.array([[[0.5]]]), np.array([[[1.0]]])
    >>> steady_state_second_moment(A, HHt, [[1.0]], [1.0]).round(4)
    array([[[1.3333]]])

    A random walk (rho = 1) has none:

    >>> steady_state_second_moment(np.array([[[1.0]]]), np.array([[[1.0]]]), [[1.0]], [1.0])
    Traceback (most recent call last):
    ...
    numpy.linalg.LinAlgError: Acl: no stationary second moment: the closed loop is not certified
    mean-square stable (rho = 1 in [1, 1], undecided; Cor. 3.2)

    The stationary moments of a design's closed loop:

    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> X = steady_state_second_moment(sys, static_output_feedback(sys))
    >>> X.shape, bool(np.all(np.linalg.eigvalsh(X) > 0))
    ((2, 2, 2), True)
    """
    if isinstance(Acl, MJLS) and is_controller(HHt):
        if T is not None or mu_inf is not None:
            raise TypeError("T, mu_inf: expected to be omitted with an MJLS and a controller (the "
                            "system's own are used), found arrays")
        Acl, HHt, T, mu_inf = (*controller_closed_loop(Acl, HHt, "HHt"), Acl.T, Acl.mu_inf)
    Acl, HHt, T, mu_inf, _ = _moment_arguments(Acl, HHt, T, mu_inf, mu_name="mu_inf")
    stability = mean_square_stability(Acl, T, check=False)
    return certified_second_moment(Acl, HHt, T, mu_inf, stability, check=False)


def certified_second_moment(Acl, HHt, T, mu_inf, stability, check=True):
    """:func:`steady_state_second_moment` with the certificate ``stability``
    (:func:`asoc.mjls.mean_square_stability` of (Acl, T)) that the caller already has: one spectral
    radius per closed loop, not one per use.

    Raises
    ------
    TypeError
        If ``stability`` is not a MeanSquareStability; the arrays as
        :func:`steady_state_second_moment` (``check=False``: float arrays of consistent shapes, not
        validated).
    numpy.linalg.LinAlgError
        As :func:`steady_state_second_moment`.

    Examples
    --------
    >>> A, T = np.array([[[0.5]]]), np.array([[1.0]])
    >>> stability = mean_square_stability(A, T)
    >>> certified_second_moment(A, np.ones((1, 1, 1)), T, np.ones(1), stability).round(4)
    array([[[1.3333]]])
    >>> certified_second_moment(A, np.ones((1, 1, 1)), T, np.ones(1), 0.25)
    Traceback (most recent call last):
    ...
    TypeError: stability: expected the MeanSquareStability of (Acl, T), found float
    """
    if check:
        Acl, HHt, T, mu_inf, _ = _moment_arguments(Acl, HHt, T, mu_inf, mu_name="mu_inf")
        if not isinstance(stability, MeanSquareStability):
            raise TypeError(f"stability: expected the MeanSquareStability of (Acl, T), found "
                            f"{type(stability).__name__}")
    if not stability.stable:
        raise np.linalg.LinAlgError(
            "Acl: no stationary second moment: the closed loop is not certified mean-square "
            f"stable (rho = {stability.rho:.6g} in "
            f"[{stability.rho_lower:.6g}, {stability.rho_upper:.6g}], "
            f"{stability.verdict.value}; Cor. 3.2)")
    noise = predecessor_sum(T, mu_inf[:, None, None] * HHt, check=False)
    solution = solve_coupled_lyapunov(Acl, T, noise)
    if not solution.accepted:
        raise np.linalg.LinAlgError("the stationary second moment was not found: relative "
                                    f"residual {solution.residual:.3g} of the coupled Lyapunov "
                                    f"solve ({solution.method})")
    return solution.X


def h2_cost(sys, L, X_inf, check=True):
    """sum_i tr[(Q_i + C_i^T L^T R_i L C_i) X_inf^i] (Prop. 3.7 and Prop. 3.15).

    Parameters
    ----------
    sys : MJLS
    L : array_like, shape (nu, ny)
        Static gain.
    X_inf : numpy.ndarray, shape (M, nx, nx)
        Stationary second moments of the closed loop (:func:`steady_state_second_moment`).
    check : bool
        Validate the arguments (False: ``L`` a float (nu, ny) array and ``X_inf`` a symmetric
        (M, nx, nx) stack, for loops over many gains).

    Returns
    -------
    float
        The average (H2) cost (3.9) of u = L y.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS or an array is not real.
    ValueError
        If ``L`` does not have shape (nu, ny) or ``X_inf`` not (M, nx, nx), or they are not finite.

    Examples
    --------
    >>> from asoc.mjls import closed_loop
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> X = steady_state_second_moment(closed_loop(sys, [[-0.4]]), sys.H @ np.swapaxes(sys.H, 1, 2),
    ...                                sys.T, sys.mu_inf)
    >>> round(h2_cost(sys, [[-0.4]], X), 4)
    0.7999
    """
    if check:
        check_system(sys)
        L = gain_matrix(L, "L", sys.nu, sys.ny)
        X_inf = semidefinite(real_array(X_inf, "X_inf", shape=(sys.M, sys.nx, sys.nx)), "X_inf")
    LC = L @ sys.C
    weight = sys.Q + transpose(LC) @ sys.R @ LC
    return float(np.einsum("iab,iba->", weight, X_inf))
