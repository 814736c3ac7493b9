"""The stages of the file tracker on its live tracks (:class:`TrackStore`): predict, gate,
associate (GNN or JPDA) and update (:mod:`navtrack.tracking.trackers.tracker` runs them scan by
scan; other trackers reuse them one by one)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.estimation.kalman import gain_update, innovation_gain, kf_predict
from navtrack.tracking.assignment import assign2d
from navtrack.tracking.gating import gate, kdtree_pregate
from navtrack.tracking.imm import imm_combine, imm_mix, imm_model_probabilities, markov_matrix
from navtrack.tracking.jpda import (
    JpdaConfig,
    JpdaMarginals,
    association_weights,
    jpda_marginals,
    pda_update,
)
from navtrack.tracking.models import LinearMeasurement, LinearMotion
from navtrack.tracking.trackers.track_config import TrackerModel

__all__ = [
    "ScanAssociation",
    "ScanGate",
    "Seeds",
    "TrackStore",
    "associate",
    "associate_gnn",
    "associate_jpda",
    "gate_edge_log_density",
    "gate_scan",
    "predict",
    "update",
]


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


def predict(store: TrackStore, dt: float, model: TrackerModel) -> None:
    """Stage 1: predict every track of ``store`` (in place) over ``dt`` seconds.

    With several motion models the IMM interaction comes first, with the switching probability
    ``1 - exp(-dt / imm_sojourn_s)`` of a continuous-time Markov chain; then the KF prediction
    of every model (:func:`~navtrack.estimation.kalman.kf_predict`), and ``mu`` becomes the
    predicted model probabilities. Nothing happens for ``dt <= 0`` or an empty store.
    """
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
        (:func:`~navtrack.estimation.kalman.innovation_gain`)
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

    Hard association: the Kalman update :func:`~navtrack.estimation.kalman.gain_update` of each
    assigned track. Soft: the PDA update :func:`~navtrack.tracking.jpda.pda_update` of each
    track with a detection probability > 0. With several models, the model probabilities
    follow (IMM; for JPDA the model likelihood is the missed term plus each detection's
    likelihood ratio against the mixture, Blom & Bloem 2000).
    """
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
