"""The paper's regime: one consistent simulated recording per Monte Carlo run.

Truth: BROAD's recorded rotation (trial ``regime_trial``), resampled to the IMU rate and set in
an east/north/up frame at the ALHAT test site so that the camera boresight (IMU ``x``) looks on
average along the line of sight from a helicopter descending towards the site. On that truth:

* an LN-200-class gyro at 400 Hz (:data:`navtrack.attitude.imu_sim.LN200`), sensing the Earth's
  rotation;
* a narrow camera (30° field of view, the paper's "thirty degree fov camera") imaging a patch
  of surveyed targets on the ground once a second; a fix needs six or more targets, so the fixes
  come in sequences while the IMU's motion keeps the patch in view;
* 1 Hz GNSS positions with 2 cm noise (paper: "a two centimeter standard deviation");
* a flash LIDAR sharing the camera's frame, ranging a smooth random DEM around the site.

The paper's method on it: eq. 3 (fixes into the inertial frame), per-sequence correction
(eq. 5), the Fig. 16 statistic per sequence, the weighted attitude (eqs. 6-7), the pose (eqs.
8-9) and the LIDAR yaw/pitch verification (eqs. 10-11) against the camera's. The extensions
(calibration, filter, smoother) run on the same recording and are reported apart.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import FloatArray, IntArray
from navtrack.attitude.frames import earth_rate_enu, from_inertial, to_inertial
from navtrack.attitude.imu_sim import LN200, GyroSpec, integrate_rates, sample_times, simulate_gyro
from navtrack.attitude.lidar import (
    Dem,
    FlashLidarConfig,
    correlation_shift,
    lidar_points,
    smooth_dem,
)
from navtrack.attitude.quaternion import attitude_errors
from navtrack.attitude.reconstruct import ESTIMATES, ReconstructionConfig, reconstruct
from navtrack.attitude.sequences import (
    AverageReading,
    SequenceStarts,
    sequence_starts,
    split_sequences,
    weighted_attitude,
)
from navtrack.attitude.smoother import SmootherConfig
from navtrack.attitude.wahba import RansacConfig, solve_fixes
from navtrack.experiments.alhat.params import AlhatParams
from navtrack.io.broad import read_broad

__all__ = [
    "MOUNT",
    "SITE_LAT_DEG",
    "SITE_LON_DEG",
    "Recording",
    "regime_run",
    "simulate_recording",
    "summarize_regime",
]

#: Test site (NASA Dryden, the Lakebed and Borrow Pit sites of paper 6), deg.
SITE_LAT_DEG, SITE_LON_DEG = 34.93, -117.89
#: Helicopter positions (site-centred ENU, m) at the start and end of the recording: a straight
#: descent along one line of sight, slant range 430 m to 200 m.
HELI_START_M = np.array([-260.0, 0.0, 340.0])
HELI_END_M = np.array([-120.0, 0.0, 160.0])
#: Smallest eq. 6 accuracy at a sequence's start, rad (a sequence whose fixes agree exactly with
#: its propagation would get an infinite weight); sequences floored are counted.
SIGMA0_FLOOR_RAD = 1e-9
#: The absolute and relative eq. 7 averages are counted as parting beyond this, rad.
AVERAGE_AGREEMENT_RAD = np.radians(0.01)
#: IMU -> camera (and LIDAR) rotation: camera ``z`` (boresight) = IMU ``x``, camera ``x`` = IMU
#: ``y``, camera ``y`` = IMU ``z`` (eq. 3's known ``M R_C``).
MOUNT = Rotation.from_matrix([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


@dataclass(frozen=True, slots=True, eq=False)
class Recording:
    """One simulated recording: truth and measurements (arrays read-only).

    Attributes
    ----------
    t_s : (n,) IMU sample times, s
    truth : (n, 4) true IMU -> ENU attitudes, scalar-last
    position_m : (n, 3) true ENU positions (site-centred), m
    gyr_rad_s : (n, 3) simulated gyro rates, rad/s
    gnss_t_s, gnss_m : (g,), (g, 3) GNSS times and noisy ENU positions
    fix_t_s : (k,) times of the usable camera fixes (on IMU samples), s
    fix_quat : (k, 4) camera -> ENU fix attitudes
    fix_sigma_rad : (k,) per-axis fix standard deviations
    fix_error_rad : (k,) fix errors against the truth
    images : int
        Images taken (one a second).
    fix_status : dict of str to int
        Fix status counts of all images.
    dem : Dem
    spec : GyroSpec
    """

    t_s: FloatArray
    truth: FloatArray
    position_m: FloatArray
    gyr_rad_s: FloatArray
    gnss_t_s: FloatArray
    gnss_m: FloatArray
    fix_t_s: FloatArray
    fix_quat: FloatArray
    fix_sigma_rad: FloatArray
    fix_error_rad: FloatArray
    images: int
    fix_status: dict[str, int]
    dem: Dem
    spec: GyroSpec

    def __post_init__(self) -> None:
        freeze_arrays(self)


def gyro_spec(params: AlhatParams) -> GyroSpec:
    """The regime's gyro: :data:`LN200` with the parameters' bias, ARW and scale factor."""
    return replace(
        LN200,
        bias_rad_s=np.radians(params.gyro_bias_deg_h) / 3600.0,
        arw_rad_sqrt_s=np.radians(params.gyro_arw_deg_sqrt_h) / 60.0,
        scale_factor=params.gyro_scale_ppm * 1e-6,
        rate_hz=params.imu_rate_hz,
    )


def _truth(params: AlhatParams, broad: Path) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Sample times, IMU -> ENU truth and positions from the BROAD trial's motion."""
    trial = read_broad(broad / f"{params.regime_trial}.mat")
    span = float(trial.t_s[-1] - trial.t_s[0])
    duration = span if params.duration_s <= 0 else min(params.duration_s, span)
    t = sample_times(duration, params.imu_rate_hz, float(trial.t_s[0]))
    w = np.stack([np.interp(t, trial.t_s, trial.gyr_rad_s[:, i]) for i in range(3)], axis=1)
    room = integrate_rates(t, w, Rotation.identity())
    frac = ((t - t[0]) / (t[-1] - t[0]))[:, None]
    pos = HELI_START_M + frac * (HELI_END_M - HELI_START_M)
    boresight = Rotation.from_quat(room).apply([1.0, 0.0, 0.0]).mean(axis=0)
    los = -pos.mean(axis=0)
    tilt = Rotation.align_vectors([los / np.linalg.norm(los)], [boresight])[0]
    return t, np.asarray((tilt * Rotation.from_quat(room)).as_quat()), pos


def simulate_recording(params: AlhatParams, broad: Path, rng: np.random.Generator) -> Recording:
    """Truth, gyro, GNSS, camera fixes and DEM of one run."""
    t, truth, pos = _truth(params, broad)
    spec = gyro_spec(params)
    lat = np.radians(SITE_LAT_DEG)
    rate = earth_rate_enu(lat)
    gyro = simulate_gyro(t, truth, spec, rng, frame_rate_rad_s=rate)
    dem = smooth_dem(rng)
    gt = np.arange(np.ceil(t[0]), t[-1], 1.0)
    gnss = np.stack([np.interp(gt, t, pos[:, i]) for i in range(3)], axis=1)
    gnss = gnss + rng.normal(0.0, params.gnss_sigma_m, gnss.shape)
    # surveyed targets: a patch around the site, on the terrain
    r_t = params.patch_radius_m * np.sqrt(rng.uniform(0, 1, params.patch_targets))
    a_t = rng.uniform(0, 2 * np.pi, params.patch_targets)
    xy = np.stack([r_t * np.cos(a_t), r_t * np.sin(a_t)], axis=1)
    targets = np.column_stack([xy, dem.height(xy)])
    # images once a second on IMU samples
    sample = np.searchsorted(t, np.arange(t[0] + 0.5, t[-1], params.fix_interval_s))
    cam = Rotation.from_quat(truth[sample]) * MOUNT.inv()  # camera -> ENU
    los = targets[None, :, :] - pos[sample, None, :]
    w_true = los / np.linalg.norm(los, axis=2, keepdims=True)
    gnss_at = np.stack([np.interp(t[sample], gt, gnss[:, i]) for i in range(3)], axis=1)
    los_g = targets[None, :, :] - gnss_at[:, None, :]
    w_ref = los_g / np.linalg.norm(los_g, axis=2, keepdims=True)
    m, nt = sample.size, params.patch_targets
    to_cam = np.asarray(cam.inv().as_matrix())
    v = np.einsum("mij,mnj->mni", to_cam, w_true)
    noise = Rotation.from_rotvec(rng.normal(0.0, params.patch_ray_sigma_rad, (m * nt, 3)))
    v = np.asarray(noise.apply(v.reshape(-1, 3))).reshape(m, nt, 3)
    visible = v[..., 2] > np.cos(np.radians(0.5 * params.camera_fov_deg))
    ransac = RansacConfig(threshold_rad=5.0 * params.patch_ray_sigma_rad, degenerate_tol=1e-6)
    fixes = solve_fixes(v, w_ref, visible, rng, ransac, min_rays=params.min_rays)
    ok = fixes.ok
    err = attitude_errors(Rotation.from_quat(fixes.quat[ok]), cam[ok])[0]
    return Recording(
        t,
        truth,
        pos,
        gyro.gyr_rad_s,
        gt,
        gnss,
        t[sample[ok]],
        fixes.quat[ok],
        fixes.sigma_rad[ok],
        err,
        m,
        fixes.status_counts(),
        dem,
        spec,
    )


def _deg_stats(e_rad: FloatArray) -> dict[str, float]:
    e = np.degrees(e_rad)
    return {"mean_deg": float(e.mean()), "max_deg": float(e.max()), "std_deg": float(e.std())}


def _fig16(starts: SequenceStarts, fix_t_s: FloatArray, labels: IntArray) -> list[dict[str, Any]]:
    """The Fig. 16 statistic of every sequence: max and std of ``e_s`` before and after."""
    rows = []
    for j in range(starts.t_q0_s.size):
        idx = labels == j
        b, a = np.degrees(starts.e_s_before_rad[idx]), np.degrees(starts.e_s_after_rad[idx])
        rows.append(
            {
                "sequence": j,
                "fixes": int(idx.sum()),
                "length_s": float(fix_t_s[idx][-1] - fix_t_s[idx][0]),
                "max_before_deg": float(b.max()),
                "max_after_deg": float(a.max()),
                "std_before_deg": float(b.std()),
                "std_after_deg": float(a.std()),
            }
        )
    return rows


def _lidar_verification(
    rec: Recording, est_imu: FloatArray, params: AlhatParams, rng: np.random.Generator
) -> dict[str, Any]:
    """Eqs. 8-11 every ``lidar_interval_s`` while the LIDAR looks at the DEM: yaw and pitch
    from the DEM-correlation shift, beside the true errors and the camera's."""
    cfg = FlashLidarConfig(pixels=params.lidar_pixels)
    t = rec.t_s
    k = np.searchsorted(t, np.arange(t[0] + 0.25, t[-1], params.lidar_interval_s))
    true_l = Rotation.from_quat(rec.truth[k]) * MOUNT.inv()
    est_l = Rotation.from_quat(est_imu[k]) * MOUNT.inv()
    gnss = np.stack([np.interp(t[k], rec.gnss_t_s, rec.gnss_m[:, i]) for i in range(3)], axis=1)
    half = 0.5 * (rec.dem.z_m.shape[0] - 1) * rec.dem.spacing_m - 5.0
    lidar, truth, status = [], [], {"ok": 0, "off_dem": 0, "not_converged": 0}
    for i in range(k.size):
        bore = true_l[i].apply([0.0, 0.0, 1.0])
        if bore[2] >= -0.1:
            status["off_dem"] += 1
            continue
        hit = rec.position_m[k[i]] + bore * (-rec.position_m[k[i], 2] / bore[2])
        if np.any(np.abs(hit[:2]) > half):
            status["off_dem"] += 1
            continue
        pts = lidar_points(rec.dem, rec.position_m[k[i]], true_l[i], rng, cfg)
        if np.mean(np.isfinite(pts[:, 0])) < 0.9:
            status["off_dem"] += 1
            continue
        sh = correlation_shift(rec.dem, gnss[i], est_l[i], pts)
        if not sh.converged:
            status["not_converged"] += 1
            continue
        status["ok"] += 1
        lidar.append([sh.yaw_eq10_rad, sh.pitch_eq11_rad])
        d = (true_l[i].inv() * est_l[i]).as_rotvec()
        truth.append([d[0], -d[1]])
    out: dict[str, Any] = {"frames": int(k.size), "status": status}
    # the camera's view of the same angles at the fixes (paper Fig. 17 B)
    cam_est = Rotation.from_quat(est_imu[np.searchsorted(t, rec.fix_t_s)]) * MOUNT.inv()
    dc = np.asarray((Rotation.from_quat(rec.fix_quat).inv() * cam_est).as_rotvec())
    cam = np.degrees(np.column_stack([dc[:, 0], -dc[:, 1]]))
    out["camera_max_abs_yaw_deg"] = float(np.abs(cam[:, 0]).max())
    out["camera_max_abs_pitch_deg"] = float(np.abs(cam[:, 1]).max())
    if lidar:
        li, tr = np.degrees(np.asarray(lidar)), np.degrees(np.asarray(truth))
        out["lidar_max_abs_yaw_deg"] = float(np.abs(li[:, 0]).max())
        out["lidar_max_abs_pitch_deg"] = float(np.abs(li[:, 1]).max())
        out["true_max_abs_yaw_deg"] = float(np.abs(tr[:, 0]).max())
        out["true_max_abs_pitch_deg"] = float(np.abs(tr[:, 1]).max())
        out["lidar_minus_true_rms_deg"] = float(np.sqrt(np.mean((li - tr) ** 2)))
    return out


def _extensions(
    rec: Recording,
    fixes: tuple[FloatArray, FloatArray, FloatArray],
    to_enu: Callable[[FloatArray], FloatArray],
    params: AlhatParams,
) -> dict[str, FloatArray]:
    """Calibration, filter and smoother on the fixes ``(t_s, quat, sigma_rad)`` of the
    propagation frame; their attitudes IMU -> ENU."""
    spec = rec.spec
    cfg = ReconstructionConfig(
        smoother=SmootherConfig(
            sigma_gyro_rad_sqrt_s=spec.arw_rad_sqrt_s,
            sigma_bias_rad_s_sqrt_s=params.regime_bias_walk_rad_s_sqrt_s,
            sigma_att0_rad=0.01,
            sigma_bias0_rad_s=10.0 * spec.bias_rad_s,
        )
    )
    recon = reconstruct(rec.t_s, rec.gyr_rad_s, *fixes, cfg)
    return {name: to_enu(recon.on_camera_clock(name, rec.t_s)) for name in ESTIMATES}


def _weighted_average(
    t_s: FloatArray, starts: SequenceStarts, params: AlhatParams
) -> tuple[FloatArray, dict[str, Any]]:
    """The paper's weighted attitude (eq. 7) of the corrected sequences in the configured
    reading of the average, and how far the other reading departs from it."""
    b = np.radians(params.b_deg_h) / 3600.0
    sigma0 = np.maximum(starts.sigma0_rad, SIGMA0_FLOOR_RAD)
    record: dict[str, Any] = {"sigma0_floored": int(np.sum(starts.sigma0_rad < SIGMA0_FLOOR_RAD))}

    def combine(average: AverageReading) -> FloatArray:
        return weighted_attitude(
            t_s,
            starts.quat,
            starts.t_q0_s,
            sigma0,
            b,
            weight_power=params.weight_power,
            average=average,
        )

    u = combine(params.average)
    other = combine("relative" if params.average == "absolute" else "absolute")
    gap = attitude_errors(Rotation.from_quat(u), Rotation.from_quat(other))[0]
    # the printed (absolute) average is undefined where the propagations straddle a rotation
    # of π; the two readings then part
    record["average_readings_differ_samples"] = int(np.sum(gap > AVERAGE_AGREEMENT_RAD))
    record["average_readings_max_gap_deg"] = float(np.degrees(gap.max()))
    return u, record


def regime_run(
    params: AlhatParams, broad: Path, rng: np.random.Generator, *, extensions: bool = False
) -> dict[str, Any]:
    """One recording through the paper's method and the LIDAR verification; with
    ``extensions`` also the calibration, filter and smoother (JSON-able dict)."""
    rec = simulate_recording(params, broad, rng)
    res: dict[str, Any] = {
        "images": rec.images,
        "fix_status": rec.fix_status,
        "fixes": int(rec.fix_t_s.size),
        "fix_error": _deg_stats(rec.fix_error_rad) if rec.fix_t_s.size else None,
        "gyro": rec.spec.name,
    }
    labels = split_sequences(rec.fix_t_s, params.sequence_gap_s)
    counts = np.bincount(labels)
    keep = counts[labels] >= 2
    res["sequences_dropped_single_fix"] = int(np.sum(counts < 2))
    ft, fq, fs = rec.fix_t_s[keep], rec.fix_quat[keep], rec.fix_sigma_rad[keep]
    labels = np.unique(labels[keep], return_inverse=True)[1]
    if ft.size < 2:
        res["status"] = "too_few_fixes"
        return res
    lat, lon = np.radians(SITE_LAT_DEG), np.radians(SITE_LON_DEG)
    t0 = float(ft[0])
    chain = params.earth_rate
    fix_i = (
        to_inertial(ft, fq, t0, lat, lon, MOUNT)
        if chain
        else np.asarray((Rotation.from_quat(fq) * MOUNT).as_quat())
    )

    def to_enu(q: FloatArray) -> FloatArray:
        return from_inertial(rec.t_s, q, t0, lat, lon) if chain else q

    starts = sequence_starts(
        rec.t_s,
        rec.gyr_rad_s,
        ft,
        fix_i,
        labels,
        method=params.method,
        order=params.order,
        correction=params.correction,
        sigma0=params.sigma0_reading,
    )
    res["status"] = "ok"
    res["sequences"] = _fig16(starts, ft, labels)
    res["fix_series"] = {
        "t_since_first_fix_s": (ft - ft[0]).tolist(),
        "sequence": labels.tolist(),
        "e_s_before_deg": np.degrees(starts.e_s_before_rad).tolist(),
        "e_s_after_deg": np.degrees(starts.e_s_after_rad).tolist(),
    }
    u, averages = _weighted_average(rec.t_s, starts, params)
    res |= averages
    eq7 = to_enu(u)
    span = (rec.t_s >= ft[0]) & (rec.t_s <= ft[-1])
    ev = np.flatnonzero(span)
    truth = Rotation.from_quat(rec.truth[ev])

    def err(q: FloatArray) -> dict[str, float]:
        return _deg_stats(attitude_errors(Rotation.from_quat(q[ev]), truth)[0])

    longest = int(np.argmax(np.bincount(labels)))
    res["paper"] = {
        "weighted_eq7": err(eq7),
        "longest_sequence_corrected": err(to_enu(starts.quat[longest])),
        "sequences": int(starts.t_q0_s.size),
    }
    res["lidar"] = _lidar_verification(rec, eq7, params, rng)
    if extensions:
        ext = _extensions(rec, (ft, fix_i, fs), to_enu, params)
        res["extensions"] = {name: err(q) for name, q in ext.items()}
    return res


def _spread(values: list[float]) -> dict[str, float] | None:
    if not values:
        return None
    v = np.asarray(values, dtype=np.float64)
    return {
        "median": float(np.median(v)),
        "p05": float(np.percentile(v, 5)),
        "p95": float(np.percentile(v, 95)),
    }


_FIG16 = ("max_before_deg", "max_after_deg", "std_before_deg", "std_after_deg")
_LIDAR = (
    "lidar_max_abs_yaw_deg",
    "lidar_max_abs_pitch_deg",
    "camera_max_abs_yaw_deg",
    "camera_max_abs_pitch_deg",
    "true_max_abs_yaw_deg",
    "true_max_abs_pitch_deg",
    "lidar_minus_true_rms_deg",
)


def summarize_regime(params: AlhatParams, runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Across runs: the Fig. 16 statistic of each run's longest sequence and of all sequences
    (median and 5-95 % range), how often the correction lowered it, the eq. 7 attitude error
    and the LIDAR/camera yaw and pitch."""
    ok = [r for r in runs if r.get("status") == "ok"]
    status: dict[str, int] = {}
    for r in runs:
        status[r.get("status", "?")] = status.get(r.get("status", "?"), 0) + 1
    out: dict[str, Any] = {"runs": len(runs), "status": status}
    if not ok:
        return out
    out["first_run_sequences"] = ok[0]["sequences"]
    longest = [max(r["sequences"], key=lambda s: s["fixes"]) for r in ok]
    every = [s for r in ok for s in r["sequences"]]
    out["longest_sequence"] = {k: _spread([s[k] for s in longest]) for k in _FIG16}
    out["longest_sequence"]["fixes"] = _spread([float(s["fixes"]) for s in longest])
    out["longest_sequence"]["length_s"] = _spread([s["length_s"] for s in longest])
    out["all_sequences"] = {k: _spread([s[k] for s in every]) for k in _FIG16}
    out["all_sequences"]["count"] = len(every)
    for kind, seqs in (("longest_sequence", longest), ("all_sequences", every)):
        out[kind]["max_lowered"] = sum(s["max_after_deg"] < s["max_before_deg"] for s in seqs)
        out[kind]["std_lowered"] = sum(s["std_after_deg"] < s["std_before_deg"] for s in seqs)
    out["sequences_per_run"] = _spread([float(len(r["sequences"])) for r in ok])
    out["sigma0_floored"] = sum(r["sigma0_floored"] for r in ok)
    out["average_readings_differ_samples"] = sum(r["average_readings_differ_samples"] for r in ok)
    out["average_readings_max_gap_deg"] = max(r["average_readings_max_gap_deg"] for r in ok)
    out["fix_error_mean_deg"] = _spread([r["fix_error"]["mean_deg"] for r in ok])
    for key in ("weighted_eq7", "longest_sequence_corrected"):
        out[key] = {k: _spread([r["paper"][key][k] for r in ok]) for k in ("mean_deg", "max_deg")}
    lid = [r["lidar"] for r in ok]
    out["lidar"] = {k: _spread([x[k] for x in lid if k in x]) for k in _LIDAR}
    out["lidar"]["frames_ok"] = sum(x["status"]["ok"] for x in lid)
    out["lidar"]["frames_off_dem"] = sum(x["status"]["off_dem"] for x in lid)
    out["lidar"]["frames_not_converged"] = sum(x["status"]["not_converged"] for x in lid)
    out["settings"] = {
        "gyro": ok[0]["gyro"],
        "truth_motion": params.regime_trial,
        "imu_rate_hz": params.imu_rate_hz,
        "camera_fov_deg": params.camera_fov_deg,
        "patch_targets": params.patch_targets,
        "patch_radius_m": params.patch_radius_m,
        "ray_sigma_rad": params.patch_ray_sigma_rad,
        "b_deg_h": params.b_deg_h,
        "earth_rate": params.earth_rate,
    }
    return out
