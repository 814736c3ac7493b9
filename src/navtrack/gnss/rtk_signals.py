"""Stages 1-3 of carrier-phase relative positioning
(:func:`navtrack.gnss.relative.solve_relative`): the signals of each receiver, the pairing of
rover and base epochs, and cycle-slip detection."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import C_MPS
from navtrack.gnss import spp
from navtrack.gnss.corrections import frequency_hz
from navtrack.gnss.rtk_config import RtkConfig

if TYPE_CHECKING:
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = [
    "SECOND_BANDS",
    "ReceiverSignals",
    "Slips",
    "carrier_bands",
    "common_epochs",
    "detect_slips",
    "receiver_signals",
]

SECOND_BANDS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "G": ("2", "5"),
        "J": ("2", "5"),
        "E": ("7", "5"),
        "C": ("7", "6", "5"),
        "R": ("2",),
    }
)
"""RINEX band digits of a system's second frequency in relative positioning, in order of
preference (L2 before L5, E5b before E5a, B2I before B3I and B2a): the first that both
receivers track is used (:func:`carrier_bands`)."""


def carrier_bands(obs: Observations, system: str, bands: Sequence[str]) -> list[str]:
    """The bands among ``bands`` in which ``obs`` holds carrier phase of ``system`` (a code of
    :data:`navtrack.gnss.spp.CODE_PRIORITY` whose ``L`` code has a value)."""
    cols = [i for i, sat in enumerate(obs.sats) if sat[0] == system]
    out = []
    for band in bands:
        for code in spp.CODE_PRIORITY.get(system, {}).get(band, ()):
            phase = "L" + code[1:]
            if (
                phase in obs.codes
                and np.isfinite(obs.values[:, cols, obs.codes.index(phase)]).any()
            ):
                out.append(band)
                break
    return out


# --------------------------------------------------------------------------- stage 1: signals
@dataclass(frozen=True, slots=True, eq=False)
class ReceiverSignals:
    """Code, carrier and Doppler of one receiver on fixed axes, with its single point positions.

    Attributes
    ----------
    path : str
        Observation file.
    t_gps_s : ndarray, shape (E,)
    sats : tuple of str, length S
    code_m : ndarray, shape (E, S, F)
        Pseudorange corrected for the satellite clock (m); NaN where missing or unusable.
    phase_m : ndarray, shape (E, S, F)
        Carrier phase times the wavelength, with the same satellite clock correction (m).
    phase_cyc : ndarray, shape (E, S, F)
        Carrier phase as observed (cycles).
    doppler_hz : ndarray, shape (E, S, F)
    lli : ndarray of int8, shape (E, S, F)
        Loss-of-lock indicator of the phase (0 where blank).
    wavelength_m : ndarray, shape (S, F)
    sat_pos_m : ndarray, shape (E, S, 3)
        Satellite ECEF position at this receiver's transmission time (m).
    spp_pos_m : ndarray, shape (E, 3)
        Single point position (ECEF, m), NaN where the SPP failed.
    """

    path: str
    t_gps_s: FloatArray
    sats: tuple[str, ...]
    code_m: FloatArray
    phase_m: FloatArray
    phase_cyc: FloatArray
    doppler_hz: FloatArray
    lli: np.ndarray
    wavelength_m: FloatArray
    sat_pos_m: FloatArray
    spp_pos_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def receiver_signals(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None,
    config: RtkConfig | None = None,
    *,
    sp3: Sp3 | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
    second_bands: Mapping[str, str] | None = None,
) -> ReceiverSignals:
    """Signals of one receiver through the SPP stages (stage 1 of
    :func:`~navtrack.gnss.relative.solve_relative`).

    Parameters
    ----------
    obs : Observations
    nav : NavData or sequence of NavData
    config : RtkConfig, optional
    sp3 : Sp3, optional
        Precise orbits and clocks instead of the broadcast ones.
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built broadcast tables (:func:`navtrack.gnss.spp.navigation_tables`).
    second_bands : mapping of str to str, optional
        Band of each system's second frequency (default: the second band of
        :data:`navtrack.gnss.spp.IONOFREE_BANDS`).

    Returns
    -------
    ReceiverSignals

    Notes
    -----
    The carrier of a band is the ``L`` code of the pseudorange code chosen for it (``C1C`` ->
    ``L1C``, RINEX 2 ``C1``/``P1`` -> ``L1``, ``P2`` -> ``L2``), its Doppler the ``D`` code.
    With SP3 no broadcast group delay is applied (precise clocks are ionosphere-free ones).
    """
    cfg = config or RtkConfig()
    tgd = "" if sp3 is not None else spp.SppConfig().tgd_systems
    scfg = spp.SppConfig(systems=cfg.systems, elmask_deg=cfg.elmask_deg, tgd_systems=tgd)
    tables = spp.navigation_tables(nav, ephemeris)
    pr = spp.code_pseudoranges(obs, scfg)
    sv = spp.satellite_states(pr, nav, sp3=sp3, config=scfg, ephemeris=tables)
    meas = spp.corrected_measurements(pr, sv, scfg)
    est = spp.estimate_position(meas, scfg)
    ok = spp.validate(est, scfg) == spp.SppStatus.OK
    sats = list(pr.sats)
    n_e, n_s, n_f = pr.t_gps_s.size, len(sats), cfg.frequencies
    sat_corr = np.where(meas.usable, meas.y_m - pr.pr_m, np.nan)  # c (dt_sat - tgd), m
    code = np.full((n_e, n_s, n_f), np.nan)
    carrier, lam = _Carrier(n_e, n_s, n_f), np.full((n_s, n_f), np.nan)
    if second_bands is None:
        second_bands = {s: b[1] for s, b in spp.IONOFREE_BANDS.items()}
    for f in range(n_f):
        bands = {
            s: (spp.PRIMARY_BAND[s] if f == 0 else second_bands[s])
            for s in pr.systems
            if f == 0 or s in second_bands
        }
        p, _, used = spp.select_pseudoranges(obs, sats, bands)
        code[:, :, f] = p + sat_corr
        lam[:, f] = _wavelengths(sats, bands, sv.freq_hz)
        carrier.gather(obs, sats, used, f)
    phase_cyc, doppler, lli = carrier.phase_cyc, carrier.doppler_hz, carrier.lli
    bad_epoch = obs.epoch_flag > 1  # flag-6 values are slip counts, not observations
    phase_cyc[bad_epoch] = np.nan
    code[bad_epoch] = np.nan
    phase_m = phase_cyc * lam[None] + sat_corr[..., None]
    return ReceiverSignals(
        path=obs.path,
        t_gps_s=pr.t_gps_s,
        sats=pr.sats,
        code_m=code,
        phase_m=np.where(np.isfinite(code), phase_m, np.nan),
        phase_cyc=phase_cyc,
        doppler_hz=doppler,
        lli=lli,
        wavelength_m=lam,
        sat_pos_m=sv.pos_m,
        spp_pos_m=np.where(ok[:, None], est.x[:, :3], np.nan),
    )


def _wavelengths(sats: list[str], bands: Mapping[str, str], freq_hz: FloatArray) -> FloatArray:
    """Carrier wavelength (m) of each satellite on its system's band; NaN where its system has
    no such band. GLONASS from the channel of the ephemerides (``freq_hz``, the primary band
    of the SPP stages, the median over epochs): G2 is G1 times 7/9 (both are multiples of the
    same channel spacing, GLONASS ICD 3.3.1.4)."""
    lam = np.full(len(sats), np.nan)
    for j, sat in enumerate(sats):
        band = bands.get(sat[0])
        if band is None:
            continue
        if sat[0] == "R":
            f1 = freq_hz[:, j][np.isfinite(freq_hz[:, j])]
            if f1.size:
                lam[j] = C_MPS / (float(np.median(f1)) * (7.0 / 9.0 if band == "2" else 1.0))
        else:
            lam[j] = C_MPS / float(frequency_hz(sat[0], band))
    return lam


class _Carrier:
    """Phase, Doppler and loss-of-lock indicator of the signals whose code was selected."""

    def __init__(self, n_e: int, n_s: int, n_f: int) -> None:
        self.phase_cyc = np.full((n_e, n_s, n_f), np.nan)
        self.doppler_hz = np.full((n_e, n_s, n_f), np.nan)
        self.lli = np.zeros((n_e, n_s, n_f), dtype=np.int8)

    def gather(self, obs: Observations, sats: list[str], used: IntArray, f: int) -> None:
        """Fill frequency ``f`` from the ``L`` and ``D`` codes of the code index ``used``
        (epochs, sats) chose (-1: none)."""
        col = {s: i for i, s in enumerate(obs.sats)}
        for j, sat in enumerate(sats):
            for k in np.unique(used[:, j][used[:, j] >= 0]):
                rows = used[:, j] == k
                name = obs.codes[k]
                for prefix, out in (("L", self.phase_cyc), ("D", self.doppler_hz)):
                    other = prefix + name[1:]
                    if other not in obs.codes:
                        continue
                    kk = obs.codes.index(other)
                    out[rows, j, f] = obs.values[rows, col[sat], kk]
                    if prefix == "L":
                        li = obs.lli[rows, col[sat], kk]
                        self.lli[rows, j, f] = np.where(li > 0, li, 0)


# --------------------------------------------------------------------------- stage 2: epochs
def common_epochs(
    t_rover_s: FloatArray, t_base_s: FloatArray, *, sync_s: float = 0.025, max_age_s: float = 30.0
) -> tuple[IntArray, IntArray, FloatArray]:
    """The base epoch of each rover epoch: the latest tagged at most ``sync_s`` after it, if it
    is at most ``max_age_s`` older.

    Parameters
    ----------
    t_rover_s, t_base_s : ndarray, shape (E,) and (B,)
        Time tags (s), ascending.
    sync_s : float
        A base tag this much after the rover's still pairs with it (the same epoch tagged a
        few milliseconds apart).
    max_age_s : float

    Returns
    -------
    rover_idx, base_idx : ndarray of int, shape (K,)
        Rover epochs with a base, ascending, and their base epochs.
    age_s : ndarray, shape (K,)
        Rover time minus base time (s; down to ``-sync_s``).
    """
    tr = np.asarray(t_rover_s, dtype=float)
    tb = np.asarray(t_base_s, dtype=float)
    k = np.searchsorted(tb, tr + sync_s, side="right") - 1
    has = k >= 0
    age = np.where(has, tr - tb[np.maximum(k, 0)], np.inf)
    ir = np.flatnonzero(has & (age <= max_age_s))
    return ir.astype(np.int64), k[ir].astype(np.int64), age[ir]


# --------------------------------------------------------------------------- stage 3: slips
@dataclass(frozen=True, slots=True, eq=False)
class Slips:
    """Cycle slips of one receiver, per kind of detector.

    Attributes
    ----------
    lli, doppler, geometry_free : ndarray of bool, shape (E, S, F)
        Slip flagged at epoch ``e`` (between ``e-1`` and ``e``) by that detector.
    half_cycle : ndarray of bool, shape (E, S, F)
        Loss-of-lock indicator bit 1 (half-cycle ambiguity unresolved): kept in the float
        solution, left out of integer fixing.
    """

    lli: BoolArray
    doppler: BoolArray
    geometry_free: BoolArray
    half_cycle: BoolArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def any(self) -> BoolArray:
        """Slip by any detector, shape (E, S, F)."""
        return self.lli | self.doppler | self.geometry_free

    def counts(self) -> dict[str, int]:
        """Slips flagged by each detector."""
        return {
            "lli": int(self.lli.sum()),
            "doppler": int(self.doppler.sum()),
            "geometry_free": int(self.geometry_free.sum()),
        }


def detect_slips(sig: ReceiverSignals, config: RtkConfig | None = None) -> Slips:
    """Cycle slips of one receiver (stage 3 of
    :func:`~navtrack.gnss.relative.solve_relative`), all epochs at once.

    Loss of lock: LLI bit 0, or bit 1 (half-cycle ambiguity) set or cleared since the epoch
    before. Doppler: ``|dL - dL_pred - median| > slip_doppler_cyc`` with
    ``dL_pred = -(D_{e-1} + D_e) dt / 2`` (RINEX sign: Doppler positive for approaching
    satellites) and the median over the epoch's satellites removing the receiver clock change.
    Geometry-free: ``|dGF| > slip_gf_m`` with ``GF = lambda_1 L_1 - lambda_2 L_2``; a jump
    flags both frequencies.

    References
    ----------
    RTKLIB 2.4.2 manual, E.7.6 (eq. E.7.25 geometry-free); RINEX 2.11 sec. 5.1 (LLI bits).
    """
    cfg = config or RtkConfig()
    L = sig.phase_cyc
    half = (sig.lli & 2) != 0
    lli_slip = (sig.lli & 1) != 0
    # the receiver resolving (or losing) the half-cycle: the phase may jump by half a cycle
    lli_slip[1:] |= half[1:] != half[:-1]
    dop = np.zeros_like(lli_slip)
    gf_slip = np.zeros_like(lli_slip)
    if L.shape[0] > 1:
        dt = np.diff(sig.t_gps_s)[:, None, None]
        if cfg.slip_doppler_cyc > 0:
            D = sig.doppler_hz
            e = np.diff(L, axis=0) + 0.5 * (D[1:] + D[:-1]) * dt
            ok = np.isfinite(e)
            any_ok = ok.any(axis=1, keepdims=True)
            med = np.zeros_like(e[:, :1])
            np.copyto(
                med, np.nanmedian(np.where(any_ok, e, 0.0), axis=1, keepdims=True), where=any_ok
            )
            dop[1:] = ok & (np.abs(e - med) > cfg.slip_doppler_cyc)
        if L.shape[2] > 1:
            gf = sig.phase_cyc[..., 0] * sig.wavelength_m[None, :, 0] - (
                sig.phase_cyc[..., 1] * sig.wavelength_m[None, :, 1]
            )
            jump = np.abs(np.diff(gf, axis=0)) > cfg.slip_gf_m
            gf_slip[1:] = jump[..., None]
    return Slips(lli=lli_slip, doppler=dop, geometry_free=gf_slip, half_cycle=half)
