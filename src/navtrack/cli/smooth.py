"""``navtrack smooth FILE``: ARI filtering, variance components and gross errors of time series."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def register(subparsers: Any) -> None:
    cmd = subparsers.add_parser(
        "smooth",
        help="ARI filtering of time series: sigma_n, sigma_e, sigma_x, r(h), gross errors",
        description="Model each column as an ARI(p,d) process observed with white noise "
        "(Lindenberger): estimate the filtered series, the observation noise sigma_n, the "
        "prediction error sigma_e, sigma_x per epoch, r(1..4) and gross errors, without a-priori "
        "stochastic information. Reads CSV/Parquet tables, navtrack solution tables and RTKLIB "
        ".pos files; gaps in the time stamps become missing epochs, and so do the rows of a "
        "solution table whose status is not ok.",
    )
    cmd.add_argument(
        "file",
        type=Path,
        nargs="?",
        help="CSV, Parquet, navtrack solution table or RTKLIB .pos",
    )
    cmd.add_argument(
        "--example",
        action="store_true",
        help="smooth the single point positions of the bundled 0759 station file (120 epochs "
        "at 30 s, 5 of them high_dop)",
    )
    cmd.add_argument(
        "--columns",
        nargs="+",
        help="columns to smooth (comma- or space-separated); default for solution files the "
        "position in --frame, else every numeric column except the time",
    )
    cmd.add_argument(
        "--frame",
        default="enu",
        choices=("enu", "ecef"),
        help="solution files: smooth east/north/up about the mean position (e_m n_m u_m, "
        "default) or ECEF x_m y_m z_m",
    )
    cmd.add_argument("--time", help="time column in seconds (default: t_gps_s, t_s, time, t)")
    cmd.add_argument("--order", default="auto", help="'auto' (BIC) or P,D (default auto)")
    cmd.add_argument(
        "--robust",
        default="danish",
        choices=("danish", "huber", "igg3", "off"),
        help="robust weight function (default danish)",
    )
    cmd.add_argument(
        "--robust-process",
        action="store_true",
        help="also reweight the process equations (edges, discontinuities)",
    )
    cmd.add_argument(
        "--estimator",
        default="exact",
        choices=("exact", "paper"),
        help="exact likelihood (default) or the paper's alternating filtering/VCE iteration",
    )
    cmd.add_argument(
        "--vce",
        default="redundancy",
        choices=("redundancy", "forstner"),
        help="variance components of --estimator paper: exact redundancy numbers (default) or "
        "Förstner's frequency-domain form",
    )
    cmd.add_argument(
        "--flag-threshold",
        type=float,
        default=3.29,
        help="|T| above which an epoch is a gross error (default 3.29)",
    )
    cmd.add_argument("--out", type=Path, help="write filtered series (.csv or .parquet)")
    cmd.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    cmd.add_argument(
        "--plot", type=Path, metavar="DIR", help="write one PNG per column into this directory"
    )
    cmd.set_defaults(func=run_smooth)


def run_smooth(args: argparse.Namespace) -> int:
    """Run the command (:func:`navtrack.cli.smooth_command.run`)."""
    # The command's body loads numpy, pandas, scipy and the library: imported only when the
    # command runs, so that `navtrack --help`, which registers every command, stays light.
    from navtrack.cli.smooth_command import run

    return run(args)
