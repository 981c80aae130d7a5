"""asoc.config: settings that check themselves (issue 32, item 4)."""

import inspect
import threading

import numpy as np
import pytest

from asoc import config
from asoc.mjls import dynamic_output_feedback, mean_square_stability
from asoc.mjls.examples import sec373_system


def test_a_typo_is_refused_with_the_closest_key():
    with pytest.raises(KeyError, match="did you mean 'mjls.rank_rtol'"):
        config.defaults["mjls.rank_rol"] = 1e-8
    with pytest.raises(KeyError, match="did you mean 'mjls.rank_rtol'"):
        config.set_defaults(**{"mjls.rank_rol": 1e-8})
    with pytest.raises(KeyError, match="did you mean 'mjls.bracket_rtol'"):
        with config.option_context(**{"mjls.braket_rtol": 1e-8}):
            pass
    assert "mjls.rank_rol" not in config.defaults


@pytest.mark.parametrize(
    "key, value, error",
    [
        ("mjls.rank_rtol", "1e-8", TypeError),
        ("mjls.cg_tolerance", None, TypeError),
        ("mjls.rank_rtol", True, TypeError),
        ("mjls.rank_rtol", 0.0, ValueError),
        ("mjls.rank_rtol", 2.0, ValueError),
        ("mjls.rank_rtol", np.nan, ValueError),
        ("mjls.dense_max_radius", 64.5, TypeError),
        ("mjls.dense_max_radius", -1, ValueError),
        ("mjls.arnoldi_subspaces", 60, TypeError),
        ("mjls.arnoldi_subspaces", (60, 1), ValueError),
        ("mjls.divergence_threshold", 0.5, ValueError),
    ],
)
def test_a_wrong_value_is_refused_when_set_naming_the_key(key, value, error):
    before = config.defaults[key]
    with pytest.raises(error, match=key):
        config.defaults[key] = value
    with pytest.raises(error, match=key):
        config.set_defaults(**{key: value})
    with pytest.raises(error, match=key):
        with config.option_context(**{key: value}):
            pass
    assert config.defaults[key] == before


def test_every_shipped_value_passes_its_own_check_and_is_described():
    assert set(config.defaults) == set(config.DESCRIPTIONS) == set(config.ALLOWED)
    for key, value in config.defaults.items():
        config.defaults[key] = value
        assert len(config.DESCRIPTIONS[key]) > 20, key


def test_the_table_of_asoc_tunables_is_what_config_serves():
    from asoc.tunables import TUNABLES

    assert list(config.defaults) == list(TUNABLES)
    for key, (value, allowed, why) in TUNABLES.items():
        assert config.ALLOWED[key] == str(allowed) and config.DESCRIPTIONS[key] == why


def test_keys_can_be_changed_but_not_removed():
    with pytest.raises(TypeError, match="cannot be removed"):
        del config.defaults["mjls.rank_rtol"]


def test_monkeypatch_and_reset_restore_the_shipped_values(monkeypatch):
    monkeypatch.setitem(config.defaults, "mjls.dense_max_radius", 0)
    assert config.defaults["mjls.dense_max_radius"] == 0
    config.reset_defaults()
    assert config.defaults["mjls.dense_max_radius"] == 64


def test_a_per_call_setting_holds_for_that_call_and_its_thread_only():
    @config.accepts_settings("mjls.bracket_rtol")
    def read(event=None, seen=None):
        if event is not None:
            event.wait()
        return config.defaults["mjls.bracket_rtol"]

    seen = []
    release = threading.Event()
    other = threading.Thread(target=lambda: seen.append(read(release)))
    other.start()
    assert read(bracket_rtol=1e-6) == 1e-6
    release.set()
    other.join()
    assert seen == [1e-12] and read() == 1e-12
    with pytest.raises(TypeError, match=r"bracket_rtol \(mjls.bracket_rtol\)"):
        read(bracket_rtol="loose")


def test_a_decorated_function_refuses_a_keyword_it_already_has():
    with pytest.raises(TypeError, match="already has"):
        config.accepts_settings("mjls.rank_rtol")(lambda rank_rtol=None: None)


def test_designs_accept_their_settings_per_call():
    rng = np.random.default_rng(0)
    A, T = rng.standard_normal((2, 5, 5)) / 5, [[0.9, 0.1], [0.5, 0.5]]
    assert mean_square_stability(A, T).method == "dense"
    assert mean_square_stability(A, T, dense_max_radius=0).method != "dense"
    assert mean_square_stability(A, T).method == "dense"
    sys = sec373_system(1)
    with pytest.raises(ValueError, match="alg32_patience"):
        dynamic_output_feedback(sys, alg32_patience=0)
    assert config.defaults["mjls.alg32_patience"] == 50
    for design in (dynamic_output_feedback, mean_square_stability):
        assert design.settings and "Other Parameters" in design.__doc__


def test_every_design_that_reads_a_setting_takes_it_per_call():
    import asoc.gp
    import asoc.mjls

    designs = [
        asoc.mjls.static_output_feedback,
        asoc.mjls.dynamic_output_feedback,
        asoc.mjls.finite_horizon_dynamic_output_feedback,
        asoc.mjls.exact_dynamic_output_feedback,
        asoc.mjls.exact_finite_horizon_dynamic_output_feedback,
        asoc.mjls.min_radius_dynamic_output_feedback,
        asoc.mjls.static_output_lmi,
        asoc.mjls.ms_spectral_radius,
        asoc.mjls.mean_square_stability,
        asoc.gp.DistributionGP.fit,
        asoc.gp.MeanKernelGP.fit,
    ]
    for design in designs:
        assert design.settings, design.__name__
        names = set(inspect.signature(design).parameters)
        assert {key.split(".", 1)[1] for key in design.settings} <= names, design.__name__


def test_a_gp_fit_takes_its_iteration_cap_per_call():
    from asoc.gp import DistributionGP

    x = np.linspace(-2, 2, 8)
    D, y = np.abs(x[:, None] - x[None]), np.sin(x)
    with pytest.warns(RuntimeWarning, match="did not converge"):
        capped = DistributionGP("se", n_restarts=0).fit(
            D, y, np.random.default_rng(0), max_iterations=1
        )
    assert capped.result.status == "max_iterations" and capped.result.iterations == 1
    assert DistributionGP("se", n_restarts=0).fit(D, y, np.random.default_rng(0)).result.converged
