"""Error-state Kalman filter and Rauch-Tung-Striebel smoother: gyro propagation + camera fixes.

The filter the paper started and did not finish ("complete the EKF and extend it to an optimal
smoother"). It runs about a fixed nominal propagation ``p_k`` (the calibrated one,
:func:`~navtrack.attitude.calibration.calibrated_propagation`) on the error state

``x = [δθ, δb]``: ``q_true = exp(δθ) ⊗ p`` (reference-frame attitude error, rad) and the residual
gyro bias ``δb`` (body frame, rad/s), with ``ω_true = ω_c - δb``. Between two nodes ``a -> b``

``δθ_b = δθ_a - A δb_a + w_θ``, ``δb_b = δb_a + w_b``, ``A = Σ_{a≤k<b} R(p_k) Δt_k``

(``R(p_k)`` body -> reference), with angle random walk ``σ_g`` and bias random walk ``σ_b``:
``Q = [[σ_g² T I + σ_b² T A Aᵀ/3, -σ_b² T A/2], [-σ_b² T Aᵀ/2, σ_b² T I]]`` (exact for a constant
``R``). A fix at IMU time ``t`` measures ``z = rotvec(q_fix ⊗ p(t)⁻¹) = δθ + v``,
``v ~ N(0, σ_fix² I)``. Nodes are the samples of the fixes plus a grid every
``node_interval_s``; between nodes the estimate is carried by the same dynamics
(``δθ_k = δθ_a - (C_k - C_a) δb_a``). Predict and update are the shared Kalman kernels
(:func:`navtrack.estimation.kalman.kf_predict`, :func:`~navtrack.estimation.kalman.kf_update`), the
smoother gain is :func:`~navtrack.estimation.kalman.kalman_gain`.

References
----------
.. [1] H. E. Rauch, F. Tung, C. T. Striebel, "Maximum likelihood estimates of linear dynamic
   systems", AIAA J. 3(8), 1965.
.. [2] J. Solà, "Quaternion kinematics for the error-state Kalman filter", arXiv:1711.02508,
   2017, section 7 (global-frame attitude error).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.attitude.quaternion import Propagation, interpolate_attitude
from navtrack.estimation.kalman import kalman_gain, kf_predict, kf_update

__all__ = [
    "SIGMA_BIAS_RAD_S_SQRT_S",
    "SIGMA_GYRO_RAD_SQRT_S",
    "SmootherConfig",
    "SmootherResult",
    "smooth_attitude",
]

_H = np.hstack([np.eye(3), np.zeros((3, 3))])

SIGMA_GYRO_RAD_SQRT_S = 2e-3
"""Default angle random walk of the smoother's gyro model, rad/√s. Far above a MEMS data-sheet
value because it also takes up the gyro errors the calibration leaves (scale nonlinearity at
high rates, time-varying bias). How it was chosen (BROAD trial 07) and judged (trial 02):
``docs/attitude.md``, method notes, "Smoother noise"."""

SIGMA_BIAS_RAD_S_SQRT_S = 1e-4
"""Default bias random walk of the smoother's gyro model, rad/s/√s."""


@dataclass(frozen=True, slots=True)
class SmootherConfig:
    """Noise model of the error-state filter.

    Attributes
    ----------
    sigma_gyro_rad_sqrt_s : float
        Angle random walk, rad/√s (default :data:`SIGMA_GYRO_RAD_SQRT_S`).
    sigma_bias_rad_s_sqrt_s : float
        Bias random walk, rad/s/√s (default :data:`SIGMA_BIAS_RAD_S_SQRT_S`).
    sigma_att0_rad, sigma_bias0_rad_s : float
        Prior standard deviations at the first node.
    node_interval_s : float
        Grid of filter nodes between fixes.
    """

    sigma_gyro_rad_sqrt_s: float = SIGMA_GYRO_RAD_SQRT_S
    sigma_bias_rad_s_sqrt_s: float = SIGMA_BIAS_RAD_S_SQRT_S
    sigma_att0_rad: float = 0.05
    sigma_bias0_rad_s: float = 1e-3
    node_interval_s: float = 0.1

    def __post_init__(self) -> None:
        vals = (
            self.sigma_gyro_rad_sqrt_s,
            self.sigma_bias_rad_s_sqrt_s,
            self.sigma_att0_rad,
            self.sigma_bias0_rad_s,
            self.node_interval_s,
        )
        if not all(v > 0 for v in vals):
            raise ValueError(
                f"SmootherConfig: every standard deviation and interval must be > 0, got {vals}"
            )


@dataclass(frozen=True, slots=True, eq=False)
class SmootherResult:
    """Filtered and smoothed attitudes (arrays read-only).

    Attributes
    ----------
    filter_quat : (n, 4) forward filter attitude at every sample (causal), scalar-last
    smoother_quat : (n, 4) RTS smoother attitude at every sample, scalar-last
    node_sample : (N,) samples of the filter nodes
    x_filter, x_smooth : (N, 6) error states ``[δθ (rad), δb (rad/s)]`` at the nodes
    sigma_smooth_rad : (N,) RMS per-axis attitude standard deviation of the smoother
    nis : (m,) normalised innovation squared of each fix (3 degrees of freedom)
    """

    filter_quat: FloatArray
    smoother_quat: FloatArray
    node_sample: IntArray
    x_filter: FloatArray
    x_smooth: FloatArray
    sigma_smooth_rad: FloatArray
    nis: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _transition(A: FloatArray, T: float, cfg: SmootherConfig) -> tuple[FloatArray, FloatArray]:
    F = np.eye(6)
    F[:3, 3:] = -A
    g2 = cfg.sigma_gyro_rad_sqrt_s**2 * T
    b2 = cfg.sigma_bias_rad_s_sqrt_s**2 * T
    Q = np.zeros((6, 6))
    Q[:3, :3] = g2 * np.eye(3) + b2 * (A @ A.T) / 3.0
    Q[:3, 3:] = -b2 * A / 2.0
    Q[3:, :3] = Q[:3, 3:].T
    Q[3:, 3:] = b2 * np.eye(3)
    return F, Q


def _carry(x_nodes: FloatArray, nodes: IntArray, C: FloatArray, n: int) -> FloatArray:
    """Node error states carried to every sample by the error dynamics: ``(n, 3)`` δθ."""
    node_of = np.searchsorted(nodes, np.arange(n), side="right") - 1
    dC = C[:n] - C[nodes[node_of]]
    xs = x_nodes[node_of]
    return np.asarray(xs[:, :3] - np.einsum("kij,kj->ki", dC, xs[:, 3:]))


def _apply(delta: FloatArray, quat: FloatArray) -> FloatArray:
    return np.asarray((Rotation.from_rotvec(delta) * Rotation.from_quat(quat)).as_quat())


def _forward(
    t: FloatArray,
    C: FloatArray,
    nodes: IntArray,
    fix_node: IntArray,
    z: FloatArray,
    fsig: FloatArray,
    cfg: SmootherConfig,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """The filter over the nodes: filtered states and covariances, predicted ones, the
    transitions into each node and the NIS of every fix."""
    N = nodes.size
    xf = np.zeros((N, 6))
    Pf = np.zeros((N, 6, 6))
    xp = np.zeros((N, 6))
    Pp = np.zeros((N, 6, 6))
    Fs = np.zeros((N, 6, 6))
    nis = np.full(z.shape[0], np.nan)
    x = np.zeros(6)
    P = np.diag([cfg.sigma_att0_rad**2] * 3 + [cfg.sigma_bias0_rad_s**2] * 3)
    fixes_at = np.split(
        np.argsort(fix_node, kind="stable"), np.cumsum(np.bincount(fix_node, minlength=N))[:-1]
    )
    for j in range(N):
        if j > 0:
            F, Q = _transition(C[nodes[j]] - C[nodes[j - 1]], t[nodes[j]] - t[nodes[j - 1]], cfg)
            x, P = kf_predict(x, P, F, Q)
            Fs[j] = F
        xp[j], Pp[j] = x, P
        for i in fixes_at[j]:
            upd = kf_update(x, P, z[i], _H, fsig[i] ** 2 * np.eye(3), joseph=True)
            x, P = upd.x, upd.P
            nis[i] = float(upd.nis)
        xf[j], Pf[j] = x, P
    return xf, Pf, xp, Pp, Fs, nis


def _backward(
    xf: FloatArray, Pf: FloatArray, xp: FloatArray, Pp: FloatArray, Fs: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Rauch–Tung–Striebel pass: smoothed states and covariances at the nodes."""
    xs = xf.copy()
    Ps = Pf.copy()
    for j in range(xf.shape[0] - 2, -1, -1):
        G = kalman_gain(Pf[j] @ Fs[j + 1].T, Pp[j + 1])
        xs[j] = xf[j] + G @ (xs[j + 1] - xp[j + 1])
        Ps[j] = Pf[j] + G @ (Ps[j + 1] - Pp[j + 1]) @ G.T
    return xs, Ps


def smooth_attitude(
    t_s: ArrayLike,
    nominal: Propagation,
    rates_rad_s: ArrayLike,
    fix_t_s: ArrayLike,
    fix_quat: ArrayLike,
    fix_sigma_rad: ArrayLike,
    config: SmootherConfig | None = None,
) -> SmootherResult:
    """Filter and smooth the nominal propagation with camera fixes.

    Parameters
    ----------
    t_s : (n,) IMU sample times, s
    nominal : Propagation
        Attitudes from ``rates_rad_s`` at every sample.
    rates_rad_s : (n, 3) the body rates the nominal was propagated with, rad/s
    fix_t_s : (m,) fix times **on the IMU clock** (stamp + calibrated timing offset), s
    fix_quat : (m, 4) fix attitudes, scalar-last
    fix_sigma_rad : (m,) per-axis fix standard deviations, rad
    config : SmootherConfig or None

    Returns
    -------
    SmootherResult
    """
    cfg = SmootherConfig() if config is None else config
    t = np.asarray(t_s, dtype=np.float64)
    n = t.size
    rates = np.asarray(rates_rad_s, dtype=np.float64)
    ft = np.asarray(fix_t_s, dtype=np.float64)
    fq = np.asarray(fix_quat, dtype=np.float64)
    fsig = np.asarray(fix_sigma_rad, dtype=np.float64)
    if nominal.quat.shape != (n, 4) or rates.shape != (n, 3):
        raise ValueError("nominal and rates_rad_s must cover the n samples of t_s")
    if fq.shape != (ft.size, 4) or fsig.shape != ft.shape:
        raise ValueError("fix_t_s (m,), fix_quat (m, 4) and fix_sigma_rad (m,) expected")
    # Reference-frame error of the nominal at each fix.
    pred = interpolate_attitude(t, nominal.quat, rates, ft)
    z = np.asarray((Rotation.from_quat(fq) * Rotation.from_quat(pred).inv()).as_rotvec())
    z = z.reshape(-1, 3)
    fix_sample = np.clip(np.searchsorted(t, ft), 0, n - 1)
    step = max(1, round(cfg.node_interval_s / float(np.median(np.diff(t)))))
    nodes = np.unique(np.concatenate([np.arange(0, n, step), fix_sample, [n - 1]]))
    fix_node = np.searchsorted(nodes, fix_sample)
    # C_k = Σ_{j<k} R(p_j) Δt_j
    Rm = np.asarray(Rotation.from_quat(nominal.quat).as_matrix())
    dt = np.diff(t)
    C = np.zeros((n, 3, 3))
    C[1:] = np.cumsum(Rm[:-1] * dt[:, None, None], axis=0)

    xf, Pf, xp, Pp, Fs, nis = _forward(t, C, nodes, fix_node, z, fsig, cfg)
    xs, Ps = _backward(xf, Pf, xp, Pp, Fs)
    filt = _apply(_carry(xf, nodes, C, n), nominal.quat)
    smooth = _apply(_carry(xs, nodes, C, n), nominal.quat)
    sigma = np.sqrt(np.trace(Ps[:, :3, :3], axis1=1, axis2=2) / 3.0)
    return SmootherResult(filt, smooth, nodes.astype(np.int64), xf, xs, sigma, nis)
