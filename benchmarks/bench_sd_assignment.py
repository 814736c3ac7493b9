"""S-D assignment: Lagrangian relaxation against the exact integer programme (scipy milp).

Run: ``PYTHONPATH=src python benchmarks/bench_sd_assignment.py [--quick] [--seed N] [--repeat R]
[--problems P] [--speed-problems Q]``.

1. Quality: seeded random problems with dummies (:func:`navtrack.tracking.assignment.
   random_sd_problem`), S = 3, 4, 5 lists of 5-10 elements; the relaxation's excess over the
   milp optimum (mean and worst, relative) and how often it is worse than greedy. The default
   seed (2026) differs from the test suite's (13), which chose the relaxation's defaults.
2. Speed: for each size, milp and the relaxation timed alternately on the same problems in this
   run, medians and their ratio, with the relaxation's excess over the optimum on those problems.
   ``--repeat R`` solves each problem R times with both (alternating) and takes the medians over
   all solves: one solve of the same problem varies by up to ~30 % on a shared machine.
   ``--problems P`` (default 10) and ``--speed-problems Q`` (default 3) set how many problems
   each size draws for the two parts; a mean excess over 10 problems has a standard error of
   0.1-0.3 %, over 40 about half that.

The exact solver is the usual set-partitioning programme (one 0/1 variable per tuple, one
equality row per real element) on ``scipy.optimize.milp`` with HiGHS' default options.

The machine load (``os.getloadavg``) is printed: under load both timings grow, their ratio less.
Wall and CPU time (``time.process_time``, this process: HiGHS and the relaxation both run in
it) are printed side by side; medians over the problems of each size.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from navtrack.tracking.assignment import (
    compile_kernels,
    random_sd_problem,
    sd_exact,
    sd_greedy,
    sd_lagrangian,
)

QUALITY = [
    ((5, 5, 5), 1.0),
    ((7, 8, 9), 1.0),
    ((10, 10, 10), 1.0),
    ((5, 6, 5, 6), 1.0),
    ((8, 8, 8, 8), 0.3),
    ((5, 5, 5, 5, 5), 0.3),
    ((7, 7, 7, 7, 7), 0.1),
]
SPEED = [((10, 10, 10), 1.0), ((10, 10, 10, 10), 0.3), ((8, 8, 8, 8, 8), 0.3)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="3 problems per size instead of 10")
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--repeat", type=int, default=1, help="timed solves per speed problem")
    ap.add_argument("--problems", type=int, default=10, help="quality problems per size")
    ap.add_argument("--speed-problems", type=int, default=3, help="speed problems per size")
    args = ap.parse_args()
    n = 3 if args.quick else args.problems
    rng = np.random.default_rng(args.seed)
    print(f"load average {os.getloadavg()}")
    compile_kernels()  # numba's one-off compilation (extra speed) is no part of any time
    print("size                 tuples  mean_excess  worst_excess  worse_than_greedy  gap_open")
    allx = []
    for sizes, density in QUALITY:
        ex_, worse, open_ = [], 0, 0
        for _ in range(n):
            p = random_sd_problem(sizes, rng, density)
            ex = sd_exact(p)
            lr = sd_lagrangian(p)
            if ex is None:
                continue
            ex_.append((lr.cost - ex.cost) / abs(ex.cost))
            worse += lr.cost > sd_greedy(p).cost + 1e-9
            open_ += lr.status != 0
        allx += ex_
        print(
            f"{sizes!s:20} {len(p.tuples):6d}  {np.mean(ex_):10.4%}  {np.max(ex_):11.4%}"
            f"  {worse:17d}  {open_:8d}"
        )
    print(f"all sizes: mean excess {np.mean(allx):.4%}, worst {np.max(allx):.4%}")
    print(
        "\nsize                 tuples  milp_s  lagrangian_s  ratio  milp_cpu_s  lagrangian_cpu_s"
        "  cpu_ratio  mean_excess  worst_excess"
    )
    for sizes, density in SPEED:
        t_ex, t_lr, c_ex, c_lr, ex_ = [], [], [], [], []
        for _ in range(args.speed_problems):
            p = random_sd_problem(sizes, rng, density)
            for _ in range(args.repeat):
                t0, c0 = time.perf_counter(), time.process_time()
                ex = sd_exact(p)
                t_ex.append(time.perf_counter() - t0)
                c_ex.append(time.process_time() - c0)
                t0, c0 = time.perf_counter(), time.process_time()
                lr = sd_lagrangian(p)
                t_lr.append(time.perf_counter() - t0)
                c_lr.append(time.process_time() - c0)
            if ex is not None:
                ex_.append((lr.cost - ex.cost) / abs(ex.cost))
        me, ml = statistics.median(t_ex), statistics.median(t_lr)
        ce, cl = statistics.median(c_ex), statistics.median(c_lr)
        print(
            f"{sizes!s:20} {len(p.tuples):6d}  {me:6.2f}  {ml:12.3f}  {me / ml:5.1f}x"
            f"  {ce:10.2f}  {cl:16.3f}  {ce / cl:8.1f}x  {np.mean(ex_):10.4%}  {np.max(ex_):11.4%}"
        )
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
