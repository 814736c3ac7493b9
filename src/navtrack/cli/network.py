"""``navtrack pos FILES... --out DIR``: single point positions of a station network (several
observation files in one command) on the Dask runner (:mod:`navtrack.experiments.network`)."""

from __future__ import annotations

import argparse
import time
from typing import TYPE_CHECKING

from navtrack.positioning.stations import StationJob, station_jobs

if TYPE_CHECKING:
    from navtrack.gnss.spp import SppConfig


def network_jobs(args: argparse.Namespace) -> list[StationJob] | None:
    """The stations of ``pos``'s files when they hold several observation files, else None."""
    files = [args.obs, *args.nav]
    if len(files) < 2:
        return None
    jobs = station_jobs(files)
    return jobs if len(jobs) > 1 else None


def run_network(args: argparse.Namespace, jobs: list[StationJob], config: SppConfig) -> int:
    """Solve the network, print one line per station and the throughput."""
    # the Monte Carlo runner (Dask) is loaded for a network run only: `pos` start-up
    from navtrack.experiments.network import solve_network

    if args.out is None or args.out.suffix:
        raise SystemExit("navtrack pos: several observation files need --out DIR (a folder)")
    for option in ("ref", "ref_llh", "plot", "sp3"):
        if getattr(args, option, None) is not None:
            raise SystemExit(f"navtrack pos: --{option.replace('_', '-')} is for one station")
    if args.lenient:
        raise SystemExit("navtrack pos: --lenient is for one station (a network reads strictly)")
    clock = time.perf_counter()
    result = solve_network(
        jobs,
        config,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.no_progress,
    )
    wall = time.perf_counter() - clock
    table = result.stations
    print(f"network        {len(jobs)} stations, {result.runs.note}")
    for row in table.itertuples():
        if row.status == "ok":
            print(f"  {row.station:<20} {row.epochs:6d} epochs, {row.solved:6d} solved")
        else:
            print(f"  {row.station:<20} error: {row.error}")
    ok = table["status"] == "ok"
    epochs = int(table.loc[ok, "epochs"].sum()) if ok.any() else 0
    counts = result.runs.counts
    print(
        f"stations       ok {int(ok.sum())}, error {int((~ok).sum())}, resumed "
        f"{counts['resumed']}; {epochs} epochs in {wall:.1f} s"
    )
    print(f"written        {args.out}/positions/station=NAME/part.parquet, {args.out}/stations.csv")
    return 0 if ok.any() else 1
