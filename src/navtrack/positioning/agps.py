"""The AGPS pipeline of a recorded file: observations -> SPP stages 1-3 (GPS L1 C/A) ->
pseudoranges corrected as an AGPS server's assistance allows -> two-satellite fixes
(:class:`navtrack.gnss.agps.AgpsProblem`) -> :func:`navtrack.gnss.agps.solve_agps`.

``navtrack agps`` (one fix) and the real-data study of the AGPS reproduction (sampled fixes of
the shared stations, :mod:`navtrack.experiments.agps.real`) both run it:
:func:`read_gps_measurements` then :func:`assisted_pseudoranges` then :func:`solve_fixes`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from navtrack._typing import ArrayLike, FloatArray
from navtrack.geodesy import azimuth_elevation, check_near_surface, ecef_to_geodetic
from navtrack.gnss.agps import AgpsConfig, AgpsProblem, AgpsResult, Solver, solve_agps
from navtrack.gnss.android import read_gnsslogger
from navtrack.gnss.corrections import klobuchar_delay_m, saastamoinen_delay_m
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.nav import NavData, read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import (
    Measurements,
    SppConfig,
    SppStatus,
    code_pseudoranges,
    corrected_measurements,
    estimate_position,
    satellite_states,
)

__all__ = [
    "assisted_pseudoranges",
    "gps_measurements",
    "problem_from_measurements",
    "pseudorange_sigma_m",
    "read_gps_measurements",
    "solve_fixes",
]


def read_gps_measurements(
    obs_path: Path, nav_path: Path, config: SppConfig, *, android: bool | None = None
) -> tuple[Observations, NavData, Measurements]:
    """Read an observation file (RINEX, or an Android GnssLogger log) and a navigation file and
    take their GPS measurements (:func:`gps_measurements`).

    Parameters
    ----------
    obs_path, nav_path : Path
    config : SppConfig
    android : bool, optional
        The observation file is a GnssLogger log (default: a ``.txt`` file is one).
    """
    is_log = obs_path.suffix == ".txt" if android is None else android
    obs = read_gnsslogger(obs_path) if is_log else read_obs(obs_path)
    nav = read_nav(nav_path)
    return obs, nav, gps_measurements(obs, nav, config)


def solve_fixes(
    meas: Measurements,
    y_m: FloatArray,
    epochs: ArrayLike,
    sats: ArrayLike,
    height_m: ArrayLike,
    start_xyz_m: ArrayLike,
    solver: Solver,
    config: AgpsConfig,
) -> AgpsResult:
    """Gather the fixes (:func:`problem_from_measurements`) and solve them
    (:func:`navtrack.gnss.agps.solve_agps`); arguments as those two."""
    problem = problem_from_measurements(meas, y_m, epochs, sats, height_m, start_xyz_m)
    return solve_agps(problem, solver, config)


def gps_measurements(
    obs: Observations, nav: NavData, config: SppConfig | None = None
) -> Measurements:
    """The GPS L1 C/A pseudoranges and satellite states two-satellite fixes take: stages 1–3 of
    single point positioning (:func:`navtrack.gnss.spp.code_pseudoranges`,
    :func:`~navtrack.gnss.spp.satellite_states`, :func:`~navtrack.gnss.spp.corrected_measurements`).

    Parameters
    ----------
    obs : Observations
    nav : NavData
        Broadcast ephemerides.
    config : SppConfig, optional
        Default ``SppConfig(systems="G")``.
    """
    cfg = config or SppConfig(systems="G")
    pr = code_pseudoranges(obs, cfg)
    return corrected_measurements(pr, satellite_states(pr, nav, config=cfg), cfg)


def assisted_pseudoranges(
    meas: Measurements, start_xyz_m: ArrayLike, config: SppConfig | None = None
) -> FloatArray:
    """Pseudoranges corrected as an AGPS server's assistance allows: satellite clock and group
    delay (:func:`navtrack.gnss.spp.corrected_measurements`), then the broadcast ionosphere and
    the troposphere of the SPP model evaluated at the cell position.

    Parameters
    ----------
    meas : Measurements
        Stage 3 of single point positioning.
    start_xyz_m : array-like, shape (3,)
        Cell (base-station) position (ECEF, m), where the atmosphere is evaluated.
    config : SppConfig, optional
        ``iono`` (``klobuchar``, ``ionofree`` or ``off``), ``tropo`` and ``elmask_deg``.

    Returns
    -------
    ndarray, shape (E, S)
        Corrected pseudoranges (m); NaN where not usable or below the elevation mask seen from
        the cell.

    Notes
    -----
    Evaluating the atmosphere at the cell rather than at each iterate changes it by
    millimetres over a few kilometres; it keeps the model of the solvers the paper's f1..f4.
    """
    cfg = config or SppConfig()
    start = check_near_surface(start_xyz_m, "start_xyz_m")
    lat, lon, h = ecef_to_geodetic(start)
    sat = np.where(np.isfinite(meas.sat_pos_m), meas.sat_pos_m, 0.0)
    azel = azimuth_elevation(sat, start)
    az, el = azel[..., 0], azel[..., 1]
    if cfg.iono == "klobuchar":
        t = meas.t_gps_s[:, None]
        iono = klobuchar_delay_m(t, lat, lon, az, el, meas.klobuchar) * meas.iono_scale
    else:
        iono = np.zeros_like(el)
    trop = saastamoinen_delay_m(lat, h, el) if cfg.tropo == "saastamoinen" else 0.0 * el
    use = meas.usable & (el >= math.radians(cfg.elmask_deg))
    return np.where(use, meas.y_m - iono - trop, np.nan)


def pseudorange_sigma_m(meas: Measurements, config: SppConfig | None = None) -> float:
    """A receiver's pseudorange noise from its own file: the root mean square of the single
    point residuals of every epoch with redundancy, scaled by ``sqrt(n / dof)``.

    Parameters
    ----------
    meas : Measurements
        Stage 3 of single point positioning (all satellites, all epochs).
    config : SppConfig, optional

    Returns
    -------
    float
        Standard deviation (m); NaN when no epoch has more satellites than unknowns.

    Notes
    -----
    A station receiver gives a few decimetres (0759: 0.5 m), a phone metres (the shared
    GnssLogger log: 6 m). The residuals also carry what the broadcast models leave, which is
    what a two-satellite fix suffers too.
    """
    est = estimate_position(meas, config)
    good = (est.status == SppStatus.OK) & (est.dof > 0)
    if not good.any():
        return math.nan
    r = np.where(est.used[good], est.residuals_m[good], 0.0)
    return float(np.sqrt(np.sum(r**2) / np.sum(est.dof[good])))


def problem_from_measurements(
    meas: Measurements,
    y_m: FloatArray,
    epochs: ArrayLike,
    sats: ArrayLike,
    height_m: ArrayLike,
    start_xyz_m: ArrayLike,
) -> AgpsProblem:
    """Gather two-satellite fixes from SPP measurements.

    Parameters
    ----------
    meas : Measurements
        Stage 3 of single point positioning (satellite positions, time tags).
    y_m : ndarray, shape (E, S)
        Corrected pseudoranges (:func:`assisted_pseudoranges`).
    epochs : array-like of int, shape (B, 2)
        The two epochs of each fix (indices into ``meas.t_gps_s``).
    sats : array-like of int, shape (B, 2)
        The two satellites of each fix (indices into ``meas.sats``).
    height_m : array-like, shape (B,) or scalar
        Assumed heights (m).
    start_xyz_m : array-like, shape (3,) or (B, 3)
        Cell positions (ECEF, m).

    Returns
    -------
    AgpsProblem
        Fixes whose satellites lack a corrected pseudorange at one of the epochs are marked not
        usable (status ``missing_measurement`` when solved).

    Raises
    ------
    ValueError
        Indices of the wrong shape or outside the arrays, the same epoch or satellite twice in
        a fix, a bad height (:class:`AgpsProblem`).
    """
    ep = np.asarray(epochs)
    sv = np.asarray(sats)
    n_e, n_s = y_m.shape
    for name, arr, size in (("epochs", ep, n_e), ("sats", sv, n_s)):
        if arr.ndim != 2 or arr.shape[1] != 2 or arr.dtype.kind not in "iu":
            raise ValueError(f"{name}: expected an integer array of shape (B, 2), got {arr.shape}")
        if arr.size and (arr.min() < 0 or arr.max() >= size):
            raise ValueError(f"{name}: indices outside 0..{size - 1}")
    if ep.shape != sv.shape:
        raise ValueError(f"sats: expected shape {ep.shape} like epochs, got {sv.shape}")
    twice = np.flatnonzero(sv[:, 0] == sv[:, 1])
    if twice.size:
        raise ValueError(
            f"sats: fix {twice[0]} uses satellite {meas.sats[sv[twice[0], 0]]} twice; "
            "two different satellites are needed"
        )
    n = ep.shape[0]
    e4 = np.stack([ep[:, 0], ep[:, 0], ep[:, 1], ep[:, 1]], axis=1)
    s4 = np.stack([sv[:, 0], sv[:, 1], sv[:, 0], sv[:, 1]], axis=1)
    y = y_m[e4, s4]
    pos = meas.sat_pos_m[e4, s4]
    start = np.broadcast_to(np.asarray(start_xyz_m, dtype=float), (n, 3))
    return AgpsProblem(
        t_gps_s=meas.t_gps_s[ep],
        sat_pos_m=pos,
        y_m=y,
        height_m=np.broadcast_to(np.asarray(height_m, dtype=float), (n,)).copy(),
        start_xyz_m=start.copy(),
        usable=np.isfinite(y),
    )
