"""The closed loops of an MJLS under a static gain (3.10) and a dynamic controller (3.39)-(3.40),
with the checks of the gains and the noise covariances they need.

- :func:`closed_loop`: A_i + B_i L C_i for u = L y;
- :func:`augmented_closed_loop`: the augmented loop of Prop. 3.20 for (3.37);
- :func:`controller_closed_loop`: the closed loop and its noise under any time-invariant
  controller or design result (what :func:`asoc.mjls.mean_square_stability` ``(sys, result)``
  and :func:`asoc.mjls.steady_state_second_moment` ``(sys, result)`` use);
- :func:`noise_covariances`: H_i H_i^T and J_i J_i^T of (3.36);
- :func:`gain_matrix`, ``_check_gains``: validated gains.

Each takes the gains as arrays, or the controller that holds them (an
:class:`asoc.mjls.Controller` or a design result with ``.controller``).
"""

import numpy as np

from ..linalg import transpose
from ..validation import real_array
from .controllers import (
    Controller,
    DynamicOutputFeedback,
    ModeDependentGain,
    StaticGain,
    as_controller,
)
from .system import check_system

__all__ = ["is_controller", "closed_loop", "gain_matrix", "noise_covariances",
           "augmented_closed_loop", "controller_closed_loop"]


def is_controller(value):
    """True for an :class:`asoc.mjls.Controller` or a design result with ``.controller``.

    Examples
    --------
    >>> is_controller(StaticGain([[1.0]])), is_controller(np.eye(2))
    (True, False)
    """
    return isinstance(value, Controller) or hasattr(type(value), "controller")   # not evaluated


def _gains(value, name, kind):
    """The controller of type ``kind`` held by ``value`` (a controller or a design result)."""
    controller = as_controller(value, name)
    if not isinstance(controller, kind) or getattr(controller, "time_variant", False):
        what = "a time-variant " if getattr(controller, "time_variant", False) else "a "
        raise TypeError(f"{name}: expected a {kind.__name__} or its gains, found {what}"
                        f"{type(controller).__name__}; average_cost(sys, controller) and "
                        f"controller_closed_loop(sys, controller) take any time-invariant "
                        f"controller")
    return controller


def closed_loop(sys, L, check=True):
    """Closed-loop matrices A_i + B_i L C_i of (3.10) for a mode-independent gain L.

    Parameters
    ----------
    sys : MJLS
    L : array_like, shape (nu, ny), StaticGain or design result
        Static output-feedback gain u = L y (3.8); a scalar when nu = ny = 1; or a
        :class:`asoc.mjls.StaticGain` or a static design's result
        (:func:`asoc.mjls.static_output_feedback`) that holds it.
    check : bool
        Validate ``sys`` and ``L`` (False: an MJLS and a float array with nu * ny entries, for the
        inner loops of Alg. 3.1).

    Returns
    -------
    numpy.ndarray, shape (M, nx, nx)

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS or ``L`` is not a real array.
    ValueError
        If ``L`` does not have shape (nu, ny) or is not finite.

    Examples
    --------
    >>> from asoc.mjls.examples import sec354_system
    >>> closed_loop(sec354_system(1, "C=[1 0]"), [[-0.5]])[0].tolist()
    [[1.2, 1.2], [-0.5, 1.0]]
    >>> from asoc.mjls import StaticGain
    >>> closed_loop(sec354_system(1, "C=[1 0]"), StaticGain([[-0.5]]))[0].tolist()
    [[1.2, 1.2], [-0.5, 1.0]]
    """
    if is_controller(L):
        L = _gains(L, "L", StaticGain).L
    if check:
        check_system(sys)
        L = gain_matrix(L, "L", sys.nu, sys.ny)
    return sys.A + sys.B @ np.reshape(L, (sys.nu, sys.ny)) @ sys.C


def gain_matrix(L, name, nu, ny):
    """A finite real gain of shape (nu, ny); a scalar or a flat array is accepted when nu = ny = 1.

    Examples
    --------
    >>> gain_matrix(-0.5, "L", 1, 1)
    array([[-0.5]])
    """
    L = real_array(L, name)
    if L.size == 1 and nu == ny == 1:
        return L.reshape(1, 1)
    if L.shape != (nu, ny):
        raise ValueError(f"{name}: expected shape ({nu}, {ny}), found shape {L.shape}")
    return L


def noise_covariances(sys):
    """H_i H_i^T (M, nx, nx) and J_i J_i^T (M, ny, ny) of (3.36); J = None means noise-free outputs.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> HHt, JJt = noise_covariances(sys)
    >>> HHt.shape, JJt.ravel().round(4)
    ((2, 2, 2), array([0.01, 0.01]))
    """
    check_system(sys)
    HHt = sys.H @ transpose(sys.H)
    JJt = np.zeros((sys.M, sys.ny, sys.ny)) if sys.J is None else sys.J @ transpose(sys.J)
    return HHt, JJt


def _check_gains(sys, F, K, L):
    """Validate F (nc, nc), K (nc, ny), L (nu, nc) of (3.37); return them as arrays.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> _check_gains(sec373_system(1), np.eye(2), np.ones((2, 1)), np.ones((1, 3)))
    Traceback (most recent call last):
    ...
    ValueError: L: expected shape (1, 2) (nc = 2 from F, nu = 1, ny = 1 from sys),
    found shape (1, 3)
    """
    check_system(sys)
    F = np.atleast_2d(real_array(F, "F"))
    nc = F.shape[0]
    F = real_array(F, "F", shape=(nc, nc))
    K, L = np.atleast_2d(real_array(K, "K")), np.atleast_2d(real_array(L, "L"))
    for name, g, shape in (("K", K, (nc, sys.ny)), ("L", L, (sys.nu, nc))):
        if g.shape != shape:
            raise ValueError(f"{name}: expected shape {shape} (nc = {nc} from F, "
                             f"nu = {sys.nu}, ny = {sys.ny} from sys), found shape {g.shape}")
    return F, K, L


def augmented_closed_loop(sys, F, K=None, L=None):
    """The augmented closed loop (3.39)-(3.40) and weight of Prop. 3.20 for x~ = [x; x^].

    A~_i = [[A_i, B_i L], [K C_i, F]], H~_i H~_i^T = diag(H_i H_i^T, K J_i J_i^T K^T),
    Q~_i = diag(Q_i, L^T R_i L).

    Parameters
    ----------
    sys : MJLS
    F, K, L : array_like, shapes (nc, nc), (nc, ny), (nu, nc)
        Gains of the controller (3.37); or F a time-invariant
        :class:`asoc.mjls.DynamicOutputFeedback` or a dynamic design's result (e.g. of
        :func:`asoc.mjls.exact_dynamic_output_feedback`), and K, L omitted.

    Returns
    -------
    At : numpy.ndarray, (M, nx + nc, nx + nc)
        The augmented closed loop (3.39).
    HHt_cl : numpy.ndarray, (M, nx + nc, nx + nc)
        Its noise covariances.
    Qt : numpy.ndarray, (M, nx + nc, nx + nc)
        Its cost weights.

    Raises
    ------
    ValueError
        If a gain has the wrong shape or non-finite entries.
    TypeError
        If F is a controller other than a time-invariant DynamicOutputFeedback, or K, L are
        given with it, or missing without it.

    Examples
    --------
    >>> from asoc.mjls.examples import sec373_system
    >>> sys = sec373_system(1)
    >>> At, Wt, Qt = augmented_closed_loop(sys, 0.5 * np.eye(2), np.ones((2, 1)), -np.ones((1, 2)))
    >>> At.shape, At[0, 2:, :2].tolist()
    ((2, 4, 4), [[1.0, 0.0], [1.0, 0.0]])

    A design result in place of the gains:

    >>> from asoc.mjls import dynamic_output_feedback
    >>> res = dynamic_output_feedback(sys)
    >>> by_gains = augmented_closed_loop(sys, res.F, res.K, res.L)
    >>> all(np.array_equal(a, b) for a, b in zip(augmented_closed_loop(sys, res), by_gains))
    True
    """
    F, K, L = _dynamic_gains(F, K, L)
    F, K, L = _check_gains(sys, F, K, L)
    M, nx, nc = sys.M, sys.nx, F.shape[0]
    HHt, JJt = noise_covariances(sys)
    At = np.zeros((M, nx + nc, nx + nc))
    At[:, :nx, :nx] = sys.A
    At[:, :nx, nx:] = sys.B @ L
    At[:, nx:, :nx] = K @ sys.C
    At[:, nx:, nx:] = F
    HHt_cl = np.zeros_like(At)
    HHt_cl[:, :nx, :nx] = HHt
    HHt_cl[:, nx:, nx:] = K @ JJt @ K.T
    Qt = np.zeros_like(At)
    Qt[:, :nx, :nx] = sys.Q
    Qt[:, nx:, nx:] = L.T @ sys.R @ L
    return At, HHt_cl, Qt


def _dynamic_gains(F, K, L):
    """(F, K, L) as given, or those of the dynamic controller (or result) passed as F."""
    if is_controller(F):
        if K is not None or L is not None:
            raise TypeError("K, L: expected to be omitted when F is a controller or a design "
                            "result, found gains")
        controller = _gains(F, "F", DynamicOutputFeedback)
        return controller.F, controller.K, controller.L
    if K is None or L is None:
        raise TypeError(f"{'K' if K is None else 'L'}: expected the gain with F, K, L as arrays, "
                        f"found None (or pass a dynamic controller or design result as F)")
    return F, K, L


def controller_closed_loop(sys, controller, name="controller"):
    """The closed loop of ``sys`` under a time-invariant controller, and its noise covariance.

    u = L y (:class:`asoc.mjls.StaticGain`, (3.10)): A_i + B_i L C_i and
    H_i H_i^T + B_i L J_i J_i^T L^T B_i^T; u = L_i y (:class:`asoc.mjls.ModeDependentGain`):
    the same with L_i; (3.37) (:class:`asoc.mjls.DynamicOutputFeedback`): the augmented loop
    (3.39)-(3.40) of :func:`augmented_closed_loop` in x~ = [x; x^].

    Parameters
    ----------
    sys : MJLS
    controller : Controller or design result
        A time-invariant controller, or a design result whose ``.controller`` is one.
    name : str
        The argument's name in error messages.

    Returns
    -------
    Acl : numpy.ndarray, shape (M, n, n)
        The closed loop; n = nx, or nx + nc for the dynamic controller.
    HHt_cl : numpy.ndarray, shape (M, n, n)
        Its noise covariances.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, or ``controller`` is not a time-invariant controller (nor a
        result holding one).
    ValueError
        If the controller does not fit the system.

    Examples
    --------
    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> sys = sec354_system(1)
    >>> res = static_output_feedback(sys)
    >>> Acl, HHt_cl = controller_closed_loop(sys, res)
    >>> bool(np.allclose(Acl, closed_loop(sys, res.L))), Acl.shape
    (True, (2, 2, 2))
    """
    check_system(sys)
    controller = as_controller(controller, name)
    controller.check(sys)
    if isinstance(controller, DynamicOutputFeedback) and not controller.time_variant:
        return augmented_closed_loop(sys, controller.F, controller.K, controller.L)[:2]
    if not isinstance(controller, (StaticGain, ModeDependentGain)):
        raise TypeError(f"{name}: expected a time-invariant controller (StaticGain, "
                        f"ModeDependentGain, DynamicOutputFeedback) or a design result with one, "
                        f"found "
                        f"{'a time-variant ' if getattr(controller, 'time_variant', False) else ''}"
                        f"{type(controller).__name__}")
    HHt, JJt = noise_covariances(sys)
    BL = sys.B @ controller.L
    return sys.A + BL @ sys.C, HHt + BL @ JJt @ transpose(BL)
