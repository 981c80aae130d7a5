"""The controllers of an MJLS (3.7): the static gains (3.8), (3.24), a gain sequence and the
dynamic controller (3.37)/(3.55), for :func:`asoc.mjls.simulate`, the exact costs, the
closed loops and python-control (``to_statespace``).

Each design's ``.controller`` is one of these, with the certificate of its closed loop
(``stability``) when the design computed one; the repr shows its type, sizes and verdict.
"""

import numpy as np

from ..validation import real_array, real_scalar
from .system import import_control

__all__ = ["Controller", "as_controller", "StaticGain", "ModeDependentGain", "TimeVariantGain",
           "DynamicOutputFeedback"]


class Controller:
    """Protocol of a controller in :func:`simulate`.

    ``start(n_runs)`` returns the initial controller state; ``input(k, y, theta, state)``
    returns ``(u, state)`` for measurements ``y`` (N, ny). ``theta`` (N,) is passed to
    every controller, but only controllers with ``observes_mode = True`` may use it.
    ``check(sys)`` raises a ValueError when the controller does not fit the system; it runs
    before the simulation. ``stability`` is the certificate of the closed loop on the system
    the controller was designed for (a :class:`asoc.mjls.MeanSquareStability`, set by a
    design's ``.controller``), or None when unknown; the repr shows it.

    Examples
    --------
    A user-defined controller: u = -0.5 y.

    >>> class Proportional(Controller):
    ...     def input(self, k, y, theta, state):
    ...         return -0.5 * y, state
    >>> Proportional().start(3) is None, Proportional()
    (True, Proportional())
    """

    observes_mode = False
    stability = None

    def start(self, n_runs):
        """The initial controller state for ``n_runs`` runs (None: stateless)."""
        return None

    def input(self, k, y, theta, state):
        """``(u, state)`` at step k for measurements ``y`` (N, ny) and modes ``theta`` (N,)."""
        raise NotImplementedError

    def check(self, sys):
        """Raise a ValueError when the controller does not fit ``sys`` (default: accept)."""

    def to_statespace(self, dt=True):
        """The controller from y to u as a python-control ``StateSpace`` (``asoc[control]``).

        Only time-invariant controllers have one; this default raises a TypeError.
        """
        raise TypeError(f"{type(self).__name__} has no time-invariant state-space realisation; "
                        f"to_statespace takes a StaticGain, a ModeDependentGain or a "
                        f"time-invariant DynamicOutputFeedback")

    def _sizes(self):
        """The sizes the repr shows, by name."""
        return {}

    def __repr__(self):
        sizes = ", ".join(f"{name}={value}" for name, value in self._sizes().items())
        known = "" if self.stability is None else f"; designed loop: {self.stability.sentence()}"
        return f"{type(self).__name__}({sizes}{known})"


def as_controller(controller, name="controller", sys=None):
    """The Controller itself, or the ``.controller`` of a design result; else a TypeError.

    A result whose ``controller`` is a method of the system
    (:class:`asoc.mjls.ModeObservedResult`) is called with ``sys``.

    Examples
    --------
    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> as_controller(static_output_feedback(sec354_system(1))).L.round(4)
    array([[-0.635]])
    >>> as_controller(np.eye(2))
    Traceback (most recent call last):
    ...
    TypeError: controller: expected an asoc.mjls.Controller (e.g. StaticGain) or a design result \
with .controller, found ndarray
    """
    if not isinstance(controller, Controller):
        inner = getattr(controller, "controller", None)
        if callable(inner) and not isinstance(inner, Controller) and sys is not None:
            inner = inner(sys)
        if isinstance(inner, Controller):
            controller = inner
    if not isinstance(controller, Controller):
        raise TypeError(f"{name}: expected an asoc.mjls.Controller (e.g. StaticGain) or a design "
                        f"result with .controller, found {type(controller).__name__}")
    return controller


def _fit(array, name, shape, sys):
    if array.shape != shape:
        raise ValueError(f"{name}: expected shape {shape} for the system (M={sys.M}, nx={sys.nx}, "
                         f"nu={sys.nu}, ny={sys.ny}), found shape {array.shape}")


def _certificate(stability):
    """``stability`` checked: a MeanSquareStability (known by its interface) or None."""
    if stability is not None and not callable(getattr(stability, "sentence", None)):
        raise TypeError(f"stability: expected an asoc.mjls.MeanSquareStability or None, found "
                        f"{type(stability).__name__}")
    return stability


def _statespace(F, K, L, D, dt, name):
    """``control.ss(F, K, L, D, dt)`` from y to u, its signals named y[j], u[i], xhat[k]."""
    control = import_control()
    if dt is None:
        dt = True
    elif dt is not True:
        dt = real_scalar(dt, "dt", low=0, low_open=True)
    (nu, ny), nc = D.shape, F.shape[0]
    return control.ss(F, K, L, D, dt, name=name, inputs=[f"y[{j}]" for j in range(ny)],
                      outputs=[f"u[{i}]" for i in range(nu)],
                      states=[f"xhat[{k}]" for k in range(nc)])


def _gain_statespace(L, dt, name):
    """The gain u = L y as a StateSpace without states (D = L)."""
    nu, ny = L.shape
    return _statespace(np.zeros((0, 0)), np.zeros((0, ny)), np.zeros((nu, 0)), L, dt, name)


class StaticGain(Controller):
    """u_k = L y_k, mode-independent (3.8).

    Parameters
    ----------
    L : array_like, shape (nu, ny)
    stability : asoc.mjls.MeanSquareStability, optional
        The certificate of the closed loop on the system the gain was designed for.

    Examples
    --------
    >>> c = StaticGain([[-0.5, 0.1]])
    >>> c.input(0, np.array([[2.0, 0.0]]), None, None)[0], c
    (array([[-1.]]), StaticGain(nu=1, ny=2))
    >>> c.to_statespace(0.1).D.tolist()
    [[-0.5, 0.1]]
    """

    def __init__(self, L, *, stability=None):
        self.L = np.atleast_2d(real_array(L, "L"))
        if self.L.ndim != 2:
            raise ValueError(f"L: expected shape (nu, ny), found shape {self.L.shape}")
        self.stability = _certificate(stability)

    def input(self, k, y, theta, state):
        """``(u, state)`` at step k (:meth:`Controller.input`)."""
        return y @ self.L.T, state

    def check(self, sys):
        """Raise a ValueError naming the gain that does not fit ``sys``."""
        _fit(self.L, "L", (sys.nu, sys.ny), sys)

    def to_statespace(self, dt=True):
        """The gain u = L y as a ``control.StateSpace`` without states (D = L), from y[j] to u[i].

        Parameters
        ----------
        dt : float, True or None
            Sampling time (True or None: discrete, period unspecified, as python-control's
            True).

        Raises
        ------
        ImportError
            If python-control is not installed.
        ValueError
            If ``dt`` is not positive.
        """
        return _gain_statespace(self.L, dt, "StaticGain")

    def _sizes(self):
        return dict(nu=self.L.shape[0], ny=self.L.shape[1])


class ModeDependentGain(Controller):
    """u_k = L_{theta_k} y_k (3.24): requires the mode, e.g. the optimal controller of [38].

    Parameters
    ----------
    L : array_like, shape (M, nu, ny)
    stability : asoc.mjls.MeanSquareStability, optional
        The certificate of the closed loop on the system the gains were designed for.

    Examples
    --------
    >>> c = ModeDependentGain([[[-1.0]], [[-2.0]]])
    >>> c.input(0, np.array([[1.0], [1.0]]), np.array([0, 1]), None)[0]
    array([[-1.],
           [-2.]])
    >>> c, [float(s.D[0, 0]) for s in c.to_statespace()]
    (ModeDependentGain(M=2, nu=1, ny=1), [-1.0, -2.0])
    """

    observes_mode = True

    def __init__(self, L, *, stability=None):
        self.L = real_array(L, "L", ndim=3)
        self.stability = _certificate(stability)

    def input(self, k, y, theta, state):
        """``(u, state)`` at step k (:meth:`Controller.input`)."""
        return np.einsum("nab,nb->na", self.L[theta], y), state

    def check(self, sys):
        """Raise a ValueError naming the gain that does not fit ``sys``."""
        _fit(self.L, "L", (sys.M, sys.nu, sys.ny), sys)

    def to_statespace(self, dt=True):
        """One ``control.StateSpace`` u = L_i y (no states, D = L_i) per mode i, in a list.

        Raises
        ------
        ImportError
            If python-control is not installed.
        ValueError
            If ``dt`` is not positive.
        """
        return [_gain_statespace(Li, dt, f"ModeDependentGain[{i}]") for i, Li in enumerate(self.L)]

    def _sizes(self):
        return dict(zip(("M", "nu", "ny"), self.L.shape))


class TimeVariantGain(Controller):
    """u_k = L_k y_k with a gain sequence L of shape (horizon, nu, ny) (e.g. [165], [163]).

    Examples
    --------
    >>> c = TimeVariantGain([[[-1.0]], [[-2.0]]])
    >>> c.input(1, np.array([[1.0]]), None, None)[0], c
    (array([[-2.]]), TimeVariantGain(horizon=2, nu=1, ny=1))
    """

    def __init__(self, L):
        self.L = real_array(L, "L", ndim=3)

    def input(self, k, y, theta, state):
        """``(u, state)`` at step k (:meth:`Controller.input`)."""
        return y @ self.L[min(k, len(self.L) - 1)].T, state

    def check(self, sys):
        """Raise a ValueError naming the gain that does not fit ``sys``."""
        _fit(self.L, "L", (len(self.L), sys.nu, sys.ny), sys)

    def _sizes(self):
        return dict(zip(("horizon", "nu", "ny"), self.L.shape))


class DynamicOutputFeedback(Controller):
    """x^_{k+1} = F_k x^_k + K_k y_k, u_k = L_k x^_k (3.37); F, K, L constant or (horizon, ...).

    Parameters
    ----------
    F, K, L : array_like
        Shapes (nc, nc), (nc, ny), (nu, nc), or each with a leading horizon (3.55).
    xhat0 : array_like, shape (nc,), optional
        The controller's initial state, default zero.
    stability : asoc.mjls.MeanSquareStability, optional
        The certificate of the closed loop on the system it was designed for.

    Examples
    --------
    >>> c = DynamicOutputFeedback([[0.5]], [[1.0]], [[-1.0]], xhat0=[2.0])
    >>> u, xhat = c.input(0, np.array([[1.0]]), None, c.start(1))
    >>> u, xhat, c
    (array([[-2.]]), array([[2.]]), DynamicOutputFeedback(nc=1, ny=1, nu=1))
    """

    def __init__(self, F, K, L, xhat0=None, *, stability=None):
        self.F, self.K, self.L = (real_array(a, name) for a, name in ((F, "F"), (K, "K"), (L, "L")))
        if self.F.ndim not in (2, 3) or self.F.shape[-1] != self.F.shape[-2]:
            raise ValueError(f"F: expected shape (nc, nc) or (horizon, nc, nc), found shape "
                             f"{self.F.shape}")
        self.time_variant = self.F.ndim == 3
        nc = self.F.shape[-1]
        self.xhat0 = np.zeros(nc) if xhat0 is None else real_array(xhat0, "xhat0")
        if self.xhat0.shape != (nc,):
            raise ValueError(f"xhat0: expected shape ({nc},) (nc = {nc} from F), found shape "
                             f"{self.xhat0.shape}")
        self.stability = _certificate(stability)

    def check(self, sys):
        """Raise a ValueError naming the gain that does not fit ``sys``."""
        lead = self.F.shape[:-2]
        nc = self.F.shape[-1]
        _fit(self.K, "K", lead + (nc, sys.ny), sys)
        _fit(self.L, "L", lead + (sys.nu, nc), sys)

    def _at(self, k):
        if not self.time_variant:
            return self.F, self.K, self.L
        k = min(k, len(self.F) - 1)
        return self.F[k], self.K[k], self.L[k]

    def start(self, n_runs):
        """The initial controller state x^_0 for ``n_runs`` runs, (n_runs, nc)."""
        return np.broadcast_to(self.xhat0, (n_runs, self.xhat0.size)).copy()

    def input(self, k, y, theta, xhat):
        """``(u, state)`` at step k (:meth:`Controller.input`)."""
        F, K, L = self._at(k)
        u = xhat @ L.T
        return u, xhat @ F.T + y @ K.T

    def to_statespace(self, dt=True):
        """(3.37) as ``control.ss(F, K, L, 0, dt)``: input y, output u, state x^.

        u = L x^ enters the plant as it is, so the loop closes with positive feedback:
        ``control.feedback(plant_mode, controller, sign=1)``.

        Parameters
        ----------
        dt : float, True or None
            Sampling time (True or None: discrete, period unspecified, as python-control's
            True).

        Raises
        ------
        TypeError
            If the controller is time-variant (3.55).
        ImportError
            If python-control is not installed.
        ValueError
            If ``dt`` is not positive.

        Examples
        --------
        >>> ss = DynamicOutputFeedback([[0.5]], [[1.0]], [[-1.0]]).to_statespace(0.1)
        >>> ss.A.tolist(), ss.input_labels, ss.output_labels, ss.dt
        ([[0.5]], ['y[0]'], ['u[0]'], 0.1)
        """
        if self.time_variant:
            super().to_statespace(dt)
        return _statespace(self.F, self.K, self.L, np.zeros((self.L.shape[0], self.K.shape[1])),
                           dt, "DynamicOutputFeedback")

    def _sizes(self):
        lead = dict(horizon=self.F.shape[0]) if self.time_variant else {}
        return lead | dict(nc=self.F.shape[-1], ny=self.K.shape[-1], nu=self.L.shape[-2])
