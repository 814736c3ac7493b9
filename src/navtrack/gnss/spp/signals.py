"""Stage 1 of single point positioning: the code pseudoranges of the configured signals (the
selection part of RTKLIB's ``prange``), the broadcast Klobuchar parameters and the start
position."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.gnss.observations import Observations
from navtrack.gnss.spp.config import CODE_PRIORITY, IONOFREE_BANDS, PRIMARY_BAND, SppConfig

__all__ = [
    "Pseudoranges",
    "code_pseudoranges",
    "klobuchar_params",
    "observation_codes",
    "select_pseudoranges",
    "start_position",
    "subset_epochs",
]


def select_pseudoranges(
    obs: Observations, sats: list[str], band_by_sys: Mapping[str, str]
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Pseudorange and C/N0 of one logical band per satellite, first available code per epoch.

    Returns
    -------
    pr_m : ndarray, shape (E, S)
    cn0_dbhz : ndarray, shape (E, S)
        Signal strength of the same signal (NaN where not recorded).
    code_index : ndarray of int, shape (E, S)
        Index into ``obs.codes`` of the code used (-1: none).
    """
    n_e = obs.t_gps_s.size
    pr = np.full((n_e, len(sats)), np.nan)
    cn0 = np.full((n_e, len(sats)), np.nan)
    used = np.full((n_e, len(sats)), -1, dtype=np.int64)
    codes = list(obs.codes)
    col = {s: i for i, s in enumerate(obs.sats)}
    for j, sat in enumerate(sats):
        sys = sat[0]
        band = band_by_sys.get(sys)
        if band is None:
            continue
        types = obs.header.obs_types.get(sys) if obs.header.obs_types else None
        for code in CODE_PRIORITY.get(sys, {}).get(band, ()):
            if code not in codes or (types and code not in types):
                continue
            k = codes.index(code)
            v = obs.values[:, col[sat], k]
            take = np.isfinite(v) & (v > 0) & np.isnan(pr[:, j])
            if not take.any():
                continue
            pr[take, j] = v[take]
            used[take, j] = k
            s_code = "S" + code[1:]
            if s_code in codes:
                cn0[take, j] = obs.values[take, col[sat], codes.index(s_code)]
    return pr, cn0, used


def observation_codes(config: SppConfig | None = None) -> frozenset[str]:
    """Every observation code single point positioning may take for a configuration: the
    pseudorange codes of its systems' bands (:data:`CODE_PRIORITY`), their signal strengths
    (:func:`code_pseudoranges`) and Dopplers (:func:`navtrack.gnss.velocity.doppler_velocity`).
    A reader given them (``read_obs(path, systems=..., codes=...)``) decodes nothing else."""
    cfg = config or SppConfig()
    codes: set[str] = set()
    for sys in cfg.systems:
        bands: tuple[str, ...] = ()
        if cfg.iono == "ionofree":
            bands = IONOFREE_BANDS.get(sys, ())
        elif sys in PRIMARY_BAND:
            bands = (PRIMARY_BAND[sys],)
        for band in bands:
            for code in CODE_PRIORITY.get(sys, {}).get(band, ()):
                codes.update((code, "S" + code[1:], "D" + code[1:]))
    return frozenset(codes)


class Pseudoranges(Record):
    """Code pseudoranges of the configured signals (the selection part of RTKLIB's ``prange``).

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Epoch time tags (receiver time, GPS s).
    sats : tuple of str, length S
        Satellites of the selected systems present in the observations (the satellite axis of
        every later stage).
    systems : tuple of str
        Selected systems present in the observations, in ``GRECJI`` order.
    pr_m : ndarray, shape (E, S)
        Pseudorange (m) of the primary band (:data:`PRIMARY_BAND`), or of the first band of the
        ionosphere-free pair (:data:`IONOFREE_BANDS`); NaN where not observed.
    pr2_m : ndarray, shape (E, S), or None
        Pseudorange (m) of the second band of the ionosphere-free pair; None for single
        frequency.
    cn0_dbhz : ndarray, shape (E, S)
        C/N0 (dB-Hz) of the signal of ``pr_m``; NaN where not recorded.
    observed : ndarray of bool, shape (E, S)
        All pseudoranges the configuration needs are present.
    approx_xyz_m : ndarray, shape (3,)
        Start position of the estimation (ECEF, m): the header's approximate position when it is
        near the earth's surface, else the earth's centre.
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    systems: tuple[str, ...]
    pr_m: FloatArray
    pr2_m: FloatArray | None
    cn0_dbhz: FloatArray
    observed: BoolArray
    approx_xyz_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def code_pseudoranges(obs: Observations, config: SppConfig | None = None) -> Pseudoranges:
    """Select the pseudoranges the configuration uses (stage 1 of :func:`solve_spp`).

    Parameters
    ----------
    obs : Observations
        RINEX or Android observations.
    config : SppConfig, optional
        ``systems`` and ``iono`` (``ionofree`` selects two bands) are read.

    Returns
    -------
    Pseudoranges
    """
    cfg = config or SppConfig()
    systems = tuple(s for s in "GRECJI" if s in cfg.systems and s in obs.systems)
    sats = [s for s in obs.sats if s[0] in systems]
    p2: FloatArray | None = None
    if cfg.iono == "ionofree":
        b1 = {s: IONOFREE_BANDS[s][0] for s in systems if s in IONOFREE_BANDS}
        b2 = {s: IONOFREE_BANDS[s][1] for s in systems if s in IONOFREE_BANDS}
        p1, cn0, _ = select_pseudoranges(obs, sats, b1)
        p2, _, _ = select_pseudoranges(obs, sats, b2)
        observed = np.isfinite(p1) & np.isfinite(p2)
    else:
        p1, cn0, _ = select_pseudoranges(obs, sats, {s: PRIMARY_BAND[s] for s in systems})
        observed = np.isfinite(p1)
    return Pseudoranges(
        t_gps_s=np.array(obs.t_gps_s, dtype=float),
        sats=tuple(sats),
        systems=systems,
        pr_m=p1,
        pr2_m=p2,
        cn0_dbhz=cn0,
        observed=observed,
        approx_xyz_m=start_position(obs),
    )


def klobuchar_params(nav_iono: Mapping[str, FloatArray]) -> FloatArray | None:
    """The broadcast Klobuchar parameters ``alpha0..3, beta0..3`` of a navigation header's
    ionosphere records (GPS, else QZSS, else BeiDou); None where none is usable."""
    if not nav_iono:
        return None
    for a, b in (("GPSA", "GPSB"), ("QZSA", "QZSB"), ("BDSA", "BDSB")):
        if a in nav_iono and b in nav_iono:
            p = np.concatenate(
                [np.asarray(nav_iono[a], float)[:4], np.asarray(nav_iono[b], float)[:4]]
            )
            if np.all(np.isfinite(p)) and np.any(p):
                return p
    return None


def start_position(obs: Observations) -> FloatArray:
    """The header's approximate position (ECEF, m) when it is near the earth's surface, else
    the earth's centre."""
    xyz = getattr(obs.header, "approx_xyz_m", None)
    if xyz is not None:
        r = float(np.linalg.norm(xyz))
        if 6.0e6 < r < 6.6e6:
            return np.asarray(xyz, dtype=float)
    return np.zeros(3)


def subset_epochs(obs: Observations, epochs: slice | IntArray) -> Observations:
    """The observations of some epochs only (same satellites and codes)."""
    return Observations(
        path=obs.path,
        header=obs.header,
        t_gps_s=np.array(obs.t_gps_s[epochs]),
        epoch_flag=np.array(obs.epoch_flag[epochs]),
        clock_offset_s=np.array(obs.clock_offset_s[epochs]),
        sats=obs.sats,
        codes=obs.codes,
        values=np.array(obs.values[epochs]),
        lli=np.array(obs.lli[epochs]),
        ssi=np.array(obs.ssi[epochs]),
    )
