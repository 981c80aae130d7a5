"""Sec. 3.4 (Prop. 3.5, eq. (3.6), Fig. 3.3): both readings of the plotted cost and their
curvature."""

import numpy as np
import pytest

from asoc.mjls.examples import SEC34_A, SEC34_B, SEC34_G, SEC34_PI, SEC34_T
from asoc.mjls.intractability import (
    expected_cost_two_steps_before_horizon,
    hessian,
    hessian_min_eigenvalue,
    min_curvature_in_u,
    nonconvex_radius,
)


def J(x, u, terms="full", g=SEC34_G):
    return expected_cost_two_steps_before_horizon(
        x, u, SEC34_A, SEC34_B, g, SEC34_T, SEC34_PI, n_nodes=60, terms=terms
    )


def test_full_cost_is_stage_cost_plus_last_term():
    x, u = np.meshgrid(np.linspace(-3, 3, 7), np.linspace(-4, 4, 5), indexing="ij")
    assert np.allclose(J(x, u), x**2 + u**2 + J(x, u, "last"), rtol=1e-13, atol=1e-12)
    with pytest.raises(ValueError, match="terms"):
        J(x, u, "first")


def test_hessian_of_a_quadratic_is_exact():
    f = lambda x, u: 2 * x**2 - 3 * x * u + 0.5 * u**2
    X, U = np.meshgrid(np.linspace(-2, 2, 5), np.linspace(-2, 2, 5), indexing="ij")
    fxx, fuu, fxu = hessian(f, X, U)
    # central differences are exact for quadratics up to rounding eps |f| / h^2
    tol = 10 * np.finfo(float).eps * 20 / 1e-3**2
    assert (
        np.allclose(fxx, 4, atol=tol)
        and np.allclose(fuu, 1, atol=tol)
        and np.allclose(fxu, -3, atol=tol)
    )
    lam = 0.5 * (5 - np.sqrt(9 + 36))
    assert hessian_min_eigenvalue(f, X, U)[0] == pytest.approx(lam, abs=tol)
    assert min_curvature_in_u(f, X, U)[0] == pytest.approx(1.0, abs=tol)
    # indefinite everywhere: the radius is the smallest max(|x|, |u|) on the grid, 0 at the origin
    assert nonconvex_radius(f, X, U) == (0.0, (0.0, 0.0))
    assert nonconvex_radius(lambda x, u: x**2 + u**2, X, U) == (float("inf"), None)


def test_the_readings_of_fig_3_3():
    xs = np.linspace(-5, 5, 41)
    X, U = np.meshgrid(xs, xs, indexing="ij")
    # text reading, only (3.6): non-convex on the printed square; caption reading, full J: convex
    # there
    assert hessian_min_eigenvalue(lambda x, u: J(x, u, "last"), X, U)[0] < 0
    assert hessian_min_eigenvalue(J, X, U)[0] > 0
    # both convex in u for every fixed x
    assert (
        min_curvature_in_u(J, X, U)[0] > 0
        and min_curvature_in_u(lambda x, u: J(x, u, "last"), X, U)[0] > 0
    )
    # the full cost turns non-convex outside the printed square
    big = np.linspace(-10, 10, 41)
    Xb, Ub = np.meshgrid(big, big, indexing="ij")
    radius, _ = nonconvex_radius(J, Xb, Ub)
    assert 5 < radius < 10


def test_cost_is_point_symmetric_and_the_representative_is_unique():
    from asoc.mjls.intractability import symmetric_representative

    x, u = np.meshgrid(np.linspace(-4, 4, 9), np.linspace(-3, 3, 7), indexing="ij")
    for terms in ("full", "last"):
        assert np.allclose(J(x, u, terms), J(-x, -u, terms), rtol=1e-12, atol=1e-12)
    for p in [(1.4, -4.9), (-1.4, 4.9), (2.0, 0.0), (-2.0, 0.0), (0.0, 0.0)]:
        r = symmetric_representative(p)
        assert r in (p, (-p[0], -p[1])) and r == symmetric_representative((-p[0], -p[1]))
        assert r[1] > 0 or (r[1] == 0 and r[0] >= 0)
