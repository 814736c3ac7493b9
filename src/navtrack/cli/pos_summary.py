"""The console summary of ``navtrack pos``: inputs and models, epochs per status, errors against
a reference, integrity (RAIM status counts, protection levels, availability, misleading
information) and the velocity line."""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from typing import TYPE_CHECKING

import numpy as np

from navtrack._typing import FloatArray
from navtrack.geodesy import ecef_to_enu
from navtrack.gnss.accuracy import enu_error_stats
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.nav import NavData
from navtrack.gnss.spp import STATUS_NAMES, SppConfig, SppResult, klobuchar_params
from navtrack.gnss.velocity import doppler_velocity
from navtrack.positioning import PositionSolution

if TYPE_CHECKING:
    from navtrack.gnss.sp3 import Sp3

__all__ = [
    "input_warnings",
    "median_finite",
    "print_errors",
    "print_header",
    "print_integrity",
    "print_statuses",
    "used_systems",
    "velocity_columns",
]


def median_finite(values: FloatArray) -> float:
    """Median of the finite values (NaN when none), from a sort: ``np.median`` and
    ``np.nanmedian`` import ``numpy.ma`` (12 ms of every run's start-up)."""
    v = np.sort(values[np.isfinite(values)])
    if v.size == 0:
        return float("nan")
    mid = v.size // 2
    return float(v[mid]) if v.size % 2 else float(0.5 * (v[mid - 1] + v[mid]))


def used_systems(result: SppResult) -> str:
    """The systems of satellites that entered a solution, not those merely observed."""
    used_sats = {result.sats[j][0] for j in np.flatnonzero(result.used.any(axis=0))}
    return "".join(s for s in "GRECJI" if s in used_sats)


def input_warnings(
    args: argparse.Namespace, config: SppConfig, obs: Observations, navs: list[NavData]
) -> list[str]:
    """What the inputs leave out of the model or the solution: a broadcast ionosphere without
    parameters, a system asked for that the file does not hold."""
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


def print_header(
    args: argparse.Namespace,
    config: SppConfig,
    result: SppResult,
    obs: Observations,
    navs: list[NavData],
    epochs: tuple[int, int, bool],
) -> None:
    """Inputs, systems and models, warnings, options file and epochs (``(selected, read,
    windowed)``)."""
    n_epochs, n_read, windowed = epochs
    print(f"observations   {args.obs}")
    nav_names = ", ".join(str(p) for p in args.nav) or ("from the log" if args.raw_log else "-")
    print(f"navigation     {nav_names}" + (f"  sp3 {args.sp3}" if args.sp3 else ""))
    print(
        f"systems        {used_systems(result) or '-'}  (clocks: {', '.join(result.clock_groups)}; "
        f"weighting {config.weighting}, elevation mask {config.elmask_deg:g} deg)"
    )
    for model, setting in (("ionosphere", config.iono), ("troposphere", config.tropo)):
        if setting == "off":
            print(f"warning        {model} model switched off")
    for why in input_warnings(args, config, obs, navs):
        print(f"warning        {why}")
    if args.conf is not None:
        print(f"options        {args.conf} (RTKLIB option file)")
    print(f"epochs         {n_epochs}" + (f" of {n_read} (--ts/--te/--ti)" if windowed else ""))
    if obs.skipped:
        reasons = Counter(sk.reason for sk in obs.skipped)
        listed = "; ".join(f"{r}: {n}" for r, n in reasons.most_common())
        print(f"rows skipped   {len(obs.skipped)} ({listed})")


def print_statuses(result: SppResult) -> int:
    """Solved epochs, epochs per status, satellites without ephemeris, satellites and PDOP;
    returns the number of solved epochs."""
    counts = result.status_counts()
    solved = counts["ok"]
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
            f"PDOP median {median_finite(result.dop[ok, 1]):.2f}"
        )
    return solved


def print_errors(result: SppResult, ref: tuple[float, float, float], source: str) -> None:
    """Mean, RMS and 95 % of the horizontal, vertical and 3-D errors of the ``ok`` epochs."""
    print(f"reference      {ref[0]:.3f} {ref[1]:.3f} {ref[2]:.3f} (ECEF m; {source})")
    st = enu_error_stats(ecef_to_enu(result.pos_m[result.status == 0], np.asarray(ref)))
    print("error vs ref   mean      RMS       95 %    (m)")
    for key, name in (("horizontal", "horizontal"), ("up", "vertical"), ("3D", "3D")):
        print(f"  {name:<12} {st[key].mean_m:8.3f}  {st[key].rms_m:8.3f}  {st[key].p95_m:8.3f}")
    e, n, u = (st[k].mean_m for k in ("east", "north", "up"))
    print(f"  mean ENU     {e:8.3f}  {n:8.3f}  {u:8.3f}")


def print_integrity(
    result: PositionSolution, ref: tuple[float, float, float] | None, hal_m: float, val_m: float
) -> None:
    """Integrity lines: epochs per RAIM status, exclusions per satellite, median protection
    levels, availability (HPL <= HAL and VPL <= VAL; HPL <= HAL) and, with a reference, the
    epochs of misleading information."""
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
        hpl, vpl = median_finite(integ.hpl_m), median_finite(integ.vpl_m)
        print(f"  HPL/VPL      median {hpl:.2f} / {vpl:.2f} m")
    av = integ.availability(hal_m, val_m)
    print(
        f"  availability {100 * av['vertical']:.1f} % (HPL <= {hal_m:g} m, VPL <= {val_m:g} m), "
        f"horizontal {100 * av['horizontal']:.1f} % (HPL <= {hal_m:g} m)"
    )
    if ref is None:
        return
    enu = ecef_to_enu(result.pos_m, np.asarray(ref))
    ok = integ.usable & np.isfinite(enu[:, 0])
    with np.errstate(invalid="ignore"):
        mi_h = int(np.sum(ok & (np.hypot(enu[:, 0], enu[:, 1]) > integ.hpl_m)))
        mi_v = int(np.sum(ok & (np.abs(enu[:, 2]) > integ.vpl_m)))
    print(f"  misleading   {mi_h} / {mi_v} epochs error > HPL / VPL (ok or excluded)")


def print_unsolved(result: SppResult) -> None:
    """The error line of a run that solved no epoch: the most frequent status, with a hint."""
    counts = result.status_counts()
    cause = max(((v, k) for k, v in counts.items() if k != "ok"), default=(0, "?"))[1]
    hint = ""
    if cause == "no_ephemeris":
        hint = (
            " (the navigation data do not cover these satellites and epochs: check that "
            "the NAV file matches the observation day and systems)"
        )
    print(f"navtrack pos: no epoch could be solved; most epochs: {cause}{hint}", file=sys.stderr)


def velocity_columns(
    obs: Observations,
    result: SppResult,
    navs: list[NavData],
    sp3: Sp3 | None,
    config: SppConfig,
    solved: int,
) -> dict[str, FloatArray]:
    """``ve_mps``, ``vn_mps``, ``vu_mps`` and ``drift_mps`` from the Doppler measurements
    (NaN without them), with a summary line."""
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
