"""Compiled per-scan loops of the tracker (numba, extra ``speed``); NumPy without it.

The tracker's scans hold a few reports against tens of tracks: its NumPy stages spend most of
their time in the fixed cost of each array operation on ``(T, r, n, n)`` arrays of a few
hundred numbers, paid every scan. Two loops here do the same arithmetic as the NumPy kernels
for all tracks in one call each:

- :func:`imm_predict`: the IMM interaction of :func:`~navtrack.tracking.imm.imm_mix`
  (Bar-Shalom, Li, Kirubarajan 2001, eq. 11.6.6-6..-11) followed by the prediction of
  :func:`~navtrack.tracking.kalman.kf_predict` (eq. 5.2.3-5, -7), in place;
- :func:`position_gate`: the innovation covariance and gain of
  :func:`~navtrack.tracking.kalman.innovation_gain` and the chi-square distances of
  :func:`~navtrack.tracking.gating.gate` for a plane position measurement (``H`` picks two
  state components) with each report's time offset along the track's velocity.

The results equal the NumPy path to rounding (``tests/tracking/test_tracker_stages.py``
runs both). ``HAVE_COMPILED`` is False without numba, or with ``NAVTRACK_NO_NUMBA`` set.
numba is imported on the first call only: its import and the load of the cached machine code
cost about half a second per process, which only long runs pay back
(:data:`~navtrack.tracking.tracker.COMPILED_MIN_SCANS`).
"""

from __future__ import annotations

import importlib.util
import os
from functools import lru_cache
from typing import Any

import numpy as np

from navtrack._typing import FloatArray

__all__ = ["HAVE_COMPILED", "imm_predict", "position_gate"]

#: True when the compiled loops (numba, extra ``speed``) are available.
HAVE_COMPILED = (
    not os.environ.get("NAVTRACK_NO_NUMBA") and importlib.util.find_spec("numba") is not None
)


def _imm_predict_py(
    x: FloatArray, P: FloatArray, mu: FloatArray, Pi: FloatArray, F: FloatArray, Q: FloatArray
) -> None:
    T, r, n = x.shape
    c = np.empty(r)
    w = np.empty((r, r))
    x0 = np.empty((r, n))
    P0 = np.empty((r, n, n))
    FP = np.empty((n, n))
    for t in range(T):
        for j in range(r):  # predicted model probabilities and mixing weights w[i, j]
            cj = 0.0
            for i in range(r):
                cj += mu[t, i] * Pi[i, j]
            c[j] = cj
            den = cj if cj > 0 else 1.0
            for i in range(r):
                w[i, j] = mu[t, i] * Pi[i, j] / den
        for j in range(r):
            for a in range(n):
                s = 0.0
                for i in range(r):
                    s += w[i, j] * x[t, i, a]
                x0[j, a] = s
            for a in range(n):
                for b in range(n):
                    s = 0.0
                    for i in range(r):
                        s += w[i, j] * (
                            P[t, i, a, b] + (x[t, i, a] - x0[j, a]) * (x[t, i, b] - x0[j, b])
                        )
                    P0[j, a, b] = s
        for j in range(r):  # x = F x0, P = F P0 Fᵀ + Q (symmetrised)
            mu[t, j] = c[j]
            for a in range(n):
                s = 0.0
                for k in range(n):
                    s += F[a, k] * x0[j, k]
                x[t, j, a] = s
                for b in range(n):
                    s = 0.0
                    for k in range(n):
                        s += F[a, k] * P0[j, k, b]
                    FP[a, b] = s
            for a in range(n):
                for b in range(a + 1):
                    s = 0.0
                    for k in range(n):
                        s += FP[a, k] * F[b, k]
                    s += Q[j, a, a] if a == b else 0.5 * (Q[j, a, b] + Q[j, b, a])
                    P[t, j, a, b] = s
                    P[t, j, b, a] = s


def _position_gate_py(
    x: FloatArray,
    P: FloatArray,
    pos: np.ndarray,
    vel: np.ndarray,
    R: FloatArray,
    z: FloatArray,
    dt: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    B, n = x.shape
    M = z.shape[0]
    S = np.empty((B, 2, 2))
    K = np.empty((B, n, 2))
    y = np.empty((B, M, 2))
    d2 = np.empty((B, M))
    det = np.empty(B)
    p0, p1 = pos[0], pos[1]
    for b in range(B):
        s00 = P[b, p0, p0] + R[0, 0]
        s11 = P[b, p1, p1] + R[1, 1]
        s01 = 0.5 * (P[b, p0, p1] + P[b, p1, p0] + R[0, 1] + R[1, 0])
        d = s00 * s11 - s01 * s01
        i00, i01, i11 = s11 / d, -s01 / d, s00 / d
        S[b, 0, 0], S[b, 0, 1], S[b, 1, 0], S[b, 1, 1] = s00, s01, s01, s11
        det[b] = d
        for a in range(n):  # K = P Hᵀ S⁻¹
            h0, h1 = P[b, a, p0], P[b, a, p1]
            K[b, a, 0] = h0 * i00 + h1 * i01
            K[b, a, 1] = h0 * i01 + h1 * i11
        for j in range(M):  # innovation of the report at its own time, and its distance
            e0 = z[j, 0] - x[b, p0] - dt[j] * x[b, vel[0]]
            e1 = z[j, 1] - x[b, p1] - dt[j] * x[b, vel[1]]
            y[b, j, 0] = e0
            y[b, j, 1] = e1
            d2[b, j] = e0 * (i00 * e0 + i01 * e1) + e1 * (i01 * e0 + i11 * e1)
    return S, K, y, d2, det


@lru_cache(maxsize=1)
def _kernels() -> tuple[Any, Any]:
    """The two loops compiled (numba's on-disk cache after the first run)."""
    if not HAVE_COMPILED:
        raise RuntimeError("the compiled tracker loops need numba (extra 'speed')")
    import numba

    jit = numba.njit(cache=True, nogil=True)
    return jit(_imm_predict_py), jit(_position_gate_py)


def imm_predict(
    x: FloatArray, P: FloatArray, mu: FloatArray, Pi: FloatArray, F: FloatArray, Q: FloatArray
) -> None:
    """IMM interaction and KF prediction of every track, in place (compiled; module notes).

    Parameters
    ----------
    x : (T, r, n), P : (T, r, n, n), mu : (T, r)
        Model-conditioned states, covariances and model probabilities (C-contiguous, written:
        the predicted states, covariances and model probabilities ``mu @ Pi``).
    Pi : (r, r) model transition matrix; F : (n, n) transition; Q : (r, n, n) process noise
        of each model.
    """
    _kernels()[0](x, P, mu, Pi, F, Q)


def position_gate(
    x: FloatArray,
    P: FloatArray,
    pos: tuple[int, ...],
    vel: tuple[int, ...],
    R: FloatArray,
    z: FloatArray,
    dt_s: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Innovations, covariances, gains and chi-square distances of a position measurement.

    Parameters
    ----------
    x : (B, n), P : (B, n, n) predicted states and covariances (tracks × models)
    pos, vel : state indices of the east/north position and velocity
    R : (2, 2) measurement noise; z : (M, 2) reports; dt_s : (M,) report time minus the
        prediction time, s (the prediction is moved by ``dt_s`` along the velocity)

    Returns
    -------
    S : (B, 2, 2), K : (B, n, 2), innovation : (B, M, 2), d2 : (B, M), det_S : (B,)
    """
    out: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray] = _kernels()[1](
        x, P, np.array(pos), np.array(vel), R, z, dt_s
    )
    return out
