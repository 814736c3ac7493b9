"""Paper 3's scenario: three range-bearing sensors, two crossing targets, one Monte Carlo run.

Parameters from Zhang, Xiong & He (ICMLC 2005, section 4) where the paper gives them; the rest
(marked "not in the paper") are this reproduction's choices, stated in
:class:`SdCmsjpdaParams`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from navtrack._typing import FloatArray
from navtrack.tracking.models import RangeBearing, constant_velocity, wrap_angle
from navtrack.tracking.multisensor import ALGORITHMS, FusionConfig, MultiScans, run_fusion
from navtrack.tracking.simulate import simulate_truth

__all__ = ["SdCmsjpdaParams", "clutter_density", "paper3_run", "sensors", "simulate_scans"]


@dataclass(frozen=True, slots=True)
class SdCmsjpdaParams:
    """Parameters of the paper-3 reproduction.

    Attributes
    ----------
    pd_values : detection probabilities studied (paper: 0.97, 0.76, 0.58)
    n_steps : scans per run (paper: 140); dt_s : scan period, s (paper: T = 1 s)
    sensor_x_m, sensor_y_m : positions of sensors 1, 2, 3, m (paper: (-500, -500), (0, 0) =
        fusion centre, (-500, 500))
    sigma_r_m, sigma_theta_rad : noise of sensors 1, 2, 3 (paper: 300/200/100 m,
        0.03/0.02/0.01 rad)
    x1, x2 : initial target states ``[x, vx, y, vy]`` (paper)
    clutter_rate : expected false measurements per sensor and scan (paper: m = 1.8)
    clutter_halfwidth_sigma : not in the paper. Clutter region: each false measurement is
        uniform in a range-bearing box centred on the true measurement of a target chosen at
        random, half-widths ``c·σ_r`` and ``c·σ_θ`` of the sensor (``c`` = this, 4) — the
        paper's "nonparametric model" counts false measurements in the gate, so the clutter is
        put where the gates are.
    accel_sigma_mps2 : not in the paper. Filter process noise, discrete white acceleration of
        this standard deviation (the truth is noise-free straight lines, as the paper's crossing
        time implies).
    init_sigma_pos_m, init_sigma_vel_mps : not in the paper. Initial estimate drawn from
        ``N(truth, P0)``, ``P0 = diag(σp², σv², σp², σv²)``, same draw for all algorithms.
    gate_probability : not in the paper; ``P_G`` = 0.99.
    divergence_m : not in the paper. Divergence rule: a run diverged for an algorithm when the
        mean position error of either target over the last ``divergence_window`` scans exceeds
        this (m) — the track is lost or swapped onto the other target.
    divergence_window : scans of that rule.
    """

    pd_values: tuple[float, ...] = (0.97, 0.76, 0.58)
    n_steps: int = 140
    dt_s: float = 1.0
    sensor_x_m: tuple[float, ...] = (-500.0, 0.0, -500.0)
    sensor_y_m: tuple[float, ...] = (-500.0, 0.0, 500.0)
    sigma_r_m: tuple[float, ...] = (300.0, 200.0, 100.0)
    sigma_theta_rad: tuple[float, ...] = (0.03, 0.02, 0.01)
    x1: tuple[float, ...] = (-29500.0, 400.0, 34500.0, -400.0)
    x2: tuple[float, ...] = (-26250.0, 296.0, 34500.0, -400.0)
    clutter_rate: float = 1.8
    clutter_halfwidth_sigma: float = 4.0
    accel_sigma_mps2: float = 1.0
    init_sigma_pos_m: float = 300.0
    init_sigma_vel_mps: float = 30.0
    gate_probability: float = 0.99
    divergence_m: float = 2000.0
    divergence_window: int = 10

    def __post_init__(self) -> None:
        S = len(self.sensor_x_m)
        for name in ("sensor_y_m", "sigma_r_m", "sigma_theta_rad"):
            if len(getattr(self, name)) != S:
                raise ValueError(f"{name}: need {S} values, one per sensor")
        if not self.pd_values or not all(0 < p <= 1 for p in self.pd_values):
            raise ValueError(f"pd_values must be in (0, 1], got {self.pd_values}")
        if self.n_steps < self.divergence_window or self.divergence_window < 1:
            raise ValueError("need 1 <= divergence_window <= n_steps")


def sensors(params: SdCmsjpdaParams) -> list[RangeBearing]:
    """The range-bearing models of sensors 1, 2, 3."""
    return [
        RangeBearing(np.diag([sr**2, st**2]), np.array([x, y]))
        for x, y, sr, st in zip(
            params.sensor_x_m,
            params.sensor_y_m,
            params.sigma_r_m,
            params.sigma_theta_rad,
            strict=True,
        )
    ]


def clutter_density(params: SdCmsjpdaParams, n_targets: int) -> tuple[float, ...]:
    """``λ_s`` per m·rad inside one clutter box (boxes of different targets taken disjoint)."""
    c = params.clutter_halfwidth_sigma
    return tuple(
        params.clutter_rate / n_targets / (4.0 * c * c * sr * st)
        for sr, st in zip(params.sigma_r_m, params.sigma_theta_rad, strict=True)
    )


def simulate_scans(
    params: SdCmsjpdaParams, truth: FloatArray, pd: float, rng: np.random.Generator
) -> MultiScans:
    """Detections (probability ``pd``) and clutter (module notes) of every sensor and scan."""
    sens = sensors(params)
    K, T, _ = truth.shape
    S = len(sens)
    n_cl = rng.poisson(params.clutter_rate, (K, S))
    N = T + int(n_cl.max())
    z = np.full((K, S, N, 2), np.nan)
    valid = np.zeros((K, S, N), dtype=bool)
    for s, model in enumerate(sens):
        zt = model.h(truth) + rng.standard_normal((K, T, 2)) @ np.linalg.cholesky(model.R).T
        zt[..., 1] = wrap_angle(zt[..., 1])
        det = rng.random((K, T)) < pd
        half = params.clutter_halfwidth_sigma * np.sqrt(np.diag(model.R))
        centre = model.h(truth)
        for k in range(K):
            pick = rng.integers(0, T, n_cl[k, s])
            zc = centre[k, pick] + (2.0 * rng.random((n_cl[k, s], 2)) - 1.0) * half
            zc[:, 1] = wrap_angle(zc[:, 1])
            zk = np.concatenate([zt[k, det[k]], zc])
            zk = zk[rng.permutation(len(zk))]
            z[k, s, : len(zk)] = zk
            valid[k, s, : len(zk)] = True
    t = np.repeat((np.arange(K) * params.dt_s)[:, None], S, axis=1)
    return MultiScans(z, valid, t)


def paper3_run(params: SdCmsjpdaParams, rng: np.random.Generator) -> dict[str, Any]:
    """One Monte Carlo run: every ``P_D`` and every algorithm on the same truth.

    Returns
    -------
    dict
        ``{pd: {algorithm: {"pos_err2_m2": (K,), "vel_err2_m2ps2": (K,), "diverged": bool,
        "failed": str, "ms_per_step": float}}}``, squared errors averaged over the targets,
        ``pd`` keyed as ``f"{pd:g}"``; ``failed`` is the error message of a filter that broke
        down numerically ("" when none), counted as diverged.
    """
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    x0 = np.array([params.x1, params.x2], dtype=float)
    truth = simulate_truth(motion, x0, params.n_steps, params.dt_s)
    T = x0.shape[0]
    sens = sensors(params)
    lam = clutter_density(params, T)
    sp, sv = params.init_sigma_pos_m, params.init_sigma_vel_mps
    P0 = np.broadcast_to(np.diag([sp**2, sv**2, sp**2, sv**2]), (T, 4, 4))
    out: dict[str, Any] = {}
    for pd in params.pd_values:
        scans = simulate_scans(params, truth, pd, rng)
        xi = x0 + rng.standard_normal(x0.shape) * np.array([sp, sv, sp, sv])
        config = FusionConfig((pd,) * len(sens), lam, params.gate_probability)
        per: dict[str, Any] = {}
        for alg in ALGORITHMS:
            try:
                res = run_fusion(alg, scans, sens, motion, xi, P0, config, t0_s=0.0)
            except (ValueError, np.linalg.LinAlgError) as exc:
                nan = np.full(params.n_steps, np.nan)
                per[alg] = {
                    "pos_err2_m2": nan,
                    "vel_err2_m2ps2": nan,
                    "diverged": True,
                    "failed": str(exc),
                    "ms_per_step": np.nan,
                }
                continue
            d = res.x - truth
            pe2 = d[..., 0] ** 2 + d[..., 2] ** 2  # (K, T)
            ve2 = d[..., 1] ** 2 + d[..., 3] ** 2
            tail = np.sqrt(pe2[-params.divergence_window :]).mean(axis=0)
            per[alg] = {
                "pos_err2_m2": pe2.mean(axis=1),
                "vel_err2_m2ps2": ve2.mean(axis=1),
                "diverged": bool(np.any(tail > params.divergence_m)),
                "failed": "",
                "ms_per_step": res.ms_per_step,
            }
        out[f"{pd:g}"] = per
    return out
