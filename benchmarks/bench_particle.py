"""Speed of the paper-4 JMPD particle filter on one configuration (no peer ratio).

Run: ``PYTHONPATH=src python benchmarks/bench_particle.py [--runs 100] [--batch 50]
[--proposal ip_jpda] [--rule wo] [--clutter]``.

Times ``--runs`` Monte Carlo runs of one configuration of Tables 3/4 (three targets, 400
particles, 30 scans, the reproduction's defaults of
:class:`navtrack.experiments.foveal.FovealParams`), ``--batch`` runs vectorised side by side
(``track_foveal`` on a ``(batch, K + 1, T, n)`` truth), and prints the seconds per run and the
time of 1000 runs, in wall time and in CPU time of the process (the CPU time is what a quiet
machine would take with single-threaded BLAS). No fair peer exists (no public implementation
of the JMPD with independent-partition proposals; a per-particle Python loop is not a peer), so
no ratio is printed. Quote the machine load with the numbers.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from navtrack.experiments.foveal import FovealParams, converged, simulate_truth, track_foveal
from navtrack.tracking.models import constant_velocity


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--batch", type=int, default=50)
    ap.add_argument(
        "--proposal", default="ip_jpda", choices=["ip_jpda", "kp", "ip_gnn", "ip_gnn_joint"]
    )
    ap.add_argument("--rule", default="wo", choices=["so", "to", "wo"])
    ap.add_argument("--clutter", action="store_true", help="Pd = 0.9, λV = 0.5 (else Pd = 1)")
    args = ap.parse_args()
    p = FovealParams()
    cfg = p.config(args.proposal)
    sensor = p.sensor("clutter" if args.clutter else "no_clutter")
    rng = np.random.default_rng(0)
    motion = constant_velocity(1, p.truth_q, p.noise)
    truths = np.stack(
        [simulate_truth(p.x0(3), motion, p.dt_s, p.steps, rng) for _ in range(args.runs)]
    )
    ok = []
    c0 = time.process_time()
    t0 = time.perf_counter()
    for s in range(0, args.runs, args.batch):
        batch = truths[s : s + args.batch]
        tr = track_foveal(batch, [args.rule] * len(batch), sensor, cfg, p.P0, rng)
        ok.append(converged(tr.position_error_m, p.threshold_m, p.last_steps))
    dt = time.perf_counter() - t0
    cpu = time.process_time() - c0
    load = os.getloadavg()[0]
    print(
        f"{args.proposal} {args.rule} {'clutter' if args.clutter else 'no clutter'}: "
        f"{args.runs} runs x {p.steps} scans x {p.n_particles} particles x 3 targets, batch "
        f"{args.batch}: {dt:.1f} s, {dt / args.runs:.3f} s/run, "
        f"1000 runs {1000 * dt / args.runs:.0f} s "
        f"(load average {load:.1f}); CPU {cpu:.1f} s, "
        f"1000 runs {1000 * cpu / args.runs:.0f} s CPU; "
        f"converged (labelled) {np.mean(np.concatenate(ok)):.2f}"
    )


if __name__ == "__main__":
    main()
