"""Immutable records: :class:`Record`, a frozen value class made without generated code."""

from __future__ import annotations

from typing import Any, ClassVar, Self, dataclass_transform


class FrozenRecordError(AttributeError):
    """Assignment to (or deletion of) a field of a :class:`Record`."""


@dataclass_transform(eq_default=False, frozen_default=True)
class Record:
    """Base of an immutable record whose fields are its class annotations, in order.

    A subclass reads like a frozen dataclass: annotated names are the fields, a class-level
    value is the field's default, ``__init__`` takes the fields by position or keyword and then
    calls ``__post_init__`` when the class defines it, fields cannot be assigned afterwards,
    and ``repr`` lists the fields. Instances compare by identity unless the class is declared
    ``class Name(Record, eq=True)``: then equal fields make equal records, hashed by fields.
    A record class is made without generating code, so defining one costs a few microseconds
    where a frozen dataclass costs about half a millisecond; the ``navtrack pos`` start-up
    defines a dozen. Assigning a field raises :class:`FrozenRecordError` (an
    ``AttributeError``, as a frozen dataclass's error is). Records are not dataclasses:
    :func:`dataclasses.replace` and :func:`dataclasses.fields` do not apply, the field names
    are :attr:`record_fields` and :meth:`replace` makes a changed copy.
    """

    record_fields: ClassVar[tuple[str, ...]] = ()
    _record_defaults: ClassVar[dict[str, Any]] = {}

    def __init_subclass__(cls, *, eq: bool = False, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        own = [
            name
            for name, annotation in vars(cls).get("__annotations__", {}).items()
            if not str(annotation).startswith(("ClassVar", "typing.ClassVar"))
        ]
        cls.record_fields = (*cls.record_fields, *(n for n in own if n not in cls.record_fields))
        defaults = {n: cls.__dict__[n] for n in own if n in cls.__dict__}
        cls._record_defaults = {**cls._record_defaults, **defaults}
        if eq:
            cls.__eq__ = Record._equal_fields  # type: ignore[method-assign,assignment]
            cls.__hash__ = Record._hash_fields  # type: ignore[method-assign,assignment]

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        names = self.record_fields
        cls = type(self).__name__
        if len(args) > len(names):
            raise TypeError(f"{cls}() takes {len(names)} arguments, {len(args)} were given")
        values = dict(zip(names, args, strict=False))
        for name, value in kwargs.items():
            if name not in names:
                raise TypeError(f"{cls}() got an unexpected keyword argument {name!r}")
            if name in values:
                raise TypeError(f"{cls}() got multiple values for argument {name!r}")
            values[name] = value
        if len(values) < len(names):
            for name in names:
                if name not in values:
                    if name not in self._record_defaults:
                        raise TypeError(f"{cls}() missing required argument {name!r}")
                    values[name] = self._record_defaults[name]
        vars(self).update(values)
        post_init = getattr(self, "__post_init__", None)
        if post_init is not None:
            post_init()

    def __setattr__(self, name: str, value: Any) -> None:
        raise FrozenRecordError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenRecordError(f"cannot delete field {name!r}")

    def replace(self, **changes: Any) -> Self:
        """A new record of the same class with the fields ``changes`` names replaced (as
        :func:`dataclasses.replace` does for a dataclass)."""
        return type(self)(**{**{n: getattr(self, n) for n in self.record_fields}, **changes})

    def _values(self) -> tuple[Any, ...]:
        return tuple(getattr(self, n) for n in self.record_fields)

    def _equal_fields(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._values() == other._values()

    def _hash_fields(self) -> int:
        return hash(self._values())

    def __repr__(self) -> str:
        fields = ", ".join(f"{n}={getattr(self, n)!r}" for n in self.record_fields)
        return f"{type(self).__qualname__}({fields})"
