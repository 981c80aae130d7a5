"""What the result of every controller design shares: the controller it designed and, for a
time-invariant design, the certificate of its closed loop (Cor. 3.2).

- :class:`DesignResult`: ``controller`` built once here from the result's gains (the
  subclass names the controller's type and the fields it takes);
- :class:`CertifiedDesignResult`: also ``stability``, the :class:`asoc.mjls.MeanSquareStability`
  of the closed loop, with ``rho``, ``rho_bracket`` and ``stabilizing`` read from it.

A finite-horizon design (Alg. 3.3, the time-variant baselines) has a :class:`DesignResult`
only: mean-square stability is a property of the infinite horizon.
"""

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..result import IterativeResult
from .controllers import StaticGain
from .stability import MeanSquareStability

__all__ = ["DesignResult", "CertifiedDesignResult"]


@dataclass(kw_only=True)
class DesignResult(IterativeResult):
    """Base of a design's result: why it stopped (:class:`asoc.result.IterativeResult`) and the
    ``controller`` it designed.

    A subclass sets ``controller_type`` (an :class:`asoc.mjls.Controller` class) and
    ``controller_fields``, the names of its fields that are the controller's arguments, in
    order.

    Examples
    --------
    >>> from asoc.mjls import static_output_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> res = static_output_feedback(sec354_system(1))
    >>> isinstance(res, DesignResult), res.controller
    (True, StaticGain(nu=1, ny=1; designed loop: rho = 0.8178, certified in [0.81776, 0.81776]: \
stable))
    """

    controller_type: ClassVar[type] = StaticGain
    controller_fields: ClassVar[tuple] = ("L",)

    @property
    def controller(self):
        """The designed controller, for :func:`asoc.mjls.simulate`, :func:`asoc.mjls.average_cost`,
        :func:`asoc.mjls.mean_square_stability` ``(sys, controller)`` and ``to_statespace``; it
        carries the design's certificate (``stability``) where there is one.

        Raises
        ------
        ValueError
            If the design returned no gain (e.g. infeasible LMIs).
        """
        gains = [getattr(self, name) for name in self.controller_fields]
        if any(g is None for g in gains):
            raise ValueError(f"controller: the design returned no gain ({self.status}: "
                             f"{self.message})")
        return self.controller_type(*gains, **self._controller_keywords())

    def _controller_keywords(self):
        """Keywords of the controller beyond its gains (none here)."""
        return {}


@dataclass(kw_only=True)
class CertifiedDesignResult(DesignResult):
    """A time-invariant design's result with the certificate of its closed loop.

    Its properties ``rho``, ``rho_bracket`` and ``stabilizing`` read ``stability``.

    Attributes
    ----------
    stability : asoc.mjls.MeanSquareStability or None
        rho of the closed loop (Cor. 3.2), its certified bracket and the verdict
        (:func:`asoc.mjls.mean_square_stability`); None when the design returned no gain.

    Examples
    --------
    >>> from asoc.mjls import observed_mode_state_feedback
    >>> from asoc.mjls.examples import sec354_system
    >>> res = observed_mode_state_feedback(sec354_system(1, "state"))
    >>> res.stabilizing, res.rho == res.stability.rho, res.rho_bracket == res.stability.bracket
    (True, True, True)
    """

    stability: MeanSquareStability | None

    def __post_init__(self):
        super().__post_init__()
        if self.stability is not None and not isinstance(self.stability, MeanSquareStability):
            raise TypeError(f"stability: expected a MeanSquareStability or None, found "
                            f"{type(self.stability).__name__}")

    def _controller_keywords(self):
        """The controller carries the certificate of its designed loop."""
        return dict(stability=self.stability)

    @property
    def rho(self) -> float:
        """Mean-square spectral radius of the closed loop (Cor. 3.2); nan without a gain."""
        return np.nan if self.stability is None else self.stability.rho

    @property
    def rho_bracket(self) -> tuple:
        """(rho_lower, rho_upper), the certified bracket of rho; (nan, nan) without a gain."""
        return (np.nan, np.nan) if self.stability is None else self.stability.bracket

    @property
    def stabilizing(self):
        """True (certified stable), False (certified unstable, or no gain) or None (undecided)."""
        return False if self.stability is None else self.stability.stabilizing
