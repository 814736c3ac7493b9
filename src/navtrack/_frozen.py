"""Read-only arrays for the frozen value classes (results, configurations, models)."""

import dataclasses
from typing import Any

import numpy as np
import numpy.typing as npt


def freeze_arrays(value: Any) -> None:
    """Make every NumPy array field of a dataclass instance read-only, in place.

    Called from ``__post_init__`` of the frozen result classes, so that a result cannot be
    changed through its arrays after it was made. Fields holding something other than an
    array (numbers, tuples, ``None``) are left as they are.
    """
    for name in _field_names(type(value)):
        arr = getattr(value, name)
        if isinstance(arr, np.ndarray):
            arr.flags.writeable = False


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def _field_names(cls: type) -> tuple[str, ...]:
    # dataclasses.fields costs microseconds per call; the trackers make several results per scan
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in dataclasses.fields(cls))
    return names


def readonly_copy(a: npt.ArrayLike, dtype: npt.DTypeLike | None = None) -> np.ndarray:
    """A read-only copy of ``a`` (the caller's array stays writable)."""
    arr = np.array(a, dtype=dtype, copy=True)
    arr.flags.writeable = False
    return arr
