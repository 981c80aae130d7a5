"""The library's tunables in one place, as python-control's ``config.defaults``.

Every switch point, tolerance and size limit that a function reads at call time lives in
:data:`defaults`, keyed ``"<subpackage>.<name>"``, with the measurement or reason behind its
value in :data:`DESCRIPTIONS` and the values it accepts in :data:`ALLOWED`. Change one for the
rest of the session with :func:`set_defaults` (or by assigning to ``defaults[key]``), for a block
of code with :func:`option_context`, for one call with the keyword that :func:`accepts_settings`
gives a function, and go back to the shipped values with :func:`reset_defaults`. A key that is
not a tunable is refused with the closest one, and a value of the wrong type or range with the
key's name, when it is set. No module keeps a tunable as a global of its own, and no caller
assigns to a module's attributes.

Examples
--------
>>> from asoc import config
>>> config.defaults["mjls.rank_rtol"]
1e-10
>>> with config.option_context(**{"mjls.rank_rtol": 1e-8}):
...     config.defaults["mjls.rank_rtol"]
1e-08
>>> config.defaults["mjls.rank_rtol"]
1e-10
>>> config.defaults["mjls.rank_rol"] = 1e-8
Traceback (most recent call last):
    ...
KeyError: "unknown configuration key 'mjls.rank_rol'; did you mean 'mjls.rank_rtol'?"
>>> config.defaults["mjls.rank_rtol"] = "1e-8"
Traceback (most recent call last):
    ...
TypeError: mjls.rank_rtol: expected a real number in (0, 1) or None, found str '1e-8'
"""

import contextlib
import contextvars
import difflib
import functools
import inspect
from collections.abc import Iterator, MutableMapping

from .setting_checks import Allowed
from .tunables import TUNABLES

__all__ = ["DESCRIPTIONS", "ALLOWED", "defaults", "set_defaults", "reset_defaults",
           "option_context", "accepts_settings"]


#: Each tunable: (shipped value, the values it accepts, why), from :mod:`asoc.tunables`.
_REGISTRY = TUNABLES


def _check_registry():
    for key, entry in _REGISTRY.items():
        if len(entry) != 3 or not isinstance(entry[1], Allowed):
            raise TypeError(f"asoc.config: the entry {key!r} must be (value, allowed values from "
                            f"asoc.setting_checks, reason), found {entry!r:.80}")
        entry[1].check(key, entry[0])


_check_registry()

#: Why each tunable has its shipped value.
DESCRIPTIONS: dict[str, str] = {key: why for key, (_, _, why) in _REGISTRY.items()}
#: The values each tunable accepts (a type and an interval).
ALLOWED: dict[str, str] = {key: str(allowed) for key, (_, allowed, _) in _REGISTRY.items()}

#: Per-call values (the keywords of :func:`accepts_settings`), above the session's values.
_CALL_VALUES: contextvars.ContextVar = contextvars.ContextVar("asoc_config_call_values", default={})


def _checked_key(key):
    if key not in _REGISTRY:
        close = difflib.get_close_matches(str(key), _REGISTRY, n=1)
        hint = f"did you mean {close[0]!r}?" if close else f"valid keys: {sorted(_REGISTRY)}"
        raise KeyError(f"unknown configuration key {key!r}; {hint}")
    return key


def _checked(key, value):
    _REGISTRY[_checked_key(key)][1].check(key, value)
    return value


class _Defaults(MutableMapping):
    """The current value of every tunable; a new value is checked when it is set.

    A key can be changed but neither added nor removed. Values given to one call through the
    keywords of :func:`accepts_settings` take precedence inside that call (and its thread).
    """

    def __init__(self):
        self._values = {key: value for key, (value, _, _) in _REGISTRY.items()}

    def __getitem__(self, key):
        call = _CALL_VALUES.get()
        return call[key] if key in call else self._values[_checked_key(key)]

    def __setitem__(self, key, value):
        self._values[key] = _checked(key, value)

    def __delitem__(self, key):
        raise TypeError(f"configuration key {key!r} cannot be removed; use reset_defaults()")

    def __iter__(self):
        return iter(self._values)

    def __len__(self):
        return len(self._values)

    def __repr__(self):
        return f"defaults({dict(self.items())!r})"

    def _reset(self):
        self._values.update({key: value for key, (value, _, _) in _REGISTRY.items()})


#: The current value of every tunable, keyed ``"<subpackage>.<name>"``.
defaults = _Defaults()


def set_defaults(**values) -> None:
    """Set tunables for the rest of the session, by their full keys.

    Parameters
    ----------
    **values
        ``"<subpackage>.<name>"`` to its new value; pass dotted keys with ``**{...}``.

    Raises
    ------
    KeyError
        If a key is not a tunable of the library (with the closest key).
    TypeError, ValueError
        If a value has the wrong type or lies outside the key's range; nothing is set then.

    Examples
    --------
    >>> from asoc import config
    >>> config.set_defaults(**{"mjls.dense_max_radius": 0})
    >>> config.defaults["mjls.dense_max_radius"]
    0
    >>> config.set_defaults(**{"mjls.dense_max_radius": -1})
    Traceback (most recent call last):
        ...
    ValueError: mjls.dense_max_radius: expected an integer >= 0, found -1
    >>> config.reset_defaults()
    """
    for key, value in values.items():
        _checked(key, value)
    defaults.update(values)


def reset_defaults() -> None:
    """Restore every tunable to its shipped value.

    Examples
    --------
    >>> from asoc import config
    >>> config.set_defaults(**{"mjls.bracket_rtol": 1e-6})
    >>> config.reset_defaults()
    >>> config.defaults["mjls.bracket_rtol"]
    1e-12
    """
    defaults._reset()


@contextlib.contextmanager
def option_context(**values) -> Iterator[None]:
    """Set tunables inside a ``with`` block, restoring the previous values on exit (also on error).

    Parameters
    ----------
    **values
        ``"<subpackage>.<name>"`` to its value inside the block, checked as by
        :func:`set_defaults`.

    Examples
    --------
    >>> from asoc import config
    >>> with config.option_context(**{"mjls.dense_max_solve": 0}):
    ...     config.defaults["mjls.dense_max_solve"]
    0
    >>> config.defaults["mjls.dense_max_solve"]
    256
    """
    for key, value in values.items():
        _checked(key, value)
    previous = {key: defaults[key] for key in values}
    defaults.update(values)
    try:
        yield
    finally:
        defaults.update(previous)


def accepts_settings(*keys):
    """Give a function one keyword per tunable it depends on, as python-control's keywords.

    python-control's functions take a keyword per setting (``method=None``) and look it up with
    ``config._get_param`` when it is None. Here the decorator adds the keywords once: the keyword
    is the key's last part (``rank_rtol`` for ``"mjls.rank_rtol"``); None, its default, uses
    :data:`defaults`. A value given is checked like an assignment to :data:`defaults` and holds
    for this call only, for everything it calls, without touching the session's values (other
    threads keep theirs). The docstring gains an "Other Parameters" list of the keywords.

    Parameters
    ----------
    *keys : str
        The ``"<subpackage>.<name>"`` keys whose values change the function's result.

    Returns
    -------
    callable
        The decorator.

    Raises
    ------
    KeyError
        If a key is not a tunable of the library.
    TypeError
        If the function already has a parameter of a key's keyword name.

    Examples
    --------
    >>> from asoc import config
    >>> @config.accepts_settings("mjls.rank_rtol")
    ... def threshold():
    ...     return config.defaults["mjls.rank_rtol"]
    >>> threshold(), threshold(rank_rtol=1e-8), threshold()
    (1e-10, 1e-08, 1e-10)
    >>> threshold(rank_rtol="tight")
    Traceback (most recent call last):
        ...
    TypeError: rank_rtol (mjls.rank_rtol): expected a real number in (0, 1) or None,
    found str 'tight'
    """
    names = {_checked_key(key).split(".", 1)[1]: key for key in keys}

    def decorate(function):
        signature = inspect.signature(function)
        clash = sorted(set(names) & set(signature.parameters))
        if clash:
            raise TypeError(f"{function.__name__} already has parameter(s) {clash}")

        @functools.wraps(function)
        def with_settings(*args, **kwargs):
            given = {names[n]: kwargs.pop(n) for n in list(kwargs) if n in names}
            given = {key: _checked_per_call(key, value) for key, value in given.items()
                     if value is not None}
            if not given:
                return function(*args, **kwargs)
            token = _CALL_VALUES.set({**_CALL_VALUES.get(), **given})
            try:
                return function(*args, **kwargs)
            finally:
                _CALL_VALUES.reset(token)

        extra = [inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=None) for n in names]
        params = list(signature.parameters.values())
        tail = [p for p in params if p.kind is inspect.Parameter.VAR_KEYWORD]
        params = [p for p in params if p.kind is not inspect.Parameter.VAR_KEYWORD]
        with_settings.__signature__ = signature.replace(parameters=params + extra + tail)
        with_settings.__doc__ = (function.__doc__ or "") + _settings_section(names)
        with_settings.settings = tuple(names.values())
        return with_settings

    return decorate


def _checked_per_call(key, value):
    try:
        return _checked(key, value)
    except (TypeError, ValueError) as err:
        name = key.split(".", 1)[1]
        raise type(err)(f"{name} ({key}): {str(err).split(': ', 1)[1]}") from None


def _settings_section(names):
    lines = ["", "", "    Other Parameters", "    ----------------"]
    for name, key in names.items():
        kind = _REGISTRY[key][1].kind
        kind = "int" if kind is int else "tuple" if kind is tuple else "float"
        lines += [f"    {name} : {kind}, optional",
                  f"        This call's ``{key}``, {ALLOWED[key]} (None, the default: "
                  f"``asoc.config.defaults``, shipped {_REGISTRY[key][0]!r}).", ""]
    return "\n".join(lines)
