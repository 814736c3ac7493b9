"""k-best S-D assignment: Murty cells solved by milp against cells solved by relaxation.

Run: ``PYTHONPATH=src python benchmarks/bench_sd_kbest.py [--problems N] [--k K] [--seed N]``.

On seeded random problems with dummies (:func:`navtrack.tracking.assignment.random_sd_problem`),
``sd_kbest`` runs with every cell solved exactly (``method="exact"`` with no size limit: scipy
milp, HiGHS' default options) and with every cell solved by the Lagrangian relaxation
(``method="lagrangian"``), alternately on the same problems in this run (which goes first
alternates too). Where a problem has more tuples than ``max_exact_tuples`` (5000), the default
(``method="exact"``: large cells relaxed, small ones by milp) is timed as well.

Printed per size: median CPU and wall seconds of each, the ratio milp / relaxed, and per rank
the relaxed cost minus the exact k-th best cost (mean and worst over the problems; 0 = the
same solution cost), the ranks the relaxed run proves, and its cells (examined / empty). The
load average is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from navtrack.tracking.assignment import (
    SdKBest,
    SdProblem,
    compile_kernels,
    random_sd_problem,
    sd_kbest,
)

SIZES = [((10, 10, 10, 10), 0.3), ((8, 8, 8, 8, 8), 0.3)]
QUICK = [((6, 6, 6, 6), 0.3), ((5, 5, 5, 5, 5), 0.2)]
MAX_EXACT = 5000


def timed(problem: SdProblem, k: int, variant: str) -> tuple[SdKBest, float, float]:
    """(result, CPU s, wall s) of one k-best run."""
    kw: dict[str, object] = {
        "milp": {"method": "exact", "max_exact_tuples": 10**9},
        "relaxed": {"method": "lagrangian"},
        "default": {"method": "exact", "max_exact_tuples": MAX_EXACT},
    }[variant]
    c0, w0 = time.process_time(), time.perf_counter()
    res = sd_kbest(problem, k, **kw)  # type: ignore[arg-type]
    return res, time.process_time() - c0, time.perf_counter() - w0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--problems", type=int, default=3, help="problems per size")
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    args = ap.parse_args()
    compile_kernels()  # numba's one-off compilation (extra speed) is no part of any time
    rng = np.random.default_rng(args.seed)
    print(f"load average {os.getloadavg()}")
    for sizes, density in QUICK if args.quick else SIZES:
        cpu: dict[str, list[float]] = {"milp": [], "relaxed": [], "default": []}
        wall: dict[str, list[float]] = {"milp": [], "relaxed": [], "default": []}
        diff, diff_default, proven, cells, empty, best = [], [], [], [], [], []
        for i in range(args.problems):
            p = random_sd_problem(sizes, rng, density)
            variants = ["milp", "relaxed"] if i % 2 == 0 else ["relaxed", "milp"]
            if len(p.tuples) > MAX_EXACT:
                variants.append("default")
            out = {}
            for v in variants:
                out[v], c, w = timed(p, args.k, v)
                cpu[v].append(c)
                wall[v].append(w)
            exact, relaxed = out["milp"], out["relaxed"]
            assert exact.proven.all()  # every cell exact: the true k best
            diff.append(relaxed.cost - exact.cost)
            best.append(exact.cost)
            if "default" in out:
                diff_default.append(out["default"].cost - exact.cost)
            proven.append(int(relaxed.proven.sum()))
            cells.append(relaxed.cells)
            empty.append(relaxed.cells_infeasible)
        d = np.array(diff)
        print(f"\n{sizes} density {density}: {len(p.tuples)} tuples (last problem), k = {args.k}")
        for v in ("milp", "relaxed", "default"):
            if cpu[v]:
                print(
                    f"  {v:8s} CPU {statistics.median(cpu[v]):7.2f} s  wall "
                    f"{statistics.median(wall[v]):7.2f} s  (median of {len(cpu[v])})"
                )
        ratio = statistics.median(cpu["milp"]) / statistics.median(cpu["relaxed"])
        print(f"  ratio milp / relaxed (CPU): {ratio:.2f}x")
        print("  rank                  " + " ".join(f"{j + 1:7d}" for j in range(d.shape[1])))
        print("  relaxed - exact, mean " + " ".join(f"{x:7.3f}" for x in d.mean(axis=0)))
        print("  relaxed - exact, max  " + " ".join(f"{x:7.3f}" for x in d.max(axis=0)))
        if diff_default:
            dd = np.array(diff_default)
            print("  default - exact, mean " + " ".join(f"{x:7.3f}" for x in dd.mean(axis=0)))
        b = np.array(best)
        print(
            f"  exact costs, mean: best {b[:, 0].mean():.3f}, k-th {b[:, -1].mean():.3f}; "
            f"relaxed: ranks proven {proven}, cells {cells} (empty {empty})"
        )
    print(f"\nload average {os.getloadavg()}")


if __name__ == "__main__":
    main()
