"""Satellite position, velocity and clock from precise products: SP3 orbits, with the satellite
clocks of the SP3 file or of a RINEX clock file attached to it (:meth:`Sp3.with_clock`).

Positions: Lagrange polynomial of degree ``order`` per ECEF axis through the ``order + 1`` SP3
nodes around ``t``, each node first rotated about z by ``Omega_e (t_node - t)`` so that the
interpolation runs in the (quasi-)inertial frame of time ``t`` (Schenewerk 2003). Clocks: linear
between the two bracketing epochs of the clock source -- the SP3 epochs (5 or 15 min) or the
RINEX clock epochs (30 s or 5 s), which follow the clock's short-term wander much more closely.

References
----------
M. Schenewerk, "A brief review of basic GPS orbit interpolation strategies", GPS Solutions 6,
2003 (SP3 interpolation in an inertial frame by rotating the nodes for earth rotation).
IS-GPS-200N 20.3.3.3.3.1 (relativistic clock correction, here in vector form ``-2 r.v / c^2``).
Kouba, J., "A guide to using International GNSS Service (IGS) products", 2015, section 4.2
(linear interpolation of 30 s satellite clocks).
Allan, D.W. (1987). Time and frequency (time-domain) characterization, estimation, and
prediction of precision clocks and oscillators. IEEE Trans. UFFC 34(6), 647-654 (the second
difference of clock samples as the measure of their wander between samples).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from navtrack._typing import FloatArray
from navtrack.geodesy import C_MPS, OMEGA_E_RAD_S
from navtrack.gnss.ephemeris import SatStates
from navtrack.gnss.rinex_clock import interpolate_clock
from navtrack.gnss.sp3 import Sp3

__all__ = [
    "ClockInterpolationError",
    "clock_interpolation_error",
    "lagrange_weights",
    "sp3_clock",
    "sp3_states",
]


def lagrange_weights(t_nodes: FloatArray, t: FloatArray) -> FloatArray:
    """Lagrange basis polynomials at ``t (N,)`` for nodes ``(N, n)``, returned ``(N, n)``."""
    n = t_nodes.shape[-1]
    d = t[:, None] - t_nodes  # (N, n)
    w = np.ones_like(t_nodes)
    for k in range(n):
        for m in range(n):
            if m != k:
                w[:, k] *= d[:, m] / (t_nodes[:, k] - t_nodes[:, m])
    return w


def sp3_clock(sp3: Sp3, sat: str, t_gps_s: FloatArray, max_gap_s: float = 900.0) -> FloatArray:
    """Satellite clock offset (s, without the relativistic correction) at ``t_gps_s``.

    From the RINEX clock file attached to ``sp3`` when there is one (linear between its
    records, :func:`navtrack.gnss.rinex_clock.interpolate_clock`), else linear between the two
    SP3 epochs bracketing ``t`` (both present, the nearer at most ``max_gap_s`` away). NaN where
    the source has no value.
    """
    ts = np.asarray(t_gps_s, dtype=float)
    if sp3.clock is not None:
        return interpolate_clock(sp3.clock, sat, ts)
    if sat not in sp3.sats:
        return np.full(ts.shape, np.nan)
    j = sp3.sats.index(sat)
    tn = np.asarray(sp3.t_gps_s, dtype=float)
    i1 = np.clip(np.searchsorted(tn, ts), 1, tn.size - 1)
    t0, t1 = tn[i1 - 1], tn[i1]
    c0, c1 = sp3.clock_s[i1 - 1, j], sp3.clock_s[i1, j]
    dts = c0 + (c1 - c0) * (ts - t0) / (t1 - t0)
    near = np.minimum(np.abs(ts - t0), np.abs(ts - t1)) <= max_gap_s
    return np.where(near, dts, np.nan)


@dataclass(frozen=True, slots=True)
class ClockInterpolationError:
    """Size of the error of linearly interpolated satellite clocks, from the clock samples.

    Attributes
    ----------
    var_m2 : ndarray, shape (S,)
        Variance (m^2) of the interpolation error between two samples of each satellite's clock
        (NaN: fewer than three samples in a row).
    interval_s : float
        Sample interval of the clock source (s): the time over which that error is correlated.
    """

    var_m2: FloatArray
    interval_s: float


def clock_interpolation_error(sp3: Sp3, sats: Sequence[str]) -> ClockInterpolationError:
    """Variance of the error that linear interpolation leaves between clock samples, measured
    on the clock source itself (the attached RINEX clock file, else the SP3 clocks).

    Each interior sample ``c_k`` is predicted from its two neighbours one interval ``h`` away;
    the misfit ``r_k = c_k - (c_{k-1} + c_{k+1}) / 2`` is the interpolation error at the middle of
    a ``2h`` span. For a clock whose phase wanders as a random walk (white frequency noise, the
    short-term behaviour of the GNSS rubidium and hydrogen-maser clocks) the error in the middle
    of an ``h`` span has half that variance: ``var = mean(r^2) / 2`` per satellite, used for every
    epoch between samples (``docs/ppp.md``, method notes: this form was chosen on WUM's 5-minute
    clocks against its 30 s clocks of 2023-01-01).
    """
    src = sp3.clock
    t_nodes = np.asarray(src.t_gps_s if src is not None else sp3.t_gps_s, dtype=float)
    names = src.sats if src is not None else sp3.sats
    values = src.clock_s if src is not None else sp3.clock_s
    steps = np.diff(t_nodes)
    h = float(np.median(steps)) if steps.size else float("nan")
    var = np.full(len(sats), np.nan)
    # second differences only across two steps of the nominal interval
    regular = (np.abs(steps[:-1] - h) < 1e-3) & (np.abs(steps[1:] - h) < 1e-3)
    for i, sat in enumerate(sats):
        if sat not in names:
            continue
        c = values[:, names.index(sat)] * C_MPS
        r = (c[1:-1] - 0.5 * (c[:-2] + c[2:]))[regular]
        r = r[np.isfinite(r)]
        if r.size:
            var[i] = 0.5 * float(np.mean(r * r))
    return ClockInterpolationError(var_m2=var, interval_s=h)


def _orbit(sp3: Sp3, j: int, t: FloatArray, n_nodes: int, max_gap_s: float) -> FloatArray:
    """ECEF position ``(N, 3)`` of SP3 column ``j`` at ``t (N,)`` (frame of time ``t``)."""
    tn = np.asarray(sp3.t_gps_s, dtype=float)
    i0 = np.clip(np.searchsorted(tn, t) - (n_nodes + 1) // 2, 0, tn.size - n_nodes)
    ii = i0[:, None] + np.arange(n_nodes)  # (N, n)
    tt = tn[ii]
    pp = sp3.pos_m[ii, j]  # (N, n, 3)
    ang = OMEGA_E_RAD_S * (tt - t[:, None])
    c, s = np.cos(ang), np.sin(ang)
    x = c * pp[..., 0] - s * pp[..., 1]
    y = s * pp[..., 0] + c * pp[..., 1]
    w = lagrange_weights(tt - t[:, None], np.zeros_like(t))
    out = np.stack([(w * x).sum(-1), (w * y).sum(-1), (w * pp[..., 2]).sum(-1)], axis=-1)
    bad = ~np.isfinite(pp).all(axis=(1, 2))
    bad |= (t < tn[0] - max_gap_s) | (t > tn[-1] + max_gap_s)
    out[bad] = np.nan
    return out


def sp3_states(
    sp3: Sp3,
    sats: Sequence[str],
    t_tx_gps_s: FloatArray,
    *,
    order: int = 10,
    max_gap_s: float = 900.0,
) -> SatStates:
    """Satellite states from an SP3 precise orbit (and its clocks, or an attached RINEX clock
    file) by interpolation.

    Velocity is a central difference over +-0.5 s. The relativistic clock correction
    ``-2 r.v / c^2`` is added to ``clock_s``; ``var_m2`` is 0 (precise).

    Parameters
    ----------
    sp3 : Sp3
        ``t_gps_s (K,)``, ``sats``, ``pos_m (K, S', 3)``, ``clock_s (K, S')`` with NaN missing,
        and optionally ``clock`` (a RINEX clock file).
    sats : sequence of str, length S
    t_tx_gps_s : ndarray, shape (E, S)
        Transmission times by the satellite clock (the clock is removed here, one step).
    order : int
        Polynomial degree (10 as RTKLIB and the IGS practice for 15-min and 5-min orbits).
    max_gap_s : float
        ``t`` may lie at most this far outside the node span (extrapolation, as RTKLIB's 900 s)
        and an SP3 clock at most this far from its nearest epoch.

    Returns
    -------
    SatStates
        ``svh`` is 0 where valid.
    """
    t_sv = np.asarray(t_tx_gps_s, dtype=float)
    n_e, n_s = t_sv.shape
    n_nodes = min(order + 1, len(sp3.t_gps_s))
    pos = np.full((n_e, n_s, 3), np.nan)
    vel = np.full((n_e, n_s, 3), np.nan)
    clk = np.full((n_e, n_s), np.nan)
    for c_, sat in enumerate(sats):
        ok = np.isfinite(t_sv[:, c_])
        if sat not in sp3.sats or not ok.any():
            continue
        j = sp3.sats.index(sat)
        ts = t_sv[ok, c_]
        dts = sp3_clock(sp3, sat, ts, max_gap_s)
        t = ts - np.nan_to_num(dts)
        p0 = _orbit(sp3, j, t, n_nodes, max_gap_s)
        v = _orbit(sp3, j, t + 0.5, n_nodes, max_gap_s) - _orbit(
            sp3, j, t - 0.5, n_nodes, max_gap_s
        )
        pos[ok, c_] = p0
        vel[ok, c_] = v
        clk[ok, c_] = dts - 2.0 * np.einsum("ni,ni->n", p0, v) / C_MPS**2
    valid = np.isfinite(clk) & np.isfinite(pos).all(axis=-1)
    var = np.where(valid, 0.0, np.nan)
    svh = np.where(valid, 0, -1).astype(np.int64)
    index = np.where(valid, 0, -1).astype(np.int64)
    return SatStates(pos, vel, clk, var, svh, index, valid)
