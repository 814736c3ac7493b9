"""The typed contract every reproduction implements, and the values passed across it.

A reproduction is one subclass of :class:`Experiment` with a frozen parameter dataclass; the
generic :func:`navtrack.experiments.reproduce` drives it:

1. ``run_one(params, rng)`` for each Monte Carlo run (seeded, resumable, through Dask:
   :mod:`navtrack.experiments.runner`);
2. ``summarize(params, runs)`` over the successful runs' results, in run order;
3. ``extra(params, context)`` for the part that is not a Monte Carlo run (real data sets,
   cross-checks against a peer library); it sees the seed, the input files, the shared data and
   a generator of its own through :class:`ExperimentContext`;
4. ``tables(results)`` -> ``tables.md``, ``figures(outcome, out_dir)`` -> PNG files,
   ``summary_lines(results)`` -> the console summary.

``results`` is the JSON-able dictionary written to ``results.json``: the common header of
:data:`HEADER_FIELDS` followed by what ``summarize`` and ``extra`` returned.
"""

from __future__ import annotations

import os
from abc import ABC, abstractmethod
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar, Generic, TypeVar

import numpy as np

from navtrack.errors import NavtrackError

__all__ = [
    "EXTRA_SPAWN_KEY",
    "HEADER_FIELDS",
    "Experiment",
    "ExperimentContext",
    "ExtraResult",
    "MissingDataError",
    "Outcome",
    "shared_data_dir",
]

P = TypeVar("P")
R = TypeVar("R")
T = TypeVar("T")

#: Spawn key of the generator of the ``extra`` step: the child ``10**6`` of the seed's
#: ``SeedSequence``, disjoint from the generators of Monte Carlo runs ``0 .. 10**6 - 1``.
EXTRA_SPAWN_KEY = 10**6

#: Keys of the common header of every ``results.json``, in the order they are written.
HEADER_FIELDS = (
    "experiment",
    "description",
    "parameters",
    "seed",
    "runs",
    "package_version",
    "git_revision",
    "backend",
    "backend_note",
    "wall_time_s",
    "run_counts",
    "run_errors",
)


class MissingDataError(NavtrackError, FileNotFoundError):
    """The shared real data sets an experiment requires are not where they are looked for."""


def shared_data_dir(*, required: bool = False) -> Path:
    """Root of the shared real data sets.

    ``NAVTRACK_SHARED_DATA`` when set, else ``shared/data`` next to the development checkout
    (``<repo>/../shared/data``), else ``../shared/data`` from the working directory.

    Parameters
    ----------
    required : bool
        Raise :class:`MissingDataError` (naming every place looked at) when the directory found
        does not exist. Without it the path is returned as found, and the experiment skips the
        data sets that are absent with a stated reason.

    Returns
    -------
    Path
    """
    env = os.environ.get("NAVTRACK_SHARED_DATA")
    checkout = Path(__file__).resolve().parents[3].parent / "shared" / "data"
    if env:
        found = Path(env)
    else:
        found = checkout if checkout.is_dir() else Path.cwd().parent / "shared" / "data"
    if required and not found.is_dir():
        looked = f"NAVTRACK_SHARED_DATA={env!r}" if env else "NAVTRACK_SHARED_DATA (not set)"
        raise MissingDataError(
            f"shared data not found: looked at {looked} and {checkout} (../shared/data next to "
            "the checkout); set NAVTRACK_SHARED_DATA to the directory holding the data sets"
        )
    return found


@dataclass(frozen=True, slots=True)
class ExperimentContext:
    """What the ``extra`` step of an experiment may use besides its parameters.

    Attributes
    ----------
    seed : int
        Root seed of the reproduction.
    rng : numpy.random.Generator
        Generator of the ``extra`` step: child :data:`EXTRA_SPAWN_KEY` of ``SeedSequence(seed)``.
    inputs : tuple of Path
        Extra input files given by the user (``navtrack reproduce ... --input FILE``).
    out_dir : Path
        Output directory.
    progress : bool
        Whether :meth:`track` shows progress bars (``navtrack reproduce --no-progress`` turns
        them off).
    workers : int
        Processes the step may use (``navtrack reproduce --workers``; 1 when not given).
    """

    seed: int
    rng: np.random.Generator
    inputs: tuple[Path, ...] = ()
    out_dir: Path = Path(".")
    progress: bool = False
    workers: int = 1

    def track(self, items: Sequence[T], desc: str) -> Iterator[T]:
        """Iterate over ``items`` with a progress bar on stderr named ``desc`` (when enabled)."""
        from tqdm.auto import tqdm  # not loaded by `navtrack --help`, which imports this module

        yield from tqdm(items, desc=desc, disable=not self.progress, leave=False)

    def shared_data(self, *, required: bool = False) -> Path:
        """Root of the shared data sets (:func:`shared_data_dir`)."""
        return shared_data_dir(required=required)


@dataclass(frozen=True, slots=True)
class ExtraResult:
    """What an experiment's ``extra`` step returns.

    Attributes
    ----------
    results : dict
        JSON-able entries added to ``results.json`` after the summary.
    artifacts : object
        In-memory values the figures need but ``results.json`` does not hold (series, fits).
    """

    results: dict[str, Any]
    artifacts: Any = None


@dataclass(frozen=True, slots=True)
class Outcome(Generic[P, R]):
    """Everything a finished reproduction produced, for its figures.

    Attributes
    ----------
    params : P
        The parameters it ran with.
    runs : tuple of R
        Results of the successful Monte Carlo runs, in run order.
    results : dict
        The ``results.json`` content (header, summary, extra).
    artifacts : object
        ``ExtraResult.artifacts``.
    """

    params: P
    runs: tuple[R, ...]
    results: dict[str, Any]
    artifacts: Any = None


class Experiment(ABC, Generic[P, R]):
    """One reproduction of a seed paper: its parameters and the steps the driver calls.

    Subclasses set the class attributes and implement the abstract methods; ``extra``,
    ``figures`` and ``summary_lines`` have empty defaults. Instances must be picklable (a
    module-level class without state does): the Monte Carlo runner ships ``run_one`` to Dask
    workers.

    Attributes
    ----------
    name : str
        Command-line name (``navtrack reproduce NAME``).
    description : str
        One line: paper and what is reproduced.
    params_type : type
        Frozen dataclass of the parameters; every field has a default taken from the paper (its
        docstring cites where). Fields of type bool, int, float, str, Path, ``Literal``, tuples
        of those and ``X | None`` can be set from the command line and TOML files.
    default_runs : int
        Monte Carlo runs of the published-style reproduction.
    """

    name: ClassVar[str]
    description: ClassVar[str]
    params_type: ClassVar[type[Any]]
    default_runs: ClassVar[int]

    def default_params(self) -> P:
        """The parameters of the published-style reproduction (the dataclass defaults)."""
        params: P = self.params_type()
        return params

    @abstractmethod
    def run_one(self, params: P, rng: np.random.Generator) -> R:
        """One Monte Carlo run with its own generator; the result must be picklable."""

    @abstractmethod
    def summarize(self, params: P, runs: Sequence[R]) -> dict[str, Any]:
        """JSON-able summary of the successful runs' results (in run order)."""

    def extra(self, params: P, context: ExperimentContext) -> ExtraResult:
        """The part of the reproduction that is not a Monte Carlo run (default: none)."""
        return ExtraResult({})

    @abstractmethod
    def tables(self, results: dict[str, Any]) -> str:
        """Markdown tables of ``results`` (written to ``tables.md``)."""

    def figures(self, outcome: Outcome[P, R], out_dir: Path) -> Iterable[Path]:
        """Write the figures into ``out_dir``; return or yield their paths (default: none).

        A generator lets the driver report each figure as it is written. May raise ImportError
        when matplotlib is missing; the driver records it.
        """
        return []

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        """Console lines summarising ``results`` beyond the header (default: none)."""
        return []
