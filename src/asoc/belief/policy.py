"""The affine policy u_k = L_k E{x_k} + d_k of eq. (2.18), and its controller with the UKF."""

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from .filters import KAPPA
from .models import NonlinearModel
from .ukf import UKF

__all__ = ["AffinePolicy", "policy_for", "MeanAffineController"]


@dataclass(frozen=True)
class AffinePolicy:
    """u_k = L_k E{x_k} + d_k for k = 0..K-1 (eq. 2.18); L (K, n_u, n_x), d (K, n_u).

    Raises
    ------
    ValueError, TypeError
        If ``L`` is not a finite real (K, n_u, n_x) array or ``d`` not (K, n_u).

    Examples
    --------
    >>> policy = AffinePolicy.zero(3, 1, 2)
    >>> policy.L.shape, policy(0, np.array([1.0, 2.0])).tolist()
    ((3, 1, 2), [0.0])
    """

    L: np.ndarray
    d: np.ndarray

    def __post_init__(self):
        L = check.real_array(self.L, "L", ndim=3)
        if 0 in L.shape:
            raise ValueError("L: expected a non-empty array of shape (K, n_u, n_x), "
                             f"found shape {L.shape}")
        object.__setattr__(self, "L", L)
        object.__setattr__(self, "d", check.real_array(self.d, "d", shape=L.shape[:2]))

    @classmethod
    def zero(cls, K, n_u, n_x):
        """The initial policy L_k = 0, d_k = 0 (Sec. 2.5.2)."""
        named = ((K, "K"), (n_u, "n_u"), (n_x, "n_x"))
        K, n_u, n_x = (check.integer(v, name, minimum=1) for v, name in named)
        return cls(np.zeros((K, n_u, n_x)), np.zeros((K, n_u)))

    def __call__(self, k, mean):
        """The input u_k = L_k mean + d_k of eq. (2.18) at step ``k``."""
        return self.L[k] @ mean + self.d[k]


def policy_for(policy, K, model, name="policy") -> AffinePolicy:
    """Raise unless ``policy`` is an AffinePolicy of horizon ``K`` for ``model``.

    Examples
    --------
    >>> from asoc.belief import landmark_example
    >>> policy_for(AffinePolicy.zero(3, 2, 2), 3, landmark_example().model).L.shape
    (3, 2, 2)
    """
    check.instance(policy, AffinePolicy, name)
    if policy.L.shape != (K, model.n_u, model.n_x):
        raise ValueError(f"{name}: expected L of shape {(K, model.n_u, model.n_x)} and d of shape "
                         f"{(K, model.n_u)}, found {policy.L.shape} and {policy.d.shape}")
    return policy


class MeanAffineController:
    """u_k = L_k E{x_k} + d_k (eq. 2.18) with the UKF estimate (the proposed controller).

    Parameters
    ----------
    model : NonlinearModel
    policy : AffinePolicy
        Of the model's dimensions.
    kappa : float, optional
        The UKF's sample scaling (default 0.5).

    Raises
    ------
    ValueError, TypeError
        If ``model`` or ``policy`` has the wrong type or dimensions.

    Examples
    --------
    >>> from asoc.belief import AffinePolicy, landmark_example
    >>> ex = landmark_example(K=2)
    >>> ctrl = MeanAffineController(ex.model, AffinePolicy(np.zeros((2, 2, 2)), np.ones((2, 2))))
    >>> ctrl.control(0, ex.mean0, ex.cov0).tolist()
    [1.0, 1.0]
    """

    def __init__(self, model, policy, kappa=None):
        model = check.instance(model, NonlinearModel, "model")
        check.instance(policy, AffinePolicy, "policy")
        if policy.L.shape[1:] != (model.n_u, model.n_x):
            raise ValueError(f"policy: expected gains of shape (K, {model.n_u}, {model.n_x}), "
                             f"found {policy.L.shape}")
        self.filter = UKF(model, KAPPA if kappa is None else kappa)
        self.policy, self.horizon = policy, policy.L.shape[0]

    def control(self, k, mean, cov):
        """The input at time k for the estimate (mean, cov)."""
        return mean @ self.policy.L[k].T + self.policy.d[k]

    def step(self, mean, cov, u, y):
        """The UKF's next estimate."""
        return self.filter.step((mean, cov), u, y)
