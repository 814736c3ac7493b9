"""The position-dependent pseudorange model of single point positioning (the kernel of
:func:`navtrack.gnss.spp.estimate.estimate_position`, RTKLIB ``rescode``) and the measurement
variance models (``varerr``)."""

from __future__ import annotations

import math

import numpy as np

from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import ecef_to_geodetic, enu_rotation
from navtrack.gnss.corrections import geometric_range, klobuchar_delay_m, saastamoinen_delay_m
from navtrack.gnss.spp.config import (
    CODE_PHASE_RATIO,
    ERR_BRDCI,
    ERR_CODE_M,
    ERR_ION_M,
    ERR_SAAS_M,
    ERR_TROP_M,
    IONOFREE_NOISE_FACTOR,
    SIGMA_EPSILON_C_M2HZ,
    SppConfig,
)
from navtrack.gnss.spp.measurements import Measurements

__all__ = ["Geometry", "PseudorangeModel", "measurement_variance", "reference_group"]


class Geometry(Record):
    """Receiver-satellite geometry of a batch ``(b, S)`` at the receiver positions ``(b, 3)``."""

    rho: FloatArray  # (b, S) geometric range with Sagnac term, m
    los: FloatArray  # (b, S, 3) unit line of sight, ECEF
    llh: FloatArray  # (b, 3) receiver latitude, longitude (rad), height (m)
    rot: FloatArray  # (b, 3, 3) ECEF -> ENU
    los_enu: FloatArray  # (b, S, 3) unit line of sight, east / north / up
    el: FloatArray  # (b, S) rad; 90 deg for receivers inside the earth
    deep: BoolArray  # (b,) receiver inside the earth (start at the centre)

    def azimuth(self, cells: BoolArray | None = None) -> FloatArray:
        """Azimuth (rad) of every satellite, or of the selected ``cells`` only (1-D)."""
        east, north = self.los_enu[..., 0], self.los_enu[..., 1]
        if cells is not None:
            east, north = east[cells], north[cells]
        return np.mod(np.arctan2(east, north), 2.0 * np.pi)


class PseudorangeModel(Record):
    """The per-epoch pseudorange model of a batch of epochs (the SPP kernel, RTKLIB ``rescode``):
    batch row ``b`` is measurement epoch ``epochs[b]``, candidates ``usable[b]``."""

    meas: Measurements
    config: SppConfig
    usable: BoolArray  # (B, S)
    epochs: IntArray  # (B,)

    def geometry(self, x: FloatArray, b: IntArray) -> Geometry:
        rcv = x[:, :3]
        rs = self.meas.sat_pos_m[self.epochs[b]]
        rho, los = geometric_range(rs, rcv[:, None, :])
        llh = ecef_to_geodetic(rcv)
        rot = enu_rotation(llh[:, 0], llh[:, 1])  # (b, 3, 3)
        # rot @ los per satellite; the transposed rotations copied first (a contiguous operand
        # makes the batched product several times faster, the same numbers)
        enu = los @ np.ascontiguousarray(np.swapaxes(rot, -1, -2))
        el = np.arcsin(np.clip(enu[..., 2], -1.0, 1.0))
        # inside the earth (start from the centre): no mask, no atmosphere (el = 90 deg)
        deep = np.linalg.norm(rcv, axis=1) < 1e6
        el = np.where(deep[:, None], np.pi / 2.0, el)
        return Geometry(rho, los, llh, rot, enu, el, deep)

    def __call__(
        self, x: FloatArray, b: IntArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        cfg, m = self.config, self.meas
        e = self.epochs[b]
        g = self.geometry(x, b)
        el, llh, deep = g.el, g.llh, g.deep
        valid = self.usable[b] & (el >= math.radians(cfg.elmask_deg))
        lat = llh[:, 0:1]
        lon = llh[:, 1:2]
        h = llh[:, 2:3]
        # the atmosphere on the cells that count only (invalid cells get no weight), 0 elsewhere
        atm = valid & ~deep[:, None]
        if cfg.iono == "klobuchar":
            iono_l1 = np.zeros_like(el)
            iono_l1[atm] = klobuchar_delay_m(
                _cells(m.t_gps_s[e, None], atm),
                _cells(lat, atm),
                _cells(lon, atm),
                g.azimuth(atm),
                el[atm],
                m.klobuchar,
            )
            iono = iono_l1 * m.iono_scale[e]
            var_iono = (ERR_BRDCI * iono_l1) ** 2
        elif cfg.iono == "ionofree":
            iono = np.zeros_like(el)
            var_iono = np.zeros_like(el)
        else:
            iono = np.zeros_like(el)
            var_iono = np.full_like(el, ERR_ION_M**2)
        if cfg.tropo == "saastamoinen":
            trop = np.zeros_like(el)
            trop[atm] = saastamoinen_delay_m(_cells(lat, atm), _cells(h, atm), el[atm])
            var_trop = (ERR_SAAS_M / (np.sin(el) + 0.1)) ** 2
        else:
            trop = np.zeros_like(el)
            var_trop = np.full_like(el, ERR_TROP_M**2)
        n_groups = len(m.clock_groups)
        clk = x[:, 3 : 3 + n_groups]
        clock = clk[:, 0:1] + np.where(m.group > 0, clk[:, np.maximum(m.group, 0)], 0.0)
        v = m.y_m[e] - (g.rho + clock + iono + trop)
        J = np.zeros((b.size, m.group.size, 3 + n_groups))
        J[..., :3] = -g.los
        J[..., 3] = 1.0
        for k in range(1, n_groups):
            J[..., 3 + k] = (m.group == k).astype(float)
        var = measurement_variance(
            el, m.var_sat_m2[e], m.var_factor, var_iono, var_trop, m.cn0_dbhz[e], cfg, m.ionofree
        )
        valid &= np.isfinite(v) & np.isfinite(var) & (var > 0)
        w = np.where(valid, 1.0 / np.where(valid, var, 1.0), 0.0)
        J[~valid] = 0.0
        # An epoch without a satellite of the first clock group: the clock column carries the
        # first group that has one, whose bias column would repeat it (a singular system)
        ref = reference_group(valid, m.group, n_groups)
        rows = np.flatnonzero(ref > 0)
        J[rows, :, 3 + ref[rows]] = 0.0
        return np.where(valid, v, 0.0), J, w, valid


def reference_group(used: BoolArray, group: IntArray, n_groups: int) -> IntArray:
    """Clock group of each epoch's receiver clock: the first group with a used satellite
    (0 where the epoch has none at all). Its inter-system bias is not estimated."""
    seen = np.stack([(used & (group == k)).any(axis=1) for k in range(n_groups)], axis=1)
    return np.argmax(seen, axis=1)


def _cells(per_epoch: FloatArray, cells: BoolArray) -> FloatArray:
    """A per-epoch column ``(B, 1)`` at the selected cells of a ``(B, S)`` grid."""
    return np.broadcast_to(per_epoch, cells.shape)[cells]


def measurement_variance(
    el_rad: FloatArray,
    var_sat_m2: FloatArray,
    var_factor: FloatArray,
    var_iono_m2: FloatArray,
    var_trop_m2: FloatArray,
    cn0_dbhz: FloatArray,
    config: SppConfig,
    ionofree: bool = False,
) -> FloatArray:
    """Pseudorange error variance (m^2) of the configured weighting model
    (:attr:`SppConfig.weighting`).

    Parameters
    ----------
    el_rad : ndarray, shape (B, S)
        Elevation (rad).
    var_sat_m2 : ndarray, shape (B, S)
        Satellite-side variance (URA^2 + code bias), ``rtklib`` only.
    var_factor : ndarray, shape (S,)
        System factor squared, ``rtklib`` only.
    var_iono_m2, var_trop_m2 : ndarray, shape (B, S)
        Variances of the ionosphere and troposphere corrections, ``rtklib`` only.
    cn0_dbhz : ndarray, shape (B, S)
        C/N0, ``cn0`` only (NaN: the ``elevation`` model).
    config : SppConfig
    ionofree : bool
        The ionosphere-free combination (``rtklib``: receiver term times 3^2).

    Returns
    -------
    ndarray, shape (B, S)

    References
    ----------
    RTKLIB 2.4.3 ``pntpos.c`` ``varerr`` and ``rescode``; Hartinger & Brunner 1999 (SIGMA-epsilon).
    """
    sin_el = np.sin(el_rad)
    if config.weighting == "rtklib":
        base = CODE_PHASE_RATIO**2 * (ERR_CODE_M**2 + ERR_CODE_M**2 / sin_el)
        if ionofree:
            base = base * IONOFREE_NOISE_FACTOR**2
        return var_factor * base + var_sat_m2 + var_iono_m2 + var_trop_m2
    if config.weighting == "elevation":
        return config.sigma0_m**2 * (1.0 + 1.0 / sin_el**2)
    if config.weighting == "cn0":
        return np.where(
            np.isfinite(cn0_dbhz),
            config.sigma0_m**2 + SIGMA_EPSILON_C_M2HZ * 10.0 ** (-np.nan_to_num(cn0_dbhz) / 10.0),
            config.sigma0_m**2 * (1.0 + 1.0 / sin_el**2),
        )
    return np.full_like(el_rad, config.sigma0_m**2)
