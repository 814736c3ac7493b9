"""The real-data step of the paper 6 reproduction: BROAD trials with simulated camera fixes.

For each trial: the truncated series against the closed form over the whole recording, the
propagation speed, simulated sightings of surveyed targets from the optical truth, RANSAC-SVD
fixes, the chain of estimates (:func:`navtrack.attitude.reconstruct.reconstruct`) and their
attitude errors against the optical truth on BROAD's movement samples. An independent check of
the calibrated timing offset: the lag between the gyro rates and the rates differenced from the
optical attitude.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._typing import BoolArray, FloatArray
from navtrack.attitude.calibration import CalibrationConfig, GyroCalibration
from navtrack.attitude.quaternion import (
    CorrectionReading,
    attitude_errors,
    correction_quaternion,
    delta_angles,
    interpolate_attitude,
    propagate,
)
from navtrack.attitude.reconstruct import (
    ESTIMATES,
    Reconstruction,
    ReconstructionConfig,
    reconstruct,
)
from navtrack.attitude.simulate import CameraSimConfig, Sightings, simulate_sightings
from navtrack.attitude.smoother import SmootherConfig
from navtrack.attitude.wahba import CameraFixes, RansacConfig, solve_fixes
from navtrack.experiments.alhat.params import AlhatParams
from navtrack.io.broad import BroadTrial, read_broad

__all__ = ["TrialOutcome", "optical_rate_lag_s", "series_accuracy", "trial_study"]


@dataclass(frozen=True, slots=True, eq=False)
class TrialOutcome:
    """What the figures need of one trial: evaluation times and errors per estimate (deg)."""

    name: str
    t_s: FloatArray
    errors_deg: dict[str, FloatArray]
    fix_t_s: FloatArray


def _median_ms(fn: Any, repeat: int = 7) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def series_accuracy(trial: BroadTrial) -> dict[str, Any]:
    """The truncated series (orders 1-3) against the closed form over the whole trial.

    Both start from the first optical attitude and run through every gyro sample; the angle
    between them is taken at every sample. The bound ``Σ θ_k⁵ / 480`` is the leading
    effect of the omitted fourth-power term on the rotation angle of each step.
    """
    d = delta_angles(trial.t_s, trial.gyr_rad_s)
    ok = np.flatnonzero(np.all(np.isfinite(trial.opt_quat_xyzw), axis=1))
    start = int(ok[0])
    q0 = trial.opt_quat_xyzw[start]
    closed = propagate(q0, d, start=start, method="closed")
    out: dict[str, Any] = {"samples": int(trial.t_s.size)}
    th = np.linalg.norm(d, axis=1)
    for order in (1, 2, 3):
        series = propagate(q0, d, start=start, method="series", order=order)
        diff = attitude_errors(series.rotation, closed.rotation)[0]
        out[f"order{order}_max_rad"] = float(diff.max())
        out[f"order{order}_norm_drift"] = float(np.max(np.abs(series.norm - 1.0)))
    out["order3_bound_rad"] = float(np.sum(th**5) / 480.0)
    out["max_step_rad"] = float(th.max())
    out["propagate_closed_ms"] = _median_ms(
        lambda: propagate(q0, delta_angles(trial.t_s, trial.gyr_rad_s), start=start)
    )
    out["propagate_series3_ms"] = _median_ms(
        lambda: propagate(
            q0, delta_angles(trial.t_s, trial.gyr_rad_s), start=start, method="series"
        )
    )
    return out


def optical_rate_lag_s(trial: BroadTrial, max_lag: int = 8) -> float:
    """Lag of the gyro behind the optical attitude, s (independent of the camera fixes).

    The body rate over each optical interval ``[k, k+1]`` (differenced attitudes) is compared
    with the gyro sample ``k + L``; the RMS difference is minimised over integer ``L`` and
    refined by a parabola. With the propagation's rectangular rule (rate ``k`` held over
    ``[t_k, t_k+1]``) a fix on the optical clock at ``t`` belongs to IMU time ``t + L Δt``: the
    value is comparable with the calibrated ``time_offset_s``.
    """
    q = trial.opt_quat_xyzw
    pair = np.all(np.isfinite(q[:-1]), axis=1) & np.all(np.isfinite(q[1:]), axis=1)
    k = np.flatnonzero(pair)
    rel = Rotation.from_quat(q[k]).inv() * Rotation.from_quat(q[k + 1])
    w_opt = np.asarray(rel.as_rotvec()) * trial.rate_hz
    lags = np.arange(-max_lag, max_lag + 1)
    rms = []
    for lag in lags:
        j = k + lag
        keep = (j >= 0) & (j < trial.t_s.size)
        diff = trial.gyr_rad_s[j[keep]] - w_opt[keep]
        rms.append(float(np.sqrt(np.mean(np.sum(diff**2, axis=1)))))
    i = int(np.clip(np.argmin(rms), 1, len(lags) - 2))
    a, b, c = rms[i - 1], rms[i], rms[i + 1]
    frac = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) > 0 else 0.0
    return float((lags[i] + frac) / trial.rate_hz)


def _first_seconds(trial: BroadTrial, duration_s: float) -> BroadTrial:
    if duration_s <= 0:
        return trial
    n = int(np.searchsorted(trial.t_s, trial.t_s[0] + duration_s))
    return BroadTrial(
        trial.name,
        trial.t_s[:n].copy(),
        trial.gyr_rad_s[:n].copy(),
        trial.opt_quat_wxyz[:n].copy(),
        trial.movement[:n].copy(),
        trial.rate_hz,
    )


def _config(params: AlhatParams) -> ReconstructionConfig:
    return ReconstructionConfig(
        method=params.method,
        order=params.order,
        correction=params.correction,
        calibration=CalibrationConfig(),
        smoother=SmootherConfig(params.sigma_gyro_rad_sqrt_s, params.sigma_bias_rad_s_sqrt_s),
    )


def _errors(
    recon: Reconstruction, name: str, trial: BroadTrial, use: BoolArray, offset_s: float
) -> FloatArray:
    """Errors (rad) of estimate ``name`` against the optical truth at samples ``use``: the
    truth at optical time ``t`` is compared with the estimate at camera time ``t - offset``."""
    est = recon.on_camera_clock(name, trial.t_s[use] - offset_s)
    return attitude_errors(Rotation.from_quat(est), Rotation.from_quat(trial.opt_quat_xyzw[use]))[0]


def _stats(e_rad: FloatArray) -> dict[str, float]:
    e = np.degrees(e_rad)
    return {
        "mean_deg": float(e.mean()),
        "max_deg": float(e.max()),
        "rms_deg": float(np.sqrt(np.mean(e**2))),
        "p95_deg": float(np.percentile(e, 95)),
    }


def _camera_fixes(
    trial: BroadTrial, params: AlhatParams, rng: np.random.Generator
) -> tuple[Sightings, CameraFixes, dict[str, Any]]:
    """Simulated sightings of the trial's optical attitude and the RANSAC fixes solved from
    them, with the fixes' summary (status counts, outliers, errors against the truth)."""
    sim = CameraSimConfig(
        interval_s=params.fix_interval_s,
        n_targets=params.n_targets,
        fov_half_angle_deg=params.fov_half_angle_deg,
        min_rays=params.min_rays,
        sigma_rad=params.ray_sigma_rad,
        outlier_fraction=params.outlier_fraction,
        time_offset_s=params.camera_offset_s,
    )
    sights = simulate_sightings(trial.t_s, trial.opt_quat_xyzw, rng, sim)
    ransac = RansacConfig(threshold_rad=params.ransac_threshold_rad, trials=params.ransac_trials)
    t0 = time.perf_counter()
    fixes = solve_fixes(
        sights.v_body, sights.w_ref, sights.visible, rng, ransac, min_rays=params.min_rays
    )
    per_fix_ms = 1e3 * (time.perf_counter() - t0) / max(fixes.status.size, 1)
    ok = fixes.ok
    out_rays = sights.outlier & sights.visible
    clean = sights.visible & ~sights.outlier
    fix_err = attitude_errors(
        Rotation.from_quat(fixes.quat[ok]),
        Rotation.from_quat(trial.opt_quat_xyzw[sights.sample[ok]]),
    )[0]
    summary = {
        "images": int(fixes.status.size),
        "images_without_truth": sights.n_no_truth,
        "status": fixes.status_counts(),
        "outlier_rays": int(out_rays[ok].sum()),
        "outliers_accepted": int((fixes.inliers & out_rays)[ok].sum()),
        "inliers_rejected": int((~fixes.inliers & clean)[ok].sum()),
        "error_mean_deg": float(np.degrees(fix_err.mean())),
        "error_max_deg": float(np.degrees(fix_err.max())),
        "sigma_mean_deg": float(np.degrees(np.nanmean(fixes.sigma_rad[ok]))),
        "ms_per_fix": per_fix_ms,
    }
    return sights, fixes, summary


def _other_correction(
    trial: BroadTrial,
    recon: Reconstruction,
    ft: FloatArray,
    fq: FloatArray,
    use: BoolArray,
    params: AlhatParams,
) -> dict[str, Any]:
    """Errors of the propagation corrected by the reading of the paper's correction quaternion
    that ``params.correction`` does not use (``paper_correction_<reading>``)."""
    other: CorrectionReading = (
        "paper_literal" if params.correction == "mean_rotvec" else "mean_rotvec"
    )
    d = delta_angles(trial.t_s, trial.gyr_rad_s)
    plain = recon.estimates["propagation"].quat
    pred = interpolate_attitude(trial.t_s, plain, trial.gyr_rad_s, ft)
    e_s, e_v = attitude_errors(Rotation.from_quat(pred), Rotation.from_quat(fq))
    start = int(np.clip(np.searchsorted(trial.t_s, ft[0]), 0, trial.t_s.size - 1))
    alt = propagate(
        correction_quaternion(e_s, e_v, other) * Rotation.from_quat(fq[0]),
        d,
        start=start,
        method=params.method,
        order=params.order,
    )
    est = interpolate_attitude(
        trial.t_s, alt.quat, trial.gyr_rad_s, trial.t_s[use] - params.camera_offset_s
    )
    alt_err = attitude_errors(
        Rotation.from_quat(est), Rotation.from_quat(trial.opt_quat_xyzw[use])
    )[0]
    return {f"paper_correction_{other}": _stats(alt_err)}


def _calibration_record(cal: GyroCalibration) -> dict[str, Any]:
    """The gyro calibration with the standard deviation of every estimated parameter."""
    names = [f"start_rotvec_{a}_rad" for a in "xyz"] + [f"bias_{a}_rad_s" for a in "xyz"]
    names += [f"scale_{a}" for a in "xyz"] + [f"misalignment_{i}" for i in range(6)]
    names += ["time_offset_s"]
    return {
        "bias_rad_s": cal.bias_rad_s,
        "scale": cal.scale,
        "misalignment": cal.misalignment,
        "time_offset_s": cal.time_offset_s,
        "sigma": dict(zip(names, cal.sigma, strict=True)),
        "rms_deg": float(np.degrees(cal.rms_rad)),
        "converged": cal.converged,
        "nfev": cal.nfev,
        "message": cal.message,
    }


def trial_study(
    path: Path, params: AlhatParams, rng: np.random.Generator
) -> tuple[dict[str, Any], TrialOutcome, Reconstruction]:
    """Run the reproduction on one BROAD trial.

    Returns
    -------
    results : dict
        JSON-able: ``series``, ``fixes``, one entry per estimate (``mean_deg``, ``max_deg``,
        ...), ``paper_correction_literal``, ``calibration``, ``timing_offset_check``.
    outcome : TrialOutcome
        Error series for the figures.
    recon : Reconstruction
    """
    trial = _first_seconds(read_broad(path), params.duration_s)
    res: dict[str, Any] = {
        "trial": trial.name,
        "duration_s": float(trial.t_s[-1] - trial.t_s[0]),
        "series": series_accuracy(trial),
    }
    sights, fixes, res["fixes"] = _camera_fixes(trial, params, rng)
    ok = fixes.ok
    ft = sights.t_stamp_s[ok]
    fq = fixes.quat[ok]
    t0 = time.perf_counter()
    recon = reconstruct(trial.t_s, trial.gyr_rad_s, ft, fq, fixes.sigma_rad[ok], _config(params))
    res["reconstruction_s"] = time.perf_counter() - t0
    use = np.all(np.isfinite(trial.opt_quat_xyzw), axis=1) & trial.movement
    use &= (trial.t_s >= ft[0]) & (trial.t_s <= ft[-1])
    res["evaluated_samples"] = int(use.sum())
    errors = {}
    for name in ESTIMATES:
        errors[name] = _errors(recon, name, trial, use, params.camera_offset_s)
        res[name] = _stats(errors[name])
    res |= _other_correction(trial, recon, ft, fq, use, params)
    res["paper_fix_errors"] = {
        "e_s_mean_deg": float(np.degrees(recon.fix_errors_rad.mean())),
        "e_s_max_deg": float(np.degrees(recon.fix_errors_rad.max())),
        "correction_deg": float(np.degrees(np.linalg.norm(recon.correction_rotvec_rad))),
    }
    cal = recon.calibration
    res["calibration"] = _calibration_record(cal)
    lag = optical_rate_lag_s(trial)
    res["timing_offset_check"] = {
        "calibrated_s": cal.time_offset_s,
        "simulated_camera_offset_s": params.camera_offset_s,
        "gyro_optical_lag_s": lag,
        "expected_s": params.camera_offset_s + lag,
    }
    res["smoother_nis_mean"] = float(np.nanmean(recon.smoother.nis))
    outcome = TrialOutcome(
        trial.name, trial.t_s[use], {k: np.degrees(v) for k, v in errors.items()}, ft
    )
    return res, outcome, recon
