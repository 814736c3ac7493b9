"""The reconstruction chain on one recording: four estimates of the attitude from gyro + fixes.

1. ``propagation`` — the gyro propagated from the first camera fix (paper eq. 4);
2. ``paper_correction`` — the start corrected by the mean correction quaternion of the errors
   at all fixes, then propagated again (paper eq. 5 and below);
3. ``calibrated`` — start, gyro bias/scale/misalignment and camera-IMU timing fitted to the fixes
   (:mod:`~navtrack.attitude.calibration`), then propagated;
4. ``filter`` / ``smoother`` — the error-state filter and RTS smoother about the calibrated
   propagation (:mod:`~navtrack.attitude.smoother`).

The first two use the configured step (the paper's third-order series by default); the
calibration, and the nominal of the filter, use the closed form.

Each estimate is attitudes at the IMU samples plus the rates and the timing offset it assumes,
so it can be evaluated (and written) on the camera clock: :meth:`Reconstruction.on_camera_clock`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray
from navtrack.attitude.calibration import (
    CalibrationConfig,
    GyroCalibration,
    calibrate_gyro,
    calibrated_propagation,
)
from navtrack.attitude.quaternion import (
    CorrectionReading,
    Method,
    attitude_errors,
    check_quaternions,
    correction_quaternion,
    delta_angles,
    interpolate_attitude,
    propagate,
)
from navtrack.attitude.smoother import SmootherConfig, SmootherResult, smooth_attitude

__all__ = ["ESTIMATES", "AttitudeEstimate", "Reconstruction", "ReconstructionConfig", "reconstruct"]

#: Names of the estimates, in the order of the chain.
ESTIMATES = ("propagation", "paper_correction", "calibrated", "filter", "smoother")


@dataclass(frozen=True, slots=True)
class ReconstructionConfig:
    """Options of :func:`reconstruct`.

    Attributes
    ----------
    method, order : propagation step (:func:`~navtrack.attitude.quaternion.delta_quaternions`);
        the paper's third-order series by default.
    correction : reading of the paper's correction quaternion
        (:func:`~navtrack.attitude.quaternion.correction_quaternion`).
    calibration : CalibrationConfig
    smoother : SmootherConfig
    """

    method: Method = "series"
    order: int = 3
    correction: CorrectionReading = "mean_rotvec"
    calibration: CalibrationConfig = field(default_factory=CalibrationConfig)
    smoother: SmootherConfig = field(default_factory=SmootherConfig)


@dataclass(frozen=True, slots=True, eq=False)
class AttitudeEstimate:
    """One attitude estimate (arrays read-only).

    Attributes
    ----------
    quat : (n, 4) attitudes at the IMU samples, body -> reference, scalar-last
    rates_rad_s : (n, 3) the body rates it was propagated with (for interpolation)
    time_offset_s : float
        IMU time = camera time + ``time_offset_s`` (0 where the timing is not estimated).
    """

    quat: FloatArray
    rates_rad_s: FloatArray
    time_offset_s: float

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class Reconstruction:
    """All estimates of one recording.

    Attributes
    ----------
    t_s : (n,) IMU sample times, s
    estimates : dict of str to AttitudeEstimate, keys :data:`ESTIMATES`
    correction_rotvec_rad : (3,) rotation vector of the correction quaternion, reference frame
    fix_errors_rad : (m,) scalar errors ``e_s`` of the plain propagation at the fixes (paper
        Figure 16 A)
    calibration : GyroCalibration
    smoother : SmootherResult
    """

    t_s: FloatArray
    estimates: dict[str, AttitudeEstimate]
    correction_rotvec_rad: FloatArray
    fix_errors_rad: FloatArray
    calibration: GyroCalibration
    smoother: SmootherResult

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def on_camera_clock(self, name: str, t_camera_s: ArrayLike) -> FloatArray:
        """Attitudes ``(k, 4)`` of estimate ``name`` at camera-clock times (IMU time
        ``t + time_offset_s``, interpolated by the gyro)."""
        est = self.estimates[name]
        tq = np.asarray(t_camera_s, dtype=np.float64) + est.time_offset_s
        return interpolate_attitude(self.t_s, est.quat, est.rates_rad_s, tq)


def reconstruct(
    t_s: ArrayLike,
    gyr_rad_s: ArrayLike,
    fix_t_s: ArrayLike,
    fix_quat: ArrayLike,
    fix_sigma_rad: ArrayLike,
    config: ReconstructionConfig | None = None,
    progress: Callable[[str], None] | None = None,
) -> Reconstruction:
    """Run the whole chain on one recording.

    Parameters
    ----------
    t_s : (n,) IMU sample times, s, strictly increasing
    gyr_rad_s : (n, 3) body rates, rad/s
    fix_t_s : (m,) camera time stamps of the usable fixes, s, increasing, m >= 2
    fix_quat : (m, 4) fix attitudes (body -> reference, scalar-last, unit)
    fix_sigma_rad : (m,) per-axis fix standard deviations, rad
    config : ReconstructionConfig or None
    progress : callable, optional
        Called with the name of each stage as it starts (``propagation``,
        ``paper_correction``, ``calibration``, ``smoother``), e.g. to advance a progress bar.

    Returns
    -------
    Reconstruction
    """
    cfg = ReconstructionConfig() if config is None else config
    step = progress or (lambda stage: None)
    t = np.asarray(t_s, dtype=np.float64)
    w = np.asarray(gyr_rad_s, dtype=np.float64)
    d = delta_angles(t, w)
    ft = np.asarray(fix_t_s, dtype=np.float64)
    fq = check_quaternions(fix_quat, "fix_quat")
    fs = np.asarray(fix_sigma_rad, dtype=np.float64)
    if ft.ndim != 1 or ft.size < 2 or fq.shape != (ft.size, 4) or fs.shape != ft.shape:
        raise ValueError(
            "fix_t_s (m,), fix_quat (m, 4), fix_sigma_rad (m,) with m >= 2 expected, got "
            f"{ft.shape}, {fq.shape}, {fs.shape}"
        )
    if np.any(np.diff(ft) <= 0):
        raise ValueError("fix_t_s: fix time stamps must increase strictly")
    start = int(np.clip(np.searchsorted(t, ft[0]), 0, t.size - 1))
    first = Rotation.from_quat(fq[0])
    step("propagation")
    plain = propagate(first, d, start=start, method=cfg.method, order=cfg.order)
    pred = interpolate_attitude(t, plain.quat, w, ft)
    e_s, e_v = attitude_errors(Rotation.from_quat(pred), Rotation.from_quat(fq))
    q_c = correction_quaternion(e_s, e_v, cfg.correction)
    step("paper_correction")
    corrected = propagate(q_c * first, d, start=start, method=cfg.method, order=cfg.order)
    step("calibration")
    cal = calibrate_gyro(t, w, ft, fq, fs, cfg.calibration)
    nominal, rates = calibrated_propagation(t, w, cal, float(ft[0]), fq[0])
    step("smoother")
    sm = smooth_attitude(t, nominal, rates, ft + cal.time_offset_s, fq, fs, cfg.smoother)
    estimates = {
        "propagation": AttitudeEstimate(plain.quat, w, 0.0),
        "paper_correction": AttitudeEstimate(corrected.quat, w, 0.0),
        "calibrated": AttitudeEstimate(nominal.quat, rates, cal.time_offset_s),
        "filter": AttitudeEstimate(sm.filter_quat, rates, cal.time_offset_s),
        "smoother": AttitudeEstimate(sm.smoother_quat, rates, cal.time_offset_s),
    }
    return Reconstruction(t, estimates, np.asarray(q_c.as_rotvec(), dtype=np.float64), e_s, cal, sm)
