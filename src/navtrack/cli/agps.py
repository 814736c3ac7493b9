"""``navtrack agps OBS NAV --sats G05,G12 --epochs T1 T2 --height H --approx LAT LON``: one
two-satellite AGPS fix (Li 2010) from real pseudoranges.

Reads the observations (RINEX 2/3 or Android GnssLogger) and the navigation file, takes the GPS
L1 pseudoranges of the two satellites at the two epochs, corrects them with the SPP stages
(satellite clock, group delay) and the broadcast ionosphere and the troposphere at the
approximate (cell) position, and solves the five equations of :mod:`navtrack.gnss.agps` from the
cell position with the chosen solver: the AGPS pipeline of :mod:`navtrack.positioning.agps`.
Prints the fix, its clock biases, iterations, DOP and status (with the reason of a
``weak_geometry`` or ``implausible`` fix), and with ``--ref`` its error; ``--out FILE.json``
writes the same. Exit code 1 when the fix is not ``ok``. ``--example`` solves a fix of the
bundled 0759 station file.

A fix is ``ok`` only when its predicted 3-D error ``dop x sigma_pr`` is at most ``--max-sigma``
(300 m) and its pseudorange residuals close to three ``sigma_pr``; ``sigma_pr`` is the
receiver's pseudorange noise estimated from the whole file's single point residuals
(:func:`navtrack.positioning.agps.pseudorange_sigma_m`), or ``--sigma-pr``. The default solver is
Gauss–Newton: on the real data of the reproduction it has the lowest mean error on every
station at every interval (``docs/agps.md``).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.cli._options import add_out_option, add_reference_options, is_android_log, reference
from navtrack.data import REFERENCE_XYZ_M, sample_path
from navtrack.geodesy import ecef_to_geodetic, enu_rotation, geodetic_to_ecef
from navtrack.gnss.agps import AgpsConfig, AgpsResult, AgpsStatus
from navtrack.gnss.spp import Measurements, SppConfig
from navtrack.positioning.agps import (
    assisted_pseudoranges,
    pseudorange_sigma_m,
    read_gps_measurements,
    solve_fixes,
)
from navtrack.timescale import gps_seconds, to_datetime64

ASSUMED_SIGMA_PR_M = 3.0
"""Pseudorange noise assumed when the file cannot tell (no epoch with five satellites): the
weak-signal phone of the reproduction's calibration."""


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "agps",
        help="two-satellite AGPS fix from two epochs (Marquardt / Gauss-Newton / MAP)",
        description="Position from two GPS satellites observed at two epochs, one receiver clock "
        "bias per epoch and an assumed height (Li 2010), starting at the cell position.",
    )
    p.add_argument("obs", type=Path, nargs="?", help="RINEX observation file or GnssLogger log")
    p.add_argument("nav", type=Path, nargs="?", help="RINEX navigation file (GPS ephemerides)")
    p.add_argument(
        "--example",
        action="store_true",
        help="a fix of the bundled 0759 station file: " + " ".join(EXAMPLE[2:]),
    )
    p.add_argument("--sats", help="the two GPS satellites, e.g. G05,G12")
    p.add_argument(
        "--epochs",
        nargs=2,
        metavar=("T1", "T2"),
        help="the two epochs: GPST calendar times (2005-04-02T00:10:00) or GPS seconds",
    )
    p.add_argument("--height", type=float, metavar="H", help="assumed ellipsoidal height, m")
    p.add_argument(
        "--approx",
        nargs=2,
        type=float,
        metavar=("LAT", "LON"),
        help="cell (base-station) position, degrees; its height is --height",
    )
    p.add_argument("--solver", choices=("gn", "lm", "map"), default="gn", help="default gn")
    p.add_argument(
        "--max-sigma",
        type=float,
        default=300.0,
        metavar="M",
        help="a fix whose predicted 3-D error dop x sigma_pr exceeds M metres is weak_geometry "
        "(default 300; inf: off)",
    )
    p.add_argument(
        "--sigma-pr",
        type=float,
        metavar="M",
        help="pseudorange noise, m (default: estimated from the file's single point residuals)",
    )
    p.add_argument(
        "--max-dop",
        type=float,
        default=float("inf"),
        metavar="D",
        help="geometry screen: a fix with a larger DOP is weak_geometry (default: off)",
    )
    add_out_option(p, "write the fix as JSON", metavar="FILE.json")
    p.add_argument(
        "--prior-sigma",
        type=float,
        default=3000.0,
        metavar="M",
        help="map: standard deviation of the cell position as prior, m (default 3000)",
    )
    add_reference_options(p)
    p.set_defaults(func=run_agps)


EXAMPLE = (
    "07590920.05o",
    "07590920.05n",
    "--sats",
    "G07,G24",
    "--epochs",
    "2005-04-02T00:10:00",
    "2005-04-02T00:20:00",
    "--height",
    "68.4",
    "--approx",
    "35.2",
    "139.6",
)
"""The bundled example: 0759 (GSI, RINEX 2), two satellites ten minutes apart, a cell about
15 km away; errors against the station's reference (``navtrack/data/README.md``)."""


def _example_args(args: argparse.Namespace) -> None:
    """Fill ``args`` from :data:`EXAMPLE` (explicit options other than the files win)."""
    if args.obs is not None or args.nav is not None:
        raise SystemExit("navtrack agps: give either OBS NAV or --example, not both")
    args.obs, args.nav = sample_path(EXAMPLE[0]), sample_path(EXAMPLE[1])
    args.sats = args.sats or EXAMPLE[3]
    args.epochs = args.epochs or list(EXAMPLE[5:7])
    args.height = float(EXAMPLE[8]) if args.height is None else args.height
    args.approx = args.approx or [float(EXAMPLE[10]), float(EXAMPLE[11])]
    if args.ref is None and args.ref_llh is None:
        args.ref = list(REFERENCE_XYZ_M[EXAMPLE[0]])


def _gps_time(text: str) -> float:
    """GPS seconds of a GPST calendar time or of a number of GPS seconds."""
    try:
        return float(text)
    except ValueError:
        pass
    try:
        return float(gps_seconds(text))
    except ValueError:
        raise SystemExit(
            f"navtrack agps: --epochs {text!r} is neither a GPST calendar time "
            "(YYYY-MM-DDTHH:MM:SS) nor GPS seconds"
        ) from None


def run_agps(args: argparse.Namespace) -> int:
    """Run ``navtrack agps``; exit code 1 when the fix is not ``ok``."""
    if args.example:
        _example_args(args)
    sats = _check_args(args)
    ref = reference(args)
    times = [_gps_time(t) for t in args.epochs]
    cfg = SppConfig(systems="G")
    _, _, meas = read_gps_measurements(args.obs, args.nav, cfg, android=is_android_log(args.obs))
    lat, lon = args.approx
    cell = geodetic_to_ecef([math.radians(lat), math.radians(lon), args.height])
    y = assisted_pseudoranges(meas, cell, cfg)
    if args.sigma_pr is not None:
        sigma_pr, sigma_from = args.sigma_pr, "--sigma-pr"
    else:
        sigma_pr, sigma_from = pseudorange_sigma_m(meas, cfg), "single point residuals of the file"
        if not math.isfinite(sigma_pr):
            sigma_pr, sigma_from = ASSUMED_SIGMA_PR_M, "assumed: no epoch with five satellites"
    epochs = [_epoch_index(args, meas, text, t) for text, t in zip(args.epochs, times, strict=True)]
    if epochs[0] == epochs[1]:
        raise SystemExit(
            f"navtrack agps: --epochs {args.epochs[0]} {args.epochs[1]}: same epoch twice"
        )
    cols = _satellite_columns(args, meas, y, sats, epochs)
    try:
        config = AgpsConfig.for_receiver(
            sigma_pr, args.max_sigma, prior_sigma_m=args.prior_sigma, max_dop=args.max_dop
        )
        res = solve_fixes(
            meas, y, np.array([epochs]), np.array([cols]), args.height, cell, args.solver, config
        )
    except ValueError as exc:
        raise SystemExit(f"navtrack agps: {exc}") from None
    dt = (meas.t_gps_s[epochs[1]] - meas.t_gps_s[epochs[0]]) / 60.0
    record = _report(args, res, sats, dt, (sigma_pr, sigma_from), ref)
    if args.out is not None:
        args.out.write_text(json.dumps(record, indent=2) + "\n")
        print(f"wrote       {args.out}")
    return 0 if res.status[0] == AgpsStatus.OK else 1


def _check_args(args: argparse.Namespace) -> list[str]:
    """Refuse missing or malformed options; the two satellites."""
    missing = [
        name
        for name, value in (("OBS", args.obs), ("NAV", args.nav), ("--sats", args.sats),
                            ("--epochs", args.epochs), ("--height", args.height),
                            ("--approx", args.approx))
        if value is None
    ]  # fmt: skip
    if missing:
        raise SystemExit(f"navtrack agps: missing {', '.join(missing)} (or use --example)")
    if args.out is not None and args.out.suffix.lower() != ".json":
        raise SystemExit(f"navtrack agps: --out {args.out}: expected a .json file")
    sats = [s.strip().upper() for s in args.sats.split(",") if s.strip()]
    if len(sats) != 2 or len(set(sats)) != 2:
        raise SystemExit(f"navtrack agps: --sats needs two different satellites, got {args.sats!r}")
    if any(s[0] != "G" for s in sats):
        raise SystemExit(f"navtrack agps: --sats must be GPS satellites (Gnn), got {args.sats!r}")
    lat, lon = args.approx
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0):
        raise SystemExit(
            f"navtrack agps: --approx {lat:g} {lon:g} is not latitude/longitude in deg"
        )
    return sats


def _epoch_index(args: argparse.Namespace, meas: Measurements, text: str, t: float) -> int:
    """The measurement epoch at ``t`` (within 0.5 s), or ``SystemExit`` naming the file's span."""
    k = int(np.argmin(np.abs(meas.t_gps_s - t))) if meas.t_gps_s.size else -1
    if k < 0 or abs(meas.t_gps_s[k] - t) > 0.5:
        span = (
            f"{to_datetime64(meas.t_gps_s[0])} .. {to_datetime64(meas.t_gps_s[-1])}"
            if meas.t_gps_s.size
            else "no epochs"
        )
        raise SystemExit(f"navtrack agps: {args.obs}: no epoch at {text} (file spans {span})")
    return k


def _satellite_columns(
    args: argparse.Namespace,
    meas: Measurements,
    y: np.ndarray,
    sats: list[str],
    epochs: list[int],
) -> list[int]:
    """The satellite axis index of each of the two satellites, each checked to have a corrected
    pseudorange at both epochs (``SystemExit`` saying why not)."""
    cols = []
    for s in sats:
        if s not in meas.sats:
            raise SystemExit(f"navtrack agps: {args.obs}: satellite {s} is never observed")
        cols.append(meas.sats.index(s))
    for s, c in zip(sats, cols, strict=True):
        for text, k in zip(args.epochs, epochs, strict=True):
            if not np.isfinite(y[k, c]):
                why = (
                    "not observed"
                    if not meas.observed[k, c]
                    else "without a usable ephemeris in " + str(args.nav)
                    if not meas.usable[k, c]
                    else "below the elevation mask seen from the cell"
                )
                raise SystemExit(f"navtrack agps: {args.obs}: {s} at {text} is {why}")
    return cols


def _report(
    args: argparse.Namespace,
    res: AgpsResult,
    sats: list[str],
    dt: float,
    sigma: tuple[float, str],
    ref: tuple[float, float, float] | None,
) -> dict[str, Any]:
    """Print the fix (and its error against the reference); the JSON record of ``--out``.
    ``sigma`` is the pseudorange noise (m) and where it comes from."""
    sigma_pr, sigma_from = sigma
    status = AgpsStatus(int(res.status[0])).name.lower()
    record: dict[str, Any] = {
        "solver": args.solver,
        "sats": sats,
        "interval_min": dt,
        "status": status,
        "reason": str(res.reason[0]),
        "iterations": int(res.iterations[0]),
        "dop": float(res.dop[0]),
        "sigma_pr_m": sigma_pr,
        "predicted_error_m": float(res.sigma_m[0]),
    }
    print(f"solver      {args.solver}   satellites {sats[0]},{sats[1]}   interval {dt:.2f} min")
    reason = f"   ({res.reason[0]})" if res.reason[0] else ""
    print(f"status      {status}   iterations {int(res.iterations[0])}{reason}")
    print(f"accuracy    dop {res.dop[0]:.0f} x sigma_pr {sigma_pr:.2f} m ({sigma_from}) = "
          f"{res.sigma_m[0]:.0f} m predicted 3-D error (1 sigma)")  # fmt: skip
    if not np.isfinite(res.pos_m[0]).all():
        return record
    xyz = res.pos_m[0]
    llh = ecef_to_geodetic(xyz)
    print(
        f"position    lat {math.degrees(llh[0]):.6f} deg  lon {math.degrees(llh[1]):.6f} deg  "
        f"h {llh[2]:.1f} m"
    )
    print(f"ecef        {xyz[0]:.1f} {xyz[1]:.1f} {xyz[2]:.1f} m")
    print(f"height      {res.height_residual_m[0]:+.1f} m from the assumed height")
    print(f"clocks      c*dt1 {res.clock_m[0, 0]:.1f} m  c*dt2 {res.clock_m[0, 1]:.1f} m")
    print(f"residuals   {res.residual_m[0]:.1f} m rms")
    record.update({
        "lat_deg": math.degrees(llh[0]),
        "lon_deg": math.degrees(llh[1]),
        "height_m": float(llh[2]),
        "x_m": float(xyz[0]), "y_m": float(xyz[1]), "z_m": float(xyz[2]),
        "height_residual_m": float(res.height_residual_m[0]),
        "clock1_m": float(res.clock_m[0, 0]),
        "clock2_m": float(res.clock_m[0, 1]),
        "residual_m": float(res.residual_m[0]),
    })  # fmt: skip
    if ref is not None:
        ref_m = np.asarray(ref, dtype=float)
        rl = ecef_to_geodetic(ref_m)
        enu = enu_rotation(rl[0], rl[1]) @ (xyz - ref_m)
        print(
            f"error       3-D {np.linalg.norm(enu):.1f} m  horizontal "
            f"{np.hypot(enu[0], enu[1]):.1f} m  (E {enu[0]:.1f}, N {enu[1]:.1f}, "
            f"U {enu[2]:.1f} m)"
        )
        record["error_m"] = float(np.linalg.norm(enu))
        record["horizontal_error_m"] = float(np.hypot(enu[0], enu[1]))
    return record
