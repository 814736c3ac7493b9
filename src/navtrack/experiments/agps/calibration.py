"""Calibration of the AGPS simulation on the paper's baseline, Gauss–Newton.

The paper states none of its error model, its satellite geometry or how far its phone was from
the base station. Gauss–Newton on the square five-equation system has no parameter of its own,
so its printed results fix them, and Marquardt's are then predictions:

1. **Table I** (Gauss–Newton's 90/80/70/60/50 % error percentiles and mean at 2 min, 11 assumed
   heights: 66 numbers) chooses the white pseudorange noise ``sigma_noise_m``, the elevation
   mask ``elmask_deg`` and the geometry screen ``max_dop`` on a grid, by the root mean square
   of ``log(simulated / printed)`` over the 66 cells (:func:`table_i_misfit`).
2. **Table III** (Gauss–Newton 2.000 iterations at every height) bounds the cell radius, the
   only setting that changes Gauss–Newton's iterations (not its fixes): the first step from a
   far cell leaves a residual of curvature above ``epsilon`` and needs one more solve. The
   same fix sets are solved from every radius; the bound is the largest radius whose mean
   iteration count at the true height exceeds that of a cell at the truth (radius 0, the
   fewest) by at most :data:`ITERATION_EXCESS` (one fix in ten needing one more solve). The
   count cannot tell radii inside the bound apart; the default radius (500 m) lies inside it
   on every seed tried (``docs/agps.md``).

``python -m navtrack.experiments.agps.calibration [--runs N] [--seed S]`` runs both searches
and prints their tables; ``docs/agps.md`` records the result.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from navtrack.experiments.agps.simulation import (
    AgpsExperimentParams,
    fix_set_problem,
    solver_config,
)
from navtrack.experiments.agps.summary import PAPER_TABLE_I, error_statistics, height_key
from navtrack.gnss.agps import AgpsProblem, AgpsStatus, solve_agps

__all__ = [
    "GRID",
    "ITERATION_EXCESS",
    "RADII_M",
    "calibrate",
    "main",
    "solver_table",
    "table_i_misfit",
]

GRID: dict[str, tuple[float, ...]] = {
    "sigma_noise_m": (2.0, 2.5, 3.0, 3.5, 4.0, 5.0),
    "elmask_deg": (5.0, 15.0, 30.0),
    "max_dop": (300.0, 500.0, 700.0, 1000.0, math.inf),
}
"""The search grid of step 1."""

RADII_M: tuple[float, ...] = (0.0, 250.0, 500.0, 750.0, 1000.0, 2000.0, 5000.0)
"""The cell radii of step 2 (m)."""

ITERATION_EXCESS = 0.1
"""Step 2: the mean excess of Gauss–Newton's iterations over a cell at the truth that bounds
the cell radius."""


def solver_table(
    params: AgpsExperimentParams, runs: int, seed: int, solver: str = "gn"
) -> tuple[dict[str, dict[str, Any]], np.ndarray]:
    """A solver's statistics per assumed height at the first interval over ``runs`` fix sets
    drawn with ``seed`` (the fixes of the reproduction's first ``runs`` runs are not the same:
    those draw from per-run generators).

    Returns
    -------
    table : dict
        :func:`~navtrack.experiments.agps.summary.error_statistics` per height key.
    iterations : ndarray, shape (runs, heights)
        Linear solves of each fix.
    """

    rng = np.random.default_rng(seed)
    n_h = len(params.heights_m)
    parts, truths = [], []
    for _ in range(runs):
        problem, truth, _meta = fix_set_problem(params, rng)
        parts.append(problem)
        truths.append(truth)

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name)[:n_h] for p in parts])

    batch = AgpsProblem(
        t_gps_s=cat("t_gps_s"),
        sat_pos_m=cat("sat_pos_m"),
        y_m=cat("y_m"),
        height_m=cat("height_m"),
        start_xyz_m=cat("start_xyz_m"),
        usable=cat("usable"),
    )
    res = solve_agps(batch, solver, solver_config(params))  # type: ignore[arg-type]
    truth = np.repeat(np.asarray(truths), n_h, axis=0)
    ok = res.status == AgpsStatus.OK
    err = np.where(ok, np.linalg.norm(res.pos_m - truth, axis=1), np.nan).reshape(runs, n_h)
    its = res.iterations.reshape(runs, n_h)
    st = res.status.reshape(runs, n_h)
    table = {
        height_key(h): error_statistics(err[:, k], its[:, k], st[:, k])
        for k, h in enumerate(params.heights_m)
    }
    return table, its


def table_i_misfit(table: dict[str, dict[str, Any]]) -> float:
    """Root mean square of ``log(simulated / printed)`` over Table I's cells present in
    ``table`` (percentiles and mean per height); infinite when a cell has no fix."""
    logs = []
    for height, printed in PAPER_TABLE_I.items():
        row = table.get(height)
        if row is None:
            continue
        for key, value in printed.items():
            sim = row.get(key)
            if sim is None or not sim > 0.0:
                return math.inf
            logs.append(math.log(sim / value))
    return math.sqrt(sum(x * x for x in logs) / len(logs)) if logs else math.inf


def calibrate(
    base: AgpsExperimentParams,
    runs: int = 300,
    seed: int = 0,
    grid: dict[str, tuple[float, ...]] | None = None,
    radii_m: Sequence[float] = RADII_M,
) -> dict[str, Any]:
    """Both calibration steps (module docstring) from ``base``.

    Returns
    -------
    dict
        ``grid``: one row per grid point (its values, ``misfit``, Gauss–Newton's ``p50_m`` and
        ``mean_m`` at the true height), best first; ``best``: the chosen values;
        ``radii``: per radius the mean iterations at the true height, their excess over radius
        0 and its standard error; ``radius_bound_m``: the bound of step 2.
    """
    grid = GRID if grid is None else grid
    true_h = height_key(min(base.heights_m, key=lambda h: abs(h - base.site_llh[2])))
    rows = []
    for values in itertools.product(*grid.values()):
        params = dataclasses.replace(base, **dict(zip(grid, values, strict=True)))  # type: ignore[arg-type]
        table, _ = solver_table(params, runs, seed)
        rows.append({
            **dict(zip(grid, values, strict=True)),
            "misfit": table_i_misfit(table),
            "p50_m": table[true_h]["p50_m"],
            "mean_m": table[true_h]["mean_m"],
        })  # fmt: skip
    rows.sort(key=lambda r: r["misfit"])
    best = {k: rows[0][k] for k in grid}
    tuned = dataclasses.replace(base, **best)
    k_true = [height_key(h) for h in base.heights_m].index(true_h)
    radii = []
    reference = None
    for radius in sorted(radii_m):
        _, its = solver_table(dataclasses.replace(tuned, cell_radius_m=radius), runs, seed)
        col = its[:, k_true].astype(float)
        reference = col if reference is None else reference
        diff = col - reference
        radii.append({
            "cell_radius_m": radius,
            "mean_iterations": float(col.mean()),
            "excess": float(diff.mean()),
            "excess_standard_error": float(diff.std(ddof=1) / math.sqrt(diff.size)),
        })  # fmt: skip
    bound = max(r["cell_radius_m"] for r in radii if r["excess"] <= ITERATION_EXCESS)
    return {"grid": rows, "best": best, "radii": radii, "radius_bound_m": bound}


def main(argv: Sequence[str] | None = None) -> int:
    """Run :func:`calibrate` from the current defaults and print its tables."""
    parser = argparse.ArgumentParser(
        prog="python -m navtrack.experiments.agps.calibration",
        description="Calibrate the AGPS simulation on Gauss-Newton's Tables I and III.",
    )
    parser.add_argument("--runs", type=int, default=300, help="fix sets per grid point")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    out = calibrate(AgpsExperimentParams(real_data=False), args.runs, args.seed)
    print("| sigma_noise_m | elmask_deg | max_dop | misfit | GN p50 56 m | GN mean 56 m |")
    print("|---|---|---|---|---|---|")
    for r in out["grid"][:10]:
        print(f"| {r['sigma_noise_m']:g} | {r['elmask_deg']:g} | {r['max_dop']:g} | "
              f"{r['misfit']:.3f} | {r['p50_m']:.0f} | {r['mean_m']:.0f} |")  # fmt: skip
    print(f"\nbest: {out['best']}  (printed p50 288, mean 494 at 56 m)\n")
    print("| cell radius m | GN mean iterations (56 m) | excess over 0 m | standard error |")
    print("|---|---|---|---|")
    for r in out["radii"]:
        print(f"| {r['cell_radius_m']:g} | {r['mean_iterations']:.3f} | {r['excess']:.3f} | "
              f"{r['excess_standard_error']:.3f} |")  # fmt: skip
    print(f"\ncell radius bound: {out['radius_bound_m']:g} m (paper: 2.000 iterations)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
