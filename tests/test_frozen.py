"""The read-only helper of the frozen value classes, and the record base class."""

import pickle
from dataclasses import dataclass

import numpy as np
import pytest

from navtrack._frozen import freeze_arrays, readonly_copy
from navtrack._record import FrozenRecordError, Record


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


class _Point(Record):
    """A record with a default and a post-init check."""

    x_m: float
    y_m: float = 0.0
    tags: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.x_m < 0:
            raise ValueError("x_m < 0")


class _Key(Record, eq=True):
    name: str
    n: int


class _Arrays(Record):
    a: np.ndarray
    label: str

    def __post_init__(self) -> None:
        freeze_arrays(self)


def test_record_takes_fields_by_position_and_keyword_with_defaults():
    p = _Point(1.0, tags=("a",))
    assert (p.x_m, p.y_m, p.tags) == (1.0, 0.0, ("a",))
    assert _Point.record_fields == ("x_m", "y_m", "tags")
    assert repr(p) == "_Point(x_m=1.0, y_m=0.0, tags=('a',))"


def test_record_refuses_wrong_arguments_as_a_dataclass_does():
    with pytest.raises(TypeError, match="missing required argument 'x_m'"):
        _Point()  # type: ignore[call-arg]
    with pytest.raises(TypeError, match="unexpected keyword argument 'z_m'"):
        _Point(1.0, z_m=2.0)  # type: ignore[call-arg]
    with pytest.raises(TypeError, match="multiple values for argument 'x_m'"):
        _Point(1.0, x_m=2.0)  # type: ignore[misc]
    with pytest.raises(TypeError, match="takes 3 arguments, 4 were given"):
        _Point(1.0, 2.0, (), 4)  # type: ignore[call-arg]
    with pytest.raises(ValueError, match="x_m < 0"):
        _Point(-1.0)


def test_record_is_frozen_and_replace_makes_a_checked_copy():
    p = _Point(1.0, 2.0)
    with pytest.raises(FrozenRecordError):
        p.x_m = 3.0  # type: ignore[misc]
    with pytest.raises(FrozenRecordError):
        del p.y_m
    q = p.replace(y_m=5.0)
    assert (q.x_m, q.y_m, p.y_m) == (1.0, 5.0, 2.0)
    with pytest.raises(ValueError, match="x_m < 0"):
        p.replace(x_m=-1.0)


def test_record_equality_by_identity_unless_declared():
    assert _Point(1.0) != _Point(1.0)
    assert _Key("a", 1) == _Key("a", 1)
    assert _Key("a", 1) != _Key("a", 2)
    assert len({_Key("a", 1), _Key("a", 1)}) == 1


def test_record_pickles_and_freezes_its_arrays():
    r = _Arrays(np.zeros(2), "z")
    with pytest.raises(ValueError, match="read-only"):
        r.a[0] = 1.0
    back = pickle.loads(pickle.dumps(r))
    assert back.label == "z"
    np.testing.assert_array_equal(back.a, r.a)
    k = pickle.loads(pickle.dumps(_Key("a", 1)))
    assert k == _Key("a", 1)
