"""The random family of the scaling study (the Scaling page, ``make bench``).

:func:`scaling_system` draws the family the targets are stated on: mode matrices of spectral
norm 0.95 (so the open loop is mean-square stable: rho <= max_i ||A_i||^2 < 1), Dirichlet
rows of T. :func:`dense_bytes` is the memory the dense Kronecker path would need.
"""

import numpy as np

from asoc.mjls import MJLS, ms_spectral_radius

__all__ = ["PUBLISHED_SIZE", "scaling_system", "published_size_system", "dense_bytes",
           "published_size_timings"]


#: The largest MJLS size in public code (a policy-gradient study in C++): states, modes, inputs =
#: outputs, open-loop
#: rho.
PUBLISHED_SIZE = {"n": 100, "M": 100, "inputs": 12, "radius": 0.99}


def scaling_system(rng, n, M, norm=0.95, inputs=None, radius=None):
    """A random MJLS with n states, M modes and ``inputs`` = ny = nu (default max(1, n // 8)).

    A_i = norm * G_i / ||G_i||_2 with G_i standard normal; B_i, C_i standard normal scaled by
    1 / sqrt(n); H_i = 0.3 I, J_i = 0.2 I, Q_i = I, R_i = I; the rows of T are Dirichlet(1, ..., 1).

    Parameters
    ----------
    rng : numpy.random.Generator
    n, M : int
        States and modes.
    norm : float
        Spectral norm of every A_i.
    inputs : int, optional
        Number of inputs and of outputs.
    radius : float, optional
        If given, every A_i is then scaled by one common factor so that the open loop has
        this mean-square spectral radius (Cor. 3.2), e.g. 0.99 for a barely stable one.

    Returns
    -------
    MJLS

    Examples
    --------
    >>> s = scaling_system(np.random.default_rng(0), 4, 2)
    >>> s.nx, s.M, s.nu, round(float(np.linalg.norm(s.A[0], 2)), 12)
    (4, 2, 1, 0.95)
    >>> from asoc.mjls import ms_spectral_radius
    >>> s = scaling_system(np.random.default_rng(0), 4, 2, radius=0.99)
    >>> round(ms_spectral_radius(s.A, s.T), 12)
    0.99
    """
    m = max(1, n // 8) if inputs is None else inputs
    A = rng.standard_normal((M, n, n))
    A *= norm / np.linalg.norm(A, 2, axis=(1, 2))[:, None, None]
    B = rng.standard_normal((M, n, m)) / np.sqrt(n)
    C = rng.standard_normal((M, m, n)) / np.sqrt(n)
    T = rng.dirichlet(np.ones(M), size=M)
    if radius is not None:
        A *= np.sqrt(radius / ms_spectral_radius(A, T))         # rho scales with the square of A
    eye = lambda k: np.broadcast_to(np.eye(k), (M, k, k))
    return MJLS(A, B, C, 0.3 * eye(n), eye(n), eye(m), T, J=0.2 * eye(m))


def published_size_system(rng):
    """The largest MJLS size in public code we found (a policy-gradient study in C++): n = 100
    states, M = 100 modes, nu = ny = 12, here with the open loop scaled to rho = 0.99.

    Building it takes one spectral radius of size M n^2 = 1e6 (a few seconds).

    Examples
    --------
    >>> PUBLISHED_SIZE
    {'n': 100, 'M': 100, 'inputs': 12, 'radius': 0.99}
    """
    return scaling_system(rng, PUBLISHED_SIZE["n"], PUBLISHED_SIZE["M"],
                          inputs=PUBLISHED_SIZE["inputs"],
                          radius=PUBLISHED_SIZE["radius"])


def dense_bytes(n, M):
    """Memory of the dense Kronecker matrix of the second-moment operator: 8 (M n^2)^2 bytes.

    Examples
    --------
    n = 10 states and M = 4 modes give a 400 x 400 matrix, 8 * 400^2 bytes:

    >>> dense_bytes(10, 4), dense_bytes(100, 100) / 1e12
    (1280000, 8.0)
    """
    return 8 * (M * n * n) ** 2


def published_size_timings(rng, n, M, inputs, radius, runs=1000, horizon=100):
    """Wall-clock seconds of three computations on one :func:`scaling_system` of the given size.

    The open loop's mean-square spectral radius (Cor. 3.2), Alg. 3.1 to its stopping rule
    (``moments="auto"``) and a Monte Carlo simulation of ``runs`` x ``horizon`` steps with the
    gain it returns. The system is drawn with its open loop scaled to ``radius``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the system, then the simulation.
    n, M, inputs : int
        States, modes, inputs (= outputs).
    radius : float
        Open-loop mean-square spectral radius.
    runs, horizon : int
        Size of the Monte Carlo simulation.

    Returns
    -------
    dict
        ``rho_s``, ``alg31_s``, ``simulate_s`` (seconds), ``alg31_iterations``, ``alg31_status``.

    Examples
    --------
    >>> t = published_size_timings(np.random.default_rng(0), 4, 3, 1, 0.9, runs=10, horizon=5)
    >>> sorted(t), t["alg31_status"]
    (['alg31_iterations', 'alg31_s', 'alg31_status', 'rho_s', 'simulate_s'], 'converged')
    """
    import time

    from asoc.mjls import simulate, static_output_feedback

    s = scaling_system(rng, n, M, inputs=inputs, radius=radius)
    start = time.perf_counter()
    ms_spectral_radius(s.A, s.T)
    rho_s = time.perf_counter() - start
    start = time.perf_counter()
    design = static_output_feedback(s, warn=False)
    alg31_s = time.perf_counter() - start
    start = time.perf_counter()
    simulate(s, design, np.zeros(n), horizon, runs, rng)
    return dict(rho_s=rho_s, alg31_s=alg31_s, simulate_s=time.perf_counter() - start,
                alg31_iterations=design.iterations, alg31_status=design.status)
