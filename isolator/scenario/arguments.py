"""The public API's arguments checked against their annotations, so that a wrong type is one clear error.

``check_public(globals())`` at the end of a module wraps every function of its ``__all__`` defined there, and
the ``__init__`` of every class (dataclasses included): an argument whose type its annotation does not
admit raises :class:`~isolator.errors.ParameterError` naming the argument and what it must be, e.g.
``lin: must be a LinearModel, got str``. A parameter annotated with a class that has a registered
conversion (:func:`register_conversion`; a ``Scenario`` takes a bundled scenario's name or a path to its
TOML file, as the command line does) is converted first; a class with a registered validator
(:func:`register_validator`; the scenario's dataclasses, by :mod:`isolator.scenario.rules`) checks its
values once built.

Only the outer type is checked (a ``Sequence[float]`` must be a sequence; its items are the function's to
check); numbers may be any real number type (numpy's too), arrays anything ``numpy.asarray`` reads as
numbers, and annotations the checker cannot read admit anything.
"""

from __future__ import annotations

import collections.abc as abc
import contextlib
import contextvars
import functools
import inspect
import numbers
import os
import types
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import IsolatorError, ParameterError

__all__ = ["check_public", "checked", "matches", "reading", "register_conversion", "register_validator"]

#: True while a reader builds the dataclasses: it checks their values itself, naming the file's keys
_READING: contextvars.ContextVar[bool] = contextvars.ContextVar("isolator_reading", default=False)

_CONVERSIONS: dict[type, Callable[[Any], Any]] = {}
_VALIDATORS: dict[type, Callable[[Any], None]] = {}
_ARRAY_LIKE = (np.ndarray, list, tuple, numbers.Number, np.generic)
_READABLE = {float: "a number", int: "a whole number", bool: "True or False", str: "a string",
             np.ndarray: "an array of numbers", Path: "a path", type(None): "None"}


def register_conversion(cls: type, convert: Callable[[Any], Any]) -> None:
    """Let parameters annotated ``cls`` take a string or path too, converted by ``convert``."""
    _CONVERSIONS[cls] = convert


@contextlib.contextmanager
def reading() -> abc.Iterator[None]:
    """While a reader builds a scenario: the validators wait (the reader checks every value, naming its key)."""
    token = _READING.set(True)
    try:
        yield
    finally:
        _READING.reset(token)


def register_validator(cls: type, validate: Callable[[Any], None]) -> None:
    """Have every ``cls`` checked by ``validate`` once built (its values; the constructor checks the types)."""
    _VALIDATORS[cls] = validate


def matches(value: object, hint: Any) -> bool:
    """Whether ``value`` is of the type ``hint`` admits (outer type only; unknown hints admit anything)."""
    test = _predicate(hint)
    return test is None or test(value)


def _predicate(hint: Any) -> Callable[[object], bool] | None:
    """A test of the values ``hint`` admits, built once per parameter (None: it admits anything)."""
    if hint is Any or hint is object or isinstance(hint, str | typing.TypeVar):
        return None
    if hint is None or hint is type(None):
        return lambda value: value is None
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        tests = [_predicate(h) for h in typing.get_args(hint)]
        if any(t is None for t in tests):
            return None
        return lambda value: any(t(value) for t in tests)  # type: ignore[misc]
    if origin is typing.Literal:
        allowed = typing.get_args(hint)
        return lambda value: value in allowed
    cls = origin if origin is not None else hint
    return _class_predicate(cls) if isinstance(cls, type) else None


def _class_predicate(cls: type) -> Callable[[object], bool] | None:
    """A test of the instances of ``cls`` as the module's description reads them."""
    if cls is float:
        return lambda v: isinstance(v, numbers.Real) and not isinstance(v, bool)
    if cls is int:
        return lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool)
    if cls is bool:
        return lambda v: isinstance(v, bool | np.bool_)
    if cls is np.ndarray:
        return lambda v: isinstance(v, _ARRAY_LIKE) and not isinstance(v, bool)
    if cls in (Path, os.PathLike):
        return lambda v: isinstance(v, str | os.PathLike)
    if cls in (tuple, list):
        return lambda v: isinstance(v, list | tuple | np.ndarray | range)
    if cls in (abc.Sequence, abc.Iterable, abc.Collection):
        return lambda v: isinstance(v, list | tuple | np.ndarray | range | cls)
    if getattr(cls, "_is_protocol", False) and not getattr(cls, "_is_runtime_protocol", False):
        return None  # a protocol isinstance cannot check
    try:
        isinstance(None, cls)
    except TypeError:
        return None
    return lambda v: isinstance(v, cls)


def _describe(hint: Any) -> str:
    """What a hint admits, in words (``a LinearModel``, ``a number or None``)."""
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        return " or ".join(dict.fromkeys(_describe(h) for h in typing.get_args(hint)))
    if origin is typing.Literal:
        return "one of " + ", ".join(repr(a) for a in typing.get_args(hint))
    cls = origin if origin is not None else hint
    if cls in _CONVERSIONS:
        return f"a {cls.__name__}, a bundled scenario's name or a path to its TOML file"
    if cls in _READABLE:
        return _READABLE[cls]
    name = getattr(cls, "__name__", str(cls))
    return f"{'an' if name[:1].lower() in 'aeiou' else 'a'} {name}"


def _shown(value: object) -> str:
    """A wrong argument in an error message: a short number, string or None as written, else its type."""
    if value is None or isinstance(value, bool | numbers.Number | str):
        text = repr(value)
        if len(text) <= 40:
            return text
    return type(value).__name__


def _hints(func: Callable[..., Any]) -> dict[str, Any]:
    """The annotations of ``func`` resolved (those that cannot be resolved are left out)."""
    try:
        return typing.get_type_hints(func)
    except Exception:
        out = {}
        for name, text in getattr(func, "__annotations__", {}).items():
            try:
                out[name] = eval(text, getattr(func, "__globals__", {})) if isinstance(text, str) else text
            except Exception:
                continue
        return out


def checked(func: Callable[..., Any]) -> Callable[..., Any]:
    """``func`` with its arguments checked against its annotations (see the module's description)."""
    signature = inspect.signature(func)
    parameters = list(signature.parameters.values())
    positional = [p.name for p in parameters if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    spread = any(p.kind is p.VAR_POSITIONAL for p in parameters)
    required = [p.name for p in parameters if p.default is p.empty and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    plan: dict[str, tuple[Any, Callable[[object], bool] | None, type | None]] | None = None
    validates = func.__name__ == "__init__"

    def check(name: str, value: object) -> object:
        """``value`` of the parameter ``name``, converted when it may be, or a ParameterError."""
        assert plan is not None
        hint, test, convert = plan[name]
        if convert is not None and not isinstance(value, convert) and isinstance(value, str | os.PathLike):
            value = _CONVERSIONS[convert](value)
        if test is not None and not test(value):
            raise ParameterError(f"{name}: must be {_describe(hint)}, got {_shown(value)}")
        return value

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        nonlocal plan
        if plan is None:
            hints = _hints(func)
            plan = {}
            for p in parameters:
                if p.name in ("self", "cls") or p.name not in hints or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                    continue
                hint = hints[p.name]
                options = typing.get_args(hint) if typing.get_origin(hint) in (typing.Union, types.UnionType) else ()
                convert = next((c for c in (hint, *options) if isinstance(c, type) and c in _CONVERSIONS), None)
                plan[p.name] = (hint, _predicate(hint), convert)
        if len(args) > len(positional) and not spread:
            raise ParameterError(f"{func.__qualname__}: takes {len(positional)} positional arguments, "
                                 f"got {len(args)}")
        given = list(args)
        for k, name in enumerate(positional[: len(given)]):
            if name in plan:
                given[k] = check(name, given[k])
        for name in kwargs:
            if name in plan:
                kwargs[name] = check(name, kwargs[name])
        missing = [n for n in required if n not in kwargs and n not in positional[: len(given)]]
        if missing:
            raise ParameterError(f"{missing[0]}: missing (a required argument of {func.__qualname__})")
        out = func(*given, **kwargs)
        if validates and given and type(given[0]) in _VALIDATORS and not _READING.get():
            _VALIDATORS[type(given[0])](given[0])
        return out

    wrapper.__checked__ = True  # type: ignore[attr-defined]
    return wrapper


def check_public(namespace: dict[str, Any], names: abc.Iterable[str] | None = None, foreign: bool | None = None
                 ) -> None:
    """Check the arguments of every function and class constructor a module exports (``names``, default its
    ``__all__``) and defines (call at the end of the module: ``check_public(globals())``); ``foreign`` (default:
    when ``names`` is not given): those it re-exports from elsewhere too (functions wrapped in this module,
    classes everywhere)."""
    module = namespace["__name__"]
    foreign = names is None if foreign is None else foreign
    for name in namespace.get("__all__", ()) if names is None else names:
        obj = namespace.get(name)
        if not foreign and getattr(obj, "__module__", None) != module:
            continue
        if inspect.isfunction(obj) and not getattr(obj, "__checked__", False):
            namespace[name] = checked(obj)
        elif inspect.isclass(obj) and not issubclass(obj, IsolatorError | BaseException) and \
                not getattr(obj, "_is_protocol", False):
            init = obj.__dict__.get("__init__")
            if init is not None and not getattr(init, "__checked__", False):
                obj.__init__ = checked(init)  # type: ignore[method-assign]
