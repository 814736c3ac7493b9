"""Simulation of the AGPS reproduction: the paper's site, real broadcast ephemerides, known truth.

One Monte Carlo run (:func:`simulate_fix_set`) is one *fix set*: a reception time, two GPS
satellites visible at the site over the next 8 min, a base station, receiver clocks and
pseudorange errors; it is solved for every interval (2/4/6/8 min) and every assumed height of
the paper with each solver. 300 runs give the paper's 300 fixes per case.

Error model of a corrected pseudorange (all documented defaults of :class:`AgpsExperimentParams`):

* receiver noise and multipath of a weak-signal phone: white, ``sigma_noise_m`` = 5 m per
  pseudorange (C/N0 near 25–30 dB-Hz; the shared Android log's code residuals are of that
  order);
* residual ionosphere after the broadcast model: per satellite, a zenith error
  ``N(0, sigma_iono_zenith_m^2)`` (2 m: about half of a mid-latitude daytime Klobuchar error)
  times the thin-shell obliquity at each epoch;
* residual troposphere: one zenith error ``N(0, sigma_tropo_zenith_m^2)`` (0.1 m) times
  ``1 / sin(el)``;
* broadcast ephemeris error: per satellite a constant 3-D orbit offset ``N(0, sigma_orbit_m^2)``
  per axis (1 m: signal-in-space range error of GPS broadcast orbits and clocks, about 1 m)
  given to the solver with the satellite position;
* receiver clock: per epoch ``c dt_k ~ U(-clock_bias_m, clock_bias_m)`` (300 m: fine-time
  assistance of about 1 µs; the solvers start from zero);
* base station: ``U(base_distance_m)`` (1–5 km, "a few km", issue 12) from the truth in a
  uniformly random horizontal direction, at the site's height.

References
----------
J.-z. Li, ICCET 2010, section IV-B (site 39.959103° N, 116.352853° E, 56.23 m; 11 heights;
300 fixes; intervals 2, 4, 6, 8 min); IS-GPS-200N 20.3.3.5.2.5 (obliquity factor);
3GPP TS 44.031 (RRLP GPS reference time assistance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from navtrack._typing import FloatArray
from navtrack.geodesy import C_MPS, azimuth_elevation, enu_rotation, geodetic_to_ecef

if TYPE_CHECKING:
    from navtrack.gnss.agps import AgpsConfig, AgpsProblem

__all__ = [
    "PAPER_HEIGHTS_M",
    "PAPER_INTERVALS_MIN",
    "PAPER_SITE_LLH",
    "AgpsExperimentParams",
    "default_nav_path",
    "fix_set_problem",
    "simulate_fix_set",
    "solver_config",
]

PAPER_SITE_LLH = (39.959103, 116.352853, 56.23)
"""Reference position of the paper's receiver (deg, deg, m; NovAtel average, section IV-B)."""

PAPER_HEIGHTS_M = (-44.0, 16.0, 36.0, 46.0, 51.0, 56.0, 61.0, 66.0, 76.0, 96.0, 156.0)
"""The eleven assumed heights of Tables I and II (m)."""

PAPER_INTERVALS_MIN = (2.0, 4.0, 6.0, 8.0)
"""Intervals between the two measurements of Figs. 2 and 3 (min)."""

SOLVER_NAMES = ("gn", "lm", "map")


@dataclass(frozen=True, slots=True)
class AgpsExperimentParams:
    """Parameters of ``navtrack reproduce agps`` (defaults: the paper's set-up, section IV-B,
    and the documented error model of :mod:`navtrack.experiments.agps.simulation`).

    Attributes
    ----------
    nav : Path or None
        RINEX navigation file with GPS broadcast ephemerides (``--set nav=FILE``); None: the
        bundled ``hour2350.16n`` (CDDIS hourly merge, 2016 day 235, a full day of records).
    site_llh : tuple of float
        Truth: latitude (deg), longitude (deg), ellipsoidal height (m).
    heights_m : tuple of float
        Assumed heights (m).
    intervals_min : tuple of float
        Intervals between the two measurements (min).
    elmask_deg : float
        Satellites must be above this elevation at both epochs.
    base_distance_m : tuple of float
        Range of the base-station distance (m), uniform.
    near_cell_distance_m : tuple of float
        Sensitivity beyond the paper: the fixes at the true height are solved again from a cell
        at this distance range (m), in the same direction.
    sigma_noise_m, sigma_iono_zenith_m, sigma_tropo_zenith_m, sigma_orbit_m : float
        Error model (m), see the module docstring.
    clock_bias_m : float
        Receiver clock bias bound (m) per epoch.
    prior_sigma_m : float
        ``map`` solver: prior standard deviation of the cell position (m).
    lm_ellipsoid_scale : float
        Factor on the height equation in Marquardt's objective
        (:attr:`navtrack.gnss.agps.AgpsConfig.lm_ellipsoid_scale`): 1 is the paper's
        dimensionless ``f_5``; 3.19e6 (``(a + h) / 2``) puts it in metres of height.
    clock_start : {"zero", "cell"}
        Start of the clock biases (:attr:`navtrack.gnss.agps.AgpsConfig.clock_start`; the
        paper: zero).
    real_data : bool
        Run the real-data study on the shared stations and the Android log.
    real_fixes : int
        Fixes per data set and interval in the real-data study (sampled without replacement
        from all satellite and epoch pairs).
    """

    nav: Path | None = None
    site_llh: tuple[float, float, float] = PAPER_SITE_LLH
    heights_m: tuple[float, ...] = PAPER_HEIGHTS_M
    intervals_min: tuple[float, ...] = PAPER_INTERVALS_MIN
    elmask_deg: float = 15.0
    base_distance_m: tuple[float, float] = (1000.0, 5000.0)
    near_cell_distance_m: tuple[float, float] = (200.0, 500.0)
    sigma_noise_m: float = 5.0
    sigma_iono_zenith_m: float = 2.0
    sigma_tropo_zenith_m: float = 0.1
    sigma_orbit_m: float = 1.0
    clock_bias_m: float = 300.0
    prior_sigma_m: float = 3000.0
    lm_ellipsoid_scale: float = 1.0
    clock_start: Literal["zero", "cell"] = "zero"
    real_data: bool = True
    real_fixes: int = 300

    def __post_init__(self) -> None:
        lo, hi = self.base_distance_m
        if not 0.0 <= lo <= hi:
            raise ValueError(f"base_distance_m: expected 0 <= lo <= hi, got {self.base_distance_m}")
        if not self.intervals_min or min(self.intervals_min) <= 0.0:
            raise ValueError(
                f"intervals_min: expected positive intervals, got {self.intervals_min}"
            )
        if not self.heights_m:
            raise ValueError("heights_m: expected at least one assumed height")
        if self.nav is not None and not Path(self.nav).is_file():
            raise ValueError(f"nav: navigation file {self.nav} not found")


def solver_config(params: AgpsExperimentParams) -> AgpsConfig:
    """The solver options of the study: the paper's Marquardt parameters, the scale of the
    height equation, the MAP prior and pseudorange sigma (the root sum square of the error
    model's zenith-level terms, at least 0.1 m)."""
    from navtrack.gnss.agps import AgpsConfig

    sigma = math.hypot(
        params.sigma_noise_m,
        params.sigma_iono_zenith_m,
        params.sigma_tropo_zenith_m,
        params.sigma_orbit_m,
    )
    return AgpsConfig(
        prior_sigma_m=params.prior_sigma_m,
        sigma_pr_m=max(sigma, 0.1),
        lm_ellipsoid_scale=params.lm_ellipsoid_scale,
        clock_start=params.clock_start,
    )


def default_nav_path() -> Path:
    """The bundled full-day GPS navigation file ``hour2350.16n``."""
    import importlib.resources

    return Path(str(importlib.resources.files("navtrack.data") / "hour2350.16n"))


@lru_cache(maxsize=4)
def _gps_tables(path: str) -> tuple[dict[str, Any], tuple[str, ...], float, float]:
    """GPS ephemeris tables of a navigation file, its satellites and its toe span (GPS s)."""
    from navtrack.gnss.ephemeris import ephemeris_tables
    from navtrack.gnss.rinex.nav import read_nav

    tables = ephemeris_tables(read_nav(path))
    if "G" not in tables:
        raise ValueError(f"nav: {path} holds no GPS ephemerides")
    gps = tables["G"]
    toe = gps.get("toe_gps_s")
    toe = toe[np.isfinite(toe)]
    if toe.size == 0:
        raise ValueError(f"nav: {path} holds no GPS ephemerides with a reference time")
    return {"G": gps}, tuple(sorted(set(gps.sat.tolist()))), float(toe.min()), float(toe.max())


def _obliquity(el_rad: FloatArray) -> FloatArray:
    """Thin-shell (350 km) ionospheric obliquity factor."""
    r = 6378.137e3 / (6378.137e3 + 350e3)
    return np.asarray(1.0 / np.sqrt(1.0 - (r * np.cos(el_rad)) ** 2))


def _states(
    tables: dict[str, Any], sats: tuple[str, ...], t_rx: FloatArray, truth: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """Satellite positions at transmission seen from ``truth`` (E, S, 3), and validity (E, S)."""
    from navtrack.gnss.corrections import geometric_range
    from navtrack.gnss.ephemeris import broadcast_states

    t_tx = np.repeat((t_rx - 0.075)[:, None], len(sats), axis=1)
    for _ in range(2):
        st = broadcast_states(tables, sats, t_rx, t_tx)
        rho, _ = geometric_range(np.where(st.valid[..., None], st.pos_m, 0.0), truth)
        t_tx = t_rx[:, None] - rho / C_MPS
    return st.pos_m, st.valid & (st.svh == 0)


def fix_set_problem(
    params: AgpsExperimentParams, rng: np.random.Generator
) -> tuple[AgpsProblem, FloatArray, dict[str, Any]]:
    """Draw one fix set: the fixes of every interval and assumed height (interval-major).

    Parameters
    ----------
    params : AgpsExperimentParams
    rng : numpy.random.Generator

    Returns
    -------
    problem : AgpsProblem
        ``intervals x heights`` fixes sharing the first epoch, the satellites, the errors and
        the base station.
    truth_m : ndarray, shape (3,)
        The true position (ECEF, m).
    meta : dict
        ``sats`` (the pair), ``t_gps_s`` (first epoch), ``base_distance_m``.
    """
    from navtrack.gnss.agps import AgpsProblem
    from navtrack.gnss.corrections import geometric_range

    nav = params.nav if params.nav is not None else default_nav_path()
    tables, sats, t_lo, t_hi = _gps_tables(str(nav))
    lat, lon = math.radians(params.site_llh[0]), math.radians(params.site_llh[1])
    truth = geodetic_to_ecef(np.array([lat, lon, params.site_llh[2]]))
    offsets_s = 60.0 * np.array((0.0, *params.intervals_min))
    span = offsets_s[-1] if offsets_s.size else 0.0
    for _attempt in range(50):
        t1 = float(rng.uniform(t_lo, max(t_lo, t_hi - span)))
        t_rx = t1 + offsets_s
        pos, valid = _states(tables, sats, t_rx, truth)
        el = azimuth_elevation(np.where(valid[..., None], pos, 0.0), truth)[..., 1]
        seen = np.flatnonzero((valid & (el >= math.radians(params.elmask_deg))).all(axis=0))
        if seen.size >= 2:
            break
    else:
        raise ValueError(f"nav: no two GPS satellites visible at the site over {span} s in {nav}")
    pair = rng.choice(seen, size=2, replace=False)
    sat_true = pos[:, pair]  # (E, 2, 3)
    el_pair = el[:, pair]
    # errors
    orbit = rng.normal(0.0, params.sigma_orbit_m, size=(2, 3))
    iono_zenith = rng.normal(0.0, params.sigma_iono_zenith_m, size=2)
    tropo_zenith = rng.normal(0.0, params.sigma_tropo_zenith_m)
    rho, _ = geometric_range(sat_true, truth)  # (E, 2)
    atmosphere = iono_zenith * _obliquity(el_pair) + tropo_zenith / np.sin(el_pair)
    noise = rng.normal(0.0, params.sigma_noise_m, size=rho.shape)
    clock = rng.uniform(-params.clock_bias_m, params.clock_bias_m, size=(rho.shape[0], 1))
    y = rho + clock + atmosphere + noise
    sat_given = sat_true + orbit
    dist = rng.uniform(*params.base_distance_m)
    az = rng.uniform(0.0, 2.0 * np.pi)
    enu = dist * np.array([math.sin(az), math.cos(az), 0.0])
    start = truth + enu_rotation(lat, lon).T @ enu

    n_i, n_h = len(params.intervals_min), len(params.heights_m)
    k = np.repeat(np.arange(1, n_i + 1), n_h)  # second epoch of each fix
    heights = np.tile(np.asarray(params.heights_m, dtype=float), n_i)
    n = k.size
    problem = AgpsProblem(
        t_gps_s=np.stack([np.full(n, t_rx[0]), t_rx[k]], axis=1),
        sat_pos_m=np.concatenate([np.repeat(sat_given[None, 0], n, 0), sat_given[k]], axis=1),
        y_m=np.concatenate([np.repeat(y[None, 0], n, 0), y[k]], axis=1),
        height_m=heights,
        start_xyz_m=np.repeat(start[None], n, 0),
        usable=np.ones((n, 4), dtype=bool),
    )
    meta = {"sats": tuple(sats[i] for i in pair), "t_gps_s": t1, "base_distance_m": dist}
    return problem, truth, meta


def simulate_fix_set(params: AgpsExperimentParams, rng: np.random.Generator) -> dict[str, Any]:
    """One fix set (:func:`fix_set_problem`) solved for every interval, assumed height and
    solver.

    Parameters
    ----------
    params : AgpsExperimentParams
    rng : numpy.random.Generator

    Returns
    -------
    dict
        ``error_m``, ``horizontal_m``, ``iterations``, ``status``: arrays of shape
        (solvers, intervals, heights) — 3-D and horizontal distance of the fix to the truth (m,
        NaN where not ``ok``), linear solves, :class:`~navtrack.gnss.agps.AgpsStatus`;
        ``sats`` (the pair), ``t_gps_s`` (first epoch), ``base_distance_m``.
    """
    from navtrack.gnss.agps import AgpsStatus, solve_agps

    problem, truth, meta = fix_set_problem(params, rng)
    n_i, n_h = len(params.intervals_min), len(params.heights_m)
    lat, lon = math.radians(params.site_llh[0]), math.radians(params.site_llh[1])
    config = solver_config(params)
    shape = (len(SOLVER_NAMES), n_i, n_h)
    out: dict[str, Any] = {
        "error_m": np.full(shape, np.nan),
        "horizontal_m": np.full(shape, np.nan),
        "iterations": np.zeros(shape, dtype=np.int64),
        "status": np.zeros(shape, dtype=np.int8),
        **meta,
    }
    rot = enu_rotation(lat, lon)
    for j, solver in enumerate(SOLVER_NAMES):
        res = solve_agps(problem, solver, config)  # type: ignore[arg-type]
        d = res.pos_m - truth
        ok = res.status == AgpsStatus.OK
        err = np.where(ok, np.linalg.norm(d, axis=1), np.nan)
        horiz = np.where(ok, np.linalg.norm((d @ rot.T)[:, :2], axis=1), np.nan)
        out["error_m"][j] = err.reshape(n_i, n_h)
        out["horizontal_m"][j] = horiz.reshape(n_i, n_h)
        out["iterations"][j] = res.iterations.reshape(n_i, n_h)
        out["status"][j] = res.status.reshape(n_i, n_h)
    out.update(_near_cell(params, rng, problem, truth, config))
    return out


def _near_cell(
    params: AgpsExperimentParams,
    rng: np.random.Generator,
    problem: AgpsProblem,
    truth: FloatArray,
    config: AgpsConfig,
) -> dict[str, np.ndarray]:
    """The fixes at the height nearest the truth's, solved from a cell moved to
    ``near_cell_distance_m`` along the same direction: ``near_error_m``, ``near_iterations``,
    ``near_status`` of shape (solvers, intervals)."""
    from navtrack.gnss.agps import AgpsProblem, AgpsStatus, solve_agps

    n_i, n_h = len(params.intervals_min), len(params.heights_m)
    h0 = int(np.argmin(np.abs(np.asarray(params.heights_m) - params.site_llh[2])))
    rows = np.arange(n_i) * n_h + h0
    offset = problem.start_xyz_m[0] - truth
    dist = rng.uniform(*params.near_cell_distance_m)
    start = truth + offset * (dist / max(float(np.linalg.norm(offset)), 1e-9))
    near = AgpsProblem(
        problem.t_gps_s[rows],
        problem.sat_pos_m[rows],
        problem.y_m[rows],
        problem.height_m[rows],
        np.repeat(start[None], rows.size, 0),
        problem.usable[rows],
    )
    shape = (len(SOLVER_NAMES), n_i)
    out = {
        "near_error_m": np.full(shape, np.nan),
        "near_iterations": np.zeros(shape, dtype=np.int64),
        "near_status": np.zeros(shape, dtype=np.int8),
    }
    for j, solver in enumerate(SOLVER_NAMES):
        res = solve_agps(near, solver, config)  # type: ignore[arg-type]
        ok = res.status == AgpsStatus.OK
        out["near_error_m"][j] = np.where(ok, np.linalg.norm(res.pos_m - truth, axis=1), np.nan)
        out["near_iterations"][j] = res.iterations
        out["near_status"][j] = res.status
    return out
