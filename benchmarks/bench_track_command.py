"""Whole-command time of ``navtrack track`` on the shared tracking files, with its stage split.

Run: ``NAVTRACK_SHARED_DATA=/work/shared/data PYTHONPATH=src python
benchmarks/bench_track_command.py [--reps 3]``.

Times what a user runs with no tuning flags, ``python -m navtrack track FILE --format ais|opensky
[--associator jpda]`` (the ``auto`` model, progress bar on stderr, no ``--out``), as whole
processes: wall clock and CPU time (user + system) of the child, median over ``--reps`` runs,
the four cases alternating in every repeat. The stage split (read / auto tune / track) is the
one the command prints in its summary; "start-up" is the median wall time of ``python -m
navtrack track --help`` (interpreter and CLI imports), measured in the same rounds. The bars
of issue 11 are 10 s (GNN) and 20 s (JPDA) per file.

No ratio is printed: no peer library runs this pipeline (model tuned from the data, IMM,
scan windows, track management) on these files; ``bench_tracking.py`` compares the JPDA
kernels with Stone Soup on simulated scans.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"
FILES = (("SolentAIS_20160112_130211.csv", "ais"), ("OpenSky_Plane_States.csv", "opensky"))
BARS_S = {"gnn": 10.0, "jpda": 20.0}
STAGES_KEY = "time read / tune / track (s)"


def run(cmd: list[str]) -> tuple[float, float, str]:
    """Wall and CPU time (s) of one child process, and its standard output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    clock = time.perf_counter()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    wall = time.perf_counter() - clock
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, out


def stages(summary: str) -> list[float]:
    """Read, tune and track seconds from the command's summary."""
    for line in summary.splitlines():
        if line.startswith(STAGES_KEY):
            return [float(v) for v in line[len(STAGES_KEY) :].split()]
    raise ValueError(f"no '{STAGES_KEY}' line in the summary")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args(argv)
    base = [sys.executable, "-m", "navtrack", "track"]
    cases = [
        (fname, fmt, assoc)
        for fname, fmt in FILES
        if (DATA / fname).exists()
        for assoc in ("gnn", "jpda")
    ]
    if not cases:
        print(f"no shared tracking files under {DATA} (set NAVTRACK_SHARED_DATA)")
        return 1
    wall: dict[tuple[str, str], list[float]] = {(f, s): [] for f, _, s in cases}
    cpu: dict[tuple[str, str], list[float]] = {(f, s): [] for f, _, s in cases}
    split: dict[tuple[str, str], list[list[float]]] = {(f, s): [] for f, _, s in cases}
    startup: list[float] = []
    for _ in range(a.reps):
        startup.append(run([*base, "--help"])[0])
        for fname, fmt, assoc in cases:
            cmd = [*base, str(DATA / fname), "--format", fmt]
            cmd += ["--associator", "jpda"] if assoc == "jpda" else []
            w, c, out = run(cmd)
            wall[fname, assoc].append(w)
            cpu[fname, assoc].append(c)
            split[fname, assoc].append(stages(out))
    load = os.getloadavg()
    print(f"load average at the end: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; {a.reps} runs each")
    print(f"start-up (navtrack track --help): {statistics.median(startup):.2f} s wall")
    print(
        "| file | associator | wall (s) | CPU (s) | read / tune / track (s) | bar (s) |\n"
        "|---|---|---|---|---|---|"
    )
    for fname, _, assoc in cases:
        key = (fname, assoc)
        med = [statistics.median(v) for v in zip(*split[key], strict=True)]
        print(
            f"| {fname} | {assoc} | {statistics.median(wall[key]):.2f} "
            f"| {statistics.median(cpu[key]):.2f} | {med[0]:.2f} / {med[1]:.2f} / {med[2]:.2f} "
            f"| {BARS_S[assoc]:.0f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
