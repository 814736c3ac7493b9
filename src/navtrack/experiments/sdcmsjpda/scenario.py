"""Paper 3's scenario: three range-bearing sensors, two crossing targets, one Monte Carlo run.

Parameters from Zhang, Xiong & He (ICMLC 2005, section 4) where the paper gives them; the rest
(marked "not in the paper") are this reproduction's choices, stated in
:class:`SdCmsjpdaParams`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from navtrack._typing import FloatArray
from navtrack.tracking.gating import chi2_threshold
from navtrack.tracking.models import RangeBearing, constant_velocity, wrap_angle
from navtrack.tracking.simulate import simulate_truth
from navtrack.tracking.trackers.multisensor import (
    ALGORITHMS,
    Algorithm,
    FusionConfig,
    MultiScans,
    run_fusion,
)

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
    clutter_rate : the paper's ``m = 1.8``: "The nonparametric model of clutter is used in the
        simulations, and expected number of false measurement is m=1.8" (section 4), and in
        eq. 26 "m is the expected number of false measurements in the gate".
    clutter_model : how ``m`` sets the clutter (the paper gives no region):

        * ``"gate"`` (default): ``m`` false measurements expected in each validation gate —
          eq. 26's definition of ``m``, the usual reading in PDA papers. The density of sensor
          ``s`` is ``λ_s = m / V_s`` with ``V_s = π γ |R_s|^{1/2}`` the area of the ``P_G``
          gate (``γ`` its chi-square threshold) of the measurement noise alone, the smallest
          gate a track has (a gate of ``S = R + H P Hᵀ`` holds more); the false measurements
          are uniform with that density over the union of the range-bearing boxes of
          half-widths ``c·σ_r × c·σ_θ`` (``c`` = ``clutter_halfwidth_sigma``) centred on the
          targets' true measurements, which contain the gates (clutter outside every gate
          never enters a tracker);
        * ``"box"``: ``m`` false measurements per sensor and scan in total, uniform over those
          boxes (the previous reading; 0.4-0.9 per gate at ``c = 4``);
        * ``"region"``: ``m`` per sensor and scan uniform over the sensor's whole surveillance
          region, ranges 0 to the largest true range plus ``c·σ_r``, all bearings (almost no
          clutter in any gate).

        The trackers use the true density (parametric JPDA, eq. 21).
    clutter_halfwidth_sigma : not in the paper; ``c`` above (6: the boxes contain every gate of
        a track whose prediction is within a few standard deviations).
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
    algorithms : the fusion trackers run: sequential, parallel, ``sdcmsjpda`` (eqs. 24-32 as
        printed, eq. 26's ``m`` = ``clutter_rate``), S-D GNN and the ML-fused reading
        ``sdcmsjpda_fused`` by default; ``sdcmsjpda_joint`` (the joint tuple likelihood, a
        diagnostic, not eq. 15) on request; a subset for quick studies of other settings
    sensitivity_runs : Monte Carlo runs of each other reading of the sensitivity table
        (:mod:`~navtrack.experiments.sdcmsjpda.sensitivity`; every tracker of ``algorithms``
        under each reading; 0: no table)
    timing_repeat : passes of the timing of SD-CMSJPDA against sequential MSJPDA, with numba
        and without (:mod:`~navtrack.experiments.sdcmsjpda.timing`; 0: not timed)
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
    clutter_model: Literal["gate", "box", "region"] = "gate"
    clutter_halfwidth_sigma: float = 6.0
    accel_sigma_mps2: float = 1.0
    init_sigma_pos_m: float = 1000.0
    init_sigma_vel_mps: float = 100.0
    gate_probability: float = 0.99
    divergence_m: float = 2000.0
    divergence_window: int = 10
    algorithms: tuple[Algorithm, ...] = (
        "sequential",
        "parallel",
        "sdcmsjpda",
        "sd_gnn",
        "sdcmsjpda_fused",
    )
    sensitivity_runs: int = 10
    timing_repeat: int = 3

    def __post_init__(self) -> None:
        S = len(self.sensor_x_m)
        for name in ("sensor_y_m", "sigma_r_m", "sigma_theta_rad"):
            if len(getattr(self, name)) != S:
                raise ValueError(f"{name}: need {S} values, one per sensor")
        if not self.pd_values or not all(0 < p <= 1 for p in self.pd_values):
            raise ValueError(f"pd_values must be in (0, 1], got {self.pd_values}")
        if self.n_steps < self.divergence_window or self.divergence_window < 1:
            raise ValueError("need 1 <= divergence_window <= n_steps")
        if not self.algorithms or any(a not in ALGORITHMS for a in self.algorithms):
            raise ValueError(f"algorithms must be a non-empty subset of {ALGORITHMS}")
        if self.sensitivity_runs < 0 or self.timing_repeat < 0:
            raise ValueError("sensitivity_runs and timing_repeat must be >= 0")
        if not (self.clutter_rate > 0 and self.clutter_halfwidth_sigma > 0):
            raise ValueError("clutter_rate and clutter_halfwidth_sigma must be > 0")


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


def _boxes_area(params: SdCmsjpdaParams, s: int) -> float:
    """Area of one clutter box of sensor ``s``, m·rad."""
    c = params.clutter_halfwidth_sigma
    return 4.0 * c * c * params.sigma_r_m[s] * params.sigma_theta_rad[s]


def _region_max_range(params: SdCmsjpdaParams, truth: FloatArray, s: int) -> float:
    """Outer range of sensor ``s``'s surveillance region (``"region"`` clutter), m."""
    model = sensors(params)[s]
    return float(
        model.h(truth)[..., 0].max() + params.clutter_halfwidth_sigma * params.sigma_r_m[s]
    )


def clutter_density(
    params: SdCmsjpdaParams, n_targets: int, truth: FloatArray | None = None
) -> tuple[float, ...]:
    """``λ_s`` per m·rad of each sensor under ``params.clutter_model`` (class notes).

    ``"box"`` takes the targets' boxes as disjoint; ``"region"`` needs the ``truth``
    ``(K, T, n)`` for the region's outer range.
    """
    m = params.clutter_rate
    S = len(params.sigma_r_m)
    if params.clutter_model == "gate":
        gamma = chi2_threshold(params.gate_probability, 2)
        return tuple(
            m / (np.pi * gamma * params.sigma_r_m[s] * params.sigma_theta_rad[s]) for s in range(S)
        )
    if params.clutter_model == "box":
        return tuple(m / n_targets / _boxes_area(params, s) for s in range(S))
    if truth is None:
        raise ValueError("clutter_density: the 'region' clutter model needs the truth")
    return tuple(m / (2.0 * np.pi * _region_max_range(params, truth, s)) for s in range(S))


def _clutter(
    params: SdCmsjpdaParams,
    model: RangeBearing,
    centre: FloatArray,
    density: float,
    region_range_m: float,
    rng: np.random.Generator,
) -> FloatArray:
    """False measurements ``(n, 2)`` of one sensor and scan, uniform with ``density``.

    ``centre (T, 2)``: the targets' true measurements. ``"gate"``: on the union of the boxes
    (each box drawn with Poisson(``density`` x area) points, those also in an earlier box
    dropped); ``"box"``: Poisson(``m``) in total, each point in the box of a random target;
    ``"region"``: Poisson(``m``) over ranges ``[0, region_range_m]`` and all bearings.
    """
    half = params.clutter_halfwidth_sigma * np.sqrt(np.diag(model.R))
    if params.clutter_model == "region":
        n = rng.poisson(params.clutter_rate)
        return np.column_stack(
            [rng.random(n) * region_range_m, (2.0 * rng.random(n) - 1.0) * np.pi]
        )
    if params.clutter_model == "box":
        pick = rng.integers(0, len(centre), rng.poisson(params.clutter_rate))
        zc = centre[pick] + (2.0 * rng.random((pick.size, 2)) - 1.0) * half
    else:
        parts = []
        for t in range(len(centre)):
            n = rng.poisson(density * 4.0 * half[0] * half[1])
            zt = centre[t] + (2.0 * rng.random((n, 2)) - 1.0) * half
            d = np.abs(zt[:, None, :] - centre[None, :t, :])
            d[..., 1] = np.abs(wrap_angle(d[..., 1]))
            parts.append(zt[~np.any(np.all(d <= half, axis=-1), axis=1)])
        zc = np.concatenate(parts)
    zc[:, 1] = wrap_angle(zc[:, 1])
    return zc


def simulate_scans(
    params: SdCmsjpdaParams, truth: FloatArray, pd: float, rng: np.random.Generator
) -> MultiScans:
    """Detections (probability ``pd``) and clutter (class notes) of every sensor and scan."""
    sens = sensors(params)
    K, T, _ = truth.shape
    S = len(sens)
    lam = clutter_density(params, T, truth)
    rows: list[list[FloatArray]] = [[] for _ in range(K)]
    for s, model in enumerate(sens):
        centre = model.h(truth)
        zt = centre + rng.standard_normal((K, T, 2)) @ np.linalg.cholesky(model.R).T
        zt[..., 1] = wrap_angle(zt[..., 1])
        det = rng.random((K, T)) < pd
        r_max = _region_max_range(params, truth, s) if params.clutter_model == "region" else 0.0
        for k in range(K):
            zc = _clutter(params, model, centre[k], lam[s], r_max, rng)
            zk = np.concatenate([zt[k, det[k]], zc])
            rows[k].append(zk[rng.permutation(len(zk))])
    N = max(len(zk) for row in rows for zk in row)
    z = np.full((K, S, max(N, 1), 2), np.nan)
    valid = np.zeros((K, S, max(N, 1)), dtype=bool)
    for k, row in enumerate(rows):
        for s, zk in enumerate(row):
            z[k, s, : len(zk)] = zk
            valid[k, s, : len(zk)] = True
    t = np.repeat((np.arange(K) * params.dt_s)[:, None], S, axis=1)
    return MultiScans(z, valid, t)


def paper3_run(params: SdCmsjpdaParams, rng: np.random.Generator) -> dict[str, Any]:
    """One Monte Carlo run: every ``P_D`` and every algorithm on the same truth.

    Returns
    -------
    dict
        ``{pd: {algorithm: {"pos_err_per_target_m": (K, T), "pos_err2_m2": (K,),
        "vel_err2_m2ps2": (K,), "diverged": bool, "failed": str, "ms_per_step": float}}}``,
        squared errors averaged over the targets (the per-target errors kept in the run
        checkpoints so that other divergence rules can be applied afterwards),
        ``pd`` keyed as ``f"{pd:g}"``; ``failed`` is the error message of a filter that broke
        down numerically ("" when none), counted as diverged.
    """
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    x0 = np.array([params.x1, params.x2], dtype=float)
    truth = simulate_truth(motion, x0, params.n_steps, params.dt_s)
    T = x0.shape[0]
    sens = sensors(params)
    lam = clutter_density(params, T, truth)
    sp, sv = params.init_sigma_pos_m, params.init_sigma_vel_mps
    P0 = np.broadcast_to(np.diag([sp**2, sv**2, sp**2, sv**2]), (T, 4, 4))
    out: dict[str, Any] = {}
    for pd in params.pd_values:
        scans = simulate_scans(params, truth, pd, rng)
        xi = x0 + rng.standard_normal(x0.shape) * np.array([sp, sv, sp, sv])
        config = FusionConfig(
            (pd,) * len(sens), lam, params.gate_probability, false_per_gate=params.clutter_rate
        )
        per: dict[str, Any] = {}
        for alg in params.algorithms:
            try:
                res = run_fusion(alg, scans, sens, motion, xi, P0, config, t0_s=0.0)
            except (ValueError, np.linalg.LinAlgError) as exc:
                nan = np.full(params.n_steps, np.nan)
                per[alg] = {
                    "pos_err_per_target_m": np.full((params.n_steps, T), np.nan),
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
                "pos_err_per_target_m": np.sqrt(pe2),
                "pos_err2_m2": pe2.mean(axis=1),
                "vel_err2_m2ps2": ve2.mean(axis=1),
                "diverged": bool(np.any(tail > params.divergence_m)),
                "failed": "",
                "ms_per_step": res.ms_per_step,
            }
        out[f"{pd:g}"] = per
    return out
