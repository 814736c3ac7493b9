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

Not applied (the inputs give no ANTEX file, and RTKLIB 2.4.3's ``-p 7`` defaults leave them
off too): satellite and receiver antenna phase-centre offsets and variations, phase wind-up,
solid-earth, ocean-loading and pole tides (solid-earth tide: up to ~0.3 m vertical, nearly
constant over an hour; it stays in the estimated position), differential code biases between
the tracked code (``C1C``) and the code of the SP3 clocks (``C1W``).

References
----------
Zumberge, J.F. et al. (1997). Precise point positioning for the efficient and robust analysis
of GPS data from large networks. JGR 102(B3), 5005-5017.
Kouba, J., Heroux, P. (2001). Precise point positioning using IGS orbit and clock products.
GPS Solutions 5(2), 12-28 (eq. 1-2, ionosphere-free observation equations).
Takasu, T. (2013). RTKLIB ver. 2.4.2 Manual, appendix E.8 (PPP: states, process noises).
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
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation

if TYPE_CHECKING:
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = ["PppConfig", "PppResult", "convergence", "solution_frame", "solve_ppp"]


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
    sigma_zwd0_m : float
        Start standard deviation of the zenith wet delay (RTKLIB: 0.3 m).
    q_zwd_m : float
        Random walk of the zenith wet delay (m / sqrt(s); RTKLIB ``prn[2]`` 1e-4).
    sigma_amb0_m : float
        Standard deviation of a (re-)started ambiguity (m).
    sigma_pos0_m : float
        Standard deviation of the start position (the median single point solution).
    min_sats : int
        Fewest satellites with both code and phase for an update.
    max_outage : int
        Epochs a satellite may be missing before its ambiguity restarts.
    """

    systems: str = "G"
    elmask_deg: float = 15.0
    sigma_phase_m: tuple[float, float] = (0.003, 0.003)
    code_phase_ratio: float = 100.0
    sigma_zwd0_m: float = 0.3
    q_zwd_m: float = 1e-4
    sigma_amb0_m: float = 30.0
    sigma_pos0_m: float = 100.0
    min_sats: int = 5
    max_outage: int = 5

    def __post_init__(self) -> None:
        if not self.systems or any(s not in "GECJ" for s in self.systems):
            raise ValueError(f"systems: expected letters of GECJ, got {self.systems!r}")
        if self.min_sats < 4:
            raise ValueError(f"min_sats: expected >= 4, got {self.min_sats}")


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
    zwd_m : ndarray, shape (E,)
        Zenith wet delay (m).
    n_sats : ndarray of int, shape (E,)
        Satellites in the update.
    updated : ndarray of bool, shape (E,)
        The epoch had enough satellites for an update.
    slips : mapping of str to int
        Slips per detector.
    """

    t_gps_s: FloatArray
    pos_m: FloatArray
    sd_enu_m: FloatArray
    zwd_m: FloatArray
    n_sats: IntArray
    updated: np.ndarray
    slips: dict[str, int]

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def quality(self) -> IntArray:
        """RTKLIB solution quality: 6 (PPP) where updated, 0 elsewhere."""
        return np.where(self.updated, 6, 0).astype(np.int64)


def _wet_mapping(lat: FloatArray, h: FloatArray, el: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Dry slant delay (m) and wet mapping function (Saastamoinen wet slant / wet zenith)."""
    from navtrack.gnss.corrections import saastamoinen_delay_m

    dry = np.asarray(saastamoinen_delay_m(lat, h, el, humidity=0.0))
    wet = np.asarray(saastamoinen_delay_m(lat, h, el, humidity=0.7)) - dry
    dry_z = np.asarray(saastamoinen_delay_m(lat, h, np.full_like(el, np.pi / 2), humidity=0.0))
    wet_z = np.asarray(saastamoinen_delay_m(lat, h, np.full_like(el, np.pi / 2))) - dry_z
    return dry, wet / wet_z


def solve_ppp(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None,
    sp3: Sp3,
    config: PppConfig | None = None,
) -> PppResult:
    """Static PPP of every epoch of a dual-frequency observation file.

    Parameters
    ----------
    obs : Observations
        Dual-frequency observations of a static receiver.
    nav : NavData or sequence of NavData, optional
        Broadcast data (GLONASS channels, Klobuchar for the start position only).
    sp3 : Sp3
        Precise orbits and clocks (clocks interpolated from the SP3 epochs).
    config : PppConfig, optional

    Returns
    -------
    PppResult

    Raises
    ------
    ValueError
        No epoch with a single point solution, or no second-frequency carrier.
    """
    from navtrack.estimation.kalman import gain_update, innovation_gain
    from navtrack.gnss.corrections import ionofree
    from navtrack.gnss.relative import RtkConfig, detect_slips, receiver_signals

    cfg = config or PppConfig()
    rcfg = RtkConfig(systems=cfg.systems, frequencies=2, elmask_deg=cfg.elmask_deg)
    sig = receiver_signals(obs, nav, rcfg, sp3=sp3)
    if not np.isfinite(sig.phase_cyc[..., 1]).any():
        raise ValueError(f"obs: {obs.path!r} has no second-frequency carrier phase for PPP")
    ok_spp = np.all(np.isfinite(sig.spp_pos_m), axis=1)
    if not ok_spp.any():
        raise ValueError(f"obs: {obs.path!r}: no epoch has a single point solution")
    slips = detect_slips(sig, rcfg)
    f = C_MPS / sig.wavelength_m  # (S, 2)
    code = ionofree(sig.code_m[..., 0], sig.code_m[..., 1], f[:, 0], f[:, 1])
    phase = ionofree(sig.phase_m[..., 0], sig.phase_m[..., 1], f[:, 0], f[:, 1])
    phase = np.where(np.isfinite(code), phase, np.nan)
    reset: np.ndarray = np.asarray(slips.any.any(axis=2))
    # geometry at a fixed linearisation point (the median SPP): the state is linear in the
    # offset from it to well below a millimetre for offsets of metres
    from navtrack.gnss.relative import _elevation

    x_lin = np.nanmedian(sig.spp_pos_m[ok_spp], axis=0)
    n_e, n_s = code.shape
    rho, los, el = _elevation(sig.sat_pos_m, np.broadcast_to(x_lin, (n_e, 3)))
    llh = ecef_to_geodetic(x_lin)
    dry, m_w = _wet_mapping(np.full_like(el, llh[0]), np.full_like(el, llh[2]), el)
    y_code = code - rho - dry
    y_phase = phase - rho - dry
    G = np.where(np.isfinite(los), -los, 0.0)
    a, b = cfg.sigma_phase_m
    var_phase = 9.0 * (a * a + b * b / np.maximum(np.sin(el), 0.05) ** 2)
    systems = [s for s in cfg.systems if any(x[0] == s for x in sig.sats)]
    sys_col = np.array([systems.index(x[0]) if x[0] in systems else -1 for x in sig.sats])
    n_c = len(systems)
    i_clk, i_zwd, i_amb = 3, 3 + n_c, 4 + n_c
    n_x = i_amb + n_s
    x = np.zeros(n_x)
    x[:3] = x_lin
    P = np.zeros((n_x, n_x))
    P[:3, :3] = np.eye(3) * cfg.sigma_pos0_m**2
    P[i_zwd, i_zwd] = cfg.sigma_zwd0_m**2
    x[i_zwd] = 0.1
    active = np.zeros(n_s, dtype=bool)
    last = np.full(n_s, -(10**9), dtype=np.int64)
    pos = np.full((n_e, 3), np.nan)
    cov = np.full((n_e, 3, 3), np.nan)
    zwd = np.full(n_e, np.nan)
    n_used = np.zeros(n_e, dtype=np.int64)
    updated = np.zeros(n_e, dtype=bool)
    mask = math.radians(cfg.elmask_deg)
    amb = np.arange(n_s) + i_amb
    t_prev = None
    for k in range(n_e):
        t = sig.t_gps_s[k]
        dt = 0.0 if t_prev is None else t - t_prev
        ok = np.isfinite(y_phase[k]) & (el[k] >= mask) & (sys_col >= 0)
        if ok.sum() < cfg.min_sats:
            continue
        t_prev = t
        P[i_zwd, i_zwd] += cfg.q_zwd_m**2 * dt
        # model at the prior: geometry offset, troposphere, then clocks from the code
        geo = G[k] @ (x[:3] - x_lin) + m_w[k] * x[i_zwd]
        for c in range(n_c):  # white clock: restarted at the median code residual
            sel = ok & (sys_col == c)
            x[i_clk + c] = float(np.median((y_code[k] - geo)[sel])) if sel.any() else 0.0
            restart_states(P, i_clk + c, 100.0**2)
        clk = np.where(sys_col >= 0, x[i_clk + np.maximum(sys_col, 0)], 0.0)
        restart = ok & (~active | reset[k] | (k - last > cfg.max_outage + 1))
        if restart.any():
            ri = amb[restart]
            restart_states(P, ri, cfg.sigma_amb0_m**2)
            x[ri] = (y_phase[k] - y_code[k])[restart]
        active |= restart
        last[ok] = k
        idx = np.flatnonzero(ok)
        m = idx.size
        H = np.zeros((2 * m, n_x))
        for rows, with_amb in ((slice(0, m), True), (slice(m, 2 * m), False)):
            H[rows, :3] = G[k, idx]
            H[rows, i_clk + sys_col[idx]] = 1.0
            H[rows, i_zwd] = m_w[k, idx]
            if with_amb:
                H[np.arange(m), amb[idx]] = 1.0
        pred = geo[idx] + clk[idx]
        y = np.concatenate([y_phase[k, idx] - pred - x[amb[idx]], y_code[k, idx] - pred])
        R = np.diag(
            np.concatenate([var_phase[k, idx], var_phase[k, idx] * cfg.code_phase_ratio**2])
        )
        S, K = innovation_gain(P, H, R)
        x, P = gain_update(x, P, y, K, S)
        pos[k] = x[:3]
        cov[k] = P[:3, :3]
        zwd[k] = x[i_zwd]
        n_used[k] = m
        updated[k] = True
    rot = enu_rotation(llh[0], llh[1])
    sd = np.sqrt(np.abs(np.einsum("ij,ejk,ik->ei", rot, cov, rot)))
    return PppResult(
        t_gps_s=sig.t_gps_s.copy(),
        pos_m=pos,
        sd_enu_m=sd,
        zwd_m=zwd,
        n_sats=n_used,
        updated=updated,
        slips=slips.counts(),
    )


def convergence(
    result: PppResult,
    ref_xyz_m: FloatArray,
    after_s: Sequence[float] = (60, 300, 600, 900, 1800, 3600),
) -> list[tuple[float, float, float, float]]:
    """Error of the static solution against a reference after given times from the first
    epoch: rows ``(t_s, horizontal_m, up_m, 3d_m)`` for each time the data reach (the last
    updated epoch at or before it)."""
    from navtrack.geodesy import ecef_to_enu

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
