"""Read time of RINEX observation files: navtrack vs georinex 1.16.2.

navtrack: median of several in-process reads (all codes, LLI and SSI). georinex: one read
(``georinex.load(path, useindicators=True)``; it is slow), then the ratio. Run from the repository
root::

    PYTHONPATH=src python benchmarks/bench_rinex_obs.py [--runs 7] [--no-georinex]

Data: the shared real files (``../shared/data/gnss`` or ``NAVTRACK_SHARED_DATA``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings
from pathlib import Path

from navtrack.gnss.rinex.obs import read_obs

REPO = Path(__file__).resolve().parents[1]
GNSS = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
FILES = (
    "cssrlib_sept/SEPT078M.21O",  # RINEX 3.04, 3.9 MB, 900 epochs
    "rtklib_gsi0759/07590920.05o",  # RINEX 2.10, 68 kB, 120 epochs
    "gpstk_arl1/arlm200a.15o",  # RINEX 2.11, 207 kB, 120 epochs, 2 lines per satellite
)


def _navtrack_s(path: Path, runs: int) -> float:
    read_obs(path)  # warm the page cache and imports
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        read_obs(path)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _georinex_s(path: Path) -> float:
    import georinex

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        georinex.load(path, useindicators=True)
        return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="navtrack reads per file (median)")
    parser.add_argument("--no-georinex", action="store_true", help="skip the georinex reads")
    args = parser.parse_args()
    print(f"{'file':<32}{'MB':>6}{'epochs':>8}{'navtrack s':>12}{'georinex s':>12}{'ratio':>9}")
    for rel in FILES:
        path = GNSS / rel
        obs = read_obs(path)
        ours = _navtrack_s(path, args.runs)
        theirs = float("nan") if args.no_georinex else _georinex_s(path)
        print(
            f"{path.name:<32}{path.stat().st_size / 1e6:6.2f}{len(obs.t_gps_s):8d}"
            f"{ours:12.4f}{theirs:12.2f}{theirs / ours:9.0f}x"
        )


if __name__ == "__main__":
    main()
