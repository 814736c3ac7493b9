"""``navtrack agps OBS NAV --sats G05,G12 --epochs T1 T2 --height H --approx LAT LON``: one
two-satellite AGPS fix (Li 2010) from real pseudoranges.

Reads the observations (RINEX 2/3 or Android GnssLogger) and the navigation file, takes the GPS
L1 pseudoranges of the two satellites at the two epochs, corrects them with the SPP stages
(satellite clock, group delay) and the broadcast ionosphere and the troposphere at the
approximate (cell) position (:func:`navtrack.gnss.agps.assisted_pseudoranges`), and solves the
five equations of :mod:`navtrack.gnss.agps` from the cell position with the chosen solver.
Prints the fix, its clock biases, iterations and status, and with ``--ref`` its error. Exit
code 1 when the fix is not ``ok``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "agps",
        help="two-satellite AGPS fix from two epochs (Marquardt / Gauss-Newton / MAP)",
        description="Position from two GPS satellites observed at two epochs, one receiver clock "
        "bias per epoch and an assumed height (Li 2010), starting at the cell position.",
    )
    p.add_argument("obs", type=Path, help="RINEX observation file or GnssLogger log")
    p.add_argument("nav", type=Path, help="RINEX navigation file (GPS ephemerides)")
    p.add_argument("--sats", required=True, help="the two GPS satellites, e.g. G05,G12")
    p.add_argument(
        "--epochs",
        nargs=2,
        required=True,
        metavar=("T1", "T2"),
        help="the two epochs: GPST calendar times (2005-04-02T00:10:00) or GPS seconds",
    )
    p.add_argument(
        "--height", type=float, required=True, metavar="H", help="assumed ellipsoidal height, m"
    )
    p.add_argument(
        "--approx",
        nargs=2,
        type=float,
        required=True,
        metavar=("LAT", "LON"),
        help="cell (base-station) position, degrees; its height is --height",
    )
    p.add_argument("--solver", choices=("gn", "lm", "map"), default="lm", help="default lm")
    p.add_argument(
        "--prior-sigma",
        type=float,
        default=3000.0,
        metavar="M",
        help="map: standard deviation of the cell position as prior, m (default 3000)",
    )
    p.add_argument(
        "--ref", nargs=3, type=float, metavar=("X", "Y", "Z"), help="reference, ECEF metres"
    )
    p.set_defaults(func=run_agps)


def _gps_time(text: str) -> float:
    """GPS seconds of a GPST calendar time or of a number of GPS seconds."""
    try:
        return float(text)
    except ValueError:
        pass
    from navtrack.timescale import gps_seconds

    try:
        return float(gps_seconds(text))
    except ValueError:
        raise SystemExit(
            f"navtrack agps: --epochs {text!r} is neither a GPST calendar time "
            "(YYYY-MM-DDTHH:MM:SS) nor GPS seconds"
        ) from None


def run_agps(args: argparse.Namespace) -> int:
    import numpy as np

    from navtrack.cli.pos import _is_android
    from navtrack.geodesy import ecef_to_geodetic, enu_rotation, geodetic_to_ecef
    from navtrack.gnss.agps import (
        AgpsConfig,
        AgpsStatus,
        assisted_pseudoranges,
        problem_from_measurements,
        solve_agps,
    )
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.spp import (
        SppConfig,
        code_pseudoranges,
        corrected_measurements,
        satellite_states,
    )
    from navtrack.timescale import to_datetime64

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
    times = [_gps_time(t) for t in args.epochs]
    if _is_android(args.obs):
        from navtrack.gnss.android import read_gnsslogger

        obs = read_gnsslogger(args.obs)
    else:
        from navtrack.gnss.rinex.obs import read_obs

        obs = read_obs(args.obs)
    nav = read_nav(args.nav)
    cfg = SppConfig(systems="G")
    pr = code_pseudoranges(obs, cfg)
    meas = corrected_measurements(pr, satellite_states(pr, nav, config=cfg), cfg)
    cell = geodetic_to_ecef([math.radians(lat), math.radians(lon), args.height])
    y = assisted_pseudoranges(meas, cell, cfg)
    epochs = []
    for text, t in zip(args.epochs, times, strict=True):
        k = int(np.argmin(np.abs(meas.t_gps_s - t))) if meas.t_gps_s.size else -1
        if k < 0 or abs(meas.t_gps_s[k] - t) > 0.5:
            span = (
                f"{to_datetime64(meas.t_gps_s[0])} .. {to_datetime64(meas.t_gps_s[-1])}"
                if meas.t_gps_s.size
                else "no epochs"
            )
            raise SystemExit(f"navtrack agps: {args.obs}: no epoch at {text} (file spans {span})")
        epochs.append(k)
    if epochs[0] == epochs[1]:
        raise SystemExit(
            f"navtrack agps: --epochs {args.epochs[0]} {args.epochs[1]}: same epoch twice"
        )
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
    try:
        problem = problem_from_measurements(
            meas, y, np.array([epochs]), np.array([cols]), args.height, cell
        )
        config = AgpsConfig(prior_sigma_m=args.prior_sigma)
    except ValueError as exc:
        raise SystemExit(f"navtrack agps: {exc}") from None
    res = solve_agps(problem, args.solver, config)
    status = AgpsStatus(int(res.status[0])).name.lower()
    dt = (meas.t_gps_s[epochs[1]] - meas.t_gps_s[epochs[0]]) / 60.0
    print(f"solver      {args.solver}   satellites {sats[0]},{sats[1]}   interval {dt:.2f} min")
    print(f"status      {status}   iterations {int(res.iterations[0])}")
    if res.status[0] in (AgpsStatus.OK, AgpsStatus.NO_CONVERGENCE):
        xyz = res.pos_m[0]
        llh = ecef_to_geodetic(xyz)
        print(
            f"position    lat {math.degrees(llh[0]):.6f} deg  lon {math.degrees(llh[1]):.6f} deg  "
            f"h {llh[2]:.1f} m"
        )
        print(f"ecef        {xyz[0]:.1f} {xyz[1]:.1f} {xyz[2]:.1f} m")
        print(f"height      {res.height_residual_m[0]:+.1f} m from the assumed height")
        print(f"clocks      c*dt1 {res.clock_m[0, 0]:.1f} m  c*dt2 {res.clock_m[0, 1]:.1f} m")
        if args.ref is not None:
            ref = np.asarray(args.ref, dtype=float)
            rl = ecef_to_geodetic(ref)
            enu = enu_rotation(rl[0], rl[1]) @ (xyz - ref)
            print(
                f"error       3-D {np.linalg.norm(enu):.1f} m  horizontal "
                f"{np.hypot(enu[0], enu[1]):.1f} m  (E {enu[0]:.1f}, N {enu[1]:.1f}, "
                f"U {enu[2]:.1f} m)"
            )
    return 0 if res.status[0] == AgpsStatus.OK else 1
