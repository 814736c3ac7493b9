"""Option groups shared by the positioning commands (``pos``, ``rtk``, ``ppp``, ``agps``):
``--systems``, ``--elmask``, ``--ref``/``--ref-llh`` (with :func:`reference` reading them),
``--out``, and the recognition of an Android GnssLogger log."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from navtrack.geodesy import check_near_surface, geodetic_to_ecef

__all__ = [
    "add_elmask_option",
    "add_lenient_option",
    "add_out_option",
    "add_reference_options",
    "add_systems_option",
    "is_android_log",
    "reference",
]


def add_systems_option(
    p: argparse.ArgumentParser, default: str | None, default_text: str | None = None
) -> None:
    """``--systems``: system letters (``default_text`` says what the default means)."""
    p.add_argument(
        "--systems",
        default=default,
        help=f"systems to use, e.g. GEJ (default {default_text or default})",
    )


def add_elmask_option(
    p: argparse.ArgumentParser, default: float | None, default_deg: float | None = None
) -> None:
    """``--elmask DEG``: the elevation mask (``default_deg`` the mask a ``None`` default
    stands for)."""
    shown = default if default_deg is None else default_deg
    p.add_argument(
        "--elmask",
        type=float,
        default=default,
        metavar="DEG",
        help=f"elevation mask in degrees (default {shown:g})",
    )


def add_lenient_option(p: argparse.ArgumentParser) -> None:
    """``--lenient``: damaged observation lines or messages are skipped and counted."""
    p.add_argument(
        "--lenient",
        action="store_true",
        help="skip damaged data lines of a RINEX observation file and damaged messages of a "
        "UBX log (counted in a warning, the first named) instead of stopping",
    )


def add_out_option(p: argparse.ArgumentParser, help_text: str, metavar: str | None = None) -> None:
    """``--out FILE``: where the command writes its result."""
    p.add_argument("--out", type=Path, metavar=metavar, help=help_text)


def add_reference_options(p: argparse.ArgumentParser, *, trajectory: bool = False) -> None:
    """``--ref X Y Z`` | ``--ref-llh LAT LON H`` (one of them), read by :func:`reference`;
    ``trajectory`` adds ``--ref-pos FILE``, an RTKLIB ``.pos`` file compared epoch by epoch."""
    ref = p.add_mutually_exclusive_group()
    ref.add_argument(
        "--ref",
        nargs=3,
        type=float,
        metavar=("X", "Y", "Z"),
        help="reference position, ECEF metres",
    )
    ref.add_argument(
        "--ref-llh",
        nargs=3,
        type=float,
        metavar=("LAT", "LON", "H"),
        help="reference position, degrees and ellipsoidal metres",
    )
    if trajectory:
        ref.add_argument(
            "--ref-pos",
            type=Path,
            metavar="FILE",
            help="reference trajectory: an RTKLIB .pos file, compared epoch by epoch",
        )


def reference(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """The reference position of ``--ref``/``--ref-llh`` in ECEF metres, refusing clearly
    implausible values (``SystemExit`` naming the option)."""
    cmd = f"navtrack {getattr(args, 'command', None) or 'pos'}"
    if args.ref is not None:
        x, y, z = args.ref
        try:
            check_near_surface(args.ref, "--ref")
        except ValueError:
            r = math.sqrt(x * x + y * y + z * z)
            raise SystemExit(
                f"{cmd}: --ref {x:g} {y:g} {z:g} is {r:.4g} m from the earth's centre, not "
                "a point near the surface: give ECEF metres (use --ref-llh for degrees)"
            ) from None
        return (x, y, z)
    if getattr(args, "ref_llh", None) is not None:
        lat, lon, h = args.ref_llh
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0 and -1000.0 <= h <= 1.0e5):
            raise SystemExit(
                f"{cmd}: --ref-llh {lat:g} {lon:g} {h:g} is not latitude/longitude in "
                "degrees and height in metres (use --ref for ECEF metres)"
            )
        xyz = geodetic_to_ecef([math.radians(lat), math.radians(lon), h])
        return (float(xyz[0]), float(xyz[1]), float(xyz[2]))
    return None


def is_android_log(path: Path) -> bool:
    """Whether ``path`` is an Android GnssLogger log (a ``.txt``/``.csv`` with ``Raw`` rows or
    ``#`` comment lines at its start)."""
    if path.suffix.lower() in (".txt", ".csv"):
        with path.open("rb") as f:
            head = f.read(4096)
        return b"Raw," in head or head.startswith(b"#")
    return False
