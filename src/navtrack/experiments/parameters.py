"""Experiment parameters from the command line and TOML files, typed by the dataclass fields.

``navtrack reproduce NAME --params FILE.toml --set key=value ...`` starts from the experiment's
defaults, applies the TOML file's top-level keys, then each ``--set``. Values are converted to
and checked against the field's annotated type: bool (``true/false/yes/no/on/off/1/0``), int,
float, str, Path, ``Literal[...]`` (one of the listed values), ``tuple[X, ...]`` and
``tuple[X, Y]`` (comma-separated on the command line, arrays in TOML) and ``X | None``
(``none``). A field of another type (e.g. a tuple of case dataclasses) cannot be set this way;
unknown keys are refused by name with the list of known ones.
"""

from __future__ import annotations

import dataclasses
import tomllib
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from navtrack.errors import FileFormatError, NavtrackError

__all__ = [
    "ParameterError",
    "ParameterField",
    "apply_parameters",
    "parameter_fields",
    "parse_assignments",
    "read_parameter_file",
]

_TRUE = frozenset({"true", "yes", "on", "1"})
_FALSE = frozenset({"false", "no", "off", "0"})


class ParameterError(NavtrackError, ValueError):
    """A parameter value or key that the experiment's parameter dataclass does not accept."""


@dataclass(frozen=True, slots=True)
class ParameterField:
    """One field of an experiment's parameter dataclass, as ``navtrack reproduce --list`` shows it.

    Attributes
    ----------
    name : str
    type : object
        The resolved annotation.
    type_name : str
        The annotation written for people (``float``, ``tuple[float, ...]``, ``{'a', 'b'}``).
    default : object
    settable : bool
        The value can be given with ``--set`` or in a TOML file.
    """

    name: str
    type: Any
    type_name: str
    default: Any
    settable: bool


def _is_union(tp: Any) -> bool:
    return typing.get_origin(tp) in (typing.Union, types.UnionType)


def _type_name(tp: Any) -> str:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin is Literal:
        return "{" + ", ".join(repr(a) for a in args) + "}"
    if _is_union(tp):
        return " | ".join("None" if a is type(None) else _type_name(a) for a in args)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"tuple[{_type_name(args[0])}, ...]"
        return "tuple[" + ", ".join(_type_name(a) for a in args) + "]"
    return getattr(tp, "__name__", str(tp))


def _settable(tp: Any) -> bool:
    if tp in (bool, int, float, str, Path) or typing.get_origin(tp) is Literal:
        return True
    args = typing.get_args(tp)
    if _is_union(tp):
        return all(a is type(None) or _settable(a) for a in args)
    if typing.get_origin(tp) is tuple:
        return all(
            a is Ellipsis or (_settable(a) and typing.get_origin(a) is not tuple) for a in args
        )
    return False


def parameter_fields(params_type: type[Any]) -> list[ParameterField]:
    """The fields of a frozen parameter dataclass with their resolved types and defaults."""
    if not dataclasses.is_dataclass(params_type):
        raise TypeError(f"params_type: expected a dataclass, got {params_type!r}")
    hints = typing.get_type_hints(params_type)
    defaults = params_type()
    return [
        ParameterField(
            f.name,
            hints[f.name],
            _type_name(hints[f.name]),
            getattr(defaults, f.name),
            _settable(hints[f.name]),
        )
        for f in dataclasses.fields(params_type)
    ]


def _convert(value: Any, tp: Any, where: str) -> Any:
    """``value`` (a command-line string or a TOML value) as type ``tp``; ParameterError if not."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    text = isinstance(value, str)
    if _is_union(tp):
        none = value is None or (text and value.strip().lower() == "none")
        if none and type(None) in args:
            return None
        errors = []
        for arm in args:
            if arm is type(None):
                continue
            try:
                return _convert(value, arm, where)
            except ParameterError as exc:
                errors.append(str(exc))
        raise ParameterError("; ".join(errors))
    if origin is Literal:
        for choice in args:
            if value == choice or (text and not isinstance(choice, str) and value == str(choice)):
                return choice
        raise ParameterError(f"{where}: {value!r} is not one of {_type_name(tp)}")
    if origin is tuple:
        if text:
            items: Sequence[Any] = [v.strip() for v in value.split(",")] if value.strip() else []
        elif isinstance(value, list | tuple):
            items = value
        else:
            raise ParameterError(f"{where}: expected {_type_name(tp)}, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], where) for v in items)
        if len(items) != len(args):
            raise ParameterError(
                f"{where}: expected {len(args)} values ({_type_name(tp)}), got {len(items)}"
            )
        return tuple(_convert(v, a, where) for v, a in zip(items, args, strict=True))
    if tp is bool:
        if isinstance(value, bool):
            return value
        if text and value.strip().lower() in _TRUE | _FALSE:
            return value.strip().lower() in _TRUE
    elif tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        if text:
            try:
                return int(value)
            except ValueError:
                pass
    elif tp is float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
        if text:
            try:
                return float(value)
            except ValueError:
                pass
    elif tp is str:
        if text:
            return value
    elif tp is Path:
        if text:
            return Path(value)
    else:
        raise ParameterError(f"{where}: a {_type_name(tp)} cannot be set from text or TOML")
    raise ParameterError(f"{where}: expected {_type_name(tp)}, got {value!r}")


def parse_assignments(assignments: Sequence[str]) -> dict[str, str]:
    """``["key=value", ...]`` as a dictionary (later keys win); ParameterError without ``=``."""
    out: dict[str, str] = {}
    for item in assignments:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ParameterError(f"--set expects key=value, got {item!r}")
        out[key.strip()] = value
    return out


def read_parameter_file(path: Path) -> dict[str, Any]:
    """The top-level keys of a TOML parameter file."""
    try:
        with Path(path).open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise FileFormatError(path, None, f"not a TOML file: {exc}") from None


def apply_parameters(
    params: Any, values: Mapping[str, Any], *, experiment: str = "experiment", source: str = ""
) -> Any:
    """A copy of the frozen dataclass ``params`` with ``values`` converted to the field types.

    Parameters
    ----------
    params : dataclass instance
        The starting parameters (usually the defaults).
    values : mapping of str to object
        Command-line strings or TOML values by field name.
    experiment : str
        Name used in the messages.
    source : str
        Where the values come from (``--set``, a file name), for the messages.

    Returns
    -------
    dataclass instance
        ``dataclasses.replace(params, ...)``; its ``__post_init__`` checks ranges.

    Raises
    ------
    ParameterError
        Unknown key (named, with the known ones), a field that cannot be set from text, or a
        value that does not convert.
    """
    fields = {f.name: f for f in parameter_fields(type(params))}
    changes: dict[str, Any] = {}
    prefix = f"{source}: " if source else ""
    for key, value in values.items():
        if key not in fields:
            raise ParameterError(
                f"{prefix}unknown parameter {key!r} of experiment {experiment!r}; known: "
                + ", ".join(fields)
            )
        f = fields[key]
        if not f.settable:
            raise ParameterError(
                f"{prefix}parameter {key!r} ({f.type_name}) cannot be set from the command line "
                "or a file"
            )
        changes[key] = _convert(value, f.type, f"{prefix}parameter {key!r}")
    try:
        return dataclasses.replace(params, **changes)
    except (ValueError, TypeError) as exc:
        raise ParameterError(f"{prefix}{exc}") from None
