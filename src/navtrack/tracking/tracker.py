"""Multi-target tracker for real data: GNN or JPDA association with track management.

The driver :func:`run_tracker` takes time-ordered 2-D position detections (local east/north, m)
and runs, per scan (detections sharing one time stamp):

1. prediction of every track to the scan time (linear motion model, batched KF);
2. gating (chi-square, with a k-d tree pre-gate when there are many pairs);
3. association: GNN (optimal 2-D assignment with missed-detection costs, :func:`assign2d`) or
   JPDA (:func:`jpda_marginals`, then the PDA update);
4. management: tentative tracks are confirmed after ``confirm_hits`` updates within
   ``confirm_window_s`` of their birth (the M-of-N rule written in time, so it applies to
   irregular report times as well as to regular scans) and dropped otherwise; tracks are
   deleted after ``max_coast_s`` without update or when their position standard deviation
   exceeds ``max_position_std_m``;
5. initiation: a detection inside no track's gate is paired with an earlier such detection
   ("seed") reachable at ``init_max_speed_mps`` within ``init_max_dt_s`` (two-point
   initiation: position and velocity from the two points); otherwise it becomes a seed.

Track ids are integers given at birth and never reused. Every detection's fate is recorded
(``det_status``) so nothing is dropped silently.

References
----------
.. [1] S. S. Blackman, R. Popoli, *Design and Analysis of Modern Tracking Systems*, Artech
   House 1999, chapter 6 (GNN), 3.3 (M-of-N confirmation) and 4 (two-point initiation).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.tracking.models import LinearMotion, constant_velocity

__all__ = [
    "DET_CONFIRMED",
    "DET_SEED",
    "DET_STARTED",
    "DET_TENTATIVE",
    "DET_UNUSED",
    "TrackerConfig",
    "TrackerResult",
    "run_tracker",
]

# det_status values
DET_CONFIRMED = 0  # updated a confirmed track
DET_TENTATIVE = 1  # updated a tentative track
DET_STARTED = 2  # second point of a two-point initiation (started a tentative track)
DET_SEED = 3  # kept as a seed for initiation (never paired)
DET_UNUSED = 4  # inside a gate but not associated (GNN loser / JPDA low probability)
DET_STATUS_NAMES = ("confirmed", "tentative", "started", "seed", "unused")


@dataclass(frozen=True, slots=True)
class TrackerConfig:
    """Tracker parameters (SI units).

    ``init_from``: which detections may start tracks: those inside no track's gate, or all
    that were not associated (GNN: unassigned; JPDA: summed association probability < 0.5).

    ``imm_q``: process-noise levels of an IMM of motion models sharing ``motion``'s form (e.g.
    ``(1e-5, 1e-2)`` for moored and manoeuvring ships); ``None`` = a single model with
    ``motion.q``. ``imm_sojourn_s``: mean time spent in a model; over a step ``dt`` the model is
    left with probability ``1 - exp(-dt / imm_sojourn_s)`` (a continuous-time Markov chain, so
    irregular report times switch models at the same rate as regular scans).

    The defaults suit ships (AIS); :meth:`for_aircraft` gives ADS-B values.
    """

    motion: LinearMotion = field(default_factory=lambda: constant_velocity(2, 0.05, "continuous"))
    sigma_m: float = 25.0
    associator: Literal["gnn", "jpda"] = "gnn"
    pd: float = 0.9
    clutter_density: float = 1e-9
    gate_probability: float = 0.9999
    init_max_speed_mps: float = 30.0
    init_max_dt_s: float = 400.0
    confirm_hits: int = 3
    confirm_window_s: float = 900.0
    max_coast_s: float = 600.0
    max_position_std_m: float = 2000.0
    max_exact_bits: int = 20
    k_best: int = 1000
    pregate_pairs: int = 4000
    init_from: Literal["outside_gates", "unassociated"] = "outside_gates"
    init_velocity_std_mps: float = 1.0
    imm_q: tuple[float, ...] | None = None
    imm_sojourn_s: float = 300.0

    def __post_init__(self) -> None:
        if self.motion.ndim != 2:
            raise ValueError("the tracker works on 2-D (east, north) positions: motion.ndim = 2")
        if self.init_from not in ("outside_gates", "unassociated"):
            raise ValueError(
                f"init_from must be 'outside_gates' or 'unassociated', got {self.init_from!r}"
            )
        if self.associator not in ("gnn", "jpda"):
            raise ValueError(f"associator must be 'gnn' or 'jpda', got {self.associator!r}")
        for name in (
            "sigma_m",
            "clutter_density",
            "init_max_speed_mps",
            "init_max_dt_s",
            "init_velocity_std_mps",
            "confirm_window_s",
            "max_coast_s",
            "max_position_std_m",
        ):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not 0 < self.pd < 1:
            raise ValueError(f"pd must be in (0, 1), got {self.pd}")
        if self.imm_q is not None and (len(self.imm_q) < 2 or min(self.imm_q) < 0):
            raise ValueError(f"imm_q must hold >= 2 values >= 0, got {self.imm_q}")
        if not (np.isfinite(self.imm_sojourn_s) and self.imm_sojourn_s > 0):
            raise ValueError(f"imm_sojourn_s must be finite and > 0, got {self.imm_sojourn_s}")
        if self.confirm_hits < 2:
            raise ValueError(f"confirm_hits must be >= 2, got {self.confirm_hits}")

    @staticmethod
    def for_ships(associator: Literal["gnn", "jpda"] = "gnn") -> TrackerConfig:
        """AIS ships: IMM of moored (q = 1e-5 m²/s³) and manoeuvring (1e-2) CV models,
        σ = 25 m, λ = 1e-6 /m² (harbours: other ships rather than clutter compete for a
        report), tracks started from unassociated reports, 3 updates within 15 min to confirm,
        coast 10 min. Values tuned on the Solent file (moored ships report every 3 min, moving
        ones every 2-10 s)."""
        return TrackerConfig(
            associator=associator,
            imm_q=(1e-5, 1e-2),
            confirm_hits=3,
            clutter_density=1e-6,
            init_from="unassociated",
        )

    @staticmethod
    def for_aircraft(associator: Literal["gnn", "jpda"] = "gnn") -> TrackerConfig:
        """Aircraft at 10 s reports: q = 300 m²/s³ (turns at a few m/s²), σ = 50 m, 350 m/s,
        coast 60 s (values tuned on the OpenSky file)."""
        return TrackerConfig(
            motion=constant_velocity(2, 300.0, "continuous"),
            sigma_m=50.0,
            associator=associator,
            pd=0.95,
            clutter_density=1e-10,
            init_max_speed_mps=350.0,
            init_max_dt_s=60.0,
            confirm_hits=3,
            confirm_window_s=60.0,
            max_coast_s=60.0,
            max_position_std_m=5000.0,
        )


@dataclass(frozen=True, slots=True, eq=False)
class TrackerResult:
    """Tracker output (arrays read-only).

    Attributes
    ----------
    det_track : (N,) int
        Id of the track each detection updated or started (``-1`` none).
    det_status : (N,) int8
        Fate of each detection: 0 confirmed-track update, 1 tentative-track update, 2 started a
        track, 3 seed never paired, 4 gated but not associated.
    track_time_s, track_id, track_x, track_std_m, track_confirmed :
        One row per track update: time (s), id, state ``[x, vx, y, vy]`` (m, m/s), position
        standard deviation ``sqrt(trace(P_pos)/2)`` (m), confirmed flag.
    report_frame, report_id, report_xy :
        Confirmed tracks predicted to each requested report time (index into
        ``report_times``), for scoring.
    counts : dict
        ``scans``, ``tracks_started``, ``tracks_confirmed``, ``deleted_coast``,
        ``deleted_covariance``, ``deleted_unconfirmed``, ``jpda_exact_clusters``,
        ``jpda_kbest_clusters``, ``seconds``.
    """

    det_track: IntArray
    det_status: np.ndarray
    track_time_s: FloatArray
    track_id: IntArray
    track_x: FloatArray
    track_std_m: FloatArray
    track_confirmed: np.ndarray
    report_frame: IntArray
    report_id: IntArray
    report_xy: FloatArray
    counts: dict[str, float]

    def __post_init__(self) -> None:
        freeze_arrays(self)


class _Tracks:
    """Mutable per-run track store (private to the driver); model axis ``r`` for the IMM."""

    def __init__(self, n: int, r: int) -> None:
        self.x = np.zeros((0, r, n))
        self.P = np.zeros((0, r, n, n))
        self.mu = np.zeros((0, r))
        self.id = np.zeros(0, dtype=np.int64)
        self.confirmed = np.zeros(0, dtype=bool)
        self.hits = np.zeros(0, dtype=np.int64)
        self.born = np.zeros(0)
        self.last = np.zeros(0)

    def keep(self, k: np.ndarray) -> None:
        for name in ("x", "P", "mu", "id", "confirmed", "hits", "born", "last"):
            setattr(self, name, getattr(self, name)[k])

    def add(self, x: FloatArray, P: FloatArray, tid: int, t: float, hits: int = 2) -> None:
        r = self.mu.shape[1]
        self.x = np.concatenate([self.x, np.broadcast_to(x, (1, r, x.size))])
        self.P = np.concatenate([self.P, np.broadcast_to(P, (1, r, *P.shape))])
        self.mu = np.concatenate([self.mu, np.full((1, r), 1.0 / r)])
        self.id = np.append(self.id, tid)
        self.confirmed = np.append(self.confirmed, False)
        self.hits = np.append(self.hits, hits)
        self.born = np.append(self.born, t)
        self.last = np.append(self.last, t)

    def combined(self) -> tuple[FloatArray, FloatArray]:
        from navtrack.tracking.imm import imm_combine

        if self.mu.shape[1] == 1:
            return self.x[:, 0], self.P[:, 0]
        return imm_combine(self.x, self.P, self.mu)


def run_tracker(
    t_s: ArrayLike,
    z: ArrayLike,
    config: TrackerConfig | None = None,
    report_times: ArrayLike | None = None,
    velocity: ArrayLike | None = None,
) -> TrackerResult:
    """Track 2-D position detections.

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

    Raises
    ------
    ValueError
        Times not non-decreasing (the first offending index is named), non-finite values.
    """
    from navtrack.tracking.assignment import assign2d
    from navtrack.tracking.gating import chi2_threshold, gate, kdtree_pregate
    from navtrack.tracking.imm import imm_mix, imm_model_probabilities, markov_matrix
    from navtrack.tracking.jpda import (
        METHOD_EXACT,
        METHOD_KBEST,
        JpdaConfig,
        association_weights,
        jpda_marginals,
        pda_update,
    )
    from navtrack.tracking.kalman import kf_predict

    cfg = config or TrackerConfig()
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
    rep = np.zeros(0) if report_times is None else np.asarray(report_times, dtype=float)
    V = np.full((t.size, 2), np.nan) if velocity is None else np.asarray(velocity, dtype=float)
    if V.shape != (t.size, 2):
        raise ValueError(f"velocity must be (N, 2) like z, got {V.shape}")
    clock = time.perf_counter()
    mot = cfg.motion
    n = mot.dim_x
    pos = list(mot.position_index)
    qs = (mot.q,) if cfg.imm_q is None else tuple(cfg.imm_q)
    models = [LinearMotion(mot.ndim, mot.order, q, mot.noise) for q in qs]
    r = len(models)
    R = np.eye(2) * cfg.sigma_m**2
    gamma = chi2_threshold(cfg.gate_probability, 2)
    jcfg = JpdaConfig(
        cfg.pd, cfg.clutter_density, cfg.gate_probability, cfg.max_exact_bits, cfg.k_best
    )
    log_miss = np.log1p(-cfg.pd * cfg.gate_probability)
    log_det_gain = np.log(cfg.pd) - np.log(cfg.clutter_density)

    N = t.size
    det_track = np.full(N, -1, dtype=np.int64)
    det_status = np.full(N, DET_SEED, dtype=np.int8)
    tr = _Tracks(n, r)
    seeds_t: list[float] = []
    seeds_z: list[FloatArray] = []
    seeds_i: list[int] = []
    next_id = 0
    counts = dict.fromkeys(
        (
            "scans",
            "tracks_started",
            "tracks_confirmed",
            "deleted_coast",
            "deleted_covariance",
            "deleted_unconfirmed",
            "jpda_exact_clusters",
            "jpda_kbest_clusters",
        ),
        0.0,
    )
    log_t: list[FloatArray] = []
    log_id: list[IntArray] = []
    log_x: list[FloatArray] = []
    log_std: list[FloatArray] = []
    log_conf: list[np.ndarray] = []
    rep_f: list[IntArray] = []
    rep_id: list[IntArray] = []
    rep_xy: list[FloatArray] = []
    r_next = 0
    now = t[0] if N else 0.0

    def report_until(limit: float, inclusive: bool) -> None:
        nonlocal r_next
        while r_next < rep.size and (rep[r_next] < limit or (inclusive and rep[r_next] <= limit)):
            g = rep[r_next]
            if g >= now:
                c = tr.confirmed
                xc, _ = tr.combined()
                xg = xc[c] @ mot.F(g - now).T
                rep_f.append(np.full(int(c.sum()), r_next, dtype=np.int64))
                rep_id.append(tr.id[c])
                rep_xy.append(xg[:, pos])
            r_next += 1

    starts = np.flatnonzero(np.r_[True, np.diff(t) > 0]) if N else np.zeros(0, dtype=np.int64)
    ends = np.r_[starts[1:], N].astype(np.int64) if N else np.zeros(0, dtype=np.int64)
    for s0, s1 in zip(starts, ends, strict=True):
        tk = t[s0]
        report_until(tk, inclusive=False)
        counts["scans"] += 1
        Zk = Z[s0:s1]
        M = Zk.shape[0]
        # 1. predict (IMM: mix, then predict every model)
        dt = tk - now
        T = tr.id.size
        c_pred = tr.mu
        if dt > 0 and T:
            if r > 1:
                Pi = markov_matrix(r, -np.expm1(-dt / cfg.imm_sojourn_s))
                x0, P0, c_pred = imm_mix(tr.x, tr.P, tr.mu, Pi)
            else:
                x0, P0 = tr.x, tr.P
            Fm = mot.F(dt)
            Qm = np.stack([m.Q(dt) for m in models])
            tr.x, tr.P = kf_predict(x0, P0, Fm, Qm)
            tr.mu = c_pred
        now = tk
        gated_any = np.zeros(M, dtype=bool)
        used = np.zeros(M, dtype=bool)
        claimed = np.zeros(M, dtype=bool)  # detections not available for initiation
        if T:
            # 2. gate every model; a pair is valid if inside some model's gate
            zp = tr.x[..., pos].reshape(T * r, 2)
            Pzz = tr.P[..., pos, :][..., pos].reshape(T * r, 2, 2)
            S = Pzz + R
            cand = kdtree_pregate(zp, S, Zk, gamma) if cfg.pregate_pairs < T * r * M else None
            g = gate(zp, S, Zk, gamma, candidates=cand)
            valid = g.valid.reshape(T, r, M).any(axis=1)
            ll_rm = g.log_likelihood().reshape(T, r, M)
            ll_rm = np.where(np.isfinite(ll_rm), ll_rm, -1e300)
            # mixture likelihood over models with the predicted model probabilities
            logc = np.log(np.where(c_pred > 0, c_pred, 1e-300))[:, :, None]
            a = logc + ll_rm
            amax = a.max(axis=1, keepdims=True)
            ll_mix = (amax + np.log(np.exp(a - amax).sum(axis=1, keepdims=True)))[:, 0]
            gated_any = np.asarray(valid.any(axis=0), dtype=bool)
            PHt = tr.P[..., :, pos].reshape(T * r, n, 2)
            K = np.swapaxes(np.linalg.solve(S, np.swapaxes(PHt, -1, -2)), -1, -2)
            S4 = S.reshape(T, r, 2, 2)
            K4 = K.reshape(T, r, n, 2)
            y4 = g.innovation.reshape(T, r, M, 2)
            hit = np.zeros(T, dtype=bool)
            # 3. associate
            if cfg.associator == "gnn":
                cost = np.where(valid, -(ll_mix + log_det_gain), np.inf)
                a_t = assign2d(cost, -log_miss).track_to_meas
                hit = a_t >= 0
                if hit.any():
                    ti = np.flatnonzero(hit)
                    y = y4[ti, :, a_t[ti]]  # (h, r, 2)
                    Kt = K4[ti]
                    tr.x[ti] = tr.x[ti] + np.einsum("hrij,hrj->hri", Kt, y)
                    Pn = tr.P[ti] - Kt @ S4[ti] @ np.swapaxes(Kt, -1, -2)
                    tr.P[ti] = 0.5 * (Pn + np.swapaxes(Pn, -1, -2))
                    if r > 1:
                        tr.mu[ti] = imm_model_probabilities(c_pred[ti], ll_rm[ti, :, a_t[ti]])
                    det_track[s0 + a_t[ti]] = tr.id[ti]
                    used[a_t[ti]] = True
                claimed = used.copy() if cfg.init_from == "unassociated" else gated_any
            else:
                W = association_weights(
                    ll_mix, valid, cfg.pd, cfg.gate_probability, cfg.clutter_density
                )
                jm = jpda_marginals(W, jcfg)
                beta = jm.beta
                active = np.flatnonzero(beta[:, 0] < 1.0)
                if active.size:
                    b_r = np.broadcast_to(beta[active, None, :], (active.size, r, M + 1))
                    xa, Pa = pda_update(
                        tr.x[active], tr.P[active], y4[active], S4[active], K4[active], b_r
                    )
                    tr.x[active], tr.P[active] = xa, Pa
                    if r > 1:
                        # model likelihood: missed term plus each measurement's likelihood
                        # ratio against the mixture (Blom & Bloem 2000, IMM-JPDA)
                        ratio = np.exp(ll_rm[active] - ll_mix[active][:, None, :])
                        lam_r = beta[active, None, 0] + np.einsum(
                            "tj,trj->tr", beta[active, 1:], ratio
                        )
                        tr.mu[active] = imm_model_probabilities(
                            c_pred[active], np.log(np.maximum(lam_r, 1e-300))
                        )
                hit = beta[:, 0] < 0.5
                for key, code in (
                    ("jpda_exact_clusters", METHOD_EXACT),
                    ("jpda_kbest_clusters", METHOD_KBEST),
                ):
                    counts[key] += len(np.unique(jm.cluster[jm.method == code]))
                if M:
                    best_t = np.argmax(beta[:, 1:], axis=0)
                    best_b = beta[best_t, 1 + np.arange(M)]
                    ok = best_b >= 0.5
                    det_track[s0 + np.flatnonzero(ok)] = tr.id[best_t[ok]]
                    used[ok] = True
                claimed = (
                    beta[:, 1:].sum(axis=0) >= 0.5 if cfg.init_from == "unassociated" else gated_any
                )
            # 4. manage
            tr.hits[hit] += 1
            tr.last[hit] = tk
            upd = np.flatnonzero(hit)
            for j in np.flatnonzero(used):
                k = np.flatnonzero(tr.id == det_track[s0 + j])[0]
                det_status[s0 + j] = DET_CONFIRMED if tr.confirmed[k] else DET_TENTATIVE
            new_conf = (
                ~tr.confirmed
                & (tr.hits >= cfg.confirm_hits)
                & (tk - tr.born <= cfg.confirm_window_s)
            )
            counts["tracks_confirmed"] += int(new_conf.sum())
            tr.confirmed |= new_conf
            xc, Pc = tr.combined()
            if upd.size:
                log_t.append(np.full(upd.size, tk))
                log_id.append(tr.id[upd])
                log_x.append(xc[upd])
                Pp = Pc[upd][:, pos][:, :, pos]
                log_std.append(np.sqrt(0.5 * np.trace(Pp, axis1=-2, axis2=-1)))
                log_conf.append(tr.confirmed[upd])
            det_status[s0 + np.flatnonzero(gated_any & ~used)] = DET_UNUSED
            std = np.sqrt(0.5 * np.trace(Pc[:, pos][:, :, pos], axis1=-2, axis2=-1))
            coast = tk - tr.last > cfg.max_coast_s
            cov = std > cfg.max_position_std_m
            unconf = ~tr.confirmed & (tk - tr.born > cfg.confirm_window_s)
            counts["deleted_coast"] += int((coast & tr.confirmed).sum())
            counts["deleted_covariance"] += int((cov & ~coast & tr.confirmed).sum())
            counts["deleted_unconfirmed"] += int((~tr.confirmed & (coast | cov | unconf)).sum())
            tr.keep(~(coast | cov | unconf))
        # 5. initiate from detections inside no gate
        if seeds_t:
            keep = [i for i, ts in enumerate(seeds_t) if tk - ts <= cfg.init_max_dt_s]
            seeds_t = [seeds_t[i] for i in keep]
            seeds_z = [seeds_z[i] for i in keep]
            seeds_i = [seeds_i[i] for i in keep]
        for j in np.flatnonzero(~claimed):
            vj = V[s0 + j]
            if np.all(np.isfinite(vj)):
                x0 = np.zeros(n)
                x0[pos] = Zk[j]
                x0[list(mot.velocity_index)] = vj
                P0 = np.zeros((n, n))
                P0[pos, pos] = cfg.sigma_m**2
                vix = list(mot.velocity_index)
                P0[vix, vix] = cfg.init_velocity_std_mps**2
                if mot.order == 2:
                    for ia in range(2, n, 3):
                        P0[ia, ia] = 1.0
                tr.add(x0, P0, next_id, tk, hits=1)
                det_track[s0 + j] = next_id
                det_status[s0 + j] = DET_STARTED
                next_id += 1
                counts["tracks_started"] += 1
                continue
            best = -1
            best_d = np.inf
            for si, (ts, zs) in enumerate(zip(seeds_t, seeds_z, strict=True)):
                dts = tk - ts
                if dts <= 0:
                    continue
                d = float(np.hypot(*(Zk[j] - zs)))
                if d <= cfg.init_max_speed_mps * dts + 3 * cfg.sigma_m and d < best_d:
                    best, best_d = si, d
            if best < 0:
                det_status[s0 + j] = DET_SEED
                seeds_t.append(tk)
                seeds_z.append(Zk[j])
                seeds_i.append(int(s0 + j))
                continue
            dts = tk - seeds_t[best]
            v = (Zk[j] - seeds_z[best]) / dts
            x0 = np.zeros(n)
            x0[pos] = Zk[j]
            x0[mot.velocity_index[0]], x0[mot.velocity_index[1]] = v
            P0 = np.zeros((n, n))
            var_v = min(2 * cfg.sigma_m**2 / dts**2, cfg.init_max_speed_mps**2)
            cov_pv = min(cfg.sigma_m**2 / dts, np.sqrt(var_v) * cfg.sigma_m)
            for ax in range(2):
                ip, iv = pos[ax], mot.velocity_index[ax]
                P0[ip, ip] = cfg.sigma_m**2
                P0[iv, iv] = var_v
                P0[ip, iv] = P0[iv, ip] = cov_pv
            if mot.order == 2:
                for ia in range(2, n, 3):
                    P0[ia, ia] = 1.0
            tr.add(x0, P0, next_id, tk)
            det_track[s0 + j] = next_id
            det_track[seeds_i[best]] = next_id
            det_status[s0 + j] = DET_STARTED
            det_status[seeds_i[best]] = DET_STARTED
            next_id += 1
            counts["tracks_started"] += 1
            del seeds_t[best], seeds_z[best], seeds_i[best]
    report_until(now, inclusive=True)
    counts["seconds"] = time.perf_counter() - clock

    def cat(parts: list, shape: tuple[int, ...], dtype: type) -> np.ndarray:
        return np.concatenate(parts) if parts else np.zeros(shape, dtype=dtype)

    return TrackerResult(
        det_track,
        det_status,
        cat(log_t, (0,), float),
        cat(log_id, (0,), np.int64),
        cat(log_x, (0, n), float),
        cat(log_std, (0,), float),
        cat(log_conf, (0,), bool),
        cat(rep_f, (0,), np.int64),
        cat(rep_id, (0,), np.int64),
        cat(rep_xy, (0, 2), float),
        counts,
    )
