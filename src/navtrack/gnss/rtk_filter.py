"""Stage 4 of carrier-phase relative positioning (:func:`navtrack.gnss.relative.solve_relative`):
the double-differenced measurements of every common epoch, the Kalman filter over them, integer
fixing with its validation, and the joining of forward and backward filters.

References
----------
Teunissen, P.J.G., Montenbruck, O. (eds.) (2017). Springer Handbook of GNSS, ch. 26 (RTK),
eq. 26.11-26.14 (double differences), 23.4 (ambiguity resolution).
Takasu, T. (2013). RTKLIB ver. 2.4.2 Manual, appendix E.7 (relative positioning: state,
measurement model, variances).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import chdtri

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.estimation.covariance import restart_states
from navtrack.estimation.kalman import gain_update, innovation_gain
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation
from navtrack.gnss.ambiguity import (
    FixStatus,
    bootstrap_success_rate,
    condition_on_fix,
    decorrelate,
    resolve_ambiguities,
)
from navtrack.gnss.corrections import geometric_range, saastamoinen_delay_m
from navtrack.gnss.rtk_config import SYSTEMS, FixRejection, RtkConfig, RtkStatus
from navtrack.gnss.rtk_signals import ReceiverSignals, Slips

if TYPE_CHECKING:
    from navtrack.gnss.spp import ProgressFn

__all__ = [
    "Baseline",
    "EpochInputs",
    "FilterOutput",
    "combine_directions",
    "dd_matrix",
    "double_differences",
    "epoch_inputs",
    "reverse_epochs",
    "reverse_output",
    "run_filter",
    "satellite_geometry",
]


def satellite_geometry(
    sat_pos: FloatArray, rcv: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Range (with Sagnac term), line of sight and elevation (rad) of ``(..., S, 3)`` satellites
    seen from ``(..., 3)`` receivers (ECEF, m)."""
    rho, los = geometric_range(sat_pos, rcv[..., None, :])
    llh = ecef_to_geodetic(rcv.reshape(-1, 3)).reshape(rcv.shape)
    rot = enu_rotation(llh[..., 0], llh[..., 1])
    up = np.einsum("...j,...sj->...s", rot[..., 2, :], los)
    return rho, los, np.arcsin(np.clip(up, -1.0, 1.0))


def _variance(el: FloatArray, cfg: RtkConfig) -> FloatArray:
    """Undifferenced phase variance (m^2), RTKLIB 2.4.2 manual eq. E.6.24 without the SNR term."""
    a, b = cfg.sigma_phase_m
    return a * a + b * b / np.maximum(np.sin(el), 0.05) ** 2


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
    llh = ecef_to_geodetic(rcv.reshape(-1, 3)).reshape(rcv.shape)
    return np.asarray(saastamoinen_delay_m(llh[..., 0:1], llh[..., 2:3], el))


def double_differences(
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


def dd_matrix(ref: IntArray, oth: IntArray, n: int) -> FloatArray:
    """The ``(D, n)`` matrix that forms the double differences ``(ref, oth)`` of
    :func:`double_differences` from ``n`` single differences (+1 other, -1 reference)."""
    D = np.zeros((ref.size, n))
    rows = np.arange(ref.size)
    D[rows, oth] = 1.0
    D[rows, ref] = -1.0
    return D


@dataclass(frozen=True, slots=True, eq=False)
class Baseline:
    """A rover paired with a base: their signals, common epochs and common satellites.

    Attributes
    ----------
    rover, base : ReceiverSignals
    base_xyz_m : ndarray, shape (3,)
        Base antenna position (ECEF, m).
    rover_idx, base_idx : ndarray of int, shape (K,)
        The common epochs (:func:`~navtrack.gnss.rtk_signals.common_epochs`).
    age_s : ndarray, shape (K,)
        Rover minus base time of each common epoch (s).
    rover_cols, base_cols : ndarray of int, shape (S,)
        Columns of the common satellites in the rover's and the base's signals.
    slips_rover, slips_base : Slips
    """

    rover: ReceiverSignals
    base: ReceiverSignals
    base_xyz_m: FloatArray
    rover_idx: IntArray
    base_idx: IntArray
    age_s: FloatArray
    rover_cols: IntArray
    base_cols: IntArray
    slips_rover: Slips
    slips_base: Slips

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def sats(self) -> tuple[str, ...]:
        """The common satellites."""
        return tuple(self.rover.sats[j] for j in self.rover_cols)


@dataclass(frozen=True, slots=True, eq=False)
class EpochInputs:
    """Inputs of the filter over the K common epochs, ``(K, S, F)`` flattened to ``N = S F``
    single-differenced ambiguities.

    Attributes
    ----------
    t : (K,) rover time tags (s)
    age : (K,) age of the base observations (s)
    sd_phase, sd_code : (K, N) single differences minus the computed ranges at ``x_lin`` and
        at the base (m)
    x_lin : (K, 3) linearisation point of the rover (its SPP, forward filled)
    G : (K, N, 3) d(range)/d(rover position) at ``x_lin``, 0 where not observed
    el : (K, N) rover elevation (rad)
    var_sd : (K, N) single-difference phase variance (m^2)
    reset : (K, N) slip: restart the ambiguity
    half : (K, N) half-cycle unresolved: not fixed
    spp : (K, 3) rover SPP
    lam : (N,) wavelength (m; 0 where the satellite's system has no such band)
    groups : (N,) system x frequency group of each ambiguity
    integer : (N,) ambiguity whose double differences are integers (not GLONASS)
    n_f : frequencies per satellite
    """

    t: FloatArray
    age: FloatArray
    sd_phase: FloatArray
    sd_code: FloatArray
    x_lin: FloatArray
    G: FloatArray
    el: FloatArray
    var_sd: FloatArray
    reset: BoolArray
    half: BoolArray
    spp: FloatArray
    lam: FloatArray
    groups: IntArray
    integer: BoolArray
    n_f: int


def epoch_inputs(pair: Baseline, cfg: RtkConfig) -> EpochInputs:
    """Single differences, geometry and variances of every common epoch, all at once."""
    rover, base, ir, ib = pair.rover, pair.base, pair.rover_idx, pair.base_idx
    js_r, js_b = pair.rover_cols, pair.base_cols
    n_f = cfg.frequencies
    base_xyz = np.broadcast_to(pair.base_xyz_m, (ib.size, 3))
    rho_b, _, el_b = satellite_geometry(base.sat_pos_m[ib][:, js_b], base_xyz)
    corr_b = (rho_b + _troposphere(base_xyz, el_b))[..., None]
    spp = rover.spp_pos_m[ir]
    x_lin = _forward_fill(spp)
    rho_r, los_r, el_r = satellite_geometry(rover.sat_pos_m[ir][:, js_r], x_lin)
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
    reset = pair.slips_rover.any[ir][:, js_r] | (
        pair.slips_base.any[ib][:, js_b] & new_base[:, None, None]
    )
    half = pair.slips_rover.half_cycle[ir][:, js_r] | pair.slips_base.half_cycle[ib][:, js_b]
    letters = [rover.sats[j][0] for j in js_r]
    sys_id = np.array([SYSTEMS.index(s) for s in letters], dtype=np.int64)
    groups = (sys_id[:, None] * 4 + np.arange(n_f)[None, :]).reshape(-1)
    # an aged base observation's error (satellite clocks, orbits, ionosphere at the base) is
    # the same for every rover epoch that uses it: its variance counts once per base epoch
    _, first, n_share = np.unique(ib, return_inverse=True, return_counts=True)
    drift = (C_MPS * cfg.clock_stability * pair.age_s) ** 2 * n_share[first]
    var_sd = _variance(el_b, cfg) + _variance(el_r, cfg) + drift[:, None]
    G = -los_r + dtrop_dh[..., None] * up[:, None, :]
    return EpochInputs(
        t=rover.t_gps_s[ir],
        age=pair.age_s,
        sd_phase=ph.reshape(k, -1),
        sd_code=co.reshape(k, -1),
        x_lin=x_lin,
        G=np.repeat(np.where(np.isfinite(G), G, 0.0), n_f, axis=1),
        el=np.repeat(el_r, n_f, axis=1),
        var_sd=np.broadcast_to(var_sd[..., None], (k, n_s, n_f)).reshape(k, -1),
        reset=reset.reshape(k, -1),
        half=half.reshape(k, -1),
        spp=spp,
        # 0 where the band is not observed (its ambiguity never enters a double difference)
        lam=np.nan_to_num(rover.wavelength_m[js_r].reshape(-1), nan=0.0),
        groups=groups,
        integer=np.repeat(np.array([s != "R" for s in letters], dtype=bool), n_f),
        n_f=n_f,
    )


class FilterOutput:
    """Per-epoch outputs of :func:`run_filter`, filled row by row."""

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
        self.rejected = np.zeros(k, dtype=np.int8)  # FixRejection of a float epoch


@dataclass(slots=True)
class _DoubleDifferences:
    """The double-differenced measurements of one epoch about the predicted state."""

    Dp: FloatArray  # (P, N) phase DDs of the single differences
    ref_p: IntArray
    oth_p: IntArray
    H: FloatArray  # (P + C, 3 + N)
    y: FloatArray  # innovations, phase then code
    R: FloatArray  # their covariance
    phase_ok: BoolArray  # (N,)
    n_sats: int


class _Filter:
    """The state (rover position, single-differenced ambiguities in cycles) and its steps."""

    def __init__(self, ep: EpochInputs, cfg: RtkConfig) -> None:
        self.ep, self.cfg = ep, cfg
        k_n, self.n_amb = ep.sd_phase.shape
        self.out = FilterOutput(k_n, self.n_amb // ep.n_f)
        self.x = np.zeros(3 + self.n_amb)
        self.P = np.zeros((3 + self.n_amb, 3 + self.n_amb))
        self.active = np.zeros(self.n_amb, dtype=bool)
        self.last_seen = np.full(self.n_amb, -(10**9), dtype=np.int64)  # epoch index
        self.have_pos = False
        self.t_prev: float | None = None
        self.rep = np.repeat(np.arange(self.n_amb // ep.n_f), ep.n_f)  # satellite of each
        self.el_mask = math.radians(cfg.elmask_deg)
        self.el_mask_ar = math.radians(max(cfg.elmask_deg, cfg.elmask_ar_deg))

    def predict(self, k: int) -> bool:
        """Position (kinematic: restarted at the SPP) and ambiguity random walk; False when
        the epoch has no position to start from."""
        ep, cfg, x, P = self.ep, self.cfg, self.x, self.P
        t = float(ep.t[k])
        dt = 0.0 if self.t_prev is None else abs(t - self.t_prev)  # backward: time runs back
        self.t_prev = t
        if cfg.mode == "kinematic" or not self.have_pos:
            spp = ep.spp[k]
            x0 = spp if np.all(np.isfinite(spp)) else (x[:3] if self.have_pos else None)
            if x0 is None or not np.all(np.isfinite(ep.x_lin[k])):
                return False
            x[:3] = x0
            restart_states(P, np.arange(3), cfg.sigma_pos0_m**2)
            self.have_pos = True
        amb = np.arange(self.n_amb) + 3
        P[amb[self.active], amb[self.active]] += cfg.q_amb_cyc**2 * dt
        return True

    def measurements(self, k: int) -> _DoubleDifferences | None:
        """Restart slipped, unseen or new ambiguities and form the double differences; None
        (status ``single``) with fewer than ``min_sats`` satellites."""
        ep, cfg, x, P = self.ep, self.cfg, self.x, self.P
        shift = ep.G[k] @ (x[:3] - ep.x_lin[k])  # residuals are linear in the offset
        code_res = ep.sd_code[k] - shift
        phase_res = ep.sd_phase[k] - shift
        up = ep.el[k] >= self.el_mask
        code_ok = np.isfinite(code_res) & up
        phase_ok = np.isfinite(phase_res) & up
        gap = k - self.last_seen > cfg.max_outage + 1
        restart = phase_ok & (~self.active | ep.reset[k] | gap)
        n_s = self.out.slip.shape[1]
        weights = phase_ok & ep.reset[k]
        self.out.slip[k] = np.bincount(self.rep, weights=weights, minlength=n_s) > 0
        if restart.any():
            ri = np.flatnonzero(restart) + 3
            restart_states(P, ri, (cfg.sigma_amb0_m / ep.lam[restart]) ** 2)
            x[ri] = (ep.sd_phase[k, restart] - ep.sd_code[k, restart]) / ep.lam[restart]
        self.active |= restart
        self.last_seen[phase_ok] = k
        ref_p, oth_p = double_differences(ep.groups, phase_ok, ep.el[k])
        ref_c, oth_c = double_differences(ep.groups, code_ok, ep.el[k])
        in_dd = np.zeros(self.n_amb, dtype=bool)
        in_dd[np.concatenate([ref_c, oth_c])] = True
        n_sat_dd = int(np.unique(self.rep[in_dd]).size)
        self.out.n_sats[k] = n_sat_dd
        if ref_c.size == 0 or n_sat_dd < cfg.min_sats:
            return None
        # zeros where a satellite is not differenced (0 * NaN would spoil the products)
        var_sd = np.where(code_ok, ep.var_sd[k], 0.0)
        Dp = dd_matrix(ref_p, oth_p, self.n_amb)
        Dc = dd_matrix(ref_c, oth_c, self.n_amb)
        n_p = ref_p.size
        H = np.zeros((n_p + ref_c.size, x.size))
        H[:n_p, :3] = Dp @ ep.G[k]
        H[:n_p, 3:] = Dp * ep.lam[None, :]
        H[n_p:, :3] = Dc @ ep.G[k]
        y = np.concatenate(
            [
                Dp @ np.where(phase_ok, phase_res, 0.0) - H[:n_p, 3:] @ x[3:],
                Dc @ np.where(code_ok, code_res, 0.0),
            ]
        )
        R = np.zeros((y.size, y.size))
        R[:n_p, :n_p] = (Dp * var_sd) @ Dp.T
        R[n_p:, n_p:] = (Dc * (var_sd * cfg.code_phase_ratio**2)) @ Dc.T
        return _DoubleDifferences(Dp, ref_p, oth_p, H, y, R, phase_ok, n_sat_dd)

    def update(self, k: int, dd: _DoubleDifferences) -> None:
        """Kalman update with the double differences; the float solution of the epoch."""
        S, K = innovation_gain(self.P, dd.H, dd.R)
        self.x, self.P = gain_update(self.x, self.P, dd.y, K, S)
        out = self.out
        out.float_pos[k] = out.pos[k] = self.x[:3]
        out.float_cov[k] = out.cov[k] = self.P[:3, :3]
        out.status[k] = RtkStatus.FLOAT if dd.ref_p.size else RtkStatus.DGNSS

    def fix(self, k: int, dd: _DoubleDifferences) -> None:
        """Integer fixing of the phase DDs, validated; the fix replaces the float solution of
        the epoch, the reason is recorded when there is none."""
        ep, cfg, x, P, out = self.ep, self.cfg, self.x, self.P, self.out
        if ep.age[k] > cfg.max_age_ar_s:
            out.rejected[k] = FixRejection.BASE_AGE
            return
        fixable = (
            ~ep.half[k, dd.oth_p]
            & ~ep.half[k, dd.ref_p]
            & ep.integer[dd.oth_p]
            & (ep.el[k, dd.oth_p] >= self.el_mask_ar)
            & (ep.el[k, dd.ref_p] >= self.el_mask_ar)
        )
        sats = np.unique(self.rep[np.concatenate([dd.oth_p[fixable], dd.ref_p[fixable]])])
        if fixable.sum() < cfg.ambiguity.min_fixed or sats.size < cfg.min_fix_sats:
            out.rejected[k] = FixRejection.TOO_FEW_SATELLITES
            return
        A = np.zeros((int(fixable.sum()), x.size))
        A[:, 3:] = dd.Dp[fixable]
        Q = A @ P @ A.T
        fix = resolve_ambiguities(A @ x, Q, cfg.ambiguity)
        out.ratio[k] = fix.ratio
        if not fix.accepted:
            out.rejected[k] = FixRejection.RATIO_TEST
            return
        if (
            fix.status == FixStatus.FIXED
            and cfg.min_success_rate > 0.0
            and bootstrap_success_rate(decorrelate(Q)[2]) < cfg.min_success_rate
        ):
            out.rejected[k] = FixRejection.SUCCESS_RATE
            return
        xf, Pf = condition_on_fix(x, P, A, fix)
        reason = self._validate(k, dd, xf)
        if reason != FixRejection.NONE:
            out.rejected[k] = reason
            return
        out.pos[k] = xf[:3]
        out.cov[k] = Pf[:3, :3]
        out.status[k] = RtkStatus.FIX
        out.n_fixed[k] = fix.n_fixed
        if cfg.hold:
            T = fix.Z.astype(float) @ A
            R = np.eye(T.shape[0]) * cfg.hold_var_cyc2
            S, K = innovation_gain(self.P, T, R)
            self.x, self.P = gain_update(self.x, self.P, fix.z - T @ self.x, K, S)

    def _validate(self, k: int, dd: _DoubleDifferences, xf: FloatArray) -> FixRejection:
        """Beyond the ratio test: the fixed state must close the phase DDs and, with
        ``float_position_test``, stay within the float position's uncertainty (chi-square tests
        at ``fix_test_p``)."""
        ep, cfg = self.ep, self.cfg
        n_p = dd.ref_p.size
        v = dd.Dp @ np.where(dd.phase_ok, ep.sd_phase[k] - ep.G[k] @ (xf[:3] - ep.x_lin[k]), 0.0)
        v -= (dd.Dp * ep.lam[None, :]) @ xf[3:]
        chi2_v = float(v @ np.linalg.solve(dd.R[:n_p, :n_p], v))
        if chi2_v > float(chdtri(n_p, cfg.fix_test_p)):
            return FixRejection.RESIDUALS
        if not cfg.float_position_test:
            return FixRejection.NONE
        d = xf[:3] - self.x[:3]
        if float(d @ np.linalg.solve(self.P[:3, :3], d)) > float(chdtri(3, cfg.fix_test_p)):
            return FixRejection.FLOAT_POSITION
        return FixRejection.NONE


def run_filter(ep: EpochInputs, cfg: RtkConfig, progress: ProgressFn | None = None) -> FilterOutput:
    """The Kalman filter over the common epochs: predict, restart slipped ambiguities, update
    with double differences, fix by LAMBDA and validate the fix."""
    flt = _Filter(ep, cfg)
    k_n = ep.t.size
    for k in range(k_n):
        if progress is not None and k % 100 == 0:
            progress(k, k_n)
        if not flt.predict(k):
            continue
        dd = flt.measurements(k)
        if dd is None:
            if np.all(np.isfinite(ep.spp[k])):
                flt.out.pos[k] = ep.spp[k]
                flt.out.status[k] = RtkStatus.SINGLE
            else:
                flt.out.n_sats[k] = 0
            continue
        flt.update(k, dd)
        if cfg.fix and dd.ref_p.size:
            flt.fix(k, dd)
    return flt.out


def reverse_epochs(ep: EpochInputs) -> EpochInputs:
    """The epochs in backward order: a slip flagged at epoch ``e`` (between ``e-1`` and ``e``)
    restarts the ambiguity when the backward filter moves on to ``e-1``."""
    reset = np.zeros_like(ep.reset)
    reset[:-1] = ep.reset[1:]
    fields = {
        name: getattr(ep, name)[::-1].copy()
        for name in ("t", "age", "sd_phase", "sd_code", "x_lin", "G", "el", "var_sd", "half", "spp")
    }
    return EpochInputs(
        **fields,
        reset=reset[::-1].copy(),
        lam=ep.lam,
        groups=ep.groups,
        integer=ep.integer,
        n_f=ep.n_f,
    )


def reverse_output(out: FilterOutput) -> FilterOutput:
    """The outputs of a backward filter in forward epoch order."""
    rev = FilterOutput(out.status.size, out.slip.shape[1])
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


def combine_directions(fwd: FilterOutput, bwd: FilterOutput) -> FilterOutput:
    """Forward and backward solutions joined epoch by epoch (RTKLIB ``postpos`` ``combres``
    rules: better status wins, equal statuses averaged, disagreeing fixes fall back to float).

    Notes
    -----
    Both filters use the epoch's own measurements, so the average counts them twice (as the
    two-filter combination of RTKLIB does); the formal covariance is slightly optimistic.
    """
    out = FilterOutput(fwd.status.size, fwd.slip.shape[1])
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
