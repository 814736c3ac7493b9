"""``navtrack attitude reconstruct IMU --out POSE``: attitude from gyro + camera fixes (paper 6).

The IMU file is a BROAD trial (``.mat``) or a table (CSV/Parquet) with ``t_s`` and
``gyr_x_rad_s``, ``gyr_y_rad_s``, ``gyr_z_rad_s`` (body frame). Camera fixes come from a table
with ``t_s`` (camera clock) and ``qx, qy, qz, qw`` (scalar-last, body -> reference; optional
``sigma_rad``), or are simulated from a BROAD trial's optical truth (``--simulate-fixes``). The
chosen estimate is written with GNSS positions (``--gnss``) as a pose trajectory (CSV/Parquet);
against a BROAD trial the error of every estimate is printed.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

EXAMPLE = "broad_07_undisturbed_fast_rotation_B_30s.mat"
"""The bundled example (``navtrack/data/README.md``)."""

#: The estimates ``--estimate`` can write (:data:`navtrack.attitude.reconstruct.ESTIMATES`).
ESTIMATE_NAMES = ("propagation", "paper_correction", "calibrated", "filter", "smoother")


def register(subparsers: Any) -> None:
    cmd = subparsers.add_parser(
        "attitude",
        help="attitude reconstruction from gyro rates and camera fixes (paper 6)",
        description="Attitude and trajectory reconstruction: gyro quaternion propagation, camera "
        "attitude fixes, the paper's correction quaternion, gyro/timing calibration and an "
        "error-state smoother.",
    )
    sub = cmd.add_subparsers(dest="attitude_command", metavar="SUBCOMMAND")
    rec = sub.add_parser(
        "reconstruct",
        help="reconstruct the attitude of a recording and write the pose trajectory",
        description="Propagate the gyro from the first camera fix, correct it (paper), "
        "calibrate bias/scale/misalignment/timing against the fixes and smooth; write one "
        "estimate as a pose trajectory.",
    )
    rec.add_argument(
        "imu", type=Path, nargs="?", help="BROAD .mat trial or CSV/Parquet with t_s, gyr_*_rad_s"
    )
    rec.add_argument(
        "--example",
        action="store_true",
        help=f"30 s of the bundled BROAD trial {EXAMPLE} (fast rotations) with simulated fixes",
    )
    rec.add_argument(
        "--out",
        type=Path,
        help="write the pose trajectory (.csv or .parquet; without --gnss and --t0-gps-s a pose "
        "table t_s, quaternion, roll/pitch/yaw)",
    )
    rec.add_argument("--fixes", type=Path, help="camera fixes: t_s, qx, qy, qz, qw [, sigma_rad]")
    rec.add_argument(
        "--simulate-fixes",
        action="store_true",
        help="simulate RANSAC-SVD fixes from the optical truth of a BROAD trial (1 Hz, 24 "
        "targets, 1 mrad rays, 20 %% outliers)",
    )
    rec.add_argument("--seed", type=int, default=0, help="seed of the simulated fixes (default 0)")
    rec.add_argument(
        "--fix-sigma-rad",
        type=float,
        default=1e-3,
        help="per-axis fix standard deviation when the fixes file has no sigma_rad (default 1e-3)",
    )
    rec.add_argument(
        "--estimate",
        choices=ESTIMATE_NAMES,
        default="smoother",
        help="estimate written to --out (default smoother)",
    )
    rec.add_argument(
        "--gnss", type=Path, help="GNSS positions (pyins time,lat,lon,alt or solution)"
    )
    rec.add_argument(
        "--gnss-offset-s",
        type=float,
        default=None,
        help="GNSS time of attitude time t is t + offset (default: align the first epochs)",
    )
    rec.add_argument(
        "--t0-gps-s",
        type=float,
        default=0.0,
        help="GPS time (s) of attitude time 0 for the t_gps_s column (default 0: the recording "
        "has no absolute time)",
    )
    rec.add_argument("--json", type=Path, help="write the summary as JSON")
    rec.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    rec.set_defaults(func=run_reconstruct)
    cmd.set_defaults(func=lambda args: cmd.print_help() or 2)


def run_reconstruct(args: argparse.Namespace) -> int:
    """Run ``attitude reconstruct`` (:func:`navtrack.cli.attitude_command.run_reconstruct`)."""
    # The command's body loads numpy, scipy, pandas and the library: imported only when the
    # command runs, so that `navtrack --help`, which registers every command, stays light.
    from navtrack.cli.attitude_command import run_reconstruct as run

    return run(args)
