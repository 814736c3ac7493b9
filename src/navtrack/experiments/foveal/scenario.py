"""Closed-loop foveal tracking runs of paper 4: truth, sensor control, filter, errors.

:func:`track_foveal` runs ``B`` filters side by side, one per batch row (the three control rules
on one truth in a reproduction run, or many Monte Carlo truths of one configuration in the speed
benchmark): each scan it predicts the estimates (Table 1 step 4), configures the sensor
(:func:`navtrack.tracking.trackers.sensor_control.configure`), simulates the scan
(:meth:`navtrack.tracking.models.FovealSensor.scan`) and updates the filter
(:func:`navtrack.tracking.trackers.particle.jmpd_step`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.tracking.models import FovealSensor, LinearMotion
from navtrack.tracking.trackers.particle import (
    JmpdConfig,
    StepStatus,
    jmpd_init,
    jmpd_step,
    predicted_estimates,
)
from navtrack.tracking.trackers.sensor_control import ControlRule, configure

__all__ = ["FovealTrack", "converged", "simulate_truth", "track_foveal"]


@dataclass(frozen=True, slots=True, eq=False)
class FovealTrack:
    """Outcome of :func:`track_foveal` for ``B`` filters over ``K`` scans (arrays read-only).

    Attributes
    ----------
    estimates : (B, K, T, n) float
        Posterior mean state of each target after scans ``1..K``.
    position_error_m : (B, K, T) float
        Estimated minus true position, m (target labels as initialised).
    gain : (B, K) float
        Foveal gain ``c_k`` used, 1/m.
    centre_m : (B, K) float
        Foveal centre ``d_k``, m.
    status_counts : (B, 4) int
        Scans per :class:`~navtrack.tracking.trackers.particle.StepStatus` value.
    resamplings : (B,) int
        Scans after which the particles were resampled.
    """

    estimates: FloatArray
    position_error_m: FloatArray
    gain: FloatArray
    centre_m: FloatArray
    status_counts: IntArray
    resamplings: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def simulate_truth(
    x0: ArrayLike, motion: LinearMotion, dt: float, steps: int, rng: np.random.Generator
) -> FloatArray:
    """Target trajectories ``x_k = F x_{k-1} + n_k`` from ``x0 (T, n)``: ``(steps + 1, T, n)``."""
    x0 = np.asarray(x0, dtype=float)
    F = motion.F(dt)
    vals, vecs = np.linalg.eigh(motion.Q(dt))
    S = vecs * np.sqrt(np.clip(vals, 0.0, None))
    out = np.empty((steps + 1, *x0.shape))
    out[0] = x0
    for k in range(1, steps + 1):
        out[k] = out[k - 1] @ F.T + rng.standard_normal(x0.shape) @ S.T
    return out


def track_foveal(
    truth: ArrayLike,
    rules: Sequence[ControlRule],
    sensor: FovealSensor,
    config: JmpdConfig,
    P0: ArrayLike,
    rng: np.random.Generator,
) -> FovealTrack:
    """Track ``B`` truths with the foveal sensor under the given control rules.

    Parameters
    ----------
    truth : (B, K + 1, T, n) float
        True states at scans ``0..K``; the particles start from ``N(truth[:, 0], P0)`` (paper:
        "mean is the true targets' state x0").
    rules : sequence of B rules ("so", "to", "wo")
        Control rule of each row.
    sensor : FovealSensor
    config : JmpdConfig
    P0 : (n, n) float
        Initial covariance of each partition (paper: ``diag(1, 0.1)``).
    rng : numpy.random.Generator

    Returns
    -------
    FovealTrack
    """
    truth = np.asarray(truth, dtype=float)
    B, K1, T, n = truth.shape
    if len(rules) != B:
        raise ValueError(f"rules: need one per truth row ({B}), got {len(rules)}")
    K = K1 - 1
    state = jmpd_init(truth[:, 0], P0, config, rng)
    est = np.empty((B, K, T, n))
    gain = np.empty((B, K))
    centre = np.empty((B, K))
    counts = np.zeros((B, len(StepStatus)), dtype=np.int64)
    resamplings = np.zeros(B, dtype=np.int64)
    groups = {rule: np.flatnonzero([r == rule for r in rules]) for rule in set(rules)}
    pos = sensor.position_index
    for k in range(1, K + 1):
        x_pred, P_pred = predicted_estimates(state, config.motion, config.dt)
        c = np.empty(B)
        d = np.empty(B)
        for rule, rows in groups.items():
            c[rows], d[rows], _ = configure(rule, x_pred[rows], P_pred[rows], sensor.R, k, pos)
        scan = sensor.scan(truth[:, k, :, pos], c, d, rng)
        step = jmpd_step(state, scan, c, d, sensor, config, rng)
        state = step.state
        est[:, k - 1] = state.x
        gain[:, k - 1] = c
        centre[:, k - 1] = d
        counts[np.arange(B), step.status] += 1
        resamplings += step.resampled
    err = est[..., pos] - truth[:, 1:, :, pos]
    return FovealTrack(est, err, gain, centre, counts, resamplings)


def converged(position_error_m: ArrayLike, threshold_m: float, last_steps: int) -> FloatArray:
    """Whether every target's ``|error| < threshold_m`` over the last ``last_steps`` scans.

    ``position_error_m (..., K, T)`` -> ``(...)`` bool (the paper's convergence, section VI).
    """
    e = np.abs(np.asarray(position_error_m, dtype=float))[..., -last_steps:, :]
    return np.asarray(np.all(e < threshold_m, axis=(-2, -1)))
