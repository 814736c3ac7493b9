"""Seeded truth and detection simulators.

Truth trajectories are batched over leading axes (e.g. Monte Carlo runs); detections come out on
fixed shapes with a ``valid`` mask (``steps × max detections``), as the rest of navtrack expects.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.models import MeasurementModel, MotionModel, wrap_angle

__all__ = ["Scans", "paper3_scenario", "simulate_detections", "simulate_truth"]


def simulate_truth(
    model: MotionModel,
    x0: ArrayLike,
    n_steps: int,
    dt: float,
    rng: np.random.Generator | None = None,
) -> FloatArray:
    """Propagate initial states through ``model`` for ``n_steps`` steps.

    Parameters
    ----------
    model : motion model
    x0 : (..., n_targets, dim_x) initial states (step 0)
    n_steps : int, number of steps including step 0
    dt : float, s
    rng : Generator or None
        Process noise ``w ~ N(0, Q(dt))`` is added when given; ``None`` gives the noise-free
        (deterministic) trajectory, as in paper 3's crossing targets.

    Returns
    -------
    truth : (..., n_steps, n_targets, dim_x)
    """
    x = np.asarray(x0, dtype=float)
    if x.ndim < 2 or x.shape[-1] != model.dim_x:
        raise ValueError(f"x0 must be (..., n_targets, {model.dim_x}), got {x.shape}")
    if n_steps < 1:
        raise ValueError(f"n_steps must be >= 1, got {n_steps}")
    out = np.empty((*x.shape[:-2], n_steps, *x.shape[-2:]))
    out[..., 0, :, :] = x
    Lq = None
    if rng is not None:
        Q = model.Q(dt)
        w, V = np.linalg.eigh(Q)
        Lq = V * np.sqrt(np.clip(w, 0, None))
    for k in range(1, n_steps):
        x = model.f(x, dt)
        if Lq is not None and rng is not None:
            x = x + rng.standard_normal(x.shape) @ Lq.T
        out[..., k, :, :] = x
    return out


@dataclass(frozen=True, slots=True, eq=False)
class Scans:
    """Detections of ``K`` scans on fixed shapes (arrays read-only).

    Attributes
    ----------
    z : (K, N, m) measurements (NaN where not valid)
    valid : (K, N) bool
    origin : (K, N) int, index of the target that produced the detection, ``-1`` = clutter
    """

    z: FloatArray
    valid: BoolArray
    origin: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def scan(self, k: int) -> FloatArray:
        """The valid measurements of scan ``k``, shape ``(M_k, m)``."""
        return np.asarray(self.z[k][self.valid[k]])


def simulate_detections(
    truth: ArrayLike,
    model: MeasurementModel,
    pd: float,
    clutter_rate: float,
    clutter_low: ArrayLike,
    clutter_high: ArrayLike,
    rng: np.random.Generator,
) -> Scans:
    """Detections of targets with probability ``pd`` plus Poisson clutter.

    Parameters
    ----------
    truth : (K, n_targets, dim_x) true states per scan (NaN rows = target absent)
    model : measurement model (noise ``N(0, R)``; angles wrapped)
    pd : float, detection probability
    clutter_rate : float, expected false detections per scan (Poisson)
    clutter_low, clutter_high : (m,) box in measurement space where clutter is uniform;
        the clutter spatial density is ``clutter_rate / prod(high - low)``.
    rng : Generator

    Returns
    -------
    Scans, with detections in random order within each scan.
    """
    X = np.asarray(truth, dtype=float)
    if X.ndim != 3:
        raise ValueError(f"truth must be (K, n_targets, dim_x), got {X.shape}")
    if not 0 <= pd <= 1 or clutter_rate < 0:
        raise ValueError("pd must be in [0, 1] and clutter_rate >= 0")
    lo = np.asarray(clutter_low, dtype=float)
    hi = np.asarray(clutter_high, dtype=float)
    K, n, _ = X.shape
    m = model.dim_z
    if lo.shape != (m,) or hi.shape != (m,):
        raise ValueError(
            f"clutter_low, clutter_high: expected shape ({m},), got {lo.shape} and {hi.shape}"
        )
    if not np.all(np.isfinite(lo) & np.isfinite(hi) & (hi >= lo)):
        raise ValueError(f"clutter box: need finite clutter_low <= clutter_high, got {lo}, {hi}")
    present = np.all(np.isfinite(X), axis=-1)
    Lr = np.linalg.cholesky(model.R)
    zt = model.h(np.where(present[..., None], X, 0.0)) + rng.standard_normal((K, n, m)) @ Lr.T
    zt = np.where(model.angle_mask, wrap_angle(zt), zt)
    det = present & (rng.random((K, n)) < pd)
    n_cl = np.asarray(rng.poisson(clutter_rate, K), dtype=np.int64)
    N = int((det.sum(axis=1) + n_cl).max()) if K else 0
    z = np.full((K, N, m), np.nan)
    valid = np.zeros((K, N), dtype=bool)
    origin = np.full((K, N), -1, dtype=np.int64)
    for k in range(K):
        tgt = np.flatnonzero(det[k])
        zc = lo + (hi - lo) * rng.random((n_cl[k], m))
        zk = np.concatenate([zt[k, tgt], zc])
        ok = np.concatenate([tgt, np.full(n_cl[k], -1)])
        perm = rng.permutation(len(zk))
        z[k, : len(zk)] = zk[perm]
        valid[k, : len(zk)] = True
        origin[k, : len(zk)] = ok[perm]
    return Scans(z, valid, origin)


def paper3_scenario() -> dict[str, object]:
    """Two crossing targets of Zhang, Xiong & He (ICMLC 2005), fusion-centre sensor only.

    Targets ``X1 = [-29500 m, 400 m/s, 34500 m, -400 m/s]``,
    ``X2 = [-26250 m, 296 m/s, 34500 m, -400 m/s]`` (state ``[x, vx, y, vy]``), T = 1 s, 140
    steps; sensor 2 at the origin with ``σ_r = 300 m``, ``σ_θ = 0.03 rad``, ``P_D = 0.97``,
    1.8 false measurements per scan. The targets meet at t ≈ 31.25 s at (-17000, 22000) m.
    """
    return {
        "x0": np.array([[-29500.0, 400.0, 34500.0, -400.0], [-26250.0, 296.0, 34500.0, -400.0]]),
        "dt": 1.0,
        "n_steps": 140,
        "sigma_r_m": 300.0,
        "sigma_theta_rad": 0.03,
        "pd": 0.97,
        "clutter_rate": 1.8,
    }
