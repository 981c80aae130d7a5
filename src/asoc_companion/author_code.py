"""The author's MATLAB code as a reference for speed and for the gains (the Scaling page).

The thesis's author published MATLAB code for Alg. 3.1 (``MJLS_StaticOutputComputeRegulatorGain.m``)
and for the dense mean-square spectral radius (``ComputeSpectralRadius.m``) at
github.com/Mxttak/MJLS. It was run under Octave beside this library, on the same random systems
of :func:`asoc_companion.scaling.scaling_system` (with J = 0: the author's code has no measurement
noise), one after the other on one otherwise idle machine. Octave is not needed to build the
book: the measured seconds, the machine they were measured on and the author's gains are
recorded in ``tests/reference/author_code_octave.json``. Neither the author's code nor the script
that ran it is part of this repository.

The recorded gains make the comparison checkable: :func:`reference_system` regenerates a case's
system from the recorded seed, so this library's Alg. 3.1 can be compared with the author's gain.
"""

import json
from collections import Counter

import numpy as np

from asoc.mjls import MJLS

from . import paths
from .scaling import scaling_system

__all__ = ["REFERENCE_FILE", "load_reference", "reference_system", "comparison_table",
           "machine_sentence"]


#: The recorded measurements, under the project root.
REFERENCE_FILE = ("tests", "reference", "author_code_octave.json")


def load_reference(root=None) -> dict:
    """The recorded side-by-side measurements (``tests/reference/author_code_octave.json``).

    Examples
    --------
    The file of the checkout this runs in:

    >>> record = load_reference()
    >>> record["author_code"]["repository"], {case["kind"] for case in record["cases"]} == {"alg31",
    ...     "rho"}
    ('https://github.com/Mxttak/MJLS', True)
    """
    return json.loads(paths.project(root).root.joinpath(*REFERENCE_FILE).read_text())


def _require(mapping, keys, name):
    """``mapping`` if it is a dict with ``keys``, else a TypeError or ValueError naming ``name``."""
    if not isinstance(mapping, dict):
        raise TypeError(f"{name}: expected a dict as in {'/'.join(REFERENCE_FILE)}, found "
                        f"{type(mapping).__name__}")
    missing = [key for key in keys if key not in mapping]
    if missing:
        raise ValueError(f"{name}: missing {', '.join(missing)} (see {'/'.join(REFERENCE_FILE)})")
    return mapping


def reference_system(record: dict, case: dict) -> MJLS:
    """The random system of one recorded ``case``, regenerated from the recorded seed (J = 0).

    Examples
    --------
    >>> record = {"seed": 2017, "cases_count": 2}
    >>> s = reference_system(record, {"n": 4, "M": 2, "radius": 0.9, "spawn": 1})
    >>> s.nx, s.M, s.J is None
    (4, 2, True)
    >>> reference_system(record, {"n": 4, "M": 2})
    Traceback (most recent call last):
    ...
    ValueError: case: missing radius, spawn (see tests/reference/author_code_octave.json)
    """
    _require(record, ("seed", "cases_count"), "record")
    _require(case, ("n", "M", "radius", "spawn"), "case")
    children = np.random.SeedSequence(record["seed"]).spawn(record["cases_count"])
    rng = np.random.default_rng(children[case["spawn"]])
    s = scaling_system(rng, case["n"], case["M"], radius=case["radius"])
    return MJLS(s.A, s.B, s.C, s.H, s.Q, s.R, s.T)


def _case_name(case: dict) -> str:
    what = "Alg. 3.1" if case["kind"] == "alg31" else "dense rho"
    return f"{what}, n = {case['n']}, M = {case['M']}, open-loop rho {case['open_loop_rho']:.3g}"


def _seconds(value: float) -> str:
    return f"{value:.3f} s" if value < 1 else f"{value:.1f} s"


def comparison_table(record: dict):
    """Header and rows of the side-by-side table: the author's code under Octave, this library.

    For Alg. 3.1 the library's three moment modes are shown (``auto``, the default; ``step``,
    the thesis's iteration, which is the author's; ``exact``) with their iteration counts, and
    the largest relative difference of the library's gain from the author's.

    Examples
    --------
    >>> case = {"kind": "alg31", "n": 4, "M": 2, "open_loop_rho": 0.5, "octave_seconds": 1.5,
    ...         "library_seconds": {"auto": 0.01, "step": 0.02, "exact": 0.03},
    ...         "library_iterations": {"auto": 5, "step": 9, "exact": 3},
    ...         "gain_difference": {"auto": 1e-7, "step": 2e-7, "exact": 1e-7}}
    >>> header, rows = comparison_table({"cases": [case]})
    >>> rows[0]
    ['Alg. 3.1, n = 4, M = 2, open-loop rho 0.5', '1.5 s', '0.010 s (5)', '0.020 s (9)',
     '0.030 s (3)', '2e-07', '150x']
    """
    _require(record, ("cases",), "record")
    header = ["case", "author's code (Octave)", "this library: auto (iterations)", "step", "exact",
              "gain vs author's (relative)", "speed-up of the default"]
    rows = []
    for i, case in enumerate(record["cases"]):
        _require(case, ("kind", "n", "M", "open_loop_rho", "octave_seconds", "library_seconds"),
                 f"record['cases'][{i}]")
        lib, octave = case["library_seconds"], case["octave_seconds"]
        if case["kind"] == "alg31":
            its = case["library_iterations"]
            modes = [f"{_seconds(lib[m])} ({its[m]})" for m in ("auto", "step", "exact")]
            agree, default = f"{max(case['gain_difference'].values()):.0e}", lib["auto"]
        else:
            default = lib["ms_spectral_radius"]
            modes = [_seconds(default), "", ""]
            agree = f"rho differs by {abs(case['open_loop_rho'] - case['author_rho']):.0e}"
        rows.append([_case_name(case), _seconds(octave), *modes, agree, f"{octave / default:.0f}x"])
    return header, rows


def machine_sentence(record: dict) -> str:
    """One sentence naming the machine, the software and the day of the measurement.

    Examples
    --------
    >>> print(machine_sentence({"machine": {"cpu": "AMD EPYC", "cores": 2, "octave": "7.3.0",
    ...                                     "numpy": "2.1.0", "blas": "scipy-openblas 0.3.27",
    ...                                     "python": "3.11.7", "date": "2026-11-25",
    ...                                     "load_average_1min": [0.2, 1.1]},
    ...                         "author_code": {"commit": "94a92e9d"},
    ...                         "cases": [{"repetitions": 3}, {"repetitions": 1}]}))
    Measured on 2026-11-25 on one AMD EPYC machine with 2 cores (1-minute load average 0.2
    before, 1.1 after): the author's code (commit 94a92e9) under Octave 7.3.0; this library under
    Python 3.11.7, NumPy 2.1.0 with scipy-openblas 0.3.27. Each time is the best of its case's
    runs: 3 for 1 case, 1 for 1 case.
    """
    m = _require(_require(record, ("machine", "author_code"), "record")["machine"],
                 ("date", "cpu", "cores", "octave", "python", "numpy", "blas"), "record['machine']")
    load = m.get("load_average_1min")
    load = f" (1-minute load average {load[0]:g} before, {load[1]:g} after)" if load else ""
    runs = Counter(case["repetitions"] for case in record.get("cases", []) if "repetitions" in case)
    runs = ("" if not runs else " Each time is the best of its case's runs: " + ", ".join(
        f"{r} for {k} case{'s' * (k != 1)}" for r, k in sorted(runs.items(), reverse=True)) + ".")
    return (f"Measured on {m['date']} on one {m['cpu']} machine with {m['cores']} cores{load}: the "
            f"author's code (commit {record['author_code']['commit'][:7]}) under Octave "
            f"{m['octave']}; this library under Python {m['python']}, NumPy {m['numpy']} with "
            f"{m['blas']}.{runs}")
