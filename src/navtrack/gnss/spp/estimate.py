"""Stages 4 and 5 of single point positioning: the weighted least-squares estimate of position
and clocks (RTKLIB ``estpos``) and its validity tests (``valsol``)."""

from __future__ import annotations

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.estimation.chi2 import chi2_quantile
from navtrack.estimation.least_squares import LsqStatus, gauss_newton
from navtrack.gnss.spp.config import SppConfig, SppStatus
from navtrack.gnss.spp.measurements import Measurements
from navtrack.gnss.spp.model import PseudorangeModel

__all__ = ["PositionEstimate", "dops", "estimate_position", "merge_estimates", "validate"]


class PositionEstimate(Record):
    """Weighted least-squares estimate of a batch of epochs with everything fault detection
    needs (RTKLIB ``estpos``).

    State per epoch: ``(x, y, z, clock, isb...)`` — ECEF position (m), receiver clock of the
    first clock group times c (m), one inter-system bias (m) per further clock group
    (``Measurements.clock_groups``); ``P = 3 + G``.

    Attributes
    ----------
    epochs : ndarray of int, shape (B,)
        Measurement epochs estimated (indices into ``Measurements.t_gps_s``).
    x : ndarray, shape (B, P)
        State at the last iterate (the start value where nothing could be solved).
    cov : ndarray, shape (B, P, P)
        Formal covariance ``(B^T W B)^-1`` (m^2), NaN where singular; zero rows/columns for
        clock groups without a used satellite.
    residuals_m : ndarray, shape (B, S)
        Observed minus computed pseudoranges at ``x`` (m), NaN where not used.
    design : ndarray, shape (B, S, P)
        Geometry (design) matrix ``B = dh/dx`` at ``x``: rows ``(-los, 1, isb indicators)``,
        zero where not used. A small state change ``dx`` changes the residuals by ``-B dx``.
    weights : ndarray, shape (B, S)
        ``1 / sigma^2`` (1/m^2) of :func:`measurement_variance` at ``x``, 0 where not used.
    used : ndarray of bool, shape (B, S)
        Satellites in the estimate (usable, above the elevation mask, not excluded).
    azel_rad : ndarray, shape (B, S, 2)
        Azimuth and elevation at ``x`` (rad).
    enu_rotation : ndarray, shape (B, 3, 3)
        ECEF to local east/north/up rotation at ``x``.
    dop : ndarray, shape (B, 4)
        GDOP, PDOP, HDOP, VDOP of the used satellites (:func:`dops`).
    chi2 : ndarray, shape (B,)
        Weighted sum of squared residuals ``v^T W v``.
    dof : ndarray of int, shape (B,)
        Redundancy: used satellites minus estimated parameters.
    iterations : ndarray of int, shape (B,)
        Gauss–Newton steps.
    status : ndarray of int8, shape (B,)
        :class:`SppStatus` of the estimation: ``ok``, ``no_ephemeris``, ``too_few_sats``,
        ``singular_geometry`` or ``no_convergence`` (the validity tests are
        :func:`validate`'s).
    """

    epochs: IntArray
    x: FloatArray
    cov: FloatArray
    residuals_m: FloatArray
    design: FloatArray
    weights: FloatArray
    used: BoolArray
    azel_rad: FloatArray
    enu_rotation: FloatArray
    dop: FloatArray
    chi2: FloatArray
    dof: IntArray
    iterations: IntArray
    status: Int8Array

    def __post_init__(self) -> None:
        freeze_arrays(self)


def estimate_position(
    meas: Measurements,
    config: SppConfig | None = None,
    *,
    epochs: IntArray | None = None,
    exclude: BoolArray | None = None,
    x0_m: FloatArray | None = None,
) -> PositionEstimate:
    """Iterated weighted least squares of position and clocks (stage 4 of :func:`solve_spp`).

    Elevation mask, ionosphere, troposphere and weights are re-evaluated at every iterate, as
    RTKLIB's ``rescode`` does; all epochs iterate in one batched Gauss–Newton
    (:func:`navtrack.estimation.least_squares.gauss_newton`, step-norm threshold ``xtol_m``).

    Parameters
    ----------
    meas : Measurements
    config : SppConfig, optional
    epochs : ndarray of int, shape (B,), optional
        Measurement epochs to estimate (default: all ``E``); integrity monitoring re-estimates a
        subset with a new ``exclude``.
    exclude : ndarray of bool, shape (B, S), optional
        Satellites left out per estimated epoch (fault exclusion); excluding a satellite is the
        same as not having observed it.
    x0_m : ndarray, shape (3,), (B, 3) or (B, P), optional
        Start position (ECEF, m), or full start state; default ``meas.approx_xyz_m`` with zero
        clocks.

    Returns
    -------
    PositionEstimate
    """
    cfg = config or SppConfig()
    idx, usable = _epochs_and_candidates(meas, epochs, exclude)
    x0 = _start_state(meas, idx.size, x0_m)
    model = PseudorangeModel(meas, cfg, usable, idx)
    lsq = gauss_newton(model, x0, max_iter=cfg.max_iter, xtol=cfg.xtol_m)

    status = _estimation_status(meas, idx, usable, lsq.status)

    geo = model.geometry(lsq.x, np.arange(idx.size))
    return PositionEstimate(
        epochs=idx,
        x=lsq.x,
        cov=lsq.cov,
        residuals_m=lsq.residuals,
        design=lsq.jacobian,
        weights=lsq.weights,
        used=lsq.valid,
        azel_rad=np.stack([geo.azimuth(), geo.el], axis=-1),
        enu_rotation=geo.rot,
        dop=dops(geo.los_enu, lsq.valid),
        chi2=lsq.cost,
        dof=lsq.dof,
        iterations=lsq.iterations,
        status=status,
    )


def _epochs_and_candidates(
    meas: Measurements, epochs: IntArray | None, exclude: BoolArray | None
) -> tuple[IntArray, BoolArray]:
    """The measurement epochs to estimate (checked, negative indices resolved) and their
    candidate satellites without the excluded ones."""
    n_e, n_s = meas.usable.shape
    if epochs is None:
        idx = np.arange(n_e)
        usable = meas.usable
    else:
        idx = np.asarray(epochs)
        if idx.ndim != 1 or idx.dtype.kind not in "iu":
            raise ValueError(f"epochs: expected a 1-D integer array, got {idx.dtype} {idx.shape}")
        if idx.size and (idx.min() < -n_e or idx.max() >= n_e):
            raise ValueError(f"epochs: indices outside the {n_e} measurement epochs")
        idx = np.where(idx < 0, idx + n_e, idx).astype(np.int64)
        usable = meas.usable[idx]
    if exclude is not None:
        ex = np.asarray(exclude)
        if ex.shape != (idx.size, n_s) or ex.dtype != bool:
            raise ValueError(f"exclude: expected a bool array of shape {(idx.size, n_s)}")
        usable = usable & ~ex
    return idx, usable


def _start_state(meas: Measurements, n_epochs: int, x0_m: FloatArray | None) -> FloatArray:
    """Start states ``(B, P)``: a position ``(3,)`` or ``(B, 3)`` with zero clocks, or full
    states ``(B, P)``; default the measurements' approximate position."""
    n_p = meas.n_params
    x0 = np.zeros((n_epochs, n_p))
    start = meas.approx_xyz_m if x0_m is None else np.asarray(x0_m, dtype=float)
    if start.shape == (n_epochs, n_p):
        x0[:] = start
    elif start.shape in ((3,), (n_epochs, 3)):
        x0[:, :3] = start
    else:
        raise ValueError(f"x0_m: expected shape (3,), {(n_epochs, 3)} or {x0.shape}")
    return x0


def _estimation_status(
    meas: Measurements, idx: IntArray, usable: BoolArray, lsq_status: np.ndarray
) -> Int8Array:
    """:class:`SppStatus` of the estimated epochs from the least-squares outcome and the
    observations (the validity tests are :func:`validate`'s)."""
    observed = meas.observed[idx].any(axis=1)
    status = np.full(idx.size, SppStatus.OK, dtype=np.int8)
    status[lsq_status == LsqStatus.NO_CONVERGENCE] = SppStatus.NO_CONVERGENCE
    status[lsq_status == LsqStatus.SINGULAR] = SppStatus.SINGULAR_GEOMETRY
    status[lsq_status == LsqStatus.TOO_FEW_MEASUREMENTS] = SppStatus.TOO_FEW_SATS
    status[~usable.any(axis=1) & observed] = SppStatus.TOO_FEW_SATS
    with_eph = (meas.has_ephemeris[idx] & meas.observed[idx]).any(axis=1)
    status[observed & ~with_eph] = SppStatus.NO_EPHEMERIS
    status[~observed] = SppStatus.TOO_FEW_SATS
    return status


def merge_estimates(estimate: PositionEstimate, update: PositionEstimate) -> PositionEstimate:
    """``estimate`` with the epochs of ``update`` replaced by ``update``'s rows (e.g. the
    re-estimates of fault exclusion on the failed epochs); ``update.epochs`` must be among
    ``estimate.epochs``.

    Parameters
    ----------
    estimate : PositionEstimate
        Of epochs ``(B,)``.
    update : PositionEstimate
        Of epochs ``(b,)`` of the same measurements (same satellites and parameters).

    Returns
    -------
    PositionEstimate
        Of epochs ``(B,)``.
    """
    if (
        update.x.shape[1:] != estimate.x.shape[1:]
        or update.used.shape[1:] != estimate.used.shape[1:]
    ):
        raise ValueError("update: estimate of other satellites or parameters")
    order = np.argsort(estimate.epochs, kind="stable")
    at = np.searchsorted(estimate.epochs, update.epochs, sorter=order)
    rows = order[np.minimum(at, max(order.size - 1, 0))] if order.size else at
    if update.epochs.size and (
        not order.size or not np.array_equal(estimate.epochs[rows], update.epochs)
    ):
        raise ValueError("update: epochs that estimate does not have")
    fields = {}
    for name in PositionEstimate.record_fields:
        value = np.array(getattr(estimate, name))
        if name != "epochs":
            value[rows] = getattr(update, name)
        fields[name] = value
    return PositionEstimate(**fields)


def validate(estimate: PositionEstimate, config: SppConfig | None = None) -> Int8Array:
    """Validity tests of the estimated epochs (stage 5 of :func:`solve_spp`, RTKLIB ``valsol``;
    the stage integrity monitoring replaces).

    An ``ok`` epoch becomes ``rejected_validity`` when its weighted residuals fail the
    chi-square test, ``v^T W v > chi2_{1 - alpha}(dof)`` (skipped for ``chi2_alpha = 0`` or
    ``dof = 0``), else ``high_dop`` when ``GDOP > max_gdop`` or GDOP is undefined.

    Parameters
    ----------
    estimate : PositionEstimate
    config : SppConfig, optional
        ``chi2_alpha`` and ``max_gdop``.

    Returns
    -------
    ndarray of int8, shape (B,)
        :class:`SppStatus` per estimated epoch.

    References
    ----------
    RTKLIB 2.4.2 manual, appendix E.6 (E.6.33, E.6.34).
    """
    cfg = config or SppConfig()
    status = estimate.status.copy()
    conv = status == SppStatus.OK
    dof = estimate.dof
    if cfg.chi2_alpha > 0:
        thr = np.array(
            [chi2_quantile(1.0 - cfg.chi2_alpha, int(k)) if k > 0 else np.inf for k in dof]
        )
        status[conv & (dof > 0) & (estimate.chi2 > thr)] = SppStatus.REJECTED_VALIDITY
    gdop = estimate.dop[:, 0]
    status[conv & (status == SppStatus.OK) & ~(gdop <= cfg.max_gdop)] = SppStatus.HIGH_DOP
    return status


def dops(los_enu: FloatArray, used: BoolArray) -> FloatArray:
    """GDOP, PDOP, HDOP, VDOP with one receiver clock and unit weights.

    Parameters
    ----------
    los_enu : ndarray, shape (E, S, 3)
        Unit line-of-sight vectors in local east/north/up.
    used : ndarray of bool, shape (E, S)

    Returns
    -------
    ndarray, shape (E, 4)
        NaN where fewer than 4 satellites or singular.
    """
    n_e = los_enu.shape[0]
    H = np.concatenate([-los_enu, np.ones((*los_enu.shape[:2], 1))], axis=-1)
    H = np.where(used[..., None], H, 0.0)
    N = np.swapaxes(H, -1, -2) @ H
    out = np.full((n_e, 4), np.nan)
    ok = used.sum(axis=1) >= 4
    ok[ok] = np.abs(np.linalg.det(N[ok])) > 1e-12
    if ok.any():
        Q = np.linalg.inv(N[ok])
        d = np.einsum("eii->ei", Q)
        out[ok, 0] = np.sqrt(d.sum(axis=1))
        out[ok, 1] = np.sqrt(d[:, :3].sum(axis=1))
        out[ok, 2] = np.sqrt(d[:, :2].sum(axis=1))
        out[ok, 3] = np.sqrt(d[:, 2])
    return out
