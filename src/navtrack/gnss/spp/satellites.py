"""Stage 2 of single point positioning: satellite positions, clocks, URA, health and group
delays at transmission (RTKLIB ``satposs`` with the group delays of ``prange``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.gnss import ephemeris as eph
from navtrack.gnss.corrections import FREQ_L1_HZ, frequency_hz, transmit_time
from navtrack.gnss.spp.config import EFACT_GLO, IONOFREE_BANDS, PRIMARY_BAND, SppConfig
from navtrack.gnss.spp.signals import Pseudoranges, klobuchar_params

if TYPE_CHECKING:
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = ["SatelliteStates", "navigation_tables", "satellite_states"]


class SatelliteStates(Record):
    """Satellite states at signal transmission and the broadcast signal parameters (RTKLIB
    ``satposs`` with the group delays of ``prange``).

    Attributes
    ----------
    sats : tuple of str, length S
    pos_m : ndarray, shape (E, S, 3)
        ECEF position at transmission, in the earth-fixed frame of that time (m).
    clock_s : ndarray, shape (E, S)
        Satellite clock offset (s) with the relativistic term, without group delay.
    var_m2 : ndarray, shape (E, S)
        Signal-in-space range error variance (m^2): broadcast URA/SISA or SP3 accuracy.
    svh : ndarray of int, shape (E, S)
        Broadcast health (0 healthy, -1 no ephemeris).
    group_delay_s : ndarray, shape (E, S)
        Group delay (s) of the measured signal, subtracted from the satellite clock: TGD/BGD of
        the band for systems in ``tgd_systems``, the ionosphere-free combination of the two
        bands' delays with ``iono="ionofree"``, 0 otherwise.
    freq_hz : ndarray, shape (E, S)
        Carrier frequency (Hz) of ``Pseudoranges.pr_m`` (GLONASS channel from the ephemeris).
    freq2_hz : ndarray, shape (E, S), or None
        Carrier frequency (Hz) of ``Pseudoranges.pr2_m`` (ionosphere-free only).
    iono_scale : ndarray, shape (E, S)
        ``(f_L1 / f)^2`` that scales the L1 Klobuchar delay to the measured band; 0 for the
        ionosphere-free combination.
    var_factor : ndarray, shape (S,)
        Square of RTKLIB's system error factor (:data:`~navtrack.gnss.spp.config.EFACT_GLO` for
        GLONASS, 1 otherwise).
    valid : ndarray of bool, shape (E, S)
        An ephemeris (of an orbit source that covers the system, and broadcast as well when
        ``sp3_needs_broadcast``) was found and evaluated; health is in ``svh``.
    klobuchar : ndarray, shape (8,), or None
        Broadcast Klobuchar alpha0-3, beta0-3 of the first navigation file that has them.
    """

    sats: tuple[str, ...]
    pos_m: FloatArray
    clock_s: FloatArray
    var_m2: FloatArray
    svh: IntArray
    group_delay_s: FloatArray
    freq_hz: FloatArray
    freq2_hz: FloatArray | None
    iono_scale: FloatArray
    var_factor: FloatArray
    valid: BoolArray
    klobuchar: FloatArray | None

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _nav_list(nav: NavData | Sequence[NavData] | None) -> list[NavData]:
    if nav is None:
        return []
    if isinstance(nav, Sequence):
        return list(nav)
    return [nav]


def navigation_tables(
    nav: NavData | Sequence[NavData] | None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> dict[str, EphemerisTable]:
    """Broadcast ephemeris tables per system: ``ephemeris`` when given, else merged from
    ``nav`` (build them once and pass them to every block of a long file)."""
    if ephemeris is not None:
        return dict(ephemeris)
    navs = _nav_list(nav)
    return eph.merge_tables([eph.ephemeris_tables(n) for n in navs]) if navs else {}


def satellite_states(
    pr: Pseudoranges,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> SatelliteStates:
    """Satellite positions, clocks and group delays at transmission (stage 2 of
    :func:`~navtrack.gnss.spp.solve_spp`).

    Parameters
    ----------
    pr : Pseudoranges
        The transmission time is ``t_rx - P / c`` (:func:`corrections.transmit_time`).
    nav : NavData or sequence of NavData, optional
        Broadcast navigation data: orbits and clocks unless ``sp3`` is given; group delays and
        Klobuchar parameters in any case.
    sp3 : Sp3, optional
        Precise orbits and clocks.
    config : SppConfig, optional
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built tables (:func:`navigation_tables`), otherwise built from ``nav``.

    Returns
    -------
    SatelliteStates

    Raises
    ------
    ValueError
        Neither broadcast ephemerides nor SP3 given.
    """
    cfg = config or SppConfig()
    tables = navigation_tables(nav, ephemeris)
    if sp3 is None and not tables:
        raise ValueError("nav: no broadcast ephemerides and no SP3 given")
    klob = None
    for n in _nav_list(nav):
        klob = klobuchar_params(n.iono)
        if klob is not None:
            break
    sats = list(pr.sats)
    t_rx = pr.t_gps_s
    t_sv = np.where(pr.observed, transmit_time(t_rx, pr.pr_m), np.nan)
    if sp3 is not None:
        from navtrack.gnss.precise import sp3_states  # with an SP3 file only (`pos` start-up)

        states = sp3_states(sp3, sats, t_sv)
    else:
        states = _broadcast(tables, sats, t_rx, t_sv, cfg, healthy_only=cfg.healthy_only)
    signals = _signal_parameters(pr, tables, states.eph_index, sp3 is not None, cfg)
    orbit_systems = set(tables) if sp3 is None else {s[0] for s in sp3.sats}
    valid = states.valid & np.array([s[0] in orbit_systems for s in sats], dtype=bool)
    if sp3 is not None and cfg.sp3_needs_broadcast:
        valid &= _broadcast(tables, sats, t_rx, t_sv, cfg, healthy_only=False).valid
    return SatelliteStates(
        sats=pr.sats,
        pos_m=states.pos_m,
        clock_s=states.clock_s,
        var_m2=states.var_m2,
        svh=states.svh,
        group_delay_s=signals.group_delay_s,
        freq_hz=signals.freq_hz,
        freq2_hz=signals.freq2_hz,
        iono_scale=signals.iono_scale,
        var_factor=signals.var_factor,
        valid=valid,
        klobuchar=klob,
    )


def _broadcast(
    tables: Mapping[str, EphemerisTable],
    sats: list[str],
    t_rx: FloatArray,
    t_sv: FloatArray,
    cfg: SppConfig,
    *,
    healthy_only: bool,
) -> eph.SatStates:
    """Broadcast orbits and clocks at transmission with the configuration's ephemeris choice."""
    return eph.broadcast_states(
        tables,
        sats,
        t_rx,
        t_sv,
        max_age_s=cfg.max_age_s,
        healthy_only=healthy_only,
        galileo_nav=cfg.galileo_nav,
    )


class _SignalParameters(Record):
    """Group delays, carrier frequencies, ionosphere scale and system error factors of the
    measured signals (fields as :class:`SatelliteStates`)."""

    group_delay_s: FloatArray
    freq_hz: FloatArray
    freq2_hz: FloatArray | None
    iono_scale: FloatArray
    var_factor: FloatArray


def _signal_parameters(
    pr: Pseudoranges,
    tables: Mapping[str, EphemerisTable],
    eph_index: IntArray,
    precise: bool,
    cfg: SppConfig,
) -> _SignalParameters:
    """Per-system group delays and frequencies from the broadcast records: the records of the
    evaluated ephemerides, or with precise orbits (``precise``) the nearest broadcast record."""
    sats = list(pr.sats)
    n_e, n_s = pr.t_gps_s.size, len(sats)
    gd = np.zeros((n_e, n_s))
    scale = np.zeros((n_e, n_s))
    freq = np.full((n_e, n_s), np.nan)
    freq2 = np.full((n_e, n_s), np.nan) if cfg.iono == "ionofree" else None
    fact = np.ones(n_s)
    for sys in pr.systems:
        cols = np.flatnonzero([sat[0] == sys for sat in sats]).astype(int)
        if cols.size == 0:
            continue
        table = tables.get(sys)
        if table is None:
            idx = np.full((n_e, cols.size), -1, dtype=np.int64)
        elif not precise:
            idx = eph_index[:, cols]
        else:  # group delays and GLONASS channels from the nearest broadcast record
            idx = eph.select_ephemeris(
                table,
                [sats[c] for c in cols],
                pr.t_gps_s,
                max_age_s=1e9,
                healthy_only=False,
                galileo_nav=cfg.galileo_nav,
            )
        fnum = None
        if sys == "R" and table is not None:
            fnum = np.where(idx >= 0, table.get("freq_num")[np.maximum(idx, 0)], np.nan)
        fact[cols] = EFACT_GLO**2 if sys == "R" else 1.0
        if freq2 is not None:
            ba, bb = IONOFREE_BANDS[sys]
            fa = frequency_hz(sys, ba, fnum)
            fb = frequency_hz(sys, bb, fnum)
            ga = eph.group_delay_s(table, idx, ba) if table is not None else 0.0
            gb = eph.group_delay_s(table, idx, bb) if table is not None else 0.0
            gd[:, cols] = (fa**2 * ga - fb**2 * gb) / (fa**2 - fb**2)
            freq[:, cols] = fa
            freq2[:, cols] = fb
        else:
            band = PRIMARY_BAND[sys]
            f = frequency_hz(sys, band, fnum)
            scale[:, cols] = (FREQ_L1_HZ / f) ** 2
            freq[:, cols] = f
            if table is not None and sys in cfg.tgd_systems:
                gd[:, cols] = eph.group_delay_s(table, idx, band)
    return _SignalParameters(gd, freq, freq2, scale, fact)
