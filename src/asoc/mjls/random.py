"""Random Markov jump linear systems (3.7)/(3.36) for studies over many instances.

Like python-control's ``drss`` for jump systems: every draw comes from the ``rng`` passed in,
so the same generator state gives the same system, and a study that spawns one seed per
instance (``numpy.random.SeedSequence(seed).spawn(n)``) can re-run any instance alone.
"""

import numpy as np

from ..validation import generator, integer, real_scalar
from .system import MJLS

__all__ = ["FAMILIES", "RADII", "random_mjls"]


FAMILIES = ("stable", "unstable", "sparse_T", "thesis_like")
RADII = {"stable": (0.1, 0.95), "unstable": (1.0, 1.5), "sparse_T": (0.1, 1.2),
         "thesis_like": (0.8, 1.3)}


def _matrix_with_radius(rng, n, radius):
    """A standard normal n x n matrix rescaled to spectral radius ``radius``."""
    G = rng.standard_normal((n, n))
    rho = np.max(np.abs(np.linalg.eigvals(G)))
    while rho < 1e-8:                      # a nilpotent draw (probability 0) has no radius to scale
        G = rng.standard_normal((n, n))
        rho = np.max(np.abs(np.linalg.eigvals(G)))
    return G * (radius / rho)


def _transition_matrix(rng, n_modes, concentration, sparse):
    """Rows ~ Dirichlet(concentration * 1); ``sparse``: each row keeps its successor on the
    cycle 1 -> 2 -> ... -> M -> 1 (so the chain stays irreducible) and every other entry
    with probability 1/2; the kept entries are Dirichlet(concentration * 1).
    """
    T = np.zeros((n_modes, n_modes))
    for i in range(n_modes):
        keep = rng.random(n_modes) < 0.5 if sparse else np.ones(n_modes, dtype=bool)
        keep[(i + 1) % n_modes] = True
        T[i, keep] = rng.dirichlet(np.full(keep.sum(), concentration))
    return T


def _weight(rng, n):
    """I + G G^T / n with G standard normal (n x n): symmetric, eigenvalues >= 1."""
    G = rng.standard_normal((n, n))
    return np.eye(n) + G @ G.T / n


def random_mjls(rng, n_states, n_inputs, n_outputs, n_modes, *, family="stable", concentration=1.0,
                noise=0.2, measurement_noise=0.1):
    """A random MJLS (3.36) with documented distributions, like ``control.drss`` for jump systems.

    For each mode i, independently:

    * ``A_i`` = a standard normal matrix rescaled to spectral radius r_i, with r_i uniform on
      [0.1, 0.95] (``"stable"``: every mode stable, the MJLS may still be mean-square
      unstable, Sec. 3.2), [1, 1.5] (``"unstable"``), [0.1, 1.2] (``"sparse_T"``) or
      [0.8, 1.3] (``"thesis_like"``, around the radii 1.2 and 1 of the examples of Secs. 3.5.4
      and 3.7.3);
    * ``B_i`` (n_states x n_inputs) and ``C_i`` (n_outputs x n_states) standard normal
      (``C_i`` has full row rank with probability 1, as Sec. 3.5.1 assumes);
    * ``H_i`` = ``noise`` x standard normal (n_states x n_states) and, if
      ``measurement_noise > 0``, ``J_i`` = ``measurement_noise`` x standard normal
      (n_outputs x n_outputs), otherwise J = None (y = C x);
    * ``Q_i`` = I + G G^T / n_states and ``R_i`` = I + G G^T / n_inputs with G standard normal.

    The rows of ``T`` are Dirichlet(``concentration`` x 1): 1 is uniform on the simplex,
    small values give nearly deterministic switching, large values rows near uniform.
    ``"sparse_T"``: each row keeps its successor on the cycle 1 -> ... -> M -> 1 (the chain
    stays irreducible, so the stationary distribution is unique) and every other entry with
    probability 1/2; the kept entries are Dirichlet(``concentration`` x 1).
    ``"thesis_like"`` is the size of the thesis's examples: 2 states, 1 input, 1 output.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of every draw; the same state gives the same system.
    n_states, n_inputs, n_outputs, n_modes : int
        Dimensions nx >= 1, nu >= 1, 1 <= ny <= nx, and the number of modes M >= 1.
    family : {"stable", "unstable", "sparse_T", "thesis_like"}
        Distribution of the mode radii and of T (see above).
    concentration : float
        Dirichlet concentration (> 0) of the rows of T.
    noise, measurement_noise : float
        Scales (>= 0) of H_i and J_i.

    Returns
    -------
    MJLS

    Raises
    ------
    TypeError
        If ``rng`` is not a Generator or a dimension is not an integer.
    ValueError
        If a dimension is out of range, ``family`` is unknown, ``"thesis_like"`` is asked
        for other than 2 states, 1 input and 1 output, or a scale is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from asoc.mjls import random_mjls, ms_spectral_radius
    >>> sys = random_mjls(np.random.default_rng(1), 3, 1, 2, 2, family="unstable")
    >>> sys.A.shape, sys.B.shape, sys.C.shape, sys.T.shape
    ((2, 3, 3), (2, 3, 1), (2, 2, 3), (2, 2))
    >>> [bool(1 <= r <= 1.5) for r in np.abs(np.linalg.eigvals(sys.A)).max(axis=1)]
    [True, True]
    >>> again = random_mjls(np.random.default_rng(1), 3, 1, 2, 2, family="unstable")
    >>> bool(np.array_equal(sys.A, again.A) and np.array_equal(sys.T, again.T))
    True
    >>> random_mjls(np.random.default_rng(1), 3, 1, 1, 2, family="thesis_like")
    Traceback (most recent call last):
    ...
    ValueError: family: expected n_states=2, n_inputs=1, n_outputs=1 for 'thesis_like',
    found 3, 1, 1
    """
    rng = generator(rng, "rng")
    n_states = integer(n_states, "n_states", minimum=1)
    n_inputs = integer(n_inputs, "n_inputs", minimum=1)
    n_outputs = integer(n_outputs, "n_outputs", minimum=1, maximum=n_states)
    n_modes = integer(n_modes, "n_modes", minimum=1)
    if family not in FAMILIES:
        raise ValueError(f"family: expected one of {FAMILIES}, found {family!r}")
    if family == "thesis_like" and (n_states, n_inputs, n_outputs) != (2, 1, 1):
        raise ValueError(f"family: expected n_states=2, n_inputs=1, n_outputs=1 for 'thesis_like', "
                         f"found {n_states}, {n_inputs}, {n_outputs}")
    concentration = real_scalar(concentration, "concentration", low=0, low_open=True)
    noise = real_scalar(noise, "noise", low=0)
    measurement_noise = real_scalar(measurement_noise, "measurement_noise", low=0)
    low, high = RADII[family]
    radii = rng.uniform(low, high, n_modes)
    A = np.stack([_matrix_with_radius(rng, n_states, r) for r in radii])
    B = rng.standard_normal((n_modes, n_states, n_inputs))
    C = rng.standard_normal((n_modes, n_outputs, n_states))
    H = noise * rng.standard_normal((n_modes, n_states, n_states))
    J = measurement_noise * rng.standard_normal((n_modes, n_outputs, n_outputs))
    Q = np.stack([_weight(rng, n_states) for _ in range(n_modes)])
    R = np.stack([_weight(rng, n_inputs) for _ in range(n_modes)])
    T = _transition_matrix(rng, n_modes, concentration, family == "sparse_T")
    return MJLS(A=A, B=B, C=C, H=H, Q=Q, R=R, T=T, J=J if measurement_noise > 0 else None)
