"""Gyro quaternion propagation, error quaternions and the mean correction quaternion (paper 6).

Conventions (pinned by ``tests/attitude/test_conventions.py``)
----------------------------------------------------------------
* Quaternions are arrays ``(..., 4)`` **scalar-last** ``[x, y, z, w]`` — scipy's
  :class:`~scipy.spatial.transform.Rotation` order and the paper's (Wertz's ``q4`` scalar).
  Scalar-first data (BROAD's ``opt_quat``) are reordered at the edge
  (:func:`from_scalar_first`).
* A quaternion ``q`` (a ``Rotation``) rotates **body vectors into the reference frame**:
  ``v_ref = q.apply(v_body)``. Products are Hamilton products (scipy's ``*``).
* Gyro rates and delta angles are in the **body frame**; propagation right-multiplies:
  ``q[k+1] = q[k] ⊗ δq(Δθ_k)`` with ``Δθ_k = ω_k (t[k+1] - t[k])`` (the rate of sample k held
  over the interval that follows it).
* Attitude errors are taken in the **reference frame**: ``q_e = q_ref ⊗ q_est⁻¹``.

Wertz's attitude quaternion maps the reference frame into the body frame and composes in the
reverse order (``A(q ⊗_W p) = A(q) A(p)``); its components equal ours for the same attitude, and
``q ⊗_W p = p ⊗ q``. So the paper's propagation ``q[k+1] = exp(½Θ) q[k]`` (eq. 4) is our
``q[k] ⊗ δq``, its error quaternion ``q_e = p⁻¹ ⊗_W q`` (eq. 5) is our ``q ⊗ p⁻¹`` and its
corrected start ``q_0 = q_1 ⊗_W q_c`` is our ``q_c ⊗ q_1``.

References
----------
.. [1] ALHAT flash-LIDAR field test 1, trajectory reconstruction (paper 6): eq. 4 (truncated
   series), eq. 5 (error quaternion), the correction quaternion below eq. 5.
.. [2] J. R. Wertz (ed.), *Spacecraft Attitude Determination and Control*, Kluwer 1978,
   pp. 558-566 (the quaternion kinematic equation ``dq/dt = ½ Ω(ω) q`` and its series).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._numba import jit, numba_module
from navtrack._typing import ArrayLike, FloatArray

_numba: Any = numba_module()  # optional accelerator: propagation as one compiled loop

__all__ = [
    "HAVE_NUMBA",
    "CorrectionReading",
    "Propagation",
    "attitude_errors",
    "check_quaternions",
    "correction_quaternion",
    "delta_angles",
    "delta_quaternions",
    "from_scalar_first",
    "interpolate_attitude",
    "propagate",
    "propagate_loop",
    "propagate_numpy",
    "qmul",
    "series_matrix",
]

#: True when propagation runs as one compiled loop (numba, extra ``speed``:
#: :func:`propagate_loop` compiled); pure NumPy (:func:`propagate_numpy`: vectorised step
#: quaternions, blocked product) otherwise. The tests check the two equal.
HAVE_NUMBA = _numba is not None

#: Tolerance on ``| |q| - 1 |`` of quaternions given as attitudes.
UNIT_TOL = 1e-6

Method = Literal["closed", "series"]
CorrectionReading = Literal["mean_rotvec", "paper_literal"]


def from_scalar_first(q_wxyz: ArrayLike) -> FloatArray:
    """``[w, x, y, z]`` -> ``[x, y, z, w]`` (shape ``(..., 4)``, a new array)."""
    q = np.asarray(q_wxyz, dtype=np.float64)
    if q.shape[-1:] != (4,):
        raise ValueError(f"q_wxyz: expected shape (..., 4), got {q.shape}")
    return np.ascontiguousarray(q[..., [1, 2, 3, 0]])


def check_quaternions(q_xyzw: ArrayLike, name: str, *, allow_nan: bool = False) -> FloatArray:
    """Validate attitude quaternions ``(..., 4)`` scalar-last: finite (or NaN rows when
    ``allow_nan``) and of unit norm within :data:`UNIT_TOL`.

    Raises
    ------
    ValueError
        Naming ``name`` and the first offending row.
    """
    q = np.asarray(q_xyzw, dtype=np.float64)
    if q.shape[-1:] != (4,):
        raise ValueError(f"{name}: expected shape (..., 4) scalar-last [x, y, z, w], got {q.shape}")
    flat = q.reshape(-1, 4)
    nan_rows = np.any(np.isnan(flat), axis=1)
    if np.any(nan_rows) and not allow_nan:
        raise ValueError(f"{name}: quaternion row {int(np.flatnonzero(nan_rows)[0])} is NaN")
    partial = nan_rows & ~np.all(np.isnan(flat), axis=1)
    bad = ~nan_rows & (np.abs(np.linalg.norm(flat, axis=1) - 1.0) > UNIT_TOL)
    bad |= partial | (~nan_rows & ~np.all(np.isfinite(flat), axis=1))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name}: quaternion row {i} is not a unit quaternion (norm "
            f"{float(np.linalg.norm(flat[i])):.9g}, tolerance {UNIT_TOL:g})"
        )
    return q


def qmul(p: FloatArray, q: FloatArray) -> FloatArray:
    """Hamilton product ``p ⊗ q`` of scalar-last quaternions ``(..., 4)`` (broadcasting).

    The same product as scipy's ``Rotation.__mul__``, without normalising, so the truncated
    series keeps its norm error visible.
    """
    px, py, pz, pw = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qx, qy, qz, qw = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz,
        ],
        axis=-1,
    )


def delta_angles(t_s: ArrayLike, gyr_rad_s: ArrayLike) -> FloatArray:
    """Body-frame delta angles ``Δθ_k = ω_k (t[k+1] - t[k])`` of sampled rates.

    Parameters
    ----------
    t_s : (n,) sample times, s, strictly increasing
    gyr_rad_s : (n, 3) body-frame angular rates, rad/s

    Returns
    -------
    (n - 1, 3) delta angles, rad

    Raises
    ------
    ValueError
        Shapes, non-finite values, or time stamps not strictly increasing (the first such
        sample is named).
    """
    t = np.asarray(t_s, dtype=np.float64)
    w = np.asarray(gyr_rad_s, dtype=np.float64)
    if t.ndim != 1 or w.shape != (t.size, 3):
        raise ValueError(f"t_s (n,) and gyr_rad_s (n, 3) expected, got {t.shape} and {w.shape}")
    if t.size < 2:
        raise ValueError(f"t_s: at least two samples are needed, got {t.size}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"t_s: sample {int(np.flatnonzero(~np.isfinite(t))[0])} is not finite")
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.flatnonzero(dt <= 0)[0])
        raise ValueError(
            f"t_s: gyro time stamps out of order at sample {k + 1} "
            f"({t[k + 1]!r} s after {t[k]!r} s); they must increase strictly"
        )
    finite = np.all(np.isfinite(w), axis=1)
    if not np.all(finite):
        raise ValueError(f"gyr_rad_s: sample {int(np.flatnonzero(~finite)[0])} is not finite")
    return w[:-1] * dt[:, None]


def series_matrix(dtheta_rad: ArrayLike) -> FloatArray:
    """The paper's 4x4 matrix ``Θ`` of delta angles (Wertz's ``Ω Δt``), shape ``(..., 4, 4)``.

    ``δq = exp(½Θ)`` applied as ``q[k+1] = exp(½Θ) q[k]`` on scalar-last components
    (paper eq. 4). Kept for the tests that check :func:`delta_quaternions` against the
    literal matrix series.
    """
    d = np.asarray(dtheta_rad, dtype=np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    o = np.zeros_like(x)
    rows = [[o, z, -y, x], [-z, o, x, y], [y, -x, o, z], [-x, -y, -z, o]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def delta_quaternions(
    dtheta_rad: ArrayLike, method: Method = "closed", order: int = 3
) -> FloatArray:
    """Step quaternions ``δq = exp(½Θ)`` of body-frame delta angles, scalar-last ``(..., 4)``.

    Parameters
    ----------
    dtheta_rad : (..., 3) delta angles, rad
    method : {"closed", "series"}
        ``closed``: ``[sin(θ/2) Δθ/θ, cos(θ/2)]`` (``θ = |Δθ|``). ``series``: the paper's
        truncated matrix series ``Σ_{j≤order} (½Θ)^j / j!`` (eq. 4 for ``order = 3``).
    order : int
        Highest power of the series (1-3 in the paper; any ``>= 1`` accepted).

    Notes
    -----
    ``Θ² = -θ² I`` (``Θ`` is skew with ``ΘᵀΘ = θ² I``), so the matrix series is a scalar
    series in ``I`` and ``Θ``: even powers add ``(-θ²/4)^m / (2m)!`` to the scalar part, odd
    powers ``½ (-θ²/4)^m / (2m+1)!`` times ``Δθ`` to the vector part. This is the *matrix*
    power; an element-wise power of ``Θ`` (``ahrs`` 0.4.0's ``'series'`` method) agrees only
    to first order. The truncated series is not of unit norm; the norm error of orders 1 and 3
    lies along the quaternion itself (even terms), so only the odd remainder turns it.
    """
    d = np.asarray(dtheta_rad, dtype=np.float64)
    if d.shape[-1:] != (3,):
        raise ValueError(f"dtheta_rad: expected shape (..., 3), got {d.shape}")
    th2 = np.einsum("...i,...i->...", d, d)
    if method == "closed":
        th = np.sqrt(th2)
        scalar = np.cos(0.5 * th)
        small = th < 1e-4  # sin(θ/2)/θ by its series where the quotient loses digits
        vec_coef = np.where(small, 0.5 - th2 / 48.0, np.sin(0.5 * th) / np.where(small, 1.0, th))
    elif method == "series":
        if order < 1:
            raise ValueError(f"order: the series needs order >= 1, got {order}")
        scalar = np.ones_like(th2)
        vec_coef = np.zeros_like(th2)
        term = np.ones_like(th2)  # (-θ²/4)^m
        for j in range(1, order + 1):
            if j % 2:  # odd power 2m+1: ½ (-θ²/4)^m / (2m+1)! Δθ
                vec_coef = vec_coef + 0.5 * term / math.factorial(j)
            else:  # even power 2m
                term = term * (-0.25 * th2)
                scalar = scalar + term / math.factorial(j)
    else:
        raise ValueError(f"method: expected 'closed' or 'series', got {method!r}")
    return np.concatenate([vec_coef[..., None] * d, scalar[..., None]], axis=-1)


def _cumulative_product_blocked(q0: FloatArray, steps: FloatArray) -> FloatArray:
    """``out[0] = q0``, ``out[k+1] = out[k] ⊗ steps[k]``, shape ``(m + 1, 4)``, pure NumPy.

    Blocked scan: the running products inside ``√m`` blocks are formed in ``√m`` vectorised
    steps across the blocks, then each block is left-multiplied by the product of the blocks
    before it. O(m) work in O(√m) NumPy calls; the products are grouped differently from a
    plain loop, which changes the result only by rounding.
    """
    m = steps.shape[0]
    out = np.empty((m + 1, 4))
    out[0] = q0
    if m == 0:
        return out
    size = max(1, math.isqrt(m))
    nb = -(-m // size)
    padded = np.zeros((nb * size, 4))
    padded[:, 3] = 1.0
    padded[:m] = steps
    local = padded.reshape(nb, size, 4)
    for j in range(1, size):
        local[:, j] = qmul(local[:, j - 1], local[:, j])
    heads = np.empty((nb, 4))
    heads[0] = q0
    for b in range(1, nb):
        heads[b] = qmul(heads[b - 1], local[b - 1, -1])
    out[1:] = qmul(heads[:, None, :], local).reshape(-1, 4)[:m]
    return out


def propagate_loop(
    q0: FloatArray, d: FloatArray, closed: bool, order: int, backward: bool
) -> tuple[FloatArray, FloatArray]:
    """Step quaternions and their running product in one loop (compiled by numba): the same
    arithmetic as :func:`delta_quaternions` then :func:`_cumulative_product_loop`; with
    ``backward`` each step is inverted (``d`` given in the order of application). Returns the
    normalised products ``(m + 1, 4)`` and the norms of the unnormalised ones ``(m + 1,)``."""
    m = d.shape[0]
    out = np.empty((m + 1, 4))
    norm = np.empty(m + 1)
    x, y, z, w = q0[0], q0[1], q0[2], q0[3]
    norm[0] = math.sqrt(x * x + y * y + z * z + w * w)
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = x, y, z, w
    for k in range(m):
        dx, dy, dz = d[k, 0], d[k, 1], d[k, 2]
        th2 = dx * dx + dy * dy + dz * dz
        if closed:
            th = math.sqrt(th2)
            sw = math.cos(0.5 * th)
            c = 0.5 - th2 / 48.0 if th < 1e-4 else math.sin(0.5 * th) / th
        else:
            sw, c, term, fact = 1.0, 0.0, 1.0, 1.0
            for j in range(1, order + 1):
                fact *= j
                if j % 2:
                    c += 0.5 * term / fact
                else:
                    term *= -0.25 * th2
                    sw += term / fact
        sx, sy, sz = c * dx, c * dy, c * dz
        if backward:
            n2 = sx * sx + sy * sy + sz * sz + sw * sw
            sx, sy, sz, sw = -sx / n2, -sy / n2, -sz / n2, sw / n2
        x, y, z, w = (
            w * sx + x * sw + y * sz - z * sy,
            w * sy - x * sz + y * sw + z * sx,
            w * sz + x * sy - y * sx + z * sw,
            w * sw - x * sx - y * sy - z * sz,
        )
        r = math.sqrt(x * x + y * y + z * z + w * w)
        norm[k + 1] = r
        out[k + 1, 0], out[k + 1, 1], out[k + 1, 2], out[k + 1, 3] = x / r, y / r, z / r, w / r
    return out, norm


_propagate_compiled: Any = jit(propagate_loop)


@dataclass(frozen=True, slots=True, eq=False)
class Propagation:
    """Attitudes propagated from gyro delta angles (arrays read-only).

    Attributes
    ----------
    quat : ndarray, shape (n, 4)
        Unit quaternions, scalar-last, body -> reference, at the sample times.
    norm : ndarray, shape (n,)
        Norm of the unnormalised product of step quaternions (1 for the closed form up to
        rounding; the truncated series drifts from 1).
    start : int
        Sample the propagation started from (``quat[start]`` is the start attitude).
    method : str
    order : int
    """

    quat: FloatArray
    norm: FloatArray
    start: int
    method: str
    order: int

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def rotation(self) -> Rotation:
        """The attitudes as one batched ``Rotation``."""
        return Rotation.from_quat(self.quat)


def propagate(
    q_start: Rotation | ArrayLike,
    dtheta_rad: ArrayLike,
    *,
    start: int = 0,
    method: Method = "closed",
    order: int = 3,
) -> Propagation:
    """Propagate an attitude through body-frame delta angles, forward and backward from ``start``.

    Parameters
    ----------
    q_start : Rotation or (4,) scalar-last unit quaternion
        Attitude (body -> reference) at sample ``start``.
    dtheta_rad : (n - 1, 3)
        Delta angles between consecutive samples (:func:`delta_angles`), rad.
    start : int
        Sample of ``q_start``; samples after it are propagated forward
        (``q[k+1] = q[k] ⊗ δq_k``), those before it backward (``q[k] = q[k+1] ⊗ δq_k⁻¹``).
    method, order
        Step quaternions (:func:`delta_quaternions`).

    Returns
    -------
    Propagation
        ``n`` attitudes.
    """
    d = np.asarray(dtheta_rad, dtype=np.float64)
    if d.ndim != 2 or d.shape[1] != 3:
        raise ValueError(f"dtheta_rad: expected shape (n - 1, 3), got {d.shape}")
    n = d.shape[0] + 1
    if not 0 <= start < n:
        raise ValueError(f"start: sample {start} outside 0..{n - 1}")
    if isinstance(q_start, Rotation):
        q0 = np.asarray(q_start.as_quat(), dtype=np.float64).reshape(4)
    else:
        q0 = check_quaternions(q_start, "q_start").reshape(4)
    if method not in ("closed", "series"):
        raise ValueError(f"method: expected 'closed' or 'series', got {method!r}")
    if method == "series" and order < 1:
        raise ValueError(f"order: the series needs order >= 1, got {order}")
    if _propagate_compiled is not None:
        closed = method == "closed"
        quat, norm = _propagate_compiled(q0, np.ascontiguousarray(d[start:]), closed, order, False)
        if start > 0:
            back = np.ascontiguousarray(d[:start][::-1])
            qb, nb = _propagate_compiled(q0, back, closed, order, True)
            quat = np.concatenate([qb[:0:-1], quat])
            norm = np.concatenate([nb[:0:-1], norm])
        return Propagation(quat, norm, start, method, order)
    return propagate_numpy(q0, d, start, method, order)


def propagate_numpy(
    q0: FloatArray, d: FloatArray, start: int, method: Method, order: int
) -> Propagation:
    """:func:`propagate` without numba: vectorised step quaternions, blocked product."""
    steps = delta_quaternions(d, method, order)
    raw = np.empty((d.shape[0] + 1, 4))
    raw[start:] = _cumulative_product_blocked(q0, steps[start:])
    if start > 0:
        back = steps[:start][::-1] * np.array([-1.0, -1.0, -1.0, 1.0])  # inverses
        back /= np.einsum("ij,ij->i", back, back)[:, None]
        raw[: start + 1] = _cumulative_product_blocked(q0, back)[::-1]
    norm = np.linalg.norm(raw, axis=1)
    return Propagation(raw / norm[:, None], norm, start, method, order)


def interpolate_attitude(
    t_s: ArrayLike, quat: ArrayLike, gyr_rad_s: ArrayLike, t_query_s: ArrayLike
) -> FloatArray:
    """Attitude between samples by the gyro: ``q(t) = q[k] ⊗ δq(ω_k (t - t[k]))``.

    Parameters
    ----------
    t_s : (n,) sample times, s (increasing)
    quat : (n, 4) scalar-last attitudes at ``t_s``
    gyr_rad_s : (n, 3) body-frame rates used for the fraction of the interval, rad/s
    t_query_s : (m,) query times, s; outside ``[t[0], t[-1]]`` extrapolated from the first or
        last sample by its rate

    Returns
    -------
    (m, 4) unit quaternions, scalar-last

    Notes
    -----
    Consistent with the rectangular rule of :func:`delta_angles`, so ``q(t[k+1])`` from sample
    ``k`` equals ``quat[k+1]`` and the result is continuous (and differentiable almost
    everywhere) in ``t`` — what the timing-offset calibration needs.
    """
    t = np.asarray(t_s, dtype=np.float64)
    tq = np.asarray(t_query_s, dtype=np.float64)
    k = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 1)
    frac = tq - t[k]
    step = delta_quaternions(np.asarray(gyr_rad_s, dtype=np.float64)[k] * frac[:, None])
    q = qmul(np.asarray(quat, dtype=np.float64)[k], step)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def attitude_errors(estimate: Rotation, reference: Rotation) -> tuple[FloatArray, FloatArray]:
    """Reference-frame attitude errors of ``estimate`` against ``reference`` (paper eq. 5).

    Parameters
    ----------
    estimate, reference : Rotation, same length ``n`` (body -> reference)

    Returns
    -------
    e_s : (n,) scalar error: the Euler angle of ``q_e = q_ref ⊗ q_est⁻¹``, rad, in ``[0, π]``
    e_v : (n, 3) vector error: Euler angle times Euler axis (the rotation vector of ``q_e``),
        reference frame, rad
    """
    e_v = np.asarray((reference * estimate.inv()).as_rotvec(), dtype=np.float64).reshape(-1, 3)
    return np.linalg.norm(e_v, axis=1), e_v


def correction_quaternion(
    e_s: ArrayLike, e_v: ArrayLike, reading: CorrectionReading = "mean_rotvec"
) -> Rotation:
    """The paper's mean correction quaternion ``q_c`` from the errors of all camera fixes.

    Parameters
    ----------
    e_s : (m,) scalar errors, rad
    e_v : (m, 3) vector errors, rad (:func:`attitude_errors`)
    reading : {"mean_rotvec", "paper_literal"}
        ``mean_rotvec``: ``q_c`` has the rotation vector ``u_e = mean(e_v)``.
        ``paper_literal``: ``q_c = [a sin(u_s/2), cos(u_s/2)]`` with the axis
        ``a = u_e / |u_e|`` and the angle ``u_s = mean(e_s)``.

    Returns
    -------
    Rotation
        ``q_c``; the corrected start attitude is ``q_c ⊗ q_1`` (paper: ``q_0 = q_1 ⊗_W q_c``).

    Notes
    -----
    The paper writes ``q_c = [u_eᵀ sin(u_s/2), cos(u_s/2)]ᵀ`` with ``u_e`` the mean vector
    error, which is a unit quaternion only when ``u_e`` is a unit vector. Reading it with the
    axis normalised (``paper_literal``) turns by the mean *scalar* error, which is at least
    ``|u_e|`` and overshoots whenever the errors change direction. The paper reports that after
    the correction "the vector error has the same shape, but now has zero mean" — which holds
    for ``q_c = exp(u_e)`` to first order (the errors become ``e_v - u_e``), so ``mean_rotvec``
    is the default; both readings are kept and reported.
    """
    es = np.asarray(e_s, dtype=np.float64)
    ev = np.asarray(e_v, dtype=np.float64)
    if ev.ndim != 2 or ev.shape[1] != 3 or es.shape != (ev.shape[0],) or es.size == 0:
        raise ValueError(
            f"e_s (m,) and e_v (m, 3) with m >= 1 expected, got {es.shape}, {ev.shape}"
        )
    u_e = ev.mean(axis=0)
    if reading == "mean_rotvec":
        return Rotation.from_rotvec(u_e)
    if reading == "paper_literal":
        norm = float(np.linalg.norm(u_e))
        if norm == 0.0:
            return Rotation.identity()
        return Rotation.from_rotvec(u_e / norm * float(es.mean()))
    raise ValueError(f"reading: expected 'mean_rotvec' or 'paper_literal', got {reading!r}")
