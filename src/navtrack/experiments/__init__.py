"""Reproductions of the seed papers' experiments (``navtrack reproduce NAME``).

Each experiment is a module registered in :data:`EXPERIMENTS` that provides

* ``DESCRIPTION`` (str) and ``DEFAULT_RUNS`` (int), and
* ``reproduce(options: ReproduceOptions) -> dict`` — runs the Monte Carlo part through
  :func:`navtrack.experiments.runner.run_monte_carlo` (seeded, resumable, Dask), writes
  ``options.out_dir / "results.json"``, ``tables.md`` and PNG figures, and returns the results.

Modules are imported only when their experiment is run.
"""

from __future__ import annotations

import importlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["EXPERIMENTS", "ReproduceOptions", "get_experiment", "reproduce", "write_json"]

#: Experiment name -> module. Later reproductions add one line each.
EXPERIMENTS: dict[str, str] = {
    "ari": "navtrack.experiments.ari",
}


@dataclass(frozen=True, slots=True)
class ReproduceOptions:
    """How to run a reproduction.

    Parameters
    ----------
    out_dir : Path
        Output directory (``results.json``, ``tables.md``, figures, ``runs/`` checkpoints).
    runs : int or None
        Monte Carlo runs; ``None`` takes the experiment's ``DEFAULT_RUNS``.
    seed : int
        Root seed of all runs.
    workers : int or None
        Local Dask cluster with this many worker processes.
    scheduler : str or None
        Address of an existing Dask scheduler.
    progress : bool
        Progress bars.
    inputs : tuple of Path
        Extra input files the experiment understands (e.g. solution tables for ``ari``).
    figures : bool
        Write PNG figures (needs matplotlib).
    """

    out_dir: Path
    runs: int | None = None
    seed: int = 0
    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True
    inputs: tuple[Path, ...] = ()
    figures: bool = True


def get_experiment(name: str) -> ModuleType:
    """The module of a registered experiment; ``ValueError`` naming the known ones."""
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; known: {', '.join(sorted(EXPERIMENTS))}")
    return importlib.import_module(EXPERIMENTS[name])


def reproduce(name: str, options: ReproduceOptions) -> dict[str, Any]:
    """Run the reproduction ``name`` with ``options``; returns its results dictionary."""
    module = get_experiment(name)
    options.out_dir.mkdir(parents=True, exist_ok=True)
    result: dict[str, Any] = module.reproduce(options)
    return result


def _clean(value: Any) -> Any:
    """JSON-safe copy: NumPy scalars/arrays to Python, NaN/inf to None."""
    import numpy as np

    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_clean(v) for v in value.tolist()]
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


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON (NaN written as null)."""
    path.write_text(json.dumps(_clean(data), indent=2) + "\n")
