"""``navtrack convert LOG --out FILE.obs``: a u-blox raw log as RINEX 3.04 files.

Reads a UBX log (:func:`navtrack.gnss.ubx.read_ubx`: RXM-RAWX observations; RXM-SFRBX GPS and
QZSS LNAV, Galileo I/NAV, BeiDou D1 and GLONASS ephemerides) and writes a RINEX 3.04
observation file and, when the log holds ephemerides, a navigation file next to it (``--nav``
names it; default the observation file's name with ``.nav``). Prints what was written and what
was not: epochs, satellites and codes per system, ephemerides per system, navigation messages
not decoded (by system and reason), measurements of unknown signals and damaged messages
skipped (``--lenient``).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

from navtrack.data import sample_path
from navtrack.gnss.rinex.write import write_nav, write_obs
from navtrack.gnss.ubx import is_ubx, read_ubx

EXAMPLE = "gnss_imu_walk_cut.ubx"


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "convert",
        help="convert a u-blox UBX raw log to RINEX 3.04 observation and navigation files",
        description="Convert a u-blox UBX log (RXM-RAWX, RXM-SFRBX) to RINEX 3.04. The "
        "observations agree with RTKLIB's convbin to the printed precision (docs/rtk.md).",
    )
    p.add_argument("log", type=Path, nargs="?", help="u-blox UBX log (.ubx)")
    p.add_argument(
        "--out",
        type=Path,
        help="RINEX observation file to write (required, except with --example: then a new "
        "temporary directory)",
    )
    p.add_argument(
        "--example",
        action="store_true",
        help=f"convert the bundled log {EXAMPLE} (a u-blox receiver walking, 15 s at 4 Hz)",
    )
    p.add_argument(
        "--nav",
        type=Path,
        help="RINEX navigation file to write (default: --out with suffix .nav, written only "
        "when the log holds ephemerides)",
    )
    p.add_argument(
        "--lenient",
        action="store_true",
        help="skip damaged messages (bad checksum, inconsistent length) and count them",
    )
    p.add_argument(
        "--max-cp-std",
        type=float,
        default=0.020,
        metavar="CYCLES",
        help="drop carrier phases whose reported standard deviation exceeds this (RTKLIB "
        "convbin's threshold)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.example:
        if args.log is not None:
            raise SystemExit("navtrack convert: give either LOG or --example, not both")
        args.log = sample_path(EXAMPLE)
        if args.out is None:
            args.out = Path(tempfile.mkdtemp(prefix="navtrack-convert-")) / "walk.obs"
    if args.log is None or args.out is None:
        raise SystemExit("navtrack convert: give LOG --out FILE.obs, or --example")
    if not args.log.is_file():
        raise SystemExit(f"navtrack convert: file {str(args.log)!r} not found")
    if not is_ubx(args.log):
        raise SystemExit(f"navtrack convert: {args.log} is not a u-blox UBX log")
    for out in (args.out, args.nav):
        if out is not None and not out.parent.is_dir():
            raise SystemExit(f"navtrack convert: directory {str(out.parent)!r} does not exist")
    log = read_ubx(args.log, lenient=args.lenient, max_cp_std_cycles=args.max_cp_std)
    comments = [f"converted from {args.log.name} (u-blox UBX)"]
    obs = log.obs
    if len(obs.t_gps_s):
        write_obs(obs, args.out, comments=comments)
        print(f"wrote          {args.out}: {len(obs.t_gps_s)} epochs, {len(obs.sats)} satellites")
    else:
        print(f"no observation file: {args.log} holds no RXM-RAWX epoch")
    for sys_letter, codes in obs.header.obs_types.items():
        n = sum(1 for s in obs.sats if s[0] == sys_letter)
        print(f"  {sys_letter}            {n} satellites, {' '.join(codes)}")
    nav_path = args.nav or args.out.with_suffix(".nav")
    if log.nav.tables:
        write_nav(log.nav, nav_path, comments=comments)
        per = ", ".join(f"{s} {len(t['sat'])}" for s, t in log.nav.tables.items())
        print(f"wrote          {nav_path}: ephemerides {per}")
    else:
        print("no navigation file: the log holds no complete ephemeris")
    for why, n in sorted(log.undecoded.items()):
        print(f"not decoded    {n} RXM-SFRBX: {why}")
    for sig, n in sorted(log.unknown_signals.items()):
        print(f"not converted  {n} measurements of gnssId/sigId {sig} (no RINEX code)")
    if log.undated_epochs:
        print(f"not converted  {log.undated_epochs} RXM-RAWX epochs before GPS time was known")
    if log.skipped:
        print(
            f"skipped        {len(log.skipped)} damaged messages (first: {log.skipped[0].reason})"
        )
    return 0
