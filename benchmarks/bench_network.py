"""Throughput of ``navtrack pos FILES... --out DIR`` (a station network) by backend.

Solves the same stations three ways in this run, each from an empty output folder: the plain
in-process loop (one station after another), Dask's in-process threaded scheduler (the
default), and Dask's multiprocessing scheduler on ``--workers`` processes; prints wall time,
stations and epochs per second, and the speed-up over the loop. Then reruns the process job on its
own folder to show the resume (every station loaded from its checkpoint).

Stations: the shared data's observation files (``--shared``), or ``--copies N`` copies of the
bundled 120-epoch SEPT file (``--full``: of the shared 900-epoch one), each in its own folder
beside its navigation file (a synthetic network: the throughput, not the positions, is the
point).

Usage::

    PYTHONPATH=src python benchmarks/bench_network.py [--copies 100] [--full] [--workers 2]
        [--shared]
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

from navtrack.data import sample_path
from navtrack.experiments import network
from navtrack.experiments.runner import run_monte_carlo
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig
from navtrack.positioning.stations import StationJob, station_jobs

_DEFAULT_SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", _DEFAULT_SHARED)) / "gnss"
SHARED_OBS = (
    "rtklib_gsi0759/07590920.05o",
    "gpstk_arl1/arlm200a.15o",
    "cssrlib_sept/SEPT078M.21O",
    "gogps_yamatogawa/yamatogawa_master.obs",
)


def _copies(root: Path, n: int, full: bool) -> list[Path]:
    obs = SHARED / "cssrlib_sept" / "SEPT078M.21O" if full else sample_path("SEPT078M_120.21O")
    out = []
    for k in range(n):
        folder = root / f"S{k:03d}"
        folder.mkdir()
        shutil.copy(obs, folder / obs.name)
        shutil.copy(sample_path("SEPT078M.21P"), folder / "SEPT078M.21P")
        out.append(folder / obs.name)
    return out


def _loop(jobs: list[StationJob], config: SppConfig, out: Path) -> None:
    out.mkdir()
    run_monte_carlo(network.solve_station, len(jobs), 0, (tuple(jobs), config, str(out)),
                    backend="loop", progress=False)  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--copies", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--shared", action="store_true", help="the shared stations instead")
    parser.add_argument(
        "--full", action="store_true", help="copies of the shared 900-epoch SEPT file"
    )
    args = parser.parse_args()
    config = SppConfig(systems="G")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        files = (
            [SHARED / f for f in SHARED_OBS]
            if args.shared
            else _copies(root, args.copies, args.full)
        )
        jobs = station_jobs(files)
        rows = []
        for label, run in (
            ("loop", lambda out: _loop(jobs, config, out)),
            ("dask threads", lambda out: network.solve_network(jobs, config, out, progress=False)),
            (f"processes {args.workers}", lambda out: network.solve_network(
                jobs, config, out, workers=args.workers, progress=False)),
        ):  # fmt: skip
            out = root / label.replace(" ", "_")
            clock = time.perf_counter()
            run(out)
            rows.append((label, time.perf_counter() - clock))
        epochs = sum(len(read_obs(j.obs).t_gps_s) for j in jobs)
        base = rows[0][1]
        print(f"{len(jobs)} stations, {epochs} epochs; load average {os.getloadavg()[0]:.1f}")
        print("backend             wall s  stations/s  epochs/s  speed-up over the loop")
        for label, wall in rows:
            rate = f"{len(jobs) / wall:11.1f} {epochs / wall:9.0f}"
            print(f"{label:<18} {wall:7.2f} {rate} {base / wall:8.2f}")
        clock = time.perf_counter()
        again = network.solve_network(jobs, config, root / f"processes_{args.workers}",
                                      workers=args.workers, progress=False)  # fmt: skip
        print(f"resume: {again.runs.counts['resumed']} of {len(jobs)} stations from checkpoints "
              f"in {time.perf_counter() - clock:.2f} s")  # fmt: skip


if __name__ == "__main__":
    main()
