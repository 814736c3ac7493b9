"""Motion and measurement models for target tracking.

State vectors are stacked per spatial axis: a 2-D constant-velocity state is ``[x, vx, y, vy]``
(the ordering of Bar-Shalom and of the paper-3 scenario), a 3-D constant-acceleration state is
``[x, vx, ax, y, vy, ay, z, vz, az]``. Units are SI (m, m/s, m/s², s, rad).

Every model exposes the small interface that the Kalman kernels of
:mod:`navtrack.estimation.kalman` and the particle filters built on them need, the protocols
:class:`~navtrack.estimation.models.MotionModel` and
:class:`~navtrack.estimation.models.MeasurementModel`:

* motion models: ``dim_x``, ``F(dt)``, ``Q(dt)``, ``f(x, dt)`` and ``jacobian(x, dt)``;
* measurement models: ``dim_x``, ``dim_z``, ``R``, ``angle_mask``, ``linear``, ``h(x)`` and
  ``jacobian(x)``, with ``x`` batched over any leading axes.

References
----------
.. [1] Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
   Navigation*, Wiley 2001, sections 6.2-6.3 (continuous and discrete white-noise acceleration
   models) and 11.7 (coordinated turn).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays, readonly_copy
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.models import MeasurementModel, wrap_angle

__all__ = [
    "CoordinatedTurn",
    "FovealScan",
    "FovealSensor",
    "FunctionMeasurement",
    "LinearMeasurement",
    "LinearMotion",
    "RangeBearing",
    "constant_acceleration",
    "constant_velocity",
    "linear_position",
    "measure",
    "range_bearing_group",
]


# --------------------------------------------------------------------------------------------
# Motion
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class LinearMotion:
    """Constant-velocity (``order=1``) or constant-acceleration (``order=2``) motion.

    Parameters
    ----------
    ndim : int
        Number of spatial axes, 1 to 3.
    order : int
        1 = nearly constant velocity, 2 = nearly constant acceleration (Wiener-process
        acceleration).
    q : float
        Process-noise level. ``noise="discrete"``: variance of the piecewise-constant
        acceleration (CV, m²/s⁴) or acceleration increment (CA) per step, Bar-Shalom eq. 6.3.2-4
        and 6.3.3-4. ``noise="continuous"``: power spectral density of the white noise
        (CV: m²/s³, CA: m²/s⁵), eq. 6.2.2-12 and 6.2.3-8; this form is consistent when a step is
        split in parts (``Q(a+b) = F(b) Q(a) F(b)ᵀ + Q(b)``), so it suits irregular real data.
    noise : {"discrete", "continuous"}
    """

    ndim: int
    order: int
    q: float
    noise: Literal["discrete", "continuous"] = "discrete"

    def __post_init__(self) -> None:
        if self.ndim not in (1, 2, 3):
            raise ValueError(f"ndim must be 1, 2 or 3, got {self.ndim}")
        if self.order not in (1, 2):
            raise ValueError(f"order must be 1 (CV) or 2 (CA), got {self.order}")
        if not (np.isfinite(self.q) and self.q >= 0):
            raise ValueError(f"q must be finite and >= 0, got {self.q}")
        if self.noise not in ("discrete", "continuous"):
            raise ValueError(f"noise must be 'discrete' or 'continuous', got {self.noise!r}")

    @property
    def dim_x(self) -> int:
        return self.ndim * (self.order + 1)

    @property
    def position_index(self) -> tuple[int, ...]:
        """Indices of the position components in the state."""
        return tuple(range(0, self.dim_x, self.order + 1))

    @property
    def velocity_index(self) -> tuple[int, ...]:
        """Indices of the velocity components in the state."""
        return tuple(range(1, self.dim_x, self.order + 1))

    def _block_F(self, dt: float) -> FloatArray:
        if self.order == 1:
            return np.array([[1.0, dt], [0.0, 1.0]])
        return np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])

    def _block_Q(self, dt: float) -> FloatArray:
        if self.noise == "discrete":
            g = np.array([0.5 * dt * dt, dt] if self.order == 1 else [0.5 * dt * dt, dt, 1.0])
            return self.q * np.outer(g, g)
        if self.order == 1:
            return self.q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        return self.q * np.array(
            [
                [dt**5 / 20, dt**4 / 8, dt**3 / 6],
                [dt**4 / 8, dt**3 / 3, dt**2 / 2],
                [dt**3 / 6, dt**2 / 2, dt],
            ]
        )

    def _block_diag(self, blk: FloatArray) -> FloatArray:
        k = self.order + 1
        out = np.zeros((self.dim_x, self.dim_x))
        for a in range(self.ndim):
            out[a * k : (a + 1) * k, a * k : (a + 1) * k] = blk
        return out

    def F(self, dt: float) -> FloatArray:
        """State transition matrix, shape ``(dim_x, dim_x)``."""
        return self._block_diag(self._block_F(float(dt)))

    def Q(self, dt: float) -> FloatArray:
        """Process-noise covariance over ``dt`` seconds, shape ``(dim_x, dim_x)``."""
        return self._block_diag(self._block_Q(float(dt)))

    def f(self, x: FloatArray, dt: float) -> FloatArray:
        """Propagate states ``x (..., dim_x)`` by ``dt`` seconds."""
        x = np.asarray(x, dtype=float)
        # one (rows, dim_x) product: a stack of small matrices would be multiplied one by one
        return np.asarray((x.reshape(-1, self.dim_x) @ self.F(dt).T).reshape(x.shape))

    def jacobian(self, x: FloatArray, dt: float) -> FloatArray:
        """``F`` broadcast to ``x.shape[:-1] + (dim_x, dim_x)``."""
        x = np.asarray(x)
        return np.broadcast_to(self.F(dt), (*x.shape[:-1], self.dim_x, self.dim_x))


def constant_velocity(
    ndim: int, q: float, noise: Literal["discrete", "continuous"] = "discrete"
) -> LinearMotion:
    """Nearly-constant-velocity model in ``ndim`` axes (see :class:`LinearMotion`)."""
    return LinearMotion(ndim, 1, q, noise)


def constant_acceleration(
    ndim: int, q: float, noise: Literal["discrete", "continuous"] = "discrete"
) -> LinearMotion:
    """Nearly-constant-acceleration model in ``ndim`` axes (see :class:`LinearMotion`)."""
    return LinearMotion(ndim, 2, q, noise)


@dataclass(frozen=True, slots=True)
class CoordinatedTurn:
    """2-D coordinated turn with unknown turn rate, state ``[x, vx, y, vy, omega]``.

    Parameters
    ----------
    q : float
        Continuous white-acceleration spectral density on each axis, m²/s³.
    q_omega : float
        Spectral density of the turn-rate random walk, rad²/s³.

    Notes
    -----
    Transition of Bar-Shalom et al. eq. 11.7.1-4 (turn rate positive counter-clockwise); the
    ``omega -> 0`` limit is taken by series expansion below ``|omega·dt| < 1e-3``.
    """

    q: float
    q_omega: float

    @property
    def dim_x(self) -> int:
        return 5

    @staticmethod
    def _terms(w: FloatArray, dt: float) -> tuple[FloatArray, ...]:
        wt = w * dt
        small = np.abs(wt) < 1e-3  # series to 5th order: error < (wT)^6 relative
        ws = np.where(small, 1.0, w)
        s, c = np.sin(wt), np.cos(wt)
        w2 = w * w
        a = np.where(small, dt - w2 * dt**3 / 6 + w2 * w2 * dt**5 / 120, s / ws)  # sin(wT)/w
        b = np.where(small, w * dt**2 / 2 - w2 * w * dt**4 / 24, (1 - c) / ws)  # (1-cos)/w
        # derivatives of a, b with respect to w
        da = np.where(small, -w * dt**3 / 3 + w2 * w * dt**5 / 30, (dt * c) / ws - s / ws**2)
        db = np.where(small, dt**2 / 2 - w2 * dt**4 / 8, (dt * s) / ws - (1 - c) / ws**2)
        return s, c, a, b, da, db

    def f(self, x: FloatArray, dt: float) -> FloatArray:
        x = np.asarray(x, dtype=float)
        px, vx, py, vy, w = np.moveaxis(x, -1, 0)
        s, c, a, b, _, _ = self._terms(w, dt)
        return np.stack(
            [px + a * vx - b * vy, c * vx - s * vy, py + b * vx + a * vy, s * vx + c * vy, w],
            axis=-1,
        )

    def jacobian(self, x: FloatArray, dt: float) -> FloatArray:
        x = np.asarray(x, dtype=float)
        _, vx, _, vy, w = np.moveaxis(x, -1, 0)
        s, c, a, b, da, db = self._terms(w, dt)
        J = np.zeros((*x.shape[:-1], 5, 5))
        J[..., 0, 0] = 1.0
        J[..., 0, 1] = a
        J[..., 0, 3] = -b
        J[..., 0, 4] = da * vx - db * vy
        J[..., 1, 1] = c
        J[..., 1, 3] = -s
        J[..., 1, 4] = -dt * s * vx - dt * c * vy
        J[..., 2, 1] = b
        J[..., 2, 2] = 1.0
        J[..., 2, 3] = a
        J[..., 2, 4] = db * vx + da * vy
        J[..., 3, 1] = s
        J[..., 3, 3] = c
        J[..., 3, 4] = dt * c * vx - dt * s * vy
        J[..., 4, 4] = 1.0
        return J

    def Q(self, dt: float) -> FloatArray:
        blk = self.q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
        Q = np.zeros((5, 5))
        Q[0:2, 0:2] = blk
        Q[2:4, 2:4] = blk
        Q[4, 4] = self.q_omega * dt
        return Q


# --------------------------------------------------------------------------------------------
# Measurements
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)
class LinearMeasurement:
    """Linear measurement ``z = H x + v``, ``v ~ N(0, R)``.

    Parameters
    ----------
    H : array, shape (dim_z, dim_x)
    R : array, shape (dim_z, dim_z)
        Noise covariance, symmetric positive definite.
    """

    H: FloatArray
    R: FloatArray
    angle_mask: BoolArray = field(default=None)  # type: ignore[arg-type]

    def __post_init__(self) -> None:
        H = readonly_copy(self.H, float)
        R = readonly_copy(self.R, float)
        if H.ndim != 2 or R.shape != (H.shape[0], H.shape[0]):
            raise ValueError(f"H must be (m, n) and R (m, m); got H {H.shape}, R {R.shape}")
        _check_spd("R", R)
        mask = np.zeros(H.shape[0], bool) if self.angle_mask is None else self.angle_mask
        mask = readonly_copy(mask, bool)
        object.__setattr__(self, "H", H)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "angle_mask", mask)

    @property
    def dim_x(self) -> int:
        return int(self.H.shape[1])

    @property
    def dim_z(self) -> int:
        return int(self.H.shape[0])

    @property
    def linear(self) -> bool:
        return True

    def h(self, x: FloatArray) -> FloatArray:
        return np.asarray(x, dtype=float) @ self.H.T

    def jacobian(self, x: FloatArray) -> FloatArray:
        x = np.asarray(x)
        return np.broadcast_to(self.H, x.shape[:-1] + self.H.shape)


def linear_position(
    dim_x: int, position_index: tuple[int, ...], sigma_m: float | ArrayLike
) -> LinearMeasurement:
    """Position measurement picking ``position_index`` out of the state.

    ``sigma_m`` is the standard deviation per axis (scalar or one per axis), m.
    """
    m = len(position_index)
    H = np.zeros((m, dim_x))
    H[np.arange(m), list(position_index)] = 1.0
    sig = np.broadcast_to(np.asarray(sigma_m, dtype=float), (m,))
    return LinearMeasurement(H, np.diag(sig**2))


@dataclass(frozen=True, slots=True, eq=False)
class RangeBearing:
    """2-D range and bearing ``z = [r, theta]`` from a sensor at ``sensor_xy``.

    Parameters
    ----------
    R : array (2, 2)
        Noise covariance of ``[range (m), bearing (rad)]``.
    sensor_xy : array (2,)
        Sensor position, m, in the same frame as the target positions.
    position_index : (int, int)
        Indices of x and y in the state (``(0, 2)`` for ``[x, vx, y, vy]``).
    dim_x : int
    from_north : bool
        False: bearing = ``atan2(dy, dx)`` measured counter-clockwise from +x (the convention of
        paper 3 and Stone Soup); True: azimuth ``atan2(dx, dy)`` clockwise from north (+y).
    """

    R: FloatArray
    sensor_xy: FloatArray = field(default_factory=lambda: np.zeros(2))
    position_index: tuple[int, int] = (0, 2)
    dim_x: int = 4
    from_north: bool = False

    def __post_init__(self) -> None:
        R = readonly_copy(self.R, float)
        if R.shape != (2, 2):
            raise ValueError(f"R must be (2, 2), got {R.shape}")
        _check_spd("R", R)
        s = readonly_copy(self.sensor_xy, float)
        if s.shape != (2,) or not np.all(np.isfinite(s)):
            raise ValueError(f"sensor_xy must be 2 finite numbers, got {s}")
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "sensor_xy", s)

    @property
    def dim_z(self) -> int:
        return 2

    @property
    def angle_mask(self) -> BoolArray:
        return np.array([False, True])

    @property
    def linear(self) -> bool:
        return False

    def h(self, x: FloatArray) -> FloatArray:
        dx, dy = _offsets(np.asarray(x, dtype=float), self.sensor_xy, self.position_index)
        return _range_bearing(dx, dy, np.sqrt(dx * dx + dy * dy), self.from_north)

    def jacobian(self, x: FloatArray) -> FloatArray:
        dx, dy = _offsets(np.asarray(x, dtype=float), self.sensor_xy, self.position_index)
        return _range_bearing_jacobian(dx, dy, self.position_index, self.dim_x, self.from_north)


def _offsets(
    x: FloatArray, sensor_xy: FloatArray, position_index: tuple[int, int]
) -> tuple[FloatArray, FloatArray]:
    """East and north offsets of the targets ``x (..., n)`` from one sensor ``(2,)``, shape
    ``(...)``, or from several sensors ``(S, 2)``, shape ``(..., S)``."""
    i, j = position_index
    if sensor_xy.ndim == 1:
        return x[..., i] - sensor_xy[0], x[..., j] - sensor_xy[1]
    return x[..., i, None] - sensor_xy[:, 0], x[..., j, None] - sensor_xy[:, 1]


def _range_bearing(dx: FloatArray, dy: FloatArray, r: FloatArray, from_north: bool) -> FloatArray:
    """``[range, bearing]`` (..., 2) of east / north offsets with range ``r`` (see
    :class:`RangeBearing`)."""
    a, b = (dy, dx) if from_north else (dx, dy)  # bearing = atan2(b, a)
    return np.stack([r, np.arctan2(b, a)], axis=-1)


def _range_bearing_jacobian(
    dx: FloatArray,
    dy: FloatArray,
    position_index: tuple[int, int],
    dim_x: int,
    from_north: bool,
    r2: FloatArray | None = None,
) -> FloatArray:
    """Jacobian (..., 2, dim_x) of :func:`_range_bearing` with respect to the state
    (``r2``: the squared range when the caller has it)."""
    if r2 is None:
        r2 = dx * dx + dy * dy
    r = np.sqrt(r2)
    i, j = position_index
    J = np.zeros((*dx.shape, 2, dim_x))
    J[..., 0, i] = dx / r
    J[..., 0, j] = dy / r
    if from_north:  # theta = atan2(dx, dy)
        J[..., 1, i] = dy / r2
        J[..., 1, j] = -dx / r2
    else:  # theta = atan2(dy, dx)
        J[..., 1, i] = -dy / r2
        J[..., 1, j] = dx / r2
    return J


def range_bearing_group(
    models: Sequence[MeasurementModel],
) -> tuple[RangeBearing, FloatArray] | None:
    """``(first model, sensor positions (S, 2))`` when all ``models`` are range-bearing with one
    ``position_index``, ``dim_x`` and ``from_north`` (evaluated together by :func:`measure`),
    else None. Cached per tuple of models, unless a model cannot be hashed."""
    try:
        return _range_bearing_group(tuple(models))
    except TypeError:
        return _range_bearing_group.__wrapped__(tuple(models))


@lru_cache(maxsize=32)
def _range_bearing_group(
    models: tuple[MeasurementModel, ...],
) -> tuple[RangeBearing, FloatArray] | None:
    """``(first model, sensor positions (S, 2))`` when all ``models`` are range-bearing with one
    ``position_index``, ``dim_x`` and ``from_north`` (one vectorised evaluation), else None."""
    rb = [m for m in models if isinstance(m, RangeBearing)]
    if len(rb) != len(models) or len({(m.position_index, m.dim_x, m.from_north) for m in rb}) > 1:
        return None
    xy = np.array([m.sensor_xy for m in rb])
    xy.setflags(write=False)
    return rb[0], xy


def measure(models: Sequence[MeasurementModel], x: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Predicted measurements and Jacobians of ``S`` sensors at the same states.

    Range-bearing sensors that share ``position_index``, ``dim_x`` and ``from_north`` are
    evaluated together, vectorised over the sensor axis (the same kernels as
    :meth:`RangeBearing.h` / :meth:`RangeBearing.jacobian`); other models one at a time.

    Parameters
    ----------
    models : S measurement models with one ``dim_z`` (``m``)
    x : (..., n) states

    Returns
    -------
    z : (..., S, m) ``h_s(x)``
    H : (..., S, m, n) ``∂h_s / ∂x`` at ``x``
    """
    x = np.asarray(x, dtype=float)
    group = range_bearing_group(models)
    if group is not None:
        m0, xy = group
        dx, dy = _offsets(x, xy, m0.position_index)
        r2 = dx * dx + dy * dy
        return (
            _range_bearing(dx, dy, np.sqrt(r2), m0.from_north),
            _range_bearing_jacobian(dx, dy, m0.position_index, m0.dim_x, m0.from_north, r2),
        )
    if len({m.dim_z for m in models}) != 1:
        raise ValueError("measure: the models need one dim_z")
    return (
        np.stack([m.h(x) for m in models], axis=-2),
        np.stack([m.jacobian(x) for m in models], axis=-3),
    )


@dataclass(frozen=True, slots=True, eq=False)
class FunctionMeasurement:
    """Hook for any nonlinear measurement ``z = h(x) + v`` (e.g. the foveal sensor of paper 4).

    Parameters
    ----------
    func : callable ``(..., dim_x) -> (..., dim_z)``
        Batched measurement function.
    R : array (dim_z, dim_z)
    dim_x : int
    jac : callable ``(..., dim_x) -> (..., dim_z, dim_x)`` or None
        Analytic Jacobian; None uses central differences (step ``1e-6·max(1, |x|)``).
    angle_mask : bool array (dim_z,) or None
        Components that are angles (innovations wrapped to ``[-pi, pi)``).
    """

    func: Callable[[FloatArray], FloatArray]
    R: FloatArray
    dim_x: int
    jac: Callable[[FloatArray], FloatArray] | None = None
    angle_mask: BoolArray = field(default=None)  # type: ignore[arg-type]

    def __post_init__(self) -> None:
        R = readonly_copy(np.atleast_2d(self.R), float)
        _check_spd("R", R)
        mask = np.zeros(R.shape[0], bool) if self.angle_mask is None else self.angle_mask
        mask = readonly_copy(mask, bool)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "angle_mask", mask)

    @property
    def dim_z(self) -> int:
        return int(self.R.shape[0])

    @property
    def linear(self) -> bool:
        return False

    def h(self, x: FloatArray) -> FloatArray:
        return np.asarray(self.func(np.asarray(x, dtype=float)), dtype=float)

    def jacobian(self, x: FloatArray) -> FloatArray:
        x = np.asarray(x, dtype=float)
        if self.jac is not None:
            return np.asarray(self.jac(x), dtype=float)
        cols = []
        for k in range(self.dim_x):
            e = np.zeros(self.dim_x)
            step = 1e-6 * np.maximum(1.0, np.abs(x[..., k]))
            e[k] = 1.0
            dz = self.h(x + step[..., None] * e) - self.h(x - step[..., None] * e)
            dz = np.where(self.angle_mask, wrap_angle(dz), dz)
            cols.append(dz / (2 * step[..., None]))
        return np.stack(cols, axis=-1)


# --------------------------------------------------------------------------------------------
# Foveal sensor (paper 4)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)
class FovealScan:
    """One scan of the foveal sensor, batched over leading axes ``B`` (runs or filters).

    Attributes
    ----------
    z : (B..., M) float
        Measurements, rad; entries where ``valid`` is False are padding (0).
    valid : (B..., M) bool
        Which entries of ``z`` are measurements.
    origin : (B..., M) int
        Target index that produced each measurement, ``-1`` for clutter and padding (truth, for
        tests and diagnostics; the filters never read it).
    """

    z: FloatArray
    valid: BoolArray
    origin: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True)
class FovealSensor:
    """Foveal sensor ``z = arctan(c_k (X - d_k)) + v``, ``v ~ N(0, R)`` (Xi & Morrell, sec. II).

    Each target is detected with probability ``pd``; the number of false alarms is Poisson with
    mean ``clutter_rate`` (= λV) and they are uniform over the measurement space
    ``(-pi/2, pi/2)``, so the volume is ``V = pi`` rad and the spatial density
    ``λ = clutter_rate / pi`` per rad.

    Parameters
    ----------
    R : float
        Measurement-noise variance, rad² (paper: 0.05). Must be > 0.
    pd : float
        Detection probability in ``(0, 1]`` (paper: 1 without clutter, 0.9 with).
    clutter_rate : float
        Expected false alarms per scan λV >= 0 (paper: 0 or 0.5).
    position_index : int
        Index of the position ``X`` in a target's state (``[X, Xdot]``: 0).
    dim_x : int
        Size of one target's state.

    Notes
    -----
    The paper clutters "the surveillance region volume V"; the measurement space of the arctan
    is the open interval ``(-pi/2, pi/2)``, which is the region read here (a measurement with
    noise may fall slightly outside it; the clutter density is not applied there differently).
    """

    R: float
    pd: float = 1.0
    clutter_rate: float = 0.0
    position_index: int = 0
    dim_x: int = 2

    def __post_init__(self) -> None:
        if not (np.isfinite(self.R) and self.R > 0):
            raise ValueError(
                f"R (foveal measurement-noise variance, rad²) must be > 0, got {self.R}"
            )
        if not (np.isfinite(self.pd) and 0.0 < self.pd <= 1.0):
            raise ValueError(f"pd (detection probability) must be in (0, 1], got {self.pd}")
        if not (np.isfinite(self.clutter_rate) and self.clutter_rate >= 0):
            raise ValueError(
                f"clutter_rate (expected false alarms per scan, λV) must be >= 0, got "
                f"{self.clutter_rate}"
            )
        if not 0 <= self.position_index < self.dim_x:
            raise ValueError(
                f"position_index must be in [0, dim_x={self.dim_x}), got {self.position_index}"
            )

    @property
    def volume(self) -> float:
        """Measurement-space volume ``V = pi`` rad (the interval ``(-pi/2, pi/2)``)."""
        return float(np.pi)

    @property
    def clutter_density(self) -> float:
        """Spatial false-alarm density ``λ = clutter_rate / V``, per rad."""
        return self.clutter_rate / self.volume

    def h(self, x: ArrayLike, c: ArrayLike, d: ArrayLike) -> FloatArray:
        """Noise-free measurement ``arctan(c (X - d))`` of states ``x (..., dim_x)``, rad.

        ``c`` (gain, 1/m) and ``d`` (foveal centre, m) broadcast against ``x.shape[:-1]``.
        """
        X = np.asarray(x, dtype=float)[..., self.position_index]
        return np.asarray(np.arctan(np.asarray(c, dtype=float) * (X - np.asarray(d, dtype=float))))

    def log_likelihood(self, z: ArrayLike, x: ArrayLike, c: ArrayLike, d: ArrayLike) -> FloatArray:
        """``log N(z; arctan(c (X - d)), R)``; ``z`` broadcasts against ``x.shape[:-1]``."""
        r = np.asarray(z, dtype=float) - self.h(x, c, d)
        return np.asarray(-0.5 * (r * r / self.R + np.log(2.0 * np.pi * self.R)))

    def measurement(self, c: float, d: float) -> FunctionMeasurement:
        """This sensor at gain ``c`` and centre ``d`` as a :class:`FunctionMeasurement` (EKF/UKF).

        The Jacobian is ``dz/dX = c / (1 + c² (X - d)²)`` on the position component.
        """
        i = self.position_index

        def jac(x: FloatArray) -> FloatArray:
            J = np.zeros((*x.shape[:-1], 1, self.dim_x))
            J[..., 0, i] = c / (1.0 + (c * (x[..., i] - d)) ** 2)
            return J

        return FunctionMeasurement(
            lambda x: self.h(x, c, d)[..., None], np.array([[self.R]]), self.dim_x, jac
        )

    def scan(
        self, positions: ArrayLike, c: ArrayLike, d: ArrayLike, rng: np.random.Generator
    ) -> FovealScan:
        """Simulate one scan: detections of the targets plus Poisson clutter.

        Parameters
        ----------
        positions : (B..., T) float
            True target positions X, m.
        c, d : (B...) float
            Gain (1/m) and foveal centre (m) of each batch element.
        rng : numpy.random.Generator

        Returns
        -------
        FovealScan
            Measurements in random order (detections, then clutter, shuffled per batch element)
            padded to the largest count in the batch.
        """
        X = np.asarray(positions, dtype=float)
        batch, T = X.shape[:-1], X.shape[-1]
        c = np.broadcast_to(np.asarray(c, dtype=float), batch)[..., None]
        d = np.broadcast_to(np.asarray(d, dtype=float), batch)[..., None]
        z_t = np.arctan(c * (X - d)) + rng.normal(0.0, np.sqrt(self.R), X.shape)
        detected = rng.random(X.shape) < self.pd
        n_clutter = rng.poisson(self.clutter_rate, batch)
        m_c = int(n_clutter.max(initial=0))
        z_c = rng.uniform(-0.5 * np.pi, 0.5 * np.pi, (*batch, m_c))
        z = np.concatenate([z_t, z_c], axis=-1)
        valid = np.concatenate([detected, np.arange(m_c) < n_clutter[..., None]], axis=-1)
        origin = np.concatenate(
            [np.broadcast_to(np.arange(T), X.shape), np.full((*batch, m_c), -1)], axis=-1
        )
        # valid entries first in a random order, padding last
        key = np.where(valid, rng.random(valid.shape), 2.0)
        order = np.argsort(key, axis=-1)
        valid = np.take_along_axis(valid, order, axis=-1)
        m = int(valid.sum(axis=-1).max(initial=0))
        z = np.where(valid, np.take_along_axis(z, order, axis=-1), 0.0)[..., :m]
        origin = np.where(valid, np.take_along_axis(origin, order, axis=-1), -1)[..., :m]
        return FovealScan(z, valid[..., :m], origin.astype(np.int64))


def _check_spd(name: str, M: FloatArray) -> None:
    if not np.all(np.isfinite(M)):
        raise ValueError(f"{name} must be finite")
    if not np.allclose(M, M.T, rtol=1e-10, atol=0):
        raise ValueError(f"{name} must be symmetric")
    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        raise ValueError(f"{name} must be positive definite") from None
