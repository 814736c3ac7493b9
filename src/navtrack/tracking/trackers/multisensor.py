"""Centralised multisensor multitarget fusion: sequential / parallel MSJPDA, SD-CMSJPDA, S-D GNN.

``S`` sensors report to a fusion centre; ``T`` targets with known initial estimates are tracked
by an EKF (linearised at the prediction, e.g. :class:`~navtrack.tracking.models.RangeBearing`).
All four trackers predict with :func:`~navtrack.estimation.kalman.kf_predict`, gate with
:func:`~navtrack.tracking.gating.gate`, weight as
:func:`~navtrack.tracking.jpda.association_weights` does and update through
:func:`~navtrack.estimation.kalman.innovation_gain` /
:func:`~navtrack.estimation.kalman.gain_update` (the one update path). They differ in how the
sensors' measurements are combined:

``sequential`` (Pao & Frei 1995)
    A single-sensor JPDA step (:func:`~navtrack.tracking.jpda.jpda_step`) per sensor in time
    order, each starting from the previous sensor's posterior; the only one that accepts sensors
    with different time stamps (it predicts between them).
``parallel`` (Pao & Frei 1995)
    Joint events over all sensors at once: each target takes one *S-tuple* ``L = (l_1..l_S)``
    (``l_s = 0``: sensor ``s`` has no detection of it); the update of a tuple is the stacked
    (centralised) EKF update with all its measurements; the posterior is the moment-matched
    mixture over tuples.
``sdcmsjpda`` (Zhang, Xiong & He 2005, eqs. 3-32 as printed)
    The same S-tuples and joint events (the S-D assignment rule: each measurement from one
    source, one measurement per sensor per tuple); the measurements of a tuple are combined
    "according to their weight in the assignment, decided by their likelihood value": eqs.
    24-32, the tuple estimate ``X̂ + Σ_s w_s K_s ν_s`` with eq. 25's weights and eq. 26's
    nonparametric ``e`` and ``b`` (``FusionConfig.false_per_gate`` is eq. 26's ``m``); see
    Notes.
``sdcmsjpda_fused``
    The prose's other reading: each tuple becomes ONE equivalent measurement, the
    maximum-likelihood fusion of its detections (:func:`~navtrack.tracking.trackers.equivalent.
    equivalent_measurement`: Gauss-Newton fit of the position to the tuple's range-bearing
    measurements, covariance
    ``(Σ_s J_sᵀ R_s⁻¹ J_s)⁻¹``), and JPDA runs on the equivalent measurements: the tuple's
    update is the (linear) Kalman update with it; see Notes.
``sdcmsjpda_joint``
    ``sdcmsjpda_fused`` with the joint likelihood of each S-tuple, ``N(ν_L; 0, S_L)`` with ``S_L``
    the joint innovation covariance of the tuple's sensors, cross-covariances
    ``H_i P̂ H_jᵀ`` through the common prediction included (eq. 14's "combined innovation
    covariance of all sensors"), in place of eq. 15's product of the members' Gaussians; the
    joint events over targets are enumerated (up to two targets). Not the paper's eq. 15: a
    diagnostic of why the factorised likelihood loses to sequential processing in clutter
    (module notes).
``sd_gnn``
    Hard decision: the best joint event, found as an (S+1)-D assignment of (targets, sensor
    1..S lists) by :func:`~navtrack.tracking.assignment.sd_assign`, then the stacked update.

Notes
-----
Reading of the paper's equations (the extraction lost their layout):

* eqs. 5-10: an S-tuple is in target ``t``'s gate when each of its real measurements is in that
  sensor's chi-square gate of ``t``.
* eqs. 11-21: the joint event probability is
  ``Π_t Π_s [l_s = 0: (1 - P_D,s P_G) ; else P_D,s N(z; ẑ_s^t, S_s^t) / λ_s]``, the parametric
  (Poisson) form of eq. 21: ``φ! μ_F(φ) / V^φ`` of the false measurements becomes
  ``Π_s λ_s^-(measurements of sensor s assigned)`` and eq. 19's joint detection probability is
  the product of the per-sensor ``P_D`` / ``1 - P_D P_G`` factors.
* eq. 22: the marginal ``β_t(L)``. Because the weight is a product over sensors and the
  exclusion constraints act within each sensor, the joint events are products of the
  per-sensor joint events, so ``β_t(L) = Π_s β_t^s(l_s)`` exactly, with ``β^s`` the
  single-sensor JPDA marginals (:func:`~navtrack.tracking.jpda.jpda_marginals`); the tests
  check this against the explicit enumeration of eq. 21. ``parallel``, ``sdcmsjpda`` and
  ``sdcmsjpda_fused`` share these marginals and differ in the tuple update only.
* The equivalent measurement (``sdcmsjpda_fused``): why the paper's text reads as one fused
  measurement per tuple, and how its update relates to ``parallel``'s, is in the notes of
  :mod:`navtrack.tracking.trackers.equivalent`.
* The literal form (``sdcmsjpda``), eqs. 24-32 as printed. The tuple estimate is
  ``X_L = X̂ + Σ_{s∈L} w_s K_s ν_s`` (eq. 24, ``K_s``, ``ν_s`` the single-sensor gain and
  innovation at the prediction, eqs. 27, 29), ``w_s = e_s / (b + Σ_{i∈L} e_i)`` (eq. 25),
  ``β_0(L) = b / (b + Σ_{i∈L} e_i)`` (eq. 28) and eq. 26's nonparametric PDA terms
  (Bar-Shalom & Fortmann (6.4)): ``e_s = exp(-ν_sᵀ S_s⁻¹ ν_s / 2)`` and
  ``b = m (2π/γ)^{n_z/2} (1 - P_D P_G) / (c_{n_z} P_D)``, ``m`` the expected number of false
  measurements in the gate, ``γ`` the gate threshold, ``c_{n_z}`` the volume of the unit
  ``n_z``-ball (π for range-bearing); with sensors of different ``P_D`` the mean is used (the
  paper's sensors share one). The state is ``Σ_L β(L) X_L`` over the tuples' marginals; eqs.
  31-32 are the covariance of that mixture: ``P_L = β_0 P̂ + Σ_s w_s (P̂ - K_s S_s K_sᵀ)``
  plus the spread of the corrections about their mean, then the spread of the ``X_L`` over the
  tuples. The weights sum to at most 1, so a tuple of three detections moves the state about
  as far as one sensor would: the sensors of a tuple are weighted alternatives, not fused.
* The joint tuple likelihood (``sdcmsjpda_joint``). Eq. 15 multiplies the members'
  ``N(z_s; ẑ_s, S_s)``, each at the prediction: the sensors are taken as independent given
  the prediction, but their innovations share the prediction error, so they are correlated
  (``cov(ν_i, ν_j) = H_i P̂ H_jᵀ``). Sequential processing accounts for it by the chain rule
  (sensor ``s`` is gated and weighted at the posterior of sensors ``1..s-1``); the product
  does not, and in clutter it over-weights tuples whose members are each plausible but
  mutually inconsistent. The joint form weights tuple ``L`` by
  ``Π_{s∈L} (P_D,s / λ_s) · N(ν_L; 0, S_L) · Π_{s∉L} (1 - P_D,s P_G)`` and needs the joint
  events over targets (no factorisation over sensors).
* The S-D GNN tuple cost is ``-log`` of the same event weight; it is additive over sensors, so
  the (S+1)-D problem is the union of per-sensor 2-D problems and the relaxation closes its gap
  (the tests check the solution against per-sensor :func:`~navtrack.tracking.assignment.assign2d`).

References
----------
.. [1] J.-W. Zhang, W. Xiong, Y. He, "S-D assignment centralized multisensor joint probabilistic
   data association algorithm", ICMLC 2005, pp. 564-569 (paper 3).
.. [2] L. Y. Pao, C. W. Frei, "A comparison of parallel and sequential implementations of a
   multisensor multitarget tracking algorithm", Proc. ACC 1995, pp. 1683-1687.
.. [3] Y. Bar-Shalom, T. E. Fortmann, *Tracking and Data Association*, Academic Press 1988,
   sections 6.4 (PDA) and 9 (JPDA).
.. [4] S. Deb et al., IEEE T-AES 33(2), 1997 (S-D assignment; see
   :mod:`navtrack.tracking.assignment`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.kalman import gain_update, innovation_gain, kf_predict
from navtrack.estimation.models import MeasurementModel
from navtrack.tracking.assignment import SdProblem, SdStatus, compile_kernels, sd_assign
from navtrack.tracking.gating import chi2_threshold, gate
from navtrack.tracking.jpda import (
    JpdaConfig,
    jpda_marginals,
    jpda_marginals_batch,
    jpda_step,
    n_joint_events,
)
from navtrack.tracking.models import LinearMotion, measure
from navtrack.tracking.trackers.equivalent import (
    compiled_gauss_newton,
    compiled_range_bearing,
    equivalent_measurement,
    sensor_constants,
)

__all__ = [
    "ALGORITHMS",
    "Algorithm",
    "FusionConfig",
    "FusionResult",
    "MultiScans",
    "SensorTerms",
    "fusion_step",
    "joint_tuple_marginals",
    "nonparametric_b",
    "run_fusion",
    "sd_gnn_tuples",
    "sensor_terms",
    "tuple_marginals",
]

Algorithm = Literal[
    "sequential", "parallel", "sdcmsjpda", "sd_gnn", "sdcmsjpda_fused", "sdcmsjpda_joint"
]
#: The fusion trackers, in the order of the reproduction's tables.
ALGORITHMS: tuple[Algorithm, ...] = (
    "sequential",
    "parallel",
    "sdcmsjpda",
    "sd_gnn",
    "sdcmsjpda_fused",
    "sdcmsjpda_joint",
)


@dataclass(frozen=True, slots=True)
class FusionConfig:
    """Parameters of the fusion trackers.

    Attributes
    ----------
    pd : tuple of float
        Detection probability of each sensor, in (0, 1].
    clutter_density : tuple of float
        Spatial density ``λ_s`` of each sensor's false measurements, per m·rad, > 0.
    gate_probability : float
        ``P_G`` of the chi-square gates (1 = no gate).
    time_tolerance_s : float
        Largest difference of the sensors' time stamps in one scan that the centralised
        trackers (all but ``sequential``) accept as simultaneous.
    max_tuples : int
        Largest number of gated S-tuples of one target (guard against a combinatorial blow-up;
        more raise ``ValueError`` naming the target and scan).
    false_per_gate : float or None
        Eq. 26's ``m``, the expected number of false measurements in a gate, > 0: the
        nonparametric ``b`` of ``sdcmsjpda`` (which needs it); the other trackers use
        ``clutter_density``.
    """

    pd: tuple[float, ...]
    clutter_density: tuple[float, ...]
    gate_probability: float = 0.99
    time_tolerance_s: float = 1e-6
    max_tuples: int = 20_000
    false_per_gate: float | None = None

    def __post_init__(self) -> None:
        if len(self.pd) != len(self.clutter_density) or not self.pd:
            raise ValueError("pd and clutter_density need one value per sensor")
        for s, (p, lam) in enumerate(zip(self.pd, self.clutter_density, strict=True)):
            if not 0.0 < p <= 1.0:
                raise ValueError(f"pd[{s}] must be in (0, 1], got {p}")
            if not (np.isfinite(lam) and lam > 0):
                raise ValueError(f"clutter_density[{s}] must be finite and > 0, got {lam}")
        if not 0.0 < self.gate_probability <= 1.0:
            raise ValueError(f"gate_probability must be in (0, 1], got {self.gate_probability}")
        if self.time_tolerance_s < 0 or self.max_tuples < 1:
            raise ValueError("time_tolerance_s must be >= 0 and max_tuples >= 1")
        if self.false_per_gate is not None and not self.false_per_gate > 0:
            raise ValueError(f"false_per_gate must be > 0, got {self.false_per_gate}")

    def jpda(self, s: int) -> JpdaConfig:
        """The single-sensor JPDA configuration of sensor ``s``."""
        return JpdaConfig(self.pd[s], self.clutter_density[s], self.gate_probability)


@dataclass(frozen=True, slots=True, eq=False)
class MultiScans:
    """Scans of ``S`` sensors on fixed shapes (arrays read-only).

    Attributes
    ----------
    z : (K, S, N, m) measurements (NaN where not valid)
    valid : (K, S, N) bool
    t_s : (K, S) time stamp of each sensor's scan, s
    """

    z: FloatArray
    valid: BoolArray
    t_s: FloatArray

    def __post_init__(self) -> None:
        z = np.asarray(self.z, dtype=float)
        valid = np.asarray(self.valid, dtype=bool)
        t = np.asarray(self.t_s, dtype=float)
        if z.ndim != 4 or valid.shape != z.shape[:3] or t.shape != z.shape[:2]:
            raise ValueError(
                f"MultiScans: need z (K, S, N, m), valid (K, S, N), t_s (K, S); got "
                f"{z.shape}, {valid.shape}, {t.shape}"
            )
        bad = valid & ~np.all(np.isfinite(z), axis=-1)
        if np.any(bad):
            k, s, j = np.argwhere(bad)[0]
            raise ValueError(f"z[{k}, {s}, {j}] is marked valid but not finite")
        if not np.all(np.isfinite(t)):
            k, s = np.argwhere(~np.isfinite(t))[0]
            raise ValueError(f"t_s[{k}, {s}] is not finite")
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "valid", valid)
        object.__setattr__(self, "t_s", t)
        freeze_arrays(self)

    def scan(self, k: int, s: int) -> FloatArray:
        """Valid measurements of sensor ``s`` in scan ``k``, ``(M, m)``."""
        return np.asarray(self.z[k, s][self.valid[k, s]])


@dataclass(frozen=True, slots=True, eq=False)
class FusionResult:
    """Output of :func:`run_fusion` (arrays read-only).

    Attributes
    ----------
    x : (K, T, n) posterior states per scan
    P : (K, T, n, n) posterior covariances
    empty_scans : (S,) int, scans in which a sensor reported nothing
    longest_silence : (S,) int, longest run of consecutive empty scans per sensor
    gap_scans : int, ``sd_gnn`` scans whose S-D solution kept a duality gap (0 otherwise)
    ms_per_step : float, mean CPU time (``time.thread_time``) of one fusion step, ms: the
        tracker's own cost, not inflated by other processes on a loaded machine
    """

    x: FloatArray
    P: FloatArray
    empty_scans: IntArray
    longest_silence: IntArray
    gap_scans: int
    ms_per_step: float

    def __post_init__(self) -> None:
        freeze_arrays(self)


# ------------------------------------------------------------------------------- kernels


@dataclass(frozen=True, slots=True, eq=False)
class SensorTerms:
    """Linearisation, gate and weights of one scan of every sensor (sensor axis first)."""

    z: FloatArray  # (S, M, m) the measurements, padded with zeros
    H: FloatArray  # (S, T, m, n)
    S: FloatArray  # (S, T, m, m)
    K: FloatArray  # (S, T, n, m)
    innovation: FloatArray  # (S, T, M, m), M = the most measurements of a sensor
    d2: FloatArray  # (S, T, M) squared Mahalanobis distances (inf outside gate / padding)
    log_w: FloatArray  # (S, T, M+1) log of the eq. 21 factors (-inf outside gate / padding)
    beta: FloatArray  # (S, T, M+1) single-sensor JPDA marginals
    n_meas: IntArray  # (S,) measurements of each sensor


def sensor_terms(
    xp: FloatArray,
    Pp: FloatArray,
    z: Sequence[FloatArray],
    sensors: Sequence[MeasurementModel],
    config: FusionConfig,
) -> SensorTerms:
    """EKF terms, gates, weights and marginals of all sensors at once (sensors as batch axis).

    The weights are those of :func:`~navtrack.tracking.jpda.association_weights` (each
    sensor's ``P_D`` and ``λ``), formed for all sensors in one pass.

    Measurements are padded to a common count with a ``valid`` mask, as in
    :func:`~navtrack.tracking.jpda.jpda_step_batch`.
    """
    S_ = len(sensors)
    m = sensors[0].dim_z
    M = max(len(zs) for zs in z)
    Z = np.zeros((S_, M, m))
    ok = np.zeros((S_, M), dtype=bool)
    for s, zs in enumerate(z):
        Z[s, : len(zs)] = zs
        ok[s, : len(zs)] = True
    zp, H = measure(sensors, xp)  # (T, S, m), (T, S, m, n)
    zp, H = np.swapaxes(zp, 0, 1), np.swapaxes(H, 0, 1)
    R = sensor_constants(sensors)[0]
    Sg, K = innovation_gain(Pp, H, R[:, None])
    pg = config.gate_probability
    g = gate(zp, Sg, Z, chi2_threshold(pg, m), angle_mask=sensors[0].angle_mask)
    valid = g.valid & ok[:, None, :]
    log_miss, log_detect = _event_logs(config)
    log_w = np.empty((*valid.shape[:-1], M + 1))
    log_w[..., :1] = log_miss
    log_w[..., 1:] = np.where(valid, g.log_likelihood() + log_detect, -np.inf)
    # the weights of association_weights, all sensors at once: each row scaled to max 1
    mx = log_w.max(axis=-1, keepdims=True)
    W = np.exp(log_w - np.where(np.isfinite(mx), mx, 0.0))
    # marginals over the measurements some target gates (the others are certain clutter):
    # column 0 and the gated columns of each sensor moved to the front (stable order), the
    # rest (weight 0, so marginal 0) cut to the most gated columns of a sensor
    keep = np.ones((S_, M + 1), dtype=bool)
    keep[:, 1:] = valid.any(axis=1)
    cols = np.argsort(~keep, axis=1, kind="stable")[:, None, : keep.sum(axis=1).max()]
    T, Mc = xp.shape[0], cols.shape[-1] - 1
    at = (np.arange(S_)[:, None, None], np.arange(T)[:, None], cols)  # (S, T, Mc + 1)
    Wc = W[at]
    if n_joint_events(T, Mc) <= 20_000:
        bc = jpda_marginals_batch(Wc)
    else:
        bc = np.array([jpda_marginals(Wc[s], config.jpda(s)).beta for s in range(S_)])
    beta = np.zeros_like(W)
    beta[at] = bc
    n_meas = np.array([len(zs) for zs in z], dtype=np.int64)
    d2 = np.where(valid, g.d2, np.inf)
    return SensorTerms(Z, H, Sg, K, g.innovation, d2, log_w, beta, n_meas)


def tuple_marginals(
    betas: Sequence[FloatArray] | FloatArray,
) -> tuple[IntArray, IntArray, FloatArray]:
    """Gated S-tuples of every target and their marginals ``β_t(L) = Π_s β_t^s(l_s)``.

    One dense product over the measurements some target may take (``β > 0``), then its
    non-zero entries: all targets at once.

    Parameters
    ----------
    betas : S arrays ``(T, M_s + 1)`` (or one ``(S, T, M + 1)``), single-sensor JPDA
        marginals (column 0 = missed)

    Returns
    -------
    target : (n_L,) int, the target of each tuple, sorted (each target's tuples contiguous)
    tuples : (n_L, S) int, ``l_s`` (0 = no detection, ``j`` = measurement ``j - 1``)
    beta : (n_L,) probabilities, summing to 1 over each target's tuples
    """
    bs = [np.asarray(b, dtype=float) for b in betas]
    T = bs[0].shape[0]
    opts = [np.flatnonzero((b > 0).any(axis=0)) for b in bs]
    p = bs[0][:, opts[0]]
    for s in range(1, len(bs)):
        p = p[..., None] * bs[s][:, opts[s]].reshape(T, *(1,) * s, opts[s].size)
    idx = np.nonzero(p)
    beta = p[idx]
    target = idx[0].astype(np.int64)
    L = np.array([o[i] for o, i in zip(opts, idx[1:], strict=True)], dtype=np.int64).T
    return target, L, beta / np.bincount(target, beta, T)[target]


def _mixtures(
    target: IntArray, w: FloatArray, x: FloatArray, P: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Moment-matched Gaussian mixture of each target: components ``(C,)`` grouped by the
    sorted ``target`` (every target ``0..T-1`` present), weights ``w`` normalised per target,
    means ``(C, n)``, covariances ``(C, n, n)``; returns ``(T, n)``, ``(T, n, n)``."""
    start = np.searchsorted(target, np.arange(target[-1] + 1))
    xm = np.add.reduceat(w[:, None] * x, start)
    d = x - xm[target]
    Pm = np.add.reduceat(w[:, None, None] * (P + d[:, :, None] * d[:, None, :]), start)
    return xm, 0.5 * (Pm + np.swapaxes(Pm, -1, -2))


def _stacked(
    xp: FloatArray,
    Pp: FloatArray,
    target: IntArray,
    L: IntArray,
    terms: SensorTerms,
    sensors: Sequence[MeasurementModel],
) -> tuple[FloatArray, FloatArray]:
    """Centralised EKF update of ``target[i]`` with tuple ``L[i]`` (``L (n_L, S)``), all
    targets' tuples in one batch.

    The stacked measurement of independent sensors, applied one sensor after the other with
    every Jacobian taken at the prediction (identical to the stacked update): the innovation
    of sensor ``s`` is re-referenced to the current estimate, ``ν_s - H_s (x - x̂)``.
    """
    x = xp[target]
    P = Pp[target]
    for s, model in enumerate(sensors):
        hit = L[:, s] > 0
        if not hit.any():
            continue
        t = target[hit]
        H = terms.H[s, t]
        dx = x[hit] - xp[t]
        y = terms.innovation[s, t, L[hit, s] - 1] - np.einsum("kij,kj->ki", H, dx)
        S, K = innovation_gain(P[hit], H, model.R)
        x[hit], P[hit] = gain_update(x[hit], P[hit], y, K, S)
    return x, P


def nonparametric_b(config: FusionConfig, dim_z: int) -> float:
    """Eq. 26's ``b = m (2π/γ)^{n_z/2} (1 - P_D P_G) / (c_{n_z} P_D)`` (module notes), ``P_D``
    the sensors' mean, ``γ`` the chi-square gate threshold of ``P_G``."""
    if config.false_per_gate is None:
        raise ValueError("sdcmsjpda needs FusionConfig.false_per_gate (eq. 26's m)")
    pd = float(np.mean(config.pd))
    pg = config.gate_probability
    gamma = chi2_threshold(pg, dim_z)
    c = math.pi ** (dim_z / 2) / math.gamma(dim_z / 2 + 1)  # volume of the unit ball
    return config.false_per_gate * (2 * math.pi / gamma) ** (dim_z / 2) * (1 - pd * pg) / (c * pd)


def _literal_update(
    xp: FloatArray,
    Pp: FloatArray,
    L: IntArray,
    beta: FloatArray,
    terms: SensorTerms,
    b: float,
    t: int,
) -> tuple[FloatArray, FloatArray]:
    """``sdcmsjpda`` update of target ``t`` over its tuples ``L`` of marginals ``beta``: eqs.
    24-32 as printed (module notes), the mixture of the prediction and the single-sensor
    updates ``(s, j)`` each weighted by ``Σ_L β(L) w_s(L)``."""
    S_ = L.shape[1]
    sidx = np.arange(S_)
    d2 = terms.d2[sidx, t, np.maximum(L - 1, 0)] if terms.d2.shape[-1] else np.zeros(L.shape)
    e = np.where(L > 0, np.exp(-0.5 * d2), 0.0)  # eq. 26
    den = b + e.sum(axis=1)
    w = e / den[:, None]  # eq. 25
    M1 = terms.log_w.shape[-1]
    a = np.bincount((sidx * M1 + L).ravel(), (beta[:, None] * w).ravel(), S_ * M1)
    a = a.reshape(S_, M1)[:, 1:]  # weight of the single-sensor update (s, j)
    s_used, j_used = np.nonzero(a > 0)
    K = terms.K[s_used, t]
    xj, Pj = gain_update(xp[t], Pp[t], terms.innovation[s_used, t, j_used], K, terms.S[s_used, t])
    weights = np.r_[float(beta @ (b / den)), a[s_used, j_used]]  # eq. 28 first
    xm, Pm = _mixtures(
        np.zeros(weights.size, dtype=np.int64),
        weights / weights.sum(),
        np.vstack([xp[t][None], xj]),
        np.concatenate([Pp[t][None], Pj]),
    )
    return xm[0], Pm[0]


@lru_cache(maxsize=64)
def _event_logs(config: FusionConfig) -> tuple[FloatArray, FloatArray]:
    """``log(1 - P_D,s P_G)`` and ``log(P_D,s / λ_s)`` of each sensor, ``(S, 1, 1)`` each: the
    eq. 21 factors of a missed and of a detected target, without the Gaussian."""
    pd = np.asarray(config.pd)[:, None, None]
    lam = np.asarray(config.clutter_density)[:, None, None]
    with np.errstate(divide="ignore"):
        miss = np.log1p(-pd * config.gate_probability)
    detect = np.log(pd) - np.log(lam)
    miss.setflags(write=False)
    detect.setflags(write=False)
    return miss, detect


def _equivalent_updates(
    xp: FloatArray,
    Pp: FloatArray,
    target: IntArray,
    L: IntArray,
    terms: SensorTerms,
    sensors: Sequence[MeasurementModel],
) -> tuple[FloatArray, FloatArray]:
    """``sdcmsjpda`` tuple updates: for tuple ``L[i]`` of ``target[i]``, the Kalman update
    with the tuple's equivalent measurement (``equivalent_measurement``, all targets'
    tuples in one batch, its first iteration on the sensors' Jacobians and innovations at
    the prediction); the empty tuple keeps the prediction."""
    x, P = xp[target], Pp[target]
    hit = L > 0
    some = np.flatnonzero(hit.any(axis=1))
    if some.size:
        t, j = target[some], np.maximum(L[some] - 1, 0)  # j: any index where not in the tuple
        sidx = np.arange(L.shape[1])
        linearised = None
        if compiled_range_bearing(sensors) is None:  # the NumPy loop starts from these
            J = terms.H[:, t].transpose(1, 0, 2, 3)  # (n, S, m, n_x) at the prediction
            linearised = J, terms.innovation[sidx, t[:, None], j]  # and (n, S, m)
        xt, Pt = xp[t], Pp[t]
        o, zeta, R_eq = equivalent_measurement(
            terms.z[sidx, j], hit[some], sensors, xt, linearised=linearised
        )
        S, K = innovation_gain(Pt, np.eye(xp.shape[-1])[o], R_eq)
        x[some], P[some] = gain_update(xt, Pt, zeta - xt[:, o], K, S, symmetrize=False)
    return x, P


def joint_tuple_marginals(
    Pp: FloatArray,
    target: IntArray,
    L: IntArray,
    terms: SensorTerms,
    sensors: Sequence[MeasurementModel],
    config: FusionConfig,
) -> FloatArray:
    """``sdcmsjpda_joint`` marginals of the gated tuples ``L[i]`` of ``target[i]`` (module
    notes): tuple weights with the joint innovation covariance of the tuple's sensors, then
    the joint events over targets (no two targets share a measurement of a sensor).

    Raises ``ValueError`` for more than two targets (the events are enumerated as pairs).
    """
    S_, T, m, n = terms.H.shape
    if T > 2:
        raise ValueError(f"sdcmsjpda_joint enumerates joint events of <= 2 targets, got {T}")
    pd = np.asarray(config.pd)
    lam = np.asarray(config.clutter_density)
    hit = L > 0
    with np.errstate(divide="ignore"):
        missed = np.log1p(-pd * config.gate_probability)
    log_w = np.where(hit, np.log(pd) - np.log(lam), missed).sum(axis=1)
    H = terms.H.transpose(1, 0, 2, 3).reshape(T, S_ * m, n)
    R = np.zeros((S_ * m, S_ * m))
    for s, model in enumerate(sensors):
        R[s * m : (s + 1) * m, s * m : (s + 1) * m] = model.R
    S_full = H @ Pp @ np.swapaxes(H, -1, -2) + R  # (T, S m, S m)
    sidx = np.arange(S_)
    if terms.innovation.shape[2]:
        nu = terms.innovation[sidx, target[:, None], np.maximum(L - 1, 0)].reshape(len(L), -1)
    else:  # no sensor reported: every tuple is empty
        nu = np.zeros((len(L), S_ * m))
    patterns, which = np.unique(hit, axis=0, return_inverse=True)
    for p, pattern in enumerate(patterns):
        k = np.repeat(pattern, m)
        rows = np.flatnonzero(which.reshape(-1) == p)
        if not k.any():
            continue
        Sk = S_full[:, k][:, :, k][target[rows]]
        y = nu[rows][:, k]
        logdet = np.linalg.slogdet(2.0 * np.pi * Sk)[1]
        d2 = np.einsum("li,li->l", y, np.linalg.solve(Sk, y[..., None])[..., 0])
        log_w[rows] += -0.5 * (d2 + logdet)
    w = np.exp(log_w - np.max(log_w))
    if T == 1:
        return w / w.sum()
    a, b = target == 0, target == 1
    shared = (L[a][:, None, :] == L[b][None, :, :]) & (L[a][:, None, :] > 0)
    pair = w[a][:, None] * w[b][None, :] * ~shared.any(axis=-1)
    beta = np.empty(len(L))
    beta[a] = pair.sum(axis=1)
    beta[b] = pair.sum(axis=0)
    return beta / pair.sum()


def sd_gnn_tuples(terms: SensorTerms, max_tuples: int) -> tuple[IntArray, bool]:
    """The best joint event as an (S+1)-D assignment.

    Returns ``(L (T, S), gap)``, ``gap`` True when the relaxation stopped with a duality gap.
    """
    S_, T = terms.log_w.shape[:2]
    sizes = np.r_[T, terms.n_meas].astype(np.int64)
    # a certain detection (P_D P_G = 1) makes "missed" impossible; the S-D problem still needs
    # each target's singleton, so it gets the cost of a weight of 1e-300 instead of +inf
    log_w = terms.log_w.copy()
    log_w[..., 0] = np.maximum(log_w[..., 0], np.log(1e-300))
    rows, costs = [], []
    for t in range(T):
        opts = [np.flatnonzero(np.isfinite(log_w[s, t])) for s in range(S_)]
        grids = np.meshgrid(*opts, indexing="ij")
        L = np.stack([g.reshape(-1) for g in grids], axis=-1)
        if len(L) > max_tuples:
            raise ValueError(f"target {t}: {len(L)} gated S-tuples > max_tuples")
        c = -log_w[np.arange(S_), t, L].sum(axis=1)
        rows.append(np.column_stack([np.full(len(L), t + 1), L]))
        costs.append(c)
    for s in range(S_):  # false alarms: each measurement alone, cost 0
        j = np.arange(1, sizes[s + 1] + 1)
        r = np.zeros((j.size, S_ + 1), dtype=np.int64)
        r[:, s + 1] = j
        rows.append(r)
        costs.append(np.zeros(j.size))
    sol = sd_assign(SdProblem(sizes, np.concatenate(rows), np.concatenate(costs)), "lagrangian")
    out = np.zeros((T, S_), dtype=np.int64)
    tgt = sol.tuples[:, 0] > 0
    out[sol.tuples[tgt, 0] - 1] = sol.tuples[tgt, 1:]
    return out, bool(sol.status != SdStatus.OPTIMAL)


def fusion_step(
    algorithm: Algorithm,
    x: ArrayLike,
    P: ArrayLike,
    z: Sequence[FloatArray],
    dt: Sequence[float],
    sensors: Sequence[MeasurementModel],
    motion: LinearMotion,
    config: FusionConfig,
) -> tuple[FloatArray, FloatArray, bool]:
    """One fusion step of ``T`` targets with one scan of every sensor.

    Parameters
    ----------
    algorithm : one of :data:`ALGORITHMS`
    x : (T, n), P : (T, n, n) estimates at the previous fusion time
    z : S arrays ``(M_s, m)``, the sensors' measurements, in processing order
    dt : S time steps, s: ``dt[0]`` from the previous fusion time to sensor 0's scan,
        ``dt[s]`` from sensor ``s - 1``'s scan to sensor ``s``'s (all 0 but ``dt[0]`` for the
        centralised trackers)
    sensors : S measurement models; motion : linear motion model; config : FusionConfig

    Returns
    -------
    x : (T, n), P : (T, n, n), gap : bool (``sd_gnn`` only: the S-D solve kept a duality gap)
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    z = [np.asarray(zs, dtype=float).reshape(-1, sensors[0].dim_z) for zs in z]
    if algorithm == "sequential":
        for s, model in enumerate(sensors):
            F, Q = motion.F(dt[s]), motion.Q(dt[s])
            st = jpda_step(x, P, z[s], F, Q, model, config.jpda(s))
            x, P = st.x, st.P
        return x, P, False
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
    xp, Pp = kf_predict(x, P, motion.F(dt[0]), motion.Q(dt[0]))
    terms = sensor_terms(xp, Pp, z, sensors, config)
    T = x.shape[0]
    if algorithm == "sd_gnn":
        Lbest, gap = sd_gnn_tuples(terms, config.max_tuples)
        xn, Pn = _stacked(xp, Pp, np.arange(T), Lbest, terms, sensors)
        return xn, Pn, gap
    target, L, beta = tuple_marginals(terms.beta)
    n_tuples = np.bincount(target, minlength=T)
    if n_tuples.max() > config.max_tuples:
        t = int(np.argmax(n_tuples))
        raise ValueError(f"target {t}: {n_tuples[t]} gated S-tuples > max_tuples")
    if algorithm == "sdcmsjpda":
        b = nonparametric_b(config, sensors[0].dim_z)
        xn, Pn = np.empty_like(xp), np.empty_like(Pp)
        for t in range(T):
            mine = target == t
            xn[t], Pn[t] = _literal_update(xp, Pp, L[mine], beta[mine], terms, b, t)
        return xn, Pn, False
    if algorithm == "parallel":
        xs, Ps = _stacked(xp, Pp, target, L, terms, sensors)
    else:
        xs, Ps = _equivalent_updates(xp, Pp, target, L, terms, sensors)
    if algorithm == "sdcmsjpda_joint":
        beta = joint_tuple_marginals(Pp, target, L, terms, sensors, config)
    xn, Pn = _mixtures(target, beta, xs, Ps)
    return xn, Pn, False


def _silence(valid: BoolArray) -> tuple[IntArray, IntArray]:
    """Empty scans and the longest run of them, per sensor, from ``valid (K, S, N)``."""
    empty = np.logical_not(np.any(valid, axis=-1)).reshape(valid.shape[:2])  # (K, S)
    longest = np.zeros(empty.shape[1], dtype=np.int64)
    run = np.zeros(empty.shape[1], dtype=np.int64)
    for k in range(empty.shape[0]):
        run = np.where(empty[k], run + 1, 0)
        longest = np.maximum(longest, run)
    return empty.sum(axis=0).astype(np.int64), longest


def run_fusion(
    algorithm: Algorithm,
    scans: MultiScans,
    sensors: Sequence[MeasurementModel],
    motion: LinearMotion,
    x0: ArrayLike,
    P0: ArrayLike,
    config: FusionConfig,
    t0_s: float | None = None,
) -> FusionResult:
    """Track ``T`` targets through all scans with one fusion algorithm.

    Parameters
    ----------
    algorithm : one of :data:`ALGORITHMS`
    scans : MultiScans with ``S = len(sensors)`` sensors
    sensors : measurement models, one per sensor
    motion : linear motion model (the Kalman prediction)
    x0 : (T, n), P0 : (T, n, n) estimates at time ``t0_s``
    config : FusionConfig with one ``pd`` / ``clutter_density`` per sensor
    t0_s : float or None, time of ``x0`` (None = the first scan's earliest time stamp)

    Raises
    ------
    ValueError
        Sensor count mismatch; time stamps going backwards; for the centralised trackers, a
        scan whose sensors' time stamps differ by more than ``config.time_tolerance_s``
        (naming the scan, sensor and times). A sensor that reports nothing is no error: it
        contributes no measurement and is counted in ``empty_scans`` / ``longest_silence``.
    """
    K, S_ = scans.t_s.shape
    if len(sensors) != S_ or len(config.pd) != S_:
        raise ValueError(
            f"scans have {S_} sensors, sensors {len(sensors)}, config {len(config.pd)}"
        )
    x = np.array(x0, dtype=float)
    P = np.array(P0, dtype=float)
    t_prev = float(scans.t_s[0].min()) if t0_s is None else float(t0_s)
    xs = np.empty((K, *x.shape))
    Ps = np.empty((K, *P.shape))
    gaps = 0
    elapsed = 0.0
    _compile(algorithm)  # a one-off compilation is no part of a step's time
    for k in range(K):
        order, dt = _schedule(algorithm, k, scans.t_s[k], t_prev, config)
        z = [scans.scan(k, int(s)) for s in order]
        sens = [sensors[int(s)] for s in order]
        cfg = _reordered(config, order) if algorithm == "sequential" else config
        c0 = time.thread_time()
        x, P, gap = fusion_step(algorithm, x, P, z, dt.tolist(), sens, motion, cfg)
        elapsed += time.thread_time() - c0
        gaps += int(gap)
        xs[k], Ps[k] = x, P
        t_prev = float(scans.t_s[k, order[-1]])
    empty, longest = _silence(scans.valid)
    return FusionResult(
        x=xs,
        P=Ps,
        empty_scans=empty,
        longest_silence=longest,
        gap_scans=gaps,
        ms_per_step=1e3 * elapsed / max(K, 1),
    )


def _compile(algorithm: Algorithm) -> None:
    """Compile the numba kernels ``algorithm`` uses (nothing to do without numba)."""
    if algorithm in ("sdcmsjpda_fused", "sdcmsjpda_joint"):
        compiled_gauss_newton()
    elif algorithm == "sd_gnn":
        compile_kernels()


def _schedule(
    algorithm: Algorithm, k: int, ts: FloatArray, t_prev: float, config: FusionConfig
) -> tuple[IntArray, FloatArray]:
    """Processing order of the sensors of scan ``k`` (time stamps ``ts``) and the time steps
    :func:`fusion_step` takes; raises ``ValueError`` for a scan the tracker cannot fuse."""
    centralised = algorithm != "sequential"
    if centralised and np.ptp(ts) > config.time_tolerance_s:
        s = int(np.argmax(np.abs(ts - ts[0])))
        raise ValueError(
            f"scan {k}: sensor {s} time stamp {ts[s]:.6f} s differs from sensor 0's "
            f"{ts[0]:.6f} s; {algorithm} fuses simultaneous scans only (time_tolerance_s = "
            f"{config.time_tolerance_s}); use 'sequential' for asynchronous sensors"
        )
    order = np.argsort(ts, kind="stable") if not centralised else np.arange(ts.size)
    times = ts[order]
    if times[0] < t_prev - config.time_tolerance_s:
        raise ValueError(f"scan {k}: time stamp {times[0]} s is before {t_prev} s")
    if centralised:
        return order, np.r_[ts[0] - t_prev, np.zeros(ts.size - 1)]
    return order, np.diff(np.r_[t_prev, times])


def _reordered(config: FusionConfig, order: IntArray) -> FusionConfig:
    """``config`` with its per-sensor values in the processing ``order``."""
    return replace(
        config,
        pd=tuple(config.pd[int(s)] for s in order),
        clutter_density=tuple(config.clutter_density[int(s)] for s in order),
    )
