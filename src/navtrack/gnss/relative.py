"""Carrier-phase relative positioning (RTK) of a rover against a base at a known position.

Stages, as RTKLIB's ``rtkpos`` chains them, over ``(epochs, satellites, frequencies)`` arrays:

1. :func:`receiver_signals` — per receiver, the SPP stages of :mod:`navtrack.gnss.spp`
   (``code_pseudoranges`` -> ``satellite_states`` -> ``corrected_measurements`` ->
   ``estimate_position``) give the satellite states, the corrected code, the single point
   position; carrier phase (m), Doppler and loss-of-lock indicators of the same signals are
   added on the same axes.
2. :func:`common_epochs` — each rover epoch paired with the latest base epoch (a base tag up
   to ``sync_s`` after the rover's counts as the same epoch, receivers tag milliseconds off
   the grid), used up to ``max_age_s`` old (RTKLIB ``maxage``): a 1 Hz rover runs against a
   5 or 30 s base, the age in the output and its satellite clock drift in the variance.
3. :func:`detect_slips` — cycle slips from the loss-of-lock indicator, the Doppler-predicted
   phase change and (dual frequency) the geometry-free combination, per receiver, batched
   over all epochs and satellites.
4. :func:`solve_relative` — a Kalman filter over the common epochs on the rover position
   and the single-differenced ambiguities (cycles) with double-differenced code and carrier
   observations (one reference satellite per system and frequency), then integer fixing of
   the double-differenced ambiguities by LAMBDA (:mod:`navtrack.gnss.ambiguity`) with the ratio
   test and partial fixing, and the position conditioned on the fixed integers.

Kinematic rovers: the position is a white process (re-initialised at the single point
solution with a 30 m standard deviation at every epoch, RTKLIB's ``dynamics off``), the
ambiguities a random walk. Static rovers: the position has no process noise, so the filter
is the recursive form of the batch least-squares solution of all epochs so far (for a linear
model both give the same estimate).

References
----------
Teunissen, P.J.G., Montenbruck, O. (eds.) (2017). Springer Handbook of GNSS, ch. 26 (RTK),
eq. 26.11-26.14 (double differences), 23.4 (ambiguity resolution).
Takasu, T. (2013). RTKLIB ver. 2.4.2 Manual, appendix E.7 (relative positioning: state,
measurement model, variances), E.7.6 (cycle slips).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import chdtri

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.errors import NavtrackError
from navtrack.estimation.covariance import restart_states
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation
from navtrack.gnss.ambiguity import AmbiguityConfig, condition_on_fix, resolve_ambiguities

if TYPE_CHECKING:
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3
    from navtrack.gnss.spp import ProgressFn

__all__ = [
    "QUALITY",
    "REJECTION_NAMES",
    "STATUS_NAMES",
    "FixRejection",
    "ReceiverSignals",
    "RelativeInputError",
    "RtkConfig",
    "RtkResult",
    "RtkStatus",
    "Slips",
    "common_epochs",
    "detect_slips",
    "receiver_signals",
    "solution_frame",
    "solve_relative",
]


class RtkStatus(IntEnum):
    """Per-epoch outcome of :func:`solve_relative` (printed by lower-case name)."""

    FIX = 0
    FLOAT = 1
    DGNSS = 2
    SINGLE = 3
    NO_BASE = 4
    NO_SOLUTION = 5


STATUS_NAMES = tuple(s.name.lower() for s in RtkStatus)


class FixRejection(IntEnum):
    """Why a fix the ratio test accepted was not used (the epoch stays float).

    ``residuals``: the phase double differences at the fixed state fail the chi-square test;
    ``float_position``: the fixed position lies outside the float position's confidence region;
    ``directions_disagree``: ``combined`` forward and backward fixes farther apart than 4
    standard deviations.
    """

    NONE = 0
    RESIDUALS = 1
    FLOAT_POSITION = 2
    DIRECTIONS_DISAGREE = 3


REJECTION_NAMES = tuple(r.name.lower() for r in FixRejection)

QUALITY: Mapping[int, int] = MappingProxyType(
    {
        RtkStatus.FIX: 1,
        RtkStatus.FLOAT: 2,
        RtkStatus.DGNSS: 4,
        RtkStatus.SINGLE: 5,
        RtkStatus.NO_BASE: 5,
        RtkStatus.NO_SOLUTION: 0,
    }
)
"""RTKLIB's solution quality ``Q`` of each status (1 fix, 2 float, 4 DGNSS, 5 single; 6 is
PPP, :mod:`navtrack.gnss.ppp`). ``no_base`` epochs carry the single point position."""


class RelativeInputError(NavtrackError, ValueError):
    """Rover and base observations that cannot be differenced (no common epochs or
    satellites); the message names both files."""


@dataclass(frozen=True, slots=True)
class RtkConfig:
    """Options of :func:`solve_relative`; defaults after RTKLIB 2.4.3's ``rnx2rtkp``.

    Attributes
    ----------
    mode : str
        ``kinematic`` or ``static``.
    systems : str
        Systems to difference (GLONASS is left out: its FDMA carriers do not give integer
        double-differenced ambiguities without inter-frequency biases).
    frequencies : int
        1 (L1/E1/B1) or 2 (adds L2/E5b/B3 where both receivers track it).
    elmask_deg : float
        Elevation mask at the rover (deg).
    min_sats : int
        Fewest satellites in the double differences (reference included) for a relative
        solution.
    sigma_phase_m : tuple of float
        ``(a, b)`` of the undifferenced carrier-phase variance ``a^2 + b^2 / sin^2(el)``
        (m; RTKLIB ``err`` 0.003, 0.003).
    code_phase_ratio : float
        Code to phase standard deviation ratio (RTKLIB ``eratio`` 100).
    sigma_pos0_m : float
        Standard deviation of the kinematic position at each epoch and of the start position
        (RTKLIB: 30 m).
    sigma_amb0_m : float
        Standard deviation of a (re-)initialised ambiguity (m; RTKLIB ``std[0]`` 30).
    q_amb_cyc : float
        Random walk of the ambiguities (cycles / sqrt(s); RTKLIB ``prn[0]`` 1e-4).
    slip_doppler_cyc : float
        Slip when the phase change departs from the Doppler prediction by more than this
        (cycles; after removing the epoch's median, the receiver clock). 0 disables.
    slip_gf_m : float
        Slip when the geometry-free combination jumps by more than this (m; RTKLIB
        ``thresslip`` 0.05).
    max_outage : int
        A satellite unseen for more than this many epochs restarts its ambiguity (RTKLIB
        ``maxout`` 5).
    max_age_s : float
        Base observations are used for rover epochs up to this much later (s; RTKLIB
        ``maxage`` 30).
    sync_s : float
        A base epoch tagged up to this much after a rover epoch is the same epoch (s).
    clock_stability : float
        Satellite clock stability (s/s, RTKLIB ``stats-clkstab`` 5e-12): the single
        difference of a base observation ``age`` seconds old gains ``(c stability age)^2`` of
        variance.
    fix_test_p : float
        False-alarm probability of the two tests a fix passes after the ratio test
        (:class:`FixRejection`): the chi-square of the phase double-difference residuals at the
        fixed state, and of the fixed position's departure from the float one in the float
        covariance (3 degrees of freedom).
    ambiguity : AmbiguityConfig
        Ratio test and partial fixing (:func:`navtrack.gnss.ambiguity.resolve_ambiguities`).
    fix : bool
        Resolve integer ambiguities (False: float solution only).
    direction : str
        ``forward`` (real-time order), ``backward``, or ``combined``: both filters joined
        epoch by epoch (RTKLIB ``-c``): the better status wins; equal statuses are averaged
        with their covariances; two fixed solutions that disagree by more than 4 standard
        deviations of their difference fall back to the combined float solution.
    """

    mode: str = "kinematic"
    systems: str = "GECJ"
    frequencies: int = 1
    elmask_deg: float = 15.0
    min_sats: int = 4
    sigma_phase_m: tuple[float, float] = (0.003, 0.003)
    code_phase_ratio: float = 100.0
    sigma_pos0_m: float = 30.0
    sigma_amb0_m: float = 30.0
    q_amb_cyc: float = 1e-4
    slip_doppler_cyc: float = 5.0
    slip_gf_m: float = 0.05
    max_outage: int = 5
    max_age_s: float = 30.0
    sync_s: float = 0.025
    clock_stability: float = 5e-12
    fix_test_p: float = 1e-3
    ambiguity: AmbiguityConfig = field(default_factory=AmbiguityConfig)
    fix: bool = True
    direction: str = "forward"

    def __post_init__(self) -> None:
        if self.mode not in ("kinematic", "static"):
            raise ValueError(f"mode: expected 'kinematic' or 'static', got {self.mode!r}")
        if self.frequencies not in (1, 2):
            raise ValueError(f"frequencies: expected 1 or 2, got {self.frequencies}")
        if "R" in self.systems:
            raise ValueError("systems: GLONASS (R) is not supported in double differences")
        if self.direction not in ("forward", "backward", "combined"):
            raise ValueError(
                f"direction: expected 'forward', 'backward' or 'combined', got {self.direction!r}"
            )
        if self.max_outage < 0:
            raise ValueError(f"max_outage: expected >= 0, got {self.max_outage}")
        if not 0.0 < self.fix_test_p < 1.0:
            raise ValueError(f"fix_test_p: expected in (0, 1), got {self.fix_test_p}")
        for name in ("max_age_s", "sync_s", "clock_stability"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name}: expected a finite number >= 0, got {value}")
        if self.min_sats < 2:
            raise ValueError(f"min_sats: expected >= 2, got {self.min_sats}")


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
) -> ReceiverSignals:
    """Signals of one receiver through the SPP stages (stage 1 of :func:`solve_relative`).

    Parameters
    ----------
    obs : Observations
    nav : NavData or sequence of NavData
    config : RtkConfig, optional
    sp3 : Sp3, optional
        Precise orbits and clocks instead of the broadcast ones.
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built broadcast tables (:func:`navtrack.gnss.spp.navigation_tables`).

    Returns
    -------
    ReceiverSignals

    Notes
    -----
    The carrier of a band is the ``L`` code of the pseudorange code chosen for it (``C1C`` ->
    ``L1C``, RINEX 2 ``C1``/``P1`` -> ``L1``, ``P2`` -> ``L2``), its Doppler the ``D`` code.
    With SP3 the broadcast group delays are not applied (precise clocks refer to the
    ionosphere-free combination of their analysis centre).
    """
    from navtrack.gnss import spp
    from navtrack.gnss.corrections import frequency_hz

    cfg = config or RtkConfig()
    # precise clocks refer to the ionosphere-free combination: no broadcast group delay on them
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
    phase_cyc = np.full((n_e, n_s, n_f), np.nan)
    doppler = np.full((n_e, n_s, n_f), np.nan)
    lli = np.zeros((n_e, n_s, n_f), dtype=np.int8)
    lam = np.full((n_s, n_f), np.nan)
    col = {s: i for i, s in enumerate(obs.sats)}
    for f in range(n_f):
        bands = {
            s: (spp.PRIMARY_BAND[s] if f == 0 else spp.IONOFREE_BANDS[s][1])
            for s in pr.systems
            if f == 0 or s in spp.IONOFREE_BANDS
        }
        p, _, used = spp.select_pseudoranges(obs, sats, bands)
        code[:, :, f] = p + sat_corr
        for j, sat in enumerate(sats):
            if sat[0] not in bands:
                continue
            lam[j, f] = C_MPS / float(frequency_hz(sat[0], bands[sat[0]]))
            for k in np.unique(used[:, j][used[:, j] >= 0]):
                rows = used[:, j] == k
                name = obs.codes[k]
                for prefix, out in (("L", phase_cyc), ("D", doppler)):
                    other = prefix + name[1:]
                    if other in obs.codes:
                        kk = obs.codes.index(other)
                        out[rows, j, f] = obs.values[rows, col[sat], kk]
                        if prefix == "L":
                            li = obs.lli[rows, col[sat], kk]
                            lli[rows, j, f] = np.where(li > 0, li, 0)
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
    """Cycle slips of one receiver (stage 3 of :func:`solve_relative`), all epochs at once.

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


# --------------------------------------------------------------------------- result
@dataclass(frozen=True, slots=True, eq=False)
class RtkResult:
    """Relative positions of every rover epoch.

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Rover epochs.
    sats : tuple of str, length S
        Satellites common to rover and base.
    pos_m : ndarray, shape (E, 3)
        Rover position (ECEF, m): fixed where ``status`` is ``fix``, float, DGNSS or single
        point otherwise; NaN for ``no_solution``.
    float_pos_m : ndarray, shape (E, 3)
        Float solution (NaN where none).
    sd_enu_m : ndarray, shape (E, 3)
        Formal standard deviation of ``pos_m`` in east, north, up (m).
    status : ndarray of int8, shape (E,)
        :class:`RtkStatus`.
    ratio : ndarray, shape (E,)
        Ratio-test value of the epoch's ambiguity search (NaN when none ran).
    n_sats : ndarray of int, shape (E,)
        Satellites in the double differences (references included).
    n_fixed : ndarray of int, shape (E,)
        Integer ambiguity combinations fixed.
    slips : mapping of str to int
        Slips flagged per detector, rover and base together.
    slip_mask : ndarray of bool, shape (E, S)
        A slip reset an ambiguity of that satellite at that epoch.
    age_s : ndarray, shape (E,)
        Age of the base observations used (rover minus base time, s; NaN without a base).
    fix_rejected : ndarray of int8, shape (E,)
        :class:`FixRejection` of an epoch whose ratio-accepted fix was not used (0 otherwise).
    n_rover_epochs, n_base_epochs, n_common_epochs : int
    warnings : tuple of str
        Input problems found (base position far from the base's own SPP, a system without
        carrier phase, different rates).
    base_spp_distance_m : float
        Distance of the given base position from the median SPP of the base observations.
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    pos_m: FloatArray
    float_pos_m: FloatArray
    sd_enu_m: FloatArray
    status: np.ndarray
    ratio: FloatArray
    n_sats: IntArray
    n_fixed: IntArray
    slips: Mapping[str, int]
    slip_mask: BoolArray
    age_s: FloatArray
    fix_rejected: np.ndarray
    n_rover_epochs: int
    n_base_epochs: int
    n_common_epochs: int
    warnings: tuple[str, ...]
    base_spp_distance_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "slips", MappingProxyType(dict(self.slips)))
        freeze_arrays(self)

    def status_counts(self) -> dict[str, int]:
        """Epochs per status name (all statuses, zeros included)."""
        return {n: int(np.sum(self.status == i)) for i, n in enumerate(STATUS_NAMES)}

    def rejection_counts(self) -> dict[str, int]:
        """Fixes the ratio test accepted and :class:`FixRejection` refused, per reason."""
        return {
            n: int(np.sum(self.fix_rejected == i))
            for i, n in enumerate(REJECTION_NAMES)
            if i != FixRejection.NONE
        }

    @property
    def quality(self) -> IntArray:
        """RTKLIB solution quality per epoch (:data:`QUALITY`)."""
        q = np.array([QUALITY[i] for i in range(len(RtkStatus))], dtype=np.int64)
        return q[self.status.astype(np.int64)]


# --------------------------------------------------------------------------- stage 4: filter
def _variance(el: FloatArray, cfg: RtkConfig) -> FloatArray:
    """Undifferenced phase variance (m^2), RTKLIB 2.4.2 manual eq. E.6.24 without the SNR term."""
    a, b = cfg.sigma_phase_m
    return a * a + b * b / np.maximum(np.sin(el), 0.05) ** 2


def _elevation(sat_pos: FloatArray, rcv: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Range (with Sagnac), line of sight and elevation of ``(..., S, 3)`` satellites seen from
    ``(..., 3)`` receivers."""
    from navtrack.gnss.corrections import geometric_range

    rho, los = geometric_range(sat_pos, rcv[..., None, :])
    llh = ecef_to_geodetic(rcv.reshape(-1, 3)).reshape(rcv.shape)
    rot = enu_rotation(llh[..., 0], llh[..., 1])
    up = np.einsum("...j,...sj->...s", rot[..., 2, :], los)
    return rho, los, np.arcsin(np.clip(up, -1.0, 1.0))


def _forward_fill(pos: FloatArray) -> FloatArray:
    """Rows of ``(K, 3)`` positions with NaN replaced by the last finite row before them (the
    first finite row before the first one)."""
    ok = np.all(np.isfinite(pos), axis=1)
    if not ok.any():
        return pos.copy()
    idx = np.where(ok, np.arange(ok.size), 0)
    idx = np.maximum.accumulate(idx)
    idx[: int(np.argmax(ok))] = int(np.argmax(ok))
    return pos[idx]


def _troposphere(rcv: FloatArray, el: FloatArray) -> FloatArray:
    from navtrack.gnss.corrections import saastamoinen_delay_m

    llh = ecef_to_geodetic(rcv.reshape(-1, 3)).reshape(rcv.shape)
    return np.asarray(saastamoinen_delay_m(llh[..., 0:1], llh[..., 2:3], el))


def _double_differences(
    groups: IntArray, ok: BoolArray, el: FloatArray
) -> tuple[IntArray, IntArray]:
    """Reference and other index of every double difference: in each group the satellite of
    highest elevation among ``ok`` is the reference. Returns ``(ref, other)`` index arrays
    into the flattened ``(S * F)`` axis."""
    ref_l: list[int] = []
    oth_l: list[int] = []
    for g in np.unique(groups[ok]):
        members = np.flatnonzero(ok & (groups == g))
        if members.size < 2:
            continue
        r = members[np.argmax(el[members])]
        others = members[members != r]
        ref_l.extend([int(r)] * others.size)
        oth_l.extend(others.tolist())
    return np.array(ref_l, dtype=np.int64), np.array(oth_l, dtype=np.int64)


def _dd_matrix(ref: IntArray, oth: IntArray, n: int) -> FloatArray:
    D = np.zeros((ref.size, n))
    rows = np.arange(ref.size)
    D[rows, oth] = 1.0
    D[rows, ref] = -1.0
    return D


@dataclass(frozen=True, slots=True, eq=False)
class _Epochs:
    """Inputs of the filter over the K common epochs, ``(K, S, F)`` with ``N = S F`` flattened
    ambiguities."""

    t: FloatArray  # (K,)
    sd_phase: FloatArray  # (K, N) SD phase minus the computed ranges at x_lin (and base), m
    sd_code: FloatArray  # (K, N)
    x_lin: FloatArray  # (K, 3) linearisation point of the rover (SPP, forward filled)
    G: FloatArray  # (K, N, 3) d(range)/d(rover position) at x_lin, 0 where not observed
    el: FloatArray  # (K, N) rover elevation, rad
    var_sd: FloatArray  # (K, N) SD phase variance, m^2
    reset: BoolArray  # (K, N) slip: restart the ambiguity
    half: BoolArray  # (K, N) half-cycle unresolved: not fixed
    spp: FloatArray  # (K, 3) rover SPP
    lam: FloatArray  # (N,)
    groups: IntArray  # (N,) system x frequency group of each ambiguity
    n_f: int


def _epoch_inputs(
    rover: ReceiverSignals,
    base: ReceiverSignals,
    base_xyz_m: FloatArray,
    ir: IntArray,
    ib: IntArray,
    age_s: FloatArray,
    js_r: IntArray,
    js_b: IntArray,
    slips_r: Slips,
    slips_b: Slips,
    cfg: RtkConfig,
) -> _Epochs:
    n_f = cfg.frequencies
    sat_b = base.sat_pos_m[ib][:, js_b]
    rho_b, _, el_b = _elevation(sat_b, np.broadcast_to(base_xyz_m, (ib.size, 3)))
    trop_b = _troposphere(np.broadcast_to(base_xyz_m, (ib.size, 3)), el_b)
    corr_b = (rho_b + trop_b)[..., None]
    spp = rover.spp_pos_m[ir]
    x_lin = _forward_fill(spp)
    sat_r = rover.sat_pos_m[ir][:, js_r]
    rho_r, los_r, el_r = _elevation(sat_r, x_lin)
    trop_r = _troposphere(x_lin, el_r)
    # the slant delay changes with the rover height too: its gradient joins the geometry
    llh = ecef_to_geodetic(x_lin)
    up = enu_rotation(llh[:, 0], llh[:, 1])[:, 2, :]
    dtrop_dh = _troposphere(x_lin + up, el_r) - trop_r
    corr_r = (rho_r + trop_r)[..., None]
    ph = rover.phase_m[ir][:, js_r] - (base.phase_m[ib][:, js_b] - corr_b) - corr_r
    co = rover.code_m[ir][:, js_r] - (base.code_m[ib][:, js_b] - corr_b) - corr_r
    # phase needs its code (for the ambiguity start value)
    ph = np.where(np.isfinite(co), ph, np.nan)
    k, n_s = ir.size, js_r.size
    # a base slip restarts the ambiguity once, at the first rover epoch that uses its epoch
    new_base = np.concatenate([[True], ib[1:] != ib[:-1]])
    reset = slips_r.any[ir][:, js_r] | (slips_b.any[ib][:, js_b] & new_base[:, None, None])
    half = slips_r.half_cycle[ir][:, js_r] | slips_b.half_cycle[ib][:, js_b]
    sys_id = np.array(["GRECJSI".index(s[0]) for s in rover.sats], dtype=np.int64)[js_r]
    groups = (sys_id[:, None] * 4 + np.arange(n_f)[None, :]).reshape(-1)
    drift = (C_MPS * cfg.clock_stability * age_s) ** 2  # the base's satellite clocks, aged
    var_sd = _variance(el_b, cfg) + _variance(el_r, cfg) + drift[:, None]
    var = np.broadcast_to(var_sd[..., None], (k, n_s, n_f))
    G = -los_r + dtrop_dh[..., None] * up[:, None, :]
    G = np.repeat(np.where(np.isfinite(G), G, 0.0), n_f, axis=1)
    return _Epochs(
        t=rover.t_gps_s[ir],
        sd_phase=ph.reshape(k, -1),
        sd_code=co.reshape(k, -1),
        x_lin=x_lin,
        G=G,
        el=np.repeat(el_r, n_f, axis=1),
        var_sd=var.reshape(k, -1),
        reset=reset.reshape(k, -1),
        half=half.reshape(k, -1),
        spp=spp,
        lam=rover.wavelength_m[js_r].reshape(-1),
        groups=groups,
        n_f=n_f,
    )


class _FilterOut:
    """Per-epoch outputs of :func:`_run_filter`, filled row by row."""

    def __init__(self, k: int, n_s: int) -> None:
        self.pos = np.full((k, 3), np.nan)
        self.float_pos = np.full((k, 3), np.nan)
        self.cov = np.full((k, 3, 3), np.nan)
        self.float_cov = np.full((k, 3, 3), np.nan)
        self.status = np.full(k, RtkStatus.NO_SOLUTION, dtype=np.int8)
        self.ratio = np.full(k, np.nan)
        self.n_sats = np.zeros(k, dtype=np.int64)
        self.n_fixed = np.zeros(k, dtype=np.int64)
        self.slip = np.zeros((k, n_s), dtype=bool)
        self.rejected = np.zeros(k, dtype=np.int8)  # FixRejection of a fix the ratio accepted


def _run_filter(ep: _Epochs, cfg: RtkConfig, progress: ProgressFn | None = None) -> _FilterOut:
    """The Kalman filter over the common epochs: predict, restart slipped ambiguities, update
    with double differences, fix by LAMBDA."""
    from navtrack.estimation.kalman import gain_update, innovation_gain

    k_n, n_amb = ep.sd_phase.shape
    n_s = n_amb // ep.n_f
    n_x = 3 + n_amb
    out = _FilterOut(k_n, n_s)
    x = np.zeros(n_x)
    P = np.zeros((n_x, n_x))
    active = np.zeros(n_amb, dtype=bool)
    last_seen = np.full(n_amb, -(10**9), dtype=np.int64)  # epoch index
    have_pos = False
    t_prev = None
    el_mask = math.radians(cfg.elmask_deg)
    var_pos0 = cfg.sigma_pos0_m**2
    ratio_c = cfg.code_phase_ratio**2
    for k in range(k_n):
        if progress is not None and k % 100 == 0:
            progress(k, k_n)
        t = ep.t[k]
        dt = 0.0 if t_prev is None else abs(t - t_prev)  # backward: time runs back
        t_prev = t
        spp = ep.spp[k]
        # predict the position
        if cfg.mode == "kinematic" or not have_pos:
            x0 = spp if np.all(np.isfinite(spp)) else (x[:3] if have_pos else None)
            if x0 is None or not np.all(np.isfinite(ep.x_lin[k])):
                continue
            x[:3] = x0
            restart_states(P, np.arange(3), var_pos0)
            have_pos = True
        el_f = ep.el[k]
        rep = np.repeat(np.arange(n_s), ep.n_f)
        # residuals at the predicted position (linear in the offset from x_lin)
        shift = ep.G[k] @ (x[:3] - ep.x_lin[k])
        code_res = ep.sd_code[k] - shift
        phase_res = ep.sd_phase[k] - shift
        up = el_f >= el_mask
        code_ok = np.isfinite(code_res) & up
        phase_ok = np.isfinite(phase_res) & up
        # ambiguities: random walk; restart after a slip, a gap or on first sight
        amb = np.arange(n_amb) + 3
        P[amb[active], amb[active]] += cfg.q_amb_cyc**2 * dt
        restart = phase_ok & (~active | ep.reset[k] | (k - last_seen > cfg.max_outage + 1))
        out.slip[k] = np.bincount(rep, weights=(phase_ok & ep.reset[k]), minlength=n_s) > 0
        if restart.any():
            ri = amb[restart]
            restart_states(P, ri, (cfg.sigma_amb0_m / ep.lam[restart]) ** 2)
            x[ri] = (ep.sd_phase[k, restart] - ep.sd_code[k, restart]) / ep.lam[restart]
        active |= restart
        last_seen[phase_ok] = k
        # double differences
        ref_p, oth_p = _double_differences(ep.groups, phase_ok, el_f)
        ref_c, oth_c = _double_differences(ep.groups, code_ok, el_f)
        in_dd = np.zeros(n_amb, dtype=bool)
        in_dd[np.concatenate([ref_c, oth_c])] = True
        n_sat_dd = int(np.unique(rep[in_dd]).size)
        if ref_c.size == 0 or n_sat_dd < cfg.min_sats:
            if np.all(np.isfinite(spp)):
                out.pos[k] = spp
                out.status[k] = RtkStatus.SINGLE
                out.n_sats[k] = n_sat_dd
            continue
        # zeros where a satellite is not differenced (0 * NaN would spoil the products)
        var_sd = np.where(code_ok, ep.var_sd[k], 0.0)
        Dp = _dd_matrix(ref_p, oth_p, n_amb)
        Dc = _dd_matrix(ref_c, oth_c, n_amb)
        G = ep.G[k]
        H = np.zeros((ref_p.size + ref_c.size, n_x))
        H[: ref_p.size, :3] = Dp @ G
        H[: ref_p.size, 3:] = Dp * ep.lam[None, :]
        H[ref_p.size :, :3] = Dc @ G
        y = np.concatenate(
            [
                Dp @ np.where(phase_ok, phase_res, 0.0) - H[: ref_p.size, 3:] @ x[3:],
                Dc @ np.where(code_ok, code_res, 0.0),
            ]
        )
        R = np.zeros((y.size, y.size))
        R[: ref_p.size, : ref_p.size] = (Dp * var_sd) @ Dp.T
        R[ref_p.size :, ref_p.size :] = (Dc * (var_sd * ratio_c)) @ Dc.T
        S, K = innovation_gain(P, H, R)
        x_new, P = gain_update(x, P, y, K, S)
        # the update is about the predicted position: add the state change to it
        x = x_new
        out.float_pos[k] = x[:3]
        out.n_sats[k] = n_sat_dd
        out.cov[k] = P[:3, :3]
        out.float_cov[k] = P[:3, :3]
        out.pos[k] = x[:3]
        out.status[k] = RtkStatus.FLOAT if ref_p.size else RtkStatus.DGNSS
        if not (cfg.fix and ref_p.size):
            continue
        fixable = ~ep.half[k, oth_p] & ~ep.half[k, ref_p]
        A = np.zeros((int(fixable.sum()), n_x))
        A[:, 3:] = Dp[fixable]
        if A.shape[0] < cfg.ambiguity.min_fixed:
            continue
        a_hat = A @ x
        Q = A @ P @ A.T
        fix = resolve_ambiguities(a_hat, Q, cfg.ambiguity)
        out.ratio[k] = fix.ratio
        if fix.accepted:
            xf, Pf = condition_on_fix(x, P, A, fix)
            # beyond the ratio test: the fixed state must close the phase DDs and stay within
            # the float position's uncertainty
            v = Dp @ np.where(phase_ok, ep.sd_phase[k] - G @ (xf[:3] - ep.x_lin[k]), 0.0)
            v -= (Dp * ep.lam[None, :]) @ xf[3:]
            chi2_v = float(v @ np.linalg.solve(R[: ref_p.size, : ref_p.size], v))
            d = xf[:3] - x[:3]
            chi2_d = float(d @ np.linalg.solve(P[:3, :3], d))
            if chi2_v > float(chdtri(ref_p.size, cfg.fix_test_p)):
                out.rejected[k] = FixRejection.RESIDUALS
                continue
            if chi2_d > float(chdtri(3, cfg.fix_test_p)):
                out.rejected[k] = FixRejection.FLOAT_POSITION
                continue
            out.pos[k] = xf[:3]
            out.cov[k] = Pf[:3, :3]
            out.status[k] = RtkStatus.FIX
            out.n_fixed[k] = fix.n_fixed
    return out


def _reversed(ep: _Epochs) -> _Epochs:
    """The epochs in backward order: a slip flagged at epoch ``e`` (between ``e-1`` and ``e``)
    restarts the ambiguity when the backward filter moves on to ``e-1``."""
    reset = np.zeros_like(ep.reset)
    reset[:-1] = ep.reset[1:]
    fields = {
        name: getattr(ep, name)[::-1].copy()
        for name in ("t", "sd_phase", "sd_code", "x_lin", "G", "el", "var_sd", "half", "spp")
    }
    return _Epochs(**fields, reset=reset[::-1].copy(), lam=ep.lam, groups=ep.groups, n_f=ep.n_f)


def _reversed_output(out: _FilterOut) -> _FilterOut:
    rev = _FilterOut(out.status.size, out.slip.shape[1])
    for name in vars(out):
        setattr(rev, name, getattr(out, name)[::-1].copy())
    return rev


def _weighted_mean(
    xa: FloatArray, Pa: FloatArray, xb: FloatArray, Pb: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Inverse-covariance weighted mean of two estimates, ``(B, 3)`` and ``(B, 3, 3)``."""
    Ia = np.linalg.inv(Pa)
    Ib = np.linalg.inv(Pb)
    P = np.linalg.inv(Ia + Ib)
    x = np.einsum(
        "bij,bj->bi", P, np.einsum("bij,bj->bi", Ia, xa) + np.einsum("bij,bj->bi", Ib, xb)
    )
    return x, P


def _combine(fwd: _FilterOut, bwd: _FilterOut) -> _FilterOut:
    """Forward and backward solutions joined epoch by epoch (RTKLIB ``postpos`` ``combres``
    rules: better status wins, equal statuses averaged, disagreeing fixes fall back to float).

    Notes
    -----
    Both filters use the epoch's own measurements, so the average counts them twice (as the
    two-filter combination of RTKLIB does); the formal covariance is slightly optimistic.
    """
    out = _FilterOut(fwd.status.size, fwd.slip.shape[1])
    better_b = bwd.status < fwd.status
    for name in vars(out):
        a, b = getattr(fwd, name), getattr(bwd, name)
        sel = better_b.reshape((-1,) + (1,) * (a.ndim - 1))
        setattr(out, name, np.where(sel, b, a))
    out.slip = fwd.slip | bwd.slip
    relative = (RtkStatus.FIX, RtkStatus.FLOAT, RtkStatus.DGNSS)
    same = (fwd.status == bwd.status) & np.isin(fwd.status, relative)
    if same.any():
        x, P = _weighted_mean(fwd.pos[same], fwd.cov[same], bwd.pos[same], bwd.cov[same])
        out.pos[same], out.cov[same] = x, P
        xf, Pf = _weighted_mean(
            fwd.float_pos[same], fwd.float_cov[same], bwd.float_pos[same], bwd.float_cov[same]
        )
        out.float_pos[same], out.float_cov[same] = xf, Pf
        d = fwd.pos[same] - bwd.pos[same]
        sd = np.sqrt(np.einsum("bii->bi", fwd.cov[same] + bwd.cov[same]))
        bad = (fwd.status[same] == RtkStatus.FIX) & np.any(np.abs(d) > 4.0 * sd, axis=1)
        rows = np.flatnonzero(same)[bad]
        out.pos[rows], out.cov[rows] = out.float_pos[rows], out.float_cov[rows]
        out.status[rows] = RtkStatus.FLOAT
        out.n_fixed[rows] = 0
        out.rejected[rows] = FixRejection.DIRECTIONS_DISAGREE
    return out


def solve_relative(
    rover_obs: Observations,
    base_obs: Observations,
    nav: NavData | Sequence[NavData] | None,
    base_xyz_m: FloatArray,
    config: RtkConfig | None = None,
    *,
    sp3: Sp3 | None = None,
    base_warn_m: float = 100.0,
    progress: ProgressFn | None = None,
) -> RtkResult:
    """Relative (RTK) positions of every rover epoch against a base at a known position.

    Parameters
    ----------
    rover_obs, base_obs : Observations
    nav : NavData or sequence of NavData
        Broadcast navigation data (orbits and clocks unless ``sp3`` is given).
    base_xyz_m : array-like, shape (3,)
        Base antenna position (ECEF, m).
    config : RtkConfig, optional
    sp3 : Sp3, optional
    base_warn_m : float
        Warn when ``base_xyz_m`` is farther than this from the base's own median SPP.
    progress : callable, optional
        ``progress(epochs_done, epochs_total)`` every 100 epochs of each filter pass.

    Returns
    -------
    RtkResult

    Raises
    ------
    RelativeInputError
        No common epochs or no common satellites of the configured systems.
    ValueError
        ``base_xyz_m`` not a point near the earth's surface.
    """
    from navtrack.geodesy import check_near_surface
    from navtrack.gnss.spp import navigation_tables

    cfg = config or RtkConfig()
    base_xyz = check_near_surface(base_xyz_m, "base_xyz_m")
    tables = navigation_tables(nav)
    rover = receiver_signals(rover_obs, nav, cfg, sp3=sp3, ephemeris=tables)
    base = receiver_signals(base_obs, nav, cfg, sp3=sp3, ephemeris=tables)
    names = f"rover {rover_obs.path!r} and base {base_obs.path!r}"
    ir, ib, age = common_epochs(
        rover.t_gps_s, base.t_gps_s, sync_s=cfg.sync_s, max_age_s=cfg.max_age_s
    )
    if ir.size == 0:
        raise RelativeInputError(
            f"{names}: no common epochs (no base epoch up to {cfg.max_age_s:g} s before a rover "
            "epoch)"
        )
    common = [s for s in rover.sats if s in base.sats]
    if not common:
        raise RelativeInputError(f"{names}: no common satellites of the systems {cfg.systems}")
    js_r = np.array([rover.sats.index(s) for s in common], dtype=np.int64)
    js_b = np.array([base.sats.index(s) for s in common], dtype=np.int64)
    warnings = _input_warnings(rover, base, base_xyz, ir, js_r, js_b, cfg)
    base_spp = np.nanmedian(base.spp_pos_m, axis=0)
    dist = float(np.linalg.norm(base_spp - base_xyz))
    if dist > base_warn_m:
        warnings.insert(
            0,
            f"base position is {dist:.1f} m from the single point solution of the base "
            f"observations {base_obs.path!r}: check --base-pos",
        )
    slips_r = detect_slips(rover, cfg)
    slips_b = detect_slips(base, cfg)
    ep = _epoch_inputs(rover, base, base_xyz, ir, ib, age, js_r, js_b, slips_r, slips_b, cfg)
    if cfg.direction == "forward":
        out = _run_filter(ep, cfg, progress)
    else:
        out = _reversed_output(_run_filter(_reversed(ep), cfg, progress))
        if cfg.direction == "combined":
            out = _combine(_run_filter(ep, cfg, progress), out)
    return _result(rover, common, ir, age, out, slips_r, slips_b, base, warnings, dist)


def _input_warnings(
    rover: ReceiverSignals,
    base: ReceiverSignals,
    base_xyz: FloatArray,
    ir: IntArray,
    js_r: IntArray,
    js_b: IntArray,
    cfg: RtkConfig,
) -> list[str]:
    out = []
    n_r, n_b, n_c = rover.t_gps_s.size, base.t_gps_s.size, ir.size
    if n_c < n_r:
        out.append(
            f"rover {n_r} and base {n_b} epochs: {n_r - n_c} rover epochs without a base epoch "
            f"up to {cfg.max_age_s:g} s before them (no_base); {n_c} common epochs used"
        )
    sats = [rover.sats[j] for j in js_r]
    for s in dict.fromkeys(x[0] for x in sats):
        cols = [i for i, x in enumerate(sats) if x[0] == s]
        for who, sig, js in (("rover", rover, js_r), ("base", base, js_b)):
            if not np.isfinite(sig.phase_cyc[:, js[cols], 0]).any():
                out.append(f"system {s}: no carrier phase in the {who} {sig.path!r}: code only")
        if cfg.frequencies == 2:
            for who, sig, js in (("rover", rover, js_r), ("base", base, js_b)):
                if not np.isfinite(sig.phase_cyc[:, js[cols], 1]).any():
                    out.append(f"system {s}: no second-frequency carrier in the {who}")
    return out


def _result(
    rover: ReceiverSignals,
    common: list[str],
    ir: IntArray,
    age_s: FloatArray,
    out: _FilterOut,
    slips_r: Slips,
    slips_b: Slips,
    base: ReceiverSignals,
    warnings: list[str],
    dist: float,
) -> RtkResult:
    n_e, n_s = rover.t_gps_s.size, len(common)
    spp_ok = np.all(np.isfinite(rover.spp_pos_m), axis=1)
    status = np.where(spp_ok, RtkStatus.NO_BASE, RtkStatus.NO_SOLUTION).astype(np.int8)
    status[ir] = out.status
    pos = np.where(spp_ok[:, None], rover.spp_pos_m, np.nan)
    pos[ir] = np.where(np.isfinite(out.pos), out.pos, pos[ir])
    float_pos = np.full((n_e, 3), np.nan)
    float_pos[ir] = out.float_pos
    llh = ecef_to_geodetic(np.where(np.isfinite(pos), pos, 6.4e6))
    rot = enu_rotation(llh[:, 0], llh[:, 1])
    cov = np.full((n_e, 3, 3), np.nan)
    cov[ir] = out.cov
    sd = np.sqrt(np.abs(np.einsum("eij,ejk,eik->ei", rot, cov, rot)))
    ratio = np.full(n_e, np.nan)
    ratio[ir] = out.ratio
    n_sats = np.zeros(n_e, dtype=np.int64)
    n_sats[ir] = out.n_sats
    n_fixed = np.zeros(n_e, dtype=np.int64)
    n_fixed[ir] = out.n_fixed
    slip_mask = np.zeros((n_e, n_s), dtype=bool)
    slip_mask[ir] = out.slip
    age = np.full(n_e, np.nan)
    age[ir] = age_s
    rejected = np.zeros(n_e, dtype=np.int8)
    rejected[ir] = out.rejected
    counts = {k: v + slips_b.counts()[k] for k, v in slips_r.counts().items()}
    counts["ambiguity_resets"] = int(out.slip.sum())
    return RtkResult(
        t_gps_s=rover.t_gps_s.copy(),
        sats=tuple(common),
        pos_m=pos,
        float_pos_m=float_pos,
        sd_enu_m=sd,
        status=status,
        ratio=ratio,
        n_sats=n_sats,
        n_fixed=n_fixed,
        slips=counts,
        slip_mask=slip_mask,
        age_s=age,
        fix_rejected=rejected,
        n_rover_epochs=n_e,
        n_base_epochs=base.t_gps_s.size,
        n_common_epochs=ir.size,
        warnings=tuple(warnings),
        base_spp_distance_m=dist,
    )


def solution_frame(result: RtkResult) -> dict[str, np.ndarray]:
    """The solution as a solution frame (:func:`navtrack.io.solution.write_solution`): the
    SPP columns ``t_gps_s``, ``x_m``, ``y_m``, ``z_m``, ``sd_e_m``, ``sd_n_m``, ``sd_u_m``,
    ``n_sats``, ``status`` (name), ``excluded`` (empty), then ``quality`` (RTKLIB Q),
    ``ratio``, ``n_fixed`` and ``age_s`` (age of the base observations)."""
    names = np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)]
    return {
        "t_gps_s": result.t_gps_s,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "sd_e_m": result.sd_enu_m[:, 0],
        "sd_n_m": result.sd_enu_m[:, 1],
        "sd_u_m": result.sd_enu_m[:, 2],
        "n_sats": result.n_sats,
        "status": names,
        "excluded": np.full(result.t_gps_s.size, "", dtype=object),
        "quality": result.quality,
        "ratio": result.ratio,
        "n_fixed": result.n_fixed,
        "age_s": result.age_s,
    }
