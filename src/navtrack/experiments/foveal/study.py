"""Parameters, one Monte Carlo run and the summary of the foveal reproduction (paper 4).

One run draws one truth for the three-target scenario and one for the two-target scenario and
tracks each with every configuration of the paper's tables on that same truth (common random
numbers make the comparisons between rules and proposals sharper):

* Tables 3/4 (three targets, without / with clutter): proposals IP-JPDA and KP, the three
  control rules SO, TO, WO side by side as three rows of one batched filter;
* Table 5 (two targets, without / with clutter): IP-JPDA, IP-GNN (the paper's) and the
  IP-GNN variant ``ip_gnn_joint``, rule :attr:`table5_rule`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from navtrack._typing import FloatArray
from navtrack.experiments.foveal.scenario import converged, simulate_truth, track_foveal
from navtrack.tracking.models import FovealSensor, constant_velocity
from navtrack.tracking.trackers.particle import JmpdConfig, Proposal, StepStatus
from navtrack.tracking.trackers.sensor_control import ControlRule

__all__ = [
    "CONDITIONS",
    "RULES",
    "TABLE5_PROPOSALS",
    "TABLE34_PROPOSALS",
    "FovealParams",
    "assigned_errors",
    "foveal_run",
    "summarize_foveal",
    "wilson_interval",
]

RULES: tuple[ControlRule, ...] = ("so", "to", "wo")
TABLE34_PROPOSALS: tuple[Proposal, ...] = ("ip_jpda", "kp")
TABLE5_PROPOSALS: tuple[Proposal, ...] = ("ip_jpda", "ip_gnn", "ip_gnn_joint")
CONDITIONS = ("no_clutter", "clutter")
#: Thresholds (m) of the sensitivity of the converged fraction to the threshold.
THRESHOLDS_M = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0)


@dataclass(frozen=True, slots=True)
class FovealParams:
    """Parameters of ``navtrack reproduce foveal`` (defaults: Xi & Morrell section VI).

    Parameters
    ----------
    q : float
        Process-noise spectral density, m²/s³ (paper: 0.01).
    truth_q : float
        Process-noise spectral density of the simulated truth, m²/s³. The paper gives one q for
        "the target motion model" and does not say how its truths were drawn; its targets are
        "closely spaced" throughout (Figs. 1-3: ASE of tracks that stay converged). With
        ``truth_q = q`` the three targets random-walk about 13 m apart and cross by scan 30;
        ``truth_q = 0`` keeps them on parallel straight lines ``spacing_m`` apart. Fitted on
        Table 3's KP row (``docs/foveal.md``, calibration).
    noise : {"continuous", "discrete"}
        Form of Q (the paper does not say; see
        :class:`~navtrack.tracking.trackers.particle.JmpdConfig`).
    R : float
        Measurement-noise variance, rad² (paper: 0.05).
    dt_s : float
        Scan interval, s (paper: 1).
    n_particles : int
        N_part (paper: 400).
    p0_position_m2, p0_velocity_m2ps2 : float
        ``P0 = diag(1, 0.1)`` (paper).
    steps : int
        Scans per run (paper's figures: 30).
    spacing_m : float
        Initial distance between neighbouring targets, m: targets at ``0, s, 2s`` (Table 5: the
        first two). Not given in the paper; fitted on Table 3's KP row.
    speed_mps : float
        Initial velocity of every target, m/s (not given; 1 m/s, the slope of Fig. 4's tracks).
    pd_clutter, clutter_rate : float
        The clutter condition: Pd = 0.9, λV = 0.5 (paper); without clutter Pd = 1, λV = 0.
    threshold_m : float
        Convergence: every target's position error (after assignment) below this over the last
        ``last_steps`` scans. Not given in the paper; fitted on Table 3's KP row.
    last_steps : int
        Paper: the last ten scans.
    table5_rule : {"so", "to", "wo"}
        Control rule of Table 5 (the paper does not say; WO, its best rule).
    resample_fraction : float
        ``N_T / N_part`` (paper: not given).
    gnn_gate : float
        Gate of the paper's IP-GNN on ``(z - h(x))² / R`` (not given; 9 = three standard
        deviations; ``inf``: no gate, every partition assigned when there are enough
        measurements).
    gain_check : bool
        Run the gain-rule check (:func:`~navtrack.experiments.foveal.gains.gain_check`) in the
        ``extra`` step (26 one-scan optimisations, about 20 s).
    """

    q: float = 0.01
    truth_q: float = 0.01
    noise: Literal["continuous", "discrete"] = "continuous"
    R: float = 0.05
    dt_s: float = 1.0
    n_particles: int = 400
    p0_position_m2: float = 1.0
    p0_velocity_m2ps2: float = 0.1
    steps: int = 30
    spacing_m: float = 2.0
    speed_mps: float = 1.0
    pd_clutter: float = 0.9
    clutter_rate: float = 0.5
    threshold_m: float = 4.0
    last_steps: int = 10
    table5_rule: Literal["so", "to", "wo"] = "wo"
    resample_fraction: float = 0.5
    gnn_gate: float = 9.0
    gain_check: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.spacing_m) and self.spacing_m >= 0):
            raise ValueError(f"spacing_m must be >= 0, got {self.spacing_m}")
        if not 1 <= self.last_steps <= self.steps:
            raise ValueError(
                f"last_steps must be in [1, steps={self.steps}], got {self.last_steps}"
            )
        if not (math.isfinite(self.truth_q) and self.truth_q >= 0):
            raise ValueError(f"truth_q must be >= 0, got {self.truth_q}")
        if not self.threshold_m > 0:
            raise ValueError(f"threshold_m must be > 0, got {self.threshold_m}")

    def config(self, proposal: Proposal) -> JmpdConfig:
        """The filter configuration with ``proposal``."""
        return JmpdConfig(
            motion=constant_velocity(1, self.q, self.noise),
            dt=self.dt_s,
            n_particles=self.n_particles,
            proposal=proposal,
            resample_fraction=self.resample_fraction,
            gnn_gate=self.gnn_gate,
        )

    def sensor(self, condition: str) -> FovealSensor:
        """The sensor of ``condition`` ("no_clutter" or "clutter")."""
        if condition == "clutter":
            return FovealSensor(self.R, self.pd_clutter, self.clutter_rate)
        return FovealSensor(self.R, 1.0, 0.0)

    def x0(self, n_targets: int) -> FloatArray:
        """Initial states ``(n_targets, 2)``: ``[i * spacing_m, speed_mps]``."""
        return np.c_[self.spacing_m * np.arange(n_targets), np.full(n_targets, self.speed_mps)]

    @property
    def P0(self) -> FloatArray:
        return np.diag([self.p0_position_m2, self.p0_velocity_m2ps2])


def assigned_errors(estimates: FloatArray, truth: FloatArray) -> FloatArray:
    """Position errors after the optimal assignment of estimates to true targets, per scan.

    In one dimension the assignment minimising the summed squared (or absolute) error pairs the
    sorted estimates with the sorted truths. ``estimates, truth : (..., T)`` positions ->
    ``(..., T)`` error of the estimate assigned to each true target (truth order).
    """
    order = np.argsort(truth, axis=-1)
    rank = np.argsort(order, axis=-1)
    est_sorted = np.sort(estimates, axis=-1)
    return np.asarray(np.take_along_axis(est_sorted, rank, axis=-1) - truth)


def _record(
    est: FloatArray, err_labelled: FloatArray, truth_pos: FloatArray, p: FovealParams
) -> dict[str, Any]:
    err = assigned_errors(est, truth_pos)
    tail = np.abs(err[-p.last_steps :]).max()
    return {
        "sq_err_m2": err * err,
        "converged": bool(converged(err, p.threshold_m, p.last_steps)),
        "converged_labelled": bool(converged(err_labelled, p.threshold_m, p.last_steps)),
        "max_tail_error_m": float(tail),
    }


def foveal_run(p: FovealParams, rng: np.random.Generator) -> dict[str, Any]:
    """One Monte Carlo run of every configuration on one truth per scenario.

    Returns
    -------
    dict
        ``table3``/``table4``: rule -> proposal -> record; ``table5``: proposal -> condition ->
        record; a record holds ``sq_err_m2 (K, T)`` (errors after assignment), ``converged``,
        ``converged_labelled`` (errors by initial label), ``max_tail_error_m``. ``status``:
        summed step-status counts; ``trajectory``: truth and IP-JPDA/WO estimates in clutter
        (Fig. 4).
    """
    motion = constant_velocity(1, p.truth_q, p.noise)
    truth3 = simulate_truth(p.x0(3), motion, p.dt_s, p.steps, rng)
    truth2 = simulate_truth(p.x0(2), motion, p.dt_s, p.steps, rng)
    out: dict[str, Any] = {"table3": {r: {} for r in RULES}, "table4": {r: {} for r in RULES}}
    out["table5"] = {prop: {} for prop in TABLE5_PROPOSALS}
    status = np.zeros(len(StepStatus), dtype=np.int64)
    for condition, table in zip(CONDITIONS, ("table3", "table4"), strict=True):
        sensor = p.sensor(condition)
        for proposal in TABLE34_PROPOSALS:
            batch = np.broadcast_to(truth3, (len(RULES), *truth3.shape))
            tr = track_foveal(batch, RULES, sensor, p.config(proposal), p.P0, rng)
            status += tr.status_counts.sum(axis=0)
            for b, rule in enumerate(RULES):
                rec = _record(tr.estimates[b, ..., 0], tr.position_error_m[b], truth3[1:, :, 0], p)
                out[table][rule][proposal] = rec
            if condition == "clutter" and proposal == "ip_jpda":
                out["trajectory"] = {
                    "truth_m": truth3[1:, :, 0],
                    "estimate_m": tr.estimates[RULES.index("wo"), ..., 0],
                }
        for proposal in TABLE5_PROPOSALS:
            tr = track_foveal(truth2[None], (p.table5_rule,), sensor, p.config(proposal), p.P0, rng)
            status += tr.status_counts.sum(axis=0)
            rec = _record(tr.estimates[0, ..., 0], tr.position_error_m[0], truth2[1:, :, 0], p)
            out["table5"][proposal][condition] = rec
    out["status"] = {s.name.lower(): int(status[s]) for s in StepStatus}
    return out


def wilson_interval(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score 95 % interval of a binomial proportion ``k / n``."""
    if n == 0:
        return (math.nan, math.nan)
    ph = k / n
    den = 1 + z * z / n
    centre = (ph + z * z / (2 * n)) / den
    half = z * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / den
    return (max(0.0, centre - half), min(1.0, centre + half))


def _cell(records: Sequence[dict[str, Any]], p: FovealParams) -> dict[str, Any]:
    n = len(records)
    k = sum(r["converged"] for r in records)
    kl = sum(r["converged_labelled"] for r in records)
    tails = np.array([r["max_tail_error_m"] for r in records])
    conv = [r["sq_err_m2"] for r in records if r["converged"]]
    ase = np.mean(conv, axis=0).T if conv else np.full((0, 0), math.nan)
    return {
        "converged_fraction": k / n if n else math.nan,
        "ci95": list(wilson_interval(k, n)),
        "runs": n,
        "converged_fraction_labelled": kl / n if n else math.nan,
        "converged_fraction_by_threshold_m": {
            f"{t:g}": float(np.mean(tails < t)) if n else math.nan for t in THRESHOLDS_M
        },
        "ase_m2": ase,  # (T, K): per target, per scan, over the converged runs
    }


def summarize_foveal(p: FovealParams, runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Tables 3-5 (converged fraction, Wilson 95 % interval, runs) and the ASE arrays."""
    table3 = {
        r: {q: _cell([x["table3"][r][q] for x in runs], p) for q in TABLE34_PROPOSALS}
        for r in RULES
    }
    table4 = {
        r: {q: _cell([x["table4"][r][q] for x in runs], p) for q in TABLE34_PROPOSALS}
        for r in RULES
    }
    table5 = {
        q: {c: _cell([x["table5"][q][c] for x in runs], p) for c in CONDITIONS}
        for q in TABLE5_PROPOSALS
    }
    status = {s.name.lower(): sum(x["status"][s.name.lower()] for x in runs) for s in StepStatus}
    return {
        "table3": table3,
        "table4": table4,
        "table5": table5,
        "step_status_counts": status,
        "initial_states": {"three": p.x0(3).tolist(), "two": p.x0(2).tolist()},
        "convergence": {
            "threshold_m": p.threshold_m,
            "last_steps": p.last_steps,
            "errors": "after the optimal assignment of estimates to true targets at each scan; "
            "converged_fraction_labelled keeps the initial labels",
        },
    }
