"""Read-only arrays for the frozen value classes (results, configurations, models)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._record import Record

if TYPE_CHECKING:
    import numpy.typing as npt


def freeze_arrays(value: Any) -> None:
    """Make every NumPy array field of a dataclass or :class:`Record` instance read-only.

    Called from ``__post_init__`` of the frozen result classes, so that a result cannot be
    changed through its arrays after it was made. Fields holding something other than an
    array (numbers, tuples, ``None``) are left as they are.
    """
    for name in _field_names(type(value)):
        arr = getattr(value, name)
        if isinstance(arr, np.ndarray):
            arr.flags.writeable = False


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def _field_names(cls: Any) -> tuple[str, ...]:
    # dataclasses.fields costs microseconds per call; the trackers make several results per scan
    names = _FIELD_NAMES.get(cls)
    if names is None:
        if issubclass(cls, Record):
            names = cls.record_fields
        else:
            names = tuple(f.name for f in dataclasses.fields(cls))
        _FIELD_NAMES[cls] = names
    return names


def readonly_copy(a: npt.ArrayLike, dtype: npt.DTypeLike | None = None) -> np.ndarray:
    """A read-only copy of ``a`` (the caller's array stays writable)."""
    arr = np.array(a, dtype=dtype, copy=True)
    arr.flags.writeable = False
    return arr
