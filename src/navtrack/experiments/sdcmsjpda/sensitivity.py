"""Sensitivity of paper 3's conclusions to the scenario readings the paper leaves unstated.

Every tracker of the study runs under a handful of readings of the calibration grid
(:mod:`~navtrack.experiments.sdcmsjpda.calibration`), :data:`READINGS`, each applied on top
of the study's parameters, ``sensitivity_runs`` Monte Carlo runs each through the experiment
runner (checkpoints in ``OUT/sensitivity/<reading>/``). The study's own reading enters with
its first ``sensitivity_runs`` runs, so every row of the table has the same run count. The
table in ``tables.md`` gives, per reading and tracker, divergences and mean RMS position error
per ``P_D``, and per reading whether the paper's two claims (SD-CMSJPDA diverges less and has
the lower RMS error than sequential MSJPDA) hold.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from navtrack.experiments.contract import ExperimentContext
from navtrack.experiments.runner import run_monte_carlo
from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams, paper3_run
from navtrack.experiments.sdcmsjpda.summary import summarize_runs

__all__ = ["READINGS", "compact", "run_readings", "sensitivity_markdown"]

#: The other readings (label, fields set on the study's parameters), from the calibration grid
#: (docs/multisensor.md): sequential MSJPDA's divergences of 50 runs there in the comments.
READINGS: tuple[tuple[str, dict[str, Any]], ...] = (
    # 0 / 0 / 0: the default before the calibration
    ("P0 300 m, 30 m/s", {"init_sigma_pos_m": 300.0, "init_sigma_vel_mps": 30.0}),
    # 2 / 3 / 6
    ("sigma_a 5 m/s2", {"accel_sigma_mps2": 5.0}),
    # 5 / 6 / 5 (step 2 of the calibration)
    ("m 3.6 per gate", {"clutter_rate": 3.6}),
    # 9 / 6 / 11: the most divergences at P_D 0.58 of the grid's 2 km rows
    ("P_G 0.95, sigma_a 5 m/s2", {"gate_probability": 0.95, "accel_sigma_mps2": 5.0}),
    # 3 / 5 / 5: the other clutter reading, 1.8 per sensor and scan in +-6 sigma boxes
    ("box clutter, P_G 0.95", {"clutter_model": "box", "gate_probability": 0.95}),
)
STUDY_LABEL = "study (closest reading)"


def compact(summary: dict[str, Any]) -> dict[str, dict[str, dict[str, float]]]:
    """Per ``P_D`` and tracker of a :func:`summarize_runs` result: ``diverged``, ``runs``,
    ``rms_pos_m``, ``rms_vel_mps``."""
    keys = ("diverged", "runs", "rms_pos_m", "rms_vel_mps")
    return {
        pd: {alg: {k: row[k] for k in keys} for alg, row in per.items()}
        for pd, per in summary["by_pd"].items()
    }


def _run(index: int, rng: np.random.Generator, params: SdCmsjpdaParams) -> dict[str, Any]:
    return paper3_run(params, rng)


def run_readings(params: SdCmsjpdaParams, context: ExperimentContext) -> list[dict[str, Any]]:
    """Every reading of :data:`READINGS` on ``params``: ``{"label", "settings", "by_pd"}``
    (:func:`compact`), ``params.sensitivity_runs`` runs each."""
    parallel = context.workers > 1
    out = []
    for i, (label, settings) in enumerate(context.track(READINGS, "sensitivity")):
        reading = dataclasses.replace(params, **settings)
        mc = run_monte_carlo(
            _run,
            params.sensitivity_runs,
            context.seed,
            reading,
            name=f"sdcmsjpda-sensitivity-{i}",
            checkpoint_dir=context.out_dir / "sensitivity" / f"reading{i}",
            workers=context.workers if parallel else None,
            backend="auto" if parallel else "loop",
            progress=False,
        )
        by_pd = compact(summarize_runs(reading, mc.results))
        out.append({"label": label, "settings": settings, "by_pd": by_pd})
    return out


def _verdict(per: dict[str, dict[str, dict[str, float]]], pds: Sequence[str]) -> tuple[str, str]:
    """Whether SD-CMSJPDA diverges less than sequential (summed over P_D) and whether its RMS
    error is lower at every P_D: ``("yes"/"no"/"equal", "yes"/"no")`` with the numbers."""
    seq = sum(per[p]["sequential"]["diverged"] for p in pds)
    sd = sum(per[p]["sdcmsjpda"]["diverged"] for p in pds)
    div = "equal" if sd == seq else ("yes" if sd < seq else "no")
    ratios = [per[p]["sdcmsjpda"]["rms_pos_m"] / per[p]["sequential"]["rms_pos_m"] for p in pds]
    lower = "yes" if all(r < 1 for r in ratios) else "no"
    return (
        f"{div} ({sd} vs {seq})",
        f"{lower} (x {' / '.join(f'{r:.2f}' for r in ratios)})",
    )


def sensitivity_markdown(study: dict[str, Any], readings: Sequence[dict[str, Any]]) -> list[str]:
    """The sensitivity tables: ``study`` is the study's first runs (:func:`compact`),
    ``readings`` the result of :func:`run_readings`."""
    rows = [{"label": STUDY_LABEL, "by_pd": study}, *readings]
    pds = list(study)
    algs = list(study[pds[0]])
    runs = study[pds[0]][algs[0]]["runs"]
    lines = [
        f"## Sensitivity: each reading x each tracker ({runs} runs per reading)",
        "",
        "Readings of the calibration grid (docs/multisensor.md), each on top of the study's "
        f"parameters; the study's row is its first {runs} runs. Divergences of {runs} runs and "
        "mean RMS position error, m (converged runs; '-' when all diverged), per P_D "
        f"{' / '.join(pds)}.",
        "",
        "| reading | tracker | divergences | RMS position m |",
        "|---|---|---|---|",
    ]
    for row in rows:
        for alg in algs:
            div = " / ".join(str(row["by_pd"][p][alg]["diverged"]) for p in pds)
            rms = " / ".join(_num(row["by_pd"][p][alg]["rms_pos_m"]) for p in pds)
            lines.append(f"| {row['label']} | {alg} | {div} | {rms} |")
    if {"sequential", "sdcmsjpda"} <= set(algs):
        lines += [
            "",
            "Which of the paper's claims hold under each reading (sdcmsjpda against sequential; "
            "RMS: ratio sdcmsjpda / sequential per P_D):",
            "",
            "| reading | fewer divergences (sum over P_D) | lower RMS at every P_D |",
            "|---|---|---|",
        ]
        for row in rows:
            div, rms = _verdict(row["by_pd"], pds)
            lines.append(f"| {row['label']} | {div} | {rms} |")
    return lines


def _num(v: float) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.0f}"
