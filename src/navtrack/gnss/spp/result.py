"""Stage 6 of single point positioning: the result of all epochs, joined over epoch blocks,
and its solution frame (the columns ``pos --out`` writes)."""

from __future__ import annotations

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.gnss.spp.config import STATUS_NAMES, SppStatus
from navtrack.gnss.spp.estimate import PositionEstimate
from navtrack.gnss.spp.measurements import Measurements
from navtrack.gnss.spp.model import reference_group

__all__ = ["SppResult", "concatenate_results", "solution_frame", "spp_result"]


class SppResult(Record):
    """Single point positions of all epochs.

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Epoch time tags (receiver time, GPS s).
    sats : tuple of str, length S
        Satellite ids of the satellite axis.
    clock_groups : tuple of str
        Clock parameter names: the first is the receiver clock of that system, the others ISBs.
    pos_m : ndarray, shape (E, 3)
        ECEF position (m); NaN where ``status`` is not ``ok`` and no estimate exists.
    clock_m : ndarray, shape (E,)
        Receiver clock offset times c (m) of the first clock group; in an epoch without a used
        satellite of that group, of the first group that has one (whose ``isb_m`` is then NaN).
    isb_m : ndarray, shape (E, G-1)
        Inter-system biases (m) of the other clock groups (NaN where the group had no satellite).
    cov : ndarray, shape (E, 3+G, 3+G)
        Covariance of ``(x, y, z, clock, isb...)`` (m^2).
    cov_enu_m2 : ndarray, shape (E, 3, 3)
        Position covariance rotated to local east/north/up.
    status : ndarray of int8, shape (E,)
        :class:`SppStatus`.
    used : ndarray of bool, shape (E, S)
        Satellites used in the final iterate.
    observed : ndarray of bool, shape (E, S)
        Satellites with a pseudorange of the selected systems.
    no_ephemeris : ndarray of bool, shape (E, S)
        Observed but without a usable (healthy, valid, in-window) ephemeris.
    residuals_m : ndarray, shape (E, S)
        Pseudorange residuals (observed minus computed, m) of the used satellites, NaN elsewhere.
    sigma_m : ndarray, shape (E, S)
        Measurement standard deviations used in the weights.
    azel_rad : ndarray, shape (E, S, 2)
        Azimuth and elevation at the solution.
    dop : ndarray, shape (E, 4)
        GDOP, PDOP, HDOP, VDOP of the used satellites (one clock, unit weights, as RTKLIB).
    chi2 : ndarray, shape (E,)
        Weighted sum of squared residuals.
    dof : ndarray of int, shape (E,)
        Redundancy.
    iterations : ndarray of int, shape (E,)
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    clock_groups: tuple[str, ...]
    pos_m: FloatArray
    clock_m: FloatArray
    isb_m: FloatArray
    cov: FloatArray
    cov_enu_m2: FloatArray
    status: np.ndarray
    used: BoolArray
    observed: BoolArray
    no_ephemeris: BoolArray
    residuals_m: FloatArray
    sigma_m: FloatArray
    azel_rad: FloatArray
    dop: FloatArray
    chi2: FloatArray
    dof: IntArray
    iterations: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def n_sats(self) -> IntArray:
        """Satellites used per epoch."""
        return self.used.sum(axis=1)

    @property
    def ok(self) -> BoolArray:
        return self.status == SppStatus.OK

    def status_counts(self) -> dict[str, int]:
        """Number of epochs per status name (all statuses, zeros included)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(SppStatus))
        return {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}

    def frame_columns(self) -> dict[str, np.ndarray]:
        """The solution frame of the result (:func:`solution_frame`)."""
        return solution_frame(self)


def spp_result(
    meas: Measurements,
    estimate: PositionEstimate,
    status: Int8Array,
) -> SppResult:
    """Assemble the :class:`SppResult` of an estimate of all measurement epochs and the
    statuses of its validation (or its integrity monitoring): positions, clocks and
    covariances of the epochs whose status is ``ok``, ``rejected_validity`` or ``high_dop``,
    NaN elsewhere."""
    n_e = meas.t_gps_s.size
    if not np.array_equal(estimate.epochs, np.arange(n_e)) or np.shape(status) != (n_e,):
        raise ValueError("estimate, status: need all measurement epochs in order")
    x, rot, n_groups = estimate.x, estimate.enu_rotation, len(meas.clock_groups)
    solved = np.isin(status, (SppStatus.OK, SppStatus.REJECTED_VALIDITY, SppStatus.HIGH_DOP))
    valid = estimate.used
    group_seen = np.stack([(valid & (meas.group == k)).any(axis=1) for k in range(n_groups)], 1)
    # the clock of an epoch without the first group is that of its reference group (the
    # group's bias, held at its start value, is added back; the bias itself is not estimated)
    ref = reference_group(valid, meas.group, n_groups)
    rows = np.arange(n_e)
    clock = x[:, 3] + np.where(ref > 0, x[rows, 3 + ref], 0.0)
    group_seen[rows, ref] &= ref == 0
    cov_enu = np.einsum("eij,ejk,elk->eil", rot, estimate.cov[:, :3, :3], rot)
    w = estimate.weights
    return SppResult(
        t_gps_s=meas.t_gps_s.copy(),
        sats=meas.sats,
        clock_groups=meas.clock_groups,
        pos_m=np.where(solved[:, None], x[:, :3], np.nan),
        clock_m=np.where(solved, clock, np.nan),
        isb_m=np.where(solved[:, None] & group_seen[:, 1:], x[:, 4:], np.nan),
        cov=estimate.cov,
        cov_enu_m2=np.where(solved[:, None, None], cov_enu, np.nan),
        status=np.array(status, dtype=np.int8),
        used=valid & solved[:, None],
        observed=meas.observed,
        no_ephemeris=meas.no_ephemeris,
        residuals_m=estimate.residuals_m,
        sigma_m=np.where(valid, 1.0 / np.sqrt(np.where(valid, w, 1.0)), np.nan),
        azel_rad=estimate.azel_rad,
        dop=estimate.dop,
        chi2=estimate.chi2,
        dof=estimate.dof,
        iterations=estimate.iterations,
    )


def concatenate_results(parts: list[SppResult]) -> SppResult:
    """Join results of consecutive epoch blocks (same satellites); clock groups are aligned by
    name, ISBs and covariance entries of groups absent from a block are NaN."""
    if not parts:
        raise ValueError("parts: need at least one result")
    groups = [g for g in "GRECJI" if any(g in p.clock_groups for p in parts)]
    if parts[0].clock_groups and parts[0].clock_groups[0] in groups:
        first = parts[0].clock_groups[0]
        groups.remove(first)
        groups.insert(0, first)
    n_p = 3 + len(groups)

    def align(p: SppResult) -> tuple[FloatArray, FloatArray]:
        e = p.t_gps_s.size
        isb = np.full((e, len(groups) - 1), np.nan)
        cov = np.full((e, n_p, n_p), np.nan)
        src = [0, 1, 2] + [
            3 + p.clock_groups.index(g) if g in p.clock_groups else -1 for g in groups
        ]
        for i, si in enumerate(src):
            for j, sj in enumerate(src):
                if si >= 0 and sj >= 0:
                    cov[:, i, j] = p.cov[:, si, sj]
        for k, g in enumerate(groups[1:]):
            if g in p.clock_groups[1:]:
                isb[:, k] = p.isb_m[:, p.clock_groups.index(g) - 1]
        return isb, cov

    aligned = [align(p) for p in parts]

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    return SppResult(
        t_gps_s=cat("t_gps_s"),
        sats=parts[0].sats,
        clock_groups=tuple(groups),
        pos_m=cat("pos_m"),
        clock_m=cat("clock_m"),
        isb_m=np.concatenate([a[0] for a in aligned]),
        cov=np.concatenate([a[1] for a in aligned]),
        cov_enu_m2=cat("cov_enu_m2"),
        status=cat("status"),
        used=cat("used"),
        observed=cat("observed"),
        no_ephemeris=cat("no_ephemeris"),
        residuals_m=cat("residuals_m"),
        sigma_m=cat("sigma_m"),
        azel_rad=cat("azel_rad"),
        dop=cat("dop"),
        chi2=cat("chi2"),
        dof=cat("dof"),
        iterations=cat("iterations"),
    )


# RTKLIB's covariance columns and the ECEF covariance element each one holds.
_RTKLIB_SD_COLUMNS = ("sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m")
_RTKLIB_SD_INDICES = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0))


def solution_frame(result: SppResult) -> dict[str, np.ndarray]:
    """The solution as a solution frame (plain arrays, no pandas), one row per epoch, all
    statuses: the input of :func:`navtrack.io.solution.write_solution`,
    :func:`navtrack.io.solution.solution_columns` (which derives ``time_gps``, ``week``,
    ``tow_s`` and the geodetic position) and :func:`navtrack.plots.gnss.plot_solution`.

    Columns: ``t_gps_s`` (GPS s), ``x_m``, ``y_m``, ``z_m`` (ECEF, m; NaN where no estimate
    exists), ``clock_m``, ``sd_e_m``, ``sd_n_m``, ``sd_u_m`` (formal standard deviations, m),
    ``n_sats`` (used), ``pdop``, ``status`` (name), ``excluded`` (space-separated ids of the
    satellites integrity monitoring excluded; empty without it), ``gdop``, ``hdop``, ``vdop``,
    the ECEF position covariance as RTKLIB writes it, ``sdx_m``, ``sdy_m``, ``sdz_m`` (standard
    deviations) and ``sdxy_m``, ``sdyz_m``, ``sdzx_m`` (signed square roots of the covariances,
    ``sign(c) sqrt(|c|)``), and one ``isb_<sys>_m`` per further clock group. The positioning
    pipeline adds the integrity columns (:func:`navtrack.positioning.solution_frame`).
    """
    sd = np.sqrt(np.einsum("eii->ei", result.cov_enu_m2))
    n = result.t_gps_s.size
    cols: dict[str, np.ndarray] = {
        "t_gps_s": result.t_gps_s,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "clock_m": result.clock_m,
        "sd_e_m": sd[:, 0],
        "sd_n_m": sd[:, 1],
        "sd_u_m": sd[:, 2],
        "n_sats": result.used.sum(axis=1) if result.used.size else np.zeros(n, np.int64),
        "pdop": result.dop[:, 1],
        "status": np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)],
        "excluded": np.full(n, "", dtype=object),
        "gdop": result.dop[:, 0],
        "hdop": result.dop[:, 2],
        "vdop": result.dop[:, 3],
    }
    c = result.cov
    for name, (i, j) in zip(_RTKLIB_SD_COLUMNS, _RTKLIB_SD_INDICES, strict=True):
        cols[name] = np.sign(c[:, i, j]) * np.sqrt(np.abs(c[:, i, j]))
    for k, g in enumerate(result.clock_groups[1:]):
        cols[f"isb_{g}_m"] = result.isb_m[:, k]
    return cols
