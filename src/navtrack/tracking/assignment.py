"""2-D assignment with missed-detection costs, Murty's k-best assignments, and S-D assignment.

A *track-oriented* assignment gives every track ``t`` either one measurement ``j`` (cost
``cost[t, j]``, ``inf`` = forbidden, e.g. outside the gate) or none (cost ``miss_cost[t]``); each
measurement is used at most once. It is solved exactly on ``scipy.optimize.linear_sum_assignment``
by augmenting the ``T × M`` cost matrix with ``T`` private "missed" columns (column ``M + t`` is
allowed for track ``t`` only), so every track row is always assignable.

References
----------
.. [1] K. G. Murty, "An algorithm for ranking all the assignments in order of increasing
   cost", Operations Research 16(3), 1968.
.. [2] I. J. Cox, M. L. Miller, "On finding ranked assignments with application to
   multitarget tracking and motion correspondence", IEEE T-AES 31(1), 1995.
.. [3] S. S. Blackman, R. Popoli, *Design and Analysis of Modern Tracking Systems*, Artech
   House 1999, section 6.5 (GNN with missed-detection costs).
.. [4] S. Deb, M. Yeddanapudi, K. Pattipati, Y. Bar-Shalom, "A generalized S-D assignment
   algorithm for multisensor-multitarget state estimation", IEEE T-AES 33(2), 1997
   (relaxation of S - 2 constraint sets, 2-D subproblems, recovery of a feasible solution).
.. [5] A. B. Poore, N. Rijavec, "A Lagrangian relaxation algorithm for multidimensional
   assignment problems arising from multitarget tracking", SIAM J. Optim. 3(3), 1993.
.. [6] M. Held, P. Wolfe, H. P. Crowder, "Validation of subgradient optimization", Math.
   Programming 6, 1974 (Polyak step with a halving step factor).
.. [8] R. L. Popp, K. R. Pattipati, Y. Bar-Shalom, "m-best S-D assignment algorithm with
   application to multitarget tracking", IEEE T-AES 37(1), 2001 (Murty's ranking over S-D
   problems whose cells are solved by Lagrangian relaxation).

S-D assignment (``S >= 3`` lists, :func:`sd_assign`) is described in the section comment
before :class:`SdProblem`; its k best solutions (:func:`sd_kbest`) in that function's notes.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import IntEnum
from functools import cache, lru_cache

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._numba import jit
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = [
    "Assignment",
    "KBest",
    "SdKBest",
    "SdMethod",
    "SdProblem",
    "SdSolution",
    "SdStatus",
    "assign2d",
    "augmented_cost",
    "compile_kernels",
    "murty",
    "random_sd_problem",
    "sd_assign",
    "sd_exact",
    "sd_greedy",
    "sd_kbest",
    "sd_lagrangian",
]


@dataclass(frozen=True, slots=True, eq=False)
class Assignment:
    """One assignment: ``track_to_meas[t]`` is a measurement index or ``-1`` (missed)."""

    track_to_meas: IntArray
    cost: float

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class KBest:
    """Ranked assignments, best first.

    Attributes
    ----------
    track_to_meas : (k, T) int, ``-1`` = missed
    cost : (k,) non-decreasing total costs
    """

    track_to_meas: IntArray
    cost: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _check(cost: ArrayLike, miss_cost: ArrayLike) -> tuple[FloatArray, FloatArray]:
    C = np.asarray(cost, dtype=float)
    if C.ndim != 2:
        raise ValueError(f"cost must be a (T, M) matrix, got shape {C.shape}")
    miss = np.broadcast_to(np.asarray(miss_cost, dtype=float), (C.shape[0],))
    if not np.all(-np.inf < C):  # (False for NaN too)
        raise ValueError("cost must not contain NaN or -inf (use +inf for forbidden pairs)")
    if not np.all(np.isfinite(miss)):
        raise ValueError("miss_cost must be finite")
    return C, miss


def augmented_cost(cost: ArrayLike, miss_cost: ArrayLike) -> FloatArray:
    """The ``T × (M + T)`` matrix ``[cost | diag(miss_cost)]`` with ``inf`` off the diagonal."""
    C, miss = _check(cost, miss_cost)
    T, M = C.shape
    A = np.full((T, M + T), np.inf)
    A[:, :M] = C
    A[np.arange(T), M + np.arange(T)] = miss
    return A


def _solve(A: FloatArray) -> tuple[IntArray, float] | None:
    """Rows-all-assigned solution of the augmented matrix, or None if infeasible."""
    from scipy.optimize import linear_sum_assignment

    if A.shape[0] == 0:
        return np.zeros(0, dtype=np.int64), 0.0
    try:
        rows, cols = linear_sum_assignment(A)
    except ValueError:  # "cost matrix is infeasible"
        return None
    total = float(A[rows, cols].sum())
    if not np.isfinite(total):
        return None
    out = np.empty(A.shape[0], dtype=np.int64)
    out[rows] = cols
    return out, total


def _to_meas(cols: IntArray, M: int) -> IntArray:
    return np.where(cols < M, cols, -1).astype(np.int64)


def assign2d(cost: ArrayLike, miss_cost: ArrayLike) -> Assignment:
    """Optimal track-oriented assignment with missed-detection costs.

    Parameters
    ----------
    cost : (T, M) cost of assigning measurement ``j`` to track ``t``; ``inf`` forbids the pair
    miss_cost : (T,) or scalar, cost of track ``t`` taking no measurement

    Returns
    -------
    Assignment
    """
    A = augmented_cost(cost, miss_cost)
    sol = _solve(A)
    if sol is None:  # cannot happen: the miss columns always give a feasible solution
        raise ValueError("assignment infeasible")
    cols, total = sol
    return Assignment(_to_meas(cols, A.shape[1] - A.shape[0]), total)


def murty(cost: ArrayLike, miss_cost: ArrayLike, k: int) -> KBest:
    """Murty's k best track-oriented assignments (fewer if fewer exist).

    Each node of the search is the augmented matrix with some pairs forbidden (``inf``) and some
    rows fixed; a solved node is split on its free rows in turn (Murty 1968), children kept in a
    heap by their optimal cost. Solutions are returned in non-decreasing cost; ties come in
    heap order.

    Parameters
    ----------
    cost : (T, M), miss_cost : (T,) or scalar
    k : int >= 1
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    A0 = augmented_cost(cost, miss_cost)
    T, W = A0.shape
    M = W - T
    sol = _solve(A0)
    if sol is None:
        raise ValueError("assignment infeasible")
    counter = 0
    # heap items: (cost, tiebreak, solution cols, matrix with exclusions, fixed-rows mask)
    heap: list[tuple[float, int, IntArray, FloatArray, np.ndarray]] = [
        (sol[1], counter, sol[0], A0, np.zeros(T, dtype=bool))
    ]
    out_cols: list[IntArray] = []
    out_cost: list[float] = []
    while heap and len(out_cols) < k:
        c, _, cols, A, fixed = heapq.heappop(heap)
        out_cols.append(cols)
        out_cost.append(c)
        if len(out_cols) == k:
            break
        # partition on the free rows
        A_child = A.copy()
        fixed_child = fixed.copy()
        for r in np.flatnonzero(~fixed):
            B = A_child.copy()
            B[r, cols[r]] = np.inf
            s = _solve_fixed(B, fixed_child, cols)
            if s is not None:
                counter += 1
                heapq.heappush(heap, (s[1], counter, s[0], B, fixed_child.copy()))
            # for the next child, row r is fixed to its current column
            keep = A_child[r, cols[r]]
            A_child[r, :] = np.inf
            A_child[:, cols[r]] = np.inf
            A_child[r, cols[r]] = keep
            fixed_child[r] = True
    return KBest(
        np.array([_to_meas(c, M) for c in out_cols], dtype=np.int64).reshape(-1, T),
        np.array(out_cost, dtype=float),
    )


def _solve_fixed(B: FloatArray, fixed: np.ndarray, cols: IntArray) -> tuple[IntArray, float] | None:
    """Solve ``B`` with ``fixed`` rows pinned to ``cols`` (solving only the free sub-matrix)."""
    free_r = np.flatnonzero(~fixed)
    used = np.zeros(B.shape[1], dtype=bool)
    used[cols[fixed]] = True
    free_c = np.flatnonzero(~used)
    sub = _solve(B[np.ix_(free_r, free_c)])
    if sub is None:
        return None
    out = cols.copy()
    out[free_r] = free_c[sub[0]]
    total = float(B[np.arange(B.shape[0]), out].sum())
    if not np.isfinite(total):
        return None
    return out, total


# --------------------------------------------------------------------------------------------
# S-D assignment with the dummy index
# --------------------------------------------------------------------------------------------
#
# ``S`` lists, list ``s`` holding ``n_s`` real elements numbered ``1..n_s``; index ``0`` is the
# dummy (no element of that list: "no detection" of a sensor, "no target" in the target list).
# A candidate *tuple* ``(i_1, ..., i_S)`` (not all zero) has a cost; a solution is a set of
# tuples covering every real index of every list exactly once (the dummy may be used any number
# of times).  As an integer programme: ``min Σ c x`` s.t. ``Σ_{tuples with i_s = i} x = 1`` for
# every list ``s`` and real ``i``, ``x ∈ {0, 1}`` (Deb et al. 1997, eq. 6-9).  Every real index
# must have its *singleton* tuple (that index with dummies elsewhere), so a solution always
# exists: all singletons.
#
# Lagrangian relaxation (Deb et al. 1997, section III; Poore & Rijavec 1993): the constraints of
# lists 3..S are moved into the objective with multipliers ``u_s (n_s + 1)`` (``u_s[0] = 0``),
# reduced costs ``c - Σ_s u_s[i_s]``.  What remains is a 2-D assignment of lists 1 and 2 with
# dummies: pair ``(i_1, i_2)`` costs the least reduced cost of its tuples, and the tuples with
# ``i_1 = i_2 = 0`` are free (taken when their reduced cost is negative).  Its optimum plus
# ``Σ u`` is a lower bound; the multipliers climb it by subgradient steps
# ``u += α (UB - LB) g / |g|²`` (Polyak step, ``α`` halved after ``patience`` iterations without
# progress, Held, Wolfe & Crowder 1974) with ``g = 1 - (times each index is used)``; each
# iteration is a few vectorised passes over the tuple arrays and one ``linear_sum_assignment``.
# A feasible solution is recovered (when the bound improved, and every ``recover_every``
# iterations) from the pairs the 2-D solution chose: they are fixed as partial tuples and list
# 3, 4, ..., S is joined to them by one 2-D assignment each, costed by the least reduced cost
# over the lists not yet joined (Deb et al. 1997, section IV, in its sequential form); a
# partial tuple may also be dissolved into its singletons, so every step is feasible; a pass
# recovers from each set of pairs once.  Every recovered solution is then improved by a local
# search: tuple insertions (a tuple displaces the chosen tuples it overlaps, their other
# elements fall back to singletons; all gains evaluated at once, compiled by numba when it is
# installed) alternating with dimension-wise variation (Karapetyan & Gutin 2011: cut every
# chosen tuple between two sides of the lists and re-pair the parts by an exact 2-D
# assignment; every one of the ``2^(S-1) - 1`` splits of the lists, not only one list against
# the rest).  The best feasible cost is the upper bound; ``UB - LB`` is the duality gap
# reported.  While the gap stays open the problem is solved again with its lists reordered
# (other lists relaxed, other pairs fixed): the S rotations, and for S >= 5 also the orders
# keeping each other pair of lists; the recoveries differ, and that, with the local search,
# is what brings the sparse S = 4, 5 problems within 1 % of the optimum
# (``benchmarks/bench_sd_assignment.py``).  A later pass starts where the best bound so far
# stands: the lists it relaxes keep their multipliers, and the two lists that were kept get
# theirs from the dual of that bound's 2-D problem (potentials of the augmented assignment by
# Bellman-Ford on its residual graph), so together they are a dual of the whole problem and
# the pass climbs on from there with a smaller step factor (``_WARM_ALPHA``) instead of
# starting again at zero.
#
# Defaults: 45 multiplier updates per pass; every rotation for S <= 4, every pair of lists for
# S >= 5; recovery every 3 iterations; step factor 2 for the first pass and 0.5 for the
# warm-started ones. How they were chosen and judged: docs/multisensor.md, "S-D relaxation
# defaults".
#
# Cost: on the 4-list benchmark problems (~4400 tuples) a solve is ~180 multiplier updates,
# ~60 recoveries and as many local searches; the variation (its 2-D assignments), the recovery
# and the updates take most of the time.  What does not change during a solve is built once
# per list order (``_prep``: the 2-D matrix with its fixed entries, the tuples in runs of equal
# (pair, i_3) for the recovery, flat element indices and each tuple's excess over its
# singletons for the insertions), so each step is a few array operations on the tuples
# concerned.  The last list of a recovery needs no minimum (a prefix and i_S fix one tuple).
#
# .. [7] D. Karapetyan, G. Gutin, "Local search heuristics for the multidimensional
#    assignment problem", J. Heuristics 17(3), 2011 (dimension-wise variation).


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


def _solution(
    problem: SdProblem,
    selected: IntArray,
    lb: float,
    iterations: int,
    method: SdMethod,
    status: SdStatus,
    message: str,
) -> SdSolution:
    sel = np.sort(np.asarray(selected, dtype=np.int64))
    cost = float(problem.cost[sel].sum())
    gap = cost - lb
    return SdSolution(
        sel,
        problem.tuples[sel],
        cost,
        lb,
        gap,
        gap / max(abs(cost), 1e-12),
        iterations,
        method,
        status,
        message,
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
    return _solution(
        problem,
        np.array(chosen, dtype=np.int64),
        -np.inf,
        0,
        SdMethod.GREEDY,
        SdStatus.HEURISTIC,
        "greedy",
    )


def _constraint_matrix(problem: SdProblem) -> object:
    """Sparse ``(Σ n_s, K)`` incidence of real indices and tuples."""
    from scipy.sparse import csr_matrix

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
    return _milp(problem, allowed, time_limit_s, "optimal (milp)")[0]


_MILP_INFEASIBLE = 2  # scipy.optimize.milp status "problem is infeasible"


def _milp(
    problem: SdProblem, allowed: BoolArray, time_limit_s: float | None, message: str
) -> tuple[SdSolution | None, int]:
    """Exact solution over the ``allowed`` tuples (None if infeasible or out of time) and the
    ``scipy.optimize.milp`` status (0 optimal, 1 time limit, 2 infeasible)."""
    from scipy.optimize import Bounds, LinearConstraint, milp

    idx = np.flatnonzero(allowed)
    if idx.size == 0:
        if problem.sizes.sum() > 0:
            return None, _MILP_INFEASIBLE
        return _solution(problem, idx, 0.0, 0, SdMethod.EXACT, SdStatus.OPTIMAL, message), 0
    A = _constraint_matrix(problem)[:, idx]  # type: ignore[index]
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
    return _solution(problem, sel, lb, 0, SdMethod.EXACT, SdStatus.OPTIMAL, message), 0


# ---------------------------------------------------------------------------- relaxation


@dataclass(frozen=True, slots=True, eq=False)
class _Prep:
    """Index arrays of one problem, built once per solve; ``K`` tuples, ``G`` (list 1, list 2)
    pairs ("groups") among them, ``L = Σ_{s >= 3} (n_s + 1)`` multipliers. Element ``i`` of
    list ``s`` has the flat index ``s · W + i`` in the ``(S, W = max n + 1)`` element tables."""

    tuples: IntArray  # (K, S)
    cost: FloatArray  # (K,)
    cost_inf: FloatArray  # (K + 1,) the costs and inf, picked by the tuple index -1 (none)
    sizes: IntArray  # (S,)
    order: IntArray  # (K,) tuples sorted by group
    starts: IntArray  # (G,) group starts in ``order``
    group_sorted: IntArray  # (K,) group of each sorted tuple
    group: IntArray  # (K,) group of each tuple
    pair: IntArray  # (G, 2) the (i_1, i_2) of each group
    dual_matrix: FloatArray  # (n1 + n2, n2 + n1) 2-D matrix with its fixed entries (0 and inf)
    cell_flat: IntArray  # (G',) flat positions of the groups other than (0, 0) in it
    cell_group: IntArray  # (G',) their group numbers
    cell_lookup: IntArray  # (n1 + n2, n2 + n1) group of each matrix cell, -1 none
    zero_group: int  # group of the pair (0, 0), -1 if none
    seg_order: IntArray  # (K,) tuples sorted by group, then by i_3 (stable)
    seg_starts: IntArray  # (G3 + 1,) starts of the runs of equal (group, i_3) in it, and K
    seg_elem: IntArray  # (G3,) i_3 of each run
    group_seg: IntArray  # (G + 1,) first run of each group, and G3
    free: IntArray  # tuples of the pair (0, 0)
    uidx: IntArray  # (S - 2, K) multiplier of each tuple's index in lists 3..S
    dummies: IntArray  # (S - 2,) positions of the dummies' multipliers (held at 0)
    radix: IntArray  # (S,) mixed-radix weights of the tuple key Σ_s i_s radix_s
    keys: IntArray  # (K,) sorted tuple keys
    key_tuple: IntArray  # (K,) tuple of each sorted key
    table: IntArray  # (Π (n_s + 1),) tuple of each key, -1 = none; empty when too large
    elem: IntArray  # (K, S) flat element index of each tuple's entries
    singleton: IntArray  # (S, W) singleton tuple of each element, -1 for the dummy
    singleton_cost: FloatArray  # (S, W) its cost, 0 for the dummy
    excess: FloatArray  # (K + 1,) cost less that of the elements as singletons; 0 for -1
    gainful: IntArray  # tuples cheaper than their elements as singletons
    gainful_elem: IntArray  # (S, gainful) their flat element indices

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _run_starts(k: IntArray) -> BoolArray:
    """Where a run of equal values of the sorted ``k`` starts."""
    first = np.ones(k.size, dtype=bool)
    first[1:] = k[1:] != k[:-1]
    return first


def _prep(problem: SdProblem) -> _Prep:
    """The index arrays of ``problem`` (:class:`_Prep`)."""
    t, n, c = problem.tuples, problem.sizes, problem.cost
    K, S = t.shape
    n1, n2 = int(n[0]), int(n[1])
    pkey = t[:, 0] * (n2 + 1) + t[:, 1]
    order = np.argsort(pkey, kind="stable")
    ks = pkey[order]
    first = _run_starts(ks)
    starts = np.flatnonzero(first)
    group_sorted = np.cumsum(first) - 1
    group = np.empty(K, dtype=np.int64)
    group[order] = group_sorted
    i1, i2 = np.divmod(ks[starts], n2 + 1)
    real = (i1 > 0) | (i2 > 0)
    rows = np.where(i1 > 0, i1 - 1, n1 + i2 - 1)
    cols = np.where(i2 > 0, i2 - 1, n2 + i1 - 1)
    cell_flat = (rows * (n1 + n2) + cols)[real]
    cell_group = np.flatnonzero(real)
    dual_matrix = np.full((n1 + n2, n2 + n1), np.inf)
    dual_matrix[n1:, n2:] = 0.0
    cell_lookup = np.full(dual_matrix.shape, -1, dtype=np.int64)
    cell_lookup.flat[cell_flat] = cell_group
    zero = np.flatnonzero(~real)
    third = t[:, 2] if S > 2 else np.zeros(K, dtype=np.int64)
    seg_order = np.lexsort((third, group))
    seg_key = (group * (int(n[2:3].sum()) + 1) + third)[seg_order]
    seg_starts = np.flatnonzero(_run_starts(seg_key))
    group_seg = np.searchsorted(group[seg_order[seg_starts]], np.arange(len(starts) + 1))
    off = np.r_[0, np.cumsum(n[2:] + 1)][:-1]
    radix = np.r_[1, np.cumprod(n[:-1] + 1)]
    key = t @ radix
    korder = np.argsort(key)
    span = int(np.prod(n + 1))
    table = np.full(span if span <= _TABLE_MAX else 0, -1, dtype=np.int64)
    if table.size:
        table[key] = np.arange(K)
    width = int(n.max()) + 1 if S else 1
    elem = t + width * np.arange(S)
    singleton = np.full((S, width), -1, dtype=np.int64)
    single = (t > 0).sum(axis=1) == 1
    for s in range(S):
        k = np.flatnonzero(single & (t[:, s] > 0))
        singleton[s, t[k, s]] = k
    singleton_cost = np.append(c, 0.0)[singleton]  # -1 (the dummy) picks the appended 0
    split_cost = singleton_cost.ravel()[elem].sum(axis=1)
    gainful = np.flatnonzero(c < split_cost)
    return _Prep(
        t,
        c,
        np.append(c, np.inf),
        n,
        order,
        starts,
        group_sorted,
        group,
        np.column_stack([i1, i2]),
        dual_matrix,
        cell_flat,
        cell_group,
        cell_lookup,
        int(zero[0]) if zero.size else -1,
        seg_order,
        np.append(seg_starts, K),
        third[seg_order[seg_starts]],
        group_seg,
        np.flatnonzero(pkey == 0),
        np.ascontiguousarray((t[:, 2:] + off).T),
        off,
        radix,
        key[korder],
        korder,
        table,
        elem,
        singleton,
        singleton_cost,
        np.append(c - split_cost, 0.0),
        gainful,
        np.ascontiguousarray(elem[gainful].T),
    )


def _ranges(start: IntArray, length: IntArray) -> IntArray:
    """The ranges ``start[i] .. start[i] + length[i] - 1``, concatenated."""
    return np.arange(int(length.sum())) + np.repeat(start - (np.cumsum(length) - length), length)


def _lsa(A: FloatArray) -> tuple[IntArray, IntArray]:
    """``linear_sum_assignment`` that also takes an empty matrix."""
    from scipy.optimize import linear_sum_assignment

    if A.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    r, c = linear_sum_assignment(A)
    return r.astype(np.int64, copy=False), c.astype(np.int64, copy=False)


def _reduced(prep: _Prep, u: FloatArray, idx: IntArray | None = None, first: int = 0) -> FloatArray:
    """Reduced costs ``c - Σ_s u_s[i_s]`` over the lists ``3 + first..S`` of the tuples ``idx``
    (all when None)."""
    ui = prep.uidx[first:] if idx is None else prep.uidx[first:, idx]
    cost = prep.cost if idx is None else prep.cost[idx]
    if ui.shape[0] == 0:
        return cost
    total = u[ui[0]]
    for row in ui[1:]:
        total += u[row]
    return cost - total


def _pair_matrix(prep: _Prep, u: FloatArray) -> tuple[FloatArray, FloatArray, IntArray, FloatArray]:
    """The relaxed problem for the multipliers ``u`` (L,) of lists 3..S.

    Returns ``(reduced costs (K,), least reduced cost per pair (G,), the first tuple (in pair
    order) reaching it, the augmented 2-D matrix)``: :attr:`_Prep.dual_matrix` with the pairs'
    costs filled in. With numba the reduced costs and the pairs' least ones come from one
    compiled pass over the tuples (:func:`_pair_loop`), the same numbers.
    """
    kernel = _compiled_pairs()
    if kernel is not None:
        red, mins, best = kernel(prep.cost, prep.uidx, u, prep.order, prep.starts)
    else:
        red = _reduced(prep, u)
        rs = red[prep.order]
        mins = np.minimum.reduceat(rs, prep.starts)
        pos = np.flatnonzero(rs <= mins[prep.group_sorted])
        best = prep.order[pos[_run_starts(prep.group_sorted[pos])]]
    A = prep.dual_matrix.copy()
    A.flat[prep.cell_flat] = mins[prep.cell_group]
    return red, mins, best, A


def _pair_loop(
    cost: FloatArray, uidx: IntArray, u: FloatArray, order: IntArray, starts: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """:func:`_pair_matrix`'s reduced costs (summed in :func:`_reduced`'s order), least reduced
    cost per pair and the first tuple reaching it, in scalar loops for numba
    (:func:`_compiled_pairs`)."""
    K = cost.size
    G = starts.size
    red = np.empty(K)
    for k in range(K):
        total = 0.0
        for r in range(uidx.shape[0]):
            total = u[uidx[r, k]] if r == 0 else total + u[uidx[r, k]]
        red[k] = cost[k] - total
    mins = np.empty(G)
    best = np.empty(G, dtype=np.int64)
    for g in range(G):
        end = starts[g + 1] if g + 1 < G else K
        least = np.inf
        arg = -1
        for p in range(starts[g], end):
            if red[order[p]] < least:
                least = red[order[p]]
                arg = order[p]
        mins[g] = least
        best[g] = arg
    return red, mins, best


@lru_cache(maxsize=1)
def _compiled_pairs() -> Callable[..., tuple[FloatArray, FloatArray, IntArray]] | None:
    """:func:`_pair_loop` compiled by numba (on the first call, for the read-only arrays of
    :class:`_Prep` and a writable ``u``), or None without numba."""
    kernel = jit(_pair_loop)
    if kernel is None:
        return None
    tiny = _tiny_prep()
    kernel(tiny.cost, tiny.uidx, np.zeros(2), tiny.order, tiny.starts)
    return kernel


def _dual(prep: _Prep, u: FloatArray) -> tuple[float, IntArray, IntArray]:
    """Optimum of the relaxed problem for the multipliers ``u`` (L,) of lists 3..S.

    Each pair's cost is the least reduced cost ``c - Σ_s u_s[i_s]`` of its tuples (one
    ``minimum.reduceat`` over the tuples sorted by pair); the 2-D problem with dummies is one
    ``linear_sum_assignment`` on the ``(n_1 + n_2) × (n_2 + n_1)`` augmented matrix.

    Returns ``(lower bound, selected tuples, chosen groups other than (0, 0))``.
    """
    red, mins, best, A = _pair_matrix(prep, u)
    r, c = _lsa(A)
    chosen = prep.cell_lookup[r, c]
    chosen = np.sort(chosen[chosen >= 0])
    sel = best[chosen]
    lb = float(mins[chosen].sum() + u.sum())
    neg = prep.free[red[prep.free] < 0]  # tuples of the pair (0, 0) are free in the relaxation
    return lb + float(red[neg].sum()), np.concatenate([sel, neg]), chosen


def _potentials(A: FloatArray, rows: IntArray, cols: IntArray) -> tuple[FloatArray, FloatArray]:
    """Dual potentials ``(a, b)`` of the optimal assignment ``rows -> cols`` of the square
    ``A``: ``a_r + b_c <= A[r, c]``, with equality on the assignment.

    Shortest distances from a source joined to every row by a zero arc, over the arcs
    row -> column (cost ``A``) and assigned column -> row (cost ``-A``): ``b`` = the columns'
    distances, ``a`` = minus the rows'. The assignment is optimal, so there is no negative
    cycle and Bellman-Ford settles within ``2 N`` rounds (ended there in any case).
    """
    N = A.shape[0]
    if N == 0:
        return np.zeros(0), np.zeros(0)
    match = np.empty(N, dtype=np.int64)
    match[rows] = cols
    back = A[np.arange(N), match]
    d_row = np.zeros(N)
    d_col = A.min(axis=0)
    for _ in range(2 * N):
        new = np.minimum(0.0, d_col[match] - back)
        if np.array_equal(new, d_row):
            break
        d_row = new
        d_col = (d_row[:, None] + A).min(axis=0)
    return -d_row, d_col


def _kept_multipliers(prep: _Prep, u: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Multipliers of lists 1 and 2 (each with the dummy's 0 first) that complete ``u`` to a
    dual of the whole problem: the LP dual of the relaxed 2-D problem with dummies.

    From the augmented matrix's potentials ``(a, b)``: ``v_1[i] = a[i] + b[n_2 + i]`` and
    ``v_2[j] = b[j] + a[n_1 + j]`` meet ``v_1[i] + v_2[j] <= m(i, j)``, ``v_1[i] <= m(i, 0)``,
    ``v_2[j] <= m(0, j)`` (the dummy block is 0) and sum to the 2-D optimum.
    """
    A = _pair_matrix(prep, u)[3]
    a, b = _potentials(A, *_lsa(A))
    n1, n2 = int(prep.sizes[0]), int(prep.sizes[1])
    return np.r_[0.0, a[:n1] + b[n2:]], np.r_[0.0, b[:n2] + a[n1:]]


def _recover(prep: _Prep, chosen: IntArray, u: FloatArray) -> IntArray:
    """Feasible solution from the pairs ``chosen`` of lists 1-2 (Deb et al. 1997, section IV).

    The pairs are fixed as partial tuples ("prefixes"); list ``k = 3..S`` is then joined to
    them by one 2-D assignment with dummies whose costs are the least reduced cost over the
    tuples extending (prefix, ``i_k``), reduced by the multipliers of lists ``k + 1..S`` only
    (true costs at ``k = S``, where a prefix and ``i_S`` fix one tuple). A prefix may also be
    dissolved into its singletons, so every step is feasible.
    """
    t, n, cost = prep.tuples, prep.sizes, prep.cost
    S = t.shape[1]
    P = chosen.size
    prefix = np.zeros((P, S), dtype=np.int64)
    prefix[:, :2] = prep.pair[chosen]
    dissolve = prep.singleton_cost[0, prefix[:, 0]] + prep.singleton_cost[1, prefix[:, 1]]
    lut = np.full(len(prep.starts), -1, dtype=np.int64)
    lut[chosen] = np.arange(1, P + 1)
    if prep.zero_group >= 0:
        lut[prep.zero_group] = 0  # prefix 0: nothing fixed yet
    # the tuples of the fixed pairs and of (0, 0), in runs of equal (pair, i_3)
    runs = _ranges(prep.group_seg[:-1][lut >= 0], np.diff(prep.group_seg)[lut >= 0])
    lo = prep.seg_starts[runs]
    length = prep.seg_starts[runs + 1] - lo
    idx = prep.seg_order[_ranges(lo, length)]
    pid = lut[prep.group[idx]]  # prefix of each of these tuples
    out: list[IntArray] = []
    for k in range(2, S):
        width = int(n[k]) + 1
        key = pid * width + t[idx, k]
        flat = np.full((P + 1) * width, np.inf)
        if k == S - 1:  # one tuple per key
            flat[key] = cost[idx]
        elif k == 2:  # least reduced cost over each run
            first = np.cumsum(length) - length
            mins = np.minimum.reduceat(_reduced(prep, u, idx, 1), first)
            flat[pid[first] * width + prep.seg_elem[runs]] = mins
        else:
            red = _reduced(prep, u, idx, k - 1)
            o = np.lexsort((red, key))
            ko = key[o]
            head = _run_starts(ko)
            flat[ko[head]] = red[o[head]]
        M = flat.reshape(P + 1, width)
        nk = width - 1
        use_dis = dissolve < M[1:, 0]
        A = np.full((P + nk, nk + P), np.inf)
        A[:P, :nk] = M[1:, 1:]
        A.flat[nk + (P + nk + 1) * np.arange(P)] = np.minimum(M[1:, 0], dissolve)
        A.flat[(P + nk) * P + (P + nk + 1) * np.arange(nk)] = M[0, 1:]
        A[P:, nk:] = 0.0
        c = _lsa(A)[1]  # the rows in order: the P prefixes, then the list-k elements
        pc, ec = c[:P], c[P:]
        miss = pc >= nk
        joined = np.flatnonzero(~miss)
        stay = np.flatnonzero(miss & ~use_dis)
        new_i = ec[ec < nk]  # list-k elements starting a prefix of their own
        ent_r = np.concatenate([joined, stay, np.full(new_i.size, -1)]) + 1
        ent_c = np.concatenate([pc[joined] + 1, np.zeros(stay.size, dtype=np.int64), new_i + 1])
        dis = prefix[miss & use_dis]
        out.append(prep.singleton[np.nonzero(dis)[1], dis[dis > 0]])
        if k == S - 1:
            arg = np.full(flat.size, -1, dtype=np.int64)
            arg[key] = idx
            out.append(arg[ent_r * width + ent_c])
            break
        prefix = np.vstack([np.zeros((1, S), dtype=np.int64), prefix])[ent_r]
        prefix[:, k] = ent_c
        dissolve = np.concatenate([[0.0], dissolve])[ent_r] + prep.singleton_cost[k, ent_c]
        P = ent_r.size
        new = np.full(flat.size, -1, dtype=np.int64)
        new[0] = 0
        new[ent_r * width + ent_c] = np.arange(1, P + 1)
        pid = new[key]
        idx, pid = idx[pid >= 0], pid[pid >= 0]
    return np.concatenate(out)


_TABLE_MAX = 1 << 21  # largest key space looked up in a dense table (16 MB)


def _lookup(prep: _Prep, key: IntArray) -> IntArray:
    """Tuple with each key (any shape), -1 where there is none."""
    if prep.table.size:
        return prep.table[key]
    pos = np.minimum(np.searchsorted(prep.keys, key), max(len(prep.keys) - 1, 0))
    if len(prep.keys) == 0:
        return np.full(np.shape(key), -1, dtype=np.int64)
    return np.where(prep.keys[pos] == key, prep.key_tuple[pos], -1)


def _improve(prep: _Prep, sel: IntArray, max_rounds: int = 50) -> IntArray:
    """Local search from the feasible ``sel``: insertions (:func:`_insert`), then one round of
    dimension-wise variation (:func:`_vary`), until a round lowers the cost no more."""
    for _ in range(max_rounds):
        sel = _insert(prep, sel)
        cost = float(prep.cost[sel].sum())
        sel = _vary(prep, sel)
        if float(prep.cost[sel].sum()) >= cost - 1e-9 * max(1.0, abs(cost)):
            break
    return sel


def _insert(prep: _Prep, sel: IntArray, max_passes: int = 1000, batch: int = 32) -> IntArray:
    """Tuple insertions while one lowers the cost.

    Inserting tuple ``σ`` displaces the chosen tuples sharing a real element with it; their
    other elements fall back to their singletons. Its gain, for all candidate ``σ`` at once:
    ``c(σ) - s(σ) - Σ_τ (c(τ) - s(τ))`` over the distinct displaced ``τ``, ``s`` = cost of a
    tuple's elements as singletons. Insertions displacing disjoint sets gain independently,
    so each pass makes up to ``batch`` of them, best first; a candidate holding a dummy
    counts as overlapping every other such candidate, so a pass inserts at most one of those.

    With numba the same passes run compiled (:func:`_insert_loop`), one candidate at a time.
    """
    kernel = _compiled_insert()
    if kernel is not None:
        width = prep.singleton.shape[1]
        return kernel(
            np.array(sel, dtype=np.int64),  # writable: one compiled signature
            prep.cost,
            prep.gainful,
            prep.excess,
            prep.elem,
            prep.singleton.ravel(),
            width,
            max_passes,
            batch,
        )
    c, elem, single = prep.cost, prep.elem, prep.singleton.ravel()
    cand, cand_elem, w = prep.gainful, prep.gainful_elem, prep.excess
    base = w[cand]
    S = elem.shape[1]
    dummy = prep.singleton.shape[1] * np.arange(S)  # flat indices of the dummies
    cover = np.full(single.size, -1, dtype=np.int64)  # chosen tuple holding each element
    gone_mask = np.zeros(len(c), dtype=bool)
    for _ in range(max_passes):
        es = elem[sel]
        cover[es.T] = sel
        cover[dummy] = -1
        conf = cover[cand_elem]  # (S, candidates), -1 = dummy
        gain = w[conf]  # w[-1] = 0 for the dummy
        delta = base - gain[0]
        for s in range(1, S):
            again = conf[s] == conf[0]
            for q in range(1, s):
                again |= conf[s] == conf[q]
            np.putmask(gain[s], again, 0.0)  # a displaced tuple counts once
            delta -= gain[s]
        good = np.flatnonzero(delta < -1e-9 * max(1.0, abs(float(c[sel].sum()))))
        if good.size == 0:
            break
        top = good[np.argsort(delta[good])][:batch]
        touched: set[int] = set()
        taken = []
        for b, row in zip(top.tolist(), conf[:, top].T.tolist(), strict=True):
            if touched.isdisjoint(row):
                touched.update(row)
                taken.append(b)
        touched.discard(-1)
        gone_mask[list(touched)] = True
        gone = gone_mask[sel]
        gone_mask[sel] = False
        covered = np.zeros(single.size, dtype=bool)
        covered[cand_elem[:, taken]] = True
        rest = es[gone]
        rest = rest[(rest != dummy) & ~covered[rest]]
        sel = np.concatenate([sel[~gone], cand[taken], single[rest]])
    return sel


def _insert_loop(
    sel: IntArray,
    cost: FloatArray,
    cand: IntArray,
    excess: FloatArray,
    elem: IntArray,
    single: IntArray,
    width: int,
    max_passes: int,
    batch: int,
) -> IntArray:
    """:func:`_insert`'s passes in scalar loops, for numba (:func:`_compiled_insert`): the same
    gains, subtracted in the same order, the same choices and the same order of the result.

    ``touched`` and the displaced tuples are indexed by tuple + 1 (0 = a dummy held).
    """
    S = elem.shape[1]
    G = cand.size
    cover = np.full(single.size, -1, dtype=np.int64)
    delta = np.empty(G)
    held = np.empty(S, dtype=np.int64)  # the chosen tuple holding each element of a candidate
    touched = np.zeros(cost.size + 1, dtype=np.bool_)
    covered = np.zeros(single.size, dtype=np.bool_)
    for _ in range(max_passes):
        for k in sel:
            for s in range(S):
                cover[elem[k, s]] = k
        for s in range(S):
            cover[s * width] = -1
        for b in range(G):
            kb = cand[b]
            d = excess[kb]
            for s in range(S):
                held[s] = cover[elem[kb, s]]
                again = held[s] < 0
                for q in range(s):
                    again |= held[q] == held[s]
                if not again:
                    d -= excess[held[s]]
            delta[b] = d
        good = np.flatnonzero(delta < -1e-9 * max(1.0, abs(cost[sel].sum())))
        if good.size == 0:
            break
        top = good[np.argsort(delta[good])][:batch]
        taken = np.zeros(top.size, dtype=np.int64)
        n_taken = 0
        for b in top:
            free = True
            for s in range(S):
                free &= not touched[cover[elem[cand[b], s]] + 1]
            if free:
                for s in range(S):
                    touched[cover[elem[cand[b], s]] + 1] = True
                    covered[elem[cand[b], s]] = True
                taken[n_taken] = b
                n_taken += 1
        out = np.empty(sel.size + n_taken + S * sel.size, dtype=np.int64)
        m = 0
        for k in sel:
            if not touched[k + 1]:
                out[m] = k
                m += 1
        for j in range(n_taken):
            out[m] = cand[taken[j]]
            m += 1
        for k in sel:
            if touched[k + 1]:
                for s in range(S):
                    e = elem[k, s]
                    if e != s * width and not covered[e]:
                        out[m] = single[e]
                        m += 1
        touched[:] = False
        for j in range(n_taken):
            for s in range(S):
                covered[elem[cand[taken[j]], s]] = False
        sel = out[:m].copy()
    return sel


def _tiny_prep() -> _Prep:
    """The :class:`_Prep` of a 3-list problem of one element each, to compile kernels on."""
    tuples = np.vstack([np.eye(3), np.ones(3)]).astype(np.int64)
    return _prep(SdProblem(np.ones(3, dtype=np.int64), tuples, -np.eye(4)[3]))


@lru_cache(maxsize=1)
def _compiled_insert() -> Callable[..., IntArray] | None:
    """:func:`_insert_loop` compiled by numba, or None without numba: :func:`_insert` then
    runs its NumPy passes. Compiled on the first call for the argument types :func:`_insert`
    passes (a writable ``sel``, the read-only arrays of :class:`_Prep`): about a second, a
    tenth of that when loaded from numba's disk cache."""
    kernel = jit(_insert_loop)
    if kernel is None:
        return None
    tiny = _tiny_prep()
    width = tiny.singleton.shape[1]
    args = (
        tiny.cost,
        tiny.gainful,
        tiny.excess,
        tiny.elem,
        tiny.singleton.ravel(),
    )
    kernel(np.arange(3), *args, width, 1, 1)  # compiled here, for the types _insert passes
    return kernel


def compile_kernels() -> None:
    """Compile the relaxation's numba kernels now (nothing to do without numba), so that no
    timed solve pays for it."""
    _compiled_insert()
    _compiled_splits()
    _compiled_pairs()


def _vary(prep: _Prep, sel: IntArray) -> IntArray:
    """One round of dimension-wise variation (Karapetyan & Gutin 2011) on ``sel``.

    For each split of the lists into two sides (:func:`_splits`) in turn, every chosen tuple is
    cut into its part on one side and its part on the other; the parts are re-paired by one
    exact 2-D assignment with dummies (a part may stand alone when that tuple exists), which
    never costs more than the current pairing. After a split that lowers the cost, the next
    ones cut the new solution.
    """
    sides = _splits(prep.tuples.shape[1])
    current = float(prep.cost[sel].sum())
    done = 0
    while done < len(sides):
        for problem in _split_problems(prep, sel, sides[done:]):
            done += 1
            if problem is None:
                continue
            A, both, alone_a, alone_b = problem
            R, C = both.shape
            r, c = _lsa(A)
            total = float(A[r, c].sum())
            if total < current - 1e-9 * max(1.0, abs(current)):
                m = r < R
                sel = np.concatenate(
                    [
                        both[r[m & (c < C)], c[m & (c < C)]],
                        alone_a[r[m & (c >= C)]],
                        alone_b[c[~m & (c < C)]],
                    ]
                )
                current = float(prep.cost[sel].sum())
                break
        else:
            break
    return sel


_SplitProblem = tuple[FloatArray, IntArray, IntArray, IntArray]


def _split_problems(prep: _Prep, sel: IntArray, sides: IntArray) -> Iterator[_SplitProblem | None]:
    """For each split in ``sides`` (rows of :func:`_splits`), the 2-D problem re-pairing the
    parts of the chosen tuples ``sel``, None when one side holds no real element.

    Each is ``(A, both, alone_a, alone_b)``: the augmented ``(R + C) × (C + R)`` matrix of the
    ``R`` side-1 parts and ``C`` side-2 parts, the tuple joining each pair of parts (-1 none,
    cost inf), and each part's tuple on its own (its dummy entry). With numba all splits are
    built by one compiled call (:func:`_split_loop`), the same matrices.
    """
    part = prep.tuples[sel] * prep.radix  # (r, S) each list's share of the chosen tuples' keys
    kernel = _compiled_splits()
    if kernel is not None:
        args = prep.table, prep.keys, prep.key_tuple, prep.cost_inf
        A_all, both_all, alone_a_all, alone_b_all, sizes = kernel(part, sides, *args)
        for j, (R, C) in enumerate(sizes.tolist()):
            if R == 0 or C == 0:
                yield None
                continue
            M = R + C
            A = A_all[j, : M * M].reshape(M, M)
            yield A, both_all[j, : R * C].reshape(R, C), alone_a_all[j, :R], alone_b_all[j, :C]
        return
    cost = prep.cost_inf
    whole = part.sum(axis=1)
    for side in sides:
        ka = part @ side
        kb = whole - ka
        a, b = ka[ka > 0], kb[kb > 0]
        R, C = a.size, b.size
        if R == 0 or C == 0:
            yield None
            continue
        both = _lookup(prep, a[:, None] + b[None, :])  # keys add: the parts are disjoint
        alone_a, alone_b = _lookup(prep, a), _lookup(prep, b)
        A = np.full((R + C, C + R), np.inf)
        A[:R, :C] = cost[both]  # the index -1 (no such tuple) picks inf
        A.flat[C + (R + C + 1) * np.arange(R)] = cost[alone_a]
        A.flat[(R + C) * R + (R + C + 1) * np.arange(C)] = cost[alone_b]
        A[R:, C:] = 0.0
        yield A, both, alone_a, alone_b


def _split_loop(
    part: IntArray,
    sides: IntArray,
    table: IntArray,
    keys: IntArray,
    key_tuple: IntArray,
    cost_inf: FloatArray,
) -> tuple[FloatArray, IntArray, IntArray, IntArray, IntArray]:
    """:func:`_split_problems`' matrices for all ``sides`` in scalar loops, for numba
    (:func:`_compiled_splits`); keys looked up as :func:`_lookup` does.

    Returns row ``j`` of each output for split ``j``, padded: the matrix flattened in the first
    ``(R + C)²`` entries, ``both`` in the first ``R · C``, and the ``(R, C)`` of each split.
    """
    r, S = part.shape
    n = sides.shape[0]
    A_all = np.empty((n, 4 * r * r))
    both_all = np.empty((n, r * r), dtype=np.int64)
    alone_a_all = np.empty((n, r), dtype=np.int64)
    alone_b_all = np.empty((n, r), dtype=np.int64)
    sizes = np.zeros((n, 2), dtype=np.int64)
    ka = np.empty(r, dtype=np.int64)
    kb = np.empty(r, dtype=np.int64)
    dense = table.size > 0

    def lookup(key: int) -> int:
        if dense:
            return int(table[key])
        pos = np.searchsorted(keys, key)
        return int(key_tuple[pos]) if pos < keys.size and keys[pos] == key else -1

    for j in range(n):
        R = 0
        C = 0
        for i in range(r):
            on_a = 0
            on_b = 0
            for s in range(S):
                if sides[j, s]:
                    on_a += part[i, s]
                else:
                    on_b += part[i, s]
            if on_a > 0:
                ka[R] = on_a
                R += 1
            if on_b > 0:
                kb[C] = on_b
                C += 1
        sizes[j, 0] = R
        sizes[j, 1] = C
        if R == 0 or C == 0:
            continue
        M = R + C
        A = A_all[j]
        A[: M * M] = np.inf
        for p in range(R):
            for q in range(C):
                k = lookup(ka[p] + kb[q])
                both_all[j, p * C + q] = k
                A[p * M + q] = cost_inf[k]
            k = lookup(ka[p])
            alone_a_all[j, p] = k
            A[p * M + C + p] = cost_inf[k]
        for q in range(C):
            k = lookup(kb[q])
            alone_b_all[j, q] = k
            A[(R + q) * M + q] = cost_inf[k]
            for p in range(R):
                A[(R + q) * M + C + p] = 0.0
    return A_all, both_all, alone_a_all, alone_b_all, sizes


@lru_cache(maxsize=1)
def _compiled_splits() -> (
    Callable[..., tuple[FloatArray, IntArray, IntArray, IntArray, IntArray]] | None
):
    """:func:`_split_loop` compiled by numba, or None without numba (:func:`_split_problems`
    then builds each split's matrix with NumPy). Compiled on the first call for the argument
    types :func:`_split_problems` passes, with the dense key table and without."""
    kernel = jit(_split_loop)
    if kernel is None:
        return None
    for size in (1, 0):  # a dense key table and none (the sorted keys)
        tiny = _tiny_prep()
        table = tiny.table[: size * tiny.table.size]
        kernel(
            tiny.tuples[:1] * tiny.radix,
            _splits(3),
            table,
            tiny.keys,
            tiny.key_tuple,
            tiny.cost_inf,
        )
    return kernel


@cache
def _splits(S: int) -> IntArray:
    """The ``2^(S-1) - 1`` splits of ``S`` lists into two non-empty sides, as 0/1 rows marking
    the side that holds list 1. Cutting at every split, not only at one list (Karapetyan &
    Gutin's DV1), halved the mean excess over the optimum of the benchmark's S = 4, 5 problems
    (seed 13)."""
    rows = [m for m in itertools.product((0, 1), repeat=S) if m[0] == 1 and 0 in m]
    out = np.array(rows, dtype=np.int64).reshape(-1, S)
    out.flags.writeable = False  # shared by every call (cached)
    return out


def _unchecked(sizes: IntArray, tuples: IntArray, cost: FloatArray) -> SdProblem:
    """An :class:`SdProblem` built without its checks (a valid problem with its lists
    permuted)."""
    p = object.__new__(SdProblem)
    for name, v in (("sizes", sizes), ("tuples", tuples), ("cost", cost)):
        object.__setattr__(p, name, v)
    return p


def _solve_2d(problem: SdProblem) -> IntArray:
    """Exact 2-D assignment with dummies on both lists (augmented ``linear_sum_assignment``)."""
    return _dual(_prep(problem), np.zeros(0))[1]


def _lagrangian(
    prep: _Prep,
    max_iter: int,
    tol: float,
    start: IntArray,
    seen: dict[bytes, IntArray],
    u: FloatArray,
    alpha: float,
    *,
    patience: int = 5,
    min_alpha: float = 2.0**-7,
    recover_every: int = 3,
) -> tuple[float, IntArray, float, int, FloatArray]:
    """One relaxation pass from the multipliers ``u`` (L,) of lists 3..S and the step factor
    ``alpha``, ``start`` the first feasible solution.

    ``seen`` maps each solution already polished by :func:`_improve` (sorted tuple indices)
    to its result: the local search is deterministic, so it runs once per solution, across
    the rotated passes too (they share the tuple order). A pass recovers from each set of
    pairs once: a quarter of the recoveries repeated the pairs of an earlier one, and skipping
    them cost the 4-list benchmark problems (seed 13) nothing.

    Returns ``(upper bound, best feasible tuples, lower bound, iterations, multipliers of the
    lower bound)``.
    """

    def polished(sel: IntArray) -> IntArray:
        key = np.sort(sel).tobytes()
        if key not in seen:
            seen[key] = _improve(prep, sel)
        return seen[key]

    tried: set[bytes] = set()  # pair sets already fixed by a recovery in this pass
    u = u.copy()
    best_u = u.copy()
    best_sel = polished(start)
    ub = float(prep.cost[best_sel].sum())
    lb = -np.inf
    stall, it = 0, 0
    while it < max_iter:
        it += 1
        phi, sel, chosen = _dual(prep, u)
        improved = lb == -np.inf or phi > lb + 1e-12 * max(1.0, abs(lb))
        fixed = chosen.tobytes()
        if (improved or it % recover_every == 0) and fixed not in tried:
            tried.add(fixed)
            rec = polished(_recover(prep, chosen, u))
            c = float(prep.cost[rec].sum())
            if c < ub:
                ub, best_sel = c, rec
        if improved:
            lb, stall = phi, 0
            best_u[:] = u
        else:
            stall += 1
            if stall >= patience:
                alpha, stall = alpha / 2.0, 0
        if ub - lb <= tol * max(abs(ub), 1e-12) or alpha < min_alpha:
            break
        g = 1.0 - np.bincount(prep.uidx[:, sel].ravel(), minlength=u.size)
        g[prep.dummies] = 0.0
        norm2 = float(g @ g)
        if norm2 == 0.0:  # relaxed solution is feasible, hence optimal
            c = float(prep.cost[sel].sum())
            if c < ub:
                ub, best_sel = c, sel
            lb = max(lb, min(ub, phi))
            break
        u += alpha * max(ub - phi, 1e-9 * max(1.0, abs(ub))) / norm2 * g
    return ub, best_sel, min(lb, ub), it, best_u


_WARM_ALPHA = 0.5  # step factor of the warm-started passes (docs/multisensor.md)


def _list_orders(S: int) -> list[IntArray]:
    """List orders of the passes: the ``S`` rotations (each keeps two neighbouring lists in the
    2-D subproblem), then one order for each other pair of lists; ``C(S, 2)`` in all."""
    rotations = [np.roll(np.arange(S), -shift) for shift in range(S)]
    kept = {frozenset(o[:2].tolist()) for o in rotations}
    others = [
        np.array([a, b, *(x for x in range(S) if x not in (a, b))])
        for a, b in itertools.combinations(range(S), 2)
        if frozenset((a, b)) not in kept
    ]
    return rotations + others


_MAX_ITER = 45  # multiplier updates per pass (docs/multisensor.md)


def sd_lagrangian(
    problem: SdProblem, max_iter: int = _MAX_ITER, tol: float = 1e-3, restarts: int | None = None
) -> SdSolution:
    """S-D assignment by Lagrangian relaxation of lists 3..S (module notes).

    Parameters
    ----------
    problem : SdProblem with ``S >= 3`` lists
    max_iter : int
        Multiplier updates per pass. Default 45 (module notes: chosen on seed 13).
    tol : float
        Stop when ``UB - LB <= tol · |UB|`` (relative duality gap).
    restarts : int, optional
        While the gap stays open, solve again with other lists kept in the 2-D subproblem (up
        to this many times, at most ``C(S, 2) - 1``): the lists rotated by 1, 2, ..., S - 1,
        then each pair of lists no rotation keeps (:func:`_list_orders`); other pairs are then
        fixed by the recovery. Each later pass starts from the multipliers of the best bound
        so far, those of the lists it now relaxes but kept before taken from the dual of that
        bound's 2-D problem, so it starts at about that bound. The best solution and the best
        bound of all passes are kept (both stay valid). Default: every rotation for ``S <= 4``
        (``S - 1``), every pair of lists for ``S >= 5`` (``C(S, 2) - 1``; module notes).

    Returns
    -------
    SdSolution
        ``status`` OPTIMAL when the gap closed to ``tol``, else GAP; never worse than
        :func:`sd_greedy` (the greedy solution, locally improved, is the first upper bound).
    """
    if problem.n_lists < 3:
        raise ValueError(f"problem: the relaxation needs S >= 3 lists, got {problem.n_lists}")
    S = problem.n_lists
    pairs = S * (S - 1) // 2
    if restarts is None:
        restarts = S - 1 if S <= 4 else pairs - 1
    if max_iter < 1 or not tol >= 0 or restarts < 0:
        raise ValueError(
            f"max_iter must be >= 1, tol >= 0, restarts >= 0; got {max_iter}, {tol}, {restarts}"
        )
    if len(problem.tuples) == 0:  # no real element in any list
        return _solution(
            problem, problem.tuples[:0, 0], 0.0, 0, SdMethod.LAGRANGIAN, SdStatus.OPTIMAL, "empty"
        )
    seen: dict[bytes, IntArray] = {}  # polished solutions, shared by the passes
    greedy = sd_greedy(problem).selected
    mult = [np.zeros(int(k) + 1) for k in problem.sizes]  # per list, the dummy's 0 first
    ub, sel, lb, it = np.inf, greedy, -np.inf, 0
    for n_pass, order in enumerate(_list_orders(S)[: min(restarts, pairs - 1) + 1]):
        # the same problem with its lists reordered: other pairs are fixed by the recovery
        rot = _unchecked(problem.sizes[order], problem.tuples[:, order], problem.cost)
        prep = _prep(rot)
        u0 = np.concatenate([mult[k] for k in order[2:]])
        alpha = 2.0 if n_pass == 0 else _WARM_ALPHA
        ub2, sel2, lb2, it2, u = _lagrangian(prep, max_iter, tol, greedy, seen, u0, alpha)
        it += it2
        if ub2 < ub:
            ub, sel = ub2, sel2
        if ub - min(max(lb, lb2), ub) <= tol * max(abs(ub), 1e-12):
            lb = max(lb, lb2)
            break
        if lb2 > lb:
            lb = lb2
            split = np.cumsum(rot.sizes[2:-1] + 1)
            for k, uk in zip(order[2:], np.split(u, split), strict=True):
                mult[k] = uk
            mult[order[0]], mult[order[1]] = _kept_multipliers(prep, u)
    lb = min(lb, ub)
    closed = ub - lb <= tol * max(abs(ub), 1e-12)
    status = SdStatus.OPTIMAL if closed else SdStatus.GAP
    rel = (ub - lb) / max(abs(ub), 1e-12)
    msg = f"relative duality gap {rel:.2e} after {it} iterations"
    return _solution(problem, sel, lb, it, SdMethod.LAGRANGIAN, status, msg)


def sd_assign(
    problem: SdProblem,
    method: str = "auto",
    *,
    max_exact_tuples: int = 5000,
    max_iter: int = _MAX_ITER,
    tol: float = 1e-3,
) -> SdSolution:
    """Solve an S-D assignment problem with the dummy index.

    Parameters
    ----------
    problem : SdProblem
    method : {"auto", "exact", "lagrangian"}
        ``"exact"``: :func:`sd_exact` when the problem has at most ``max_exact_tuples`` tuples;
        a larger one is solved by relaxation instead, ``status`` TOO_LARGE and ``message``
        saying so with the duality gap. ``"lagrangian"``: :func:`sd_lagrangian`. ``"auto"``:
        2 lists exactly by ``linear_sum_assignment``, else the relaxation.
    max_exact_tuples : int
        Size limit of the exact solver. Default 5000: above it HiGHS takes seconds (see
        ``benchmarks/bench_sd_assignment.py``).
    max_iter, tol : relaxation limits (:func:`sd_lagrangian`)
    """
    if method not in ("auto", "exact", "lagrangian"):
        raise ValueError(f"method must be 'auto', 'exact' or 'lagrangian', got {method!r}")
    if problem.n_lists == 2:
        sel = _solve_2d(problem)
        return _solution(
            problem,
            sel,
            float(problem.cost[sel].sum()),
            0,
            SdMethod.EXACT,
            SdStatus.OPTIMAL,
            "optimal (2-D)",
        )
    if method == "exact":
        K = len(problem.tuples)
        too_large = len(problem.tuples) > max_exact_tuples
        if not too_large:
            sol = sd_exact(problem)
            if sol is not None:
                return sol
        lr = sd_lagrangian(problem, max_iter, tol)
        why = (
            f"{K} tuples > max_exact_tuples = {max_exact_tuples}"
            if too_large
            else "milp found no optimum"
        )
        return SdSolution(
            lr.selected,
            lr.tuples,
            lr.cost,
            lr.lower_bound,
            lr.gap,
            lr.relative_gap,
            lr.iterations,
            lr.method,
            SdStatus.TOO_LARGE,
            f"exact solver not used ({why}); Lagrangian relaxation: {lr.message}",
        )
    return sd_lagrangian(problem, max_iter, tol)


# --------------------------------------------------------------------------------------------
# k-best S-D solutions (Murty's partitioning with exact or relaxed cells)
# --------------------------------------------------------------------------------------------


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
class _Cell:
    """A Murty cell: the solutions that hold every ``forced`` tuple, the rest from ``free``."""

    forced: IntArray  # tuples in every solution of the cell
    free: BoolArray  # (K,) not forbidden and sharing no real element with a forced tuple
    bound: float  # lower bound on the cell's costs known before solving it (the parent's)
    start: IntArray | None = None  # a solution of the cell known before solving it

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class _Remainder:
    """The S-D problem left by a cell once its forced tuples are taken out."""

    problem: SdProblem  # remaining elements renumbered; the free tuples, then penalty singletons
    tuple_of: IntArray  # (K',) tuple of the full problem behind each, -1 for a penalty singleton
    forced_cost: float
    max_cost: float  # no solution of the remainder within the cell costs more

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _remainder(problem: SdProblem, cell: _Cell) -> _Remainder | None:
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
    return _Remainder(
        reduced,
        np.r_[idx, np.full(len(rows), -1, dtype=np.int64)],
        float(problem.cost[cell.forced].sum()),
        U,
    )


@dataclass(frozen=True, slots=True)
class _KBestOptions:
    method: str
    max_exact_tuples: int
    max_iter: int
    tol: float
    time_limit_s: float | None


def _solve_cell(
    problem: SdProblem, cell: _Cell, opt: _KBestOptions
) -> tuple[SdSolution | None, float]:
    """Best solution found in the cell and a lower bound on its costs.

    ``(None, inf)``: the cell is empty. ``(None, bound)``: unresolved (the relaxation kept a
    penalty singleton, the cell is too large for milp and came with no start).
    """
    rem = _remainder(problem, cell)
    if rem is None:
        return None, np.inf
    R = rem.problem
    real = rem.tuple_of >= 0
    n_free = int(real.sum())
    head = f"Murty cell with {cell.forced.size} forced and {n_free} free tuples"
    small = n_free <= opt.max_exact_tuples
    too_large = ""
    if opt.method == "exact" and small:
        sol, st = _milp(R, real, opt.time_limit_s, "optimal (milp)")
        if sol is not None:
            return _exact_in_cell(problem, cell, rem, sol, head)
        if st == _MILP_INFEASIBLE:
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
        sol = _solution(problem, selected, -np.inf, 0, SdMethod.LAGRANGIAN, SdStatus.GAP, "")
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
        return _solution(problem, sol.selected, lb, it, SdMethod.LAGRANGIAN, status, message), lb
    # a penalty singleton was kept: the cell is empty, or the relaxation missed its solutions
    if relaxed.lower_bound > rem.max_cost + 1e-9 * max(1.0, abs(rem.max_cost)):
        return None, np.inf
    if small:
        sol, st = _milp(R, real, opt.time_limit_s, "optimal (milp; the relaxation kept a penalty)")
        if sol is not None:
            return _exact_in_cell(problem, cell, rem, sol, head)
        if st == _MILP_INFEASIBLE:
            return None, np.inf
    return None, max(cell.bound, bound)


def _exact_in_cell(
    problem: SdProblem, cell: _Cell, rem: _Remainder, sol: SdSolution, head: str
) -> tuple[SdSolution, float]:
    """The remainder's exact solution as a solution of the full problem in ``cell``."""
    selected = np.sort(np.r_[cell.forced, rem.tuple_of[sol.selected]])
    cost = float(problem.cost[selected].sum())
    message = f"{head}: {sol.message}"
    return _solution(problem, selected, cost, 0, sol.method, SdStatus.OPTIMAL, message), cost


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


def _children(problem: SdProblem, cell: _Cell, sol: SdSolution) -> list[_Cell]:
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
        out.append(_Cell(forced, child, sol.lower_bound, start))
        free &= ~np.any((t == t[tau]) & (t[tau] > 0), axis=1)  # force tau: drop its clashes
        forced = np.append(forced, tau)
    return out


def sd_kbest(
    problem: SdProblem,
    k: int,
    method: str = "exact",
    *,
    max_exact_tuples: int = 5000,
    max_iter: int = _MAX_ITER,
    tol: float = 1e-3,
    time_limit_s: float | None = None,
) -> SdKBest:
    """The ``k`` best S-D solutions (fewer if fewer exist) by Murty's partitioning.

    A *cell* of the partition is the set of solutions that hold some forced tuples and avoid
    some forbidden ones. The best solution found in a cell, with tuples ``τ_1..τ_r`` besides
    the forced ones, splits the rest of the cell into ``r`` cells: cell ``j`` forbids ``τ_j``
    and forces ``τ_1..τ_{j-1}`` (Murty 1968 with tuples in place of matrix cells; Popp,
    Pattipati & Bar-Shalom 2001 for S-D). Cells wait in a heap by the cost of their solution;
    the cheapest is taken next.

    **How a cell is solved.** Its forced tuples are taken out: their elements leave the lists
    (the rest renumbered) and their cost is added; the free tuples touching no forced element
    stay, forbidden ones are dropped. What remains is an ordinary S-D problem except where a
    forbidden tuple is an element's singleton: that element must then be covered by a real
    tuple, which the relaxation's greedy start and recovery (they fall back to singletons)
    cannot respect. It gets a *penalty singleton* instead, costing more than the spread of
    all costs the cell allows (:func:`_remainder`), so that (i) the penalised problem holds
    every solution of the cell at its own cost, and its lower bounds are lower bounds of the
    cell; (ii) its optimum uses a penalty only if the cell is empty. A relaxation result
    without penalties is a solution of the cell; one with a penalty whose lower bound exceeds
    every cost the cell allows proves the cell empty; otherwise (and without a start from the
    parent, below) the cell is solved by milp when it has at most ``max_exact_tuples`` tuples,
    else it is counted as unresolved and its bound kept. A cell with an element that no
    allowed tuple covers is empty without a solve.

    **Guarantees.** Every solution returned is feasible and in its own cell, so they are
    pairwise distinct; they are the ``k`` cheapest of all solutions found, in non-decreasing
    cost. With exact cells (milp or 2-D) they are the ``k`` best solutions. With relaxed
    cells a cell's solution may be above the cell's optimum, so a better solution may be
    missed or found later, and the ranking is approximate: each solution's ``lower_bound``
    and ``gap`` bound its cell, and ``SdKBest.lower_bound[j] = min(cost[j], L)`` bounds the
    true ``(j + 1)``-th best cost, ``L`` the least bound of the unexplored cells (the cells
    still in the heap, the last one taken, the unresolved ones): every solution not returned
    lies in one of them or costs at least ``cost[k - 1]``.

    **Cheaper Murty.** A cell inherits its parent's lower bound (it is a subset of the
    parent) and starts from its parent's solution: with ``τ_j`` replaced by the cheapest cover
    of its elements the cell allows, that solution is in the cell, and a relaxed cell returns
    it when the relaxation finds nothing cheaper (or keeps a penalty). The partition forces
    the tuples with most real elements first, so the later cells have small remainders (often
    under ``max_exact_tuples``); the forced tuples of a cell are never partitioned on again;
    a cell with an element no allowed tuple covers is dropped unsolved; and no cell is split
    once ``k`` were taken. Skipping a cell whose inherited bound exceeds the ``k``-th cost
    found never applies: the parent was the cheapest cell left, so its bound is below every
    cost in the heap (a child bound tighter than the parent's would need the relaxation's
    multipliers).

    Parameters
    ----------
    problem : SdProblem
    k : int >= 1
    method : {"exact", "auto", "lagrangian"}
        As in :func:`sd_assign`, per cell (the size rule applies to the cell's remainder).
        ``"exact"`` (default): milp on cells of at most ``max_exact_tuples`` tuples, the
        relaxation on larger ones (``status`` TOO_LARGE). ``"lagrangian"``, ``"auto"``: the
        relaxation on every cell (2-D assignment when ``S = 2``); milp only for an unresolved
        forbidden singleton.
    max_exact_tuples : int
        Size limit of milp, as in :func:`sd_assign`. Default 5000.
    max_iter, tol : relaxation limits per cell (:func:`sd_lagrangian`)
    time_limit_s : float or None
        Per milp solve; a cell that runs out of time is solved by relaxation (TOO_LARGE).

    Returns
    -------
    SdKBest

    References
    ----------
    Murty 1968 [1]_; Popp, Pattipati & Bar-Shalom 2001 [8]_ (module references).
    """
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be an integer >= 1, got {k!r}")
    if method not in ("auto", "exact", "lagrangian"):
        raise ValueError(f"method must be 'auto', 'exact' or 'lagrangian', got {method!r}")
    if max_exact_tuples < 0:
        raise ValueError(f"max_exact_tuples must be >= 0, got {max_exact_tuples}")
    if time_limit_s is not None and not time_limit_s > 0:
        raise ValueError(f"time_limit_s must be > 0 or None, got {time_limit_s}")
    opt = _KBestOptions(method, max_exact_tuples, max_iter, tol, time_limit_s)
    heap: list[tuple[float, int, SdSolution, _Cell]] = []
    unexplored: list[float] = []  # lower bounds of the parts of the space not searched
    cells = infeasible = unresolved = 0

    def add(cell: _Cell) -> None:
        nonlocal cells, infeasible, unresolved
        cells += 1
        sol, bound = _solve_cell(problem, cell, opt)
        if sol is not None:
            heapq.heappush(heap, (sol.cost, cells, sol, cell))
        elif bound == np.inf:
            infeasible += 1
        else:
            unresolved += 1
            unexplored.append(bound)

    K = len(problem.tuples)
    add(_Cell(np.zeros(0, dtype=np.int64), np.ones(K, dtype=bool), -np.inf))
    taken: list[SdSolution] = []
    while heap and len(taken) < k:
        _, _, sol, cell = heapq.heappop(heap)
        taken.append(sol)
        if len(taken) == k:
            unexplored.append(sol.lower_bound)  # the rest of its cell
            break
        for child in _children(problem, cell, sol):
            add(child)
    found = taken + [item[2] for item in heap]
    unexplored += [item[2].lower_bound for item in heap]
    best = np.argsort([s.cost for s in found], kind="stable")[:k]
    out = tuple(found[i] for i in best)
    cost = np.array([s.cost for s in out], dtype=float)
    return SdKBest(
        out, np.minimum(cost, min(unexplored, default=np.inf)), cells, infeasible, unresolved
    )
