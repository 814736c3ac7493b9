"""``navtrack pos OBS NAV...``: single point positions of a RINEX file or an Android raw log.

Reads the observations (RINEX 2/3 or Android GnssLogger), the navigation file(s) and optionally
an SP3 file, keeps the epochs ``--ts/--te/--ti`` select, solves them by weighted least squares
(:func:`navtrack.gnss.spp.solve_spp`), prints a summary (epochs, solved, count of each status,
and with a reference the mean, RMS and 95 % of the horizontal, vertical and 3D errors), writes
the solution with ``--out`` (CSV, Parquet, RTKLIB .pos, NMEA GGA+RMC, KML, GPX by suffix) and
figures with ``--plot``. ``--conf`` reads an RTKLIB option file; options given on the command
line win over it. An output that cannot be written (unknown suffix, missing directory, missing
extra) is refused before anything is read (exit 2). The exit code is 1 when no epoch could be
solved, the input cannot be read, or the ``--out`` file could not be written.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Mapping

    from navtrack._typing import FloatArray
    from navtrack.gnss.accuracy import ErrorStats
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3
    from navtrack.gnss.spp import SppConfig, SppResult
    from navtrack.positioning import PositionSolution

EXAMPLE_OBS = "SEPT078M_120.21O"
EXAMPLE_NAV = "SEPT078M.21P"
# cssrlib's xyz_ref of station SEPT (src/navtrack/data/README.md)
EXAMPLE_REF_SOURCE = "station SEPT, cssrlib's xyz_ref (src/navtrack/data/README.md)"
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
    p.add_argument(
        "--systems", help=f"systems to use, e.g. GEJ (default {DEFAULT_SYSTEMS}: all present)"
    )
    p.add_argument(
        "--elmask",
        type=float,
        metavar="DEG",
        help=f"elevation mask in degrees (default {DEFAULT_ELMASK_DEG:g})",
    )
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
    p.add_argument(
        "--out",
        type=Path,
        help="write the solution (.csv, .parquet, .pos RTKLIB, .nmea GGA+RMC, .kml, .gpx)",
    )
    p.add_argument("--plot", type=Path, metavar="DIR", help="write figures into this directory")
    p.add_argument(
        "--example",
        action="store_true",
        help=f"run on the bundled {EXAMPLE_OBS} + {EXAMPLE_NAV}; errors against "
        f"{EXAMPLE_REF_SOURCE}",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
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
    # --- integrity monitoring (navtrack.integrity.raim)
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
    p.set_defaults(func=run_pos)


def _median(values: FloatArray) -> float:
    """Median of the finite values (NaN when none), from a sort: ``np.median`` and
    ``np.nanmedian`` import ``numpy.ma`` (12 ms of every run's start-up)."""
    import numpy as np

    v = np.sort(values[np.isfinite(values)])
    if v.size == 0:
        return float("nan")
    mid = v.size // 2
    return float(v[mid]) if v.size % 2 else float(0.5 * (v[mid - 1] + v[mid]))


def _raim_config(args: argparse.Namespace) -> Any:
    """The RaimConfig of ``--raim/--pfa/--pmd`` (None for ``off``)."""
    if args.raim == "off":
        return None
    from navtrack.errors import NavtrackError
    from navtrack.integrity.ism import read_ism
    from navtrack.integrity.raim import RaimConfig

    try:
        ism = None if args.ism is None else read_ism(args.ism)
    except NavtrackError as exc:
        raise SystemExit(f"navtrack pos: --ism: {exc}") from None
    try:
        return RaimConfig(method=args.raim, pfa=args.pfa, pmd=args.pmd, ism=ism)
    except ValueError as exc:
        raise SystemExit(f"navtrack pos: --raim {args.raim}: {exc}") from None


def _print_raim_summary(result: PositionSolution, hal_m: float = 40.0, val_m: float = 35.0) -> None:
    """Integrity lines of the summary: epochs per RAIM status, exclusions per satellite,
    median protection levels, availability (HPL <= HAL and VPL <= VAL; HPL <= HAL)."""
    import numpy as np

    integ = result.integrity
    if integ is None:
        return
    counts = integ.status_counts()
    print(f"integrity      {integ.method}: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    per_sat = integ.excluded.sum(axis=0)
    if per_sat.any():
        print(
            "  excluded     "
            + " ".join(f"{result.sats[j]}:{per_sat[j]}" for j in np.flatnonzero(per_sat))
        )
    if np.isfinite(integ.hpl_m).any():
        print(f"  HPL/VPL      median {_median(integ.hpl_m):.2f} / {_median(integ.vpl_m):.2f} m")
    av = integ.availability(hal_m, val_m)
    print(
        f"  availability {100 * av['vertical']:.1f} % (HPL <= {hal_m:g} m, VPL <= {val_m:g} m), "
        f"horizontal {100 * av['horizontal']:.1f} % (HPL <= {hal_m:g} m)"
    )


def _print_misleading(result: PositionSolution, ref: tuple[float, float, float]) -> None:
    """Summary line: epochs whose status is ``ok`` or ``excluded`` and whose error against the
    reference exceeds the protection level (misleading information)."""
    import numpy as np

    from navtrack.geodesy import ecef_to_enu
    from navtrack.integrity.raim import RaimStatus

    integ = result.integrity
    assert integ is not None
    enu = ecef_to_enu(result.pos_m, np.asarray(ref))
    usable = (integ.status == RaimStatus.OK) | (integ.status == RaimStatus.EXCLUDED)
    ok = usable & np.isfinite(enu[:, 0])
    with np.errstate(invalid="ignore"):
        mi_h = int(np.sum(ok & (np.hypot(enu[:, 0], enu[:, 1]) > integ.hpl_m)))
        mi_v = int(np.sum(ok & (np.abs(enu[:, 2]) > integ.vpl_m)))
    print(f"  misleading   {mi_h} / {mi_v} epochs error > HPL / VPL (ok or excluded)")


def add_reference_options(p: argparse.ArgumentParser, *, trajectory: bool = False) -> None:
    """``--ref X Y Z`` | ``--ref-llh LAT LON H`` (one of them), read by :func:`_reference`;
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


def _reference(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """The reference position in ECEF metres, refusing clearly implausible values."""
    cmd = f"navtrack {getattr(args, 'command', None) or 'pos'}"
    if args.ref is not None:
        from navtrack.geodesy import check_near_surface

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
    if args.ref_llh is not None:
        lat, lon, h = args.ref_llh
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0 and -1000.0 <= h <= 1.0e5):
            raise SystemExit(
                f"{cmd}: --ref-llh {lat:g} {lon:g} {h:g} is not latitude/longitude in "
                "degrees and height in metres (use --ref for ECEF metres)"
            )
        from navtrack.geodesy import geodetic_to_ecef

        xyz = geodetic_to_ecef([math.radians(lat), math.radians(lon), h])
        return (float(xyz[0]), float(xyz[1]), float(xyz[2]))
    return None


def _is_android(path: Path) -> bool:
    if path.suffix.lower() in (".txt", ".csv"):
        with path.open("rb") as f:
            head = f.read(4096)
        return b"Raw," in head or head.startswith(b"#")
    return False


def _read_inputs(
    args: argparse.Namespace, config: SppConfig
) -> tuple[Observations, list[NavData], Sp3 | None]:
    """The observations (of the configured systems' pseudorange codes only), navigation data
    (of those systems only) and precise orbits."""
    from navtrack.gnss.rinex.nav import read_nav

    navs = [read_nav(p, systems=config.systems) for p in args.nav]
    if args.android:
        from navtrack.gnss.android import read_gnsslogger

        obs = read_gnsslogger(args.obs)
    else:
        from navtrack.cli.inputs import read_observations
        from navtrack.gnss.spp import observation_codes

        obs, log_nav = read_observations(
            args.obs, systems=config.systems, codes=observation_codes(config)
        )
        if log_nav is not None:
            navs.insert(0, log_nav)
    sp3 = None
    if args.sp3 is not None:
        from navtrack.gnss.sp3 import read_sp3

        sp3 = read_sp3(args.sp3)
        for bad in sp3.implausible:
            print(f"navtrack pos: {args.sp3}, line {bad.line}: {bad.reason}", file=sys.stderr)
    return obs, navs, sp3


def _input_warnings(
    args: argparse.Namespace, config: SppConfig, obs: Observations, navs: list[NavData]
) -> list[str]:
    """What the inputs leave out of the model or the solution: a broadcast ionosphere without
    parameters, a system asked for that the file does not hold."""
    from navtrack.gnss.spp import klobuchar_params

    out = []
    if config.iono == "klobuchar" and not any(klobuchar_params(n.iono) is not None for n in navs):
        given = "no navigation file" if not navs else "no ionosphere parameters in the navigation"
        out.append(
            f"ionosphere not modelled: {given} (Klobuchar needs them); give a NAV file or "
            "--iono ionofree"
        )
    if args.systems:
        present = set(obs.header.obs_types or {}) | {s[0] for s in obs.sats}
        absent = [s for s in dict.fromkeys(args.systems.upper()) if s not in present]
        if absent:
            held = "".join(s for s in "GRECJI" if s in present) or "none"
            out.append(f"--systems {''.join(absent)}: not in {args.obs.name} (it holds {held})")
    return out


def _error_stats(pos_m: FloatArray, ref: tuple[float, float, float]) -> dict[str, ErrorStats]:
    import numpy as np

    from navtrack.geodesy import ecef_to_enu
    from navtrack.gnss.accuracy import enu_error_stats

    return enu_error_stats(ecef_to_enu(pos_m, np.asarray(ref)))


def run_pos(args: argparse.Namespace) -> int:
    import numpy as np

    from navtrack.gnss.spp import STATUS_NAMES
    from navtrack.positioning import solution_frame

    # first: a greedy --ts/--te may have taken the input files
    window = _time_window(args)
    if args.example:
        if args.obs is not None:
            raise SystemExit("navtrack pos: give either OBS NAV... or --example, not both")
        from navtrack.data import sample_path

        args.obs = sample_path(EXAMPLE_OBS)
        args.nav = [sample_path(EXAMPLE_NAV)]
        if args.ref is None and args.ref_llh is None:
            from navtrack.data import REFERENCE_XYZ_M

            args.ref = list(REFERENCE_XYZ_M[EXAMPLE_OBS])
            args.ref_source = EXAMPLE_REF_SOURCE
    if args.obs is None:
        raise SystemExit("navtrack pos: give OBS and NAV files, or --example")
    if not args.obs.is_file():
        raise SystemExit(f"navtrack pos: observation file {str(args.obs)!r} not found")
    for p in [*args.nav, *([args.sp3] if args.sp3 else [])]:
        if not p.is_file():
            raise SystemExit(f"navtrack pos: file {str(p)!r} not found")
    from navtrack.cli.inputs import is_raw_log

    raw_log = is_raw_log(args.obs)
    if not args.nav and args.sp3 is None and not raw_log:
        raise SystemExit(
            "navtrack pos: no navigation file given: positions need broadcast ephemerides "
            "(RINEX NAV) or precise orbits (--sp3)"
        )
    args.android = _is_android(args.obs)
    config = _config(args)
    from navtrack.cli.network import network_jobs, run_network

    jobs = None if args.android or raw_log else network_jobs(args)
    if jobs is not None:
        if window is not None:
            raise SystemExit("navtrack pos: --ts/--te/--ti are for one station")
        return run_network(args, jobs, config)
    if args.workers is not None or args.scheduler is not None:
        raise SystemExit("navtrack pos: --workers/--scheduler need several observation files")
    ref = _reference(args)
    from navtrack.cli.outputs import check_outputs
    from navtrack.io.solution import FORMATS

    check_outputs("navtrack pos", args.out, FORMATS, args.plot)

    obs, navs, sp3 = _read_inputs(args, config)
    n_read = len(obs.t_gps_s)
    if window is not None:
        from navtrack.gnss.spp import subset_epochs
        from navtrack.timescale import select_epochs

        obs = subset_epochs(obs, np.flatnonzero(select_epochs(obs.t_gps_s, *window)))
    n_epochs = len(obs.t_gps_s)
    if n_epochs == 0:
        why = " selected by --ts/--te/--ti" if window is not None and n_read else ""
        print(f"navtrack pos: {args.obs}: no observation epochs{why}", file=sys.stderr)
        return 1
    if sp3 is None and not any(nav.tables for nav in navs):
        for why in _input_warnings(args, config, obs, navs):
            print(f"warning        {why}")
        names = ", ".join(map(str, args.nav or [args.obs]))
        print(
            f"navtrack pos: {names}: no ephemerides of the systems {config.systems}",
            file=sys.stderr,
        )
        return 1
    raim = _raim_config(args)
    tables = None
    if args.rtklib_compatible:
        from navtrack.gnss.ephemeris import first_record_group_delays
        from navtrack.gnss.spp import navigation_tables

        tables = first_record_group_delays(navigation_tables(navs))
    result = _solve(
        obs, navs, sp3, config, progress=not args.no_progress, raim=raim, ephemeris=tables
    )
    counts = result.status_counts()
    solved = counts["ok"]
    # the systems of satellites that entered a solution, not those merely observed
    used_sats = {result.sats[j][0] for j in np.flatnonzero(result.used.any(axis=0))}
    used_systems = "".join(s for s in "GRECJI" if s in used_sats)

    print(f"observations   {args.obs}")
    nav_names = ", ".join(str(p) for p in args.nav) or ("from the log" if raw_log else "-")
    print(f"navigation     {nav_names}" + (f"  sp3 {args.sp3}" if args.sp3 else ""))
    print(
        f"systems        {used_systems or '-'}  (clocks: {', '.join(result.clock_groups)}; "
        f"weighting {config.weighting}, elevation mask {config.elmask_deg:g} deg)"
    )
    for model, setting in (("ionosphere", config.iono), ("troposphere", config.tropo)):
        if setting == "off":
            print(f"warning        {model} model switched off")
    for why in _input_warnings(args, config, obs, navs):
        print(f"warning        {why}")
    if args.conf is not None:
        print(f"options        {args.conf} (RTKLIB option file)")
    print(f"epochs         {n_epochs}" + (f" of {n_read} (--ts/--te/--ti)" if window else ""))
    if obs.skipped:
        reasons = Counter(sk.reason for sk in obs.skipped)
        listed = "; ".join(f"{r}: {n}" for r, n in reasons.most_common())
        print(f"rows skipped   {len(obs.skipped)} ({listed})")
    print(f"solved         {solved}")
    for name in STATUS_NAMES:
        if counts[name]:
            print(f"  {name:<18} {counts[name]}")
    no_eph = sorted(result.sats[j] for j in np.flatnonzero(result.no_ephemeris.any(axis=0)))
    if no_eph:
        print(
            f"no ephemeris   {len(no_eph)} satellites ({' '.join(no_eph)}); their measurements "
            "were not used"
        )
    if solved:
        ok = result.status == 0
        print(
            f"satellites     {np.mean(result.n_sats[ok]):.1f} used per solved epoch; "
            f"PDOP median {_median(result.dop[ok, 1]):.2f}"
        )
    if ref is not None and solved:
        source = getattr(args, "ref_source", "--ref-llh" if args.ref is None else "--ref")
        print(f"reference      {ref[0]:.3f} {ref[1]:.3f} {ref[2]:.3f} (ECEF m; {source})")
        st = _error_stats(result.pos_m[result.status == 0], ref)
        print("error vs ref   mean      RMS       95 %    (m)")
        for key, name in (("horizontal", "horizontal"), ("up", "vertical"), ("3D", "3D")):
            print(f"  {name:<12} {st[key].mean_m:8.3f}  {st[key].rms_m:8.3f}  {st[key].p95_m:8.3f}")
        e, n, u = (st[k].mean_m for k in ("east", "north", "up"))
        print(f"  mean ENU     {e:8.3f}  {n:8.3f}  {u:8.3f}")
    _print_raim_summary(result, args.hal, args.val)
    if ref is not None and result.integrity is not None:
        _print_misleading(result, ref)
    if solved == 0:
        cause = max(((v, k) for k, v in counts.items() if k != "ok"), default=(0, "?"))[1]
        hint = ""
        if cause == "no_ephemeris":
            hint = (
                " (the navigation data do not cover these satellites and epochs: check that "
                "the NAV file matches the observation day and systems)"
            )
        print(
            f"navtrack pos: no epoch could be solved; most epochs: {cause}{hint}", file=sys.stderr
        )

    table = solution_frame(result)
    table.update(_velocity_columns(obs, result, navs, sp3, config, solved))
    status_code = 0 if solved else 1
    if args.out is not None:
        from navtrack.io.solution import write_solution

        try:
            path = write_solution(
                table,
                args.out,
                talker="GN" if len(used_systems) > 1 else "GP",
                nmea_rmc=True,
                header=_pos_header(args, obs, config),
            )
            print(f"written        {path}")
        except OSError as exc:
            print(f"navtrack pos: solution NOT written: {exc}", file=sys.stderr)
            status_code = 1
    if args.plot is not None:
        from navtrack.plots.gnss import plot_solution

        paths = plot_solution(
            table,
            args.plot,
            ref_xyz_m=ref,
            azel=(result.azel_rad, list(result.sats)),
            max_gdop=config.max_gdop,
            elmask_deg=config.elmask_deg,
        )
        print(f"figures        {', '.join(str(p) for p in paths)}")
    return status_code


def _velocity_columns(
    obs: Observations,
    result: SppResult,
    navs: list[NavData],
    sp3: Sp3 | None,
    config: SppConfig,
    solved: int,
) -> dict[str, FloatArray]:
    """``ve_mps``, ``vn_mps``, ``vu_mps`` and ``drift_mps`` from the Doppler measurements
    (NaN without them), with a summary line."""
    import numpy as np

    from navtrack.gnss.velocity import doppler_velocity

    vel = doppler_velocity(obs, result, navs, sp3=sp3, config=config)
    n_vel = int(np.isfinite(vel.vel_mps[result.status == 0, 0]).sum())
    if solved and n_vel == 0:
        print("warning        no Doppler measurements used: velocity columns are empty")
    elif solved:
        print(f"velocity       {n_vel} of {solved} solved epochs (Doppler)")
    return {
        "ve_mps": vel.vel_enu_mps[:, 0],
        "vn_mps": vel.vel_enu_mps[:, 1],
        "vu_mps": vel.vel_enu_mps[:, 2],
        "drift_mps": vel.drift_mps,
    }


def _time_window(args: argparse.Namespace) -> tuple[float | None, float | None, float] | None:
    """``(start, end, interval)`` of ``--ts/--te/--ti`` in GPS seconds, or None without them."""
    from navtrack.timescale import parse_gpst

    if args.ts is None and args.te is None and args.ti is None:
        return None
    bounds: list[float | None] = []
    for name, words in (("--ts", args.ts), ("--te", args.te)):
        if words is not None and len(words) > 2:
            raise SystemExit(
                f"navtrack pos: {name}: expected a date and a time, got {' '.join(words)} "
                "(give the input files before --ts/--te)"
            )
        try:
            bounds.append(None if words is None else parse_gpst(" ".join(words)))
        except ValueError as exc:
            raise SystemExit(f"navtrack pos: {name}: {exc}") from None
    if args.ti is not None and not (args.ti >= 0.0 and math.isfinite(args.ti)):
        raise SystemExit(f"navtrack pos: --ti {args.ti:g}: expected an interval >= 0 s")
    start, end = bounds
    if start is not None and end is not None and end < start:
        raise SystemExit("navtrack pos: --te is before --ts")
    return start, end, args.ti or 0.0


def _config(args: argparse.Namespace) -> SppConfig:
    """The solver settings: command line first, then ``--conf``, then navtrack's defaults."""
    from navtrack.gnss.spp import SppConfig

    conf = None
    if args.conf is not None:
        from navtrack.io.rtklib_conf import read_conf

        if not args.conf.is_file():
            raise SystemExit(f"navtrack pos: --conf file {str(args.conf)!r} not found")
        from navtrack.errors import FileFormatError

        try:
            conf = read_conf(args.conf)
        except FileFormatError as exc:
            raise SystemExit(f"navtrack pos: {exc}") from None
        if conf.precise_ephemeris and args.sp3 is None:
            raise SystemExit(
                f"navtrack pos: {args.conf}, line {conf.lines['pos1-sateph']}: "
                "pos1-sateph=precise needs the SP3 file (--sp3)"
            )

    def pick(cli: Any, name: str, default: Any) -> Any:
        from_conf = None if conf is None else getattr(conf, name)
        return cli if cli is not None else from_conf if from_conf is not None else default

    systems = pick(args.systems, "systems", DEFAULT_SYSTEMS)
    # phone pseudoranges are far noisier than RTKLIB's receiver model assumes: C/N0 weights
    weighting = args.weighting or ("cn0" if args.android else "rtklib")
    defaults = SppConfig()
    try:
        return SppConfig(
            systems="".join(dict.fromkeys(systems.upper())),
            elmask_deg=pick(args.elmask, "elmask_deg", DEFAULT_ELMASK_DEG),
            weighting=weighting,
            iono=pick(args.iono, "iono", DEFAULT_IONO),
            tropo=pick(None, "tropo", defaults.tropo),
            max_gdop=pick(None, "max_gdop", defaults.max_gdop),
        )
    except ValueError as exc:
        raise SystemExit(f"navtrack pos: {exc}") from None


def _pos_header(args: argparse.Namespace, obs: Observations, config: SppConfig) -> list[str]:
    """Header lines of a ``.pos`` file: program, inputs, epochs and options, as RTKLIB's."""
    from navtrack import __version__
    from navtrack.timescale import to_datetime64, week_tow

    def when(t: float) -> str:
        week, tow = week_tow(t)
        text = str(to_datetime64(t).astype("datetime64[ms]")).replace("-", "/").replace("T", " ")
        return f"{text[:-2]} GPST (week{int(week)} {float(tow):.1f}s)"

    files = [args.obs, *args.nav, *([args.sp3] if args.sp3 else [])]
    t = obs.t_gps_s
    return [
        f"program   : navtrack {__version__}",
        *(f"inp file  : {f}" for f in files),
        *([f"obs start : {when(t[0])}", f"obs end   : {when(t[-1])}"] if t.size else []),
        "pos mode  : Single",
        f"elev mask : {config.elmask_deg:.1f} deg",
        f"ionos opt : {_IONO_NAMES[config.iono]}",
        f"tropo opt : {'Saastamoinen' if config.tropo == 'saastamoinen' else 'OFF'}",
        f"ephemeris : {'Precise' if args.sp3 else 'Broadcast'}",
        f"navi sys  : {' '.join(_SYSTEM_NAMES[s] for s in config.systems if s in _SYSTEM_NAMES)}",
    ]


_IONO_NAMES = {"klobuchar": "Broadcast", "ionofree": "Iono-Free LC", "off": "OFF"}
_SYSTEM_NAMES = {"G": "GPS", "R": "GLONASS", "E": "Galileo", "J": "QZSS", "C": "BeiDou"}


def _solve(
    obs: Observations,
    navs: list[NavData],
    sp3: Sp3 | None,
    config: SppConfig,
    *,
    progress: bool,
    raim: Any = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> PositionSolution:
    """Solve all epochs, with a progress bar on files of more than one block."""
    from navtrack.gnss.spp import CHUNK_EPOCHS
    from navtrack.positioning import solve_positions

    n = len(obs.t_gps_s)
    with contextlib.ExitStack() as stack:
        report = None
        if progress and n > CHUNK_EPOCHS:
            from tqdm import tqdm

            bar = stack.enter_context(
                tqdm(total=n, unit="epoch", desc="solving", file=sys.stderr, disable=None)
            )

            def report(done: int, _total: int) -> None:
                bar.update(done - bar.n)

        return solve_positions(
            obs,
            navs,
            sp3=sp3,
            config=config,
            chunk_epochs=CHUNK_EPOCHS,
            progress=report,
            raim=raim,
            ephemeris=ephemeris,
        )
