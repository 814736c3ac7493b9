"""Monte Carlo runner shared by every paper reproduction.

One seed drives everything: run ``i`` gets the generator
``numpy.random.default_rng(numpy.random.SeedSequence(seed).spawn(n)[i])`` — the ``i``-th child
of the seed's sequence, which depends on ``seed`` and ``i`` only (not on ``n``), so any single
run can be replayed alone with :func:`run_generator` / :func:`replay_run`.

Execution goes through Dask when it is installed (extra ``navtrack[dask]``):

* default: in-process, Dask's local threaded scheduler, no cluster;
* ``workers=N``: Dask's multiprocessing scheduler on a pool of ``N`` local worker processes
  (forked where the platform forks, so they start without importing anything again);
* ``scheduler="tcp://host:port"``: an existing Dask cluster (``dask scheduler`` and
  ``dask worker``, or any ``distributed`` deployment).

Without Dask the runs execute in a plain in-process loop with identical results; the result's
``backend`` says which path ran. Each finished run is checkpointed under ``DIR/runs/`` (one
pickle per run, written atomically) when ``checkpoint_dir`` is given, and skipped on a rerun, so
an interrupted reproduction resumes with results identical to an uninterrupted one. An exception
in one run is captured as that run's ``status == RunStatus.ERROR`` (with the traceback) and does
not stop the others. A ``manifest.json`` next to the checkpoints records the experiment name,
seed and parameters; resuming with different ones raises ``ValueError`` instead of mixing
results.

The run function has the signature ``fn(index, rng, params) -> result`` and must be a module-level
(picklable) function; ``params`` is any picklable value (typically a frozen config) and ``result``
any picklable value (typically a dict of floats).
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import os
import pickle
import tempfile
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from enum import IntEnum
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from navtrack._typing import StrPath
from navtrack.errors import CheckpointMismatchError, MissingDependencyError

__all__ = [
    "MonteCarloResult",
    "RunRecord",
    "RunStatus",
    "dask_available",
    "replay_run",
    "run_generator",
    "run_monte_carlo",
]

RunFunction = Callable[[int, np.random.Generator, Any], Any]


class RunStatus(IntEnum):
    """Outcome of one Monte Carlo run (``RunRecord.status``); names are lower-cased in counts."""

    OK = 0
    """The run function returned; its value is the record's ``result``."""
    ERROR = 1
    """The run function raised (or its worker died); the record's ``error`` holds why."""


@dataclass(frozen=True, slots=True)
class RunRecord:
    """Outcome of one Monte Carlo run.

    Attributes
    ----------
    index : int
        Run number ``0..n-1`` (its generator is the ``index``-th child of the seed).
    status : RunStatus
    result : object
        The run function's return value (``None`` on error).
    error : str
        Exception type, message and traceback when ``status == RunStatus.ERROR``.
    resumed : bool
        True when the record was loaded from a checkpoint instead of computed.
    """

    index: int
    status: RunStatus
    result: Any
    error: str = ""
    resumed: bool = False


@dataclass(frozen=True, slots=True)
class MonteCarloResult:
    """All runs of one experiment, in run order.

    Attributes
    ----------
    records : tuple of RunRecord
    seed : int
    backend : str
        ``"dask-threads"``, ``"dask-processes"``, ``"dask-scheduler"`` or ``"loop"``.
    note : str
        Why that backend ran (e.g. "dask is not installed").
    counts : dict of str to int
        Runs per status (``"ok"``, ``"error"``: :class:`RunStatus` names lower-cased) and
        ``"resumed"``, the runs loaded from checkpoints.
    """

    records: tuple[RunRecord, ...]
    seed: int
    backend: str
    note: str = ""
    counts: dict[str, int] = field(default_factory=dict)

    @property
    def results(self) -> list[Any]:
        """Results of the successful runs, in run order."""
        return [r.result for r in self.records if r.status == RunStatus.OK]

    @property
    def n_ok(self) -> int:
        return sum(r.status == RunStatus.OK for r in self.records)

    @property
    def n_error(self) -> int:
        return sum(r.status == RunStatus.ERROR for r in self.records)

    @property
    def n_resumed(self) -> int:
        return sum(r.resumed for r in self.records)


def dask_available() -> bool:
    """True when ``dask`` (and for clusters ``distributed``) can be imported."""
    try:
        import dask  # noqa: F401  # optional dependency (extra navtrack[dask])
    except ImportError:
        return False
    return True


def run_generator(seed: int, index: int) -> np.random.Generator:
    """The generator of run ``index``: the ``index``-th child of ``SeedSequence(seed)``.

    Identical to ``default_rng(SeedSequence(seed).spawn(n)[index])`` for any ``n > index``.
    """
    if index < 0:
        raise ValueError(f"index must be >= 0, got {index}")
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index,)))


def replay_run(fn: RunFunction, seed: int, index: int, params: Any = None) -> Any:
    """Run one Monte Carlo run alone (same result as inside :func:`run_monte_carlo`)."""
    return fn(index, run_generator(seed, index), params)


def _execute(fn: RunFunction, seed: int, index: int, params: Any) -> RunRecord:
    try:
        result = fn(index, run_generator(seed, index), params)
    except Exception as exc:  # one failing run must not lose the others
        text = f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}"
        return RunRecord(index, RunStatus.ERROR, None, text)
    return RunRecord(index, RunStatus.OK, result)


class _Checkpoints:
    """One pickle per finished run under ``DIR/runs/``, plus a manifest."""

    def __init__(self, directory: StrPath, name: str, seed: int, params: Any) -> None:
        self.dir = Path(directory) / "runs"
        self.dir.mkdir(parents=True, exist_ok=True)
        digest = hashlib.sha256(pickle.dumps(params, protocol=4)).hexdigest()
        manifest = {"name": name, "seed": int(seed), "params_sha256": digest}
        path = self.dir / "manifest.json"
        if path.exists():
            old = json.loads(path.read_text())
            if old != manifest:
                raise CheckpointMismatchError(
                    f"checkpoint_dir {self.dir} holds runs of {old}; refusing to mix them with "
                    f"{manifest}: give a new output folder, or delete {self.dir} to start over "
                    "(the same experiment, seed and parameters resume from it)"
                )
        else:
            path.write_text(json.dumps(manifest, indent=2) + "\n")

    def path(self, index: int) -> Path:
        return self.dir / f"run_{index:06d}.pkl"

    def load(self, index: int) -> RunRecord | None:
        path = self.path(index)
        if not path.exists():
            return None
        try:
            with path.open("rb") as fh:
                record = pickle.load(fh)
        except (OSError, pickle.UnpicklingError, EOFError):
            return None  # a torn file from an interrupted write: recompute
        if not isinstance(record, RunRecord) or record.index != index:
            return None
        return RunRecord(record.index, record.status, record.result, record.error, True)

    def save(self, record: RunRecord) -> None:
        fd, tmp = tempfile.mkstemp(dir=self.dir, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(record, fh, protocol=4)
        os.replace(tmp, self.path(record.index))


def run_monte_carlo(
    fn: RunFunction,
    n_runs: int,
    seed: int,
    params: Any = None,
    *,
    name: str = "experiment",
    checkpoint_dir: StrPath | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    backend: str = "auto",
    retry_errors: bool = True,
    progress: bool = True,
) -> MonteCarloResult:
    """Run ``fn`` for ``n_runs`` seeded runs, resumably, through Dask when available.

    Parameters
    ----------
    fn : callable
        ``fn(index, rng, params) -> result``, module-level (picklable).
    n_runs : int
        Number of runs.
    seed : int
        Root seed; run ``i`` uses :func:`run_generator` ``(seed, i)``.
    params : object, optional
        Passed unchanged to every run (picklable).
    name : str
        Experiment name recorded in the checkpoint manifest.
    checkpoint_dir : path, optional
        Directory whose ``runs/`` subfolder holds one checkpoint per finished run.
    workers : int, optional
        Run on this many local worker processes (Dask's multiprocessing scheduler).
    scheduler : str, optional
        Address of an existing Dask scheduler (``tcp://host:port``).
    backend : {"auto", "loop"}
        ``"loop"`` forces the plain in-process loop (the no-Dask path).
    retry_errors : bool
        Recompute runs whose checkpoint recorded an error.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    MonteCarloResult
    """
    _check_options(n_runs, workers, scheduler, backend)
    store = _Checkpoints(checkpoint_dir, name, seed, params) if checkpoint_dir is not None else None
    records = _resumed(store, n_runs, retry_errors)
    pending = [i for i in range(n_runs) if i not in records]
    bar = tqdm(
        total=n_runs,
        initial=n_runs - len(pending),
        desc=name,
        disable=not progress,
        unit="run",
    )

    def finished(record: RunRecord) -> None:
        records[record.index] = record
        if store is not None:
            store.save(record)
        bar.update(1)

    chosen, note = _choose_backend(backend, workers, scheduler)
    try:
        if chosen == "loop":
            for i in pending:
                finished(_execute(fn, seed, i, params))
        elif chosen == "dask-threads":
            _run_dask_local(fn, seed, params, pending, finished)
        elif chosen == "dask-processes":
            _run_dask_processes(fn, seed, params, pending, finished, workers or 1)
        else:
            _run_distributed(fn, seed, params, pending, finished, scheduler)
    finally:
        bar.close()
    ordered = tuple(records[i] for i in range(n_runs))
    counts = {status.name.lower(): sum(r.status == status for r in ordered) for status in RunStatus}
    counts["resumed"] = sum(r.resumed for r in ordered)
    return MonteCarloResult(ordered, int(seed), chosen, note, counts)


def _check_options(n_runs: int, workers: int | None, scheduler: str | None, backend: str) -> None:
    """``ValueError`` naming the first option of :func:`run_monte_carlo` out of its range."""
    if n_runs < 0:
        raise ValueError(f"n_runs must be >= 0, got {n_runs}")
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if workers is not None and scheduler is not None:
        raise ValueError("give at most one of workers and scheduler")
    if backend not in ("auto", "loop"):
        raise ValueError(f"backend must be 'auto' or 'loop', got {backend!r}")


def _resumed(store: _Checkpoints | None, n_runs: int, retry_errors: bool) -> dict[int, RunRecord]:
    """The runs a checkpoint folder already holds (without errors when ``retry_errors``)."""
    records: dict[int, RunRecord] = {}
    if store is not None:
        for i in range(n_runs):
            rec = store.load(i)
            if rec is not None and (rec.status == RunStatus.OK or not retry_errors):
                records[i] = rec
    return records


def _choose_backend(backend: str, workers: int | None, scheduler: str | None) -> tuple[str, str]:
    """The backend that will run the runs and the note that says why.

    Raises
    ------
    MissingDependencyError
        ``scheduler`` given but dask is not installed.
    """
    if backend == "loop":
        return "loop", "plain in-process loop (requested)"
    if not dask_available():
        if scheduler is not None:
            raise MissingDependencyError("distributed", "dask", "--scheduler")
        return (
            "loop",
            "dask is not installed: runs execute in a plain in-process loop (same results)",
        )
    if scheduler is not None:
        return "dask-scheduler", f"existing Dask cluster at {scheduler}"
    if workers is not None:
        return (
            "dask-processes",
            f"Dask multiprocessing scheduler on {workers} local worker processes",
        )
    return "dask-threads", "in-process Dask threaded scheduler (no cluster)"


def _batches(items: list[int], size: int) -> Iterable[list[int]]:
    for start in range(0, len(items), size):
        yield items[start : start + size]


def _run_dask_local(
    fn: RunFunction,
    seed: int,
    params: Any,
    pending: list[int],
    finished: Callable[[RunRecord], None],
) -> None:
    import dask  # optional dependency (extra navtrack[dask])

    # Batches keep the progress bar and the checkpoints current without a cluster.
    batch_size = max(1, min(8, os.cpu_count() or 1) * 2)
    task = dask.delayed(_execute, pure=False)
    for batch in _batches(pending, batch_size):
        outs = dask.compute(*[task(fn, seed, i, params) for i in batch], scheduler="threads")
        for record in outs:
            finished(record)


def _run_dask_processes(
    fn: RunFunction,
    seed: int,
    params: Any,
    pending: list[int],
    finished: Callable[[RunRecord], None],
    workers: int,
) -> None:
    import dask  # optional dependency (extra navtrack[dask])

    task = dask.delayed(_execute, pure=False)
    # One pool for every batch; a run per task (chunksize 1) and many tasks per worker in a batch
    # keep the workers busy up to each checkpoint.
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context()) as pool:
        for batch in _batches(pending, 16 * workers):
            try:
                outs = dask.compute(
                    *[task(fn, seed, i, params) for i in batch],
                    scheduler="processes",
                    pool=pool,
                    chunksize=1,
                )
            except Exception as exc:  # a worker died: its pool cannot run the batch
                message = f"{type(exc).__name__}: {exc}"
                outs = tuple(RunRecord(i, RunStatus.ERROR, None, message) for i in batch)
            for record in outs:
                finished(record)


def _run_distributed(
    fn: RunFunction,
    seed: int,
    params: Any,
    pending: list[int],
    finished: Callable[[RunRecord], None],
    scheduler: str | None,
) -> None:
    try:
        from distributed import Client, as_completed  # optional (extra navtrack[dask])
    except ImportError as exc:
        raise MissingDependencyError("distributed", "dask", "Dask clusters") from exc
    client = Client(scheduler)
    try:
        futures = {client.submit(_execute, fn, seed, i, params, pure=False): i for i in pending}
        for future in as_completed(futures):
            index = futures[future]
            try:
                record = future.result()
            except Exception as exc:  # a worker died, a task could not be deserialised, ...
                record = RunRecord(index, RunStatus.ERROR, None, f"{type(exc).__name__}: {exc}")
            finished(record)
    finally:
        client.close()
