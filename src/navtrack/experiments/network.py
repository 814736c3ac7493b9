"""Single point positions of a network of stations: many observation files in one job.

Each station is one run of the Monte Carlo runner (:mod:`navtrack.experiments.runner`), solved
by the positioning pipeline (:func:`navtrack.positioning.solve_positions`):
in-process by default, on local worker processes (``workers``) or an existing Dask cluster
(``scheduler``), with a checkpoint per finished station so that an interrupted job resumes where
it stopped. Every station's solution is written to one Parquet dataset partitioned by station
(``OUT/positions/station=NAME/part.parquet``, the columns of ``pos --out``; read it whole with
``pandas.read_parquet(OUT / "positions")``), its summary to
``OUT/stations.csv``.

Navigation data: the files given with the observations serve every station; without any, each
station takes the navigation files beside its observation file (same folder).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack.errors import MissingDependencyError
from navtrack.experiments.runner import MonteCarloResult, RunStatus, run_monte_carlo
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, observation_codes
from navtrack.positioning import solve_positions
from navtrack.positioning.stations import StationJob

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["NetworkResult", "solve_network", "solve_station"]


@dataclass(frozen=True, slots=True, eq=False)
class NetworkResult:
    """Outcome of :func:`solve_network`.

    Attributes
    ----------
    stations : pandas.DataFrame
        One row per station: ``station``, ``obs``, ``status`` (``ok``, or ``error`` with
        ``error``), ``epochs``, ``solved``, ``x_m``, ``y_m``, ``z_m`` (median of the ``ok``
        epochs), ``seconds`` (run time) and ``resumed``.
    runs : MonteCarloResult
        The runner's record (backend, counts).
    """

    stations: pd.DataFrame
    runs: MonteCarloResult


def solve_station(index: int, rng: np.random.Generator, params: Any) -> dict[str, Any]:
    """Run ``index`` of the runner: one station read, solved and written."""
    jobs, config, out_dir = params
    job = jobs[index]
    clock = time.perf_counter()
    obs = read_obs(job.obs, systems=config.systems, codes=observation_codes(config))
    navs = [read_nav(p, systems=config.systems) for p in job.navs]
    result = solve_positions(obs, navs, config=config)
    table = result.to_frame()
    folder = Path(out_dir) / "positions" / f"station={job.name}"
    folder.mkdir(parents=True, exist_ok=True)
    table.to_parquet(folder / "part.parquet", index=False)
    ok = result.status == 0
    centre = np.median(result.pos_m[ok], axis=0) if ok.any() else np.full(3, np.nan)
    return {
        "station": job.name,
        "obs": str(job.obs),
        "epochs": int(result.t_gps_s.size),
        "solved": int(ok.sum()),
        "x_m": float(centre[0]),
        "y_m": float(centre[1]),
        "z_m": float(centre[2]),
        "seconds": time.perf_counter() - clock,
    }


def solve_network(
    jobs: Sequence[StationJob],
    config: SppConfig,
    out_dir: Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> NetworkResult:
    """Solve every station of ``jobs`` and write the partitioned dataset and the summaries.

    Parameters
    ----------
    jobs : sequence of StationJob
    config : SppConfig
    out_dir : Path
        Created if missing; holds the dataset (``positions/``), ``stations.csv`` and the
        runner's checkpoints (``runs/``): a rerun with the same stations and options resumes.
    workers, scheduler : optional
        As :func:`navtrack.experiments.runner.run_monte_carlo`.
    progress : bool

    Raises
    ------
    MissingDependencyError
        pyarrow (extra ``parquet``) is not installed; checked before any station is solved.
    """
    import pandas as pd  # pandas: only for the summary table of a network run

    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MissingDependencyError("pyarrow", "parquet", "the network dataset") from None
    out_dir.mkdir(parents=True, exist_ok=True)
    params = (tuple(jobs), config, str(out_dir))
    runs = run_monte_carlo(
        solve_station,
        len(jobs),
        0,
        params,
        name="network",
        checkpoint_dir=out_dir,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
    )
    rows = []
    for job, record in zip(jobs, runs.records, strict=True):
        if record.status == RunStatus.OK:
            rows.append({**record.result, "status": "ok", "error": "", "resumed": record.resumed})
        else:
            last = (record.error or "").strip().splitlines()
            rows.append({"station": job.name, "obs": str(job.obs), "status": "error",
                         "error": last[-1] if last else "", "resumed": record.resumed})  # fmt: skip
    stations = pd.DataFrame(rows)
    stations.to_csv(out_dir / "stations.csv", index=False, float_format="%.4f")
    return NetworkResult(stations, runs)
