"""The exact average cost (3.9) of a time-invariant controller without mode observation."""

from .controllers import DynamicOutputFeedback, StaticGain, as_controller
from .dynamic import steady_state_cost
from .static import static_cost
from .system import check_system

__all__ = ["average_cost"]


def average_cost(sys, controller):
    """The exact average cost (3.9) of a time-invariant controller without mode observation.

    u = L y (:class:`StaticGain`): Prop. 3.7 with the measurement noise J
    (:func:`asoc.mjls.static_cost`); the dynamic controller (3.37)
    (:class:`DynamicOutputFeedback` with constant F, K, L): Prop. 3.24
    (:func:`asoc.mjls.steady_state_cost`). Its initial state does not enter the
    average cost.

    Parameters
    ----------
    sys : MJLS
    controller : StaticGain, DynamicOutputFeedback, or a design result with ``.controller``

    Returns
    -------
    float
        inf when the closed loop is not certified mean-square stable.

    Raises
    ------
    TypeError
        If ``sys`` is not an MJLS, or ``controller`` is not one of these (a time-variant or
        mode-observing controller has no average cost here; use
        :func:`asoc.mjls.finite_horizon_cost` or :func:`simulate`).
    ValueError
        If the controller does not fit the system.

    Examples
    --------
    The networked loop: a static gain against the exact dynamic design.

    >>> from asoc.mjls import exact_dynamic_output_feedback, static_output_feedback
    >>> from asoc.mjls.examples import networked_loop
    >>> sys = networked_loop()
    >>> static, dynamic = static_output_feedback(sys), exact_dynamic_output_feedback(sys)
    >>> round(average_cost(sys, static), 4), round(average_cost(sys, dynamic), 4)
    (0.1412, 0.1376)
    """
    check_system(sys)
    controller = as_controller(controller)
    controller.check(sys)
    if isinstance(controller, StaticGain):
        return static_cost(sys, controller.L)[0]
    if isinstance(controller, DynamicOutputFeedback) and not controller.time_variant:
        return steady_state_cost(sys, controller.F, controller.K, controller.L)[0]
    variant = " (time-variant)" if getattr(controller, "time_variant", False) else ""
    raise TypeError("controller: expected a StaticGain or a time-invariant DynamicOutputFeedback, "
                    f"found {type(controller).__name__}{variant}; "
                    "for a finite horizon use finite_horizon_cost or simulate")
