"""Reproductions of the seed papers' experiments (``navtrack reproduce NAME``).

Each reproduction is one :class:`~navtrack.experiments.contract.Experiment` (typed parameters,
``run_one``, ``summarize``, optional ``extra``, ``tables``, ``figures``, ``summary_lines``),
registered by name in :data:`EXPERIMENTS`; its module exposes the instance as ``EXPERIMENT`` and is
imported only when asked for. :func:`reproduce` does everything else, the same way for all of
them: the seeded, resumable Monte Carlo runs (:mod:`navtrack.experiments.runner`, in-process,
local Dask cluster or remote scheduler), the ``extra`` step with its own generator and the shared
data (:func:`~navtrack.experiments.contract.shared_data_dir`), the common header of
``results.json`` (:data:`~navtrack.experiments.contract.HEADER_FIELDS`), and the files
``results.json``, ``tables.md`` and the figures.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack import __version__
from navtrack.experiments.contract import (
    EXTRA_SPAWN_KEY,
    HEADER_FIELDS,
    Experiment,
    ExperimentContext,
    ExtraResult,
    MissingDataError,
    Outcome,
    shared_data_dir,
)

if TYPE_CHECKING:
    from navtrack.experiments.runner import MonteCarloResult

__all__ = [
    "EXPERIMENTS",
    "HEADER_FIELDS",
    "Experiment",
    "ExperimentContext",
    "ExtraResult",
    "MissingDataError",
    "Outcome",
    "ReproduceOptions",
    "get_experiment",
    "header_lines",
    "reproduce",
    "shared_data_dir",
    "write_json",
]

#: Experiment name -> module holding its ``EXPERIMENT``. Later reproductions add one line each.
EXPERIMENTS: dict[str, str] = {
    "foveal": "navtrack.experiments.foveal",
    "ari": "navtrack.experiments.ari",
    "agps": "navtrack.experiments.agps",
    "alhat": "navtrack.experiments.alhat",
    "raim-fcm": "navtrack.experiments.raim_fcm",
    "sdcmsjpda": "navtrack.experiments.sdcmsjpda",
}


@dataclass(frozen=True, slots=True)
class ReproduceOptions:
    """How to run a reproduction.

    Parameters
    ----------
    out_dir : Path
        Output directory (``results.json``, ``tables.md``, figures, ``runs/`` checkpoints).
    runs : int or None
        Monte Carlo runs; ``None`` takes the experiment's ``default_runs``.
    seed : int
        Root seed of all runs.
    params : object or None
        Instance of the experiment's ``params_type``; ``None`` takes its defaults.
    workers : int or None
        Local Dask cluster with this many worker processes.
    scheduler : str or None
        Address of an existing Dask scheduler.
    backend : {"auto", "loop"}
        ``"loop"`` forces the plain in-process loop (see :func:`~.runner.run_monte_carlo`).
    progress : bool
        Progress bars.
    inputs : tuple of Path
        Extra input files the experiment understands (e.g. solution tables for ``ari``).
    figures : bool
        Write PNG figures (needs matplotlib).
    log : callable or None
        Receives one line per stage as it starts and ends (the ``extra`` step, each figure as it is
        written); ``navtrack reproduce`` prints them. ``None``: silent.
    """

    out_dir: Path
    runs: int | None = None
    seed: int = 0
    params: Any = None
    workers: int | None = None
    scheduler: str | None = None
    backend: str = "auto"
    progress: bool = True
    inputs: tuple[Path, ...] = ()
    figures: bool = True
    log: Callable[[str], None] | None = None


def get_experiment(name: str) -> Experiment[Any, Any]:
    """The registered experiment ``name``; ``ValueError`` naming the known ones."""
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; known: {', '.join(sorted(EXPERIMENTS))}")
    experiment = importlib.import_module(EXPERIMENTS[name]).EXPERIMENT
    if not isinstance(experiment, Experiment) or experiment.name != name:
        raise TypeError(f"{EXPERIMENTS[name]}.EXPERIMENT is not the Experiment {name!r}")
    return experiment


class _RunOne:
    """The runner's ``fn(index, rng, params)`` of an experiment (picklable with it)."""

    def __init__(self, experiment: Experiment[Any, Any]) -> None:
        self.experiment = experiment

    def __call__(self, index: int, rng: np.random.Generator, params: Any) -> Any:
        return self.experiment.run_one(params, rng)


def _git_revision() -> str | None:
    """Commit of the checkout the package runs from, or None (installed package, no git)."""
    try:
        out = subprocess.run(
            ["git", "-C", str(Path(__file__).resolve().parent), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def reproduce(experiment: Experiment[Any, Any] | str, options: ReproduceOptions) -> dict[str, Any]:
    """Run a reproduction and write ``results.json``, ``tables.md`` and its figures.

    Parameters
    ----------
    experiment : Experiment or str
        The experiment, or its registered name.
    options : ReproduceOptions

    Returns
    -------
    dict
        The ``results.json`` content: the header of :data:`HEADER_FIELDS`, then the entries of
        ``summarize`` and ``extra``, then ``figures`` (paths) or ``figures_error``.
    """
    # The runner loads tqdm, multiprocessing and the Dask probe: imported when a reproduction
    # runs, since `navtrack --help` imports this package for the list of experiments.
    from navtrack.experiments.runner import run_monte_carlo

    exp = get_experiment(experiment) if isinstance(experiment, str) else experiment
    params = exp.default_params() if options.params is None else options.params
    if not isinstance(params, exp.params_type):
        raise TypeError(
            f"options.params: expected {exp.params_type.__name__} for experiment {exp.name!r}, "
            f"got {type(params).__name__}"
        )
    runs = exp.default_runs if options.runs is None else options.runs
    out = options.out_dir
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    mc = run_monte_carlo(
        _RunOne(exp),
        runs,
        options.seed,
        params,
        name=exp.name,
        checkpoint_dir=out,
        workers=options.workers,
        scheduler=options.scheduler,
        backend=options.backend,
        progress=options.progress,
    )
    log = options.log or (lambda line: None)
    summary = exp.summarize(params, mc.results)
    rng = np.random.default_rng(np.random.SeedSequence(options.seed, spawn_key=(EXTRA_SPAWN_KEY,)))
    context = ExperimentContext(
        options.seed,
        rng,
        tuple(options.inputs),
        out,
        progress=options.progress,
        workers=options.workers or 1,
    )
    t_extra = time.perf_counter()
    log("extra      real data and cross-checks ...")
    extra = exp.extra(params, context)
    log(f"extra      done in {time.perf_counter() - t_extra:.1f} s")
    header = _header(exp, params, options.seed, runs, mc)
    results = header | _merged(exp.name, header, summary, extra.results)
    if options.figures:
        outcome = Outcome(params, tuple(mc.results), results, extra.artifacts)
        results |= _figures(exp, outcome, out, log)
    results["wall_time_s"] = time.perf_counter() - t0
    (out / "tables.md").write_text(exp.tables(results))
    write_json(out / "results.json", results)
    return results


def _header(
    exp: Experiment[Any, Any], params: Any, seed: int, runs: int, mc: MonteCarloResult
) -> dict[str, Any]:
    """The header entries of ``results.json`` (:data:`HEADER_FIELDS`)."""
    return {
        "experiment": exp.name,
        "description": exp.description,
        "parameters": dataclasses.asdict(params),
        "seed": seed,
        "runs": runs,
        "package_version": __version__,
        "git_revision": _git_revision(),
        "backend": mc.backend,
        "backend_note": mc.note,
        "wall_time_s": math.nan,
        "run_counts": mc.counts,
        "run_errors": [r.error.splitlines()[0] for r in mc.records if r.error],
    }


def _merged(
    name: str, header: dict[str, Any], summary: dict[str, Any], extra: dict[str, Any]
) -> dict[str, Any]:
    """``summary | extra``; ``ValueError`` when an experiment returns a key twice (or one of
    the header's)."""
    clash = (set(header) & set(summary)) | (set(header) & set(extra))
    clash |= set(summary) & set(extra)
    if clash:
        raise ValueError(f"experiment {name!r} returned keys twice: {sorted(clash)}")
    return summary | extra


def _figures(
    exp: Experiment[Any, Any], outcome: Outcome, out: Path, log: Callable[[str], None]
) -> dict[str, Any]:
    """Write the experiment's figures: ``{"figures": paths}``, or ``{"figures_error": why}``
    when the plotting dependency is missing."""
    paths: list[str] = []
    try:
        for figure in exp.figures(outcome, out):
            paths.append(str(figure))
            log(f"figure     {figure}")
    except ImportError as exc:
        return {"figures": paths, "figures_error": str(exc)}
    return {"figures": paths}


def header_lines(results: dict[str, Any]) -> list[str]:
    """Console lines of the common header of a results dictionary (``navtrack reproduce``)."""
    counts = results["run_counts"]
    return [
        f"experiment {results['experiment']}: {results['runs']} runs, seed {results['seed']}",
        f"backend    {results['backend']} — {results['backend_note']}",
        "runs       "
        + ", ".join(f"{k} {v}" for k, v in counts.items() if k != "resumed")
        + f", resumed from checkpoints {counts.get('resumed', 0)}",
        f"wall time  {results['wall_time_s']:.1f} s",
    ]


def _clean(value: Any) -> Any:
    """JSON-safe copy: NumPy scalars/arrays to Python, enums by name, NaN/inf to None."""
    if isinstance(value, dict):
        return {_key(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_clean(v) for v in value.tolist()]
    if isinstance(value, Enum):
        return value.name.lower()
    if isinstance(value, np.bool_ | bool):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating | float):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, Path):
        return str(value)
    return value


def _key(key: Any) -> str:
    return key.name.lower() if isinstance(key, Enum) else str(key)


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON (NaN written as null, enums by lower-cased name)."""
    path.write_text(json.dumps(_clean(data), indent=2) + "\n")
