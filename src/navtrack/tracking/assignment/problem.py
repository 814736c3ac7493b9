"""The S-D assignment problem with the dummy index, its solutions, and the exact and greedy solvers.

``S`` lists, list ``s`` holding ``n_s`` real elements numbered ``1..n_s``; index ``0`` is the
dummy (no element of that list: "no detection" of a sensor, "no target" in the target list).
A candidate *tuple* ``(i_1, ..., i_S)`` (not all zero) has a cost; a solution is a set of
tuples covering every real index of every list exactly once (the dummy may be used any number
of times). As an integer programme: ``min Σ c x`` s.t. ``Σ_{tuples with i_s = i} x = 1`` for
every list ``s`` and real ``i``, ``x ∈ {0, 1}`` (Deb et al. 1997, eq. 6-9). Every real index
must have its *singleton* tuple (that index with dummies elsewhere), so a solution always
exists: all singletons.

:func:`sd_exact` solves the integer programme by ``scipy.optimize.milp`` (HiGHS branch and
bound); :func:`sd_greedy` takes tuples in increasing cost. The Lagrangian relaxation is in
:mod:`navtrack.tracking.assignment.relaxation`.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_matrix

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = [
    "MILP_INFEASIBLE",
    "SdMethod",
    "SdProblem",
    "SdSolution",
    "SdStatus",
    "milp_solve",
    "random_sd_problem",
    "sd_exact",
    "sd_greedy",
]


class SdMethod(IntEnum):
    """How an S-D solution was found (``SdSolution.method``)."""

    EXACT = 0  # integer programme by scipy.optimize.milp (HiGHS branch and bound)
    LAGRANGIAN = 1  # Lagrangian relaxation with recovery; optimal when the gap closed
    GREEDY = 2  # tuples in increasing cost while their indices are free


class SdStatus(IntEnum):
    """Outcome of an S-D solve (``SdSolution.status``)."""

    OPTIMAL = 0  # exact optimum, or duality gap within the tolerance
    GAP = 1  # feasible, stopped at the iteration limit with the gap above the tolerance
    TOO_LARGE = 2  # exact solver asked for but too large: relaxation result, gap reported
    HEURISTIC = 3  # greedy: no bound


@dataclass(frozen=True, slots=True, eq=False)
class SdProblem:
    """A sparse S-D assignment problem with the dummy index 0.

    Parameters
    ----------
    sizes : (S,) int
        ``n_s``, the number of real elements of list ``s`` (indices ``1..n_s``).
    tuples : (K, S) int
        Candidate tuples, index 0 = dummy; no all-dummy tuple, no tuple twice.
    cost : (K,) float
        Finite cost of each tuple.

    Raises
    ------
    ValueError
        Naming the parameter: wrong shapes, indices out of ``0..n_s``, an all-dummy or repeated
        tuple, a non-finite cost, or a real index without its singleton tuple.
    """

    sizes: IntArray
    tuples: IntArray
    cost: FloatArray

    def __post_init__(self) -> None:
        n = np.array(self.sizes, dtype=np.int64).reshape(-1)
        tup = np.array(self.tuples, dtype=np.int64)
        c = np.array(self.cost, dtype=float).reshape(-1)
        S = n.size
        if S < 2 or np.any(n < 0):
            raise ValueError(f"sizes: need >= 2 lists of >= 0 elements, got {n.tolist()}")
        if tup.ndim != 2 or tup.shape[1] != S:
            raise ValueError(f"tuples must be (K, {S}) for {S} lists, got shape {tup.shape}")
        if c.shape != (tup.shape[0],):
            raise ValueError(f"cost must be ({tup.shape[0]},), got shape {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("cost must be finite (leave a forbidden tuple out of the list)")
        bad = (tup < 0) | (tup > n)
        if np.any(bad):
            k, s = np.argwhere(bad)[0]
            raise ValueError(f"tuples[{k}, {s}] = {tup[k, s]} is outside 0..{n[s]}")
        real = tup > 0
        if np.any(~real.any(axis=1)):
            raise ValueError(f"tuples[{int(np.flatnonzero(~real.any(axis=1))[0])}] is all dummy")
        if len(np.unique(tup, axis=0)) != len(tup):
            raise ValueError("tuples: a tuple is listed twice")
        single = real.sum(axis=1) == 1
        for s in range(S):
            have = np.zeros(n[s] + 1, dtype=bool)
            have[tup[single & real[:, s], s]] = True
            if not np.all(have[1:]):
                i = int(np.flatnonzero(~have[1:])[0]) + 1
                raise ValueError(f"tuples: list {s} element {i} has no singleton tuple")
        object.__setattr__(self, "sizes", n)
        object.__setattr__(self, "tuples", tup)
        object.__setattr__(self, "cost", c)
        freeze_arrays(self)

    @property
    def n_lists(self) -> int:
        """``S``."""
        return int(self.sizes.size)

    def is_feasible(self, selected: ArrayLike) -> bool:
        """Whether the tuples ``selected`` (indices into ``tuples``) cover each real index once."""
        sel = np.asarray(selected, dtype=np.int64)
        return all(
            np.array_equal(
                np.bincount(self.tuples[sel, s], minlength=self.sizes[s] + 1)[1:],
                np.ones(self.sizes[s], dtype=np.int64),
            )
            for s in range(self.n_lists)
        )

    def subset(self, keep: BoolArray) -> SdProblem:
        """The problem restricted to the tuples where ``keep`` is True."""
        return SdProblem(self.sizes, self.tuples[keep], self.cost[keep])


@dataclass(frozen=True, slots=True, eq=False)
class SdSolution:
    """Solution of an :class:`SdProblem` (arrays read-only).

    Attributes
    ----------
    selected : (r,) int
        Indices of the chosen tuples in ``problem.tuples``, ascending.
    tuples : (r, S) int
        The chosen tuples.
    cost : float
        Their total cost (the upper bound).
    lower_bound : float
        Best Lagrangian lower bound (``cost`` for an exact solution, ``-inf`` for greedy).
    gap : float
        ``cost - lower_bound`` (0 exact, ``inf`` greedy).
    relative_gap : float
        ``gap / max(|cost|, 1e-12)``.
    iterations : int
        Multiplier updates (0 for exact and greedy).
    method : SdMethod
    status : SdStatus
    message : str
    """

    selected: IntArray
    tuples: IntArray
    cost: float
    lower_bound: float
    gap: float
    relative_gap: float
    iterations: int
    method: SdMethod
    status: SdStatus
    message: str

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @classmethod
    def from_selection(
        cls,
        problem: SdProblem,
        selected: ArrayLike,
        *,
        lower_bound: float,
        iterations: int,
        method: SdMethod,
        status: SdStatus,
        message: str,
    ) -> SdSolution:
        """The solution choosing the tuples ``selected`` of ``problem`` (any order), its cost,
        gap and relative gap computed from ``lower_bound``."""
        sel = np.sort(np.asarray(selected, dtype=np.int64))
        cost = float(problem.cost[sel].sum())
        gap = cost - lower_bound
        return cls(
            selected=sel,
            tuples=problem.tuples[sel],
            cost=cost,
            lower_bound=lower_bound,
            gap=gap,
            relative_gap=gap / max(abs(cost), 1e-12),
            iterations=iterations,
            method=method,
            status=status,
            message=message,
        )


def random_sd_problem(
    sizes: ArrayLike, rng: np.random.Generator, density: float = 1.0
) -> SdProblem:
    """A random S-D problem with dummies, for tests and benchmarks.

    Every singleton costs 0 (an element left unassigned: false alarm / missed target); every
    other tuple of the full grid ``Π (n_s + 1)`` is kept with probability ``density`` and costs
    ``-Σ_{real i_s} (1 + u)`` plus ``N(0, 2)``-ish spread, ``u ~ U(0, 1)``: tuples with more real
    elements gain more, as log-likelihood ratios of detections from one source do, and the
    lists compete for the same elements.

    Parameters
    ----------
    sizes : (S,) int, elements per list
    rng : Generator
    density : float in (0, 1], share of the non-singleton tuples kept
    """
    n = np.asarray(sizes, dtype=np.int64)
    if not 0 < density <= 1:
        raise ValueError(f"density must be in (0, 1], got {density}")
    grid = np.stack(np.meshgrid(*[np.arange(k + 1) for k in n], indexing="ij"), -1)
    tup = grid.reshape(-1, n.size)
    n_real = (tup > 0).sum(axis=1)
    tup, n_real = tup[n_real > 0], n_real[n_real > 0]
    keep = (n_real == 1) | (rng.random(len(tup)) < density)
    tup, n_real = tup[keep], n_real[keep]
    gain = n_real * (1.0 + rng.random(len(tup))) + 2.0 * rng.standard_normal(len(tup))
    cost = np.where(n_real == 1, 0.0, -(gain - 1.5 * n_real))
    return SdProblem(n, tup, cost)


def sd_greedy(problem: SdProblem) -> SdSolution:
    """Greedy S-D solution: tuples in increasing cost while all their real indices are free.

    Every index left over is covered by its singleton. No bound (``status`` HEURISTIC).
    """
    width = int(problem.sizes.max()) + 1 if problem.n_lists else 1
    order = np.argsort(problem.cost, kind="stable")
    elem = problem.tuples[order] + width * np.arange(problem.n_lists)  # flat element indices
    dummies = set(range(0, width * problem.n_lists, width))
    used: set[int] = set()
    chosen: list[int] = []
    n_real = int(problem.sizes.sum())
    for k, row in zip(order.tolist(), elem.tolist(), strict=True):
        real = set(row) - dummies
        if used.isdisjoint(real):
            chosen.append(k)
            used |= real
            if len(used) == n_real:
                break
    return SdSolution.from_selection(
        problem,
        np.array(chosen, dtype=np.int64),
        lower_bound=-np.inf,
        iterations=0,
        method=SdMethod.GREEDY,
        status=SdStatus.HEURISTIC,
        message="greedy",
    )


def _constraint_matrix(problem: SdProblem) -> csr_matrix:
    """Sparse ``(Σ n_s, K)`` incidence of real indices and tuples."""
    offs = np.concatenate([[0], np.cumsum(problem.sizes)])
    rows, cols = [], []
    for s in range(problem.n_lists):
        k = np.flatnonzero(problem.tuples[:, s] > 0)
        rows.append(offs[s] + problem.tuples[k, s] - 1)
        cols.append(k)
    r, c = np.concatenate(rows), np.concatenate(cols)
    return csr_matrix((np.ones(r.size), (r, c)), shape=(int(offs[-1]), len(problem.tuples)))


def sd_exact(problem: SdProblem, time_limit_s: float | None = None) -> SdSolution | None:
    """Exact S-D solution as a 0/1 integer programme (``scipy.optimize.milp``, HiGHS).

    Returns None when the time limit was hit before an optimum.
    """
    allowed = np.ones(len(problem.tuples), dtype=bool)
    return milp_solve(problem, allowed, time_limit_s, "optimal (milp)")[0]


#: ``scipy.optimize.milp`` status "problem is infeasible".
MILP_INFEASIBLE = 2


def milp_solve(
    problem: SdProblem, allowed: BoolArray, time_limit_s: float | None, message: str
) -> tuple[SdSolution | None, int]:
    """Exact solution over the ``allowed`` tuples (None if infeasible or out of time) and the
    ``scipy.optimize.milp`` status (0 optimal, 1 time limit, :data:`MILP_INFEASIBLE`)."""
    idx = np.flatnonzero(allowed)
    if idx.size == 0:
        if problem.sizes.sum() > 0:
            return None, MILP_INFEASIBLE
        return _exact(problem, idx, 0.0, message), 0
    A = _constraint_matrix(problem)[:, idx]
    options = {} if time_limit_s is None else {"time_limit": time_limit_s}
    res = milp(
        problem.cost[idx],
        constraints=LinearConstraint(A, 1.0, 1.0),
        integrality=np.ones(idx.size),
        bounds=Bounds(0.0, 1.0),
        options=options,
    )
    if res.status != 0 or res.x is None:
        return None, int(res.status)
    sel = idx[res.x > 0.5]
    lb = float(problem.cost[sel].sum())
    return _exact(problem, sel, lb, message), 0


def _exact(problem: SdProblem, selected: IntArray, lb: float, message: str) -> SdSolution:
    return SdSolution.from_selection(
        problem,
        selected,
        lower_bound=lb,
        iterations=0,
        method=SdMethod.EXACT,
        status=SdStatus.OPTIMAL,
        message=message,
    )
