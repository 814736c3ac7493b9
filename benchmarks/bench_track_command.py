"""Whole-command time of ``navtrack track`` on the shared tracking files, with its stage split.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_command.py [--reps 3] [--baseline DIR]``.

Times what a user runs with no tuning flags, ``python -m navtrack track FILE --format ais|opensky
[--associator jpda]`` (the ``auto`` model, progress bar on stderr, no ``--out``), as whole
processes: wall clock and CPU time (user + system) of the child, median over ``--reps`` runs,
the cases alternating in every repeat. The stage split (read / auto tune / track) is the one
the command prints in its summary; "start-up" is the median wall time of ``python -m navtrack
track --help`` (interpreter and CLI imports), measured in the same rounds. The bars of issue
11 are 10 s (GNN) and 20 s (JPDA) per file. One untimed run comes first (file cache).

``--baseline DIR`` also runs every case with ``PYTHONPATH=DIR`` (an earlier release's ``src``,
e.g. a checkout of the previous main), alternating with the default in the same rounds; the
ratios of its CPU and wall medians to the default's are printed. No peer ratio is printed: no
peer library runs this pipeline (model tuned from the data, IMM, scan windows, track
management) on these files; ``bench_tracking.py`` compares the JPDA kernels with Stone Soup on
simulated scans.
"""

from __future__ import annotations

import argparse
import os
import re
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


def run(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float, str]:
    """Wall and CPU time (s) of one child process, and its standard output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    clock = time.perf_counter()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout
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
    ap.add_argument("--baseline", type=Path, help="also time this src directory (PYTHONPATH)")
    a = ap.parse_args(argv)
    base = [sys.executable, "-m", "navtrack", "track"]
    paths = {"default": dict(os.environ)}
    if a.baseline is not None:
        paths["baseline"] = {**os.environ, "PYTHONPATH": str(a.baseline.resolve())}
    cases = [
        (fname, fmt, assoc, path)
        for fname, fmt in FILES
        if (DATA / fname).exists()
        for assoc in ("gnn", "jpda")
        for path in paths
    ]
    if not cases:
        print(f"no shared tracking files under {DATA} (set NAVTRACK_SHARED_DATA)")
        return 1
    keys = [(f, s, p) for f, _, s, p in cases]
    wall: dict[tuple[str, str, str], list[float]] = {k: [] for k in keys}
    cpu: dict[tuple[str, str, str], list[float]] = {k: [] for k in keys}
    split: dict[tuple[str, str, str], list[list[float]]] = {k: [] for k in keys}
    mota: dict[tuple[str, str, str], str] = {}
    startup: list[float] = []
    fname, fmt = cases[0][:2]
    run([*base, str(DATA / fname), "--format", fmt])  # untimed: files in the page cache
    load0 = os.getloadavg()
    for _ in range(a.reps):
        startup.append(run([*base, "--help"])[0])
        for fname, fmt, assoc, path in cases:
            cmd = [*base, str(DATA / fname), "--format", fmt]
            cmd += ["--associator", "jpda"] if assoc == "jpda" else []
            w, c, out = run(cmd, paths[path])
            key = (fname, assoc, path)
            wall[key].append(w)
            cpu[key].append(c)
            split[key].append(stages(out))
            mota[key] = summary_value(out, "MOTA") + " / " + summary_value(out, "HOTA").split()[0]
            mota[key] += " / " + ":".join(summary_value(out, "ids / confirmed").split(" / ")[::-1])
    load1 = os.getloadavg()
    print(
        f"load average at the start: {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f}, "
        f"at the end: {load1[0]:.1f} {load1[1]:.1f} {load1[2]:.1f}; {a.reps} runs each "
        f"(2 cores)"
    )
    print(f"start-up (navtrack track --help): {statistics.median(startup):.2f} s wall")
    print(
        "| file | associator | path | wall (s) | CPU (s) | read / tune / track (s) "
        "| MOTA / HOTA / tracks:ids | bar (s) |\n|---|---|---|---|---|---|---|---|"
    )
    for key in keys:
        fname, assoc, path = key
        med = [statistics.median(v) for v in zip(*split[key], strict=True)]
        print(
            f"| {fname} | {assoc} | {path} | {statistics.median(wall[key]):.2f} "
            f"| {statistics.median(cpu[key]):.2f} | {med[0]:.2f} / {med[1]:.2f} / {med[2]:.2f} "
            f"| {mota[key]} | {BARS_S[assoc]:.0f} |"
        )
    for other in [p for p in paths if p != "default"]:
        print(f"{other} / default, CPU and wall (medians of the same rounds):")
        for fname, assoc, path in keys:
            if path == "default":
                ratios = [
                    statistics.median(v[fname, assoc, other])
                    / statistics.median(v[fname, assoc, "default"])
                    for v in (cpu, wall)
                ]
                print(f"  {fname} {assoc}: {ratios[0]:.2f} {ratios[1]:.2f}")
    return 0


def summary_value(summary: str, key: str) -> str:
    """The value of the first summary line starting with ``key``."""
    for line in summary.splitlines():
        if line.startswith(key):
            return re.split(r"\s{2,}", line, maxsplit=1)[1].strip()
    raise ValueError(f"no '{key}' line in the summary")


if __name__ == "__main__":
    sys.exit(main())
