"""``navtrack ppp OBS NAV... --sp3 FILE [--clk FILE] [--antex FILE]``: static PPP.

Reads a dual-frequency observation file (RINEX or u-blox UBX), optional navigation files, an SP3
precise orbit file and optionally a RINEX clock file whose 30 s or 5 s satellite clocks replace
the SP3's, solves every epoch (:func:`navtrack.gnss.ppp.solve_ppp`), prints a summary (the final
position, its formal standard deviation, and with ``--ref`` the error over time and the share of
epochs whose error lies inside the formal 95 % bound) and writes the solution with ``--out``.
The exit code is 1 when no epoch was solved.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.cli._options import (
    add_elmask_option,
    add_lenient_option,
    add_out_option,
    add_reference_options,
    add_systems_option,
    reference,
)
from navtrack.cli.inputs import read_observations
from navtrack.cli.outputs import check_outputs
from navtrack.data import REFERENCE_XYZ_M, sample_path
from navtrack.gnss.antex import read_antex
from navtrack.gnss.ppp import PppConfig, PppResult, convergence, solution_frame, solve_ppp
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex_clock import read_clock
from navtrack.gnss.sp3 import Sp3, read_sp3
from navtrack.io.solution import FORMATS, write_solution
from navtrack.plots.ppp import plot_ppp  # matplotlib is imported only when a figure is drawn
from navtrack.timescale import to_datetime64

PPP_EXAMPLE = (
    "SEPT078M_120.21O",
    "SEPT078M.21P",
    "COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3",
)
"""The bundled files of ``ppp --example`` (``navtrack/data/README.md``)."""


def register(subparsers: Any) -> None:
    q = subparsers.add_parser(
        "ppp",
        help="static precise point positioning with SP3 orbits and clocks",
        description="Dual-frequency ionosphere-free code and phase, Saastamoinen + estimated "
        "zenith wet delay, float ambiguities, static position (convergence over time).",
    )
    q.add_argument("obs", type=Path, nargs="?", help="RINEX observation file (dual frequency)")
    q.add_argument("nav", nargs="*", type=Path, help="RINEX navigation file(s) (optional)")
    q.add_argument("--sp3", type=Path, help="precise orbits and clocks (SP3)")
    q.add_argument(
        "--clk",
        type=Path,
        help="RINEX clock file (30 s or 5 s satellite clocks, used instead of the SP3 clocks)",
    )
    q.add_argument(
        "--antex",
        type=Path,
        help="ANTEX file: receiver (header ANT # / TYPE) and satellite antenna phase centres",
    )
    q.add_argument(
        "--example",
        action="store_true",
        help=f"two minutes of the bundled SEPT station ({PPP_EXAMPLE[0]}) with the bundled CODE "
        "orbits and clocks, against the station's reference position",
    )
    add_systems_option(q, "G")
    add_elmask_option(q, 15.0)
    add_lenient_option(q)
    add_reference_options(q, trajectory=True)
    add_out_option(q, "write the solution (.csv, .parquet, .nmea, .kml, .gpx)")
    q.add_argument(
        "--plot",
        type=Path,
        metavar="DIR",
        help="write the error and its formal 95 %% bound over time (needs --ref or --ref-llh)",
    )
    q.set_defaults(func=run_ppp)


def _resolve_inputs(args: argparse.Namespace) -> None:
    """Fill in the bundled files for ``--example`` and check that every input exists."""
    if args.example:
        if args.obs is not None or args.sp3 is not None:
            raise SystemExit("navtrack ppp: give either OBS --sp3 SP3 or --example, not both")
        args.obs, args.nav, args.sp3 = (
            sample_path(PPP_EXAMPLE[0]),
            [sample_path(PPP_EXAMPLE[1])],
            sample_path(PPP_EXAMPLE[2]),
        )
        if args.ref is None and args.ref_llh is None and args.ref_pos is None:
            args.ref = list(REFERENCE_XYZ_M[PPP_EXAMPLE[0]])
    if args.obs is None or args.sp3 is None:
        raise SystemExit("navtrack ppp: give OBS and --sp3 SP3, or --example")
    optional = [p for p in (args.clk, args.antex) if p is not None]
    for path in [args.obs, *args.nav, args.sp3, *optional]:
        if not path.is_file():
            raise SystemExit(f"navtrack ppp: file {str(path)!r} not found")


def _precise_products(args: argparse.Namespace, t_obs_s: np.ndarray) -> Sp3:
    """The SP3 orbits, with the clock file's satellite clocks when ``--clk`` is given; every
    leniency of the readers is printed as a warning. A clock file that covers none of the
    observation epochs ``t_obs_s`` is refused."""
    sp3 = read_sp3(args.sp3)
    for why in sp3.warnings:
        print(f"warning        {args.sp3}: {why}", file=sys.stderr)
    if args.clk is None:
        return sp3
    clock = read_clock(args.clk)
    for why in clock.warnings:
        print(f"warning        {args.clk}: {why}", file=sys.stderr)
    t0, t1 = clock.t_gps_s[0], clock.t_gps_s[-1]
    if t_obs_s.size and (t_obs_s[-1] < t0 or t_obs_s[0] > t1):
        span = " to ".join(str(t)[:19] for t in to_datetime64(np.array([t0, t1])))
        obs = " to ".join(str(t)[:19] for t in to_datetime64(t_obs_s[[0, -1]]))
        raise SystemExit(
            f"navtrack ppp: --clk {args.clk} covers {span} GPST, the observations {obs}"
        )
    return sp3.with_clock(clock)


def run_ppp(args: argparse.Namespace) -> int:
    _resolve_inputs(args)
    check_outputs("navtrack ppp", args.out, FORMATS, args.plot)
    try:
        config = PppConfig(systems=args.systems.upper(), elmask_deg=args.elmask)
    except ValueError as exc:
        raise SystemExit(f"navtrack ppp: {exc}") from None
    obs, log_nav = read_observations(args.obs, lenient=args.lenient)
    navs = [read_nav(p) for p in args.nav] + ([log_nav] if log_nav is not None else [])
    sp3 = _precise_products(args, obs.t_gps_s)
    antex = read_antex(args.antex) if args.antex is not None else None
    try:
        result = solve_ppp(obs, navs, sp3, config, antex=antex)
    except ValueError as exc:
        raise SystemExit(f"navtrack ppp: {exc}") from None
    for why in result.warnings:
        print(f"warning        {why}", file=sys.stderr)
    solved = _print_summary(args, config, result)
    code = 0 if solved else 1
    ref = reference(args) if args.ref_pos is None else None
    if args.plot is not None and solved and ref is not None:
        paths = plot_ppp(result, np.asarray(ref), args.plot)
        print(f"figures        {', '.join(str(p) for p in paths)}")
    if args.out is not None:
        try:
            path = write_solution(solution_frame(result), args.out, ok_status="ppp")
            print(f"written        {path}")
        except OSError as exc:
            print(f"navtrack ppp: solution NOT written: {exc}", file=sys.stderr)
            code = 1
    return code


def _print_summary(args: argparse.Namespace, config: PppConfig, result: PppResult) -> bool:
    """Print what was solved; whether any epoch was."""
    print(f"observations   {args.obs}")
    print(f"orbits/clocks  {args.sp3}" + (f", clocks {args.clk}" if args.clk else ""))
    if args.antex is not None:
        print(f"antennas       {args.antex}")
    print(f"systems        {config.systems}, elevation mask {config.elmask_deg:g} deg, static")
    print(f"epochs         {result.t_gps_s.size}, updated {int(result.updated.sum())}")
    s = result.slips
    print(
        f"slips          lli {s['lli']}, doppler {s['doppler']}, geometry-free {s['geometry_free']}"
    )
    last = np.flatnonzero(result.updated)
    if not last.size:
        return False
    x, y, z = result.pos_m[last[-1]]
    e, n, u = result.sd_enu_m[last[-1]]
    print(f"final position {x:.4f} {y:.4f} {z:.4f}")
    print(
        f"formal sd      E/N/U {e:.3f} {n:.3f} {u:.3f} m (the filter's model of the error, "
        "including correlated code and unmodelled range errors; compare --ref)"
    )
    print(f"final ZWD      {result.zwd_m[last[-1]]:.3f} m")
    ref = reference(args) if args.ref_pos is None else None
    if ref is not None:
        print("convergence    time (s)  horizontal  up      3D   (m, error vs ref)")
        for t, h, up, d in convergence(result, np.asarray(ref)):
            print(f"  {t:14.0f}  {h:10.3f}  {up:7.3f}  {d:7.3f}")
        inside = result.inside_bound(np.asarray(ref))
        print(
            f"inside 95 %    {inside[result.updated].mean() * 100:.1f} % of the solved epochs "
            "(error inside the formal 95 % ellipsoid)"
        )
    return True
