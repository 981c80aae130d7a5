"""The tests mirror the modules (issue 32, item 6): every module of the library has a test file
named after it, or one named test file that covers it (it imports the module or one of its
exported names). A new module without either fails here."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src" / "asoc"

#: module (under src/asoc) -> the test file (under tests/) that covers it, where it has none
#: of its own name.
COVERED_BY = {
    "belief/damped.py": "asoc/belief/test_claims_and_bend.py",
    "belief/planning.py": "asoc/belief/test_claims_and_bend.py",
    "belief/ekf.py": "asoc/belief/test_belief.py",
    "belief/filters.py": "asoc/belief/test_belief.py",
    "belief/improvement.py": "asoc/belief/test_belief.py",
    "belief/models.py": "asoc/belief/test_belief.py",
    "belief/particle.py": "asoc/belief/test_belief.py",
    "belief/policy.py": "asoc/belief/test_belief.py",
    "belief/simulate.py": "asoc/belief/test_belief.py",
    "belief/stage.py": "asoc/belief/test_belief.py",
    "belief/sweep.py": "asoc/belief/test_belief.py",
    "belief/taylor.py": "asoc/belief/test_belief.py",
    "belief/trajectory.py": "asoc/belief/test_belief.py",
    "belief/ukf.py": "asoc/belief/test_belief.py",
    "belief/vdberg.py": "asoc/belief/test_belief.py",
    "gp/cramer_von_mises.py": "asoc/gp/test_gp_distances.py",
    "gp/densities.py": "asoc/gp/test_gp_distances.py",
    "gp/experiment.py": "asoc/gp/test_gp_regression.py",
    "gp/kernels.py": "asoc/gp/test_gp_regression.py",
    "gp/mixture_checks.py": "asoc/gp/test_gp_distances.py",
    "gp/regression.py": "asoc/gp/test_gp_regression.py",
    "gp/sampling.py": "asoc/gp/test_gp_distances.py",
    "gp/study.py": "asoc/gp/test_fits_converge.py",
    "gp/transport.py": "asoc/gp/test_gp_distances.py",
    "linalg.py": "asoc/test_core.py",
    "optimize.py": "asoc/test_core.py",
    "progress.py": "asoc/test_core.py",
    "result.py": "asoc/test_core.py",
    "setting_checks.py": "asoc/test_core.py",
    "stats.py": "asoc/test_core.py",
    "threads.py": "asoc/test_core.py",
    "tunables.py": "asoc/test_config.py",
    "validation.py": "asoc/test_fuzz_belief_gp.py",
    "mjls/baselines.py": "asoc/mjls/test_mjls.py",
    "mjls/certificate.py": "asoc/mjls/test_certified.py",
    "mjls/closed_loops.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/controllers.py": "asoc/mjls/test_design_result.py",
    "mjls/costs.py": "asoc/mjls/test_mjls.py",
    "mjls/dynamic.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/exact_cost_design.py": "asoc/mjls/test_mjls_exact.py",
    "mjls/examples.py": "asoc/mjls/test_mjls.py",
    "mjls/finite_horizon.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/finite_horizon_model.py": "asoc/mjls/test_mjls_exact.py",
    "mjls/gradients.py": "asoc/mjls/test_mjls_exact.py",
    "mjls/lmi.py": "asoc/mjls/test_mjls.py",
    "mjls/lyapunov.py": "asoc/mjls/test_operators.py",
    "mjls/moment_bounds.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/moment_operator.py": "asoc/mjls/test_operators.py",
    "mjls/moments.py": "asoc/mjls/test_mjls.py",
    "mjls/monte_carlo.py": "asoc/mjls/test_mjls.py",
    "mjls/monte_carlo_comparison.py": "asoc/mjls/test_mjls.py",
    "mjls/observed_mode_feedback.py": "asoc/mjls/test_peers.py",
    "mjls/observed_mode_lqg.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/optimality.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/random.py": "asoc/mjls/test_random_mjls.py",
    "mjls/spectral_estimate.py": "asoc/mjls/test_certified.py",
    "mjls/stability.py": "asoc/mjls/test_certified.py",
    "mjls/static.py": "asoc/mjls/test_mjls.py",
    "mjls/static_iterates.py": "asoc/mjls/test_mjls_exact.py",
    "mjls/scaled_pair.py": "asoc/mjls/test_mjls_exact.py",
    "mjls/stopping.py": "asoc/mjls/test_mjls_dynamic.py",
    "mjls/system.py": "asoc/mjls/test_statespace.py",
}


def modules():
    return sorted(
        p.relative_to(SRC).as_posix() for p in SRC.rglob("*.py") if p.name != "__init__.py"
    )


def own_test(module):
    stem = Path(module).stem
    return next(iter(sorted((ROOT / "tests").rglob(f"test_{stem}.py"))), None)


def exported(module):
    tree = ast.parse((SRC / module).read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            getattr(t, "id", None) == "__all__" for t in node.targets
        ):
            return list(ast.literal_eval(node.value))
    return []


def covers(test_file, module):
    """Whether ``test_file`` imports ``module`` or uses one of its exported names."""
    text = test_file.read_text()
    dotted = "asoc." + module[:-3].replace("/", ".")
    return dotted in text or any(
        re.search(rf"\b{re.escape(name)}\b", text) for name in exported(module)
    )


def test_every_module_has_a_test_file():
    missing = [m for m in modules() if own_test(m) is None and m not in COVERED_BY]
    assert not missing, (
        f"modules without a test file of their name or an entry in COVERED_BY: {missing}"
    )


def test_the_named_test_files_cover_their_modules():
    wrong = [
        f"{m} -> {t}"
        for m, t in COVERED_BY.items()
        if not (ROOT / "tests" / t).exists() or not covers(ROOT / "tests" / t, m)
    ]
    assert not wrong, (
        f"COVERED_BY names test files that do not exist or do not use the module: {wrong}"
    )
    stale = sorted(set(COVERED_BY) - set(modules()))
    assert not stale, f"COVERED_BY names modules that no longer exist: {stale}"


def private_uses(source):
    """``name._helper`` and ``from asoc... import _helper`` in a test's source, where ``name`` is
    bound by an import from ``asoc`` or ``asoc_companion`` (dunder names are not private)."""
    tree = ast.parse(source)
    ours, found = set(), []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in (
            "asoc",
            "asoc_companion",
        ):
            for alias in node.names:
                ours.add(alias.asname or alias.name)
                if alias.name.startswith("_") and not alias.name.startswith("__"):
                    found.append(f"line {node.lineno}: imports {alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] in ("asoc", "asoc_companion"):
                    ours.add(alias.asname or alias.name.split(".")[0])
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in ours
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
        ):
            found.append(f"line {node.lineno}: {node.value.id}.{node.attr}")
    return found


def test_no_test_reaches_into_a_private_helper():
    """Tests use the public surface (issue 32, item 6): no private name imported from the
    library or the tooling, none read off a name imported from them."""
    offenders = {
        str(path.relative_to(ROOT)): uses
        for path in sorted((ROOT / "tests").rglob("test_*.py"))
        if path.name != "test_test_files.py" and (uses := private_uses(path.read_text()))
    }
    assert not offenders, f"tests that use private helpers: {offenders}"


def test_the_private_helper_check_finds_planted_uses():
    source = (
        "import asoc.mjls as m\nfrom asoc.gp.regression import _exp_in_place, EXP\n"
        "from asoc_companion import cli\nimport argparse\n"
        "m._spectral(1)\ncli._parser()\nargparse._SubParsersAction\ncli.__name__\n"
    )
    assert private_uses(source) == [
        "line 2: imports _exp_in_place",
        "line 5: m._spectral",
        "line 6: cli._parser",
    ]
