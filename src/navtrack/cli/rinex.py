"""``navtrack rinex info FILE``: what a RINEX observation/navigation or SP3 file holds."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from navtrack.data import sample_path
from navtrack.gnss.rinex import read_bytes, sniff
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.sp3 import read_sp3

EXAMPLE = "SEPT078M_120.21O"


def register(subparsers: Any) -> None:
    rinex = subparsers.add_parser("rinex", help="inspect RINEX and SP3 files")
    sub = rinex.add_subparsers(dest="rinex_command", metavar="SUBCOMMAND", required=True)
    info = sub.add_parser(
        "info",
        help="print what a RINEX observation/navigation or SP3 file holds",
        description="Print version, type, marker, receiver, time span, epochs, satellites per "
        "system and observation codes (navigation files: records per system, ionosphere "
        "parameters, leap seconds; SP3: epochs, satellites, span).",
    )
    info.add_argument("file", nargs="?", type=Path, help="RINEX (.o/.n/.rnx/.crx/.gz) or SP3 file")
    info.add_argument(
        "--example", action="store_true", help=f"use the bundled sample file {EXAMPLE}"
    )
    info.add_argument("--out", type=Path, help="also write the summary as JSON to this file")
    info.set_defaults(func=run_info)


def run_info(args: argparse.Namespace) -> int:
    if args.example == (args.file is not None):
        raise SystemExit("navtrack rinex info: give exactly one of FILE or --example")
    path = sample_path(EXAMPLE) if args.example else args.file
    data = read_bytes(path)
    kind = sniff(path, data)
    summary: dict[str, Any]
    if kind.format == "sp3":
        summary = read_sp3(path).summary()
    elif kind.file_type == "O":
        summary = read_obs(path).summary()
    else:
        summary = read_nav(path).summary()
    width = max(len(k) for k in summary)
    for key, value in summary.items():
        print(f"{key:<{width}}  {_format(value)}")
    if args.out:
        args.out.write_text(json.dumps(summary, indent=2, default=str) + "\n")
    return 0


def _format(value: Any) -> str:
    if isinstance(value, dict | list | tuple) and not value:
        return "none"
    if isinstance(value, dict):
        return "; ".join(f"{k}: {_format(v)}" for k, v in value.items())
    if isinstance(value, list | tuple):
        return " ".join(str(v) for v in value)
    return str(value)
