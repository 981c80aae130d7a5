"""asoc.mjls.random_mjls: documented distributions, determinism, argument checks."""

import numpy as np
import pytest

from asoc.mjls import MJLS, random_mjls
from asoc.mjls.random import FAMILIES, RADII


def _radii(sys):
    return np.abs(np.linalg.eigvals(sys.A)).max(axis=1)


@pytest.mark.parametrize("family", FAMILIES)
def test_mode_radii_lie_in_the_documented_interval(family):
    dims = (2, 1, 1) if family == "thesis_like" else (3, 2, 2)
    low, high = RADII[family]
    for seed in range(50):
        sys = random_mjls(np.random.default_rng(seed), *dims, 3, family=family)
        assert isinstance(sys, MJLS)
        assert (sys.nx, sys.nu, sys.ny, sys.M) == (*dims, 3)
        assert np.all(_radii(sys) >= low - 1e-12) and np.all(_radii(sys) <= high + 1e-12)


def test_unstable_family_radii_cover_one_to_one_and_a_half():
    radii = np.concatenate(
        [
            _radii(random_mjls(np.random.default_rng(s), 2, 1, 1, 4, family="unstable"))
            for s in range(200)
        ]
    )
    assert radii.min() >= 1.0 and radii.max() <= 1.5
    # uniform on [1, 1.5]: both ends are reached
    assert radii.min() < 1.05 and radii.max() > 1.45


def test_same_generator_state_gives_the_same_system_and_the_draw_advances_it():
    rng = np.random.default_rng(7)
    first, second = random_mjls(rng, 2, 1, 1, 2), random_mjls(rng, 2, 1, 1, 2)
    again = random_mjls(np.random.default_rng(7), 2, 1, 1, 2)
    for name in ("A", "B", "C", "H", "J", "Q", "R", "T"):
        assert np.array_equal(getattr(first, name), getattr(again, name))
    assert not np.array_equal(first.A, second.A)


def test_dirichlet_rows_and_weights():
    for seed in range(30):
        sys = random_mjls(np.random.default_rng(seed), 3, 2, 1, 4, concentration=0.5)
        assert np.allclose(sys.T.sum(axis=1), 1) and np.all(sys.T >= 0)
        assert np.all(np.linalg.eigvalsh(sys.Q) >= 1 - 1e-12)
        assert np.all(np.linalg.eigvalsh(sys.R) >= 1 - 1e-12)
        assert np.all(np.linalg.matrix_rank(sys.C) == 1)


def test_large_concentration_gives_nearly_uniform_rows():
    T = random_mjls(np.random.default_rng(0), 2, 1, 1, 3, concentration=1e6).T
    assert np.allclose(T, 1 / 3, atol=5e-3)


def test_sparse_T_keeps_the_cycle_and_has_zeros():
    zeros = 0
    for seed in range(40):
        sys = random_mjls(np.random.default_rng(seed), 2, 1, 1, 4, family="sparse_T")
        assert np.all(sys.T[np.arange(4), (np.arange(4) + 1) % 4] > 0)
        zeros += int((sys.T == 0).sum())
        # irreducible: unique, positive stationary law
        assert np.all(sys.mu_inf > 0)
    assert zeros > 0


def test_noise_free_outputs_when_measurement_noise_is_zero():
    assert random_mjls(np.random.default_rng(0), 2, 1, 1, 2, measurement_noise=0).J is None
    assert np.all(random_mjls(np.random.default_rng(0), 2, 1, 1, 2, noise=0).H == 0)


@pytest.mark.parametrize(
    "kwargs, error, text",
    [
        (dict(rng=0), TypeError, "rng: expected a numpy.random.Generator"),
        (dict(n_states=2.0), TypeError, "n_states: expected an integer, found 2.0"),
        (dict(n_outputs=3), ValueError, "n_outputs: expected an integer <= 2, found 3"),
        (dict(n_modes=0), ValueError, "n_modes: expected an integer >= 1, found 0"),
        (dict(family="chaotic"), ValueError, "family: expected one of"),
        (dict(concentration=0.0), ValueError, "concentration: expected a finite real number > 0"),
        (dict(noise=-1.0), ValueError, "noise: expected a finite real number >= 0"),
        (dict(n_states=3, family="thesis_like"), ValueError, "for 'thesis_like', found 3, 1, 1"),
    ],
)
def test_bad_arguments_are_named(kwargs, error, text):
    args = dict(rng=np.random.default_rng(0), n_states=2, n_inputs=1, n_outputs=1, n_modes=2)
    args.update(kwargs)
    with pytest.raises(error, match=text.replace("(", r"\(").replace(")", r"\)")):
        random_mjls(
            args.pop("rng"),
            args.pop("n_states"),
            args.pop("n_inputs"),
            args.pop("n_outputs"),
            args.pop("n_modes"),
            **args,
        )
