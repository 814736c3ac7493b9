"""Joint multitarget particle filter (JMPD) with independent-partition proposals (paper 4).

A particle is the concatenation of one *partition* (state) per target,
``particles (B, N, T, n)``: ``B`` independent filters (Monte Carlo runs or sensor-control rules
run side by side), ``N`` particles, ``T`` targets, ``n`` states per target. Weights are kept as
normalised log-weights ``(B, N)``. One call of :func:`jmpd_step` is steps 7-12 of Table 1 of Xi &
Morrell; the predicted estimates of step 4 come from :func:`predicted_estimates` and the sensor
configuration of step 5 from :mod:`navtrack.tracking.trackers.sensor_control`.

Stages (each a small function, batched over ``B`` and ``N``):

* :func:`predict_particles` — kinematic prior ``p(x_k | x_{k-1})`` for every partition;
* :func:`target_log_likelihoods` — ``log Pd g(z_j | x_t)`` and ``log (1 - Pd)`` per particle,
  target and measurement;
* :func:`association_hypotheses` / :func:`joint_log_likelihood` — the sum over the feasible
  joint association hypotheses of step 8;
* :func:`ip_jpda_log_likelihoods` (Table 2, step 1b-c), :func:`gnn_assignment` (the paper's GNN:
  gated one-to-one assignment of least total distance) and :func:`ip_gnn_log_likelihoods` —
  partition weights of the independent-partition proposals, and :func:`resample_partitions`
  (Table 2, steps 2-3) giving the bias terms;
* :func:`kmeans_permute` — step 10; :func:`systematic_resample` — step 12.

References
----------
.. [1] F. Xi, D. Morrell, "Tracking multiple closely spaced targets using an adaptive foveal
   sensor", ICASSP 2005, V-941..944: Tables 1 and 2, section V.
.. [2] M. Orton, W. Fitzgerald, "A Bayesian approach to tracking multiple targets using sensor
   arrays and particle filters", IEEE T-SP 50(2), 2002 (independent partitions, permutation).
.. [3] C. Kreucher, K. Kastella, A. O. Hero, "Multitarget tracking using the joint multitarget
   probability density", IEEE T-AES 41(4), 2005 (IP proposal with bias terms, K-means
   partition sorting).
.. [4] Y. Bar-Shalom, T. E. Fortmann, *Tracking and Data Association*, Academic Press 1988,
   section 9.4 (JPDA joint-event likelihood with Poisson clutter).
.. [5] S. Blackman, R. Popoli, *Design and Analysis of Modern Tracking Systems*, Artech House
   1999, section 6.4 (GNN: gated one-to-one assignment of least total distance).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from enum import IntEnum
from functools import lru_cache
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.kalman import kf_predict
from navtrack.tracking.models import FovealScan, FovealSensor, LinearMotion, constant_velocity

__all__ = [
    "MAX_HYPOTHESES",
    "JmpdConfig",
    "JmpdState",
    "JmpdStep",
    "Proposal",
    "StepStatus",
    "association_hypotheses",
    "effective_sample_size",
    "gnn_assignment",
    "hypothesis_count",
    "ip_gnn_log_likelihoods",
    "ip_jpda_log_likelihoods",
    "jmpd_init",
    "jmpd_step",
    "joint_log_likelihood",
    "kmeans_permute",
    "measurement_distances",
    "predict_particles",
    "predicted_estimates",
    "resample_partitions",
    "systematic_resample",
    "target_log_likelihoods",
    "weighted_estimates",
]

#: Largest number of joint association hypotheses enumerated in one scan. ``T`` targets and
#: ``M`` measurements give ``sum_k C(T, k) M!/(M-k)!`` hypotheses (3 targets, 5 measurements:
#: 136; 6 targets, 6 measurements: 13 327; 7 targets, 7 measurements: 130 922).
MAX_HYPOTHESES = 20_000

Proposal = Literal["kp", "ip_jpda", "ip_gnn", "ip_gnn_joint"]
_PROPOSALS = ("kp", "ip_jpda", "ip_gnn", "ip_gnn_joint")

_LOG_TINY = math.log(np.finfo(float).tiny)


class StepStatus(IntEnum):
    """Outcome of one filter step for one batch element (``JmpdStep.status``)."""

    OK = 0
    """Weights updated normally."""
    UNDERFLOW_RECOVERED = 1
    """Every particle's likelihood was below the smallest normal float (linear weights would all
    be zero); the log-domain normalisation kept them."""
    NO_FEASIBLE_HYPOTHESIS = 2
    """No particle had a feasible association of the scan (all likelihoods exactly zero, e.g. more
    measurements than targets without clutter): the scan was not used, prior weights kept."""
    TOO_MANY_HYPOTHESES = 3
    """The scan had so many measurements that the joint hypotheses exceed
    :data:`MAX_HYPOTHESES`: the scan was not used (prediction only)."""


@dataclass(frozen=True, slots=True)
class JmpdConfig:
    """Configuration of the joint multitarget particle filter.

    Parameters
    ----------
    motion : LinearMotion
        Per-target motion model (paper: 1-D constant velocity, ``q = 0.01``). Default
        ``constant_velocity(1, 0.01, "continuous")``.
    dt : float
        Time between scans, s (paper: 1).
    n_particles : int
        ``N_part`` (paper: 400); >= 1.
    proposal : {"kp", "ip_jpda", "ip_gnn", "ip_gnn_joint"}
        Kinematic prior, or an independent-partition proposal with JPDA or GNN partition weights
        (paper section V). ``ip_gnn`` is the paper's GNN: per particle, the gated one-to-one
        assignment of measurements to partitions of least total normalised distance
        (:func:`gnn_assignment`); ``ip_gnn_joint`` takes instead each particle's most likely
        joint association hypothesis with its miss and clutter terms (a variant, not the
        paper's).
    gnn_gate : float
        Gate of ``ip_gnn`` on the normalised squared distance ``(z - h(x))² / R`` (the paper does
        not give it; 9 = three standard deviations). A partition left unassigned costs the gate.
    resample_fraction : float
        ``N_T = resample_fraction * n_particles``: resample when ``N_eff < N_T`` (Table 1 step
        12; the paper does not give ``N_T``; 0.5 is the common choice).
    kmeans_iterations : int
        Passes of the K-means partition permutation (Table 1 step 10); 0 disables it.

    Notes
    -----
    The paper's Q is "a zero-mean Gaussian process with covariance Q" without its form; the
    continuous white-noise acceleration form (Bar-Shalom eq. 6.2.2-12) is the default, full
    rank; ``noise="discrete"`` models are accepted too.
    """

    motion: LinearMotion = field(default_factory=lambda: constant_velocity(1, 0.01, "continuous"))
    dt: float = 1.0
    n_particles: int = 400
    proposal: Proposal = "ip_jpda"
    resample_fraction: float = 0.5
    kmeans_iterations: int = 3
    gnn_gate: float = 9.0

    def __post_init__(self) -> None:
        if isinstance(self.n_particles, bool) or int(self.n_particles) != self.n_particles:
            raise ValueError(f"n_particles must be an integer, got {self.n_particles!r}")
        if self.n_particles < 1:
            raise ValueError(f"n_particles (N_part) must be >= 1, got {self.n_particles}")
        if self.proposal not in _PROPOSALS:
            raise ValueError(f"proposal must be one of {_PROPOSALS}, got {self.proposal!r}")
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt must be > 0, got {self.dt}")
        if not 0.0 < self.resample_fraction <= 1.0:
            raise ValueError(f"resample_fraction must be in (0, 1], got {self.resample_fraction}")
        if self.kmeans_iterations < 0:
            raise ValueError(f"kmeans_iterations must be >= 0, got {self.kmeans_iterations}")
        if not self.gnn_gate > 0:
            raise ValueError(f"gnn_gate must be > 0, got {self.gnn_gate}")


@dataclass(frozen=True, slots=True, eq=False)
class JmpdState:
    """Particles, weights and per-target estimates of ``B`` filters (arrays read-only).

    Attributes
    ----------
    particles : (B, N, T, n) float
        Concatenated partitions.
    log_weights : (B, N) float
        Normalised log-weights (``logsumexp = 0`` over ``N``).
    x : (B, T, n) float
        Weighted-mean state of each target (Table 1 step 11).
    P : (B, T, n, n) float
        Weighted covariance of each target's partition.
    """

    particles: FloatArray
    log_weights: FloatArray
    x: FloatArray
    P: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class JmpdStep:
    """Result of one :func:`jmpd_step` (arrays read-only).

    Attributes
    ----------
    state : JmpdState
        Posterior after the step (after resampling when it happened).
    status : (B,) int
        :class:`StepStatus` of each filter.
    n_eff : (B,) float
        Effective sample size before resampling (Table 1 step 12).
    resampled : (B,) bool
    n_hypotheses : int
        Joint association hypotheses enumerated (0 when the scan was not used).
    """

    state: JmpdState
    status: IntArray
    n_eff: FloatArray
    resampled: BoolArray
    n_hypotheses: int

    def __post_init__(self) -> None:
        freeze_arrays(self)


# ------------------------------------------------------------------------------ hypotheses


def hypothesis_count(n_targets: int, n_measurements: int) -> int:
    """Number of feasible joint association hypotheses, ``sum_k C(T, k) M!/(M-k)!``.

    A hypothesis assigns each target either one measurement or none (missed), no measurement to
    two targets; unassigned measurements are clutter.
    """
    T, M = int(n_targets), int(n_measurements)
    return sum(math.comb(T, k) * math.perm(M, k) for k in range(min(T, M) + 1))


@lru_cache(maxsize=256)
def _hypotheses(T: int, M: int) -> IntArray:
    rows = []
    for k in range(min(T, M) + 1):
        for targets in itertools.combinations(range(T), k):
            for meas in itertools.permutations(range(M), k):
                row = [-1] * T
                for t, j in zip(targets, meas, strict=True):
                    row[t] = j
                rows.append(row)
    H = np.array(rows, dtype=np.int64).reshape(len(rows), T)
    H.flags.writeable = False
    return H


def association_hypotheses(n_targets: int, n_measurements: int) -> IntArray:
    """All feasible joint association hypotheses of ``T`` targets and ``M`` measurements.

    Returns
    -------
    H : (N_H, T) int, read-only
        ``H[h, t]`` = measurement index assigned to target ``t`` under hypothesis ``h``, or
        ``-1`` when ``t`` is not detected. Row 0 is "no target detected".

    Raises
    ------
    ValueError
        When ``N_H`` exceeds :data:`MAX_HYPOTHESES` (the message gives the count and the limit).
    """
    T, M = int(n_targets), int(n_measurements)
    if T < 1 or M < 0:
        raise ValueError(f"need n_targets >= 1 and n_measurements >= 0, got {T}, {M}")
    n = hypothesis_count(T, M)
    if n > MAX_HYPOTHESES:
        raise ValueError(
            f"{T} targets and {M} measurements give {n} joint association hypotheses, more than "
            f"the enumeration limit MAX_HYPOTHESES = {MAX_HYPOTHESES}"
        )
    return _hypotheses(T, M)


def _check_target_count(T: int) -> None:
    n = hypothesis_count(T, T)
    if n > MAX_HYPOTHESES:
        raise ValueError(
            f"{T} targets cannot be handled by the hypothesis enumeration: even a scan with one "
            f"detection per target gives {n} joint hypotheses, more than the limit "
            f"MAX_HYPOTHESES = {MAX_HYPOTHESES} (at most 6 targets)"
        )


# ------------------------------------------------------------------------------ likelihoods


def _logsumexp(a: FloatArray, axis: int) -> FloatArray:
    if a.shape[axis] == 0:  # an empty sum (a scan without measurements)
        return np.full(np.delete(a.shape, axis), -np.inf)
    m = np.max(a, axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        s = np.log(np.sum(np.exp(a - m), axis=axis, keepdims=True))
    return np.asarray(np.squeeze(s + m, axis=axis))


def _log(x: float) -> float:
    return math.log(x) if x > 0 else -math.inf


def target_log_likelihoods(
    particles: FloatArray, scan: FovealScan, c: ArrayLike, d: ArrayLike, sensor: FovealSensor
) -> FloatArray:
    """Per-target detection log-likelihoods of every particle.

    Parameters
    ----------
    particles : (B, N, T, n)
    scan : FovealScan with ``z, valid (B, M)``
    c, d : (B,) sensor gain (1/m) and centre (m)
    sensor : FovealSensor

    Returns
    -------
    L : (B, N, T, M + 1)
        ``L[..., t, j] = log(Pd g(z_j | x_t))`` for valid ``j < M`` (``-inf`` for padding), and
        ``L[..., t, M] = log(1 - Pd)`` (target not detected).
    """
    c = np.asarray(c, dtype=float)[:, None, None, None]
    d = np.asarray(d, dtype=float)[:, None, None, None]
    z = scan.z[:, None, None, :]
    ll = sensor.log_likelihood(z, particles[..., None, :], c, d) + math.log(sensor.pd)
    ll = np.where(scan.valid[:, None, None, :], ll, -np.inf)
    miss = np.full((*ll.shape[:-1], 1), _log(1.0 - sensor.pd))
    return np.concatenate([ll, miss], axis=-1)


def joint_log_likelihood(
    L: FloatArray, valid: BoolArray, clutter_density: float
) -> tuple[FloatArray, IntArray, int]:
    """``log sum_l p(z_k | theta_l, x_i)`` over the feasible joint hypotheses (Table 1 step 8).

    Parameters
    ----------
    L : (B, N, T, M + 1)
        From :func:`target_log_likelihoods`; the valid measurements of each row must come first
        (as :meth:`~navtrack.tracking.models.FovealSensor.scan` returns them).
    valid : (B, M) bool
    clutter_density : float
        λ, false alarms per rad.

    Returns
    -------
    loglik : (B, N)
        Up to a constant per scan: ``log sum_h prod_{t detected} Pd g(z_{h_t}|x_t)
        prod_{t missed} (1 - Pd) λ^(number of clutter measurements)`` (Bar-Shalom & Fortmann
        9.4; the Poisson clutter-count factor and ``V^-M`` are common to all particles).
    best : (B, N, T) int
        The most likely hypothesis of each particle (proposal ``ip_gnn_joint``): measurement
        index assigned to each target, ``-1`` when not detected.
    n_hypotheses : int
        Hypotheses enumerated for the row with the most measurements.

    Notes
    -----
    Rows are grouped by their count of valid measurements, so padding costs nothing. Within a
    group the sum is taken in the linear domain after shifting each target's terms by their
    maximum (``prod_t`` of numbers <= 1 times the clutter weight); particles whose shifted sum
    underflows to 0 are recomputed by log-sum-exp, so nothing is lost to underflow.
    """
    B, N, T, M1 = L.shape
    counts = valid.sum(axis=-1)
    loglik = np.empty((B, N))
    best = np.full((B, N, T), -1, dtype=np.int64)
    log_lam = _log(clutter_density)
    n_max = 0
    for m in np.unique(counts):
        rows = np.flatnonzero(counts == m)
        H = association_hypotheses(T, int(m))
        cols = np.where(H < 0, M1 - 1, H)
        n_clutter = int(m) - (H >= 0).sum(axis=-1)
        with np.errstate(invalid="ignore"):
            log_c = np.where(n_clutter > 0, n_clutter * log_lam, 0.0)  # (N_H,)
        Lg = L[rows][..., np.r_[0 : int(m), M1 - 1]]  # (G, N, T, m + 1)
        top = Lg.max(axis=-1, keepdims=True)
        top = np.where(np.isfinite(top), top, 0.0)
        E = np.exp(Lg - top)
        mc = np.where(H < 0, int(m), H)
        prod = np.prod(E[..., np.arange(T), mc], axis=-1)  # (G, N, N_H)
        c_top = float(log_c.max()) if np.isfinite(log_c.max()) else 0.0
        wc = np.exp(log_c - c_top)
        total = prod @ wc
        with np.errstate(divide="ignore"):
            ll = np.log(total) + top[..., 0].sum(axis=-1) + c_top
        lost = total == 0.0
        if np.any(lost):
            g, i = np.nonzero(lost)
            per_h = L[rows[g], i][:, np.arange(T), cols].sum(axis=-1) + log_c
            ll[g, i] = _logsumexp(per_h, axis=-1)
        loglik[rows] = ll
        best[rows] = H[np.argmax(prod * wc, axis=-1)]
        n_max = max(n_max, int(H.shape[0]))
    return loglik, best, n_max


def ip_jpda_log_likelihoods(L: FloatArray, sensor: FovealSensor) -> FloatArray:
    """Partition log-weights of IP-JPDA: JPDA for each target alone (Table 2 step 1b-c).

    Parameters
    ----------
    L : (B, N, T, M + 1) from :func:`target_log_likelihoods`
    sensor : FovealSensor

    Returns
    -------
    (B, N, T)
        ``log[(1 - Pd) λ_t + sum_j Pd g(z_j | x_t)]``, the sum over the ``M + 1`` hypotheses of
        one target (none or one of the ``M`` measurements is its own; the rest are false alarms)
        divided by the common ``λ_t^(M-1)``.

    Notes
    -----
    The paper treats "observations from other targets as false alarms"; the false-alarm
    density used is therefore ``λ_t = λ + (T - 1) Pd / V``: the clutter plus the expected
    detections of the other targets spread over the measurement space (without it, a scan
    without clutter would make every single-target hypothesis impossible before the common
    factor is divided out). It weighs only the missed-detection term, so it matters for
    ``Pd < 1``.
    """
    T = L.shape[-2]
    lam_t = sensor.clutter_density + (T - 1) * sensor.pd / sensor.volume
    detected = _logsumexp(L[..., :-1], axis=-1)
    with np.errstate(divide="ignore"):
        missed = L[..., -1] + _log(lam_t)
    return np.asarray(np.logaddexp(detected, missed))


def measurement_distances(
    particles: FloatArray, scan: FovealScan, c: ArrayLike, d: ArrayLike, sensor: FovealSensor
) -> FloatArray:
    """Normalised squared distances ``(z_j - h(x_t))² / R`` of every particle's partitions.

    ``particles (B, N, T, n)``, ``scan.z (B, M)``, ``c, d (B,)`` -> ``(B, N, T, M)``, ``inf``
    for padding measurements.
    """
    c = np.asarray(c, dtype=float)[:, None, None, None]
    d = np.asarray(d, dtype=float)[:, None, None, None]
    r = scan.z[:, None, None, :] - sensor.h(particles[..., None, :], c, d)
    return np.asarray(np.where(scan.valid[:, None, None, :], r * r / sensor.R, np.inf))


def gnn_assignment(D2: FloatArray, valid: BoolArray, gate: float) -> IntArray:
    """Gated one-to-one assignment of least total distance, per particle (the paper's GNN).

    Parameters
    ----------
    D2 : (B, N, T, M) float
        Normalised squared distances (:func:`measurement_distances`); the valid measurements
        of each row come first.
    valid : (B, M) bool
    gate : float
        A pair with ``D2 >= gate`` cannot be assigned; a partition left unassigned costs
        ``gate`` (Blackman & Popoli's non-assignment cost).

    Returns
    -------
    (B, N, T) int
        Measurement assigned to each partition, ``-1`` when none: the assignment minimising
        ``sum_assigned D2 + gate * (number unassigned)``, found exactly by enumerating the
        one-to-one assignments (:func:`association_hypotheses`).
    """
    B, N, T, _ = D2.shape
    counts = valid.sum(axis=-1)
    best = np.full((B, N, T), -1, dtype=np.int64)
    for m in np.unique(counts):
        rows = np.flatnonzero(counts == m)
        H = association_hypotheses(T, int(m))
        D = D2[rows][..., : int(m)]
        gated = np.where(D < gate, D, np.inf)  # noqa: SIM300 (D is an array)
        C = np.concatenate([gated, np.full((*D.shape[:-1], 1), gate)], axis=-1)
        cost = C[..., np.arange(T), np.where(H < 0, int(m), H)].sum(axis=-1)  # (G, N, N_H)
        best[rows] = H[np.argmin(cost, axis=-1)]
    return best


def ip_gnn_log_likelihoods(L: FloatArray, assignment: IntArray) -> FloatArray:
    """Partition log-weights of IP-GNN: each partition's term under its assignment.

    Parameters
    ----------
    L : (B, N, T, M + 1)
    assignment : (B, N, T) int
        Measurement assigned to each partition of each particle, ``-1`` when none: the paper's
        GNN (:func:`gnn_assignment`) or the most likely joint hypothesis
        (:func:`joint_log_likelihood`, proposal ``ip_gnn_joint``).

    Returns
    -------
    (B, N, T)
        ``log Pd g(z_j|x_t)`` of the assigned measurement, ``log(1 - Pd)`` when unassigned.
    """
    M = L.shape[-1] - 1
    cols = np.where(assignment < 0, M, assignment)
    return np.take_along_axis(L, cols[..., None], axis=-1)[..., 0]


# ------------------------------------------------------------------------------ sampling


def systematic_resample(log_weights: FloatArray, rng: np.random.Generator) -> IntArray:
    """Systematic resampling indices, batched over leading axes.

    Parameters
    ----------
    log_weights : (..., N)
        Log-weights (need not be normalised); a row that is all ``-inf`` is drawn uniformly.
    rng : numpy.random.Generator

    Returns
    -------
    (..., N) int
        Ancestor indices, non-decreasing along the last axis.
    """
    lw = np.asarray(log_weights, dtype=float)
    batch, N = lw.shape[:-1], lw.shape[-1]
    lw = np.where(np.isfinite(lw.max(axis=-1, keepdims=True)), lw, 0.0)
    w = np.exp(lw - lw.max(axis=-1, keepdims=True))
    cdf = np.cumsum(w, axis=-1)
    cdf = cdf / cdf[..., -1:]
    cdf[..., -1] = 1.0
    rows = np.arange(math.prod(batch), dtype=float).reshape(*batch, 1)
    u = (rng.random((*batch, 1)) + np.arange(N)) / N
    idx = np.searchsorted((cdf + rows).ravel(), (u + rows).ravel(), side="right")
    idx = idx.reshape(*batch, N) - (rows * N).astype(np.int64)
    return np.asarray(np.clip(idx, 0, N - 1), dtype=np.int64)


def _sqrt_psd(Q: FloatArray) -> FloatArray:
    """A matrix ``S`` with ``S Sᵀ = Q`` for a symmetric positive semi-definite ``Q``."""
    vals, vecs = np.linalg.eigh(Q)
    return np.asarray(vecs * np.sqrt(np.clip(vals, 0.0, None)))


def predict_particles(
    particles: FloatArray, motion: LinearMotion, dt: float, rng: np.random.Generator
) -> FloatArray:
    """Sample every partition from the kinematic prior ``x' = F x + n``, ``n ~ N(0, Q)``."""
    n = particles.shape[-1]
    noise = rng.standard_normal((particles.size // n, n)) @ _sqrt_psd(motion.Q(dt)).T
    return np.asarray(motion.f(particles, dt) + noise.reshape(particles.shape))


def resample_partitions(
    particles: FloatArray,
    log_prior: FloatArray,
    log_partition: FloatArray,
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Draw each target's partitions independently by their weights (Table 2 steps 2-3).

    Parameters
    ----------
    particles : (B, N, T, n)
        Proposed partitions (from the kinematic prior).
    log_prior : (B, N)
        Log-weights of the particles before the scan.
    log_partition : (B, N, T)
        Partition log-likelihoods (:func:`ip_jpda_log_likelihoods` or
        :func:`ip_gnn_log_likelihoods`).
    rng : numpy.random.Generator

    Returns
    -------
    particles : (B, N, T, n)
        New particles; partition ``t`` of particle ``i`` is partition ``t`` of particle
        ``j_t(i)``.
    log_bias : (B, N, T)
        ``log b_{t,i}`` = the partition log-likelihood of the chosen partition.
    idx : (B, N, T) int
        ``j_t(i)``.
    """
    lw = log_prior[:, :, None] + log_partition  # (B, N, T)
    idx = systematic_resample(np.moveaxis(lw, 1, 2), rng)  # (B, T, N)
    idx = np.moveaxis(idx, 1, 2)  # (B, N, T)
    chosen = _partition_index(idx)
    return particles[chosen], log_partition[chosen], idx


def _partition_index(idx: IntArray) -> tuple[IntArray, IntArray, IntArray]:
    """Index of ``a[b, idx[b, i, t], t]`` for arrays ``a (B, N, T, ...)``: partition ``t`` of
    particle ``idx[b, i, t]``."""
    B, _, T = idx.shape
    return (np.arange(B)[:, None, None], idx, np.arange(T)[None, None, :])


# ------------------------------------------------------------------------------ estimates


def weighted_estimates(
    particles: FloatArray, log_weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Weighted mean ``(B, T, n)`` and covariance ``(B, T, n, n)`` of each target's partition."""
    B, N, T, n = particles.shape
    w = np.exp(log_weights)[:, None, :]  # (B, 1, N)
    x = (w @ particles.reshape(B, N, T * n)).reshape(B, T, n)
    e = np.moveaxis(particles - x[:, None], 1, -1)  # (B, T, n, N)
    P = (e * w[:, None]) @ np.swapaxes(e, -1, -2)
    return x, P


def predicted_estimates(
    state: JmpdState, motion: LinearMotion, dt: float
) -> tuple[FloatArray, FloatArray]:
    """Step 4 of Table 1: ``x⁻ = F x̂``, ``P⁻ = F P̂ Fᵀ + Q`` per target, ``(B, T, n[, n])``."""
    return kf_predict(state.x, state.P, motion.F(dt), motion.Q(dt))


def effective_sample_size(log_weights: FloatArray) -> FloatArray:
    """``N_eff = 1 / sum_i w_i²`` of normalised log-weights ``(..., N)`` -> ``(...)``."""
    return np.asarray(1.0 / np.sum(np.exp(2.0 * log_weights), axis=-1))


@lru_cache(maxsize=16)
def _permutations(T: int) -> IntArray:
    p = np.array(list(itertools.permutations(range(T))), dtype=np.int64)
    p.flags.writeable = False
    return p


def kmeans_permute(
    particles: FloatArray, log_weights: FloatArray, iterations: int, dt: float = 1.0
) -> FloatArray:
    """Relabel the partitions of each particle to the nearest target centres (Table 1 step 10).

    K-means with the ``T`` centres = weighted means of the partitions: each particle takes the
    permutation of its partitions that minimises the summed squared distance to the centres,
    then the centres are recomputed (Kreucher et al. 2005, section IV-C).

    Parameters
    ----------
    particles : (B, N, T, n)
    log_weights : (B, N)
    iterations : int
        Passes (stops early when no particle changes).
    dt : float
        The distance is over ``[X, Xdot·dt]`` (position now and the displacement per scan), s.

    Returns
    -------
    (B, N, T, n)
    """
    T, n = particles.shape[-2:]
    if T == 1 or iterations == 0:
        return particles
    B, N = particles.shape[:2]
    perms = _permutations(T)
    # select[s * T + t, p] = 1 when permutation p moves source partition s to target t
    select = np.zeros((T * T, len(perms)))
    select[perms * T + np.arange(T), np.arange(len(perms))[:, None]] = 1.0
    scale = np.where(np.arange(n) % 2 == 0, 1.0, dt * dt)
    w = np.exp(log_weights)[:, None, :]  # (B, 1, N)
    rows = (np.arange(B)[:, None, None], np.arange(N)[None, :, None])
    x = particles
    for _ in range(iterations):
        mu = (w @ x.reshape(B, N, T * n)).reshape(B, T, n) * scale
        # sum_t |x_perm(t) - mu_t|² = const - 2 sum_t x_perm(t) · mu_t
        C = x.reshape(B, N * T, n) @ np.swapaxes(mu, -1, -2)  # (B, N T_src, T_dst)
        best = np.argmax(C.reshape(B, N, T * T) @ select, axis=-1)  # (B, N)
        if not np.any(best):
            break
        x = x[(*rows, perms[best])]
    return np.asarray(x)


# ------------------------------------------------------------------------------ filter


def jmpd_init(
    x0: ArrayLike, P0: ArrayLike, config: JmpdConfig, rng: np.random.Generator
) -> JmpdState:
    """Initial particles from ``N(x0, P0)`` with equal weights (Table 1 steps 1-2).

    Parameters
    ----------
    x0 : (B, T, n) float
        Initial mean of every target of every filter.
    P0 : (n, n) float
        Initial covariance of a partition (paper: ``diag(1, 0.1)``), positive semi-definite.
    config : JmpdConfig
    rng : numpy.random.Generator
    """
    x0 = np.asarray(x0, dtype=float)
    P0 = np.asarray(P0, dtype=float)
    if x0.ndim != 3:
        raise ValueError(f"x0 must be (B, T, n), got shape {x0.shape}")
    B, T, n = x0.shape
    if n != config.motion.dim_x:
        raise ValueError(f"x0 has {n} states per target, the motion model {config.motion.dim_x}")
    if P0.shape != (n, n) or not np.all(np.isfinite(P0)):
        raise ValueError(f"P0 must be a finite ({n}, {n}) covariance, got shape {P0.shape}")
    _check_target_count(T)
    N = config.n_particles
    particles = x0[:, None] + rng.standard_normal((B, N, T, n)) @ _sqrt_psd(P0).T
    log_w = np.full((B, N), -math.log(N))
    return JmpdState(particles, log_w, *weighted_estimates(particles, log_w))


def jmpd_step(
    state: JmpdState,
    scan: FovealScan,
    c: ArrayLike,
    d: ArrayLike,
    sensor: FovealSensor,
    config: JmpdConfig,
    rng: np.random.Generator,
) -> JmpdStep:
    """One scan of the joint multitarget particle filter (Table 1 steps 7-12): a :class:`JmpdStep`.

    Parameters
    ----------
    state : JmpdState, the posterior at ``k - 1``
    scan : FovealScan, measurements ``z, valid (B, M)`` taken with gain ``c`` and centre ``d``
    c, d : (B,) float, foveal gain (1/m) and centre (m) used for the scan
    sensor : FovealSensor; config : JmpdConfig; rng : numpy.random.Generator

    Notes
    -----
    Weights. KP: ``w_i ∝ w_{i,k-1} sum_l p(z | theta_l, x_i)``. IP proposals: the partitions of
    target ``t`` are drawn from the predicted partitions with probability
    ``∝ w_{j,k-1} l_t(x_{t,j})`` (Table 2, with the previous weight folded in so that it also
    holds between resamplings) and ``w_i ∝ sum_l p(z | theta_l, x_i) / prod_t b_{t,i}`` with
    ``b_{t,i} = l_t`` of the chosen partition. With equal previous weights (after a
    resampling) this is exactly Table 1 step 8 with Table 2; the general form is the importance
    weight under the independent-partition (product of marginals) prior.
    """
    B, N, T, _ = state.particles.shape
    c = np.broadcast_to(np.asarray(c, dtype=float), (B,))
    d = np.broadcast_to(np.asarray(d, dtype=float), (B,))
    if scan.z.shape[0] != B:
        raise ValueError(f"scan has {scan.z.shape[0]} batch rows, the state {B}")
    pred = predict_particles(state.particles, config.motion, config.dt, rng)
    status = np.zeros(B, dtype=np.int64)
    M = scan.z.shape[-1]
    if hypothesis_count(T, M) > MAX_HYPOTHESES:
        status[:] = StepStatus.TOO_MANY_HYPOTHESES
        log_w, n_h = state.log_weights, 0
    else:
        L = target_log_likelihoods(pred, scan, c, d, sensor)
        if config.proposal == "kp":
            loglik, _, n_h = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
            log_w = state.log_weights + loglik
            fallback = state.log_weights
        else:
            log_part = _partition_log_likelihoods(L, pred, scan, c, d, sensor, config)
            pred, log_bias, idx = resample_partitions(pred, state.log_weights, log_part, rng)
            L = L[_partition_index(idx)]
            loglik, _, n_h = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
            with np.errstate(invalid="ignore"):
                log_w = loglik - log_bias.sum(axis=-1)
            log_w = np.where(np.isnan(log_w), -np.inf, log_w)
            fallback = np.full((B, N), -math.log(N))
        top = log_w.max(axis=-1)
        dead = ~np.isfinite(top)
        status[top < _LOG_TINY] = StepStatus.UNDERFLOW_RECOVERED
        status[dead] = StepStatus.NO_FEASIBLE_HYPOTHESIS
        log_w = np.where(dead[:, None], fallback, log_w)
    log_w = log_w - _logsumexp(log_w, axis=-1)[:, None]
    particles = kmeans_permute(pred, log_w, config.kmeans_iterations, config.dt)
    x, P = weighted_estimates(particles, log_w)
    n_eff = effective_sample_size(log_w)
    resampled = n_eff < config.resample_fraction * N
    if np.any(resampled):
        idx = systematic_resample(log_w[resampled], rng)
        particles = particles.copy()
        particles[resampled] = np.take_along_axis(particles[resampled], idx[..., None, None], 1)
        log_w = np.where(resampled[:, None], -math.log(N), log_w)
    return JmpdStep(JmpdState(particles, log_w, x, P), status, n_eff, resampled, n_h)


def _partition_log_likelihoods(
    L: FloatArray,
    pred: FloatArray,
    scan: FovealScan,
    c: FloatArray,
    d: FloatArray,
    sensor: FovealSensor,
    config: JmpdConfig,
) -> FloatArray:
    """Per-target partition log-likelihoods of the IP proposal ``config.proposal``."""
    if config.proposal == "ip_jpda":
        return ip_jpda_log_likelihoods(L, sensor)
    if config.proposal == "ip_gnn":
        D2 = measurement_distances(pred, scan, c, d, sensor)
        return ip_gnn_log_likelihoods(L, gnn_assignment(D2, scan.valid, config.gnn_gate))
    _, best, _ = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
    return ip_gnn_log_likelihoods(L, best)
