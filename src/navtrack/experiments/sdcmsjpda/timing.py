"""Time per fusion step of SD-CMSJPDA relative to sequential MSJPDA, as paper 3 reports it.

The paper gives 28.2 ms (SD-CMSJPDA) against 25.1 ms (sequential MSJPDA) per step on a 2.0 GHz
PC, a ratio of 1.12; only the ratio is compared here. :func:`time_ratios` simulates a few scan
sets of the scenario, then runs the trackers on each set in turn, their order rotated from set
to set, and returns each tracker's median CPU ms per step (``FusionResult.ms_per_step``) and the
median of its paired ratios to sequential MSJPDA on the same scan set. :func:`both_paths` does
this in this process (numba as installed) and in a child process with ``NAVTRACK_NO_NUMBA=1``
(the NumPy paths).

``python -m navtrack.experiments.sdcmsjpda.timing [--scan-sets N] [--repeat N] [--seed S]``
prints the result of this process as JSON (``both_paths`` calls it so);
``benchmarks/bench_sdcmsjpda_ratio.py`` prints both paths as a table.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from navtrack._numba import HAVE_NUMBA
from navtrack.experiments.parameters import apply_parameters
from navtrack.experiments.sdcmsjpda.scenario import (
    SdCmsjpdaParams,
    clutter_density,
    sensors,
    simulate_scans,
)
from navtrack.tracking.models import constant_velocity
from navtrack.tracking.simulate import simulate_truth
from navtrack.tracking.trackers.multisensor import Algorithm, FusionConfig, run_fusion

__all__ = ["PAPER_RATIO", "TIMED", "both_paths", "main", "ratio_markdown", "time_ratios"]

#: Paper 3, section 4: SD-CMSJPDA / sequential MSJPDA time per step (28.2 / 25.1 ms).
PAPER_RATIO = 28.2 / 25.1
#: The trackers timed: the baseline first (the ratios are to it).
TIMED: tuple[Algorithm, ...] = ("sequential", "sdcmsjpda", "sdcmsjpda_fused")


def time_ratios(
    params: SdCmsjpdaParams, scan_sets: int = 2, repeat: int = 3, seed: int = 7
) -> dict[str, Any]:
    """Median CPU ms per step of each tracker of :data:`TIMED` and the median of its paired
    ratios to sequential MSJPDA, over ``repeat`` passes of ``scan_sets`` scan sets per ``P_D``
    (one untimed warm-up run per tracker first)."""
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    x0 = np.array([params.x1, params.x2], dtype=float)
    truth = simulate_truth(motion, x0, params.n_steps, params.dt_s)
    sens = sensors(params)
    lam = clutter_density(params, 2, truth)
    sp, sv = params.init_sigma_pos_m, params.init_sigma_vel_mps
    P0 = np.broadcast_to(np.diag([sp**2, sv**2, sp**2, sv**2]), (2, 4, 4))
    rng = np.random.default_rng(seed)
    jobs = []
    for _ in range(scan_sets):
        for pd in params.pd_values:
            scans = simulate_scans(params, truth, pd, rng)
            xi = x0 + rng.standard_normal(x0.shape) * np.array([sp, sv, sp, sv])
            cfg = FusionConfig(
                (pd,) * len(sens), lam, params.gate_probability, false_per_gate=params.clutter_rate
            )
            jobs.append((scans, xi, cfg))

    def ms(alg: Algorithm, job: int) -> float:
        scans, xi, cfg = jobs[job]
        return run_fusion(alg, scans, sens, motion, xi, P0, cfg, t0_s=0.0).ms_per_step

    for alg in TIMED:
        ms(alg, 0)
    times: dict[str, list[float]] = {a: [] for a in TIMED}
    turn = 0
    for _ in range(repeat):
        for job in range(len(jobs)):
            order = TIMED[turn % len(TIMED) :] + TIMED[: turn % len(TIMED)]
            turn += 1
            for alg in order:
                times[alg].append(ms(alg, job))
    base = np.array(times[TIMED[0]])
    return {
        "numba": HAVE_NUMBA,
        "pairs": int(base.size),
        "ms_per_step": {a: float(np.median(v)) for a, v in times.items()},
        "ratio_to_sequential": {
            a: float(np.median(np.array(v) / base)) for a, v in times.items() if a != TIMED[0]
        },
    }


def both_paths(
    params: SdCmsjpdaParams, scan_sets: int = 2, repeat: int = 3, seed: int = 7
) -> dict[str, Any]:
    """:func:`time_ratios` here (``"this_process"``) and in a child process without numba
    (``"numpy"``), one after the other; ``paper_ratio`` beside them."""
    here = time_ratios(params, scan_sets, repeat, seed)
    env = {**os.environ, "NAVTRACK_NO_NUMBA": "1"}
    fields = json.dumps(dataclasses.asdict(params))
    cmd = [sys.executable, "-m", __name__, "--scan-sets", str(scan_sets), "--repeat",
           str(repeat), "--seed", str(seed), "--params", fields]  # fmt: skip
    child = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return {"this_process": here, "numpy": json.loads(child.stdout), "paper_ratio": PAPER_RATIO}


def ratio_markdown(timing: dict[str, Any]) -> list[str]:
    """Markdown lines: ms per step and ratio to sequential per path, the paper's beside."""
    lines = [
        "| path | " + " | ".join(f"{a} ms" for a in TIMED) + " | "
        + " | ".join(f"{a} / sequential" for a in TIMED[1:]) + " |",
        "|---|" + "---|" * (2 * len(TIMED) - 1),
    ]  # fmt: skip
    for name in ("this_process", "numpy"):
        t = timing[name]
        label = "numba" if t["numba"] else "NumPy (no numba)"
        cells = [f"{t['ms_per_step'][a]:.2f}" for a in TIMED]
        cells += [f"{t['ratio_to_sequential'][a]:.2f}" for a in TIMED[1:]]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines.append(f"| paper (2.0 GHz PC) | 25.1 | 28.2 | - | {timing['paper_ratio']:.2f} | - |")
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: :func:`time_ratios` of this process as JSON on stdout."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scan-sets", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--params", default="{}", help="SdCmsjpdaParams fields as JSON")
    args = ap.parse_args(argv)
    params = apply_parameters(SdCmsjpdaParams(), json.loads(args.params), experiment="sdcmsjpda")
    print(json.dumps(time_ratios(params, args.scan_sets, args.repeat, args.seed)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
