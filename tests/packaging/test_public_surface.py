"""One public surface per module (issue 32, item 1): what looks public is exported, and what is
exported validates its input.

- Every module of ``src/asoc`` declares ``__all__``, and every top-level function or class whose
  name does not start with an underscore is in it.
- Every function exported by ``asoc.mjls``, ``asoc.belief`` and ``asoc.gp``, called with an
  obviously wrong value (a string) for each of its required arguments, raises a ValueError or
  TypeError whose message names one of those arguments as the caller wrote it (not an internal
  name, and not Python's own "missing argument" error).
"""

import ast
import inspect
import re
import warnings
from pathlib import Path

import pytest

import asoc.belief
import asoc.gp
import asoc.mjls

SRC = Path(__file__).resolve().parents[2] / "src" / "asoc"
WRONG = "not an array"


def declared_all(tree):
    """The names of a module's ``__all__`` (None if it has none)."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            getattr(t, "id", None) == "__all__" for t in node.targets
        ):
            return set(ast.literal_eval(node.value))
    return None


def public_outside_all(root=SRC):
    """``file: name`` for every public-looking top-level def/class missing from ``__all__``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        exported = declared_all(tree)
        if exported is None:
            found.append(f"{path.relative_to(root)}: no __all__")
            continue
        found += [
            f"{path.relative_to(root)}: {node.name}"
            for node in tree.body
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
            and not node.name.startswith("_")
            and node.name not in exported
        ]
    return found


def test_every_public_looking_name_is_exported():
    assert public_outside_all() == []


def test_the_name_check_finds_a_planted_name(tmp_path):
    (tmp_path / "a.py").write_text(
        "__all__ = ['f']\ndef f(): pass\ndef g(): pass\ndef _h(): pass\n"
    )
    (tmp_path / "b.py").write_text("class C: pass\n")
    assert public_outside_all(tmp_path) == ["a.py: g", "b.py: no __all__"]


def exported_functions():
    for package in (asoc.mjls, asoc.belief, asoc.gp):
        for name in package.__all__:
            obj = getattr(package, name)
            if inspect.isfunction(obj):
                yield pytest.param(obj, id=f"{package.__name__}.{name}")


def required(function):
    """(positional, keyword-only) names of the arguments without a default."""
    params = inspect.signature(function).parameters.values()
    positional = [
        p.name
        for p in params
        if p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
    ]
    keyword = [p.name for p in params if p.default is p.empty and p.kind is p.KEYWORD_ONLY]
    return positional, keyword


@pytest.mark.parametrize("function", exported_functions())
def test_an_exported_function_names_its_wrong_argument(function):
    positional, keyword = required(function)
    if not positional + keyword:  # nothing required: try the first argument
        first = next(iter(inspect.signature(function).parameters), None)
        if first is None:
            pytest.skip("takes no arguments")
        positional = [first]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises((ValueError, TypeError)) as caught:
            function(*[WRONG] * len(positional), **{name: WRONG for name in keyword})
    message = str(caught.value)
    assert "required positional argument" not in message and "unexpected keyword" not in message
    assert any(re.search(rf"\b{re.escape(name)}\b", message) for name in positional + keyword), (
        f"{function.__name__}: the error does not name {positional + keyword}: {message}"
    )


@pytest.mark.parametrize("function", [asoc.mjls.successor_average, asoc.mjls.predecessor_sum])
def test_mode_averages_validate(function):
    with pytest.raises(ValueError, match="T: expected"):
        function([[0.5, 0.6], [0.5, 0.5]], [1.0, 2.0])
    with pytest.raises(ValueError, match="one per mode of T"):
        function([[1.0]], [1.0, 2.0])
    with pytest.raises(TypeError, match="T: expected a real array"):
        function("T", [1.0])
    assert function([[1.0]], [[2.0]], check=False).tolist() == [[2.0]]
