"""Simulation of the AGPS reproduction: the paper's site, real broadcast ephemerides, known truth.

One Monte Carlo run (:func:`simulate_fix_set`) is one *fix set*: a reception time, two GPS
satellites visible at the site over the next 8 min, a base station, receiver clocks and
pseudorange errors; it is solved for every interval (2/4/6/8 min) and every assumed height of
the paper with each solver. 300 runs give the paper's 300 fixes per case.

Error model of a corrected pseudorange (all documented defaults of :class:`AgpsExperimentParams`):

* receiver noise and multipath of a weak-signal phone: white, ``sigma_noise_m`` per
  pseudorange (3 m, calibrated on the paper's Gauss–Newton Table I, see below);
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
* base station (the cell the fix starts from): the phone uniformly over a disc of radius
  ``cell_radius_m`` around it, at the site's height (500 m, calibrated as below).

Satellite pair: two GPS satellites above ``elmask_deg`` at the site over all intervals whose
two-minute fix has a DOP (:func:`navtrack.gnss.agps.fix_dop`) at most ``max_dop``, drawn at
random among those.

Calibration (:mod:`navtrack.experiments.agps.calibration`): Gauss–Newton has no tunable
parameter, so the paper's Table I (its 2-min error percentiles and means at the 11 heights)
fixes the unstated ``sigma_noise_m``, ``elmask_deg`` and ``max_dop``; its Table III (2.000
iterations) bounds ``cell_radius_m``, the only setting that changes Gauss–Newton's iterations.
Marquardt's Table II, Table III and Figs. 2–3 are then predictions.

References
----------
J.-z. Li, ICCET 2010, section IV-B (site 39.959103° N, 116.352853° E, 56.23 m; 11 heights;
300 fixes; intervals 2, 4, 6, 8 min); IS-GPS-200N 20.3.3.5.2.5 (obliquity factor);
3GPP TS 44.031 (RRLP GPS reference time assistance).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Literal

import numpy as np

from navtrack._typing import FloatArray, IntArray
from navtrack.geodesy import C_MPS, azimuth_elevation, enu_rotation, geodetic_to_ecef
from navtrack.gnss.agps import AgpsConfig, AgpsProblem, AgpsStatus, F5Units, fix_dop, solve_agps
from navtrack.gnss.corrections import geometric_range
from navtrack.gnss.ephemeris import broadcast_states, ephemeris_tables
from navtrack.gnss.rinex.nav import read_nav

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
    max_dop : float
        Geometry screen of the satellite pair: DOP of its fix at the first interval.
    cell_radius_m : float
        The phone lies uniformly over a disc of this radius (m) around the cell.
    cell_radius_sweep_m : tuple of float
        Sensitivity: the 2-min fixes re-solved from cells at these radii (same direction,
        same fraction of the radius).
    noise_sweep : tuple of float
        Sensitivity: the 2-min fixes re-solved with the white noise scaled by these factors.
    sigma_noise_m, sigma_iono_zenith_m, sigma_tropo_zenith_m, sigma_orbit_m : float
        Error model (m), see the module docstring.
    clock_bias_m : float
        Receiver clock bias bound (m) per epoch.
    prior_sigma_m : float or None
        ``map`` solver: prior standard deviation of the cell position per axis (m); None: half
        the cell radius, the standard deviation per axis of a phone uniform over the disc.
    f5_units : {"m", "dimensionless"}
        Scale of the height equation in Marquardt's objective
        (:attr:`navtrack.gnss.agps.AgpsConfig.f5_units`); the other reading is solved too, as
        a sensitivity.
    clock_start : {"zero", "cell"}
        Start of the clock biases (:attr:`navtrack.gnss.agps.AgpsConfig.clock_start`; the
        paper: zero).
    real_data : bool
        Run the real-data study on the shared stations and the Android log.
    real_fixes : int
        Fixes per data set and interval in the real-data study (sampled without replacement
        from all satellite and epoch pairs).
    real_max_dop : float
        Geometry screen of the real-data fixes (and of ``navtrack agps``).
    """

    nav: Path | None = None
    site_llh: tuple[float, float, float] = PAPER_SITE_LLH
    heights_m: tuple[float, ...] = PAPER_HEIGHTS_M
    intervals_min: tuple[float, ...] = PAPER_INTERVALS_MIN
    elmask_deg: float = 15.0
    max_dop: float = 700.0
    cell_radius_m: float = 500.0
    cell_radius_sweep_m: tuple[float, ...] = (0.0, 100.0, 250.0, 500.0, 1000.0, 2000.0, 5000.0)
    noise_sweep: tuple[float, ...] = (0.5, 1.0, 2.0)
    sigma_noise_m: float = 3.0
    sigma_iono_zenith_m: float = 2.0
    sigma_tropo_zenith_m: float = 0.1
    sigma_orbit_m: float = 1.0
    clock_bias_m: float = 300.0
    prior_sigma_m: float | None = None
    f5_units: F5Units = "m"
    clock_start: Literal["zero", "cell"] = "zero"
    real_data: bool = True
    real_fixes: int = 300
    real_max_dop: float = 700.0

    def __post_init__(self) -> None:
        radii = (self.cell_radius_m, *self.cell_radius_sweep_m)
        if not all(math.isfinite(r) and r >= 0.0 for r in radii):
            raise ValueError(f"cell_radius_m: expected radii >= 0 m, got {radii}")
        if not self.max_dop > 0.0 or not self.real_max_dop > 0.0:
            raise ValueError("max_dop: expected a positive DOP screen")
        if not all(k >= 0.0 for k in self.noise_sweep):
            raise ValueError(f"noise_sweep: expected factors >= 0, got {self.noise_sweep}")
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
    model's zenith-level terms, at least 0.1 m). The paper's statistics count every fix: no
    plausibility checks, and no geometry screen (the simulated pairs are screened when drawn,
    the real-data study sets its own)."""

    sigma = math.hypot(
        params.sigma_noise_m,
        params.sigma_iono_zenith_m,
        params.sigma_tropo_zenith_m,
        params.sigma_orbit_m,
    )
    return AgpsConfig(
        prior_sigma_m=(
            params.prior_sigma_m
            if params.prior_sigma_m is not None
            else max(params.cell_radius_m / 2.0, 1.0)
        ),
        sigma_pr_m=max(sigma, 0.1),
        f5_units=params.f5_units,
        clock_start=params.clock_start,
        max_height_residual_m=math.inf,
        max_residual_m=math.inf,
    )


def default_nav_path() -> Path:
    """The bundled full-day GPS navigation file ``hour2350.16n``."""
    return Path(str(importlib.resources.files("navtrack.data") / "hour2350.16n"))


@lru_cache(maxsize=4)
def _gps_tables(path: str) -> tuple[dict[str, Any], tuple[str, ...], float, float]:
    """GPS ephemeris tables of a navigation file, its satellites and its toe span (GPS s)."""

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

    t_tx = np.repeat((t_rx - 0.075)[:, None], len(sats), axis=1)
    for _ in range(2):
        st = broadcast_states(tables, sats, t_rx, t_tx)
        rho, _ = geometric_range(np.where(st.valid[..., None], st.pos_m, 0.0), truth)
        t_tx = t_rx[:, None] - rho / C_MPS
    return st.pos_m, st.valid & (st.svh == 0)


def _pair_dops(
    sat_pos_m: FloatArray, seen: np.ndarray, t_rx: FloatArray, cell: FloatArray, height_m: float
) -> tuple[np.ndarray, FloatArray]:
    """All pairs of the satellites ``seen`` and the DOP of their fix over the first interval
    (epochs 0 and 1), solved from ``cell``."""

    i, j = np.triu_indices(seen.size, k=1)
    pairs = np.stack([seen[i], seen[j]], axis=1)
    n = pairs.shape[0]
    pos = np.concatenate([sat_pos_m[0][pairs], sat_pos_m[1][pairs]], axis=1)
    problem = AgpsProblem(
        t_gps_s=np.repeat(t_rx[None, :2], n, 0),
        sat_pos_m=pos,
        y_m=np.zeros((n, 4)),
        height_m=np.full(n, height_m),
        start_xyz_m=np.repeat(cell[None], n, 0),
        usable=np.ones((n, 4), dtype=bool),
    )
    return pairs, fix_dop(problem)


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
        ``sats`` (the pair), ``t_gps_s`` (first epoch), ``cell_direction`` (ECEF unit vector
        from the truth to the cell) and ``cell_fraction`` (its distance over the cell radius),
        ``dop`` (the pair's DOP at the first interval), ``noise_m`` (the white noise in
        ``problem.y_m``, same shape, for the noise sensitivity).
    """

    nav = params.nav if params.nav is not None else default_nav_path()
    sats = _gps_tables(str(nav))[1]
    lat, lon = math.radians(params.site_llh[0]), math.radians(params.site_llh[1])
    truth = geodetic_to_ecef(np.array([lat, lon, params.site_llh[2]]))
    fraction = math.sqrt(rng.uniform())  # uniform over the disc
    az = rng.uniform(0.0, 2.0 * np.pi)
    direction = enu_rotation(lat, lon).T @ np.array([math.sin(az), math.cos(az), 0.0])
    cell = truth + params.cell_radius_m * fraction * direction
    t1, t_rx, pos, el, pair, pair_dop = _draw_pair(params, str(nav), truth, cell, rng)
    sat_true = pos[:, pair]  # (E, 2, 3)
    el_pair = el[:, pair]
    orbit = rng.normal(0.0, params.sigma_orbit_m, size=(2, 3))
    iono_zenith = rng.normal(0.0, params.sigma_iono_zenith_m, size=2)
    tropo_zenith = rng.normal(0.0, params.sigma_tropo_zenith_m)
    rho, _ = geometric_range(sat_true, truth)  # (E, 2)
    atmosphere = iono_zenith * _obliquity(el_pair) + tropo_zenith / np.sin(el_pair)
    noise = rng.normal(0.0, params.sigma_noise_m, size=rho.shape)
    clock = rng.uniform(-params.clock_bias_m, params.clock_bias_m, size=(rho.shape[0], 1))
    y = rho + clock + atmosphere + noise
    sat_given = sat_true + orbit

    n_i, n_h = len(params.intervals_min), len(params.heights_m)
    k2 = np.repeat(np.arange(1, n_i + 1), n_h)  # second epoch of each fix
    n = k2.size

    def both(a: FloatArray) -> FloatArray:
        return np.concatenate([np.repeat(a[None, 0], n, 0), a[k2]], axis=1)

    problem = AgpsProblem(
        t_gps_s=np.stack([np.full(n, t_rx[0]), t_rx[k2]], axis=1),
        sat_pos_m=both(sat_given),
        y_m=both(y),
        height_m=np.tile(np.asarray(params.heights_m, dtype=float), n_i),
        start_xyz_m=np.repeat(cell[None], n, 0),
        usable=np.ones((n, 4), dtype=bool),
    )
    meta = {
        "sats": tuple(sats[i] for i in pair),
        "t_gps_s": t1,
        "cell_direction": direction,
        "cell_fraction": fraction,
        "dop": pair_dop,
        "noise_m": both(noise),
    }
    return problem, truth, meta


def _draw_pair(
    params: AgpsExperimentParams,
    nav: str,
    truth: FloatArray,
    cell: FloatArray,
    rng: np.random.Generator,
) -> tuple[float, FloatArray, FloatArray, FloatArray, IntArray, float]:
    """A first epoch and a satellite pair seen above the mask at every interval with a DOP at
    most ``max_dop`` (up to 100 draws): the epoch, the epochs' times, the satellite positions
    and elevations of all satellites, the pair and its DOP."""
    tables, sats, t_lo, t_hi = _gps_tables(nav)
    offsets_s = 60.0 * np.array((0.0, *params.intervals_min))
    span = offsets_s[-1] if offsets_s.size else 0.0
    for _attempt in range(100):
        t1 = float(rng.uniform(t_lo, max(t_lo, t_hi - span)))
        t_rx = t1 + offsets_s
        pos, valid = _states(tables, sats, t_rx, truth)
        el = azimuth_elevation(np.where(valid[..., None], pos, 0.0), truth)[..., 1]
        seen = np.flatnonzero((valid & (el >= math.radians(params.elmask_deg))).all(axis=0))
        if seen.size < 2:
            continue
        pairs, dop = _pair_dops(pos, seen, t_rx, cell, params.site_llh[2])
        good = np.flatnonzero(dop <= params.max_dop)
        if good.size:
            k = int(rng.choice(good))
            return t1, t_rx, pos, el, pairs[k], float(dop[k])
    raise ValueError(
        f"nav: no two GPS satellites above {params.elmask_deg:g} deg with a DOP at most "
        f"{params.max_dop:g} at the site over {span:g} s in 100 draws from {nav}"
    )


def sensitivity_names(params: AgpsExperimentParams) -> list[str]:
    """Names of the sensitivity variants of :func:`simulate_fix_set`: the other ``f5``
    reading, each cell radius of the sweep, each noise factor."""
    other = "dimensionless" if params.f5_units == "m" else "m"
    return [
        f"f5_{other}",
        *(f"cell_{r:g}" for r in params.cell_radius_sweep_m),
        *(f"noise_{k:g}" for k in params.noise_sweep),
    ]


def _solve_against(
    prob: AgpsProblem, solver: str, cfg: AgpsConfig, truth: FloatArray
) -> tuple[Any, FloatArray]:
    """Solve the fixes; their ECEF errors against the truth (NaN where not ``ok``)."""
    res = solve_agps(prob, solver, cfg)  # type: ignore[arg-type]
    ok = res.status == AgpsStatus.OK
    return res, np.where(ok[:, None], res.pos_m - truth, np.nan)


def _sensitivity_problems(
    params: AgpsExperimentParams, problem: AgpsProblem, truth: FloatArray, meta: dict[str, Any]
) -> tuple[AgpsProblem, AgpsProblem]:
    """The first-interval fixes (``base``) and, stacked into one batch, the same fixes under
    each cell-radius and noise variant of :func:`sensitivity_names` (the f5 reading changes
    the solver, not the problem)."""
    n_h = len(params.heights_m)
    first = slice(0, n_h)  # the fixes of the first interval
    base = AgpsProblem(
        problem.t_gps_s[first],
        problem.sat_pos_m[first],
        problem.y_m[first],
        problem.height_m[first],
        problem.start_xyz_m[first],
        problem.usable[first],
    )
    names = sensitivity_names(params)
    starts, ys = [], []
    for name in names[1:]:
        kind, value = name.split("_", 1)
        if kind == "cell":
            cell = truth + float(value) * meta["cell_fraction"] * meta["cell_direction"]
            starts.append(np.repeat(cell[None], n_h, 0))
            ys.append(base.y_m)
        else:
            starts.append(base.start_xyz_m)
            ys.append(base.y_m + (float(value) - 1.0) * meta["noise_m"][first])
    n_v = len(starts)
    stacked = AgpsProblem(
        np.tile(base.t_gps_s, (n_v, 1)),
        np.tile(base.sat_pos_m, (n_v, 1, 1)),
        np.concatenate(ys),
        np.tile(base.height_m, n_v),
        np.concatenate(starts),
        np.tile(base.usable, (n_v, 1)),
    )
    return base, stacked


def simulate_fix_set(params: AgpsExperimentParams, rng: np.random.Generator) -> dict[str, Any]:
    """One fix set (:func:`fix_set_problem`) solved for every interval, assumed height and
    solver, and its first-interval fixes again under each sensitivity variant.

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
        ``sens_error_m``, ``sens_iterations``, ``sens_status`` of shape (variants, 2, heights)
        for Gauss–Newton and Marquardt at the first interval (:func:`sensitivity_names`);
        ``sats`` (the pair), ``t_gps_s`` (first epoch), ``dop``, ``cell_distance_m``.
    """

    problem, truth, meta = fix_set_problem(params, rng)
    n_i, n_h = len(params.intervals_min), len(params.heights_m)
    lat, lon = math.radians(params.site_llh[0]), math.radians(params.site_llh[1])
    config = solver_config(params)
    rot = enu_rotation(lat, lon)

    shape = (len(SOLVER_NAMES), n_i, n_h)
    out: dict[str, Any] = {
        "error_m": np.full(shape, np.nan),
        "horizontal_m": np.full(shape, np.nan),
        "iterations": np.zeros(shape, dtype=np.int64),
        "status": np.zeros(shape, dtype=np.int8),
        "sats": meta["sats"],
        "t_gps_s": meta["t_gps_s"],
        "dop": meta["dop"],
        "cell_distance_m": params.cell_radius_m * meta["cell_fraction"],
    }
    for j, solver in enumerate(SOLVER_NAMES):
        res, d = _solve_against(problem, solver, config, truth)
        out["error_m"][j] = np.linalg.norm(d, axis=1).reshape(n_i, n_h)
        out["horizontal_m"][j] = np.linalg.norm((d @ rot.T)[:, :2], axis=1).reshape(n_i, n_h)
        out["iterations"][j] = res.iterations.reshape(n_i, n_h)
        out["status"][j] = res.status.reshape(n_i, n_h)

    base, stacked = _sensitivity_problems(params, problem, truth, meta)
    names = sensitivity_names(params)
    other_f5 = dataclasses.replace(
        config, f5_units="dimensionless" if config.f5_units == "m" else "m"
    )
    sens_shape = (len(names), 2, n_h)
    out["sens_error_m"] = np.full(sens_shape, np.nan)
    out["sens_iterations"] = np.zeros(sens_shape, dtype=np.int64)
    out["sens_status"] = np.zeros(sens_shape, dtype=np.int8)
    for j, solver in enumerate(("gn", "lm")):
        for rows, prob, cfg in ((slice(0, 1), base, other_f5), (slice(1, None), stacked, config)):
            res, d = _solve_against(prob, solver, cfg, truth)
            out["sens_error_m"][rows, j] = np.linalg.norm(d, axis=1).reshape(-1, n_h)
            out["sens_iterations"][rows, j] = res.iterations.reshape(-1, n_h)
            out["sens_status"][rows, j] = res.status.reshape(-1, n_h)
    return out
