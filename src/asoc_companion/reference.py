"""The reference files ``tests/reference/thesis_values/<notebook>.yaml`` and each value's status.

Each notebook has its own file (so work on one section does not touch another's). Each entry is
keyed ``<notebook>.<key>`` and holds

``where``    where the thesis prints it (section, figure, table, page);
``kind``     ``deterministic`` (a number to its printed decimals), ``monte_carlo`` (a
             median whose bootstrap interval is recorded), ``claim`` (a qualitative
             statement turned into a check with a stated threshold) or ``measured`` (a
             number the thesis does not print, shown for the reader);
``thesis``   the printed value (number, list, or the claim's text); null for ``measured``;
``tol``      absolute tolerance (deterministic; rounding of Monte Carlo values);
``ci_rtol``  relative tolerance of a ``ci``-fidelity run against our own ``full`` value;
``expect``   ``reproduced``, ``deviates``, ``not-resolved`` (a statistical claim whose interval
             does not decide it) or ``new``: the status the ledger must show, so a change in
             status is a test failure, not a silent edit;
``note``     the reason for a deviation, the reading chosen, what was tried;
``evidence`` on a deviating row, whose fault the deviation is (:mod:`asoc_companion.evidence`):
             ``kind`` ``thesis-error`` (with ``certificate`` and ``section``), ``unspecified``
             (with ``readings`` and ``closest``) or ``open`` (with ``tried``).

Tolerances follow from the accuracy of the quantity, never from one machine's agreement
(another CPU's BLAS kernels move the last digits; the architecture page, "Portability"). The YAML
states each derivation next to the number; the rules are:

- ``tol`` of a printed number: half a unit of its last printed decimal (5e-5 for four
  decimals; 6e-5 leaves room for our own computation error, which is < 1e-10 for every
  such value here), or, for a Monte Carlo median, the rounding of the printed value.
- ``ci_rtol`` of a direct computation (eigenvalues, Riccati recursions, closed forms,
  quadrature): a few orders of magnitude above its rounding error, condition number
  times machine epsilon.
- ``ci_rtol`` of an iterative solver's output: its stopping rule. A fixed-point
  iteration stopped at relative change ``tol`` with contraction ``q`` is within
  ``tol q / (1 - q)`` of its limit; an optimiser stopped at gradient norm ``g`` has its
  minimiser within ``g / lambda_min(Hessian)`` and its minimum within ``g^2 / lambda_min``.
- ``ci_rtol`` of a Monte Carlo estimate: four combined standard errors of the ci and the
  full estimate (:func:`monte_carlo_rtol`, standard errors from the 95% intervals); the
  notebook tests check that no ``ci_rtol`` is tighter than that.
- claims: ``ci_rtol: 0`` asks for the same verdict at both fidelities, null for a check
  that only makes sense at full fidelity.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from . import paths
from .evidence import is_statistic, statistic_status

__all__ = ["SAFE_LOADER", "KINDS", "EXPECT", "Entry", "load_reference", "status", "Z_MONTE_CARLO",
           "monte_carlo_rtol", "agrees_with_full"]


# libyaml's safe loader when PyYAML has it (the same documents, ten times faster), else PyYAML's own
SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
KINDS = ("deterministic", "monte_carlo", "claim", "measured")
EXPECT = ("reproduced", "deviates", "not-resolved", "new")


@dataclass(frozen=True)
class Entry:
    """One reference entry ``<notebook>.<name>``; the fields are described in the module docstring.

    Examples
    --------
    >>> entry = Entry("sec3_5.rho_open_T1", where="an example", kind="deterministic", thesis=0.25,
    ...     tol=5e-5)
    >>> entry.notebook, entry.name, entry.expect
    ('sec3_5', 'rho_open_T1', 'reproduced')
    """

    key: str
    where: str
    kind: str
    thesis: object = None
    tol: float | None = None
    ci_rtol: float | None = None
    expect: str = "reproduced"
    note: str = ""
    evidence: dict | None = None

    @property
    def notebook(self) -> str:
        """The notebook that records the value: the key's part before the first dot."""
        return self.key.split(".", 1)[0]

    @property
    def name(self) -> str:
        """The value's name in its notebook: the key's part after the first dot."""
        return self.key.split(".", 1)[1]


def load_reference(path=None) -> dict:
    """Load and check the reference files (a folder of YAML files, or one file) as ``{key: Entry}``.

    Parameters
    ----------
    path : path, optional
        Default ``tests/reference/thesis_values/``.

    Returns
    -------
    dict
        ``{key: Entry}``.

    Raises
    ------
    ValueError
        If a key appears twice, sits in the wrong file, is not ``<notebook>.<name>``, or an
        entry has an unknown kind or expect, or a deterministic entry has no ``tol``.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = (Path(folder) / "demo.yaml").write_text(
    ...         "demo.rho: {where: an example, kind: deterministic, thesis: 0.25, tol: 5.0e-5}")
    ...     reference = load_reference(folder)
    >>> reference["demo.rho"].thesis, reference["demo.rho"].tol
    (0.25, 5e-05)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = (Path(folder) / "demo.yaml").write_text(
    ...         "demo.rho: {where: an example, kind: deterministic}")
    ...     load_reference(folder)
    Traceback (most recent call last):
    ...
    ValueError: reference demo.rho: a deterministic value needs tol
    """
    path = Path(path or paths.project().reference)
    raw = {}
    for file in sorted(path.glob("*.yaml")) if path.is_dir() else [path]:
        with open(file) as handle:
            for key, spec in (yaml.load(handle, Loader=SAFE_LOADER) or {}).items():
                if key in raw:
                    raise ValueError(f"reference key {key!r} appears twice (in {file.name})")
                if path.is_dir() and not key.startswith(file.stem + "."):
                    raise ValueError(f"reference key {key!r} belongs in {key.split('.')[0]}.yaml, "
                                     f"not {file.name}")
                raw[key] = spec
    entries = {}
    for key, spec in raw.items():
        if "." not in key:
            raise ValueError(f"reference key {key!r}: expected '<notebook>.<name>'")
        entry = Entry(key=key, **spec)
        if entry.kind not in KINDS:
            raise ValueError(f"reference {key}: kind must be one of {KINDS}, found {entry.kind!r}")
        if entry.expect not in EXPECT:
            raise ValueError(f"reference {key}: expect must be one of {EXPECT}, found "
                             f"{entry.expect!r}")
        if entry.kind == "deterministic" and entry.tol is None:
            raise ValueError(f"reference {key}: a deterministic value needs tol")
        entries[key] = entry
    return entries


def _max_abs_diff(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return float("inf")
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def status(entry: Entry, ours) -> str:
    """``reproduced``, ``deviates``, ``new`` or ``missing`` for our value ``ours``.

    Parameters
    ----------
    entry : Entry
    ours : object
        Our recorded value (None if missing).

    Returns
    -------
    str

    Raises
    ------
    KeyError
        If a Monte Carlo or claim value lacks ``ci`` or ``holds``.

    Examples
    --------
    A deterministic value agrees to ``tol``; a Monte Carlo one when the thesis's value lies in
    our interval (widened by ``tol``):

    >>> rho = Entry("demo.rho", where="an example", kind="deterministic", thesis=0.25, tol=5e-5)
    >>> status(rho, 0.25003), status(rho, 0.2501), status(rho, None)
    ('reproduced', 'deviates', 'missing')
    >>> cost = Entry("demo.cost", where="an example", kind="monte_carlo", thesis=10.0, tol=0.05)
    >>> status(cost, {"median": 10.4, "ci": [9.98, 10.9]}), status(cost, {"median": 10.4,
    ...     "ci": [10.1, 10.9]})
    ('reproduced', 'deviates')
    """
    if ours is None:
        return "missing"
    if entry.kind == "measured":
        return "new"
    if entry.kind == "claim":
        if is_statistic(ours):
            return statistic_status(ours)
        return "reproduced" if ours["holds"] else "deviates"
    if entry.kind == "deterministic":
        return "reproduced" if _max_abs_diff(ours, entry.thesis) <= entry.tol else "deviates"
    lo, hi = ours["ci"]
    slack = entry.tol or 0.0
    return "reproduced" if lo - slack <= float(entry.thesis) <= hi + slack else "deviates"


def _estimate(record):
    """The number of a record: the value itself, or a Monte Carlo record's ``value``/``median``."""
    if isinstance(record, dict) and ("value" in record or "median" in record):
        return record.get("value", record.get("median"))
    return record


Z_MONTE_CARLO = 4.0   # standard errors: two-sided false alarm 6e-5 per value under normality


def monte_carlo_rtol(ours_ci, ours_full, z: float = Z_MONTE_CARLO):
    """Relative tolerance of a ci-fidelity Monte Carlo estimate against the full one.

    ``z`` combined standard errors, each taken from its record's 95% interval
    (half-width / 1.96): ``z sqrt(se_ci^2 + se_full^2) / |full|``. None when a record
    carries no interval.

    Examples
    --------
    Standard errors 2 / 3.92 and 1 / 3.92 from the two 95% intervals, four of them combined,
    relative to the full estimate 10:

    >>> round(monte_carlo_rtol({"median": 10.0, "ci": [9.0, 11.0]}, {"median": 10.0, "ci": [9.5,
    ...     10.5]}), 4)
    0.2282
    >>> print(monte_carlo_rtol(10.0, {"median": 10.0, "ci": [9.5, 10.5]}))
    None
    """
    if not all(isinstance(r, dict) and "ci" in r for r in (ours_ci, ours_full)):
        return None
    se = [(r["ci"][1] - r["ci"][0]) / (2 * 1.959964) for r in (ours_ci, ours_full)]
    return z * float(np.hypot(*se)) / max(abs(float(_estimate(ours_full))), 1e-12)


def agrees_with_full(entry: Entry, ours_ci, ours_full) -> tuple[bool, str]:
    """Whether a ``ci``-fidelity value agrees with our ``full``-fidelity value.

    Deterministic values must agree to ``tol`` at any fidelity; Monte Carlo values to
    ``ci_rtol`` (relative); claims must give the same verdict unless ``ci_rtol`` is null
    (claims that only make sense at full fidelity); measured values to ``ci_rtol``.

    Examples
    --------
    >>> rho = Entry("demo.rho", where="an example", kind="deterministic", thesis=0.25, tol=5e-5)
    >>> agrees_with_full(rho, 0.25001, 0.25)
    (True, '|ci - full| = 1e-05, tol 5e-05')
    >>> cost = Entry("demo.cost", where="an example", kind="monte_carlo", thesis=10.0, ci_rtol=0.02)
    >>> agrees_with_full(cost, {"median": 10.4, "ci": [9.4, 11.4]}, {"median": 10.0, "ci": [9.5,
    ...     10.5]})
    (False, 'relative |ci - full| = 0.04, ci_rtol 0.02')

    A measured record may nest fields; its words (a verdict, a version) must be equal:

    >>> margin = Entry("demo.margin", where="an example", kind="measured", ci_rtol=1e-3)
    >>> agrees_with_full(margin, {"m": -0.03832, "verdict": "infeasible"},
    ...                  {"m": -0.03833, "verdict": "infeasible"})
    (True, 'relative |ci - full| = 0.000261, ci_rtol 0.001')
    >>> agrees_with_full(margin, {"m": 0.1, "verdict": "feasible"}, {"m": -0.1,
    ...     "verdict": "infeasible"})
    (False, "verdict: ci 'feasible', full 'infeasible'")
    """
    if entry.kind == "deterministic":
        diff = _max_abs_diff(ours_ci, ours_full)
        return diff <= entry.tol, f"|ci - full| = {diff:.3g}, tol {entry.tol}"
    if entry.kind == "claim":
        if entry.ci_rtol is None:
            return True, "claim checked at full fidelity only"
        verdicts = [r["verdict"] if is_statistic(r) else r["holds"] for r in (ours_ci, ours_full)]
        return verdicts[0] == verdicts[1], f"verdict: ci {verdicts[0]}, full {verdicts[1]}"
    a, b = _estimate(ours_ci), _estimate(ours_full)
    if entry.ci_rtol is None:
        return True, "compared at full fidelity only"
    leaves_a, leaves_b = dict(_leaves(a)), dict(_leaves(b))
    if leaves_a.keys() != leaves_b.keys():
        return False, f"fields differ: ci {sorted(leaves_a)}, full {sorted(leaves_b)}"
    words = [path for path, leaf in leaves_b.items() if isinstance(leaf, (str, bool))]
    if any(leaves_a[path] != leaves_b[path] for path in words):
        return False, "; ".join(f"{'.'.join(p) or 'value'}: ci {leaves_a[p]!r}, full "
                                f"{leaves_b[p]!r}" for p in words
                                if leaves_a[p] != leaves_b[p])
    rel = max((_relative_difference(leaves_a[p], leaves_b[p]) for p in leaves_b if p not in words),
              default=0.0)
    return rel <= entry.ci_rtol, f"relative |ci - full| = {rel:.3g}, ci_rtol {entry.ci_rtol}"


def _leaves(value, path=()):
    """(path, leaf) of a nested record: a dict's fields in turn, anything else as one leaf."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _leaves(item, (*path, str(key)))
    else:
        yield path, value


def _relative_difference(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return float("inf")
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-12))) if a.size else 0.0
