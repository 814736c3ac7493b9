"""Sequences of camera fixes, their corrected starts and the weighted attitude (paper 6, eqs. 5-7).

The paper groups the camera fixes into sequences of consecutive images (one per pass over the
target site). For each sequence it propagates the gyro from the sequence's first fix, takes the
errors ``e_s``, ``e_v`` at the sequence's fixes (eq. 5), forms the correction quaternion and the
corrected start ``q0`` at the first fix, and the standard deviation ``σ0`` of ``e_s``. Then every
sequence's ``q0`` is propagated across the whole flight; at each step the ``M`` propagations are
averaged in axis-angle form with the weights of eq. 6-7:

``σ_j(t_k) = σ0_j + b |t_k - t_q0_j|``,  ``w_j = σ_j⁻¹``,  ``u = (1/W) Σ_j w_j θ_j a_j``

and ``u`` is turned back into a quaternion (``[v sin(θ/2), cos(θ/2)]``, ``θ = |u|``,
``v = u/θ``).

Readings (parameters, see docs/attitude.md): the paper leaves ``b`` unset ("an arbitrary scale
factor"), does not say whether ``σ0`` is taken before or after the sequence's correction, and
prints the weight as ``σ_j`` to a power lost in the extraction (read ``-1``). The average of
eq. 7 is of absolute axis-angle vectors (``absolute``), which is undefined where the attitudes
straddle a rotation of π; ``relative`` averages the axis-angle vectors relative to the
best-weighted propagation instead (equal to first order where both are defined).

References
----------
.. [1] ALHAT flash-LIDAR field test 1, trajectory reconstruction (paper 6): eq. 5, the
   correction quaternion below it, "Determining the attitude of the IMU with respect to ECI",
   eqs. 6-7.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.attitude.quaternion import (
    CorrectionReading,
    Method,
    attitude_errors,
    check_quaternions,
    correction_quaternion,
    delta_angles,
    delta_quaternions,
    interpolate_attitude,
    propagate,
    qmul,
)

__all__ = [
    "AverageReading",
    "SequenceStarts",
    "Sigma0Reading",
    "propagate_from_fix",
    "sequence_starts",
    "split_sequences",
    "weighted_attitude",
]

AverageReading = Literal["absolute", "relative"]
Sigma0Reading = Literal["after", "before"]


def split_sequences(fix_t_s: ArrayLike, max_gap_s: float) -> IntArray:
    """Sequence label ``(m,)`` of each fix: a new sequence starts after a gap > ``max_gap_s``."""
    t = np.asarray(fix_t_s, dtype=np.float64)
    if t.ndim != 1 or np.any(np.diff(t) <= 0):
        raise ValueError("fix_t_s: (m,) strictly increasing fix times expected")
    if not max_gap_s > 0:
        raise ValueError(f"max_gap_s must be > 0, got {max_gap_s}")
    return np.concatenate([[0], np.cumsum(np.diff(t) > max_gap_s)]).astype(np.int64)


def propagate_from_fix(
    t_s: FloatArray,
    gyr_rad_s: FloatArray,
    dtheta: FloatArray,
    t_fix_s: float,
    q_fix: Rotation,
    method: Method,
    order: int,
) -> FloatArray:
    """Attitudes ``(n, 4)`` at every sample propagated forward and backward from an attitude at
    ``t_fix_s`` (which may fall between samples: the fix is first carried back to the sample
    before it by that sample's rate, the inverse of
    :func:`~navtrack.attitude.quaternion.interpolate_attitude`)."""
    k = int(np.clip(np.searchsorted(t_s, t_fix_s, side="right") - 1, 0, t_s.size - 1))
    back = delta_quaternions(-gyr_rad_s[k] * (t_fix_s - t_s[k]))
    qk = qmul(np.asarray(q_fix.as_quat(), dtype=np.float64).reshape(4), back)
    qk /= np.linalg.norm(qk)
    return np.asarray(propagate(qk, dtheta, start=k, method=method, order=order).quat)


@dataclass(frozen=True, slots=True, eq=False)
class SequenceStarts:
    """Per-sequence corrected starts and the errors of eq. 5 (arrays read-only).

    Attributes
    ----------
    labels : (m,) sequence of each fix
    e_s_before_rad, e_s_after_rad : (m,) scalar errors at each fix of its own sequence's
        propagation from the first fix (before) and from the corrected start ``q0`` (after)
    e_v_before_rad, e_v_after_rad : (m, 3) vector errors, reference frame
    t_q0_s : (M,) time of each sequence's first fix (where ``q0`` sits)
    q0 : (M, 4) corrected starts, scalar-last
    sigma0_rad : (M,) standard deviation of ``e_s`` of each sequence (reading ``sigma0``)
    quat : (M, n, 4) each ``q0`` propagated across the whole recording
    """

    labels: IntArray
    e_s_before_rad: FloatArray
    e_s_after_rad: FloatArray
    e_v_before_rad: FloatArray
    e_v_after_rad: FloatArray
    t_q0_s: FloatArray
    q0: FloatArray
    sigma0_rad: FloatArray
    quat: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def sequence_starts(
    t_s: ArrayLike,
    gyr_rad_s: ArrayLike,
    fix_t_s: ArrayLike,
    fix_quat: ArrayLike,
    labels: ArrayLike,
    *,
    method: Method = "series",
    order: int = 3,
    correction: CorrectionReading = "mean_rotvec",
    sigma0: Sigma0Reading = "after",
) -> SequenceStarts:
    """The paper's per-sequence correction (eq. 5) and each corrected start propagated over the
    whole recording.

    Parameters
    ----------
    t_s : (n,) IMU sample times, s
    gyr_rad_s : (n, 3) body rates, rad/s (in the frame the fixes are given in: inertial for
        the paper's eq. 3 chain)
    fix_t_s : (m,) fix times on the IMU clock, s, strictly increasing
    fix_quat : (m, 4) fix attitudes (IMU body -> reference), scalar-last
    labels : (m,) sequence labels 0..M-1 (:func:`split_sequences`); every sequence needs two
        fixes or more
    method, order : propagation step (the paper's third-order series by default)
    correction : reading of the correction quaternion
    sigma0 : ``after`` (std of ``e_s`` after the correction, default) or ``before``
    """
    if sigma0 not in ("after", "before"):
        raise ValueError(f"sigma0: expected 'after' or 'before', got {sigma0!r}")
    t = np.asarray(t_s, dtype=np.float64)
    w = np.asarray(gyr_rad_s, dtype=np.float64)
    d = delta_angles(t, w)
    ft = np.asarray(fix_t_s, dtype=np.float64)
    fq = check_quaternions(fix_quat, "fix_quat")
    lab = np.asarray(labels, dtype=np.int64)
    if fq.shape != (ft.size, 4) or lab.shape != ft.shape:
        raise ValueError(f"fix_t_s (m,), fix_quat (m, 4), labels (m,) expected: {fq.shape}")
    n_seq = int(lab.max()) + 1
    counts = np.bincount(lab, minlength=n_seq)
    if np.any(counts < 2):
        raise ValueError(f"labels: sequence {int(np.argmin(counts))} has fewer than two fixes")
    m = ft.size
    es_b, es_a = np.empty(m), np.empty(m)
    ev_b, ev_a = np.empty((m, 3)), np.empty((m, 3))
    t_q0, q0 = np.empty(n_seq), np.empty((n_seq, 4))
    sig0 = np.empty(n_seq)
    quat = np.empty((n_seq, t.size, 4))
    for j in range(n_seq):
        idx = np.flatnonzero(lab == j)
        first = Rotation.from_quat(fq[idx[0]])
        ref = Rotation.from_quat(fq[idx])
        plain = propagate_from_fix(t, w, d, ft[idx[0]], first, method, order)
        pred = Rotation.from_quat(interpolate_attitude(t, plain, w, ft[idx]))
        es_b[idx], ev_b[idx] = attitude_errors(pred, ref)
        start = correction_quaternion(es_b[idx], ev_b[idx], correction) * first
        quat[j] = propagate_from_fix(t, w, d, ft[idx[0]], start, method, order)
        pred = Rotation.from_quat(interpolate_attitude(t, quat[j], w, ft[idx]))
        es_a[idx], ev_a[idx] = attitude_errors(pred, ref)
        t_q0[j] = ft[idx[0]]
        q0[j] = start.as_quat()
        sig0[j] = np.std(es_a[idx] if sigma0 == "after" else es_b[idx])
    return SequenceStarts(lab, es_b, es_a, ev_b, ev_a, t_q0, q0, sig0, quat)


def weighted_attitude(
    t_s: ArrayLike,
    quat: ArrayLike,
    t_q0_s: ArrayLike,
    sigma0_rad: ArrayLike,
    b_rad_s: float,
    *,
    weight_power: float = 1.0,
    average: AverageReading = "absolute",
) -> FloatArray:
    """The weighted axis-angle average of ``M`` propagations (paper eqs. 6-7).

    Parameters
    ----------
    t_s : (n,) times, s
    quat : (M, n, 4) propagated attitudes ``p_j``, scalar-last
    t_q0_s : (M,) time of each propagation's start ``q0``
    sigma0_rad : (M,) accuracy at the start, rad (> 0)
    b_rad_s : float
        Growth of the accuracy with time from the start, rad/s (eq. 6's ``b``).
    weight_power : float
        ``w_j = σ_j^(-weight_power)`` (1: the paper's ``σ_j⁻¹``; 2: inverse variance).
    average : {"absolute", "relative"}
        Average the axis-angle vectors ``θ_j a_j`` of the attitudes themselves (eq. 7 as
        printed) or relative to the best-weighted propagation at each time.

    Returns
    -------
    (n, 4) averaged attitudes, scalar-last
    """
    t = np.asarray(t_s, dtype=np.float64)
    q = np.asarray(quat, dtype=np.float64)
    tq = np.asarray(t_q0_s, dtype=np.float64)
    s0 = np.asarray(sigma0_rad, dtype=np.float64)
    n_seq = tq.size
    if q.shape != (n_seq, t.size, 4) or s0.shape != tq.shape:
        raise ValueError(
            f"quat (M, n, 4), t_q0_s (M,), sigma0_rad (M,) expected, got {q.shape}, "
            f"{tq.shape}, {s0.shape} for n = {t.size}"
        )
    if np.any(s0 <= 0) or b_rad_s < 0:
        raise ValueError("sigma0_rad must be > 0 and b_rad_s >= 0 (eq. 6)")
    sigma = s0[:, None] + b_rad_s * np.abs(t[None, :] - tq[:, None])
    wgt = sigma ** (-weight_power)
    rot = Rotation.from_quat(q.reshape(-1, 4))
    if average == "absolute":
        rv = np.asarray(rot.as_rotvec(), dtype=np.float64).reshape(n_seq, t.size, 3)
        u = np.einsum("jn,jni->ni", wgt, rv) / wgt.sum(axis=0)[:, None]
        return np.asarray(Rotation.from_rotvec(u).as_quat(), dtype=np.float64)
    if average == "relative":
        best = np.argmax(wgt, axis=0)
        ref = Rotation.from_quat(q[best, np.arange(t.size)])
        rel = Rotation.from_quat(np.tile(ref.as_quat(), (n_seq, 1))).inv() * rot
        rv = np.asarray(rel.as_rotvec(), dtype=np.float64).reshape(n_seq, t.size, 3)
        u = np.einsum("jn,jni->ni", wgt, rv) / wgt.sum(axis=0)[:, None]
        return np.asarray((ref * Rotation.from_rotvec(u)).as_quat(), dtype=np.float64)
    raise ValueError(f"average: expected 'absolute' or 'relative', got {average!r}")
