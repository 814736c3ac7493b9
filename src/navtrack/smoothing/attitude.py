"""Attitude as time series for ARI smoothing: rotation-vector increments, or Euler angles.

An ARI model (paper 5) smooths one scalar series at a time; the paper smooths the INS roll,
pitch and yaw. Euler angles are singular at ``|pitch| = 90 deg`` (gimbal lock): there a small
rotation moves yaw and roll by up to ``1 / cos(pitch)`` times its angle, in opposite jumps that
no smooth process explains, and the robust fit flags them as gross errors.

:func:`increment_path` writes the attitude without that singularity: the running sum of the
rotation vectors (axis times angle) of the body-frame increments ``R_{k-1}^-1 R_k`` between
successive samples. For a rotation about a fixed body axis it is that axis' angle; in general
it is the integral of the body angular rate (what a gyroscope measures), a continuous series
of three components whatever the attitude. :func:`rotations_from_path` turns a path (for
example the filtered one) back into rotations from the first attitude. :func:`euler_path` and
:func:`euler_artefacts` keep the paper's angles and mark the epochs where they are singular.

All conversions are :class:`scipy.spatial.transform.Rotation`'s. Quaternions are scalar-last
``[x, y, z, w]`` (scipy's order); missing samples are rows of NaN.

Notes
-----
The increment across a gap of missing samples is the rotation between the samples on either
side, assigned to the first sample after the gap: it is unambiguous only while the body turns
by less than 180 deg during the gap. The path is path-dependent (two motions between the same
attitudes may end at different sums): it is a series to smooth, not an attitude parameter; its
noise is that of the samples, rotated by the motion between two samples.
"""

from __future__ import annotations

import warnings
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._typing import ArrayLike, BoolArray, FloatArray

__all__ = [
    "ATTITUDE_COLUMNS",
    "ATTITUDE_FORMS",
    "EULER_AMPLIFICATION",
    "AttitudeForm",
    "euler_artefacts",
    "euler_path",
    "increment_path",
    "rotations_from_path",
]

AttitudeForm = Literal["rotvec", "euler"]

#: Forms of :func:`navtrack.experiments.ari.broad.broad_series` and their order of preference.
ATTITUDE_FORMS: tuple[AttitudeForm, ...] = ("rotvec", "euler")

#: Column names (deg) of each form: body-axis rotation-vector path, or yaw, pitch, roll.
ATTITUDE_COLUMNS: dict[str, tuple[str, str, str]] = {
    "rotvec": ("rotvec_x_deg", "rotvec_y_deg", "rotvec_z_deg"),
    "euler": ("yaw_deg", "pitch_deg", "roll_deg"),
}

#: Euler increments (|d yaw| + |d roll|) above this multiple of the rotation angle between two
#: samples are Euler-angle artefacts (model errors), not motion. How it was chosen (BROAD
#: trial 07) and judged (trial 02): docs/ari.md, method notes, "Attitude without the
#: gimbal-lock singularity".
EULER_AMPLIFICATION = 3.0


def _quaternions(quat_xyzw: ArrayLike) -> tuple[FloatArray, BoolArray]:
    q = np.asarray(quat_xyzw, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != 4:
        raise ValueError(f"quat_xyzw: expected shape (n, 4), got {q.shape}")
    ok = np.all(np.isfinite(q), axis=1)
    if np.any(np.linalg.norm(q[ok], axis=1) < 1e-9):
        raise ValueError("quat_xyzw: zero quaternion in a row not marked missing (NaN)")
    return q, ok


def increment_path(quat_xyzw: ArrayLike) -> FloatArray:
    """Running sum of the body-frame rotation-vector increments between successive samples.

    Parameters
    ----------
    quat_xyzw : array_like, shape (n, 4)
        Attitude quaternions, scalar-last, rotating body vectors into the reference frame;
        NaN rows are missing samples.

    Returns
    -------
    ndarray, shape (n, 3)
        ``theta_k = sum_{j <= k} rotvec(R_{j-1}^-1 R_j)`` over the observed samples (rad, body
        axes), 0 at the first observed sample, NaN where missing.
    """
    q, ok = _quaternions(quat_xyzw)
    path = np.full((q.shape[0], 3), np.nan)
    seen = np.flatnonzero(ok)
    if seen.size:
        rot = Rotation.from_quat(q[seen])
        steps = (rot[:-1].inv() * rot[1:]).as_rotvec() if seen.size > 1 else np.zeros((0, 3))
        path[seen] = np.vstack([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
    return path


def rotations_from_path(path: ArrayLike, first_xyzw: ArrayLike) -> FloatArray:
    """Quaternions of a rotation-vector path: the inverse of :func:`increment_path`.

    Parameters
    ----------
    path : array_like, shape (n, 3)
        Path (rad), e.g. the filtered one; NaN rows are skipped.
    first_xyzw : array_like, shape (4,)
        Attitude at the first observed epoch of ``path`` (scalar-last).

    Returns
    -------
    ndarray, shape (n, 4)
        ``R_k = R_first prod_j exp(theta_j - theta_{j-1})`` (scalar-last, ``w >= 0``), NaN
        where ``path`` is missing.
    """
    th = np.asarray(path, dtype=np.float64)
    if th.ndim != 2 or th.shape[1] != 3:
        raise ValueError(f"path: expected shape (n, 3), got {th.shape}")
    out = np.full((th.shape[0], 4), np.nan)
    seen = np.flatnonzero(np.all(np.isfinite(th), axis=1))
    rot = Rotation.from_quat(np.asarray(first_xyzw, dtype=np.float64))
    for k, step in zip(seen, np.diff(th[seen], axis=0, prepend=th[seen[:1]]), strict=True):
        rot = rot * Rotation.from_rotvec(step)
        out[k] = rot.as_quat(canonical=True)
    return out


def euler_path(quat_xyzw: ArrayLike) -> FloatArray:
    """Yaw, pitch, roll (rad): intrinsic z-y'-x'' angles, each unwrapped over the observed
    samples.

    Parameters
    ----------
    quat_xyzw : array_like, shape (n, 4)
        As :func:`increment_path`.

    Returns
    -------
    ndarray, shape (n, 3)
        ``[yaw, pitch, roll]`` per sample, NaN where missing.
    """
    q, ok = _quaternions(quat_xyzw)
    angles = np.full((q.shape[0], 3), np.nan)
    if np.any(ok):
        with warnings.catch_warnings():  # at the lock: what euler_artefacts marks
            warnings.filterwarnings("ignore", "Gimbal lock detected", UserWarning)
            ypr = Rotation.from_quat(q[ok]).as_euler("ZYX")
        angles[ok] = np.unwrap(ypr, axis=0)
    return angles


def euler_artefacts(
    quat_xyzw: ArrayLike, amplification: float = EULER_AMPLIFICATION
) -> tuple[BoolArray, FloatArray]:
    """Epochs whose Euler increments are artefacts of the representation (near gimbal lock).

    An increment whose ``|d yaw| + |d roll|`` exceeds ``amplification`` times the rotation
    angle between the two samples marks both its epochs.

    Parameters
    ----------
    quat_xyzw : array_like, shape (n, 4)
        As :func:`increment_path`.
    amplification : float
        Threshold ratio (default :data:`EULER_AMPLIFICATION`).

    Returns
    -------
    artefact : ndarray of bool, shape (n,)
    step_rad : ndarray, shape (n,)
        Rotation angle from the previous observed sample (NaN at the first and where missing).
    """
    q, ok = _quaternions(quat_xyzw)
    n = q.shape[0]
    ypr = euler_path(q)
    step = np.full(n, np.nan)
    seen = np.flatnonzero(ok)
    if seen.size > 1:
        rot = Rotation.from_quat(q[seen])
        step[seen[1:]] = (rot[:-1].inv() * rot[1:]).magnitude()
    euler_step = np.full(n, np.nan)
    euler_step[1:] = np.abs(np.diff(ypr[:, 0])) + np.abs(np.diff(ypr[:, 2]))
    amplified = euler_step > amplification * np.maximum(step, 1e-8)
    return amplified | np.concatenate([amplified[1:], [False]]), step
