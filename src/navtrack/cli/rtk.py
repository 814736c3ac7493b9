"""``navtrack rtk ROVER BASE NAV...``: carrier-phase relative positions of a rover against a base.

Reads the rover and base observations (RINEX), the navigation file(s) and optionally an SP3
file, solves every rover epoch with double-differenced code and carrier phase and integer
ambiguities (:func:`navtrack.gnss.relative.solve_relative`), prints a summary (epochs of each
receiver and in common, count of each status, fix rate, slips per detector, ratio-test values,
input warnings, and with ``--ref``/``--ref-pos`` the error statistics), and writes the solution
with ``--out`` (CSV, Parquet, NMEA GGA, KML, GPX by suffix) with RTKLIB's ``quality`` column.
The exit code is 1 when no epoch has a relative solution or the input cannot be read.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

from navtrack.cli._options import (
    add_elmask_option,
    add_lenient_option,
    add_out_option,
    add_reference_options,
    add_systems_option,
    reference,
)
from navtrack.cli.inputs import is_raw_log, read_observations
from navtrack.cli.outputs import check_outputs
from navtrack.data import REFERENCE_XYZ_M, sample_path
from navtrack.geodesy import geodetic_to_ecef
from navtrack.gnss.ambiguity import AmbiguityConfig
from navtrack.gnss.relative import (
    AFTER_RATIO_TEST,
    STATUS_NAMES,
    RtkConfig,
    RtkResult,
    solution_frame,
    solve_relative,
)
from navtrack.gnss.rinex.nav import NavData, read_nav
from navtrack.gnss.rtcm import is_rtcm3, read_rtcm
from navtrack.gnss.sp3 import Sp3, read_sp3
from navtrack.io.solution import FORMATS, write_solution

if TYPE_CHECKING:
    from navtrack._typing import FloatArray
    from navtrack.gnss.observations import Observations


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "rtk",
        help="carrier-phase relative positioning (RTK) of a rover against a base",
        description="Double-differenced code and carrier phase, Kalman filter (kinematic) or "
        "least squares (static), integer ambiguities by LAMBDA with the ratio test.",
    )
    p.add_argument(
        "rover", type=Path, nargs="?", help="rover RINEX observation file or u-blox UBX log"
    )
    p.add_argument(
        "base",
        type=Path,
        nargs="?",
        help="base RINEX observation file, u-blox UBX log or RTCM 3 file (MSM4-7)",
    )
    p.add_argument(
        "nav",
        nargs="*",
        type=Path,
        help="RINEX navigation file(s) (optional when a UBX log holds ephemerides)",
    )
    p.add_argument(
        "--example",
        action="store_true",
        help="static L1+L2 baseline of the bundled GEONET stations 0759 (rover) and 3040 (base, "
        "3.3 km), against 0759's reference",
    )
    _add_base_options(p)
    p.add_argument("--static", action="store_true", help="static rover (default kinematic)")
    p.add_argument(
        "--direction",
        choices=("forward", "backward", "combined"),
        default="forward",
        help="filter direction; combined = forward and backward joined (RTKLIB -c)",
    )
    add_systems_option(p, "GECJ")
    p.add_argument(
        "--freq", type=int, choices=(1, 2), default=1, help="frequencies: 1 (L1) or 2 (L1+L2)"
    )
    add_elmask_option(p, 15.0)
    add_lenient_option(p)
    _add_fix_options(p)
    p.add_argument("--sp3", type=Path, help="precise orbits/clocks (SP3) instead of broadcast")
    add_reference_options(p, trajectory=True)
    add_out_option(p, "write the solution (.csv, .parquet, .nmea, .kml, .gpx)")
    p.add_argument("--plot", type=Path, metavar="DIR", help="write figures into this directory")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run_rtk)


_DEFAULTS = RtkConfig()


def _add_base_options(p: argparse.ArgumentParser) -> None:
    """The base position (default: the base file's header position)."""
    base = p.add_mutually_exclusive_group()
    base.add_argument(
        "--base-pos", nargs=3, type=float, metavar=("X", "Y", "Z"), help="base ECEF metres"
    )
    base.add_argument(
        "--base-llh",
        nargs=3,
        type=float,
        metavar=("LAT", "LON", "H"),
        help="base position, degrees and ellipsoidal metres",
    )


def _add_fix_options(p: argparse.ArgumentParser) -> None:
    """Ambiguity resolution, its validation and the base age."""
    p.add_argument("--ratio", type=float, default=3.0, help="ratio-test threshold (default 3)")
    p.add_argument("--partial", action="store_true", help="partial ambiguity fixing")
    p.add_argument("--float", action="store_true", help="no integer fixing (float solution)")
    p.add_argument(
        "--elmask-ar",
        type=float,
        default=0.0,
        metavar="DEG",
        help="elevation mask of ambiguity resolution (the larger of it and --elmask applies)",
    )
    p.add_argument(
        "--min-fix-sats",
        type=int,
        default=_DEFAULTS.min_fix_sats,
        metavar="N",
        help="fewest satellites with fixable ambiguities for a fix",
    )
    p.add_argument(
        "--max-age-ar",
        type=float,
        default=_DEFAULTS.max_age_ar_s,
        metavar="S",
        help="resolve ambiguities only with base observations up to this old (s)",
    )
    p.add_argument(
        "--min-success-rate",
        type=float,
        default=_DEFAULTS.min_success_rate,
        metavar="P",
        help="fewest bootstrapped success rate of a full fix (0: no such test)",
    )
    p.add_argument(
        "--hold", action="store_true", help="fix-and-hold: feed validated fixes to the filter"
    )
    p.add_argument(
        "--float-position-test",
        action="store_true",
        help="refuse a fix outside the float position's confidence region (off: the float "
        "covariance is optimistic where code multipath is correlated in time)",
    )
    p.add_argument(
        "--max-age",
        type=float,
        default=_DEFAULTS.max_age_s,
        metavar="S",
        help="use base observations up to this old (s)",
    )


RTK_EXAMPLE = ("07590920.05o", "30400920.05o", "07590920.05n")
"""The bundled files of ``rtk --example`` (``navtrack/data/README.md``)."""


def _base_position(args: argparse.Namespace) -> tuple[FloatArray, str]:
    if args.base_pos is not None:
        return np.asarray(args.base_pos, dtype=float), "--base-pos"
    if args.base_llh is not None:
        lat, lon, h = args.base_llh
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0):
            raise SystemExit(f"navtrack rtk: --base-llh {lat:g} {lon:g} {h:g} is not in degrees")
        return geodetic_to_ecef([math.radians(lat), math.radians(lon), h]), "--base-llh"
    return np.full(3, np.nan), "header"


def reference_errors(
    t_gps_s: FloatArray, pos_m: FloatArray, args: argparse.Namespace
) -> tuple[FloatArray, str] | None:
    """Per-epoch 3-D error (m, NaN where not compared) against ``--ref``/``--ref-llh`` or the
    epochs of ``--ref-pos`` (same time tags to 1 ms), and a label; None without a reference."""
    if args.ref_pos is not None:
        from navtrack.io.rtklib import read_pos  # pandas: only with --ref-pos

        ref = read_pos(args.ref_pos)
        kr = np.round(ref["t_gps_s"].to_numpy() * 1e3).astype(np.int64)
        kn = np.round(t_gps_s * 1e3).astype(np.int64)
        _, a, b = np.intersect1d(kn, kr, return_indices=True)
        err = np.full(t_gps_s.size, np.nan)
        xyz = ref[["x_m", "y_m", "z_m"]].to_numpy()[b]
        err[a] = np.linalg.norm(pos_m[a] - xyz, axis=1)
        return err, f"{args.ref_pos} ({a.size} epochs in common)"
    point = reference(args)
    if point is None:
        return None
    return np.linalg.norm(pos_m - np.asarray(point), axis=1), "reference point"


def _example_inputs(args: argparse.Namespace) -> None:
    """``--example``: the bundled GEONET baseline, static, L1+L2, with its reference."""
    if args.rover is not None:
        raise SystemExit("navtrack rtk: give either ROVER BASE NAV... or --example, not both")
    args.rover, args.base, nav = (sample_path(name) for name in RTK_EXAMPLE)
    args.nav = [nav]
    args.static, args.freq = True, 2
    if args.base_pos is None and args.base_llh is None:
        args.base_pos = list(REFERENCE_XYZ_M[RTK_EXAMPLE[1]])
    if args.ref is None and args.ref_llh is None and args.ref_pos is None:
        args.ref = list(REFERENCE_XYZ_M[RTK_EXAMPLE[0]])


def _rtk_config(args: argparse.Namespace) -> RtkConfig:
    try:
        return RtkConfig(
            mode="static" if args.static else "kinematic",
            systems="".join(dict.fromkeys(args.systems.upper())),
            frequencies=args.freq,
            elmask_deg=args.elmask,
            elmask_ar_deg=args.elmask_ar,
            min_fix_sats=args.min_fix_sats,
            max_age_ar_s=args.max_age_ar,
            min_success_rate=args.min_success_rate,
            hold=args.hold,
            float_position_test=args.float_position_test,
            max_age_s=args.max_age,
            ambiguity=AmbiguityConfig(ratio_threshold=args.ratio, partial=args.partial),
            fix=not args.float,
            direction=args.direction,
        )
    except ValueError as exc:
        raise SystemExit(f"navtrack rtk: {exc}") from None


def _read_inputs(
    args: argparse.Namespace,
) -> tuple[Observations, Observations, list[NavData], Sp3 | None, FloatArray, str]:
    """Rover, base, navigation data, SP3 and the base position with its source."""
    base_xyz, base_src = _base_position(args)
    rover, rover_nav = read_observations(args.rover, lenient=args.lenient)
    base_nav = None
    if args.base.is_file() and is_rtcm3(args.base):
        log = read_rtcm(args.base, float(np.median(rover.t_gps_s)))
        base = log.obs
        if base_src == "header" and log.station_xyz_m is not None:
            base_xyz = log.station_xyz_m
            base_src = f"RTCM 1005/1006 of {args.base} (give --base-pos for a surveyed one)"
    else:
        base, base_nav = read_observations(args.base, lenient=args.lenient)
    if base_src == "header":
        if base.header.approx_xyz_m is None:
            raise SystemExit(
                f"navtrack rtk: {args.base} has no APPROX POSITION XYZ: give --base-pos"
            )
        base_xyz = np.asarray(base.header.approx_xyz_m, dtype=float)
        base_src = f"header APPROX POSITION of {args.base} (give --base-pos for a surveyed one)"
    navs = [n for n in (rover_nav, base_nav) if n is not None]
    navs += [read_nav(p) for p in args.nav]
    if not any(n.tables for n in navs):
        raise SystemExit("navtrack rtk: no ephemerides: give a RINEX navigation file")
    sp3 = None
    if args.sp3 is not None:
        sp3 = read_sp3(args.sp3)
        for why in sp3.warnings:
            print(f"warning        {args.sp3}: {why}", file=sys.stderr)
    return rover, base, navs, sp3, base_xyz, base_src


def _solve(
    args: argparse.Namespace,
    config: RtkConfig,
    inputs: tuple[Observations, Observations, list[NavData], Sp3 | None, FloatArray, str],
) -> RtkResult:
    """:func:`solve_relative` under a progress bar over both filter passes."""
    rover, base, navs, sp3, base_xyz, _ = inputs
    n_common = min(len(rover.t_gps_s), len(base.t_gps_s))
    n_total = (2 if args.direction == "combined" else 1) * n_common
    disable = True if args.no_progress else None  # None: only on a terminal
    with tqdm(
        total=n_total, unit="epoch", desc="filtering", file=sys.stderr, disable=disable
    ) as bar:
        state = {"done_passes": 0, "last": 0}

        def progress(done: int, total: int) -> None:
            if done < state["last"]:  # the next filter pass started
                state["done_passes"] += state["last"]
            state["last"] = done
            bar.n = min(state["done_passes"] + done, n_total)
            bar.refresh()

        try:
            result = solve_relative(rover, base, navs, base_xyz, config, sp3=sp3, progress=progress)
        except ValueError as exc:
            raise SystemExit(f"navtrack rtk: {exc}") from None
        bar.n = n_total
        bar.refresh()
    return result


def run_rtk(args: argparse.Namespace) -> int:
    if args.example:
        _example_inputs(args)
    if args.rover is None or args.base is None:
        raise SystemExit("navtrack rtk: give ROVER BASE NAV..., or --example")
    if not args.nav and not (is_raw_log(args.rover) or is_raw_log(args.base)):
        raise SystemExit("navtrack rtk: give ROVER BASE NAV... (NAV optional for UBX logs)")
    for path in [args.rover, args.base, *args.nav, *([args.sp3] if args.sp3 else [])]:
        if not path.is_file():
            raise SystemExit(f"navtrack rtk: file {str(path)!r} not found")
    check_outputs("navtrack rtk", args.out, FORMATS, args.plot)
    config = _rtk_config(args)
    inputs = _read_inputs(args)
    result = _solve(args, config, inputs)
    _print_summary(args, result, config, inputs[4], inputs[5])
    counts = result.status_counts()
    code = 0 if counts["fix"] + counts["float"] + counts["dgnss"] else 1
    if code:
        print("navtrack rtk: no epoch has a relative solution", file=sys.stderr)
    if args.plot is not None:
        from navtrack.plots.rtk import plot_rtk  # matplotlib: only with --plot

        errs = reference_errors(result.t_gps_s, result.pos_m, args)
        paths = plot_rtk(
            result,
            args.plot,
            error_m=None if errs is None else errs[0],
            ratio_threshold=config.ambiguity.ratio_threshold,
        )
        print(f"figures        {', '.join(str(p) for p in paths)}")
    if args.out is not None:
        try:
            path = write_solution(
                solution_frame(result),
                args.out,
                ok_status=("fix", "float", "dgnss", "single", "no_base"),
            )
            print(f"written        {path}")
        except OSError as exc:
            print(f"navtrack rtk: solution NOT written: {exc}", file=sys.stderr)
            code = 1
    return code


def _print_summary(
    args: argparse.Namespace,
    result: RtkResult,
    config: RtkConfig,
    base_xyz: FloatArray,
    base_src: str,
) -> None:
    counts = result.status_counts()
    print(f"rover          {args.rover}")
    print(f"base           {args.base}")
    x, y, z = (float(v) for v in base_xyz)
    print(f"base position  {x:.4f} {y:.4f} {z:.4f}  ({base_src})")
    print(
        f"navigation     {', '.join(str(p) for p in args.nav) or 'from the UBX log(s)'}"
        + (f"  sp3 {args.sp3}" if args.sp3 else "")
    )
    systems = "".join(dict.fromkeys(s[0] for s in result.sats))
    bands = "L1+L2" if config.frequencies == 2 else "L1"
    print(
        f"mode           {config.mode}, {config.direction}, {bands}, "
        f"systems {systems or '-'}, elevation mask {config.elmask_deg:g} deg, ratio "
        f"{config.ambiguity.ratio_threshold:g}{', partial' if config.ambiguity.partial else ''}"
        + (", fix-and-hold" if config.hold else "")
    )
    print(
        f"epochs         rover {result.n_rover_epochs}, base {result.n_base_epochs}, "
        f"common {result.n_common_epochs}"
    )
    age = result.age_s[np.isfinite(result.age_s)]
    if age.size:
        print(
            f"base age       median {np.median(age):.3f} s, max {age.max():.3f} s "
            f"(up to {config.max_age_s:g} s used)"
        )
    for name in STATUS_NAMES:
        if counts[name]:
            print(f"  {name:<12} {counts[name]}")
    n_c = max(result.n_common_epochs, 1)
    print(f"fix rate       {100.0 * counts['fix'] / n_c:.1f} % of the common epochs")
    _print_fix_outcomes(result)
    s = result.slips
    print(
        f"slips          lli {s['lli']}, doppler {s['doppler']}, geometry-free "
        f"{s['geometry_free']}; ambiguities restarted by a slip {s['ambiguity_resets']}"
    )
    ratio = result.ratio[np.isfinite(result.ratio)]
    if ratio.size:
        print(
            f"ratio test     median {np.median(ratio):.2f}, max {np.max(ratio):.2f} over "
            f"{ratio.size} searches"
        )
    print(f"base vs SPP    {result.base_spp_distance_m:.2f} m (base position minus its own SPP)")
    for w in result.warnings:
        print(f"warning        {w}", file=sys.stderr)
    _print_errors(args, result)


def _print_fix_outcomes(result: RtkResult) -> None:
    """Float epochs by reason: before or at the ratio test, and fixes refused after it."""
    counts = {k: v for k, v in result.rejection_counts().items() if v}
    after = {r.name.lower() for r in AFTER_RATIO_TEST}
    not_fixed = {k: v for k, v in counts.items() if k not in after}
    refused = {k: v for k, v in counts.items() if k in after}
    if not_fixed:
        print("not fixed      " + ", ".join(f"{k} {v}" for k, v in not_fixed.items()))
    if refused:
        print(
            "fixes refused  "
            + ", ".join(f"{k} {v}" for k, v in refused.items())
            + " (ratio test passed; kept float)"
        )


def _print_errors(args: argparse.Namespace, result: RtkResult) -> None:
    errs = reference_errors(result.t_gps_s, result.pos_m, args)
    if errs is None:
        return
    err, label = errs
    print(f"error vs ref   {label}: median / 95 % / max 3-D (m)")
    for name in ("fix", "float", "dgnss", "single"):
        sel = (result.status == STATUS_NAMES.index(name)) & np.isfinite(err)
        if sel.any():
            e = err[sel]
            print(
                f"  {name:<12} {np.median(e):8.3f}  {np.percentile(e, 95):8.3f}  "
                f"{e.max():8.3f}  ({sel.sum()} epochs)"
            )
