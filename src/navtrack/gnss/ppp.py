"""Static precise point positioning (PPP): dual-frequency ionosphere-free code and carrier phase
with precise orbits and clocks, float ambiguities per satellite arc.

Model per satellite ``s`` and epoch (undifferenced, ionosphere-free combinations, m)::

    P_IF = rho + c dt_r + T_h m_h + ZWD m_w + e_P
    L_IF = rho + c dt_r + T_h m_h + ZWD m_w + N_s + e_L

with ``rho`` the geometric range to the SP3 satellite position at transmission (Sagnac
included), ``dt_r`` one receiver clock per system (white noise, re-estimated every epoch),
``T_h`` the Saastamoinen dry slant delay as the a priori, ``ZWD`` the zenith wet delay, a
random walk whose mapping ``m_w`` is the ratio of the Saastamoinen wet slant to zenith delay,
and ``N_s`` a float ambiguity (m) per satellite arc, restarted by every cycle slip
(:func:`navtrack.gnss.relative.detect_slips`). The position is static (no process noise): the
Kalman filter is the recursive least-squares solution of all epochs so far, and its position
at each epoch is the convergence series.

The station is corrected for the solid Earth tide (IERS 2010 step 1,
:mod:`navtrack.gnss.tides`), the phase for the carrier wind-up (:mod:`navtrack.gnss.windup`),
the antennas for their phase centres when an ANTEX file is given. Not applied: satellite antenna
nadir variations, ocean-loading and pole tides, differential code biases between
the tracked code (``C1C``) and the code of the SP3 clocks (``C1W``). The errors they leave are
part of the model instead, so that the formal covariance describes the error of the position
(``docs/ppp.md``): code errors correlated over :data:`CODE_CORRELATION_S`, phase noise over
:data:`PHASE_CORRELATION_S`, a range error common to code and phase per satellite
(:data:`SIGMA_MODEL_M`, a first-order Gauss-Markov state correlated over
:data:`MODEL_CORRELATION_S`), and the error of the linearly interpolated satellite clocks,
measured on the clock product itself (:func:`navtrack.gnss.precise.clock_interpolation_error`).

References
----------
Zumberge, J.F. et al. (1997). Precise point positioning for the efficient and robust analysis
of GPS data from large networks. JGR 102(B3), 5005-5017.
Kouba, J., Heroux, P. (2001). Precise point positioning using IGS orbit and clock products.
GPS Solutions 5(2), 12-28 (eq. 1-2, ionosphere-free observation equations).
Takasu, T. (2013). RTKLIB ver. 2.4.2 Manual, appendix E.8 (PPP: states, process noises).
Gelb, A. (ed.) (1974). Applied Optimal Estimation, MIT Press, chapter 4 (correlated
measurement errors as first-order Markov states of the filter).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import FloatArray, IntArray
from navtrack.estimation.covariance import restart_states
from navtrack.estimation.kalman import gain_update, innovation_gain
from navtrack.geodesy import C_MPS, ecef_to_enu, ecef_to_geodetic, enu_rotation
from navtrack.gnss.antex import AntennaPattern, Antex, receiver_range_m, satellite_offset_m
from navtrack.gnss.corrections import geometric_range, ionofree, saastamoinen_delay_m
from navtrack.gnss.observations import ObsHeader
from navtrack.gnss.precise import ClockInterpolationError, clock_interpolation_error
from navtrack.gnss.relative import (
    ReceiverSignals,
    RtkConfig,
    Slips,
    detect_slips,
    receiver_signals,
)
from navtrack.gnss.tides import solid_tide_m, sun_moon_ecef_m
from navtrack.gnss.windup import phase_windup_cyc

if TYPE_CHECKING:
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = [
    "CODE_CORRELATION_S",
    "MODEL_CORRELATION_S",
    "PHASE_CORRELATION_S",
    "PppConfig",
    "PppResult",
    "antenna_range_m",
    "convergence",
    "solution_frame",
    "solve_ppp",
]


CODE_CORRELATION_S = 600.0
"""Correlation time of the code errors (s): the code variance is multiplied by
``max(1, tau / interval)``, so that code epochs closer than ``tau`` count as one (multipath is
correlated over minutes, not seconds). How it was chosen: ``docs/ppp.md``, method notes."""

PHASE_CORRELATION_S = 30.0
"""Correlation time of the phase errors left by the model (s), applied as
:data:`CODE_CORRELATION_S` to the phase variance (``docs/ppp.md``, method notes)."""

SIGMA_MODEL_M = 0.015
"""Standard deviation (m, at zenith; divided by ``sin(el)``) of the range error the model
leaves in code and phase alike: orbit, satellite and receiver antenna variations, wind-up,
tides and troposphere mapping (``docs/ppp.md``, method notes: chosen on four 3-hour NIST
sessions, judged on four others, ARL1, SEPT and TLSE)."""


MODEL_CORRELATION_S = 1800.0
"""Correlation time (s) of the range error :data:`SIGMA_MODEL_M`: orbit, antenna and
troposphere mapping errors change with the geometry, over many minutes (chosen with
:data:`SIGMA_MODEL_M`, ``docs/ppp.md``, method notes)."""


@dataclass(frozen=True, slots=True)
class PppConfig:
    """Options of :func:`solve_ppp`; variances and noises after RTKLIB 2.4.3's PPP defaults.

    Attributes
    ----------
    systems : str
        Systems (each with its own receiver clock).
    elmask_deg : float
        Elevation mask (deg).
    sigma_phase_m : tuple of float
        ``(a, b)`` of the undifferenced phase variance ``a^2 + b^2 / sin^2(el)``, times 3^2 for
        the ionosphere-free combination (RTKLIB ``err``, ``EFACT``).
    code_phase_ratio : float
        Code to phase standard deviation ratio (RTKLIB ``eratio`` 100).
    code_correlation_s, phase_correlation_s : float
        Correlation times of the code and phase errors (:data:`CODE_CORRELATION_S`,
        :data:`PHASE_CORRELATION_S`); 0 treats every epoch as independent.
    sigma_model_m : float
        Range error left by the model (:data:`SIGMA_MODEL_M`, at zenith, divided by
        ``sin(el)``), common to code and phase.
    model_correlation_s : float
        Its correlation time (:data:`MODEL_CORRELATION_S`): a first-order Gauss-Markov state per
        satellite; 0 adds it to the code and phase variances instead (every epoch independent
        after the phase's correlation factor).
    sigma_zwd0_m : float
        Start standard deviation of the zenith wet delay (RTKLIB: 0.3 m).
    q_zwd_m : float
        Random walk of the zenith wet delay (m / sqrt(s); RTKLIB ``prn[2]`` 1e-4).
    sigma_amb0_m : float
        Standard deviation of a (re-)started ambiguity (m).
    sigma_pos0_m : float
        Standard deviation of the start position (the median single point solution).
    solid_tide : bool
        Correct the station for the solid Earth tide (:func:`navtrack.gnss.tides.solid_tide_m`,
        IERS 2010 step 1); off leaves up to ~0.4 m of twice-daily motion in the position.
    clock_interpolation : bool
        Add the error of the linearly interpolated satellite clocks to the code and phase
        variances, measured on the clock source (:func:`navtrack.gnss.precise.
        clock_interpolation_error`) and correlated over its sample interval; off treats the
        interpolated clocks as exact (the 5- or 15-minute SP3 clocks then make the formal
        bound too tight).
    phase_windup : bool
        Remove the carrier phase wind-up from the phase (:func:`navtrack.gnss.windup.
        phase_windup_cyc`, satellites in nominal yaw attitude, receiver antenna pointed north).
    min_sats : int
        Fewest satellites with both code and phase for an update.
    max_outage : int
        Epochs a satellite may be missing before its ambiguity restarts.
    """

    systems: str = "G"
    elmask_deg: float = 15.0
    sigma_phase_m: tuple[float, float] = (0.003, 0.003)
    code_phase_ratio: float = 100.0
    code_correlation_s: float = CODE_CORRELATION_S
    phase_correlation_s: float = PHASE_CORRELATION_S
    sigma_model_m: float = SIGMA_MODEL_M
    model_correlation_s: float = MODEL_CORRELATION_S
    sigma_zwd0_m: float = 0.3
    q_zwd_m: float = 1e-4
    sigma_amb0_m: float = 30.0
    sigma_pos0_m: float = 100.0
    solid_tide: bool = True
    clock_interpolation: bool = True
    phase_windup: bool = True
    min_sats: int = 5
    max_outage: int = 5

    def __post_init__(self) -> None:
        if not self.systems or any(s not in "GECJ" for s in self.systems):
            raise ValueError(f"systems: expected letters of GECJ, got {self.systems!r}")
        if self.min_sats < 4:
            raise ValueError(f"min_sats: expected >= 4, got {self.min_sats}")
        values = (
            self.code_correlation_s,
            self.phase_correlation_s,
            self.sigma_model_m,
            self.model_correlation_s,
        )
        if min(values) < 0:
            raise ValueError(
                "code_correlation_s, phase_correlation_s, sigma_model_m, model_correlation_s: "
                "expected >= 0"
            )


@dataclass(frozen=True, slots=True, eq=False)
class PppResult:
    """Static PPP solution after each epoch.

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
    pos_m : ndarray, shape (E, 3)
        Position estimate using the epochs up to this one (ECEF, m; NaN before the first
        update).
    sd_enu_m : ndarray, shape (E, 3)
        Its formal standard deviation, east/north/up (m).
    cov_enu_m2 : ndarray, shape (E, 3, 3)
        Its formal covariance in east/north/up (m^2).
    zwd_m : ndarray, shape (E,)
        Zenith wet delay (m).
    n_sats : ndarray of int, shape (E,)
        Satellites in the update.
    updated : ndarray of bool, shape (E,)
        The epoch had enough satellites for an update.
    slips : mapping of str to int
        Slips per detector.
    warnings : tuple of str
        Corrections left out (an antenna missing from the ANTEX file).
    """

    t_gps_s: FloatArray
    pos_m: FloatArray
    sd_enu_m: FloatArray
    cov_enu_m2: FloatArray
    zwd_m: FloatArray
    n_sats: IntArray
    updated: np.ndarray
    slips: dict[str, int]
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def quality(self) -> IntArray:
        """RTKLIB solution quality: 6 (PPP) where updated, 0 elsewhere."""
        return np.where(self.updated, 6, 0).astype(np.int64)

    def inside_bound(self, ref_xyz_m: FloatArray, probability: float = 0.95) -> np.ndarray:
        """Whether the error against a reference lies inside the formal ``probability``
        ellipsoid of each updated epoch (``e^T C^-1 e <= chi2_3(probability)``; False where
        not updated)."""
        from scipy.stats import chi2  # scipy.stats costs a noticeable import: only when asked

        enu = ecef_to_enu(self.pos_m, np.asarray(ref_xyz_m, dtype=float))
        out = np.zeros(self.t_gps_s.size, dtype=bool)
        k = np.flatnonzero(self.updated)
        q = np.einsum("ei,eij,ej->e", enu[k], np.linalg.inv(self.cov_enu_m2[k]), enu[k])
        out[k] = q <= chi2.ppf(probability, 3)
        return out


def _wet_mapping(lat: FloatArray, h: FloatArray, el: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Dry slant delay (m) and wet mapping function (Saastamoinen wet slant / wet zenith)."""
    dry = np.asarray(saastamoinen_delay_m(lat, h, el, humidity=0.0))
    wet = np.asarray(saastamoinen_delay_m(lat, h, el, humidity=0.7)) - dry
    dry_z = np.asarray(saastamoinen_delay_m(lat, h, np.full_like(el, np.pi / 2), humidity=0.0))
    wet_z = np.asarray(saastamoinen_delay_m(lat, h, np.full_like(el, np.pi / 2))) - dry_z
    return dry, wet / wet_z


@dataclass(frozen=True, slots=True, eq=False)
class _Problem:
    """Ionosphere-free observables reduced by the a priori model, per epoch and satellite.

    ``y_code``/``y_phase`` are the IF code and phase minus the range to the linearisation point
    ``x_lin`` and the dry delay; ``G`` the design rows of the position, ``m_w`` the wet
    mapping, ``var_*`` the measurement variances (m^2), ``sys_col`` each satellite's clock
    (-1: system not solved), ``reset`` a slip restarting the ambiguity.
    """

    t_gps_s: FloatArray
    x_lin: FloatArray
    y_code: FloatArray
    y_phase: FloatArray
    G: FloatArray
    m_w: FloatArray
    el: FloatArray
    var_code: FloatArray
    var_phase: FloatArray
    var_model: FloatArray
    sys_col: IntArray
    n_clk: int
    reset: np.ndarray


def _range_elevation(sat_pos: FloatArray, rcv: FloatArray) -> tuple[FloatArray, ...]:
    """Range (Sagnac included), line of sight and elevation of ``(E, S, 3)`` satellites from
    one receiver position."""
    rho, los = geometric_range(sat_pos, rcv)
    llh = ecef_to_geodetic(rcv)
    up = np.einsum("j,esj->es", enu_rotation(llh[0], llh[1])[2], los)
    return rho, los, np.arcsin(np.clip(up, -1.0, 1.0))


def _correlation_factor(t_gps_s: FloatArray, tau_s: float) -> float:
    """Variance factor ``max(1, tau / interval)`` for errors correlated over ``tau_s``."""
    steps = np.diff(t_gps_s)
    interval = float(np.median(steps)) if steps.size else 1.0
    return max(1.0, tau_s / interval) if interval > 0 else 1.0


def _clock_variance(clock_error: ClockInterpolationError, t_gps_s: FloatArray) -> FloatArray:
    """Per-epoch variance ``(1, S)`` (m^2) of the interpolated satellite clocks: the variance
    between samples, counted once per sample interval (the error is one value of a random walk
    bridged between two samples, the same for all epochs in between). A satellite whose clock
    source gives no measure takes the largest of the others."""
    var = clock_error.var_m2
    if not np.isfinite(var).any():
        return np.zeros((1, var.size))
    var = np.where(np.isfinite(var), var, np.nanmax(var))
    return var[None, :] * _correlation_factor(t_gps_s, clock_error.interval_s)


_BAND_CODES = ((1575.42e6, "01"), (1227.60e6, "02"), (1176.45e6, "05"), (1207.14e6, "07"))
"""Carrier frequencies (Hz) and their ANTEX frequency numbers (L1/E1, L2, L5/E5a, E5b)."""


def _antenna_codes(sat: str, f_hz: FloatArray, patterns: dict[str, AntennaPattern]) -> list[str]:
    """ANTEX frequency codes of a satellite's two carriers; the GPS code of the same band when
    the antenna has none of that system (the usual case for receiver antennas)."""
    codes = []
    for f in f_hz:
        band = next((c for freq, c in _BAND_CODES if abs(freq - f) < 1e5), "")
        code = sat[0] + band
        codes.append(code if code in patterns else "G" + band)
    return codes


def antenna_range_m(
    sig: ReceiverSignals,
    header: ObsHeader,
    antex: Antex | None,
    los_m: FloatArray,
    sun_m: FloatArray,
) -> tuple[FloatArray, list[str]]:
    """Ionosphere-free range corrections (m, ``(E, S)``) of the antennas, and warnings.

    Always the antenna reference point's eccentricity (``ANTENNA: DELTA H/E/N``); with an ANTEX
    file the receiver antenna's offsets and zenith variations and the satellites' offsets (nominal
    attitude), each combined like the observations. A missing antenna is a warning and its
    correction is left out.
    """
    f = C_MPS / sig.wavelength_m  # (S, 2)
    w1 = f[:, 0] ** 2 / (f[:, 0] ** 2 - f[:, 1] ** 2)
    w2 = 1.0 - w1
    llh = ecef_to_geodetic(np.nanmedian(sig.spp_pos_m, axis=0))
    rot = enu_rotation(llh[0], llh[1])
    los_enu = np.einsum("ij,esj->esi", rot, np.nan_to_num(los_m))
    h, e, n = header.antenna_delta_hen_m if header.antenna_delta_hen_m is not None else (0, 0, 0)
    out = -(los_enu[..., 0] * e + los_enu[..., 1] * n + los_enu[..., 2] * h)
    if antex is None:
        return out, []
    warnings: list[str] = []
    try:
        rcv, note = antex.receiver(header.antenna)
        warnings += [note] if note else []
    except KeyError as exc:
        rcv, warnings = {}, [f"{exc.args[0]}: receiver phase centre not corrected"]
    t_mid = float(np.median(sig.t_gps_s))
    missing = []
    for s, sat in enumerate(sig.sats):
        if rcv:
            c1, c2 = _antenna_codes(sat, f[s], rcv)
            if c1 in rcv and c2 in rcv:
                d1 = receiver_range_m(rcv[c1], los_enu[:, s])
                out[:, s] += w1[s] * d1 + w2[s] * receiver_range_m(rcv[c2], los_enu[:, s])
        pats = antex.satellite(sat, t_mid)
        codes = _antenna_codes(sat, f[s], pats) if pats else []
        if not pats or not all(c in pats for c in codes):
            missing.append(sat)
            continue
        body = w1[s] * pats[codes[0]].offset_m + w2[s] * pats[codes[1]].offset_m
        off = satellite_offset_m(body, sig.sat_pos_m[:, s], sun_m)
        out[:, s] += np.einsum("ej,ej->e", np.nan_to_num(los_m[:, s]), off)
    if missing:
        warnings.append(
            f"no antenna valid at the observations in {antex.path} for {', '.join(missing)}: "
            "their satellite phase centres not corrected"
        )
    return out, warnings


def _problem(
    sig: ReceiverSignals,
    slips: Slips,
    cfg: PppConfig,
    antenna: tuple[ObsHeader, Antex | None],
    clock_error: ClockInterpolationError,
) -> tuple[_Problem, list[str]]:
    """The reduced observables of :class:`_Problem` from a receiver's signals, and the
    warnings of the antenna corrections."""
    f = C_MPS / sig.wavelength_m  # (S, 2)
    code = ionofree(sig.code_m[..., 0], sig.code_m[..., 1], f[:, 0], f[:, 1])
    phase = ionofree(sig.phase_m[..., 0], sig.phase_m[..., 1], f[:, 0], f[:, 1])
    phase = np.where(np.isfinite(code), phase, np.nan)
    ok_spp = np.all(np.isfinite(sig.spp_pos_m), axis=1)
    # geometry at a fixed linearisation point (the median SPP): the state is linear in the
    # offset from it to well below a millimetre for offsets of metres
    x_lin = np.nanmedian(sig.spp_pos_m[ok_spp], axis=0)
    rho, los, el = _range_elevation(sig.sat_pos_m, x_lin)
    G = np.where(np.isfinite(los), -los, 0.0)
    sun, moon = sun_moon_ecef_m(sig.t_gps_s)
    if cfg.solid_tide:  # the station moves by d(t): the range changes by G d(t)
        rho = rho + np.einsum("esj,ej->es", G, solid_tide_m(x_lin, sun, moon))
    d_ant, warnings = antenna_range_m(sig, antenna[0], antenna[1], los, sun)
    rho = rho + d_ant
    if cfg.phase_windup:  # the same cycles on both carriers: c / (f1 + f2) metres per cycle
        phase = phase - C_MPS / f.sum(axis=1) * phase_windup_cyc(sig.sat_pos_m, x_lin, sun)
    warnings += [
        f"{name} switched off (PppConfig.{flag}=False): left in the position"
        for name, flag, on in (
            ("solid Earth tide", "solid_tide", cfg.solid_tide),
            ("carrier phase wind-up", "phase_windup", cfg.phase_windup),
            ("satellite clock interpolation error", "clock_interpolation", cfg.clock_interpolation),
        )
        if not on
    ]
    llh = ecef_to_geodetic(x_lin)
    dry, m_w = _wet_mapping(np.full_like(el, llh[0]), np.full_like(el, llh[2]), el)
    a, b = cfg.sigma_phase_m
    sin_el2 = np.maximum(np.sin(el), 0.05) ** 2
    var_phase = 9.0 * (a * a + b * b / sin_el2)
    var_model = cfg.sigma_model_m**2 / sin_el2
    white_model = var_model if cfg.model_correlation_s == 0 else 0.0
    var_clock = _clock_variance(clock_error, sig.t_gps_s) if cfg.clock_interpolation else 0.0
    systems = [s for s in cfg.systems if any(x[0] == s for x in sig.sats)]
    sys_col = np.array([systems.index(x[0]) if x[0] in systems else -1 for x in sig.sats])
    prob = _Problem(
        t_gps_s=sig.t_gps_s,
        x_lin=x_lin,
        y_code=code - rho - dry,
        y_phase=phase - rho - dry,
        G=G,
        m_w=m_w,
        el=el,
        var_code=(var_phase * cfg.code_phase_ratio**2 + white_model)
        * _correlation_factor(sig.t_gps_s, cfg.code_correlation_s)
        + var_clock,
        var_phase=(var_phase + white_model)
        * _correlation_factor(sig.t_gps_s, cfg.phase_correlation_s)
        + var_clock,
        var_model=var_model,
        sys_col=sys_col.astype(np.int64),
        n_clk=len(systems),
        reset=np.asarray(slips.any.any(axis=2)),
    )
    return prob, warnings


def solve_ppp(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None,
    sp3: Sp3,
    config: PppConfig | None = None,
    antex: Antex | None = None,
) -> PppResult:
    """Static PPP of every epoch of a dual-frequency observation file.

    Parameters
    ----------
    obs : Observations
        Dual-frequency observations of a static receiver.
    nav : NavData or sequence of NavData, optional
        Broadcast data (GLONASS channels, Klobuchar for the start position only).
    sp3 : Sp3
        Precise orbits and clocks (clocks interpolated from the SP3 epochs, or from the RINEX
        clock file attached with :meth:`Sp3.with_clock`).
    config : PppConfig, optional
    antex : Antex, optional
        Antenna phase centres (:func:`navtrack.gnss.antex.read_antex`) for the receiver antenna
        named in the observation header and the satellites (:func:`antenna_range_m`).

    Returns
    -------
    PppResult

    Raises
    ------
    ValueError
        No epoch with a single point solution, or no second-frequency carrier.
    """
    cfg = config or PppConfig()
    rcfg = RtkConfig(systems=cfg.systems, frequencies=2, elmask_deg=cfg.elmask_deg)
    sig = receiver_signals(obs, nav, rcfg, sp3=sp3)
    if not np.isfinite(sig.phase_cyc[..., 1]).any():
        raise ValueError(f"obs: {obs.path!r} has no second-frequency carrier phase for PPP")
    if not np.all(np.isfinite(sig.spp_pos_m), axis=1).any():
        raise ValueError(f"obs: {obs.path!r}: no epoch has a single point solution")
    slips = detect_slips(sig, rcfg)
    clock_error = clock_interpolation_error(sp3, sig.sats)
    prob, warnings = _problem(sig, slips, cfg, (obs.header, antex), clock_error)
    pos, cov, zwd, n_used, updated = _run_filter(prob, cfg)
    llh = ecef_to_geodetic(prob.x_lin)
    rot = enu_rotation(llh[0], llh[1])
    cov_enu = np.einsum("ij,ejk,lk->eil", rot, cov, rot)
    sd = np.sqrt(np.abs(np.einsum("eii->ei", cov_enu)))
    return PppResult(
        t_gps_s=sig.t_gps_s.copy(),
        pos_m=pos,
        sd_enu_m=sd,
        cov_enu_m2=cov_enu,
        zwd_m=zwd,
        n_sats=n_used,
        updated=updated,
        slips=slips.counts(),
        warnings=tuple(warnings),
    )


def _run_filter(
    prob: _Problem, cfg: PppConfig
) -> tuple[FloatArray, FloatArray, FloatArray, IntArray, np.ndarray]:
    """The Kalman filter over all epochs: position, its covariance (ECEF), ZWD, satellites
    used and whether each epoch was updated.

    States: position, one clock per system, ZWD, one ambiguity per satellite and, with
    ``model_correlation_s > 0``, one range error per satellite (first-order Gauss-Markov)."""
    n_e, n_s = prob.y_code.shape
    i_zwd, i_amb = 3 + prob.n_clk, 4 + prob.n_clk
    n_rng = n_s if cfg.model_correlation_s > 0 else 0
    x = np.zeros(i_amb + n_s + n_rng)
    x[:3] = prob.x_lin
    x[i_zwd] = 0.1
    P = np.zeros((x.size, x.size))
    P[:3, :3] = np.eye(3) * cfg.sigma_pos0_m**2
    P[i_zwd, i_zwd] = cfg.sigma_zwd0_m**2
    active = np.zeros(n_s, dtype=bool)
    last = np.full(n_s, -(10**9), dtype=np.int64)
    pos = np.full((n_e, 3), np.nan)
    cov = np.full((n_e, 3, 3), np.nan)
    zwd = np.full(n_e, np.nan)
    n_used = np.zeros(n_e, dtype=np.int64)
    mask = math.radians(cfg.elmask_deg)
    t_prev = None
    for k in range(n_e):
        ok = np.isfinite(prob.y_phase[k]) & (prob.el[k] >= mask) & (prob.sys_col >= 0)
        if ok.sum() < cfg.min_sats:
            continue
        t = prob.t_gps_s[k]
        dt = 0.0 if t_prev is None else t - t_prev
        P[i_zwd, i_zwd] += cfg.q_zwd_m**2 * dt
        t_prev = t
        restart = ok & (~active | prob.reset[k] | (k - last > cfg.max_outage + 1))
        if n_rng:
            _propagate_range_errors(prob, cfg, k, dt, restart, x, P)
        active |= restart
        last[ok] = k
        x, P = _update(prob, cfg, k, ok, restart, x, P)
        pos[k], cov[k], zwd[k], n_used[k] = x[:3], P[:3, :3], x[i_zwd], ok.sum()
    return pos, cov, zwd, n_used, n_used > 0


def _propagate_range_errors(
    prob: _Problem,
    cfg: PppConfig,
    k: int,
    dt: float,
    restart: np.ndarray,
    x: FloatArray,
    P: FloatArray,
) -> None:
    """Predict the per-satellite range errors over ``dt`` (first-order Gauss-Markov with the
    variance of the current elevation) in place; a restarted arc starts its error afresh."""
    n_s = prob.sys_col.size
    rng = np.arange(n_s) + 4 + prob.n_clk + n_s
    var = np.nan_to_num(prob.var_model[k], nan=0.0)
    phi = math.exp(-dt / cfg.model_correlation_s)
    x[rng] *= phi
    P[rng, :] *= phi
    P[:, rng] *= phi
    P[rng, rng] += var * (1.0 - phi * phi)
    if restart.any():
        restart_states(P, rng[restart], var[restart])
        x[rng[restart]] = 0.0


def _update(
    prob: _Problem,
    cfg: PppConfig,
    k: int,
    ok: np.ndarray,
    restart: np.ndarray,
    x: FloatArray,
    P: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """One epoch: clocks restarted from the code, new ambiguities started from phase minus
    code, then the Kalman update with the phase and code of the satellites ``ok``."""
    i_clk, i_zwd, i_amb = 3, 3 + prob.n_clk, 4 + prob.n_clk
    amb = np.arange(prob.sys_col.size) + i_amb
    sys_col = prob.sys_col
    # model at the prior: geometry offset, troposphere, then clocks from the code
    geo = prob.G[k] @ (x[:3] - prob.x_lin) + prob.m_w[k] * x[i_zwd]
    for c in range(prob.n_clk):  # white clock: restarted at the median code residual
        sel = ok & (sys_col == c)
        x[i_clk + c] = float(np.median((prob.y_code[k] - geo)[sel])) if sel.any() else 0.0
        restart_states(P, i_clk + c, 100.0**2)
    clk = np.where(sys_col >= 0, x[i_clk + np.maximum(sys_col, 0)], 0.0)
    if restart.any():
        restart_states(P, amb[restart], cfg.sigma_amb0_m**2)
        x[amb[restart]] = (prob.y_phase[k] - prob.y_code[k])[restart]
    idx = np.flatnonzero(ok)
    m = idx.size
    H = np.zeros((2 * m, x.size))
    for rows in (slice(0, m), slice(m, 2 * m)):
        H[rows, :3] = prob.G[k, idx]
        H[rows, i_clk + sys_col[idx]] = 1.0
        H[rows, i_zwd] = prob.m_w[k, idx]
    H[np.arange(m), amb[idx]] = 1.0
    pred = geo[idx] + clk[idx]
    if x.size > amb[-1] + 1:  # the range error of each satellite, in its code and phase
        rng = amb[idx] + prob.sys_col.size
        H[np.arange(m), rng] = 1.0
        H[np.arange(m, 2 * m), rng] = 1.0
        pred = pred + x[rng]
    y = np.concatenate([prob.y_phase[k, idx] - pred - x[amb[idx]], prob.y_code[k, idx] - pred])
    R = np.diag(np.concatenate([prob.var_phase[k, idx], prob.var_code[k, idx]]))
    S, K = innovation_gain(P, H, R)
    return gain_update(x, P, y, K, S)


def convergence(
    result: PppResult,
    ref_xyz_m: FloatArray,
    after_s: Sequence[float] = (60, 300, 600, 900, 1800, 3600),
) -> list[tuple[float, float, float, float]]:
    """Error of the static solution against a reference after given times from the first
    epoch: rows ``(t_s, horizontal_m, up_m, 3d_m)`` for each time the data reach (the last
    updated epoch at or before it)."""
    t0 = result.t_gps_s[0]
    enu = ecef_to_enu(result.pos_m, np.asarray(ref_xyz_m, dtype=float))
    rows = []
    for t in after_s:
        sel = np.flatnonzero(result.updated & (result.t_gps_s - t0 <= t + 1e-6))
        if not sel.size or result.t_gps_s[-1] - t0 < t - 1.0:
            continue
        e = enu[sel[-1]]
        rows.append((float(t), float(np.hypot(e[0], e[1])), float(e[2]), float(np.linalg.norm(e))))
    return rows


def solution_frame(result: PppResult) -> dict[str, np.ndarray]:
    """Solution frame for :func:`navtrack.io.solution.write_solution`: ``t_gps_s``, ``x_m``,
    ``y_m``, ``z_m``, ``sd_e_m``, ``sd_n_m``, ``sd_u_m``, ``n_sats``, ``status`` (``ppp`` or
    ``no_solution``), ``excluded``, ``quality`` (6), ``zwd_m``."""
    return {
        "t_gps_s": result.t_gps_s,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "sd_e_m": result.sd_enu_m[:, 0],
        "sd_n_m": result.sd_enu_m[:, 1],
        "sd_u_m": result.sd_enu_m[:, 2],
        "n_sats": result.n_sats,
        "status": np.where(result.updated, "ppp", "no_solution").astype(object),
        "excluded": np.full(result.t_gps_s.size, "", dtype=object),
        "quality": result.quality,
        "zwd_m": result.zwd_m,
    }
