"""Simulated strapdown gyros on a truth attitude: bias, angle random walk, scale factor,
misalignment, an optional Gauss-Markov in-run bias (paper 6's LN-200 regime).

The measurement model of one triad, sample ``k``::

    ω_meas[k] = S ω_true[k] + b + d[k] + n[k],   n[k] ~ N(0, N² / Δt_k)

with ``S = I + diag(s) + offdiag(m)`` (scale-factor errors ``s``, misalignments ``m``), a
turn-on bias ``b`` constant over the recording, an optional first-order Gauss-Markov in-run bias
``d`` and white rate noise of angle random walk ``N`` (so the angle over one sample interval has
the variance ``N² Δt``). ``ω_true`` are the body rates of the truth **in inertial space**: the
rates of the truth attitude (:func:`body_rates`) plus, when the truth is given in an Earth-fixed
frame, the rotation of that frame (``frame_rate_rad_s``, e.g.
:func:`navtrack.attitude.frames.earth_rate_enu`).

:func:`body_rates` inverts the propagation's rectangular rule, so integrating the error-free
rates with :func:`integrate_rates` returns the truth at every sample (to rounding).

References
----------
.. [1] Northrop Grumman, *LN-200 FOG Family Advanced Airborne IMU* data sheet: gyro bias
   repeatability 1 to 10 °/h (1σ), angle random walk 0.04 to 0.1 °/√h, scale-factor stability
   100 ppm (1σ), data rate 400 Hz (the LN-200 paper 6 flew, sampled every 2.5 ms).
.. [2] IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test Procedure for
   Single-Axis Interferometric Fiber Optic Gyros* (angle random walk, bias instability).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray
from navtrack.attitude.quaternion import check_quaternions, delta_angles, propagate

__all__ = [
    "LN200",
    "GyroRecord",
    "GyroSpec",
    "body_rates",
    "integrate_rates",
    "sample_times",
    "simulate_gyro",
]

_DEG_H = np.pi / 180.0 / 3600.0  # 1 °/h in rad/s
_DEG_SQRT_H = np.pi / 180.0 / 60.0  # 1 °/√h in rad/√s


@dataclass(frozen=True, slots=True)
class GyroSpec:
    """Error budget of a gyro triad (1σ values, per axis).

    Attributes
    ----------
    name : str
    bias_rad_s : float
        Turn-on bias, drawn once per recording.
    arw_rad_sqrt_s : float
        Angle random walk ``N`` (white rate noise of density ``N``).
    scale_factor : float
        Scale-factor error, dimensionless (100 ppm = 1e-4).
    misalignment_rad : float
        Sense-axis misalignment, each off-diagonal element of ``S``.
    bias_instability_rad_s : float
        Standard deviation of the Gauss-Markov in-run bias (0: none).
    bias_tau_s : float
        Correlation time of the in-run bias.
    rate_hz : float
        Output rate the device runs at (:func:`sample_times`).
    """

    name: str
    bias_rad_s: float
    arw_rad_sqrt_s: float
    scale_factor: float
    misalignment_rad: float = 0.0
    bias_instability_rad_s: float = 0.0
    bias_tau_s: float = 3600.0
    rate_hz: float = 400.0

    def __post_init__(self) -> None:
        values = (
            self.bias_rad_s,
            self.arw_rad_sqrt_s,
            self.scale_factor,
            self.misalignment_rad,
            self.bias_instability_rad_s,
        )
        if any(not np.isfinite(v) or v < 0 for v in values):
            raise ValueError(f"GyroSpec {self.name!r}: error terms must be finite and >= 0")
        if not self.bias_tau_s > 0 or not self.rate_hz > 0:
            raise ValueError(f"GyroSpec {self.name!r}: bias_tau_s and rate_hz must be > 0")

    @property
    def bias_deg_h(self) -> float:
        """Turn-on bias in °/h."""
        return self.bias_rad_s / _DEG_H

    @property
    def arw_deg_sqrt_h(self) -> float:
        """Angle random walk in °/√h."""
        return self.arw_rad_sqrt_s / _DEG_SQRT_H


#: An LN-200-class fibre-optic gyro triad at its data sheet's best bias grade: 1 °/h turn-on
#: bias, 0.07 °/√h angle random walk (the middle of the data sheet's 0.04-0.1 °/√h), 100 ppm
#: scale factor, 400 Hz. The data sheet gives no misalignment or in-run bias instability; both
#: are 0 here (set them with ``dataclasses.replace``).
LN200 = GyroSpec(
    name="LN-200",
    bias_rad_s=1.0 * _DEG_H,
    arw_rad_sqrt_s=0.07 * _DEG_SQRT_H,
    scale_factor=100e-6,
    rate_hz=400.0,
)


@dataclass(frozen=True, slots=True, eq=False)
class GyroRecord:
    """A simulated gyro recording and the errors drawn for it (arrays read-only).

    Attributes
    ----------
    t_s : (n,) sample times, s
    gyr_rad_s : (n, 3) measured body rates, rad/s
    true_rad_s : (n, 3) error-free inertial body rates, rad/s
    bias_rad_s : (3,) turn-on bias drawn, rad/s
    sensor_matrix : (3, 3) ``S`` drawn (scale factor and misalignment)
    in_run_bias_rad_s : (n, 3) Gauss-Markov in-run bias drawn (zeros when switched off)
    spec : GyroSpec
    """

    t_s: FloatArray
    gyr_rad_s: FloatArray
    true_rad_s: FloatArray
    bias_rad_s: FloatArray
    sensor_matrix: FloatArray
    in_run_bias_rad_s: FloatArray
    spec: GyroSpec

    def __post_init__(self) -> None:
        freeze_arrays(self)


def sample_times(duration_s: float, rate_hz: float, t0_s: float = 0.0) -> FloatArray:
    """Sample times ``t0 + k / rate_hz`` covering ``[t0, t0 + duration_s]``, shape ``(n,)``."""
    if not duration_s > 0 or not rate_hz > 0:
        raise ValueError(f"duration_s and rate_hz must be > 0, got {duration_s}, {rate_hz}")
    n = int(np.floor(duration_s * rate_hz + 1e-9)) + 1
    return t0_s + np.arange(n) / rate_hz


def body_rates(t_s: ArrayLike, truth_xyzw: ArrayLike) -> FloatArray:
    """Body rates ``(n, 3)`` of a truth attitude under the propagation's rectangular rule.

    ``ω_k = log(q_k⁻¹ ⊗ q_{k+1}) / (t_{k+1} - t_k)``; the last sample repeats the rate before
    it. Integrating these rates (:func:`integrate_rates`) from ``q_0`` returns the truth.

    Parameters
    ----------
    t_s : (n,) sample times, s, strictly increasing, n >= 2
    truth_xyzw : (n, 4) body -> reference attitudes, scalar-last, unit, no NaN
    """
    t = np.asarray(t_s, dtype=np.float64)
    q = check_quaternions(truth_xyzw, "truth_xyzw")
    if t.ndim != 1 or t.size < 2 or q.shape != (t.size, 4):
        raise ValueError(f"t_s (n,) and truth_xyzw (n, 4), n >= 2, expected: {t.shape}, {q.shape}")
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ValueError(f"t_s: times must increase strictly (sample {int(np.argmin(dt)) + 1})")
    r = Rotation.from_quat(q)
    step = np.asarray((r[:-1].inv() * r[1:]).as_rotvec(), dtype=np.float64) / dt[:, None]
    return np.concatenate([step, step[-1:]], axis=0)


def _in_run_bias(spec: GyroSpec, dt_s: float, n: int, rng: np.random.Generator) -> FloatArray:
    """First-order Gauss-Markov sequence ``(n, 3)``, stationary from the first sample."""
    if spec.bias_instability_rad_s == 0.0:
        return np.zeros((n, 3))
    phi = np.exp(-dt_s / spec.bias_tau_s)
    drive = rng.normal(0.0, spec.bias_instability_rad_s, (n, 3))
    drive[1:] *= np.sqrt(1.0 - phi * phi)
    return np.asarray(lfilter([1.0], [1.0, -phi], drive, axis=0), dtype=np.float64)


def simulate_gyro(
    t_s: ArrayLike,
    truth_xyzw: ArrayLike,
    spec: GyroSpec,
    rng: np.random.Generator,
    *,
    frame_rate_rad_s: ArrayLike | None = None,
) -> GyroRecord:
    """Gyro rates measured along a truth attitude.

    Parameters
    ----------
    t_s : (n,) sample times, s, strictly increasing (e.g. :func:`sample_times` at
        ``spec.rate_hz``)
    truth_xyzw : (n, 4) true body -> reference attitudes, scalar-last
    spec : GyroSpec
        Error budget (e.g. :data:`LN200`).
    rng : numpy.random.Generator
        Draws the bias, ``S``, the in-run bias and the noise, in that order.
    frame_rate_rad_s : (3,) or (n, 3), optional
        Rotation rate of the reference frame relative to inertial space, expressed in the
        reference frame (:func:`navtrack.attitude.frames.earth_rate_enu` for an ENU truth);
        ``None`` when the reference frame is inertial.

    Returns
    -------
    GyroRecord

    Notes
    -----
    The in-run bias uses the mean sample interval for its correlation step; the white noise
    uses each sample's own interval.
    """
    t = np.asarray(t_s, dtype=np.float64)
    w_true = body_rates(t, truth_xyzw)
    if frame_rate_rad_s is not None:
        frame = np.array(
            np.broadcast_to(np.asarray(frame_rate_rad_s, dtype=np.float64), (t.size, 3))
        )
        to_body = Rotation.from_quat(np.asarray(truth_xyzw, dtype=np.float64)).inv()
        w_true = w_true + np.asarray(to_body.apply(frame), dtype=np.float64)
    n = t.size
    bias = rng.normal(0.0, spec.bias_rad_s, 3)
    s = np.eye(3) + np.diag(rng.normal(0.0, spec.scale_factor, 3))
    off = ~np.eye(3, dtype=bool)
    s[off] += rng.normal(0.0, spec.misalignment_rad, 6)
    dt = np.diff(t)
    drift = _in_run_bias(spec, float(dt.mean()), n, rng)
    noise_sd = spec.arw_rad_sqrt_s / np.sqrt(np.append(dt, dt[-1]))
    noise = rng.normal(0.0, 1.0, (n, 3)) * noise_sd[:, None]
    meas = w_true @ s.T + bias + drift + noise
    return GyroRecord(t, meas, w_true, bias, s, drift, spec)


def integrate_rates(
    t_s: ArrayLike,
    gyr_rad_s: ArrayLike,
    q_start: Rotation | ArrayLike,
    *,
    start: int = 0,
) -> FloatArray:
    """Attitudes ``(n, 4)`` (scalar-last) from body rates by the closed-form step
    (:func:`~navtrack.attitude.quaternion.propagate` of
    :func:`~navtrack.attitude.quaternion.delta_angles`), from ``q_start`` at sample ``start``."""
    d = delta_angles(t_s, gyr_rad_s)
    return np.asarray(propagate(q_start, d, start=start, method="closed").quat)
