"""Least-squares calibration of the gyro and the camera-IMU timing against camera fixes.

The step the paper names but did not take ("by formulating the effects that gyroscope
misalignments, biases and timing offsets has on the propagated trajectory the parameter values
that minimize error between the camera estimates and the propagated trajectories can be found"):
the whole trial is propagated from the first fix with corrected rates, and the reference-frame
errors at every fix are minimised over

* the start attitude (a small rotation ``exp(δ₀) ⊗ q_fix,1``),
* the gyro bias ``b`` (rad/s), scale factors ``s`` and axis misalignments ``m`` (6 non-orthogonal
  couplings, which also take up a constant camera-IMU rotation): corrected rates
  ``ω_c = ω - b - K ω`` with ``K = diag(s) + offdiag(m)`` (first order in ``K``),
* the camera-IMU timing offset ``τ``: a fix stamped ``t`` is compared with the propagation at
  IMU time ``t + τ`` (:func:`~navtrack.attitude.quaternion.interpolate_attitude`).

Observability: scale and misalignment are seen only through rotations about the sensed axes;
``sigma`` (from the Jacobian at the solution) says how well each parameter was determined, so a
slow trial shows it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray
from navtrack.attitude.quaternion import (
    Propagation,
    check_quaternions,
    delta_angles,
    interpolate_attitude,
    propagate,
)

__all__ = [
    "CalibrationConfig",
    "GyroCalibration",
    "calibrate_gyro",
    "calibrated_propagation",
    "corrected_rates",
    "fix_residuals",
]

# (row, column) of the misalignment couplings m0..m5 in K.
_OFFDIAG = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))


@dataclass(frozen=True, slots=True)
class CalibrationConfig:
    """Which parameters the calibration estimates (the start attitude always).

    Attributes
    ----------
    bias, scale, misalignment, time_offset : bool
    loss : str
        ``scipy.optimize.least_squares`` loss on the σ-normalised residuals; ``soft_l1`` (with
        ``f_scale`` 3) keeps a fix that RANSAC got wrong from pulling the fit.
    max_nfev : int
        Residual evaluations (each propagates the whole trial).
    """

    bias: bool = True
    scale: bool = True
    misalignment: bool = True
    time_offset: bool = True
    loss: str = "soft_l1"
    max_nfev: int = 400


@dataclass(frozen=True, slots=True, eq=False)
class GyroCalibration:
    """Calibrated gyro and timing (arrays read-only). Fixed parameters are 0 with sigma NaN.

    Attributes
    ----------
    bias_rad_s : (3,) gyro bias, rad/s
    scale : (3,) scale-factor errors (dimensionless; 1e-3 = 1000 ppm)
    misalignment : (3, 3) off-diagonal couplings ``K`` (diagonal 0), rad
    time_offset_s : float
        IMU time of a fix = its camera stamp + ``time_offset_s``.
    start_rotvec_rad : (3,) rotation applied to the first fix to start the propagation
    sigma : (16,) standard deviations of ``[δ₀(3), b(3), s(3), m(6), τ]`` (units as above)
    rms_rad : float
        RMS fix residual after calibration (all three axes), rad.
    n_fixes : int
    converged : bool
    message : str
    nfev : int
    """

    bias_rad_s: FloatArray
    scale: FloatArray
    misalignment: FloatArray
    time_offset_s: float
    start_rotvec_rad: FloatArray
    sigma: FloatArray
    rms_rad: float
    n_fixes: int
    converged: bool
    message: str
    nfev: int

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def K(self) -> FloatArray:
        """``diag(scale) + misalignment``, shape (3, 3)."""
        return np.diag(self.scale) + self.misalignment


def corrected_rates(gyr_rad_s: ArrayLike, bias_rad_s: ArrayLike, K: ArrayLike) -> FloatArray:
    """``ω_c = ω - b - K ω`` for rates ``(n, 3)`` (rad/s)."""
    w = np.asarray(gyr_rad_s, dtype=np.float64)
    return np.asarray(w - np.asarray(bias_rad_s) - w @ np.asarray(K).T, dtype=np.float64)


def fix_residuals(
    t_s: FloatArray,
    prop: Propagation,
    rates_rad_s: FloatArray,
    fix_t_s: FloatArray,
    fix_quat: FloatArray,
) -> FloatArray:
    """Reference-frame errors ``rotvec(q_fix ⊗ p(t_fix)⁻¹)`` of a propagation at the fixes, rad,
    shape ``(m, 3)`` (``fix_t_s`` already on the IMU clock)."""
    pred = interpolate_attitude(t_s, prop.quat, rates_rad_s, fix_t_s)
    rel = Rotation.from_quat(fix_quat) * Rotation.from_quat(pred).inv()
    return np.asarray(rel.as_rotvec(), dtype=np.float64).reshape(-1, 3)


def _unpack(x: FloatArray, cfg: CalibrationConfig) -> tuple[FloatArray, ...]:
    full = np.zeros(16)
    full[_mask(cfg)] = x
    K = np.diag(full[6:9])
    for (i, j), v in zip(_OFFDIAG, full[9:15], strict=True):
        K[i, j] = v
    return full[:3], full[3:6], K, full, np.array(full[15])


def _mask(cfg: CalibrationConfig) -> np.ndarray:
    return np.array(
        [True] * 3 + [cfg.bias] * 3 + [cfg.scale] * 3 + [cfg.misalignment] * 6 + [cfg.time_offset],
        dtype=bool,
    )


def calibrate_gyro(
    t_s: ArrayLike,
    gyr_rad_s: ArrayLike,
    fix_t_s: ArrayLike,
    fix_quat: ArrayLike,
    fix_sigma_rad: ArrayLike,
    config: CalibrationConfig | None = None,
) -> GyroCalibration:
    """Fit start attitude, gyro errors and timing offset to camera fixes (least squares).

    Parameters
    ----------
    t_s : (n,) IMU sample times, s (strictly increasing)
    gyr_rad_s : (n, 3) measured body rates, rad/s
    fix_t_s : (m,) camera time stamps of the fixes, s (m >= 2)
    fix_quat : (m, 4) fix attitudes, body -> reference, scalar-last, unit
    fix_sigma_rad : (m,) per-axis standard deviation of each fix, rad
    config : CalibrationConfig or None

    Returns
    -------
    GyroCalibration
    """
    cfg = CalibrationConfig() if config is None else config
    t = np.asarray(t_s, dtype=np.float64)
    w = np.asarray(gyr_rad_s, dtype=np.float64)
    delta_angles(t, w)  # validates times and rates
    ft = np.asarray(fix_t_s, dtype=np.float64)
    fq = check_quaternions(fix_quat, "fix_quat")
    sig = np.asarray(fix_sigma_rad, dtype=np.float64)
    if ft.ndim != 1 or ft.size < 2 or fq.shape != (ft.size, 4) or sig.shape != ft.shape:
        raise ValueError(
            f"fix_t_s (m,), fix_quat (m, 4), fix_sigma_rad (m,) with m >= 2 expected, got "
            f"{ft.shape}, {fq.shape}, {sig.shape}"
        )
    if not np.all(sig > 0):
        raise ValueError("fix_sigma_rad: every fix needs a standard deviation > 0")
    mask = _mask(cfg)

    def residuals(x: FloatArray) -> FloatArray:
        rot0, b, K, _, tau = _unpack(x, cfg)
        rates = corrected_rates(w, b, K)
        prop = _start_propagation(t, rates, rot0, ft[0], fq[0])
        r = fix_residuals(t, prop, rates, ft + float(tau), fq)
        return np.asarray((r / sig[:, None]).ravel())

    scale = np.concatenate([[1e-3] * 3, [1e-4] * 3, [1e-3] * 3, [1e-3] * 6, [1e-3]])[mask]
    sol = least_squares(
        residuals,
        np.zeros(int(mask.sum())),
        x_scale=scale,
        loss=cfg.loss,
        f_scale=3.0,
        max_nfev=cfg.max_nfev,
        method="trf",
    )
    rot0, b, K, full, tau = _unpack(sol.x, cfg)
    sigma = np.full(16, np.nan)
    dof = max(sol.fun.size - sol.x.size, 1)
    s2 = float(np.sum(sol.fun**2)) / dof
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * s2
        sigma[mask] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        pass
    raw = (sol.fun.reshape(-1, 3)) * sig[:, None]
    return GyroCalibration(
        bias_rad_s=b,
        scale=full[6:9].copy(),
        misalignment=K - np.diag(np.diag(K)),
        time_offset_s=float(tau),
        start_rotvec_rad=rot0,
        sigma=sigma,
        rms_rad=float(np.sqrt(np.mean(raw**2))),
        n_fixes=int(ft.size),
        converged=bool(sol.status > 0),
        message=str(sol.message),
        nfev=int(sol.nfev),
    )


def _start_propagation(
    t: FloatArray, rates: FloatArray, rot0: FloatArray, t_first: float, q_first: FloatArray
) -> Propagation:
    start = int(np.clip(np.searchsorted(t, t_first), 0, t.size - 1))
    q0 = Rotation.from_rotvec(np.array(rot0)) * Rotation.from_quat(np.array(q_first))
    return propagate(q0, delta_angles(t, rates), start=start)


def calibrated_propagation(
    t_s: ArrayLike,
    gyr_rad_s: ArrayLike,
    calibration: GyroCalibration,
    first_fix_t_s: float,
    first_fix_quat: ArrayLike,
) -> tuple[Propagation, FloatArray]:
    """The propagation the calibration fitted: corrected rates from the corrected start.

    Returns
    -------
    prop : Propagation
        Started at the sample at or after ``first_fix_t_s`` from
        ``exp(δ₀) ⊗ q_fix,1``.
    rates : (n, 3) corrected rates, rad/s
    """
    t = np.asarray(t_s, dtype=np.float64)
    rates = corrected_rates(gyr_rad_s, calibration.bias_rad_s, calibration.K)
    prop = _start_propagation(
        t, rates, calibration.start_rotvec_rad, first_fix_t_s, np.asarray(first_fix_quat)
    )
    return prop, rates
