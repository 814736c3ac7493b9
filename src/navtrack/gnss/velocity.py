"""Receiver velocity and clock drift from Doppler measurements (after :mod:`navtrack.gnss.spp`).

For each satellite used in an epoch's position solution, the Doppler shift ``D`` (Hz) of the
signal whose pseudorange was used gives the measured range rate ``-lambda D`` (m/s). Its model
is ``e . (v_sat - v_rx) + c (dt_rx' - dt_sat')`` with ``e`` the unit line of sight from the
receiver to the satellite, so one epoch's range rates are a linear least-squares problem in
``(v_rx, c dt_rx')``, solved here for all epochs at once (unit weights). Satellite velocity and
clock drift are central differences of the broadcast (or SP3) states over +-0.5 s.

References
----------
E. D. Kaplan, C. J. Hegarty, *Understanding GPS: Principles and Applications*, 2nd ed., 2006,
section 2.5.2 (velocity from Doppler); IS-GPS-200N 20.3.3.4.3 (satellite velocity).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation
from navtrack.gnss.spp import (
    PRIMARY_BAND,
    SppConfig,
    SppResult,
    code_pseudoranges,
    satellite_states,
    select_pseudoranges,
)

if TYPE_CHECKING:
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = ["DopplerVelocity", "doppler_velocity"]

# Half the interval (s) of the central differences of satellite position and clock.
_HALF_STEP_S = 0.5
# Unknowns of one epoch: velocity (3) and receiver clock drift.
_N_UNKNOWNS = 4


class DopplerVelocity(Record):
    """Receiver velocity of every epoch.

    Attributes
    ----------
    vel_mps : ndarray, shape (E, 3)
        ECEF velocity (m/s); NaN where fewer than four used satellites have a Doppler
        measurement (or the file has none).
    vel_enu_mps : ndarray, shape (E, 3)
        The same in local east/north/up at the epoch's position.
    drift_mps : ndarray, shape (E,)
        Receiver clock drift times c (m/s).
    n_doppler : ndarray of int, shape (E,)
        Satellites whose Doppler entered the solution.
    """

    vel_mps: FloatArray
    vel_enu_mps: FloatArray
    drift_mps: FloatArray
    n_doppler: np.ndarray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _doppler_hz(obs: Observations, sats: list[str], systems: str) -> FloatArray:
    """Doppler (Hz) of the signal whose pseudorange SPP uses, shape (E, S); NaN where none."""
    _, _, code_index = select_pseudoranges(obs, sats, {s: PRIMARY_BAND[s] for s in systems})
    col = {s: i for i, s in enumerate(obs.sats)}
    doppler_of = {
        k: obs.codes.index("D" + c[1:]) for k, c in enumerate(obs.codes) if "D" + c[1:] in obs.codes
    }
    out = np.full(code_index.shape, np.nan)
    for j, sat in enumerate(sats):
        for k, d in doppler_of.items():
            rows = code_index[:, j] == k
            out[rows, j] = obs.values[rows, col[sat], d]
    return out


def doppler_velocity(
    obs: Observations,
    result: SppResult,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> DopplerVelocity:
    """Velocity and clock drift of the receiver from the Doppler of the satellites used.

    Parameters
    ----------
    obs : Observations
        The observations ``result`` was solved from (same epochs).
    result : SppResult
        Positions and used satellites (:func:`navtrack.gnss.spp.solve_spp` with ``config``).
    nav, sp3, ephemeris, config
        As given to :func:`navtrack.gnss.spp.solve_spp`.

    Returns
    -------
    DopplerVelocity
    """
    cfg = config or SppConfig()
    pr = code_pseudoranges(obs, cfg)
    if pr.sats != result.sats:
        raise ValueError("result: its satellites are not those of obs and config")
    doppler = _doppler_hz(obs, list(pr.sats), "".join(pr.systems))
    if not np.isfinite(doppler).any():  # no Doppler in the file: no satellite states needed
        nan = np.full((pr.t_gps_s.size, 3), np.nan)
        return DopplerVelocity(
            vel_mps=nan,
            vel_enu_mps=nan.copy(),
            drift_mps=nan[:, 0].copy(),
            n_doppler=np.zeros(pr.t_gps_s.size, dtype=np.int64),
        )
    shifted = [
        satellite_states(
            pr.replace(t_gps_s=pr.t_gps_s + dt),
            nav,
            sp3=sp3,
            config=cfg,
            ephemeris=ephemeris,
        )
        for dt in (-_HALF_STEP_S, 0.0, _HALF_STEP_S)
    ]
    before, now, after = shifted
    sat_vel = (after.pos_m - before.pos_m) / (2 * _HALF_STEP_S)
    sat_drift = (after.clock_s - before.clock_s) / (2 * _HALF_STEP_S) * C_MPS
    range_rate = -doppler * C_MPS / now.freq_hz
    los = now.pos_m - result.pos_m[:, None, :]
    e = los / np.linalg.norm(los, axis=-1, keepdims=True)
    y = range_rate - np.einsum("esk,esk->es", e, sat_vel) + sat_drift
    use = result.used & np.isfinite(y) & np.isfinite(e).all(axis=-1)
    vel, drift, n = _solve_epochs(e, y, use)
    llh = ecef_to_geodetic(np.where(np.isfinite(result.pos_m), result.pos_m, 0.0))
    rot = enu_rotation(llh[:, 0], llh[:, 1])
    vel_enu = np.einsum("eij,ej->ei", rot, vel)
    return DopplerVelocity(vel_mps=vel, vel_enu_mps=vel_enu, drift_mps=drift, n_doppler=n)


def _solve_epochs(
    e: FloatArray, y: FloatArray, use: BoolArray
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Least squares of ``y = -e . v + d`` per epoch over the ``use`` satellites."""
    h = np.concatenate([-e, np.ones((*e.shape[:-1], 1))], axis=-1)
    h = np.where(use[..., None], h, 0.0)
    yy = np.where(use, y, 0.0)
    n = use.sum(axis=1)
    ok = n >= _N_UNKNOWNS
    ht = np.swapaxes(h, -1, -2)
    normal = ht @ h
    normal[~ok] = np.eye(_N_UNKNOWNS)
    x = np.linalg.solve(normal, ht @ yy[..., None])[..., 0]
    x[~ok] = np.nan
    return x[:, :3], x[:, 3], n
