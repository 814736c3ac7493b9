"""Fusion trackers: CPU ms per step on the paper-3 scenario, this checkout against a git revision.

Run: ``PYTHONPATH=src python benchmarks/bench_fusion.py [--baseline REV] [--repeat 5]
[--runs 2] [--clutter gate|box] [--algorithms a,b,...] [--no-numba-too]``.

The scans (paper-3 scenario, :mod:`navtrack.experiments.sdcmsjpda.scenario`, ``--runs`` scan
sets per P_D = 0.97, 0.76, 0.58, seed ``--seed``) are simulated once by this checkout and
written to a temporary file. One worker process per code tree loads them: this checkout's
``src`` and, with ``--baseline REV``, the ``src`` of revision ``REV`` (``git archive``); with
``--no-numba-too`` also this checkout with numba disabled (its NumPy paths). After
one untimed warm-up pass per tracker, the workers run each tracker on each scan set in turn,
the two trees alternating on every scan set (order swapped every time), and report
``FusionResult.ms_per_step`` (CPU time of the fusion step, ``time.thread_time``, as the study's
``ms_per_step``).

Printed: the load average before each repeat; per tracker the median over repeats and scan
sets of each tree's ms per step and the median of the paired ratios (baseline / this checkout,
one pair per scan set and repeat); SD-CMSJPDA over sequential
MSJPDA in this checkout; and the largest difference between the two trees' posterior position
estimates over all steps, targets and scan sets, in units of the posterior's standard deviation
(``|Δx| / sqrt(P_xx)`` and the same for y), which shows whether a change moved the estimates.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_ALGORITHMS = "sequential,parallel,sdcmsjpda,sd_gnn,sdcmsjpda_fused"


def make_scans(path: Path, runs: int, clutter: str, seed: int) -> None:
    """Simulate the scan sets and their initial estimates into ``path`` (npz)."""
    # navtrack is imported here and in worker(): the tree it comes from is chosen per process
    from navtrack.experiments.sdcmsjpda.scenario import (
        SdCmsjpdaParams,
        clutter_density,
        simulate_scans,
    )
    from navtrack.tracking.models import constant_velocity
    from navtrack.tracking.simulate import simulate_truth

    params = SdCmsjpdaParams(clutter_model=clutter)  # type: ignore[arg-type]
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    x0 = np.array([params.x1, params.x2], dtype=float)
    truth = simulate_truth(motion, x0, params.n_steps, params.dt_s)
    rng = np.random.default_rng(seed)
    sig = np.array([params.init_sigma_pos_m, params.init_sigma_vel_mps] * 2)
    out: dict[str, np.ndarray] = {"lam": np.array(clutter_density(params, 2, truth))}
    i = 0
    for _ in range(runs):
        for pd in params.pd_values:
            sc = simulate_scans(params, truth, pd, rng)
            out[f"z{i}"], out[f"valid{i}"], out[f"t{i}"] = sc.z, sc.valid, sc.t_s
            out[f"x{i}"] = x0 + rng.standard_normal(x0.shape) * sig
            out[f"pd{i}"] = np.array(pd)
            i += 1
    np.savez(path, n=np.array(i), clutter=np.array(clutter), **out)


def worker(scans: Path) -> None:
    """Serve timing requests on stdin with the ``navtrack`` on ``sys.path``: ``ALG I`` runs
    tracker ALG on scan set I and prints its ms per step (keeping the posterior), ``save PATH``
    writes the posteriors kept so far."""
    # this process's tree (PYTHONPATH), not the one the script was started from
    from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams, sensors
    from navtrack.tracking.models import constant_velocity
    from navtrack.tracking.trackers.multisensor import FusionConfig, MultiScans, run_fusion

    d = np.load(scans)
    params = SdCmsjpdaParams()
    sens = sensors(params)
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    sp, sv = params.init_sigma_pos_m, params.init_sigma_vel_mps
    P0 = np.broadcast_to(np.diag([sp**2, sv**2, sp**2, sv**2]), (2, 4, 4))
    lam = tuple(float(v) for v in d["lam"])
    jobs = [
        (
            MultiScans(d[f"z{i}"], d[f"valid{i}"], d[f"t{i}"]),
            d[f"x{i}"],
            FusionConfig(
                (float(d[f"pd{i}"]),) * 3,
                lam,
                params.gate_probability,
                false_per_gate=params.clutter_rate,
            ),
        )
        for i in range(int(d["n"]))
    ]
    post: dict[str, np.ndarray] = {}
    for line in sys.stdin:
        cmd, arg = line.split()
        if cmd == "save":
            np.savez(arg, **post)
            print("ok", flush=True)
            continue
        sc, xi, cfg = jobs[int(arg)]
        res = run_fusion(cmd, sc, sens, motion, xi, P0, cfg, t0_s=0.0)  # type: ignore[arg-type]
        post[f"{cmd}_x{arg}"], post[f"{cmd}_P{arg}"] = res.x, res.P
        print(res.ms_per_step, flush=True)


def tree_of(rev: str, where: Path) -> Path:
    """The ``src`` folder of revision ``rev`` extracted under ``where``."""
    blob = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev, "src"], check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(blob)) as tar:
        tar.extractall(where, filter="data")
    return where / "src"


class Tree:
    """A worker process on one code tree."""

    def __init__(self, src: Path, scans: Path, no_numba: bool = False) -> None:
        env = {**os.environ, "PYTHONPATH": str(src)}
        if no_numba:
            env["NAVTRACK_NO_NUMBA"] = "1"
        cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", str(scans)]
        self.proc = subprocess.Popen(
            cmd, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        if self.proc.stdin is None or self.proc.stdout is None:
            raise RuntimeError("worker without pipes")
        self.stdin, self.stdout = self.proc.stdin, self.proc.stdout

    def ask(self, line: str) -> str:
        self.stdin.write(line + "\n")
        self.stdin.flush()
        return self.stdout.readline().strip()

    def close(self) -> None:
        self.stdin.close()
        self.proc.wait()


def max_sigma_difference(a: Path, b: Path) -> dict[str, float]:
    """Per tracker: largest ``|x_a - x_b| / σ_b`` of the positions over steps, targets, sets."""
    da, db = np.load(a), np.load(b)
    worst: dict[str, float] = {}
    for key in da.files:
        if "_x" not in key:
            continue
        alg = key.rsplit("_x", 1)[0]
        P = db[key.replace("_x", "_P")]
        dx = np.abs(da[key] - db[key])[..., [0, 2]]
        sig = np.sqrt(np.stack([P[..., 0, 0], P[..., 2, 2]], axis=-1))
        worst[alg] = max(worst.get(alg, 0.0), float(np.nanmax(dx / sig)))
    return worst


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--baseline", help="git revision to compare against (e.g. main)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--runs", type=int, default=2, help="scan sets per P_D")
    ap.add_argument("--clutter", default="gate", choices=["gate", "box"])
    ap.add_argument("--algorithms", default=DEFAULT_ALGORITHMS)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument(
        "--no-numba-too",
        action="store_true",
        help="also run this checkout without numba (NAVTRACK_NO_NUMBA=1): the NumPy paths",
    )
    ap.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    algorithms = args.algorithms.split(",")
    if args.worker is not None:
        worker(args.worker)
        return
    with tempfile.TemporaryDirectory() as tmp_:
        tmp = Path(tmp_)
        scans = tmp / "scans.npz"
        make_scans(scans, args.runs, args.clutter, args.seed)
        srcs = {"this": ROOT / "src"}
        if args.baseline:
            srcs[args.baseline] = tree_of(args.baseline, tmp / "baseline")
        trees = {name: Tree(src, scans) for name, src in srcs.items()}
        if args.no_numba_too:
            trees["numpy"] = Tree(ROOT / "src", scans, no_numba=True)
        n_sets = 3 * args.runs
        print(
            f"paper-3 scenario, {args.clutter} clutter, {args.runs} scan sets per P_D (seed "
            f"{args.seed}), 140 steps each; CPU ms per fusion step; the trees alternate on "
            "each scan set (order swapped every time)"
        )
        for tree in trees.values():  # warm-up: first calls fill caches and import lazily
            for a in algorithms:
                tree.ask(f"{a} 0")
        times: dict[str, dict[str, list[float]]] = {t: {a: [] for a in algorithms} for t in trees}
        names = list(trees)
        flip = 0
        for r in range(args.repeat):
            print(f"repeat {r + 1}: load average {os.getloadavg()}")
            for a in algorithms:
                for i in range(n_sets):
                    flip += 1
                    for name in names if flip % 2 else names[::-1]:
                        times[name][a].append(float(trees[name].ask(f"{a} {i}")))
            print(
                "  "
                + "; ".join(
                    f"{name}: "
                    + ", ".join(f"{a} {np.mean(times[name][a][-n_sets:]):.2f}" for a in algorithms)
                    for name in names
                )
            )
        for name, tree in trees.items():
            tree.ask(f"save {tmp / f'post_{name}.npz'}")
            tree.close()
        med = {t: {a: statistics.median(v) for a, v in times[t].items()} for t in trees}
        head = f"{'tracker':20s} {'this ms':>8s}"
        if args.no_numba_too:
            head += f" {'no numba ms':>12s} {'ratio':>6s} {'max |dx|/sigma':>15s}"
            diff_np = max_sigma_difference(tmp / "post_this.npz", tmp / "post_numpy.npz")
        if args.baseline:
            head += f" {args.baseline + ' ms':>12s} {'ratio':>6s} {'max |dx|/sigma':>15s}"
            diff = max_sigma_difference(tmp / "post_this.npz", tmp / f"post_{args.baseline}.npz")
        print(f"\nmedians over {args.repeat} repeats x {n_sets} scan sets (ratio: median of the")
        print(f"paired ratios, other / this)\n{head}")
        for a in algorithms:
            line = f"{a:20s} {med['this'][a]:8.2f}"
            if args.no_numba_too:
                pairs = np.array(times["numpy"][a]) / np.array(times["this"][a])
                line += f" {med['numpy'][a]:12.2f} {np.median(pairs):6.2f} {diff_np[a]:15.2e}"
            if args.baseline:
                b = med[args.baseline][a]
                pairs = np.array(times[args.baseline][a]) / np.array(times["this"][a])
                line += f" {b:12.2f} {np.median(pairs):6.2f} {diff[a]:15.2e}"
            print(line)
        if {"sequential", "sdcmsjpda"} <= set(algorithms):
            for tree in ("this", "numpy") if args.no_numba_too else ("this",):
                ratio = med[tree]["sdcmsjpda"] / med[tree]["sequential"]
                print(f"sdcmsjpda / sequential ({tree}): {ratio:.2f} [paper 28.2 / 25.1 = 1.12]")
        print(f"load average at the end {os.getloadavg()}")


if __name__ == "__main__":
    main()
