"""Multi-target tracker for real data: GNN or JPDA association with track management.

:func:`run_tracker` takes time-ordered 2-D position detections (local east/north, m) and runs,
per scan (detections sharing one time stamp), a chain of named stages over a
:class:`TrackStore` (the live tracks); each stage is importable on its own, so other trackers
(multisensor fusion, particle filters) can reuse them:

1. :func:`predict` every track to the scan time (IMM mixing, then the batched KF prediction of
   :mod:`navtrack.estimation.kalman`);
2. :func:`gate_scan`: innovation covariance and gain from the Kalman kernels, chi-square gate
   (with a k-d tree pre-gate when there are many pairs), per-model and mixture likelihoods;
3. :func:`associate`: :func:`associate_gnn` (optimal 2-D assignment with missed-detection costs,
   :func:`~navtrack.tracking.assignment.assign2d`) or :func:`associate_jpda`
   (:func:`~navtrack.tracking.jpda.jpda_marginals`);
4. :func:`update`: Kalman update of the assigned tracks (GNN) or PDA update (JPDA), and IMM
   model probabilities;
5. :func:`manage`: tentative tracks are confirmed after ``confirm_hits`` updates within
   ``confirm_window_s`` of their birth (the M-of-N rule written in time, so it applies to
   irregular report times as well as to regular scans) and dropped otherwise; tracks are
   deleted after ``max_coast_s`` without update or when their position standard deviation
   exceeds ``max_position_std_m``;
6. :func:`initiate`: a detection not claimed by a track starts a tentative track on its own
   when it carries a reported velocity (one-point initiation), or is paired with an earlier
   unclaimed detection ("seed") reachable at ``init_max_speed_mps`` within ``init_max_dt_s``
   (two-point initiation: position and velocity from the two points); otherwise it becomes a
   seed.

Track ids are integers given at birth and never reused. Every detection's fate is recorded
(``det_status``, :class:`DetStatus`) so nothing is dropped silently.

References
----------
.. [1] S. S. Blackman, R. Popoli, *Design and Analysis of Modern Tracking Systems*, Artech
   House 1999, chapter 6 (GNN), 3.3 (M-of-N confirmation) and 4 (two-point initiation).
.. [2] Y. Bar-Shalom, T. E. Fortmann, *Tracking and Data Association*, Academic Press 1988,
   chapter 6 (PDA update) and 9 (JPDA).
.. [3] H. A. P. Blom, E. A. Bloem, "Probabilistic data association avoiding track coalescence",
   IEEE T-AC 45(2), 2000 (IMM-JPDA model likelihoods).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.spatial import cKDTree

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, Int8Array, IntArray
from navtrack.tracking.jpda import JpdaMethod
from navtrack.tracking.trackers.management import (
    EndedTracks,
    Management,
    continuation,
    initiate,
    manage,
    repeat_reports,
    report,
    same_scan_repeats,
)
from navtrack.tracking.trackers.stages import (
    ScanAssociation,
    ScanGate,
    Seeds,
    TrackStore,
    associate,
    gate_scan,
    predict,
    update,
)
from navtrack.tracking.trackers.track_config import (
    DET_STATUS_NAMES,
    TRACK_END_NAMES,
    DetStatus,
    TrackEnd,
    TrackerConfig,
    TrackerModel,
)

__all__ = [
    "DET_STATUS_NAMES",
    "TRACK_END_NAMES",
    "DetStatus",
    "TrackEnd",
    "TrackerConfig",
    "TrackerCounts",
    "TrackerModel",
    "TrackerResult",
    "run_tracker",
    "scan_windows",
    "window_separation_m",
]


@dataclass(frozen=True, slots=True)
class TrackerCounts:
    """What happened in a run (counts, printed by the CLI summary).

    Attributes
    ----------
    scans : distinct detection times processed
    tracks_started, tracks_confirmed : births and confirmations
    deleted_coast, deleted_covariance : confirmed tracks deleted for coasting longer than
        ``max_coast_s`` / for a position standard deviation above ``max_position_std_m``
    deleted_unconfirmed : tentative tracks dropped (not confirmed within ``confirm_window_s``,
        or coasting, or diverged)
    jpda_exact_clusters, jpda_kbest_clusters : JPDA clusters (summed over scans) solved exactly
        / by k-best (:class:`~navtrack.tracking.jpda.JpdaMethod`)
    ambiguous_detections : detections inside the gates of two or more confirmed tracks
        (gates wide for the spacing of the targets; :mod:`navtrack.tracking.trackers.autotune`)
    tracks_continued : newly confirmed tracks that took the id of an ended track
        (``TrackerConfig.continue_tracks``)
    """

    scans: int = 0
    tracks_started: int = 0
    tracks_confirmed: int = 0
    deleted_coast: int = 0
    deleted_covariance: int = 0
    deleted_unconfirmed: int = 0
    jpda_exact_clusters: int = 0
    jpda_kbest_clusters: int = 0
    ambiguous_detections: int = 0
    tracks_continued: int = 0


@dataclass(frozen=True, slots=True, eq=False, kw_only=True)
class TrackerResult:
    """Tracker output (arrays read-only).

    Attributes
    ----------
    det_track : (N,) int
        Id of the track each detection updated or started (``-1`` none).
    det_status : (N,) int8
        Fate of each detection, a :class:`DetStatus`: 0 confirmed-track update, 1 tentative-track
        update, 2 started a track, 3 seed never paired, 4 gated but not associated.
    track_time_s, track_id, track_x, track_std_m, track_confirmed, track_p_update :
        One row per track update: time (s), id, state ``[x, vx, y, vy]`` (m, m/s), position
        standard deviation ``sqrt(trace(P_pos)/2)`` (m), confirmed flag, and the probability
        that a detection of this scan updated the track (1 for a GNN assignment; JPDA's
        ``1 - β₀``: every soft update that moved the track has a row, also below 1/2).
    report_frame, report_id, report_xy :
        Confirmed tracks predicted to each requested report time (index into
        ``report_times``), for scoring; a track more than ``max_coast_s`` past its last update
        is left out.
    counts : TrackerCounts
    det_nis : (N,) float
        Normalised innovation squared ``νᵀ S⁻¹ ν`` of each detection against the track it
        updated, at the prediction, the smallest over the motion models (NaN for detections
        that updated no track; :mod:`navtrack.tracking.trackers.autotune` reads it).
    det_log_likelihood : (N,) float
        ``log N(z; h(x), S)`` of each detection against the track it updated, mixed over the
        motion models with their predicted probabilities (NaN for detections that updated no
        track; the likelihood :mod:`navtrack.tracking.trackers.autotune` maximises over q).
    end_id, end_time_s, end_reason : (K,)
        One row per track: its id, when it ended (s; the time of the scan that deleted it, or
        of the last scan) and why (a :class:`TrackEnd`).
    """

    det_track: IntArray
    det_status: Int8Array
    track_time_s: FloatArray
    track_id: IntArray
    track_x: FloatArray
    track_std_m: FloatArray
    track_confirmed: BoolArray
    report_frame: IntArray
    report_id: IntArray
    report_xy: FloatArray
    counts: TrackerCounts
    det_nis: FloatArray = field(default_factory=lambda: np.zeros(0))
    det_log_likelihood: FloatArray = field(default_factory=lambda: np.zeros(0))
    track_p_update: FloatArray = field(default_factory=lambda: np.zeros(0))
    end_id: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    end_time_s: FloatArray = field(default_factory=lambda: np.zeros(0))
    end_reason: Int8Array = field(default_factory=lambda: np.zeros(0, dtype=np.int8))

    def __post_init__(self) -> None:
        freeze_arrays(self)


def scan_windows(
    t_s: FloatArray, z: FloatArray, window_s: float, separation_m: float
) -> tuple[IntArray, IntArray]:
    """Group time-ordered detections into scans: first and one-past-last index of each.

    Detections sharing a time are always one scan. With ``window_s > 0`` the following
    distinct times join the scan while they stay within ``window_s`` of its first time and
    none of their detections lies within ``separation_m`` of a detection already in the scan
    (two such reports may come from one target, and a scan gives a track at most one
    detection). ``window_s = 0`` gives one scan per distinct time.

    Parameters
    ----------
    t_s : (N,) non-decreasing times, s
    z : (N, 2) positions, m
    window_s, separation_m : float

    Returns
    -------
    starts, ends : (W,) int
    """
    N = t_s.size
    if not N:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    g0 = np.flatnonzero(np.r_[True, np.diff(t_s) > 0])
    g1 = np.r_[g0[1:], N]
    if window_s <= 0:
        return g0.astype(np.int64), g1.astype(np.int64)
    # the closest earlier detection within window_s of each detection, found in one k-d tree
    # query of (time, position) points scaled so that window_s and separation_m both map to 1
    # (the max norm, p = inf): a neighbour closer in both senses can end a window
    pts = np.column_stack([t_s / window_s, z / separation_m])
    pairs = cKDTree(pts).query_pairs(1.0, p=np.inf, output_type="ndarray")
    # for each detection, the latest earlier detection (distinct time) it conflicts with
    later = np.maximum(pairs[:, 0], pairs[:, 1])
    earlier = np.minimum(pairs[:, 0], pairs[:, 1])
    diff_t = t_s[later] > t_s[earlier]
    conflict = np.full(N, -1, dtype=np.int64)
    np.maximum.at(conflict, later[diff_t], earlier[diff_t])
    group_conflict = np.maximum.reduceat(conflict, g0)  # per distinct time
    starts = [0]
    first_t = t_s[0]
    for k in range(1, g0.size):
        s = g0[k]
        if t_s[s] - first_t > window_s or group_conflict[k] >= g0[starts[-1]]:
            starts.append(k)
            first_t = t_s[s]
    st = g0[np.asarray(starts)]
    return st.astype(np.int64), np.r_[st[1:], N].astype(np.int64)


def run_tracker(
    t_s: ArrayLike,
    z: ArrayLike,
    config: TrackerConfig | None = None,
    report_times: ArrayLike | None = None,
    velocity: ArrayLike | None = None,
    progress: Callable[[int], object] | None = None,
) -> TrackerResult:
    """Track 2-D position detections: the stages of the module notes, scan by scan.

    Parameters
    ----------
    t_s : (N,) detection times, s, non-decreasing (equal times form one scan)
    z : (N, 2) east/north positions, m, finite
    config : TrackerConfig
    report_times : (F,) or None
        Times at which the confirmed tracks are reported (predicted) for scoring.
    velocity : (N, 2) or None
        Reported east/north velocity of each detection (m/s; NaN where unknown), e.g. AIS speed
        and course over ground or ADS-B velocity and heading. A detection with a velocity
        starts a tentative track on its own (one-point initiation, velocity standard deviation
        ``init_velocity_std_mps``) instead of waiting for a second point; the velocity is used
        for initiation only, not in the updates.
    progress : callable or None
        Called after each scan with the number of detections that scan held (e.g. a tqdm
        bar's ``update``).
    Raises
    ------
    ValueError
        Times not non-decreasing (the first offending index is named), non-finite values.
    """
    cfg = config or TrackerConfig()
    t, Z, V = _checked_inputs(t_s, z, velocity)
    rep = np.zeros(0) if report_times is None else np.asarray(report_times, dtype=float)
    run = _Run(cfg, t.size, rep)
    now = t[0] if t.size else 0.0
    starts, ends = scan_windows(t, Z, cfg.scan_window_s, window_separation_m(run.model))
    done = 0  # detections reported to ``progress``
    for s0, s1 in zip(starts, ends, strict=True):
        if progress is not None and s0:
            progress(s0 - done)
            done = s0
        tk = t[s1 - 1]  # a window of reports is processed at its last time
        run.log.report_until(run.store, now, tk, cfg, inclusive=False)
        predict(run.store, tk - now, run.model)
        now = tk
        run.scan(s0, t[s0:s1], Z[s0:s1], V[s0:s1], tk)
    run.log.report_until(run.store, now, now, cfg, inclusive=True)
    run.log.ends(now, run.store.id, np.full(run.store.size, TrackEnd.END_OF_DATA, dtype=np.int8))
    if progress is not None:
        progress(t.size - done)
    return run.result()


def _checked_inputs(
    t_s: ArrayLike, z: ArrayLike, velocity: ArrayLike | None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Times ``(N,)``, positions and velocities ``(N, 2)`` (NaN without velocities), checked."""
    t = np.asarray(t_s, dtype=float)
    Z = np.asarray(z, dtype=float)
    if t.ndim != 1 or Z.shape != (t.size, 2):
        raise ValueError(f"t_s must be (N,) and z (N, 2); got {t.shape} and {Z.shape}")
    if not np.all(np.isfinite(t)) or not np.all(np.isfinite(Z)):
        bad = int(np.flatnonzero(~(np.isfinite(t) & np.isfinite(Z).all(axis=1)))[0])
        raise ValueError(f"detections must be finite: detection {bad} is not")
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        raise ValueError(
            f"t_s must be non-decreasing: detection {back[0] + 1} ({t[back[0] + 1]}) is earlier "
            f"than detection {back[0]} ({t[back[0]]})"
        )
    V = np.full((t.size, 2), np.nan) if velocity is None else np.asarray(velocity, dtype=float)
    if V.shape != (t.size, 2):
        raise ValueError(f"velocity must be (N, 2) like z, got {V.shape}")
    return t, Z, V


class _Run:
    """The state of one :func:`run_tracker` call: the live tracks, the seeds, the fate of every
    detection, the counts and the rows of the result."""

    def __init__(self, cfg: TrackerConfig, n: int, report_times: FloatArray) -> None:
        self.cfg = cfg
        self.model = TrackerModel.from_config(cfg)
        self.store = TrackStore(cfg.motion.dim_x, len(self.model.motions))
        self.seeds = Seeds()
        self.log = _Log(report_times)
        self.det_track = np.full(n, -1, dtype=np.int64)
        self.det_status = np.full(n, DetStatus.SEED, dtype=np.int8)
        self.det_nis = np.full(n, np.nan)
        self.det_ll = np.full(n, np.nan)
        self.counts = dict.fromkeys(TrackerCounts.__dataclass_fields__, 0)
        self.ended = EndedTracks(cfg.motion.dim_x)
        self.alias: dict[int, int] = {}  # id of a continuing track -> id it continues

    def scan(self, s0: int, t: FloatArray, Z: FloatArray, V: FloatArray, tk: float) -> None:
        """One scan (detections ``s0, s0 + 1, ...`` at times ``t``), the tracks predicted to
        ``tk``: repeats set aside, then gate, associate, update, manage and initiate."""
        cfg, store = self.cfg, self.store
        self.counts["scans"] += 1
        twice = same_scan_repeats(Z, V, self.model)
        self.det_status[s0 + np.flatnonzero(twice)] = DetStatus.UNUSED
        keep = np.flatnonzero(~twice)
        rows = s0 + keep
        Zk, Vk, dt_k = Z[keep], V[keep], t[keep] - tk
        claimed = np.zeros(keep.size, dtype=bool)  # detections not available for initiation
        if store.size:
            g = gate_scan(store, Zk, self.model, dt_k)
            a = associate(g, self.model)
            update(store, g, a)
            self._fates(rows, g, a)
            claimed = a.associated if cfg.init_from == "unassociated" else g.gated
            repeat = repeat_reports(store, Zk, a.hit, self.model, dt_k) & ~claimed
            self.det_status[rows[repeat]] = DetStatus.UNUSED
            claimed = claimed | repeat
            m = manage(store, a.hit, tk, cfg)
            if cfg.continue_tracks:
                self._continue(m, tk)
            self.log.updates(tk, m, 1.0 - a.beta[:, 0])
            _add_counts(self.counts, a, m)
        free = np.flatnonzero(~claimed)
        if not free.size:  # (seeds are pruned by age when next used: same result)
            return
        ini = initiate(store, self.seeds, tk, Zk[free], Vk[free], rows[free], cfg, t[keep][free])
        self.det_track[rows[free]] = ini.track
        self.det_status[rows[free]] = ini.status
        self.det_track[ini.seed_det] = ini.seed_track
        self.det_status[ini.seed_det] = DetStatus.STARTED
        self.counts["tracks_started"] += int(np.count_nonzero(ini.track >= 0))

    def _continue(self, m: Management, t_s: float) -> None:
        """Give each newly confirmed track that continues an ended one the ended track's id
        (:func:`continuation`), then add this scan's lost tracks to the ended ones."""
        new = np.flatnonzero(m.confirmed_new)
        if new.size:
            old = continuation(self.ended, m.x[new], m.P[new], t_s, self.model)
            hit = old >= 0
            if hit.any():
                self.alias.update(zip(m.id[new[hit]].tolist(), old[hit].tolist(), strict=True))
                rows = np.flatnonzero(np.isin(self.store.id, m.id[new[hit]]))
                self.store.id[rows] = [self.alias[int(i)] for i in self.store.id[rows]]
                self.counts["tracks_continued"] += int(hit.sum())
        self.ended.add(m, t_s)

    def _fates(self, rows: IntArray, g: ScanGate, a: ScanAssociation) -> None:
        """Fates of the associated detections, by the status of their track before manage."""
        store = self.store
        k = a.detection_track
        used = np.flatnonzero(k >= 0)
        self.det_track[rows[used]] = store.id[k[used]]
        self.det_status[rows[used]] = np.where(
            store.confirmed[k[used]], DetStatus.CONFIRMED, DetStatus.TENTATIVE
        )
        self.det_status[rows[g.gated & (k < 0)]] = DetStatus.UNUSED
        self.counts["ambiguous_detections"] += int(
            np.count_nonzero(g.valid[store.confirmed].sum(axis=0) >= 2)
        )
        self.det_nis[rows[used]] = g.d2[k[used], :, used].min(axis=1)
        self.det_ll[rows[used]] = g.log_likelihood_mix[k[used], used]

    def result(self) -> TrackerResult:
        res = self.log.result(
            self.det_track,
            self.det_status,
            self.det_nis,
            self.cfg.motion.dim_x,
            TrackerCounts(**self.counts),
            self.det_ll,
        )
        if not self.alias:
            return res
        # the rows a continuing track wrote under its own id before it was confirmed, and the
        # end rows of the tracks it continued
        new = np.array(list(self.alias), dtype=np.int64)
        old = np.array(list(self.alias.values()), dtype=np.int64)
        order = np.argsort(new)
        new, old = new[order], old[order]

        def renamed(ids: IntArray) -> IntArray:
            k = np.clip(np.searchsorted(new, ids), 0, new.size - 1)
            return np.where(new[k] == ids, old[k], ids)

        last_end = np.zeros(res.end_id.size, dtype=bool)  # (rows are in time order)
        _, last = np.unique(res.end_id[::-1], return_index=True)
        last_end[res.end_id.size - 1 - last] = True
        return replace(
            res,
            det_track=renamed(res.det_track),
            track_id=renamed(res.track_id),
            end_id=res.end_id[last_end],
            end_time_s=res.end_time_s[last_end],
            end_reason=res.end_reason[last_end],
        )


def window_separation_m(model: TrackerModel) -> float:
    """Distance within which two reports at distinct times may not share a scan window: how
    far two reports of one target can lie apart, the largest initiation speed over the window
    plus the gate radius of the difference of two measurement errors, ``sqrt(2 γ) σ``."""
    cfg = model.config
    return float(
        np.sqrt(2 * model.gamma) * cfg.sigma_m + cfg.init_max_speed_mps * cfg.scan_window_s
    )


def _add_counts(counts: dict[str, int], a: ScanAssociation, m: Management) -> None:
    counts["tracks_confirmed"] += m.confirmed_now
    counts["deleted_coast"] += m.deleted_coast
    counts["deleted_covariance"] += m.deleted_covariance
    counts["deleted_unconfirmed"] += m.deleted_unconfirmed
    jm = a.marginals
    if jm is not None:
        for key, code in (
            ("jpda_exact_clusters", JpdaMethod.EXACT),
            ("jpda_kbest_clusters", JpdaMethod.KBEST),
        ):
            counts[key] += len(np.unique(jm.cluster[jm.method == code]))


class _Log:
    """Rows of the result: track updates, and confirmed tracks at the report times."""

    def __init__(self, report_times: FloatArray) -> None:
        self.rep = report_times
        self.r_next = 0
        self.t: list[FloatArray] = []
        self.id: list[IntArray] = []
        self.x: list[FloatArray] = []
        self.std: list[FloatArray] = []
        self.conf: list[BoolArray] = []
        self.rep_f: list[IntArray] = []
        self.rep_id: list[IntArray] = []
        self.rep_xy: list[FloatArray] = []
        self.p: list[FloatArray] = []
        self.end_t: list[FloatArray] = []
        self.end_id: list[IntArray] = []
        self.end_reason: list[Int8Array] = []

    def updates(self, t_s: float, m: Management, p_update: FloatArray) -> None:
        """Rows for the tracks a detection moved this scan (``p_update > 0``), and the ends of
        the tracks :func:`manage` deleted."""
        upd = np.flatnonzero(p_update > 0.0)
        if upd.size:
            self.t.append(np.full(upd.size, t_s))
            self.id.append(m.id[upd])
            self.x.append(m.x[upd])
            self.std.append(m.std_m[upd])
            self.conf.append(m.confirmed[upd])
            self.p.append(p_update[upd])
        gone = np.flatnonzero(~m.kept)
        if gone.size:
            self.ends(t_s, m.id[gone], m.end_reason[gone])

    def ends(self, t_s: float, ids: IntArray, reason: Int8Array) -> None:
        if ids.size:
            self.end_t.append(np.full(ids.size, t_s))
            self.end_id.append(np.asarray(ids, dtype=np.int64))
            self.end_reason.append(np.asarray(reason, dtype=np.int8))

    def report_until(
        self, store: TrackStore, now_s: float, limit_s: float, cfg: TrackerConfig, inclusive: bool
    ) -> None:
        rep = self.rep
        while self.r_next < rep.size and (
            rep[self.r_next] < limit_s or (inclusive and rep[self.r_next] <= limit_s)
        ):
            if rep[self.r_next] >= now_s:
                ids, xy = report(store, now_s, rep[self.r_next], cfg.motion, cfg.max_coast_s)
                self.rep_f.append(np.full(ids.size, self.r_next, dtype=np.int64))
                self.rep_id.append(ids)
                self.rep_xy.append(xy)
            self.r_next += 1

    def result(
        self,
        det_track: IntArray,
        det_status: Int8Array,
        det_nis: FloatArray,
        n: int,
        counts: TrackerCounts,
        det_ll: FloatArray,
    ) -> TrackerResult:
        def cat(parts: list, shape: tuple[int, ...], dtype: type) -> np.ndarray:
            return np.concatenate(parts) if parts else np.zeros(shape, dtype=dtype)

        return TrackerResult(
            det_track=det_track,
            det_status=det_status,
            track_time_s=cat(self.t, (0,), float),
            track_id=cat(self.id, (0,), np.int64),
            track_x=cat(self.x, (0, n), float),
            track_std_m=cat(self.std, (0,), float),
            track_confirmed=cat(self.conf, (0,), bool),
            report_frame=cat(self.rep_f, (0,), np.int64),
            report_id=cat(self.rep_id, (0,), np.int64),
            report_xy=cat(self.rep_xy, (0, 2), float),
            counts=counts,
            det_nis=det_nis,
            det_log_likelihood=det_ll,
            track_p_update=cat(self.p, (0,), float),
            end_id=cat(self.end_id, (0,), np.int64),
            end_time_s=cat(self.end_t, (0,), float),
            end_reason=cat(self.end_reason, (0,), np.int8),
        )
