"""Multi-target tracker for real data: GNN or JPDA association with track management.

:func:`run_tracker` takes time-ordered 2-D position detections (local east/north, m) and runs,
per scan (detections sharing one time stamp), a chain of named stages over a
:class:`TrackStore` (the live tracks); each stage is importable on its own, so other trackers
(multisensor fusion, particle filters) can reuse them:

1. :func:`predict` every track to the scan time (IMM mixing, then the batched KF prediction of
   :mod:`navtrack.tracking.kalman`);
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
from dataclasses import dataclass, field
from enum import IntEnum
from functools import lru_cache
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, Int8Array, IntArray
from navtrack.tracking.jpda import JpdaConfig, JpdaMarginals
from navtrack.tracking.models import (
    LinearMeasurement,
    LinearMotion,
    MeasurementModel,
    constant_velocity,
    linear_position,
)

__all__ = [
    "DET_STATUS_NAMES",
    "TRACK_END_NAMES",
    "DetStatus",
    "Initiation",
    "Management",
    "ScanAssociation",
    "ScanGate",
    "Seeds",
    "TrackEnd",
    "TrackStore",
    "TrackerConfig",
    "TrackerCounts",
    "TrackerModel",
    "TrackerResult",
    "associate",
    "associate_gnn",
    "associate_jpda",
    "gate_edge_log_density",
    "gate_scan",
    "initiate",
    "manage",
    "one_point_state",
    "predict",
    "report",
    "run_tracker",
    "scan_windows",
    "two_point_state",
    "update",
    "window_separation_m",
]


class DetStatus(IntEnum):
    """Fate of a detection (``TrackerResult.det_status``; names as the CLI prints them)."""

    CONFIRMED = 0  # updated a confirmed track
    TENTATIVE = 1  # updated a tentative track
    STARTED = 2  # started a track (one-point, or either point of a two-point initiation)
    SEED = 3  # kept as a seed for initiation (never paired)
    UNUSED = 4  # inside a gate but not associated (GNN loser / JPDA low probability)


DET_STATUS_NAMES = tuple(s.name.lower() for s in DetStatus)


class TrackEnd(IntEnum):
    """Why a track ended (``TrackerResult.end_reason``; names as written in the track table)."""

    COAST = 0  # no update for longer than ``max_coast_s``
    COVARIANCE = 1  # position standard deviation above ``max_position_std_m``
    UNCONFIRMED = 2  # tentative, not confirmed within ``confirm_window_s``
    END_OF_DATA = 3  # alive after the last detection


TRACK_END_NAMES = tuple(s.name.lower() for s in TrackEnd)


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

    ``scan_window_s``: reports at distinct times within this span are processed as one scan
    (:func:`scan_windows`); 0 = one scan per distinct time.

    ``gnn_density_at_gate``: GNN only. False: one competing-report density
    ``clutter_density`` for every track. True: each track's own, the density at which a
    report on the edge of its gate ties a missed detection (:func:`gate_edge_log_density`,
    from the track's predicted innovation covariance), so that every report inside a gate
    is worth assigning; one λ from σ alone keeps a report only well inside the gate of a
    track whose prediction is uncertain (NIS below 3.7 against a gate at 18.4 for 10 s
    ADS-B reports), and the reports it leaves start duplicate tracks.

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
    scan_window_s: float = 0.0
    gnn_density_at_gate: bool = False

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
        if not (np.isfinite(self.scan_window_s) and self.scan_window_s >= 0):
            raise ValueError(f"scan_window_s must be finite and >= 0, got {self.scan_window_s}")
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
class TrackerModel:
    """What the stages need, derived once from a :class:`TrackerConfig`.

    Attributes
    ----------
    config : TrackerConfig
    motions : tuple of LinearMotion
        The ``r`` motion models (one, or the IMM's, sharing ``config.motion``'s form).
    measurement : MeasurementModel
        Measurement of the scans (the tracker: east/north position, ``sigma_m`` per axis).
    gamma : float
        Chi-square gate size for ``config.gate_probability`` and the measurement dimension.
    jpda : JpdaConfig
        JPDA parameters (``pd``, ``clutter_density``, ``gate_probability``, ``max_exact_bits``,
        ``k_best`` of the config).
    """

    config: TrackerConfig
    motions: tuple[LinearMotion, ...]
    measurement: MeasurementModel
    gamma: float
    jpda: JpdaConfig

    @property
    def q(self) -> FloatArray:
        """(r,) process-noise level of each motion model."""
        return np.array([m.q for m in self.motions])

    @staticmethod
    def from_config(config: TrackerConfig) -> TrackerModel:
        """Motion models, position measurement, gate size and JPDA parameters of ``config``."""
        from navtrack.tracking.gating import chi2_threshold

        mot = config.motion
        qs = (mot.q,) if config.imm_q is None else tuple(config.imm_q)
        meas = linear_position(mot.dim_x, mot.position_index, config.sigma_m)
        return TrackerModel(
            config,
            tuple(LinearMotion(mot.ndim, mot.order, q, mot.noise) for q in qs),
            meas,
            chi2_threshold(config.gate_probability, meas.dim_z),
            JpdaConfig(
                config.pd,
                config.clutter_density,
                config.gate_probability,
                config.max_exact_bits,
                config.k_best,
            ),
        )


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


@dataclass(frozen=True, slots=True, eq=False)
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
        ``report_times``), for scoring.
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


class TrackStore:
    """The live tracks of one run, in birth order: the mutable state the stages work on.

    The attributes are views of the first ``size`` rows of buffers whose capacity doubles when
    a birth finds them full, so ``T`` births cost ``O(T)`` copies in all (amortised growth)
    instead of a copy of every track at every birth. Writing into an attribute's rows writes
    into the store; :meth:`add` and :meth:`keep` change the set of tracks and re-slice the
    attributes (read them afresh after either: an older view may no longer be the store).

    Parameters
    ----------
    dim_x : int
        State dimension ``n``.
    n_models : int
        Motion models ``r`` per track (1, or the IMM's).
    capacity : int
        Rows allocated at the start.

    Attributes
    ----------
    size : int
        Live tracks ``T``.
    next_id : int
        Id the next birth gets.
    x : (T, r, n) model-conditioned states
    P : (T, r, n, n) model-conditioned covariances
    mu : (T, r) model probabilities
    id : (T,) int track ids, given at birth from ``next_id`` and never reused
    confirmed : (T,) bool
    hits : (T,) int updates counted for confirmation (the initiating points included)
    born_s, last_s : (T,) birth time and time of the last update, s
    """

    _FIELDS = ("x", "P", "mu", "id", "confirmed", "hits", "born_s", "last_s")

    x: FloatArray
    P: FloatArray
    mu: FloatArray
    id: IntArray
    confirmed: BoolArray
    hits: IntArray
    born_s: FloatArray
    last_s: FloatArray

    def __init__(self, dim_x: int, n_models: int = 1, capacity: int = 16) -> None:
        if dim_x < 1 or n_models < 1 or capacity < 1:
            raise ValueError(
                f"dim_x, n_models and capacity must be >= 1, got {dim_x}, {n_models}, {capacity}"
            )
        n, r = dim_x, n_models
        self.size = 0
        self.next_id = 0
        self._buf: dict[str, np.ndarray] = {
            "x": np.zeros((capacity, r, n)),
            "P": np.zeros((capacity, r, n, n)),
            "mu": np.zeros((capacity, r)),
            "id": np.zeros(capacity, dtype=np.int64),
            "confirmed": np.zeros(capacity, dtype=bool),
            "hits": np.zeros(capacity, dtype=np.int64),
            "born_s": np.zeros(capacity),
            "last_s": np.zeros(capacity),
        }
        self._views()

    @property
    def capacity(self) -> int:
        """Rows allocated (``>= size``)."""
        return int(self._buf["id"].shape[0])

    @property
    def n_models(self) -> int:
        """Motion models ``r`` per track."""
        return int(self._buf["mu"].shape[1])

    def _views(self) -> None:
        for name in self._FIELDS:
            setattr(self, name, self._buf[name][: self.size])

    def add(self, x: FloatArray, P: FloatArray, t_s: float, hits: int) -> int:
        """Append a tentative track with state ``x (n,)``, covariance ``P (n, n)`` in every model
        (equal model probabilities), born at ``t_s``; returns its id."""
        if self.size == self.capacity:
            for name, b in self._buf.items():
                grown = np.zeros((2 * b.shape[0], *b.shape[1:]), dtype=b.dtype)
                grown[: self.size] = b[: self.size]
                self._buf[name] = grown
        i = self.size
        tid = self.next_id
        buf = self._buf
        buf["x"][i] = x
        buf["P"][i] = P
        buf["mu"][i] = 1.0 / self.n_models
        buf["id"][i] = tid
        buf["confirmed"][i] = False
        buf["hits"][i] = hits
        buf["born_s"][i] = t_s
        buf["last_s"][i] = t_s
        self.size += 1
        self.next_id += 1
        self._views()
        return tid

    def keep(self, mask: BoolArray) -> None:
        """Keep the tracks where ``mask (T,)`` is True, in their order."""
        k = int(np.count_nonzero(mask))
        if k == self.size:
            return
        for b in self._buf.values():
            b[:k] = b[: self.size][mask]
        self.size = k
        self._views()

    def combined(self) -> tuple[FloatArray, FloatArray]:
        """Moment-matched state ``(T, n)`` and covariance ``(T, n, n)`` over the models."""
        from navtrack.tracking.imm import imm_combine

        if self.n_models == 1:
            return self.x[:, 0], self.P[:, 0]
        return imm_combine(self.x, self.P, self.mu)


class Seeds:
    """Unclaimed detections waiting for a partner (two-point initiation), oldest first."""

    def __init__(self) -> None:
        self.t_s: list[float] = []
        self.z: list[FloatArray] = []
        self.det: list[int] = []

    def __len__(self) -> int:
        return len(self.t_s)

    def prune(self, t_s: float, max_age_s: float) -> None:
        """Forget the seeds older than ``max_age_s`` at ``t_s``."""
        keep = [i for i, ts in enumerate(self.t_s) if t_s - ts <= max_age_s]
        self.t_s = [self.t_s[i] for i in keep]
        self.z = [self.z[i] for i in keep]
        self.det = [self.det[i] for i in keep]

    def nearest(self, t_s: float, z: FloatArray, max_speed_mps: float, slack_m: float) -> int:
        """Index of the nearest earlier seed within ``max_speed_mps · dt + slack_m``, or -1."""
        best = -1
        best_d = np.inf
        for si, (ts, zs) in enumerate(zip(self.t_s, self.z, strict=True)):
            dts = t_s - ts
            if dts <= 0:
                continue
            d = float(np.hypot(*(z - zs)))
            if d <= max_speed_mps * dts + slack_m and d < best_d:
                best, best_d = si, d
        return best

    def add(self, t_s: float, z: FloatArray, det: int) -> None:
        self.t_s.append(t_s)
        self.z.append(z)
        self.det.append(det)

    def pop(self, i: int) -> tuple[float, FloatArray, int]:
        return self.t_s.pop(i), self.z.pop(i), self.det.pop(i)


# ---------------------------------------------------------------------------------- stages


def predict(store: TrackStore, dt: float, model: TrackerModel) -> None:
    """Stage 1: predict every track of ``store`` (in place) over ``dt`` seconds.

    With several motion models the IMM interaction comes first, with the switching probability
    ``1 - exp(-dt / imm_sojourn_s)`` of a continuous-time Markov chain; then the KF prediction
    of every model (:func:`~navtrack.tracking.kalman.kf_predict`), and ``mu`` becomes the
    predicted model probabilities. Nothing happens for ``dt <= 0`` or an empty store.
    """
    from navtrack.estimation.kalman import kf_predict
    from navtrack.tracking.imm import imm_mix, markov_matrix

    if not (dt > 0 and store.size):
        return
    r = len(model.motions)
    if r > 1:
        Pi = markov_matrix(r, -np.expm1(-dt / model.config.imm_sojourn_s))
        x0, P0, c_pred = imm_mix(store.x, store.P, store.mu, Pi)
        store.mu[:] = c_pred
    else:
        x0, P0 = store.x, store.P
    Qm = model.q[:, None, None] * _unit_motion(model.config.motion).Q(dt)
    store.x[:], store.P[:] = kf_predict(x0, P0, model.config.motion.F(dt), Qm)


@lru_cache(maxsize=8)
def _unit_motion(motion: LinearMotion) -> LinearMotion:
    """``motion`` with ``q = 1``: ``Q(dt)`` is linear in ``q``, so one evaluation scaled by each
    model's ``q`` gives the IMM's (the same products as ``Q(dt)`` of each model)."""
    return LinearMotion(motion.ndim, motion.order, 1.0, motion.noise)


@dataclass(frozen=True, slots=True, eq=False)
class ScanGate:
    """Gating of the ``T`` tracks (``r`` models) against the ``M`` detections of one scan.

    Attributes
    ----------
    innovation : (T, r, M, m) ``z_j - h(x_t)``
    S : (T, r, m, m) innovation covariance; K : (T, r, n, m) gain
        (:func:`~navtrack.tracking.kalman.innovation_gain`)
    valid : (T, M) bool, the pair is inside the gate of some model
    log_likelihood : (T, r, M) ``log N(z_j; h(x_t), S_t)`` per model (``-1e300`` where the
        pre-gate did not compute it)
    log_likelihood_mix : (T, M) log of the model mixture with the predicted probabilities
    d2 : (T, r, M) normalised innovation squared ``νᵀ S⁻¹ ν`` per model (``inf`` where the
        pre-gate did not compute it)
    S_mix : (T, m, m) innovation covariance of the model mixture, ``Σ_r μ_r S_r`` with the
        predicted model probabilities (``S[:, 0]`` for one model)
    """

    innovation: FloatArray
    S: FloatArray
    K: FloatArray
    valid: BoolArray
    log_likelihood: FloatArray
    log_likelihood_mix: FloatArray
    d2: FloatArray
    S_mix: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def gated(self) -> BoolArray:
        """(M,) detections inside some track's gate."""
        return np.asarray(self.valid.any(axis=0), dtype=bool)


def gate_scan(
    store: TrackStore, z: FloatArray, model: TrackerModel, dt_s: FloatArray | None = None
) -> ScanGate:
    """Stage 2: innovation covariances and gains, chi-square gate and likelihoods.

    Every model of every track is gated against ``z (M, m)`` with ``model.measurement``
    (linearised at the prediction: its Jacobian is ``H`` for a linear model) and
    ``model.gamma``; a k-d tree pre-gate cuts the pairs when there are more than
    ``config.pregate_pairs`` and the measurement has no angle.

    ``dt_s (M,)``: time of each detection minus the prediction time (a window of reports,
    :func:`scan_windows`; ``dt_s <= 0``). The predicted position of a pair is moved along the
    track's velocity, ``H x + dt_j v`` (the position measurement of the tracker); ``S`` and
    ``K`` stay those of the prediction time. The neglected terms, ``dt² P_vv`` and the process
    noise over ``dt``, are small beside ``R`` for windows a fraction of the report interval.
    """
    from navtrack.estimation.kalman import innovation_gain
    from navtrack.tracking.gating import gate, kdtree_pregate

    meas = model.measurement
    T, r, n = store.x.shape
    M, m = z.shape[0], meas.dim_z
    xf = store.x.reshape(T * r, n)
    H = meas.H if isinstance(meas, LinearMeasurement) else meas.jacobian(xf)  # (one H: faster)
    S, K = innovation_gain(store.P.reshape(T * r, n, n), H, meas.R)
    zp = meas.h(xf)
    v = offset = None
    if dt_s is not None and (dt_s != 0).any():
        v = xf[:, list(model.config.motion.velocity_index)]  # (T r, 2)
        offset = dt_s[None, :, None] * v[:, None, :]
    angles = bool(meas.angle_mask.any())
    cand = None
    if model.config.pregate_pairs < T * r * M and not angles:
        margin = 0.0
        if v is not None and dt_s is not None:
            margin = np.abs(dt_s).max() * np.hypot(v[:, 0], v[:, 1])
        cand = kdtree_pregate(zp, S, z, model.gamma, margin)
    g = gate(
        zp,
        S,
        z,
        model.gamma,
        angle_mask=meas.angle_mask if angles else None,
        candidates=cand,
        pair_offset=offset,
    )
    valid = np.asarray(g.valid.reshape(T, r, M).any(axis=1), dtype=bool)
    ll_rm = g.log_likelihood().reshape(T, r, M)
    if cand is not None:  # pairs left out by the pre-gate (d2 = inf)
        ll_rm = np.where(np.isfinite(ll_rm), ll_rm, -1e300)
    S_rm = S.reshape(T, r, m, m)
    if r == 1:  # the mixture of one model is the model
        ll_mix = ll_rm[:, 0]
        S_mix = S_rm[:, 0]
    else:  # mixture likelihood over models with the predicted model probabilities
        c_pred = store.mu
        a = np.log(np.where(c_pred > 0, c_pred, 1e-300))[:, :, None] + ll_rm
        ll_mix = np.logaddexp.reduce(a, axis=1)
        S_mix = np.einsum("tr,trij->tij", c_pred, S_rm)
    return ScanGate(
        g.innovation.reshape(T, r, M, m),
        S.reshape(T, r, m, m),
        K.reshape(T, r, n, m),
        valid,
        ll_rm,
        ll_mix,
        g.d2.reshape(T, r, M),
        S_mix,
    )


@dataclass(frozen=True, slots=True, eq=False)
class ScanAssociation:
    """Association of one scan.

    Attributes
    ----------
    beta : (T, M+1)
        Association probabilities, column 0 = no detection: JPDA marginals, or the 0/1
        assignment of GNN.
    hard : bool
        True for an assignment (GNN): each track takes its column of 1 by a Kalman update.
    marginals : JpdaMarginals or None
        The JPDA marginals with their clusters and methods (None for GNN).
    """

    beta: FloatArray
    hard: bool
    marginals: JpdaMarginals | None = None

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def hit(self) -> BoolArray:
        """(T,) tracks counted as updated (probability of a detection above 1/2)."""
        return np.asarray(self.beta[:, 0] < 0.5)

    @property
    def detection_track(self) -> IntArray:
        """(M,) index of the track a detection is associated with (probability >= 1/2), -1."""
        M = self.beta.shape[1] - 1
        if self.beta.shape[0] == 0:
            return np.full(M, -1, dtype=np.int64)
        best = np.argmax(self.beta[:, 1:], axis=0)
        ok = self.beta[best, 1 + np.arange(M)] >= 0.5
        return np.where(ok, best, -1).astype(np.int64)

    @property
    def associated(self) -> BoolArray:
        """(M,) detections whose summed association probability is >= 1/2."""
        return np.asarray(self.beta[:, 1:].sum(axis=0) >= 0.5)


def gate_edge_log_density(
    S: FloatArray, pd: float, gate_probability: float, gamma: float
) -> FloatArray:
    """``log λ`` at which a report on the gate of innovation covariance ``S`` ties a miss.

    ``λ = P_D / (1 - P_D P_G) · exp(-γ / 2) / sqrt(det(2π S))``: with it the GNN cost of a
    pair, ``-(log N(ν; 0, S) + log P_D - log λ)``, equals the cost of a missed track,
    ``-log(1 - P_D P_G)``, exactly at ``νᵀ S⁻¹ ν = γ``.

    Parameters
    ----------
    S : (..., m, m) innovation covariances
    """
    m = S.shape[-1]
    _sign, logdet = np.linalg.slogdet(S)
    return np.asarray(
        np.log(pd)
        - np.log1p(-pd * gate_probability)
        - 0.5 * gamma
        - 0.5 * (m * np.log(2 * np.pi) + logdet)
    )


def associate_gnn(
    gated: ScanGate,
    pd: float,
    gate_probability: float,
    clutter_density: float | FloatArray,
) -> ScanAssociation:
    """Stage 3 (GNN): optimal 2-D assignment maximising the likelihood ratio.

    Cost of a gated pair ``-(log L_mix + log P_D - log λ)``, of a missed track
    ``-log(1 - P_D P_G)`` (Blackman & Popoli 1999, 6.2). ``clutter_density``: one λ, or one
    per track ``(T,)`` (``TrackerConfig.gnn_density_at_gate``).
    """
    from navtrack.tracking.assignment import assign2d

    log_miss = np.log1p(-pd * gate_probability)
    T, M = gated.valid.shape
    log_det_gain = np.broadcast_to(np.log(pd) - np.log(clutter_density), (T,))[:, None]
    beta = np.zeros((T, M + 1))
    beta[:, 0] = 1.0
    # a track that gates no detection takes its miss column in every optimum: the assignment
    # is solved among the tracks that gate some detection (a few of the tens alive)
    rows = np.flatnonzero(gated.valid.any(axis=1))
    if rows.size:
        valid = gated.valid[rows]
        cost = np.where(valid, -(gated.log_likelihood_mix[rows] + log_det_gain[rows]), np.inf)
        if valid.sum(axis=0).max() == 1:  # no detection in two gates: each track on its own
            best = np.argmin(cost, axis=1)
            a_t = np.where(cost[np.arange(rows.size), best] < -log_miss, best, -1)
        else:
            a_t = assign2d(cost, -log_miss).track_to_meas
        beta[rows, 0] = 0.0
        beta[rows, a_t + 1] = 1.0
    return ScanAssociation(beta, True)


def associate_jpda(gated: ScanGate, config: JpdaConfig) -> ScanAssociation:
    """Stage 3 (JPDA): marginal association probabilities of the mixture likelihoods."""
    from navtrack.tracking.jpda import association_weights, jpda_marginals

    W = association_weights(
        gated.log_likelihood_mix,
        gated.valid,
        config.pd,
        config.gate_probability,
        config.clutter_density,
    )
    jm = jpda_marginals(W, config)
    return ScanAssociation(jm.beta, False, jm)


def associate(gated: ScanGate, model: TrackerModel) -> ScanAssociation:
    """Stage 3: :func:`associate_gnn` or :func:`associate_jpda`, as ``config.associator`` says."""
    cfg = model.config
    if cfg.associator == "gnn":
        density: float | FloatArray = cfg.clutter_density
        if cfg.gnn_density_at_gate:
            log_lam = gate_edge_log_density(gated.S_mix, cfg.pd, cfg.gate_probability, model.gamma)
            density = np.exp(log_lam)
        return associate_gnn(gated, cfg.pd, cfg.gate_probability, density)
    return associate_jpda(gated, model.jpda)


def update(store: TrackStore, gated: ScanGate, assoc: ScanAssociation) -> None:
    """Stage 4: measurement update of the tracks of ``store`` (in place).

    Hard association: the Kalman update :func:`~navtrack.tracking.kalman.gain_update` of each
    assigned track. Soft: the PDA update :func:`~navtrack.tracking.jpda.pda_update` of each
    track with a detection probability > 0. With several models, the model probabilities
    follow (IMM; for JPDA the model likelihood is the missed term plus each detection's
    likelihood ratio against the mixture, Blom & Bloem 2000).
    """
    from navtrack.estimation.kalman import gain_update
    from navtrack.tracking.imm import imm_model_probabilities
    from navtrack.tracking.jpda import pda_update

    beta = assoc.beta
    r = store.n_models
    c_pred = store.mu
    if assoc.hard:
        ti = np.flatnonzero(assoc.hit)
        if not ti.size:
            return
        a_t = np.argmax(beta[ti, 1:], axis=1)
        y = gated.innovation[ti, :, a_t]  # (h, r, m)
        store.x[ti], store.P[ti] = gain_update(
            store.x[ti], store.P[ti], y, gated.K[ti], gated.S[ti]
        )
        if r > 1:
            store.mu[ti] = imm_model_probabilities(c_pred[ti], gated.log_likelihood[ti, :, a_t])
        return
    active = np.flatnonzero(beta[:, 0] < 1.0)
    if not active.size:
        return
    M = beta.shape[1] - 1
    b_r = np.broadcast_to(beta[active, None, :], (active.size, r, M + 1))
    store.x[active], store.P[active] = pda_update(
        store.x[active],
        store.P[active],
        gated.innovation[active],
        gated.S[active],
        gated.K[active],
        b_r,
    )
    if r > 1:
        ratio = np.exp(gated.log_likelihood[active] - gated.log_likelihood_mix[active][:, None, :])
        lam_r = beta[active, None, 0] + np.einsum("tj,trj->tr", beta[active, 1:], ratio)
        store.mu[active] = imm_model_probabilities(
            c_pred[active], np.log(np.maximum(lam_r, 1e-300))
        )


@dataclass(frozen=True, slots=True, eq=False)
class Management:
    """Outcome of :func:`manage` for the ``T`` tracks before deletion.

    Attributes
    ----------
    id : (T,) track ids; x : (T, n) combined state; std_m : (T,) position standard deviation
        ``sqrt(trace(P_pos) / 2)``, m; confirmed : (T,) after this scan's confirmations
    kept : (T,) bool, still in the store
    end_reason : (T,) int8, the :class:`TrackEnd` of each deleted track, -1 where kept
    confirmed_now, deleted_coast, deleted_covariance, deleted_unconfirmed : int
        Counts as in :class:`TrackerCounts`.
    """

    id: IntArray
    x: FloatArray
    std_m: FloatArray
    confirmed: BoolArray
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
        std,
        conf,
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
    store: TrackStore, now_s: float, t_s: float, motion: LinearMotion
) -> tuple[IntArray, FloatArray]:
    """Ids ``(k,)`` and positions ``(k, 2)`` (m) of the confirmed tracks, predicted from their
    last scan at ``now_s`` to ``t_s >= now_s`` without noise."""
    c = store.confirmed
    xc, _ = store.combined()
    xg = xc[c] @ motion.F(t_s - now_s).T
    return store.id[c], xg[:, list(motion.position_index)]


# ---------------------------------------------------------------------------------- driver


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
    from scipy.spatial import cKDTree

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
    model = TrackerModel.from_config(cfg)
    store = TrackStore(cfg.motion.dim_x, len(model.motions))
    seeds = Seeds()
    log = _Log(rep)
    N = t.size
    det_track = np.full(N, -1, dtype=np.int64)
    det_status = np.full(N, DetStatus.SEED, dtype=np.int8)
    det_nis = np.full(N, np.nan)
    det_ll = np.full(N, np.nan)
    counts = dict.fromkeys(TrackerCounts.__dataclass_fields__, 0)
    now = t[0] if N else 0.0
    starts, ends = scan_windows(t, Z, cfg.scan_window_s, window_separation_m(model))
    done = 0  # detections reported to ``progress``
    for s0, s1 in zip(starts, ends, strict=True):
        if progress is not None and s0:
            progress(s0 - done)
            done = s0
        tk = t[s1 - 1]  # a window of reports is processed at its last time
        dt_k = t[s0:s1] - tk
        log.report_until(store, now, tk, cfg.motion, inclusive=False)
        counts["scans"] += 1
        Zk = Z[s0:s1]
        predict(store, tk - now, model)
        now = tk
        claimed = np.zeros(Zk.shape[0], dtype=bool)  # detections not available for initiation
        if store.size:
            g = gate_scan(store, Zk, model, dt_k)
            a = associate(g, model)
            update(store, g, a)
            # fates of the associated detections, by the status of their track before manage
            k = a.detection_track
            used = np.flatnonzero(k >= 0)
            det_track[s0 + used] = store.id[k[used]]
            det_status[s0 + used] = np.where(
                store.confirmed[k[used]], DetStatus.CONFIRMED, DetStatus.TENTATIVE
            )
            det_status[s0 + np.flatnonzero(g.gated & (k < 0))] = DetStatus.UNUSED
            counts["ambiguous_detections"] += int(
                np.count_nonzero(g.valid[store.confirmed].sum(axis=0) >= 2)
            )
            det_nis[s0 + used] = g.d2[k[used], :, used].min(axis=1)
            det_ll[s0 + used] = g.log_likelihood_mix[k[used], used]
            hit = a.hit
            m = manage(store, hit, tk, cfg)
            log.updates(tk, m, 1.0 - a.beta[:, 0])
            _add_counts(counts, a, m)
            claimed = a.associated if cfg.init_from == "unassociated" else g.gated
        free = np.flatnonzero(~claimed)
        if not free.size:  # (seeds are pruned by age when next used: same result)
            continue
        ini = initiate(store, seeds, tk, Zk[free], V[s0 + free], s0 + free, cfg, t[s0 + free])
        det_track[s0 + free] = ini.track
        det_status[s0 + free] = ini.status
        det_track[ini.seed_det] = ini.seed_track
        det_status[ini.seed_det] = DetStatus.STARTED
        counts["tracks_started"] += int(np.count_nonzero(ini.track >= 0))
    log.report_until(store, now, now, cfg.motion, inclusive=True)
    log.ends(now, store.id, np.full(store.size, TrackEnd.END_OF_DATA, dtype=np.int8))
    if progress is not None:
        progress(N - done)
    return log.result(
        det_track, det_status, det_nis, cfg.motion.dim_x, TrackerCounts(**counts), det_ll
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
    from navtrack.tracking.jpda import JpdaMethod

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
        self, store: TrackStore, now_s: float, limit_s: float, motion: LinearMotion, inclusive: bool
    ) -> None:
        rep = self.rep
        while self.r_next < rep.size and (
            rep[self.r_next] < limit_s or (inclusive and rep[self.r_next] <= limit_s)
        ):
            if rep[self.r_next] >= now_s:
                ids, xy = report(store, now_s, rep[self.r_next], motion)
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
            det_track,
            det_status,
            cat(self.t, (0,), float),
            cat(self.id, (0,), np.int64),
            cat(self.x, (0, n), float),
            cat(self.std, (0,), float),
            cat(self.conf, (0,), bool),
            cat(self.rep_f, (0,), np.int64),
            cat(self.rep_id, (0,), np.int64),
            cat(self.rep_xy, (0, 2), float),
            counts,
            det_nis,
            det_ll,
            cat(self.p, (0,), float),
            cat(self.end_id, (0,), np.int64),
            cat(self.end_t, (0,), float),
            cat(self.end_reason, (0,), np.int8),
        )
