"""Track management stages of the file tracker: reports a scan already explains, confirmation
and deletion, initiation, and the confirmed tracks reported at a time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.tracking.gating import chi2_threshold
from navtrack.tracking.models import LinearMotion
from navtrack.tracking.trackers.stages import Seeds, TrackStore
from navtrack.tracking.trackers.track_config import DetStatus, TrackEnd, TrackerConfig, TrackerModel

__all__ = [
    "EndedTracks",
    "Initiation",
    "Management",
    "continuation",
    "initiate",
    "manage",
    "one_point_state",
    "repeat_reports",
    "report",
    "same_scan_repeats",
    "two_point_state",
]


def same_scan_repeats(z: FloatArray, velocity: FloatArray, model: TrackerModel) -> BoolArray:
    """(M,) detections of one scan that repeat an earlier detection of the same scan.

    Two detections at one time are one moving target reported twice (several receivers, a
    report and its relay, sub-second ADS-B trace points stamped with one second) when they
    lie within the gate of the difference of two measurement errors (``|Δz|² <= 2 γ σ²``)
    and both carry reported velocities that agree within the gate of the difference of two
    velocity errors (``|Δv|² <= 2 γ σ_v²``, ``σ_v = init_velocity_std_mps``) at a speed
    above that gate's radius. The later one (in file order) is the repeat. Two targets do
    not share a place and a velocity; still targets (moored ships alongside each other) do
    share them, hence the speed condition. Without reported velocities nothing is a repeat.
    """
    M = z.shape[0]
    twice = np.zeros(M, dtype=bool)
    if M < 2:
        return twice
    cfg = model.config
    ok = np.flatnonzero(np.isfinite(velocity).all(axis=1))
    dv_max = np.sqrt(2 * model.gamma) * cfg.init_velocity_std_mps
    ok = ok[np.hypot(velocity[ok, 0], velocity[ok, 1]) > dv_max]
    if ok.size < 2:
        return twice
    dz_max = np.sqrt(2 * model.gamma) * cfg.sigma_m
    dz = z[ok, None, :] - z[None, ok, :]
    dv = velocity[ok, None, :] - velocity[None, ok, :]
    close = (np.einsum("abi,abi->ab", dz, dz) <= dz_max**2) & (
        np.einsum("abi,abi->ab", dv, dv) <= dv_max**2
    )
    twice[ok] = np.triu(close, 1).any(axis=0)
    return twice


def repeat_reports(
    store: TrackStore,
    z: FloatArray,
    hit: BoolArray,
    model: TrackerModel,
    dt_s: FloatArray | None = None,
) -> BoolArray:
    """(M,) detections of a scan that the tracks it just updated already explain.

    A detection is a repeat when it lies inside the gate (``model.gamma``) of a track updated
    in this scan (``hit (T,)``, the stores's states after :func:`update`), under the track's
    updated position covariance plus the measurement noise. A target reported twice within
    one scan (two receivers, a report and its relay, sub-second ADS-B trace points stamped
    with one second) leaves such a second report; it must not start a second track on the
    same target, which would then take every other report (track fragmentation at fast
    report rates). ``dt_s (M,)``: detection time minus the scan time, as for
    :func:`gate_scan`.
    """
    M = z.shape[0]
    ti = np.flatnonzero(hit)
    if not (ti.size and M):
        return np.zeros(M, dtype=bool)
    mot = model.config.motion
    pos, vel = list(mot.position_index), list(mot.velocity_index)
    xc, Pc = store.combined()
    zp = np.broadcast_to(xc[ti][:, None, pos], (ti.size, M, 2))
    if dt_s is not None:
        zp = zp + dt_s[None, :, None] * xc[ti][:, None, vel]
    S = Pc[ti][:, pos][:, :, pos] + model.measurement.R
    nu = z[None, :, :] - zp
    d2 = np.einsum("hmi,hij,hmj->hm", nu, np.linalg.inv(S), nu)
    return np.asarray((d2 <= model.gamma).any(axis=0), dtype=bool)


@dataclass(frozen=True, slots=True, eq=False)
class Management:
    """Outcome of :func:`manage` for the ``T`` tracks before deletion.

    Attributes
    ----------
    id : (T,) track ids; x : (T, n) combined state; P : (T, n, n) its covariance; std_m : (T,)
        position standard deviation ``sqrt(trace(P_pos) / 2)``, m; confirmed : (T,) after this
        scan's confirmations; confirmed_new : (T,) confirmed by this scan
    kept : (T,) bool, still in the store
    end_reason : (T,) int8, the :class:`TrackEnd` of each deleted track, -1 where kept
    confirmed_now, deleted_coast, deleted_covariance, deleted_unconfirmed : int
        Counts as in :class:`TrackerCounts`.
    """

    id: IntArray
    x: FloatArray
    P: FloatArray
    std_m: FloatArray
    confirmed: BoolArray
    confirmed_new: BoolArray
    kept: BoolArray
    end_reason: Int8Array
    confirmed_now: int
    deleted_coast: int
    deleted_covariance: int
    deleted_unconfirmed: int

    def __post_init__(self) -> None:
        freeze_arrays(self)


def manage(store: TrackStore, hit: BoolArray, t_s: float, config: TrackerConfig) -> Management:
    """Stage 5: count the hits, confirm (M-of-N in time), delete (coast, covariance, age).

    ``hit (T,)`` marks the tracks updated at ``t_s``. A tentative track is confirmed once it
    has ``confirm_hits`` hits within ``confirm_window_s`` of its birth and dropped when that
    window has passed; any track is deleted after ``max_coast_s`` without a hit or when its
    position standard deviation exceeds ``max_position_std_m``. ``store`` changes in place.
    """
    store.hits[hit] += 1
    store.last_s[hit] = t_s
    new_conf = (
        ~store.confirmed
        & (store.hits >= config.confirm_hits)
        & (t_s - store.born_s <= config.confirm_window_s)
    )
    store.confirmed |= new_conf
    xc, Pc = store.combined()
    pos = list(config.motion.position_index)
    std = np.sqrt(0.5 * Pc[:, pos, pos].sum(axis=-1))  # (the trace of the position block)
    coast = t_s - store.last_s > config.max_coast_s
    cov = std > config.max_position_std_m
    conf = store.confirmed.copy()
    unconf = ~conf & (t_s - store.born_s > config.confirm_window_s)
    gone = coast | cov | unconf
    n_gone = np.count_nonzero(gone)
    reason = np.full(gone.shape, -1, dtype=np.int8)
    if n_gone:
        reason[gone & conf & cov] = TrackEnd.COVARIANCE
        reason[gone & conf & coast] = TrackEnd.COAST
        reason[gone & ~conf] = TrackEnd.UNCONFIRMED
    out = Management(
        store.id.copy(),
        np.array(xc),
        np.array(Pc),
        std,
        conf,
        new_conf & ~gone,
        ~gone,
        reason,
        int(np.count_nonzero(new_conf)),
        int(np.count_nonzero(coast & conf)) if n_gone else 0,
        int(np.count_nonzero(cov & ~coast & conf)) if n_gone else 0,
        int(np.count_nonzero(gone & ~conf)) if n_gone else 0,
    )
    if n_gone:
        store.keep(~gone)
    return out


def _initial_covariance(
    motion: LinearMotion, var_p: float, var_v: float, cov_pv: float
) -> FloatArray:
    """``P0``: per axis position variance, velocity variance and their covariance; 1 m²/s⁴ for
    the accelerations of a CA model."""
    n = motion.dim_x
    P0 = np.zeros((n, n))
    for ip, iv in zip(motion.position_index, motion.velocity_index, strict=True):
        P0[ip, ip] = var_p
        P0[iv, iv] = var_v
        P0[ip, iv] = P0[iv, ip] = cov_pv
    if motion.order == 2:
        for ia in range(2, n, 3):
            P0[ia, ia] = 1.0
    return P0


def one_point_state(
    z: FloatArray, v: FloatArray, config: TrackerConfig
) -> tuple[FloatArray, FloatArray]:
    """Initial state from one position ``z (2,)`` (m) and a reported velocity ``v (2,)`` (m/s):
    variances ``sigma_m²`` and ``init_velocity_std_mps²``."""
    mot = config.motion
    x0 = np.zeros(mot.dim_x)
    x0[list(mot.position_index)] = z
    x0[list(mot.velocity_index)] = v
    return x0, _initial_covariance(mot, config.sigma_m**2, config.init_velocity_std_mps**2, 0.0)


def two_point_state(
    z: FloatArray, z_seed: FloatArray, dt: float, config: TrackerConfig
) -> tuple[FloatArray, FloatArray]:
    """Initial state from two positions ``dt`` seconds apart (Blackman & Popoli 1999, 4):
    velocity ``(z - z_seed) / dt``, variance ``2σ²/dt²`` and position-velocity covariance
    ``σ²/dt``, each capped for short ``dt`` (``init_max_speed_mps²``; correlation <= 1)."""
    mot = config.motion
    sig2 = config.sigma_m**2
    x0 = np.zeros(mot.dim_x)
    x0[list(mot.position_index)] = z
    x0[mot.velocity_index[0]], x0[mot.velocity_index[1]] = (z - z_seed) / dt
    var_v = min(2 * sig2 / dt**2, config.init_max_speed_mps**2)
    cov_pv = min(sig2 / dt, np.sqrt(var_v) * config.sigma_m)
    return x0, _initial_covariance(mot, sig2, var_v, cov_pv)


@dataclass(frozen=True, slots=True, eq=False)
class Initiation:
    """Outcome of :func:`initiate` for the ``k`` candidate detections.

    Attributes
    ----------
    track : (k,) id of the track each detection started (``-1``: it became a seed)
    status : (k,) int8 :class:`DetStatus` (``STARTED`` or ``SEED``)
    seed_det, seed_track : (p,) detection index of each seed used as a first point, and the id
        of the track it started
    """

    track: IntArray
    status: Int8Array
    seed_det: IntArray
    seed_track: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def initiate(
    store: TrackStore,
    seeds: Seeds,
    t_s: float,
    z: FloatArray,
    velocity: FloatArray,
    det: IntArray,
    config: TrackerConfig,
    det_t_s: FloatArray | None = None,
) -> Initiation:
    """Stage 6: start tracks from the detections ``z (k, 2)`` that no track claimed.

    A detection with a finite reported ``velocity`` starts a track alone (one hit); otherwise
    it is paired with the nearest seed reachable at ``init_max_speed_mps`` (plus 3σ) and both
    start a track (two hits), or it becomes a seed. Seeds older than ``init_max_dt_s`` are
    forgotten first. ``det (k,)`` are the detections' indices, kept with the seeds. ``store``
    and ``seeds`` change in place.

    ``det_t_s (k,)``: the detections' own times when they are a window of reports before
    ``t_s`` (default ``t_s``); seeds keep their own time, and a new state is predicted from
    its detection's time to ``t_s`` (without process noise).
    """
    seeds.prune(t_s, config.init_max_dt_s)
    k = z.shape[0]
    tj = np.full(k, t_s) if det_t_s is None else np.asarray(det_t_s, dtype=float)
    track = np.full(k, -1, dtype=np.int64)
    status = np.full(k, DetStatus.SEED, dtype=np.int8)
    seed_det: list[int] = []
    seed_track: list[int] = []
    F = config.motion.F

    def born(x0: FloatArray, P0: FloatArray, t0: float, hits: int) -> int:
        if t0 != t_s:
            Fk = F(t_s - t0)
            x0, P0 = Fk @ x0, Fk @ P0 @ Fk.T
        return store.add(x0, P0, t_s, hits=hits)

    for j in range(k):
        if np.all(np.isfinite(velocity[j])):
            x0, P0 = one_point_state(z[j], velocity[j], config)
            track[j] = born(x0, P0, tj[j], 1)
            status[j] = DetStatus.STARTED
            continue
        best = seeds.nearest(tj[j], z[j], config.init_max_speed_mps, 3 * config.sigma_m)
        if best < 0:
            seeds.add(tj[j], z[j], int(det[j]))
            continue
        ts, zs, dj = seeds.pop(best)
        x0, P0 = two_point_state(z[j], zs, tj[j] - ts, config)
        track[j] = born(x0, P0, tj[j], 2)
        status[j] = DetStatus.STARTED
        seed_det.append(dj)
        seed_track.append(int(track[j]))
    return Initiation(
        track, status, np.array(seed_det, dtype=np.int64), np.array(seed_track, dtype=np.int64)
    )


def report(
    store: TrackStore, now_s: float, t_s: float, motion: LinearMotion, max_coast_s: float
) -> tuple[IntArray, FloatArray]:
    """Ids ``(k,)`` and positions ``(k, 2)`` (m) of the confirmed tracks, predicted from their
    last scan at ``now_s`` to ``t_s >= now_s`` without noise. A track without an update for
    longer than ``max_coast_s`` at ``t_s`` is not reported: the next scan deletes it, and when
    no report comes for a long time (a quiet night at an airfield) that scan may be hours
    later."""
    c = store.confirmed & (t_s - store.last_s <= max_coast_s)
    xc, _ = store.combined()
    xg = xc[c] @ motion.F(t_s - now_s).T
    return store.id[c], xg[:, list(motion.position_index)]


class EndedTracks:
    """Confirmed tracks that ended by coasting or by their covariance, each with its state and
    covariance at its end, waiting for a new track to continue them (:func:`continuation`)."""

    def __init__(self, dim_x: int) -> None:
        self.id = np.zeros(0, dtype=np.int64)
        self.t_s = np.zeros(0)
        self.x = np.zeros((0, dim_x))
        self.P = np.zeros((0, dim_x, dim_x))

    def add(self, m: Management, t_s: float) -> None:
        """The confirmed tracks of ``m`` deleted for coasting or covariance at ``t_s``."""
        lost = ~m.kept & m.confirmed & (m.end_reason != TrackEnd.UNCONFIRMED)
        if lost.any():
            self.id = np.concatenate([self.id, m.id[lost]])
            self.t_s = np.concatenate([self.t_s, np.full(int(lost.sum()), t_s)])
            self.x = np.concatenate([self.x, m.x[lost]])
            self.P = np.concatenate([self.P, m.P[lost]])

    def remove(self, k: IntArray) -> None:
        """Forget the ended tracks ``k``."""
        keep = np.ones(self.id.size, dtype=bool)
        keep[k] = False
        self.keep(keep)

    def keep(self, keep: BoolArray) -> None:
        """Keep the ended tracks where ``keep`` is True."""
        self.id, self.t_s, self.x, self.P = (
            self.id[keep],
            self.t_s[keep],
            self.x[keep],
            self.P[keep],
        )


def continuation(
    ended: EndedTracks, x: FloatArray, P: FloatArray, t_s: float, model: TrackerModel
) -> IntArray:
    """(k,) id of the ended track that each newly confirmed track continues, -1.

    A target that goes unreported for longer than its track can coast comes back as a new
    track (track fragmentation after gaps). Each ended track is predicted from its end to
    ``t_s`` with the motion model (the last of an IMM's, the most manoeuvrable) and compared
    with each new track's state ``x (k, n)``, ``P (k, n, n)`` over the whole state (position
    and velocity): ``Δ = x - x_end``, ``S = P + P_end`` with the prediction ``x_end``,
    ``P_end``. An ended track whose predicted position standard deviation exceeds
    ``config.max_position_std_m`` (the widest a live track may be) continues nothing. A pair
    is a continuation when ``Δ`` lies inside the chi-square gate of ``S``
    (``config.gate_probability``, ``n`` degrees of freedom) and each of the two is the
    other's likeliest partner by ``log N(Δ; 0, S)``, which does not favour an old track for
    the width of its prediction. ``ended`` forgets the tracks continued and those too wide
    to continue any; the caller gives the new track the ended track's id (track segment
    association, as in Yeom, Kirubarajan & Bar-Shalom 2004, with a mutual-best rule in
    place of their assignment).
    """
    k, E = x.shape[0], ended.id.size
    link = np.full(k, -1, dtype=np.int64)
    if not (k and E):
        return link
    motion = model.motions[-1]
    n = x.shape[1]
    xe = np.empty((E, n))
    Pe = np.empty((E, n, n))
    for e in range(E):
        F = motion.F(t_s - ended.t_s[e])
        xe[e] = F @ ended.x[e]
        Pe[e] = F @ ended.P[e] @ F.T + motion.Q(t_s - ended.t_s[e])
    d = x[:, None, :] - xe[None, :, :]  # (k, E, n)
    S = P[:, None] + Pe[None, :]
    Si = np.linalg.inv(S)
    d2 = np.einsum("kei,keij,kej->ke", d, Si, d)
    _sign, logdet = np.linalg.slogdet(S)
    pos = list(model.config.motion.position_index)
    std_e = np.sqrt(0.5 * Pe[:, pos, pos].sum(axis=-1))
    inside = (d2 <= chi2_threshold(model.config.gate_probability, n)) & (
        std_e <= model.config.max_position_std_m
    )
    ll = np.where(inside, -0.5 * (d2 + logdet), -np.inf)
    best_e = np.argmax(ll, axis=1)
    best_k = np.argmax(ll, axis=0)
    ok = np.isfinite(ll[np.arange(k), best_e]) & (best_k[best_e] == np.arange(k))
    link[ok] = ended.id[best_e[ok]]
    keep = std_e <= model.config.max_position_std_m  # (their predictions only widen)
    keep[best_e[ok]] = False
    ended.keep(keep)
    return link
