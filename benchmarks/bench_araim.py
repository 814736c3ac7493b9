"""Timing of ``navtrack pos --raim araim`` against ``--raim chi2`` on the same file, measured in
the same run as whole processes, alternating, medians.

Printed: the wall time of each command (s), their ratio, and the ARAIM share of the run
(``araim`` minus ``chi2``, the extra cost of MHSS over the chi-square test). Default file:
SEPT (900 epochs), GPS + Galileo, ionosphere-free; ``--iono klobuchar`` for L1, ``--obs`` /
``--nav`` for another file (e.g. a 24 h station of docs/integrity.md).

Usage::

    NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python benchmarks/bench_araim.py \
        [--repeat 5] [--iono ionofree|klobuchar] [--systems GE] [--obs F --nav F]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"


def _command(args: argparse.Namespace, method: str) -> list[str]:
    return [
        sys.executable, "-m", "navtrack", "pos", str(args.obs), *map(str, args.nav),
        "--systems", args.systems, "--iono", args.iono, "--raim", method, "--no-progress",
    ]  # fmt: skip


def _time(cmd: list[str], env: dict[str, str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--iono", default="ionofree", choices=("ionofree", "klobuchar"))
    ap.add_argument("--systems", default="GE")
    ap.add_argument("--obs", type=Path, default=SHARED / "cssrlib_sept" / "SEPT078M.21O")
    ap.add_argument(
        "--nav", type=Path, nargs="+", default=[SHARED / "cssrlib_sept" / "SEPT078M.21P"]
    )
    args = ap.parse_args()
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    cmds = {m: _command(args, m) for m in ("chi2", "araim")}
    times: dict[str, list[float]] = {m: [] for m in cmds}
    for m in cmds:  # warm the file cache
        _time(cmds[m], env)
    for i in range(args.repeat):
        order = ("chi2", "araim") if i % 2 == 0 else ("araim", "chi2")
        for m in order:
            times[m].append(_time(cmds[m], env))
    med = {m: statistics.median(t) for m, t in times.items()}
    print(f"{args.obs.name}, --systems {args.systems} --iono {args.iono}, medians of {args.repeat}")
    print(f"  pos --raim chi2   {med['chi2']:.3f} s")
    print(f"  pos --raim araim  {med['araim']:.3f} s")
    print(f"  ratio araim/chi2  {med['araim'] / med['chi2']:.2f}")
    print(f"  ARAIM extra       {med['araim'] - med['chi2']:.3f} s")


if __name__ == "__main__":
    main()
