"""The run of ``navtrack pos`` (:mod:`navtrack.cli.pos` holds its options): check the inputs,
read them, solve every epoch with the positioning pipeline
(:func:`navtrack.positioning.solve_positions`), print the summary (:mod:`.pos_summary`),
write the solution and the figures."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack import __version__
from navtrack.cli import pos_summary as summary
from navtrack.cli._options import is_android_log, reference
from navtrack.cli.inputs import is_raw_log, read_observations
from navtrack.cli.network import network_jobs, run_network
from navtrack.cli.outputs import check_outputs
from navtrack.cli.pos import (
    DEFAULT_ELMASK_DEG,
    DEFAULT_IONO,
    DEFAULT_SYSTEMS,
    EXAMPLE_NAV,
    EXAMPLE_OBS,
    EXAMPLE_REF_SOURCE,
)
from navtrack.data import REFERENCE_XYZ_M, sample_path
from navtrack.errors import FileFormatError, NavtrackError
from navtrack.gnss.ephemeris import EphemerisTable, first_record_group_delays
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.nav import NavData, read_nav
from navtrack.gnss.spp import (
    CHUNK_EPOCHS,
    SppConfig,
    navigation_tables,
    observation_codes,
    subset_epochs,
)
from navtrack.io.solution import FORMATS, write_solution
from navtrack.positioning import PositionSolution, solution_frame, solve_positions
from navtrack.timescale import parse_gpst, select_epochs, to_datetime64, week_tow

if TYPE_CHECKING:
    from navtrack.gnss.sp3 import Sp3
    from navtrack.integrity.raim import RaimConfig

__all__ = ["run_pos"]


def run_pos(args: argparse.Namespace) -> int:
    """Run ``navtrack pos``; the exit code (0 solved, 1 nothing solved or not written)."""
    window = _time_window(args)  # first: a greedy --ts/--te may have taken the input files
    _check_inputs(args)
    config = _config(args)
    jobs = None if args.android or args.raw_log else network_jobs(args)
    if jobs is not None:
        if window is not None:
            raise SystemExit("navtrack pos: --ts/--te/--ti are for one station")
        return run_network(args, jobs, config)
    if args.workers is not None or args.scheduler is not None:
        raise SystemExit("navtrack pos: --workers/--scheduler need several observation files")
    ref = reference(args)
    check_outputs("navtrack pos", args.out, FORMATS, args.plot)

    obs, navs, sp3 = _read_inputs(args, config)
    n_read = len(obs.t_gps_s)
    if window is not None:
        obs = subset_epochs(obs, np.flatnonzero(select_epochs(obs.t_gps_s, *window)))
    if len(obs.t_gps_s) == 0:
        why = " selected by --ts/--te/--ti" if window is not None and n_read else ""
        print(f"navtrack pos: {args.obs}: no observation epochs{why}", file=sys.stderr)
        return 1
    if sp3 is None and not any(nav.tables for nav in navs):
        for why in summary.input_warnings(args, config, obs, navs):
            print(f"warning        {why}")
        names = ", ".join(map(str, args.nav or [args.obs]))
        print(
            f"navtrack pos: {names}: no ephemerides of the systems {config.systems}",
            file=sys.stderr,
        )
        return 1
    tables = None
    if args.rtklib_compatible:
        tables = first_record_group_delays(navigation_tables(navs))
    raim = _raim_config(args)
    result = _solve(obs, navs, sp3, config, not args.no_progress, raim, tables)

    summary.print_header(args, config, result, obs, navs, (len(obs.t_gps_s), n_read, bool(window)))
    solved = summary.print_statuses(result)
    if ref is not None and solved:
        source = getattr(args, "ref_source", "--ref-llh" if args.ref is None else "--ref")
        summary.print_errors(result, ref, source)
    summary.print_integrity(result, ref, args.hal, args.val)
    if solved == 0:
        summary.print_unsolved(result)
    table = solution_frame(result)
    table.update(summary.velocity_columns(obs, result, navs, sp3, config, solved))
    written = _write(args, table, summary.used_systems(result), obs, config)
    if args.plot is not None:
        # matplotlib: imported only when figures are asked for
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
    return 0 if solved and written else 1


def _check_inputs(args: argparse.Namespace) -> None:
    """The files of ``--example`` or of the command line, checked to exist; sets
    ``args.raw_log`` and ``args.android``."""
    if args.example:
        if args.obs is not None:
            raise SystemExit("navtrack pos: give either OBS NAV... or --example, not both")
        args.obs = sample_path(EXAMPLE_OBS)
        args.nav = [sample_path(EXAMPLE_NAV)]
        if args.ref is None and args.ref_llh is None:
            args.ref = list(REFERENCE_XYZ_M[EXAMPLE_OBS])
            args.ref_source = EXAMPLE_REF_SOURCE
    if args.obs is None:
        raise SystemExit("navtrack pos: give OBS and NAV files, or --example")
    if not args.obs.is_file():
        raise SystemExit(f"navtrack pos: observation file {str(args.obs)!r} not found")
    for p in [*args.nav, *([args.sp3] if args.sp3 else [])]:
        if not p.is_file():
            raise SystemExit(f"navtrack pos: file {str(p)!r} not found")
    args.raw_log = is_raw_log(args.obs)
    if not args.nav and args.sp3 is None and not args.raw_log:
        raise SystemExit(
            "navtrack pos: no navigation file given: positions need broadcast ephemerides "
            "(RINEX NAV) or precise orbits (--sp3)"
        )
    args.android = is_android_log(args.obs)


def _raim_config(args: argparse.Namespace) -> RaimConfig | None:
    """The RaimConfig of ``--raim/--pfa/--pmd/--ism`` (None for ``off``)."""
    if args.raim == "off":
        return None
    # integrity monitoring is imported only when asked for: pos's start-up without RAIM
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


def _read_inputs(
    args: argparse.Namespace, config: SppConfig
) -> tuple[Observations, list[NavData], Sp3 | None]:
    """The observations (of the configured systems' pseudorange codes only), navigation data
    (of those systems only) and precise orbits."""
    navs = [read_nav(p, systems=config.systems) for p in args.nav]
    if args.android:
        # the Android reader is loaded for an Android log only (`pos` start-up)
        from navtrack.gnss.android import read_gnsslogger

        obs = read_gnsslogger(args.obs)
    else:
        obs, log_nav = read_observations(
            args.obs,
            lenient=args.lenient,
            systems=config.systems,
            codes=observation_codes(config),
        )
        if log_nav is not None:
            navs.insert(0, log_nav)
    sp3 = None
    if args.sp3 is not None:
        from navtrack.gnss.sp3 import read_sp3  # precise orbits with --sp3 only (start-up)

        sp3 = read_sp3(args.sp3)
        for bad in sp3.implausible:
            print(f"navtrack pos: {args.sp3}, line {bad.line}: {bad.reason}", file=sys.stderr)
    return obs, navs, sp3


def _write(
    args: argparse.Namespace,
    table: dict[str, np.ndarray],
    systems: str,
    obs: Observations,
    config: SppConfig,
) -> bool:
    """Write ``--out`` (if given); False when it could not be written."""
    if args.out is None:
        return True
    try:
        path = write_solution(
            table,
            args.out,
            talker="GN" if len(systems) > 1 else "GP",
            nmea_rmc=True,
            header=_pos_header(args, obs, config),
        )
    except OSError as exc:
        print(f"navtrack pos: solution NOT written: {exc}", file=sys.stderr)
        return False
    print(f"written        {path}")
    return True


def _time_window(args: argparse.Namespace) -> tuple[float | None, float | None, float] | None:
    """``(start, end, interval)`` of ``--ts/--te/--ti`` in GPS seconds, or None without them."""
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


def _read_conf(args: argparse.Namespace) -> Any:
    """The RTKLIB option file of ``--conf`` (None without it)."""
    if args.conf is None:
        return None
    if not args.conf.is_file():
        raise SystemExit(f"navtrack pos: --conf file {str(args.conf)!r} not found")
    try:
        from navtrack.io.rtklib_conf import read_conf  # with --conf only (start-up)

        conf = read_conf(args.conf)
    except FileFormatError as exc:
        raise SystemExit(f"navtrack pos: {exc}") from None
    if conf.precise_ephemeris and args.sp3 is None:
        raise SystemExit(
            f"navtrack pos: {args.conf}, line {conf.lines['pos1-sateph']}: "
            "pos1-sateph=precise needs the SP3 file (--sp3)"
        )
    return conf


def _config(args: argparse.Namespace) -> SppConfig:
    """The solver settings: command line first, then ``--conf``, then navtrack's defaults."""
    conf = _read_conf(args)

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


_IONO_NAMES = {"klobuchar": "Broadcast", "ionofree": "Iono-Free LC", "off": "OFF"}
_SYSTEM_NAMES = {"G": "GPS", "R": "GLONASS", "E": "Galileo", "J": "QZSS", "C": "BeiDou"}


def _pos_header(args: argparse.Namespace, obs: Observations, config: SppConfig) -> list[str]:
    """Header lines of a ``.pos`` file: program, inputs, epochs and options, as RTKLIB's."""

    def when(t: float) -> str:
        week, tow = week_tow(t)
        text = str(to_datetime64(t).astype("datetime64[ms]")).replace("-", "/").replace("T", " ")
        return f"{text[:-2]} GPST (week{int(week)} {float(tow):.1f}s)"

    files: list[Path] = [args.obs, *args.nav, *([args.sp3] if args.sp3 else [])]
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


def _solve(
    obs: Observations,
    navs: list[NavData],
    sp3: Sp3 | None,
    config: SppConfig,
    progress: bool,
    raim: RaimConfig | None,
    ephemeris: Mapping[str, EphemerisTable] | None,
) -> PositionSolution:
    """Solve all epochs, with a progress bar on files of more than one block."""
    n = len(obs.t_gps_s)
    with contextlib.ExitStack() as stack:
        report = None
        if progress and n > CHUNK_EPOCHS:
            from tqdm import tqdm  # imported only for files long enough to show a bar

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
            raim=raim,
            chunk_epochs=CHUNK_EPOCHS,
            progress=report,
            ephemeris=ephemeris,
        )
