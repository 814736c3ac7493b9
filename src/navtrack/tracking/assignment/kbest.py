"""The k best S-D solutions by Murty's partitioning, with exact or relaxed cells.

A *cell* of the partition is the set of solutions that hold some forced tuples and avoid some
forbidden ones (:class:`MurtyCell`). The best solution found in a cell, with tuples
``τ_1..τ_r`` besides the forced ones, splits the rest of the cell into ``r`` cells: cell ``j``
forbids ``τ_j`` and forces ``τ_1..τ_{j-1}`` (:func:`murty_children`; Murty 1968 with tuples in
place of matrix cells; Popp, Pattipati & Bar-Shalom 2001 for S-D). Cells wait in a heap by the
cost of their solution; the cheapest is taken next (:func:`sd_kbest`).

**How a cell is solved** (:func:`solve_cell`). Its forced tuples are taken out: their elements
leave the lists (the rest renumbered) and their cost is added; the free tuples touching no
forced element stay, forbidden ones are dropped. What remains is an ordinary S-D problem
except where a forbidden tuple is an element's singleton: that element must then be covered by
a real tuple, which the relaxation's greedy start and recovery (they fall back to singletons)
cannot respect. It gets a *penalty singleton* instead, costing more than the spread of all
costs the cell allows (:func:`cell_remainder`), so that (i) the penalised problem holds every
solution of the cell at its own cost, and its lower bounds are lower bounds of the cell; (ii)
its optimum uses a penalty only if the cell is empty. A relaxation result without penalties is
a solution of the cell; one with a penalty whose lower bound exceeds every cost the cell
allows proves the cell empty; otherwise (and without a start from the parent, below) the cell
is solved by milp when it has at most ``max_exact_tuples`` tuples, else it is counted as
unresolved and its bound kept. A cell with an element that no allowed tuple covers is empty
without a solve.

**Guarantees.** Every solution returned is feasible and in its own cell, so they are pairwise
distinct; they are the ``k`` cheapest of all solutions found, in non-decreasing cost. With
exact cells (milp or 2-D) they are the ``k`` best solutions. With relaxed cells a cell's
solution may be above the cell's optimum, so a better solution may be missed or found later,
and the ranking is approximate: each solution's ``lower_bound`` and ``gap`` bound its cell,
and ``SdKBest.lower_bound[j] = min(cost[j], L)`` bounds the true ``(j + 1)``-th best cost,
``L`` the least bound of the unexplored cells (the cells still in the heap, the last one
taken, the unresolved ones): every solution not returned lies in one of them or costs at
least ``cost[k - 1]``.

**Cheaper Murty.** A cell inherits its parent's lower bound (it is a subset of the parent) and
starts from its parent's solution: with ``τ_j`` replaced by the cheapest cover of its elements
the cell allows, that solution is in the cell, and a relaxed cell returns it when the
relaxation finds nothing cheaper (or keeps a penalty). The partition forces the tuples with
most real elements first, so the later cells have small remainders (often under
``max_exact_tuples``); the forced tuples of a cell are never partitioned on again; a cell with
an element no allowed tuple covers is dropped unsolved; and no cell is split once ``k`` were
taken. Skipping a cell whose inherited bound exceeds the ``k``-th cost found never applies:
the parent was the cheapest cell left, so its bound is below every cost in the heap (a child
bound tighter than the parent's would need the relaxation's multipliers).

References
----------
.. [1] K. G. Murty, "An algorithm for ranking all the assignments in order of increasing
   cost", Operations Research 16(3), 1968.
.. [2] R. L. Popp, K. R. Pattipati, Y. Bar-Shalom, "m-best S-D assignment algorithm with
   application to multitarget tracking", IEEE T-AES 37(1), 2001 (Murty's ranking over S-D
   problems whose cells are solved by Lagrangian relaxation).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.tracking.assignment.problem import (
    MILP_INFEASIBLE,
    SdMethod,
    SdProblem,
    SdSolution,
    SdStatus,
    milp_solve,
)
from navtrack.tracking.assignment.relaxation import MAX_ITER, relaxation_solution, sd_assign

__all__ = [
    "CellOptions",
    "CellRemainder",
    "MurtyCell",
    "SdKBest",
    "cell_remainder",
    "murty_children",
    "sd_kbest",
    "solve_cell",
]


@dataclass(frozen=True, slots=True, eq=False)
class SdKBest:
    """Ranked S-D solutions, best first (:func:`sd_kbest`).

    Attributes
    ----------
    solutions : tuple of SdSolution
        Pairwise distinct feasible solutions in non-decreasing cost. Each carries the
        ``method``, ``status``, ``lower_bound`` and ``gap`` of the solve of its Murty cell:
        its ``lower_bound`` bounds the best solution of that cell.
    lower_bound : (k,) float
        ``lower_bound[j]`` is at most the true ``(j + 1)``-th best cost of the problem:
        ``min(cost[j], L)``, ``L`` the least lower bound of the parts of the solution space
        left unexplored. Rank ``j`` is proven when ``lower_bound[j] == cost[j]`` (a milp
        optimum is proven to HiGHS' default relative gap, 1e-4).
    cells : int
        Murty cells examined (each solved at most once).
    cells_infeasible : int
        Cells found empty: before any solve (an element with no allowed tuple), by milp, or by
        the relaxation's lower bound exceeding every cost the cell allows.
    cells_unresolved : int
        Cells whose relaxation kept a forbidden singleton without proving the cell empty, too
        large for milp and with no start from the parent: no solution of theirs is returned,
        and their lower bounds enter ``lower_bound``.
    """

    solutions: tuple[SdSolution, ...]
    lower_bound: FloatArray
    cells: int
    cells_infeasible: int
    cells_unresolved: int

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def cost(self) -> FloatArray:
        """(k,) costs."""
        return np.array([s.cost for s in self.solutions], dtype=float)

    @property
    def proven(self) -> BoolArray:
        """(k,) whether each cost is proven to be the true cost of its rank."""
        return self.lower_bound >= self.cost


@dataclass(frozen=True, slots=True, eq=False)
class MurtyCell:
    """A Murty cell: the solutions that hold every ``forced`` tuple, the rest from ``free``."""

    forced: IntArray  # tuples in every solution of the cell
    free: BoolArray  # (K,) not forbidden and sharing no real element with a forced tuple
    bound: float  # lower bound on the cell's costs known before solving it (the parent's)
    start: IntArray | None = None  # a solution of the cell known before solving it

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class CellRemainder:
    """The S-D problem left by a cell once its forced tuples are taken out."""

    problem: SdProblem  # remaining elements renumbered; the free tuples, then penalty singletons
    tuple_of: IntArray  # (K',) tuple of the full problem behind each, -1 for a penalty singleton
    forced_cost: float
    max_cost: float  # no solution of the remainder within the cell costs more

    def __post_init__(self) -> None:
        freeze_arrays(self)


def cell_remainder(problem: SdProblem, cell: MurtyCell) -> CellRemainder | None:
    """The cell's remainder problem, None when an element has no allowed tuple left.

    An element whose singleton the cell forbids gets a penalty singleton costing
    ``M = 2 (U - D) + 1``, with ``U`` (``D``) the sum over the remaining elements of the
    largest positive (smallest negative) cost of a free tuple holding it: charging each tuple
    to one of its elements, every solution within the cell costs at most ``U`` and every set
    of disjoint free tuples at least ``D``, so a solution using a penalty costs more than
    ``U + (U - D)``.
    """
    t, n = problem.tuples, problem.sizes
    S = problem.n_lists
    idx = np.flatnonzero(cell.free)
    parts, hi, lo, new_sizes = [], [], [], []
    for s in range(S):
        taken = np.zeros(n[s] + 1, dtype=bool)
        taken[t[cell.forced, s]] = True
        taken[0] = False
        number = np.cumsum(~taken) - 1  # new index of each remaining element, 0 the dummy
        new_sizes.append(int(n[s] - taken.sum()))
        parts.append(number[t[idx, s]])
    tt = np.stack(parts, axis=1)
    c = problem.cost[idx]
    real = tt > 0
    single = real.sum(axis=1) == 1
    extra = []
    for s in range(S):
        top = np.full(new_sizes[s] + 1, -np.inf)
        bottom = np.full(new_sizes[s] + 1, np.inf)
        np.maximum.at(top, tt[:, s], c)
        np.minimum.at(bottom, tt[:, s], c)
        if not np.all(np.isfinite(top[1:])):
            return None  # an element no allowed tuple covers: the cell is empty
        hi.append(np.maximum(top[1:], 0.0).sum())
        lo.append(np.minimum(bottom[1:], 0.0).sum())
        has_single = np.zeros(new_sizes[s] + 1, dtype=bool)
        has_single[tt[single & real[:, s], s]] = True
        for i in np.flatnonzero(~has_single[1:]) + 1:
            row = np.zeros(S, dtype=np.int64)
            row[s] = i
            extra.append(row)
    U, D = float(sum(hi)), float(sum(lo))
    rows = np.array(extra, dtype=np.int64).reshape(-1, S)
    penalty = 2.0 * (U - D) + 1.0
    reduced = SdProblem(
        np.array(new_sizes), np.vstack([tt, rows]), np.r_[c, np.full(len(rows), penalty)]
    )
    return CellRemainder(
        reduced,
        np.r_[idx, np.full(len(rows), -1, dtype=np.int64)],
        float(problem.cost[cell.forced].sum()),
        U,
    )


@dataclass(frozen=True, slots=True)
class CellOptions:
    """How the cells are solved (the options of :func:`sd_kbest`)."""

    method: str
    max_exact_tuples: int
    max_iter: int
    tol: float
    time_limit_s: float | None


def solve_cell(
    problem: SdProblem, cell: MurtyCell, opt: CellOptions
) -> tuple[SdSolution | None, float]:
    """Best solution found in the cell and a lower bound on its costs.

    ``(None, inf)``: the cell is empty. ``(None, bound)``: unresolved (the relaxation kept a
    penalty singleton, the cell is too large for milp and came with no start).
    """
    rem = cell_remainder(problem, cell)
    if rem is None:
        return None, np.inf
    R = rem.problem
    real = rem.tuple_of >= 0
    n_free = int(real.sum())
    head = f"Murty cell with {cell.forced.size} forced and {n_free} free tuples"
    small = n_free <= opt.max_exact_tuples
    too_large = ""
    if opt.method == "exact" and small:
        sol, st = milp_solve(R, real, opt.time_limit_s, "optimal (milp)")
        if sol is not None:
            return _exact_in_cell(problem, cell, rem, sol, head)
        if st == MILP_INFEASIBLE:
            return None, np.inf
        too_large = f"milp found no optimum (status {st})"
        small = False  # milp was tried
    elif opt.method == "exact":
        too_large = f"{n_free} tuples > max_exact_tuples = {opt.max_exact_tuples}"
    relaxed = sd_assign(R, "lagrangian", max_iter=opt.max_iter, tol=opt.tol)
    if relaxed.method != SdMethod.LAGRANGIAN:  # S = 2: the penalised problem solved exactly
        if np.all(real[relaxed.selected]):
            return _exact_in_cell(problem, cell, rem, relaxed, head)
        return None, np.inf
    bound = rem.forced_cost + relaxed.lower_bound
    found = []  # (cost, selected, how)
    if np.all(real[relaxed.selected]):
        mine = np.r_[cell.forced, rem.tuple_of[relaxed.selected]]
        found.append((float(problem.cost[mine].sum()), mine, f"remainder {relaxed.message}"))
    if cell.start is not None:
        how = f"the parent's solution with one tuple re-covered (remainder {relaxed.message})"
        found.append((float(problem.cost[cell.start].sum()), cell.start, how))
    if found:
        _, selected, how = min(found, key=lambda f: f[0])
        sol = relaxation_solution(problem, selected, -np.inf, 0, SdStatus.GAP, "")
        lb = min(max(cell.bound, bound), sol.cost)
        if too_large:
            status = SdStatus.TOO_LARGE
            how = f"exact solver not used ({too_large}); Lagrangian relaxation, {how}"
        else:
            closed = sol.cost - lb <= opt.tol * max(abs(sol.cost), 1e-12)
            status = SdStatus.OPTIMAL if closed else SdStatus.GAP
            how = f"Lagrangian relaxation, {how}"
        message = f"{head}: {how}"
        it = relaxed.iterations
        return relaxation_solution(problem, sol.selected, lb, it, status, message), lb
    # a penalty singleton was kept: the cell is empty, or the relaxation missed its solutions
    if relaxed.lower_bound > rem.max_cost + 1e-9 * max(1.0, abs(rem.max_cost)):
        return None, np.inf
    if small:
        how = "optimal (milp; the relaxation kept a penalty)"
        sol, st = milp_solve(R, real, opt.time_limit_s, how)
        if sol is not None:
            return _exact_in_cell(problem, cell, rem, sol, head)
        if st == MILP_INFEASIBLE:
            return None, np.inf
    return None, max(cell.bound, bound)


def _exact_in_cell(
    problem: SdProblem, cell: MurtyCell, rem: CellRemainder, sol: SdSolution, head: str
) -> tuple[SdSolution, float]:
    """The remainder's exact solution as a solution of the full problem in ``cell``."""
    selected = np.sort(np.r_[cell.forced, rem.tuple_of[sol.selected]])
    cost = float(problem.cost[selected].sum())
    message = f"{head}: {sol.message}"
    out = SdSolution.from_selection(
        problem,
        selected,
        lower_bound=cost,
        iterations=0,
        method=sol.method,
        status=SdStatus.OPTIMAL,
        message=message,
    )
    return out, cost


def _cover(problem: SdProblem, free: BoolArray, tau: int) -> IntArray | None:
    """Cheapest set of ``free`` tuples covering exactly the real elements of tuple ``tau``
    (exact cover by dynamic programming over the ``<= S`` elements), None if there is none."""
    t = problem.tuples
    row = t[tau]
    cand = np.flatnonzero(free & np.all((t == 0) | (t == row), axis=1))
    pos = np.flatnonzero(row > 0)
    bits = ((t[cand][:, pos] > 0) @ (1 << np.arange(pos.size))).tolist()
    costs = problem.cost[cand].tolist()
    full = (1 << pos.size) - 1
    best = [np.inf] * (full + 1)
    back: list[tuple[int, int]] = [(0, -1)] * (full + 1)
    best[0] = 0.0
    for mask in range(full):
        if best[mask] == np.inf:
            continue
        low = ~mask & (mask + 1)  # the first element not yet covered
        for b, c, k in zip(bits, costs, cand.tolist(), strict=True):
            if b & low and not b & mask and best[mask] + c < best[mask | b]:
                best[mask | b] = best[mask] + c
                back[mask | b] = (mask, k)
    if best[full] == np.inf:
        return None
    out, mask = [], full
    while mask:
        mask, k = back[mask]
        out.append(k)
    return np.array(out, dtype=np.int64)


def murty_children(problem: SdProblem, cell: MurtyCell, sol: SdSolution) -> list[MurtyCell]:
    """Murty's partition of ``cell`` minus ``sol``: with ``τ_1..τ_r`` the tuples of ``sol``
    the cell does not force, child ``j`` forbids ``τ_j`` and forces ``τ_1..τ_{j-1}``.

    The tuples with most real elements go first, so the later children (most forced
    elements) have the smallest remainders. Each child starts from ``sol`` with ``τ_j``
    replaced by the cheapest cover of its elements that the child allows (:func:`_cover`).
    """
    t = problem.tuples
    mine = sol.selected[~np.isin(sol.selected, cell.forced)]
    mine = mine[np.argsort(-(t[mine] > 0).sum(axis=1), kind="stable")]
    free, forced = cell.free.copy(), cell.forced
    out = []
    for tau in mine.tolist():
        child = free.copy()
        child[tau] = False
        cover = _cover(problem, child, tau)
        start = None if cover is None else np.r_[sol.selected[sol.selected != tau], cover]
        out.append(MurtyCell(forced, child, sol.lower_bound, start))
        free &= ~np.any((t == t[tau]) & (t[tau] > 0), axis=1)  # force tau: drop its clashes
        forced = np.append(forced, tau)
    return out


@dataclass
class _MurtySearch:
    """The cells waiting in a heap by the cost of their solution, and the counts of
    :class:`SdKBest`."""

    problem: SdProblem
    options: CellOptions
    heap: list[tuple[float, int, SdSolution, MurtyCell]] = field(default_factory=list)
    unexplored: list[float] = field(default_factory=list)  # bounds of the parts not searched
    cells: int = 0
    infeasible: int = 0
    unresolved: int = 0

    def add(self, cell: MurtyCell) -> None:
        """Solve ``cell`` and keep its solution in the heap, or count it."""
        self.cells += 1
        sol, bound = solve_cell(self.problem, cell, self.options)
        if sol is not None:
            heapq.heappush(self.heap, (sol.cost, self.cells, sol, cell))
        elif bound == np.inf:
            self.infeasible += 1
        else:
            self.unresolved += 1
            self.unexplored.append(bound)

    def result(self, taken: list[SdSolution], k: int) -> SdKBest:
        """The ``k`` cheapest of the solutions taken and still waiting."""
        found = taken + [item[2] for item in self.heap]
        unexplored = self.unexplored + [item[2].lower_bound for item in self.heap]
        best = np.argsort([s.cost for s in found], kind="stable")[:k]
        out = tuple(found[i] for i in best)
        cost = np.array([s.cost for s in out], dtype=float)
        return SdKBest(
            solutions=out,
            lower_bound=np.minimum(cost, min(unexplored, default=np.inf)),
            cells=self.cells,
            cells_infeasible=self.infeasible,
            cells_unresolved=self.unresolved,
        )


def sd_kbest(
    problem: SdProblem,
    k: int,
    method: str = "exact",
    *,
    max_exact_tuples: int = 5000,
    max_iter: int = MAX_ITER,
    tol: float = 1e-3,
    time_limit_s: float | None = None,
) -> SdKBest:
    """The ``k`` best S-D solutions (fewer if fewer exist) by Murty's partitioning (module
    notes: how a cell is solved, what is guaranteed).

    Parameters
    ----------
    problem : SdProblem
    k : int >= 1
    method : {"exact", "auto", "lagrangian"}
        As in :func:`~navtrack.tracking.assignment.relaxation.sd_assign`, per cell (the size
        rule applies to the cell's remainder). ``"exact"`` (default): milp on cells of at most
        ``max_exact_tuples`` tuples, the relaxation on larger ones (``status`` TOO_LARGE).
        ``"lagrangian"``, ``"auto"``: the relaxation on every cell (2-D assignment when
        ``S = 2``); milp only for an unresolved forbidden singleton.
    max_exact_tuples : int
        Size limit of milp, as in ``sd_assign``. Default 5000.
    max_iter, tol : relaxation limits per cell (``sd_lagrangian``)
    time_limit_s : float or None
        Per milp solve; a cell that runs out of time is solved by relaxation (TOO_LARGE).
    """
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be an integer >= 1, got {k!r}")
    if method not in ("auto", "exact", "lagrangian"):
        raise ValueError(f"method must be 'auto', 'exact' or 'lagrangian', got {method!r}")
    if max_exact_tuples < 0:
        raise ValueError(f"max_exact_tuples must be >= 0, got {max_exact_tuples}")
    if time_limit_s is not None and not time_limit_s > 0:
        raise ValueError(f"time_limit_s must be > 0 or None, got {time_limit_s}")
    options = CellOptions(
        method=method,
        max_exact_tuples=max_exact_tuples,
        max_iter=max_iter,
        tol=tol,
        time_limit_s=time_limit_s,
    )
    search = _MurtySearch(problem, options)
    search.add(MurtyCell(np.zeros(0, dtype=np.int64), np.ones(len(problem.tuples), bool), -np.inf))
    taken: list[SdSolution] = []
    while search.heap and len(taken) < k:
        _, _, sol, cell = heapq.heappop(search.heap)
        taken.append(sol)
        if len(taken) == k:
            search.unexplored.append(sol.lower_bound)  # the rest of its cell
            break
        for child in murty_children(problem, cell, sol):
            search.add(child)
    return search.result(taken, k)
