"""Every small numerical constant of the library is a setting or has a stated reason (issue 32).

A float literal 0 < |v| < 1e-3 in ``src/asoc`` outside ``config.py`` is a tolerance, a step or a
floor that can change a result. Each one is either read from :data:`asoc.config.defaults` (where
its reason is recorded) or listed below under its file and top-level name (function, class or
module constant), with the reason it stays where it is. The list has at most 30 entries, and an
entry that no longer matches a literal is an error too (so it cannot outlive its reason).
"""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "asoc"
MAX_ENTRIES = 30
#: The settings and their table (asoc.config, asoc.tunables), where small constants belong.
SETTINGS_FILES = ("config.py", "tunables.py")

#: (file under src/asoc, top-level name) -> why its small literals are not settings; keyword
#: defaults per subpackage ("mjls/*", "<keyword defaults>").
ALLOWED = {
    # keyword defaults: documented in the signature, changed per call by the caller
    ("mjls/*", "<keyword defaults>"): (
        "the designs' tolerances and starts (tol, init of Algs. 3.1-3.3 with the thesis's values, "
        "the Riccati iteration's and the exact designs' tol), shown in each signature"
    ),
    ("belief/*", "<keyword defaults>"): (
        "the trajectory optimisers' rtol and the sweep's perturbation scale, shown in each "
        "signature"
    ),
    ("*", "<keyword defaults>"): "tol of asoc.optimize.bfgs (relative predicted decrease)",
    ("mjls/lmi.py", "EPS"): (
        "keyword default eps of static_output_lmi (Thm. 3.9's margin), per call"
    ),
    # rounding guards, ladders and numerical-differentiation steps
    ("mjls/finite_horizon.py", "finite_horizon_dynamic_output_feedback"): (
        "rounding margins 1e-8 / 1e-12 of Alg. 3.3's monotonicity checks (a bound may not "
        "rise by more than rounding between iterations)"
    ),
    ("mjls/baselines.py", "_gain"): (
        "rcond of a least-squares solve: singular values below 1e-12 of the largest are rounding"
    ),
    ("mjls/monte_carlo.py", "_psd_sqrt"): (
        "eigenvalues of a covariance above -1e-10 of its largest are rounding of a PSD matrix"
    ),
    ("mjls/random.py", "_matrix_with_radius"): (
        "a draw with spectral radius below 1e-8 is nilpotent up to rounding and cannot be "
        "rescaled (probability 0; the test only redraws)"
    ),
    ("belief/stage.py", "StageProblem"): (
        "rounding margins 1e-9 of the eigenvalue tests of a Schur complement, and the "
        "bisection's relative stopping width 1e-6 of the regularising shift (the shift only "
        "needs to make the stage problem convex)"
    ),
    ("belief/vdberg.py", "_linearize"): "base step 1e-4 of numdifftools' finite differences",
    ("gp/cramer_von_mises.py", "ROUNDING_RTOL"): (
        "rounding of the mCvMd closed form's square relative to its terms: below it, 0; beyond it, "
        "b_max is too small and the distance is refused"
    ),
    ("gp/experiment.py", "evaluation_grid"): (
        "1e-9 past the end point so that numpy.arange includes it (grid of step 0.1)"
    ),
    ("gp/regression.py", "_cholesky"): (
        "jitter ladder 1e-12 ... 1e-6 tried in turn on a kernel matrix that is singular to rounding"
    ),
    ("gp/regression.py", "_projected_gradient"): (
        "1e-9 in log-parameters: a parameter this close to its bound counts as at the bound"
    ),
    ("gp/regression.py", "DistributionGP"): (
        "central-difference step 1e-6 in log l for the covariances without an analytic derivative"
    ),
    ("gp/sampling.py", "_lcd_standard_normal"): (
        "gradient tolerance 1e-9 of BFGS for the Dirac approximation of N(0, 1) (converges in tens)"
    ),
    ("mjls/exact_cost_design.py", "<module>"): (
        "_RADIUS_STALL = 1e-5: the min-radius search stops when BFGS steps lower rho by less "
        "than this relative (rho is not smooth at its minimum)"
    ),
    ("mjls/exact_static_design.py", "_minimise"): (
        "BFGS's decrease tolerance set to 1e-16, i.e. off: the exact static design stops on its "
        "scaled-gradient tolerance gtol instead"
    ),
    ("mjls/stopping.py", "StoppingRule"): (
        "a cycle needs a lag-p change below 1e-4 times the lag-1 change: a contraction factor "
        "-(1 - e) has their ratio about e, so only e < 1e-4 is taken for a cycle"
    ),
    # the certified rho and the input checks
    ("mjls/certificate.py", "_SHIFTS"): (
        "shifts tried in turn where the Perron stack is singular to rounding (0 first, then "
        "growing); each bound is certified whatever shift succeeds"
    ),
    ("mjls/certificate.py", "_RESOLVENT_GAPS"): (
        "relative gaps r = rho (1 + gap) tried in turn for the resolvent stacks, the widest "
        "first; each gives a certified upper bound"
    ),
    ("mjls/certificate.py", "_DEFLATED_GAPS"): (
        "gaps tried in turn for the deflated resolvent bounds (a ladder of half decades); "
        "each gives a certified upper bound, the tightest is kept"
    ),
    ("mjls/certificate.py", "_resolvent_bounds"): (
        "1e-300 floor of rho in the resolvent radius: rho = 0 still gives a positive radius"
    ),
    ("validation.py", "SYMMETRY_RTOL"): (
        "input checks: asymmetry and negative eigenvalues of a symmetric positive "
        "semidefinite argument up to rounding of data computed elsewhere are accepted"
    ),
    ("validation.py", "WEIGHT_ATOL"): (
        "input checks: probability vectors and rows of T that sum to 1 within rounding of "
        "data computed elsewhere are accepted, and used as given"
    ),
}


def _top_level_names(tree):
    """(top-level name, node) for every function, class and assigned module constant."""
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            yield node.name, node
        elif (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
        ):
            yield node.targets[0].id, node
        else:
            yield "<module>", node


def _small(node):
    return [
        sub.value
        for sub in ast.walk(node)
        if isinstance(sub, ast.Constant)
        and isinstance(sub.value, float)
        and 0 < abs(sub.value) < 1e-3
    ]


def small_literals(root=SRC):
    """{(file, top-level name): [values]} of every float literal 0 < |v| < 1e-3 outside config.py.

    The keyword defaults of the functions (and methods) of one subpackage share one entry,
    ``("<subpackage>/*", "<keyword defaults>")``: a value shown in a signature and changed per
    call is the caller's setting, not a hidden constant.
    """
    found = {}
    for path in sorted(root.rglob("*.py")):
        if path.name in SETTINGS_FILES:
            continue
        file = path.relative_to(root).as_posix()
        for name, node in _top_level_names(ast.parse(path.read_text(), filename=str(path))):
            defaults = [
                d
                for sub in ast.walk(node)
                if isinstance(sub, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
                for d in sub.args.defaults + [k for k in sub.args.kw_defaults if k is not None]
            ]
            in_defaults = [v for d in defaults for v in _small(d)]
            rest = _small(node)
            for value in in_defaults:
                rest.remove(value)
            package = f"{path.parent.relative_to(root).as_posix()}/*".lstrip("./")
            for key, values in (
                ((package or "*", "<keyword defaults>"), in_defaults),
                ((file, name), rest),
            ):
                if values:
                    found.setdefault(key, []).extend(values)
    return found


def test_small_literals_are_settings_or_allowed_with_a_reason():
    found = small_literals()
    unexplained = {key: values for key, values in found.items() if key not in ALLOWED}
    assert not unexplained, (
        f"small float literals outside asoc.config: make each a key of "
        f"asoc.config (with its reason) or allow it here: {unexplained}"
    )


def test_the_allow_list_is_short_and_current():
    assert len(ALLOWED) <= MAX_ENTRIES
    stale = sorted(set(ALLOWED) - set(small_literals()))
    assert not stale, f"allow-list entries without a literal any more: {stale}"
    assert all(len(reason) > 20 for reason in ALLOWED.values())


def test_the_scan_finds_a_planted_literal(tmp_path):
    (tmp_path / "planted.py").write_text("def f(x, tol=1e-9):\n    return x + 2e-4\n")
    (tmp_path / "config.py").write_text("X = 1e-9\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "deep.py").write_text("class C:\n    def g(self, *, h=-5e-7): pass\n")
    assert small_literals(tmp_path) == {
        ("*", "<keyword defaults>"): [1e-9],
        ("planted.py", "f"): [2e-4],
        ("sub/*", "<keyword defaults>"): [5e-7],  # the literal of -5e-7
    }
