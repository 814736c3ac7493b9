"""The body of ``navtrack attitude reconstruct`` (:mod:`navtrack.cli.attitude` holds its
options)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation
from tqdm import tqdm

from navtrack.attitude.quaternion import attitude_errors
from navtrack.attitude.reconstruct import Reconstruction, reconstruct
from navtrack.attitude.simulate import simulate_sightings
from navtrack.attitude.trajectory import pose_frame
from navtrack.attitude.wahba import solve_fixes
from navtrack.cli.attitude import ESTIMATE_NAMES, EXAMPLE
from navtrack.cli.outputs import check_outputs
from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.io.broad import BroadTrial, read_broad
from navtrack.io.positions import read_gnss_positions
from navtrack.io.solution import write_solution
from navtrack.io.tables import read_table

_GYRO_COLUMNS = ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s")
_FIX_COLUMNS = ("t_s", "qx", "qy", "qz", "qw")


def _read_imu(path: Path) -> tuple[Any, Any, Any]:
    """(t_s, gyr_rad_s, BroadTrial or None)."""
    if path.suffix.lower() == ".mat":
        trial = read_broad(path)
        return trial.t_s, trial.gyr_rad_s, trial
    df = read_table(path)
    missing = [c for c in ("t_s", *_GYRO_COLUMNS) if c not in df.columns]
    if missing:
        raise FileFormatError(path, None, f"IMU table lacks the columns {', '.join(missing)}")
    return df["t_s"].to_numpy(float), df[list(_GYRO_COLUMNS)].to_numpy(np.float64), None


def _read_fixes(path: Path, sigma_rad: float) -> tuple[Any, Any, Any]:
    df = read_table(path)
    missing = [c for c in _FIX_COLUMNS if c not in df.columns]
    if missing:
        raise FileFormatError(path, None, f"fixes table lacks the columns {', '.join(missing)}")
    q = df[["qx", "qy", "qz", "qw"]].to_numpy(np.float64)
    sig = (
        df["sigma_rad"].to_numpy(np.float64)
        if "sigma_rad" in df.columns
        else np.full(len(df), sigma_rad)
    )
    return df["t_s"].to_numpy(np.float64), q, sig


def _write_pose(args: argparse.Namespace, est: Any, t: Any) -> dict[str, Any]:
    """Write ``--out``: a solution frame when there is a GNSS position or an absolute time,
    else a pose table of the columns that have values."""
    t_cam = t - est.time_offset_s
    gnss = read_gnss_positions(args.gnss) if args.gnss is not None else None
    offset = args.gnss_offset_s
    if offset is None:
        offset = float(gnss.t_s[0] - t_cam[0]) if gnss is not None else 0.0
    frame = pose_frame(t_cam, est.quat, gnss, gnss_offset_s=offset, t0_gps_s=args.t0_gps_s)
    if gnss is None and args.t0_gps_s == 0.0:
        keep = ("qx", "qy", "qz", "qw", "roll_deg", "pitch_deg", "yaw_deg")
        table = pd.DataFrame({"t_s": t_cam, **{k: frame[k] for k in keep}})
        if args.out.suffix.lower() == ".parquet":
            table.to_parquet(args.out, index=False)
        else:
            table.to_csv(args.out, index=False, float_format="%.10g")
        print(f"wrote      {args.out}: {args.estimate}, {t_cam.size} epochs (no GNSS positions)")
        return {"out": str(args.out), "epochs_with_position": 0}
    path = write_solution(frame, args.out)
    n_pos = int(np.count_nonzero(frame["status"] == "ok"))
    print(f"wrote      {path}: {args.estimate}, {t_cam.size} epochs, {n_pos} with a GNSS position")
    return {"out": str(path), "epochs_with_position": n_pos}


def _check_inputs(args: argparse.Namespace) -> None:
    """Refuse contradictory inputs; ``--example`` sets the bundled trial with simulated fixes."""
    if args.example:
        if args.imu is not None or args.fixes is not None:
            raise SystemExit(
                "navtrack attitude reconstruct: give either IMU (--fixes | --simulate-fixes) or "
                "--example, not both"
            )
        args.imu, args.simulate_fixes = sample_path(EXAMPLE), True
    if args.imu is None:
        raise SystemExit("navtrack attitude reconstruct: give an IMU file, or --example")
    check_outputs("navtrack attitude reconstruct", args.out, (".csv", ".parquet"))
    if (args.fixes is None) == (not args.simulate_fixes):
        raise SystemExit(
            "navtrack attitude reconstruct: give exactly one of --fixes and --simulate-fixes"
        )


def _camera_fixes(
    args: argparse.Namespace, t: Any, trial: BroadTrial | None, summary: dict[str, Any]
) -> tuple[Any, Any, Any]:
    """(t_s, quat, sigma_rad) of the camera fixes: read from ``--fixes`` or simulated from the
    trial's optical truth (their status counts go into ``summary``)."""
    if not args.simulate_fixes:
        return _read_fixes(args.fixes, args.fix_sigma_rad)
    if trial is None:
        raise SystemExit("navtrack attitude reconstruct: --simulate-fixes needs a BROAD .mat trial")
    rng = np.random.default_rng(args.seed)
    sights = simulate_sightings(t, trial.opt_quat_xyzw, rng)
    fixes = solve_fixes(sights.v_body, sights.w_ref, sights.visible, rng, min_rays=6)
    summary["fix_status"] = fixes.status_counts()
    return sights.t_stamp_s[fixes.ok], fixes.quat[fixes.ok], fixes.sigma_rad[fixes.ok]


def _errors_vs_optical(
    recon: Reconstruction, trial: BroadTrial, t: Any, ft: Any
) -> dict[str, dict[str, float]]:
    """Mean and largest error of every estimate against the trial's optical attitude, over the
    moving samples inside the span of the fixes (printed, and returned for the summary)."""
    use = np.all(np.isfinite(trial.opt_quat_xyzw), axis=1) & trial.movement
    use &= (t >= ft[0]) & (t <= ft[-1])
    truth = Rotation.from_quat(trial.opt_quat_xyzw[use])
    errors: dict[str, dict[str, float]] = {}
    for name in ESTIMATE_NAMES:
        e = np.degrees(
            attitude_errors(Rotation.from_quat(recon.on_camera_clock(name, t[use])), truth)[0]
        )
        errors[name] = {"mean_deg": float(e.mean()), "max_deg": float(e.max())}
        print(f"{name:<17} error vs optical: mean {e.mean():.3f} deg, max {e.max():.3f} deg")
    return errors


def run_reconstruct(args: argparse.Namespace) -> int:
    _check_inputs(args)
    t, gyr, trial = _read_imu(args.imu)
    summary: dict[str, Any] = {"imu": str(args.imu), "samples": int(np.size(t))}
    ft, fq, fs = _camera_fixes(args, t, trial, summary)
    with tqdm(total=4, unit=" stages", disable=args.no_progress, leave=False) as bar:

        def stage(name: str) -> None:
            bar.set_description(name)
            bar.update(1)

        try:
            recon = reconstruct(t, gyr, ft, fq, fs, progress=stage)
        except ValueError as exc:
            raise SystemExit(f"navtrack attitude reconstruct: {args.imu}: {exc}") from None
    cal = recon.calibration
    summary["fixes"] = int(ft.size)
    summary["calibration"] = {
        "bias_rad_s": cal.bias_rad_s.tolist(),
        "scale": cal.scale.tolist(),
        "time_offset_s": cal.time_offset_s,
        "rms_deg": float(np.degrees(cal.rms_rad)),
        "converged": cal.converged,
    }
    print(f"imu        {args.imu}: {np.size(t)} samples, {ft.size} camera fixes")
    if "fix_status" in summary:
        print("fix status " + ", ".join(f"{k} {v}" for k, v in summary["fix_status"].items()))
    print(
        f"calibrated bias {np.array2string(cal.bias_rad_s, precision=5)} rad/s, scale "
        f"{np.array2string(cal.scale, precision=5)}, time offset {cal.time_offset_s * 1e3:.2f} "
        f"ms, fix rms {np.degrees(cal.rms_rad):.3f} deg"
    )
    if trial is not None:
        summary["error_vs_optical"] = _errors_vs_optical(recon, trial, t, ft)
    if args.out is not None:
        summary.update(_write_pose(args, recon.estimates[args.estimate], t))
    if args.json is not None:
        args.json.write_text(json.dumps(summary, indent=2) + "\n")
    return 0
