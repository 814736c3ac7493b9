"""``navtrack pos OBS NAV...``: single point positions of a RINEX file or an Android raw log.

Reads the observations (RINEX 2/3 or Android GnssLogger), the navigation file(s) and optionally
an SP3 file, keeps the epochs ``--ts/--te/--ti`` select, solves them by weighted least squares
with validation or integrity monitoring (:func:`navtrack.positioning.solve_positions`), prints a
summary (epochs, solved, count of each status, and with a reference the mean, RMS and 95 % of
the horizontal, vertical and 3D errors), writes the solution with ``--out`` (CSV, Parquet,
RTKLIB .pos, NMEA GGA+RMC, KML, GPX by suffix) and figures with ``--plot``. ``--conf`` reads an
RTKLIB option file; options given on the command line win over it. An output that cannot be
written (unknown suffix, missing directory, missing extra) is refused before anything is read
(exit 2). The exit code is 1 when no epoch could be solved, the input cannot be read, or the
``--out`` file could not be written.

This module holds the options; the run is :func:`navtrack.cli.pos_run.run_pos`.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from navtrack.cli._options import (
    add_elmask_option,
    add_lenient_option,
    add_out_option,
    add_reference_options,
    add_systems_option,
)

EXAMPLE_OBS = "SEPT078M_120.21O"
EXAMPLE_NAV = "SEPT078M.21P"
EXAMPLE_REF_SOURCE = "station SEPT, cssrlib's xyz_ref (src/navtrack/data/README.md)"
"""Where the reference of the example comes from (cssrlib's xyz_ref of station SEPT)."""
WEIGHTINGS = ("rtklib", "elevation", "cn0", "equal")
# Settings of --systems/--elmask/--iono when neither the command line nor --conf gives them.
DEFAULT_SYSTEMS = "GREJC"
DEFAULT_ELMASK_DEG = 15.0
DEFAULT_IONO = "klobuchar"


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "pos",
        help="single point positioning of a RINEX observation file or an Android raw log",
        description="Single point positions (weighted least squares, multi-GNSS with inter-system "
        "biases, Klobuchar + Saastamoinen, RTKLIB's models and weights) of every epoch. "
        "Differs from RTKLIB 2.4.3 by default in one point: the Galileo group delay is the one "
        "of the ephemeris used, as the ICD specifies; RTKLIB takes that of the satellite's "
        "first record (often F/NAV, BGD 0), which moves multi-GNSS positions by ~0.5 m "
        "(--rtklib-compatible reproduces it; docs/rtklib-users.md).",
    )
    p.add_argument(
        "obs",
        nargs="?",
        type=Path,
        help="RINEX observation file, u-blox UBX log or GnssLogger log",
    )
    p.add_argument(
        "nav",
        nargs="*",
        type=Path,
        help="RINEX navigation file(s) (optional for a UBX log holding ephemerides)",
    )
    p.add_argument("--sp3", type=Path, help="precise orbits/clocks (SP3) instead of broadcast")
    _add_model_options(p)
    _add_epoch_and_output_options(p)
    _add_network_options(p)
    _add_integrity_options(p)
    p.set_defaults(func=run_pos)


def _add_model_options(p: argparse.ArgumentParser) -> None:
    """Systems, elevation mask, weighting, ionosphere, RTKLIB option file and compatibility."""
    add_systems_option(p, None, f"{DEFAULT_SYSTEMS}: all present")
    add_elmask_option(p, None, DEFAULT_ELMASK_DEG)
    add_lenient_option(p)
    p.add_argument(
        "--weighting",
        choices=WEIGHTINGS,
        default=None,
        help="measurement weighting model (default: rtklib for RINEX, cn0 for Android logs)",
    )
    p.add_argument(
        "--iono",
        choices=("klobuchar", "ionofree", "off"),
        help=f"ionosphere: broadcast Klobuchar, dual-frequency iono-free, or none "
        f"(default {DEFAULT_IONO})",
    )
    p.add_argument(
        "--conf",
        type=Path,
        metavar="FILE",
        help="RTKLIB option file (rnx2rtkp -k): elevation mask, systems, ionosphere, "
        "troposphere, ephemeris, frequency, GDOP limit; other options must keep RTKLIB's "
        "defaults; command-line options win",
    )
    p.add_argument(
        "--rtklib-compatible",
        action="store_true",
        help="take each satellite's group delay from its first navigation record, as RTKLIB "
        "2.4.3 does (Galileo F/NAV: none), to match an existing RTKLIB pipeline",
    )


def _add_epoch_and_output_options(p: argparse.ArgumentParser) -> None:
    """Epoch selection, reference, outputs, the example and the progress bar."""
    p.add_argument(
        "--ts",
        nargs="+",
        metavar="TIME",
        help="first epoch, GPST: 2005/04/02 00:10:00 (as RTKLIB's -ts) or ISO 8601",
    )
    p.add_argument("--te", nargs="+", metavar="TIME", help="last epoch, GPST (as --ts)")
    p.add_argument(
        "--ti",
        type=float,
        metavar="SEC",
        help="interval: keep only epochs on this grid of the GPS week (RTKLIB's -ti)",
    )
    add_reference_options(p)
    add_out_option(p, "write the solution (.csv, .parquet, .pos RTKLIB, .nmea GGA+RMC, .kml, .gpx)")
    p.add_argument("--plot", type=Path, metavar="DIR", help="write figures into this directory")
    p.add_argument(
        "--example",
        action="store_true",
        help=f"run on the bundled {EXAMPLE_OBS} + {EXAMPLE_NAV}; errors against "
        f"{EXAMPLE_REF_SOURCE}",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _add_network_options(p: argparse.ArgumentParser) -> None:
    """Several observation files: workers or a Dask scheduler."""
    net = p.add_argument_group(
        "network",
        "several observation files (a station network): one Parquet dataset partitioned by "
        "station under --out DIR/positions, per-station summaries in DIR/stations.csv, resumable; "
        "navigation files given serve every station, else those beside each file",
    )
    net.add_argument(
        "--workers", type=int, metavar="N", help="N local worker processes (Dask multiprocessing)"
    )
    net.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler")


def _add_integrity_options(p: argparse.ArgumentParser) -> None:
    """Integrity monitoring (:mod:`navtrack.integrity.raim`): method, probabilities, ISM,
    alert limits."""
    p.add_argument(
        "--raim",
        choices=("off", "chi2", "loo", "fde", "ss", "fcm", "araim"),
        default="off",
        help="integrity monitoring: chi-square test only, leave-one-out (RTKLIB-like), "
        "iterative exclusion, solution separation (up to 2 faults), fuzzy c-means, "
        "ARAIM multiple-hypothesis solution separation (default off)",
    )
    p.add_argument("--pfa", type=float, default=1e-3, help="false-alarm probability (1e-3)")
    p.add_argument("--pmd", type=float, default=1e-3, help="missed-detection probability (1e-3)")
    p.add_argument(
        "--ism",
        metavar="FILE",
        help="integrity support message (TOML) behind every protection level "
        "(default: the ARAIM ADD baseline, navtrack/data/ism_add.toml)",
    )
    p.add_argument("--hal", type=float, default=40.0, help="horizontal alert limit, m (40)")
    p.add_argument("--val", type=float, default=35.0, help="vertical alert limit, m (35)")


def run_pos(args: argparse.Namespace) -> int:
    """Run the command (:func:`navtrack.cli.pos_run.run_pos`)."""
    # the solver and its readers are imported when the command runs, not when it is registered
    from navtrack.cli import pos_run

    return pos_run.run_pos(args)
