"""Whole days of clean data: every RAIM method's protection levels against the actual errors
(the misleading-information count and the Stanford diagrams of docs/integrity.md).

The 24 h files are not in the shared data; ``navtrack reproduce raim-fcm --input FILE ...``
names them, and a station of :data:`DAY_STATIONS` runs when both its observation and its
navigation file are among the inputs (matched by file name). Each station runs on the single
frequency with the broadcast Klobuchar correction and on the ionosphere-free combination, with
all its systems and with GPS alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.geodesy import ecef_to_enu
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig
from navtrack.integrity.raim import RaimConfig, RaimStatus
from navtrack.positioning import solve_positions

__all__ = ["DAY_STATIONS", "DayStation", "whole_day_protection"]


@dataclass(frozen=True, slots=True)
class DayStation:
    """A 24 h station: files, systems and reference position.

    Attributes
    ----------
    obs, nav : str
        File names (RINEX 3 observations, Hatanaka-compressed allowed; mixed navigation).
    systems : str
        All the systems to use.
    ref_xyz_m : tuple of float
        Antenna reference point (ECEF, m): the IGS SINEX marker coordinate plus the antenna
        height of the RINEX header along the ellipsoidal up direction.
    """

    obs: str
    nav: str
    systems: str
    ref_xyz_m: tuple[float, float, float]


#: Data: github.com/jtec/prx (MIT), commit f93dde72b16978cc7fb2c09756d52afac1f0664b, folders
#: ``src/prx/test/datasets/TLSE_2023001`` and ``TLSE_2022001`` (the TLSE files unzipped).
#: References: IGS weekly SINEX igs10P1565 (2010-01-02..11, in RTKLIB's ``data/``), markers
#: NIST 49507M002 and TLSE 10003M009; TLSE's antenna height 1.053 m (header) added along up.
#: Plate motion since 2010 (0.2-0.3 m) is not applied (docs/integrity.md).
#: BELE (Belem, 2024-01-10) and DGAR (Diego Garcia, the same day; RINEX 2.11, GPS + Galileo +
#: GLONASS): github.com/eureka-0/pygnss-tec (MIT), ``data/rinex_obs_v3``, ``rinex_obs_v2`` and
#: ``rinex_nav_v3``; references from the IGS daily SINEX IGS0OPSSNX_20240350000_01D_01D_CRD
#: (estimates) plus the antenna height of the SINEX eccentricity along up. BOR1 (Borowiec,
#: 2024-02-04, GPS only: its navigation file holds GPS alone), the SINEX and the navigation
#: file from github.com/HJpierzchala/GNX ``sample_data`` (the observations at commit 1e2c3d87).
DAY_STATIONS: dict[str, DayStation] = {
    "NIST": DayStation(
        "NIST00USA_R_20230010000_01D_30S_MO.crx.gz",
        "BRDC00IGS_R_20230010000_01D_MN.rnx.gz",
        "GEC",
        (-1288398.3765, -4721696.9223, 4078625.3960),
    ),
    "TLSE": DayStation(
        "TLSE00FRA_R_20220010000_01D_30S_GO.rnx",
        "BRDC00IGS_R_20220010000_01D_MN.rnx",
        "G",
        (4627852.5368, 119640.1371, 4372994.3357),
    ),
    "BELE": DayStation(
        "BELE00BRA_R_20240100000_01D_30S_MO.crx.gz",
        "BRDC00IGS_R_20240100000_01D_MN.rnx.gz",
        "GEC",
        (4228138.9799, -4772752.1624, -155761.0691),
    ),
    "DGAR": DayStation(
        "dgar0100.24o.gz",
        "BRDC00IGS_R_20240100000_01D_MN.rnx.gz",
        "GE",
        (1916268.6168, 6029977.8816, -801719.2937),
    ),
    "BOR1": DayStation(
        "BOR100POL_R_20240350000_01D_30S_MO.crx.gz",
        "BRDC00CNE_R_20240350000_01D_GN.rnx",
        "G",
        (3738358.1695, 1148174.0200, 5021815.9830),
    ),
}

_IONO = {"L1": "klobuchar", "IF": "ionofree"}


def _outcome(
    integ: Any, pos_m: np.ndarray, ref: np.ndarray, hal_m: float, val_m: float
) -> tuple[dict[str, Any], tuple[np.ndarray, ...]]:
    enu = ecef_to_enu(pos_m, ref)
    eh, ev = np.hypot(enu[:, 0], enu[:, 1]), np.abs(enu[:, 2])
    ok = (integ.status == RaimStatus.OK) | (integ.status == RaimStatus.EXCLUDED)
    hpl = np.where(ok, integ.hpl_m, np.nan)
    vpl = np.where(ok, integ.vpl_m, np.nan)
    with np.errstate(invalid="ignore"):
        mi_h, mi_v = int(np.sum(eh > hpl)), int(np.sum(ev > vpl))
    av = integ.availability(hal_m, val_m)
    n = max(int(ok.sum()), 1)
    res = {
        "epochs": int(integ.status.size),
        "statuses": integ.status_counts(),
        "mi_h": mi_h,
        "mi_v": mi_v,
        "hpl_median_m": float(np.nanmedian(hpl)) if ok.any() else None,
        "vpl_median_m": float(np.nanmedian(vpl)) if ok.any() else None,
        "err_h_p95_m": float(np.nanpercentile(eh[ok], 95)) if ok.any() else None,
        "err_v_p95_m": float(np.nanpercentile(ev[ok], 95)) if ok.any() else None,
        "vpl_le_val": float(np.sum(vpl <= val_m) / n),
        "availability_v": av["vertical"],
        "availability_h": av["horizontal"],
    }
    return res, (eh, hpl, ev, vpl)


def whole_day_protection(
    inputs: Sequence[Path],
    methods: Sequence[str],
    hal_m: float = 40.0,
    val_m: float = 35.0,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Every method on every whole-day station found among ``inputs``.

    Parameters
    ----------
    inputs : sequence of Path
        Files given with ``--input``.
    methods : sequence of str
        :data:`navtrack.integrity.raim.METHODS`.
    hal_m, val_m : float
        Alert limits of the availability (LPV-200: 40 m, 35 m).

    Returns
    -------
    results : dict
        ``{"STATION GEC IF": {method: {...}}}``: epochs, statuses, misleading-information
        epochs ``mi_h``/``mi_v`` (error above the level while ``ok`` or ``excluded``), medians,
        95 % errors, availability.
    artifacts : dict
        ``{"STATION_GEC_IF": {method: (err_h, hpl, err_v, vpl)}}`` for the Stanford diagrams
        (levels NaN where the status is neither ``ok`` nor ``excluded``).
    """
    by_name = {p.name: p for p in inputs}
    results: dict[str, Any] = {}
    art: dict[str, Any] = {}
    for name, st in DAY_STATIONS.items():
        if st.obs not in by_name or st.nav not in by_name:
            continue
        obs = read_obs(by_name[st.obs])
        nav = read_nav(by_name[st.nav])
        ref = np.asarray(st.ref_xyz_m)
        for systems in dict.fromkeys((st.systems, "G")):
            for tag, iono in _IONO.items():
                key = f"{name} {systems} {tag}"
                results[key], art[key.replace(" ", "_")] = {}, {}
                cfg = SppConfig(systems=systems, iono=iono)
                for m in methods:
                    r = solve_positions(obs, nav, config=cfg, raim=RaimConfig(m))
                    res, arrays = _outcome(r.integrity, r.pos_m, ref, hal_m, val_m)
                    results[key][m] = res
                    art[key.replace(" ", "_")][m] = arrays
    return results, art
