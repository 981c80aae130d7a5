"""The numerical examples of Chapter 3, with the thesis's parameters, and a networked loop that
loses input packets (not in the thesis).
"""

import numpy as np

from ..validation import choice
from .system import MJLS

__all__ = ["SEC32_A", "SEC32_T", "SEC32_X0", "SEC34_A", "SEC34_B", "SEC34_G", "SEC34_T", "SEC34_PI",
           "SEC354_A", "SEC354_B", "SEC354_H", "SEC354_T", "SEC354_C", "SEC354_X0", "sec32_system",
           "sec354_system", "SEC373_C", "SEC373_T", "SEC373_MU0", "SEC373_MEAN0", "SEC373_COV0",
           "sec373_system", "NETWORKED_A", "NETWORKED_B", "NETWORKED_C", "NETWORKED_T",
           "networked_loop", "networked_loop_lossy"]


# Sec. 3.2: two stable modes whose switching makes the MJLS mean-square unstable (Fig. 3.2).
SEC32_A = np.array([[[0.9, 1.0], [0.0, 0.5]], [[0.9, 0.0], [1.0, 0.5]]])
SEC32_T = np.array([[0.7, 0.3], [0.4, 0.6]])
SEC32_X0 = np.array([-4.0, 8.0])

# Sec. 3.4: scalar example of the intractable optimal cost (Fig. 3.3).
SEC34_A = np.array([1.0, 0.3])
SEC34_B = np.array([1.0, 0.8])
SEC34_G = 0.2
SEC34_T = np.array([[0.7, 0.3], [0.2, 0.8]])
SEC34_PI = np.array([0.4, 0.6])

# Sec. 3.5.4: the static output-feedback example (Figs. 3.4, 3.5, Table 3.2).
SEC354_A = np.array([[[1.2, 1.2], [0.0, 1.0]], [[1.0, 0.8], [0.0, 1.0]]])
SEC354_B = np.array([[[0.0], [1.0]], [[0.0], [0.2]]])
SEC354_H = np.diag([0.2, 0.1])
SEC354_T = {1: np.array([[0.7, 0.3], [0.6, 0.4]]), 2: np.array([[0.9, 0.1], [0.1, 0.9]])}
SEC354_C = {"C=[1 0]": np.array([[1.0, 0.0]]),
            "C1=[1 2], C2=[2 1]": np.array([[[1.0, 2.0]], [[2.0, 1.0]]]),
            "state": np.eye(2)}
SEC354_X0 = {1: np.array([0.0, 0.0]), 2: np.array([3.0, 0.0])}


def sec32_system() -> MJLS:
    """x_{k+1} = A_theta x_k of Sec. 3.2 as an MJLS without input and noise.

    Examples
    --------
    >>> sys = sec32_system()
    >>> sys.M, sys.nx
    (2, 2)
    """
    return MJLS(A=SEC32_A, B=np.zeros((2, 1)), C=np.eye(2), H=np.zeros((2, 1)),
                Q=np.eye(2), R=np.eye(1), T=SEC32_T)


def sec354_system(T: int = 1, C: str = "C1=[1 2], C2=[2 1]", H=SEC354_H) -> MJLS:
    """The MJLS of Sec. 3.5.4 with transition matrix T[1] or T[2] and output matrices ``C``.

    Q_i = I and R_i = 1 (the thesis writes R_i = I_{n_x}; with one input, R_i is 1 x 1).

    Examples
    --------
    >>> sys = sec354_system(2, "C=[1 0]")
    >>> sys.T.tolist(), sys.C[1].tolist()
    ([[0.9, 0.1], [0.1, 0.9]], [[1.0, 0.0]])
    """
    choice(T, "T", tuple(SEC354_T))
    choice(C, "C", tuple(SEC354_C))
    return MJLS(A=SEC354_A, B=SEC354_B, C=SEC354_C[C], H=H, Q=np.eye(2), R=np.eye(1),
                T=SEC354_T[T])


# Sec. 3.7.3: the dynamic output-feedback example (Figs. 3.6-3.8, Table 3.3).
SEC373_C = np.array([[[1.0, 0.0]], [[0.8, 0.0]]])
SEC373_T = {1: np.array([[0.7, 0.3], [0.6, 0.4]]), 2: np.array([[0.9, 0.1], [0.9, 0.1]])}
SEC373_MU0 = np.array([1.0, 0.0])
SEC373_MEAN0 = {1: np.array([[5.0, 0.0], [0.0, 0.0]]), 2: np.zeros((2, 2))}   # xi_0[1], xi_0[2]
SEC373_COV0 = np.stack([0.1 ** 2 * np.eye(2), np.zeros((2, 2))])              # Xi_0^1, Xi_0^2


def sec373_system(T: int = 1) -> MJLS:
    """The MJLS of Sec. 3.7.3 (A, B as in Sec. 3.5.4, C1 = [1 0], C2 = [0.8 0], H = 0.2 I,
    J = 0.1, Q = I, R = 1) with transition matrix T[1] or T[2].

    Examples
    --------
    >>> sys = sec373_system(1)
    >>> sys.J.ravel().tolist(), sys.C[1].tolist()
    ([0.1, 0.1], [[0.8, 0.0]])
    """
    choice(T, "T", tuple(SEC373_T))
    return MJLS(A=SEC354_A, B=SEC354_B, C=SEC373_C, H=0.2 * np.eye(2), Q=np.eye(2), R=np.eye(1),
                T=SEC373_T[T], J=0.1 * np.ones((1, 1)))


# Not in the thesis: a networked loop whose input packets are lost (the engineer's example
# of asoc.mjls).
NETWORKED_A = np.array([[0.24, 0.58, 0.23], [-0.92, 0.64, 0.32], [-0.38, 0.41, 0.26]])
NETWORKED_B = np.array([[0.03], [0.55], [-0.74]])
NETWORKED_C = np.array([[-0.16, -0.48, 0.6]])
NETWORKED_T = np.array([[0.9, 0.1], [0.6, 0.4]])


def networked_loop() -> MJLS:
    """A 3-state plant controlled over a network that loses input packets; not in the thesis.

    Mode 1: the packet arrives (B = NETWORKED_B); mode 2: it is lost (B = 0). A lost packet is
    followed by another with probability 0.4, a delivered one by a loss with probability 0.1
    (T = [[0.9, 0.1], [0.6, 0.4]]). y = C x without measurement noise, H = 0.1 I, Q = I, R = 1;
    A has spectral radius 0.90. Alg. 3.2 settles into a 2-cycle on it
    (:mod:`asoc.mjls.dynamic`).

    Examples
    --------
    >>> sys = networked_loop()
    >>> sys.M, sys.nx, sys.B[1].ravel().tolist(), sys.mu_inf.round(3).tolist()
    (2, 3, [0.0, 0.0, 0.0], [0.857, 0.143])
    """
    return MJLS(A=NETWORKED_A, B=[NETWORKED_B, np.zeros_like(NETWORKED_B)], C=NETWORKED_C,
                H=0.1 * np.eye(3), Q=np.eye(3), R=np.eye(1), T=NETWORKED_T)


def _lossy_plant(dt=0.1):
    """The plant of :func:`networked_loop_lossy`: x1' = a x1 + x2, x2' = -x2 + x3, x3' = -2 x3 + u
    with a = ln(1.08) / dt (the discrete unstable pole 1.08), y = (x1, x3), discretised with a
    zero-order hold (``control.c2d``). Returns (A, B, C).

    Examples
    --------
    >>> A, B, C = _lossy_plant()
    >>> round(float(max(abs(np.linalg.eigvals(A)))), 6), C.shape
    (1.08, (2, 3))
    """
    import control

    a = np.log(1.08) / dt
    Ac = np.array([[a, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, -2.0]])
    outputs = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    plant = control.c2d(control.ss(Ac, [[0.0], [0.0], [1.0]], outputs, 0), dt)
    return np.asarray(plant.A), np.asarray(plant.B), np.asarray(plant.C)


def networked_loop_lossy() -> MJLS:
    """An unstable 3-state plant (pole 1.08, 2 outputs) losing input packets; not in the thesis.

    A networked loop on which Alg. 3.1 cycles: mode 1 the packet arrives, mode 2 it is lost
    (u = 0); T = [[0.9, 0.1], [0.6, 0.4]], Q = I, R = 0.1, H = 0.05 I, J = 0.01 I. The
    plant (``_lossy_plant``) has the poles, sampling and outputs of a user's report whose
    matrices were not given; its iterates settle into a 2-cycle between a stabilising and a
    non-stabilising gain, so which one a fixed ``max_iter`` returns depends on its parity.

    Examples
    --------
    >>> sys = networked_loop_lossy()
    >>> sys.M, sys.nx, sys.ny, sys.B[1].ravel().tolist()
    (2, 3, 2, [0.0, 0.0, 0.0])
    """
    A, B, C = _lossy_plant()
    return MJLS(A=A, B=[B, np.zeros_like(B)], C=C, H=0.05 * np.eye(3), Q=np.eye(3),
                R=0.1 * np.eye(1), T=NETWORKED_T, J=0.01 * np.eye(2))
