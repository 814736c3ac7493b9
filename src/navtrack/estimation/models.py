"""The interfaces a filter needs from its models, and the angle wrap of angular residuals.

The Kalman kernels (:mod:`navtrack.estimation.kalman`) take any object with these methods: the
concrete motion and measurement models of target tracking live in
:mod:`navtrack.tracking.models` (constant velocity, coordinated turn, range-bearing, ...).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from navtrack._typing import ArrayLike, BoolArray, FloatArray

__all__ = ["MeasurementModel", "MotionModel", "wrap_angle"]


def wrap_angle(a: ArrayLike) -> FloatArray:
    """Wrap angles to ``[-pi, pi)`` (rad)."""
    return np.asarray((np.asarray(a, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi, dtype=float)


class MotionModel(Protocol):
    """What the filters need from a motion model."""

    @property
    def dim_x(self) -> int: ...

    def f(self, x: FloatArray, dt: float) -> FloatArray: ...

    def jacobian(self, x: FloatArray, dt: float) -> FloatArray: ...

    def Q(self, dt: float) -> FloatArray: ...


class MeasurementModel(Protocol):
    """What the filters need from a measurement model."""

    @property
    def dim_x(self) -> int: ...

    @property
    def dim_z(self) -> int: ...

    @property
    def R(self) -> FloatArray: ...

    @property
    def angle_mask(self) -> BoolArray: ...

    @property
    def linear(self) -> bool: ...

    def h(self, x: FloatArray) -> FloatArray: ...

    def jacobian(self, x: FloatArray) -> FloatArray: ...
