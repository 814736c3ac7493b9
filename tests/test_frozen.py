"""The read-only helper of the frozen value classes."""

from dataclasses import dataclass

import numpy as np
import pytest

from navtrack._frozen import freeze_arrays, readonly_copy


@dataclass(frozen=True, slots=True, eq=False)
class _Result:
    x: np.ndarray
    n: int
    maybe: np.ndarray | None = None

    def __post_init__(self) -> None:
        freeze_arrays(self)


def test_freeze_arrays_makes_every_array_field_read_only():
    r = _Result(np.zeros(3), 2, np.ones((2, 2)))
    with pytest.raises(ValueError, match="read-only"):
        r.x[0] = 1.0
    assert r.maybe is not None
    with pytest.raises(ValueError, match="read-only"):
        r.maybe[0, 0] = 2.0
    assert r.n == 2


def test_freeze_arrays_leaves_none_fields():
    assert _Result(np.zeros(1), 0).maybe is None


def test_readonly_copy_keeps_the_callers_array_writable():
    a = np.arange(3)
    b = readonly_copy(a, float)
    a[0] = 7
    assert b.dtype == np.float64
    assert b[0] == 0.0
    assert not b.flags.writeable
