"""Real-data study of the AGPS reproduction: two satellites of real pseudoranges, twice.

For each shared data set (:data:`REAL_DATA_SETS`: the static stations 0759, ARL1, SEPT, the
yamatogawa master and the Android GnssLogger phone), the SPP stages of
:mod:`navtrack.gnss.spp` give corrected GPS L1 C/A pseudoranges and satellite states; the
assistance corrections (ionosphere, troposphere) are evaluated at a base station (cell) with
the reference position uniformly over a disc of ``cell_radius_m`` around it
(:func:`navtrack.positioning.agps.assisted_pseudoranges`).

Fine-time assistance: an AGPS phone gets GPS time from the network to about a microsecond, so
its clock biases are known to a few hundred metres before any iteration. Station receivers'
clocks are milliseconds off (0759's reaches 1355 km). The study therefore removes each epoch's
receiver clock as the network would know it — the clock of a single point position of all
satellites in view (:func:`navtrack.gnss.spp.solve_spp`) — and leaves an error
``U(-clock_bias_m, clock_bias_m)`` per epoch (300 m, as the simulation). The same fixes with
the station's own clocks are solved too (``station_clock``), an extension beyond an AGPS phone.
Fixes are sampled without replacement from all (epoch pair at the interval, satellite pair
usable at both epochs) combinations, then solved at the reference height plus the paper's
height offsets (its heights minus its true 56 m) with every solver, and compared with the
reference position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np

from navtrack.experiments.agps.simulation import SOLVER_NAMES
from navtrack.geodesy import ecef_to_geodetic, enu_rotation
from navtrack.gnss.agps import AgpsConfig, AgpsStatus, Solver
from navtrack.gnss.spp import Measurements, SppConfig, solve_spp
from navtrack.positioning.agps import assisted_pseudoranges, read_gps_measurements, solve_fixes

__all__ = ["REAL_DATA_SETS", "RealDataSet", "fix_pairs", "real_data_study"]

_SOLVERS = cast("tuple[Solver, ...]", SOLVER_NAMES)  # the solvers of the result arrays, in order


@dataclass(frozen=True, slots=True)
class RealDataSet:
    """One shared data set with its reference position.

    Attributes
    ----------
    name : str
    obs : str
        Observation file (RINEX, or Android GnssLogger ``.txt``), relative to the shared
        ``gnss`` folder.
    nav : str
        GPS navigation file, same.
    ref_xyz_m : tuple of float
        Reference position (ECEF, m), from ``shared/data/gnss/README.md``.
    """

    name: str
    obs: str
    nav: str
    ref_xyz_m: tuple[float, float, float]


REAL_DATA_SETS: tuple[RealDataSet, ...] = (
    RealDataSet(
        "0759",
        "rtklib_gsi0759/07590920.05o",
        "rtklib_gsi0759/07590920.05n",
        (-3976219.188, 3382371.606, 3652511.143),
    ),
    RealDataSet(
        "ARL1",
        "gpstk_arl1/arlm200a.15o",
        "gpstk_arl1/arlm2000.15n",
        (-740289.9180, -5457071.7340, 3207245.5420),
    ),
    RealDataSet(
        "SEPT",
        "cssrlib_sept/SEPT078M.21O",
        "cssrlib_sept/SEPT078M.21P",
        (-3962108.673, 3381309.574, 3668678.638),
    ),
    RealDataSet(
        "yamatogawa_master",
        "gogps_yamatogawa/yamatogawa_master.obs",
        "gogps_yamatogawa/brdc0060.10n",
        (-3749943.5172, 3683398.2394, 3600629.5295),
    ),
    RealDataSet(
        "android",
        "google_gnsslogger/pseudoranges_log_2016_08_22_14_45_50.txt",
        "google_gnsslogger/hour2350.16n",
        (-2693671.749, -4297132.643, 3854726.439),
    ),
)


def fix_pairs(
    t_gps_s: np.ndarray, usable: np.ndarray, interval_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """All (epoch pair, satellite pair) combinations at ``interval_s`` (within 0.5 s)."""
    ep: list[tuple[int, int]] = []
    sv: list[tuple[int, int]] = []
    j = np.searchsorted(t_gps_s, t_gps_s + interval_s - 0.5)
    for i, jj in enumerate(j):
        if jj >= t_gps_s.size or abs(t_gps_s[jj] - t_gps_s[i] - interval_s) > 0.5:
            continue
        both = np.flatnonzero(usable[i] & usable[jj])
        for a in range(both.size):
            for b in range(a + 1, both.size):
                ep.append((i, int(jj)))
                sv.append((int(both[a]), int(both[b])))
    return np.array(ep, dtype=np.int64).reshape(-1, 2), np.array(sv, dtype=np.int64).reshape(-1, 2)


def real_data_study(
    gnss_dir: Path,
    rng: np.random.Generator,
    *,
    height_offsets_m: tuple[float, ...],
    intervals_min: tuple[float, ...],
    fixes: int,
    cell_radius_m: float,
    clock_bias_m: float,
    config: AgpsConfig,
    elmask_deg: float = 15.0,
) -> tuple[dict[str, Any], list[str]]:
    """Solve sampled two-satellite fixes of every shared data set found.

    Parameters
    ----------
    gnss_dir : Path
        The shared ``gnss`` folder.
    rng : numpy.random.Generator
        Sampling of the fixes and base stations.
    height_offsets_m : tuple of float
        Assumed height minus the reference height (m).
    intervals_min : tuple of float
    fixes : int
        Fixes per data set and interval (fewer when fewer combinations exist).
    cell_radius_m : float
        The reference position lies uniformly over a disc of this radius around the cell (m).
    clock_bias_m : float
        Bound of the fine-time assistance error per epoch (m).
    config : AgpsConfig
        Solver options (its ``max_dop`` screens the fixes).
    elmask_deg : float

    Returns
    -------
    arrays : dict
        ``error_m``, ``iterations``, ``status`` of shape (n, solvers, intervals, heights),
        padded with NaN / 0 / status -1 where an interval has fewer fixes, and ``set`` (n,)
        the data set of each
        row; ``station_clock`` the (error, iterations, status) arrays (n, solvers, intervals)
        of the same fixes with the station's own clocks at the height offset nearest 0;
        ``n_fixes[name][interval]`` counts.
    skipped : list of str
        Data sets not run, with the reason.
    """
    cfg = SppConfig(systems="G", elmask_deg=elmask_deg)
    shape = (len(SOLVER_NAMES), len(intervals_min), len(height_offsets_m))
    zero_h = int(np.argmin(np.abs(np.asarray(height_offsets_m))))
    rows: list[_SetFixes] = []
    counts: dict[str, dict[str, int]] = {}
    skipped: list[str] = []
    for ds in REAL_DATA_SETS:
        if not (gnss_dir / ds.obs).is_file() or not (gnss_dir / ds.nav).is_file():
            skipped.append(f"{ds.name}: {ds.obs} or {ds.nav} not found under {gnss_dir}")
            continue
        obs, nav, meas = read_gps_measurements(gnss_dir / ds.obs, gnss_dir / ds.nav, cfg)
        network_clock_m = solve_spp(obs, nav, config=cfg).clock_m
        assist_error_m = rng.uniform(-clock_bias_m, clock_bias_m, network_clock_m.shape)
        fine_time = (assist_error_m - network_clock_m)[:, None]  # NaN: no network time
        ref = np.asarray(ds.ref_xyz_m)
        per_interval = _sample_fixes(
            meas, ref, fine_time, rng, intervals_min, fixes, cell_radius_m, cfg
        )
        counts[ds.name] = {
            f"{iv:g}": int(p[1].shape[0]) for iv, p in zip(intervals_min, per_interval, strict=True)
        }
        n_max = max((p[1].shape[0] for p in per_interval), default=0)
        if n_max == 0:
            skipped.append(f"{ds.name}: no satellite pair usable at two epochs at any interval")
            continue
        fixes_of_set = _SetFixes.empty(ds.name, n_max, shape)
        for ii, ep, sv, y, y_station in per_interval:
            if ep.shape[0]:
                run = _IntervalFixes(meas, ref, ii, ep, sv, y, y_station)
                _solve_interval(
                    run, fixes_of_set, rng, height_offsets_m, zero_h, cell_radius_m, config
                )
        rows.append(fixes_of_set)
    return _collect(rows, shape, counts), skipped


@dataclass(frozen=True, slots=True, eq=False)
class _IntervalFixes:
    """The sampled fixes of one data set at one interval: epoch and satellite pairs and the
    pseudoranges with fine-time assistance (``y``) and with the station's clocks."""

    meas: Measurements
    ref: np.ndarray
    interval: int
    epochs: np.ndarray
    sats: np.ndarray
    y: np.ndarray
    y_station: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class _SetFixes:
    """Error, iterations and status of the fixes of one data set, (n, solvers, intervals,
    heights), and with the station's clocks, (n, solvers, intervals)."""

    name: str
    err: np.ndarray
    its: np.ndarray
    sts: np.ndarray
    cc: tuple[np.ndarray, np.ndarray, np.ndarray]

    @classmethod
    def empty(cls, name: str, n_max: int, shape: tuple[int, int, int]) -> _SetFixes:
        n_s, n_i, _ = shape
        return cls(
            name,
            np.full((n_max, *shape), np.nan),
            np.zeros((n_max, *shape), dtype=np.int64),
            np.full((n_max, *shape), -1, dtype=np.int8),  # -1: padding, no fix
            (
                np.full((n_max, n_s, n_i), np.nan),
                np.zeros((n_max, n_s, n_i), dtype=np.int64),
                np.full((n_max, n_s, n_i), -1, dtype=np.int8),
            ),
        )


def _sample_fixes(
    meas: Measurements,
    ref: np.ndarray,
    fine_time: np.ndarray,
    rng: np.random.Generator,
    intervals_min: tuple[float, ...],
    fixes: int,
    cell_radius_m: float,
    cfg: SppConfig,
) -> list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per interval: up to ``fixes`` sampled (epoch pair, satellite pair) combinations and the
    assisted pseudoranges (with fine time, with the station's clocks)."""
    lat, lon, _ = ecef_to_geodetic(ref)
    rot = enu_rotation(lat, lon)
    per_interval = []
    for ii, interval in enumerate(intervals_min):
        # cells are drawn per fix; the atmosphere is evaluated at the data set's first cell
        az = rng.uniform(0.0, 2.0 * np.pi)
        dist = cell_radius_m * math.sqrt(rng.uniform())
        cell = ref + rot.T @ (dist * np.array([math.sin(az), math.cos(az), 0.0]))
        y_station = assisted_pseudoranges(meas, cell, cfg)
        y = y_station + fine_time
        ep, sv = fix_pairs(meas.t_gps_s, np.isfinite(y), 60.0 * interval)
        take = rng.permutation(ep.shape[0])[:fixes]
        per_interval.append((ii, ep[take], sv[take], y, y_station))
    return per_interval


def _solve_interval(
    run: _IntervalFixes,
    out: _SetFixes,
    rng: np.random.Generator,
    height_offsets_m: tuple[float, ...],
    zero_h: int,
    cell_radius_m: float,
    config: AgpsConfig,
) -> None:
    """Solve the fixes of one interval at every height offset with every solver (and with the
    station's clocks at the offset nearest 0) into ``out``."""
    ref, ii, n = run.ref, run.interval, run.epochs.shape[0]
    lat, lon, h_ref = ecef_to_geodetic(ref)
    rot = enu_rotation(lat, lon)
    az = rng.uniform(0.0, 2.0 * np.pi, n)
    dist = cell_radius_m * np.sqrt(rng.uniform(size=n))
    enu = np.stack([dist * np.sin(az), dist * np.cos(az), np.zeros(n)], axis=1)
    cells = ref + enu @ rot
    for hh, dh in enumerate(height_offsets_m):
        for j, solver in enumerate(_SOLVERS):
            res = solve_fixes(
                run.meas, run.y, run.epochs, run.sats, h_ref + dh, cells, solver, config
            )
            d = np.linalg.norm(res.pos_m - ref, axis=1)
            out.err[:n, j, ii, hh] = np.where(res.status == AgpsStatus.OK, d, np.nan)
            out.its[:n, j, ii, hh] = res.iterations
            out.sts[:n, j, ii, hh] = res.status
        if hh != zero_h:
            continue
        for j, solver in enumerate(_SOLVERS):
            res = solve_fixes(
                run.meas, run.y_station, run.epochs, run.sats, h_ref + dh, cells, solver, config
            )
            d = np.linalg.norm(res.pos_m - ref, axis=1)
            out.cc[0][:n, j, ii] = np.where(res.status == AgpsStatus.OK, d, np.nan)
            out.cc[1][:n, j, ii] = res.iterations
            out.cc[2][:n, j, ii] = res.status


def _collect(
    rows: list[_SetFixes], shape: tuple[int, int, int], counts: dict[str, dict[str, int]]
) -> dict[str, Any]:
    """The arrays of all data sets, concatenated (empty ones without any)."""
    if not rows:
        empty = np.zeros((0, *shape))
        return {
            "error_m": empty,
            "iterations": empty.astype(np.int64),
            "status": empty.astype(np.int8),
            "set": np.array([], dtype=str),
            "station_clock": tuple(np.zeros((0, *shape[:2])) for _ in range(3)),
            "n_fixes": counts,
        }
    return {
        "error_m": np.concatenate([r.err for r in rows]),
        "iterations": np.concatenate([r.its for r in rows]),
        "status": np.concatenate([r.sts for r in rows]),
        "set": np.array([r.name for r in rows for _ in range(r.err.shape[0])]),
        "station_clock": tuple(np.concatenate([r.cc[k] for r in rows]) for k in range(3)),
        "n_fixes": counts,
    }
