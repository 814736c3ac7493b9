"""The ``navtrack`` command.

argparse rather than a decorator framework: it ships with Python, costs nothing at start-up (the
positioning command is timed as a whole process against RTKLIB), and keeps each command a plain
function over the library. Every command module registers its sub-parser and imports its heavy
dependencies only when run.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from navtrack import __version__

# Command modules, each with ``register(subparsers)``; kept in the order ``--help`` lists them.
COMMAND_MODULES = (
    "navtrack.cli.pos",
    "navtrack.cli.rinex",
    "navtrack.cli.track",
    "navtrack.cli.smooth",
    "navtrack.cli.reproduce",
    "navtrack.cli.rtk",
    "navtrack.cli.agps",
    "navtrack.cli.attitude",
)


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every command registered."""
    parser = argparse.ArgumentParser(
        prog="navtrack",
        description="Positioning, navigation integrity and multi-target tracking on real data.",
    )
    parser.add_argument("--version", action="version", version=f"navtrack {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit code."""
    from navtrack.errors import NavtrackError

    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (NavtrackError, OSError) as exc:
        print(f"navtrack: error: {exc}", file=sys.stderr)
        return 1
