"""Equivalent measurements of S-tuples: the maximum-likelihood fusion of a tuple's detections.

The ``sdcmsjpda_fused`` and ``sdcmsjpda_joint`` trackers of
:mod:`navtrack.tracking.trackers.multisensor` turn each S-tuple of detections into ONE
measurement of the observed state components (the position for range-bearing sensors): the
Gauss-Newton fit ``ζ`` of those components to the tuple's measurements, with covariance
``R_eq = (Σ_s J_sᵀ R_s⁻¹ J_s)⁻¹`` (:func:`equivalent_measurement`). In a linear-Gaussian model the
Kalman update with ``(ζ, R_eq)`` is exactly the stacked update of all the tuple's measurements;
with range-bearing sensors the two agree to the linearisation order.

Two implementations of the same loop, the same numbers (the tests run both):

* compiled: :func:`gauss_newton_range_bearing`, one tuple at a time in scalar arithmetic,
  compiled by numba (:func:`compiled_gauss_newton`) when numba is installed (extra ``speed``)
  and every sensor is range-bearing with one ``position_index``;
* NumPy: the batched loop of :func:`equivalent_measurement`, for any measurement models, and
  the path of an installation without numba.

**Reading of the paper** (Zhang, Xiong & He 2005, ``sdcmsjpda_fused``). The abstract ("all of
measurements in each assignment are combined into one equivalent measurement ... the joint
association probability of each equivalent measurement is calculated"), section 3.1 ("a
equivalent measurement is gained in each combination ... the multisensor joint association
probability of each equivalent measurement is calculated according to its joint likelihood
value") and eqs. 3-16 (events, validation matrix and likelihood are all written over equivalent
measurements ``Z_L``; eq. 14's volume uses "the combined innovation covariance of all sensors")
say that a tuple is one fused measurement. Its likelihood is eqs. 15-16, the product of the
members' ``N(z_s; ẑ_s, S_s)`` at the prediction (the tracker's tuple marginals); its update is
the Kalman update with the tuple's ML position ``ζ`` and covariance ``R_eq`` (measurement matrix
the rows of the identity at the position). In a linear-Gaussian model this is exactly the
stacked update of ``parallel``; with range-bearing sensors the two agree to the linearisation
order (the fused update is linearised at the tuple's ML position, the stacked EKF at the
prediction; the tests check both facts). A single detection's equivalent measurement is its
polar-to-Cartesian conversion with the linearised covariance.

The fit does not use :func:`navtrack.estimation.least_squares.gauss_newton`: that one takes
diagonal weights, stops on the Euclidean step norm and re-evaluates the model at the end, while
this one whitens with each full ``R_s``, stops on the step's size in ``R_eq`` and falls back to
the first (EKF) step for a tuple that does not converge.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import lru_cache

import numpy as np

from navtrack._numba import jit
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.estimation.kalman import stacked_inverse
from navtrack.estimation.models import MeasurementModel, wrap_angle
from navtrack.tracking.models import RangeBearing, measure, range_bearing_group

__all__ = [
    "STEP_TOL",
    "compiled_gauss_newton",
    "compiled_range_bearing",
    "equivalent_measurement",
    "gauss_newton_range_bearing",
    "sensor_constants",
]

#: A tuple's Gauss-Newton iteration stops when its step is below this many standard deviations
#: of its equivalent measurement (``δᵀ R_eq⁻¹ δ < STEP_TOL²``); how it was chosen:
#: docs/multisensor.md, "Equivalent measurement: stopping rule".
STEP_TOL = 0.02


def equivalent_measurement(
    z: FloatArray,
    hit: BoolArray,
    sensors: Sequence[MeasurementModel],
    x_ref: FloatArray,
    iterations: int = 10,
    tol: float = STEP_TOL,
    *,
    linearised: tuple[FloatArray, FloatArray] | None = None,
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Equivalent measurements of S-tuples: ML fit of the observed state components.

    The observed components ``o`` are the state components the sensors' Jacobians depend on
    at ``x_ref`` (the position for range-bearing). For each tuple, Gauss-Newton from
    ``x_ref[o]`` minimises ``Σ_{s: hit} |z_s - h_s(x)|²_{R_s⁻¹}`` over ``x[o]`` (the other
    components held at ``x_ref``); the result ``ζ`` with covariance ``R_eq`` (the Jacobian
    columns ``o`` at the last iterate, within ``tol`` standard deviations of ``ζ``) is a linear
    measurement ``ζ = E x + w``, ``w ~ N(0, R_eq)``, ``E`` the rows ``o`` of the identity.

    All tuples are solved in one batch, the tuple axis last (:func:`_fit_batch`), or compiled,
    one tuple at a time (module notes: which runs when).

    Parameters
    ----------
    z : (n_L, S, m) the tuples' measurements (any finite value where not ``hit``)
    hit : (n_L, S) bool, sensor ``s`` has a measurement in the tuple; every tuple needs one
    sensors : S measurement models, each with ``dim_z >= len(o)`` (alone it fixes ``x[o]``)
    x_ref : (n,) or (n_L, n) linearisation point and start (the prediction)
    iterations : int, most Gauss-Newton steps; a tuple that has not converged after them
        (e.g. a single range-bearing detection of a target passing over the sensor, whose
        measured range may be below the noise) keeps its first step, linearised at ``x_ref``
        (the EKF's information form)
    tol : float, a tuple stops when its step is below ``tol`` standard deviations of its
        equivalent measurement, ``δᵀ R_eq⁻¹ δ < tol²`` (default :data:`STEP_TOL`)
    linearised : optional ``(J (n_L, S, m, n), r (n_L, S, m))``, the Jacobians and wrapped
        residuals ``z_s - h_s(x_ref)`` at ``x_ref`` when the caller already has them (the
        tracker's Jacobians and innovations at the prediction): the first iteration of the
        NumPy loop then evaluates no model (the compiled loop evaluates them itself)

    Returns
    -------
    o : (n_o,) int, the observed components
    zeta : (n_L, n_o) equivalent measurements
    R_eq : (n_L, n_o, n_o) their covariances
    """
    x_ref = np.asarray(x_ref, dtype=float)
    o = _observed_components(sensors, x_ref, linearised)
    if any(model.dim_z < o.size for model in sensors):
        raise ValueError(
            f"equivalent_measurement: every sensor must observe the {o.size} state "
            f"components {o.tolist()} alone (dim_z >= {o.size})"
        )
    if not hit.any(axis=1).all():
        raise ValueError("equivalent_measurement: every tuple needs one measurement")
    compiled = compiled_range_bearing(sensors)
    if compiled is None:
        zeta, info = _fit_batch(z, hit, sensors, x_ref, o, iterations, tol, linearised)
        return o.astype(np.int64), zeta, stacked_inverse(info)
    kernel, (model, xy) = compiled
    ij = np.array(model.position_index)
    p0 = np.broadcast_to(x_ref, (z.shape[0], x_ref.shape[-1]))[:, ij]
    # fresh C arrays: the argument types the kernel was compiled for
    zc, hc = np.array(z, dtype=float), np.array(hit, dtype=bool)
    Ct = sensor_constants(sensors)[1]
    p, info = kernel(zc, hc, p0, xy, Ct, model.from_north, iterations, tol)
    if ij[0] > ij[1]:  # back to the order of o
        p, info = p[:, ::-1], info[:, ::-1, ::-1]
    return o.astype(np.int64), p, stacked_inverse(info)


def _observed_components(
    sensors: Sequence[MeasurementModel],
    x_ref: FloatArray,
    linearised: tuple[FloatArray, FloatArray] | None,
) -> IntArray:
    """The state components the sensors observe: the position of range-bearing sensors (in
    state order), else those their Jacobians at ``x_ref`` depend on."""
    group = range_bearing_group(sensors)
    if group is not None:
        return np.sort(np.array(group[0].position_index))
    J0 = measure(sensors, x_ref)[1] if linearised is None else np.asarray(linearised[0])
    return np.flatnonzero((J0 != 0.0).reshape(-1, x_ref.shape[-1]).any(axis=0))


def _fit_batch(
    z: FloatArray,
    hit: BoolArray,
    sensors: Sequence[MeasurementModel],
    x_ref: FloatArray,
    o: IntArray,
    iterations: int,
    tol: float,
    linearised: tuple[FloatArray, FloatArray] | None,
) -> tuple[FloatArray, FloatArray]:
    """:func:`equivalent_measurement`'s NumPy loop: the fitted components ``(n_L, n_o)`` and
    the information matrices ``Σ_s J_sᵀ R_s⁻¹ J_s`` ``(n_L, n_o, n_o)``.

    Each iteration evaluates the sensors' models once for the tuples still iterating
    (range-bearing sensors in one vectorised call), whitens each sensor's rows with one product
    (``R_s⁻¹ = C_s C_sᵀ``), zeroes the rows of sensors not in the tuple, sums the normal
    equations and solves them (Cramer's rule for ``n_o = 2``); a tuple whose step fell below
    ``tol`` leaves the batch, and the loop ends when none is left.
    """
    n_L, S_, m = z.shape
    n_o = o.size
    Ct, angle = sensor_constants(sensors)[1:]
    # the tuple axis last (k tuples): residuals (S, m, k), whitened rows (S, m, n_o, k), those
    # of a sensor missing from a tuple weighted 0, normal equations (n_o, n_o, k)
    w = hit.T[:, None, None, :]
    zt = z.transpose(1, 2, 0)
    x = np.array(np.broadcast_to(x_ref, (n_L, x_ref.shape[-1])), dtype=float)
    info_last = np.empty((n_o, n_o, n_L))
    todo = np.arange(n_L)  # the tuples not converged yet
    for it in range(iterations):
        if it == 0 and linearised is not None:
            J = np.asarray(linearised[0])[..., o]
            r = np.asarray(linearised[1]).transpose(1, 2, 0)
        else:
            zp, J = measure(sensors, x[todo])
            J, r = J[..., o], zt[..., todo] - zp.transpose(1, 2, 0)
            r[angle] = wrap_angle(r[angle])
        k = todo.size
        B = (Ct @ J.transpose(1, 2, 3, 0).reshape(S_, m, n_o * k)).reshape(S_, m, n_o, k)
        B *= w[..., todo]
        info = np.einsum("smpk,smqk->pqk", B, B)  # Σ_s J_sᵀ R_s⁻¹ J_s
        g = np.einsum("smpk,smk->pk", B, Ct @ r)  # Σ_s J_sᵀ R_s⁻¹ r_s
        step = _solve_last(info, g)
        info_last[..., todo] = info
        x[todo[:, None], o] += step.T
        if it == 0:
            first = x.copy(), info_last.copy()
        todo = todo[np.einsum("pk,pk->k", step, g) >= tol * tol]  # δᵀ R_eq⁻¹ δ = δᵀ g
        if todo.size == 0:
            break
    # not converged: the first step, linearised at x_ref
    x[todo], info_last[..., todo] = first[0][todo], first[1][..., todo]
    return x[:, o], info_last.transpose(2, 0, 1)


def gauss_newton_range_bearing(
    z: FloatArray,
    hit: BoolArray,
    p0: FloatArray,
    xy: FloatArray,
    Ct: FloatArray,
    from_north: bool,
    iterations: int,
    tol: float,
) -> tuple[FloatArray, FloatArray]:
    """The Gauss-Newton loop of :func:`equivalent_measurement` for range-bearing sensors, one
    tuple at a time in scalar arithmetic (compiled by numba: :func:`compiled_gauss_newton`).

    ``z (n_L, S, 2)``, ``hit (n_L, S)``, start positions ``p0 (n_L, 2)`` (the state's
    ``position_index`` components), sensor positions ``xy (S, 2)``, whitening ``Ct (S, 2,
    2)``. The same steps, stopping rule and fallback to the first step as the NumPy loop.
    Returns the positions ``(n_L, 2)`` and information matrices ``(n_L, 2, 2)``. Its NumPy twin
    is :func:`equivalent_measurement`'s batched loop (any sensors), used without numba.
    """
    n_L, S_ = hit.shape
    out = np.empty((n_L, 2))
    info = np.empty((n_L, 2, 2))
    two_pi = 2.0 * math.pi
    for k in range(n_L):
        px, py = p0[k, 0], p0[k, 1]
        first = (px, py, 0.0, 0.0, 0.0)
        a00 = a01 = a11 = 0.0
        converged = False
        for it in range(iterations):
            a00 = a01 = a11 = g0 = g1 = 0.0
            for s in range(S_):
                if not hit[k, s]:
                    continue
                dx, dy = px - xy[s, 0], py - xy[s, 1]
                r2 = dx * dx + dy * dy
                r = math.sqrt(r2)
                if from_north:
                    bearing, j10, j11 = math.atan2(dx, dy), dy / r2, -dx / r2
                else:
                    bearing, j10, j11 = math.atan2(dy, dx), -dy / r2, dx / r2
                j00, j01 = dx / r, dy / r
                e0 = z[k, s, 0] - r
                e1 = (z[k, s, 1] - bearing + math.pi) % two_pi - math.pi
                c00, c01, c10, c11 = Ct[s, 0, 0], Ct[s, 0, 1], Ct[s, 1, 0], Ct[s, 1, 1]
                b00, b01 = c00 * j00 + c01 * j10, c00 * j01 + c01 * j11
                b10, b11 = c10 * j00 + c11 * j10, c10 * j01 + c11 * j11
                w0, w1 = c00 * e0 + c01 * e1, c10 * e0 + c11 * e1
                a00 += b00 * b00 + b10 * b10
                a01 += b00 * b01 + b10 * b11
                a11 += b01 * b01 + b11 * b11
                g0 += b00 * w0 + b10 * w1
                g1 += b01 * w0 + b11 * w1
            det = a00 * a11 - a01 * a01
            d0, d1 = (a11 * g0 - a01 * g1) / det, (a00 * g1 - a01 * g0) / det
            px, py = px + d0, py + d1
            if it == 0:
                first = (px, py, a00, a01, a11)
            if d0 * g0 + d1 * g1 < tol * tol:
                converged = True
                break
        if not converged:  # the first step, linearised at the start
            px, py, a00, a01, a11 = first
        out[k, 0], out[k, 1] = px, py
        info[k, 0, 0], info[k, 0, 1], info[k, 1, 0], info[k, 1, 1] = a00, a01, a01, a11
    return out, info


@lru_cache(maxsize=1)
def compiled_gauss_newton() -> Callable[..., tuple[FloatArray, FloatArray]] | None:
    """:func:`gauss_newton_range_bearing` compiled by numba, or None without numba
    (:func:`equivalent_measurement` then runs its NumPy loop).

    Compiled on the first call (about a second; loaded from numba's disk cache afterwards, a
    tenth of that) for the argument types :func:`equivalent_measurement` passes: writable
    ``z``, ``hit``, ``p0``, read-only (cached) sensor positions and whitening.
    """
    kernel = jit(gauss_newton_range_bearing)
    if kernel is None:
        return None
    fixed = np.zeros((1, 2)), np.eye(2)[None]
    for a in fixed:
        a.setflags(write=False)
    kernel(np.ones((1, 1, 2)), np.ones((1, 1), dtype=bool), np.ones((1, 2)), *fixed, False, 1, 0.0)
    return kernel


def compiled_range_bearing(
    sensors: Sequence[MeasurementModel],
) -> tuple[Callable[..., tuple[FloatArray, FloatArray]], tuple[RangeBearing, FloatArray]] | None:
    """The compiled Gauss-Newton loop and the sensors' range-bearing group (first model,
    positions) when both exist (numba installed, all sensors range-bearing with one
    ``position_index``), else None."""
    group = range_bearing_group(sensors)
    kernel = compiled_gauss_newton() if group is not None else None
    return None if kernel is None or group is None else (kernel, group)


def _solve_last(A: FloatArray, b: FloatArray) -> FloatArray:
    """Solutions ``(n, k)`` of ``k`` linear systems stored with the system axis last, ``A (n,
    n, k)``, ``b (n, k)`` (closed form for ``n = 2``: the adjugate over the determinant)."""
    if A.shape[0] != 2:
        return np.asarray(np.linalg.solve(A.transpose(2, 0, 1), b.T[..., None])[..., 0].T)
    adj = A[::-1, ::-1] * _ADJUGATE_SIGN
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    return np.asarray(np.einsum("pqk,qk->pk", adj, b) / det)


_ADJUGATE_SIGN = np.array([[1.0, -1.0], [-1.0, 1.0]])[..., None]  # adj(A) = sign * A[::-1, ::-1]


def sensor_constants(sensors: Sequence[MeasurementModel]) -> tuple[FloatArray, ...]:
    """Noise covariances ``R_s`` (S, m, m), whitening ``C_sᵀ`` with ``R_s⁻¹ = C_s C_sᵀ`` (S, m,
    m) and angle masks (S, m) of the sensors (read-only; computed once per set of sensors,
    which are immutable, unless a model cannot be hashed)."""
    try:
        return _constants_of(tuple(sensors))
    except TypeError:
        return _constants_of.__wrapped__(tuple(sensors))


@lru_cache(maxsize=16)
def _constants_of(sensors: tuple[MeasurementModel, ...]) -> tuple[FloatArray, ...]:
    R = np.array([model.R for model in sensors])
    Ct = np.ascontiguousarray(np.swapaxes(np.linalg.cholesky(np.linalg.inv(R)), 1, 2))
    angle = np.array([model.angle_mask for model in sensors])
    for a in (R, Ct, angle):
        a.setflags(write=False)
    return R, Ct, angle
