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

S-D assignment (``S >= 3`` lists, :func:`sd_assign`) is described in the section comment
before :class:`SdProblem`.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from navtrack._frozen import freeze_arrays
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
    if np.any(np.isnan(C)) or np.any(-np.inf == C):
        raise ValueError("cost must not contain NaN or -inf (use +inf for forbidden pairs)")
    if not np.all(np.isfinite(miss)):
        raise ValueError("miss_cost must be finite")
    return C, miss


def augmented_cost(cost: ArrayLike, miss_cost: ArrayLike) -> FloatArray:
    """The ``T × (M + T)`` matrix ``[cost | diag(miss_cost)]`` with ``inf`` off the diagonal."""
    C, miss = _check(cost, miss_cost)
    T = C.shape[0]
    D = np.full((T, T), np.inf)
    D[np.arange(T), np.arange(T)] = miss
    return np.concatenate([C, D], axis=1)


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
# progress, Held, Wolfe & Crowder 1974) with ``g = 1 - (times each index is used)``.  A feasible
# solution is recovered from the pairs the 2-D solution chose: they become the real elements of
# a merged list and the (S - 1)-D problem over (pairs, lists 3..S) is solved the same way
# (exactly when it is 2-D).  A chosen pair also keeps the option of being split back into its
# two singletons, so the recovery problem is always feasible.  The best feasible cost is the
# upper bound; ``UB - LB`` is the duality gap reported.


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
    used = [np.zeros(k + 1, dtype=bool) for k in problem.sizes]
    chosen: list[int] = []
    tup = problem.tuples
    for k in np.argsort(problem.cost, kind="stable"):
        row = tup[k]
        if any(i > 0 and used[s][i] for s, i in enumerate(row)):
            continue
        chosen.append(int(k))
        for s, i in enumerate(row):
            if i > 0:
                used[s][i] = True
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
    return _milp(problem, allowed, time_limit_s, "optimal (milp)")


def _milp(
    problem: SdProblem, allowed: BoolArray, time_limit_s: float | None, message: str
) -> SdSolution | None:
    """Exact solution over the ``allowed`` tuples; None if infeasible or out of time."""
    from scipy.optimize import Bounds, LinearConstraint, milp

    idx = np.flatnonzero(allowed)
    if idx.size == 0:
        if problem.sizes.sum() > 0:
            return None
        return _solution(problem, idx, 0.0, 0, SdMethod.EXACT, SdStatus.OPTIMAL, message)
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
        return None
    sel = idx[res.x > 0.5]
    lb = float(problem.cost[sel].sum())
    return _solution(problem, sel, lb, 0, SdMethod.EXACT, SdStatus.OPTIMAL, message)


# ---------------------------------------------------------------------------- relaxation


@dataclass(frozen=True, slots=True, eq=False)
class _Pairs:
    """Tuples grouped by their (list 1, list 2) pair, sorted once per problem."""

    order: IntArray  # tuple order, grouped by pair key
    starts: IntArray  # group starts in ``order``
    group: IntArray  # group number of each sorted tuple
    key: IntArray  # pair key of each group: i1 * (n2 + 1) + i2


def _pairs(problem: SdProblem) -> _Pairs:
    t = problem.tuples
    key = t[:, 0] * (problem.sizes[1] + 1) + t[:, 1]
    order = np.argsort(key, kind="stable")
    ks = key[order]
    first = np.r_[True, ks[1:] != ks[:-1]] if len(ks) else np.zeros(0, bool)
    starts = np.flatnonzero(first)
    return _Pairs(order, starts, np.cumsum(first) - 1, ks[starts])


def _relaxed(
    problem: SdProblem, pairs: _Pairs, u: list[FloatArray]
) -> tuple[float, IntArray, IntArray]:
    """Optimum of the relaxed problem for multipliers ``u`` of lists 3..S.

    Returns ``(lower bound, selected tuples, chosen pair keys other than (0, 0))``.
    """
    from scipy.optimize import linear_sum_assignment

    t = problem.tuples
    n1, n2 = int(problem.sizes[0]), int(problem.sizes[1])
    red = problem.cost.copy()
    for s, us in enumerate(u, start=2):
        red -= us[t[:, s]]
    rs = red[pairs.order]
    mins = np.minimum.reduceat(rs, pairs.starts)
    pos = np.flatnonzero(rs <= mins[pairs.group])
    first = pos[np.r_[True, pairs.group[pos[1:]] != pairs.group[pos[:-1]]]]
    best = pairs.order[first]  # best tuple of each group
    i1, i2 = np.divmod(pairs.key, n2 + 1)
    # 2-D with dummies: rows = list-1 elements then list-2 "dummy rows", columns likewise
    A = np.full((n1 + n2, n2 + n1), np.inf)
    both = (i1 > 0) & (i2 > 0)
    A[i1[both] - 1, i2[both] - 1] = mins[both]
    only1 = (i1 > 0) & (i2 == 0)
    A[i1[only1] - 1, n2 + i1[only1] - 1] = mins[only1]
    only2 = (i1 == 0) & (i2 > 0)
    A[n1 + i2[only2] - 1, i2[only2] - 1] = mins[only2]
    A[n1:, n2:] = 0.0
    rows, cols = linear_sum_assignment(A)
    r1 = np.where(rows < n1, rows + 1, 0)
    c2 = np.where(cols < n2, cols + 1, 0)
    keys = r1 * (n2 + 1) + c2
    chosen = np.sort(keys[keys > 0])
    g = np.searchsorted(pairs.key, chosen)
    sel = best[g]
    lb = float(mins[g].sum()) + sum(float(us.sum()) for us in u)
    if len(pairs.key) and pairs.key[0] == 0:  # free tuples of the (0, 0) pair
        z = pairs.order[pairs.starts[0] : (pairs.starts[1] if len(pairs.starts) > 1 else None)]
        neg = z[red[z] < 0]
        sel = np.concatenate([sel, neg])
        lb += float(red[neg].sum())
    return lb, sel, chosen


def _recover(
    problem: SdProblem, chosen: IntArray, max_iter: int, tol: float, u: list[FloatArray]
) -> IntArray:
    """Feasible solution with the pairs ``chosen`` of lists 1-2 fixed (module notes).

    The recovery problem relaxes lists 4..S; its multipliers start from ``u[1:]``, the
    outer problem's multipliers of the same lists.
    """
    t = problem.tuples
    n2 = int(problem.sizes[1])
    key = t[:, 0] * (n2 + 1) + t[:, 1]
    pid = np.zeros(len(t), dtype=np.int64)  # merged index: 0 = pair (0, 0), p = chosen[p-1]
    inpair = np.isin(key, chosen)
    pid[inpair] = np.searchsorted(chosen, key[inpair]) + 1
    keep = inpair | (key == 0)
    rest = t[:, 2:]
    single_cost = _singleton_costs(problem)
    # the split option of pair p: its two singletons (one if the pair has a dummy)
    ci1, ci2 = np.divmod(chosen, n2 + 1)
    split = single_cost[0][ci1] + single_cost[1][ci2]
    sub_t = np.column_stack([pid[keep], rest[keep]])
    sub_c = problem.cost[keep]
    origin = np.flatnonzero(keep)  # sub tuple -> original tuple, -1 - p for the split of p
    is_plain = (sub_t[:, 1:] == 0).all(axis=1)
    plain = dict(zip(sub_t[is_plain, 0].tolist(), np.flatnonzero(is_plain).tolist(), strict=True))
    add_t, add_c, add_o = [], [], []
    for p in range(1, len(chosen) + 1):
        k = plain.get(p)
        if k is None:
            add_t.append(p)
            add_c.append(split[p - 1])
            add_o.append(-p)
        elif split[p - 1] < sub_c[k]:  # splitting beats the pair's own plain tuple
            sub_c[k] = split[p - 1]
            origin[k] = -p
    if add_t:
        z = np.zeros((len(add_t), sub_t.shape[1] - 1), dtype=np.int64)
        sub_t = np.concatenate([sub_t, np.column_stack([add_t, z])])
        sub_c = np.concatenate([sub_c, add_c])
        origin = np.concatenate([origin, add_o])
    sub = _unchecked(np.r_[len(chosen), problem.sizes[2:]], sub_t, sub_c)
    picked = _solve_2d(sub) if sub.n_lists == 2 else _lagrangian(sub, max_iter, tol, u[1:])[1]
    out = []
    for o in origin[picked].tolist():
        if o >= 0:
            out.append(o)
        else:  # split pair: its singletons in the original problem
            i1, i2 = int(ci1[-o - 1]), int(ci2[-o - 1])
            out += [k for k in (_singleton(problem, 0, i1), _singleton(problem, 1, i2)) if k >= 0]
    return np.array(out, dtype=np.int64)


def _unchecked(sizes: IntArray, tuples: IntArray, cost: FloatArray) -> SdProblem:
    """An :class:`SdProblem` built without its checks (recovery problems are valid by
    construction: every real index keeps a singleton)."""
    p = object.__new__(SdProblem)
    for name, v in (("sizes", sizes), ("tuples", tuples), ("cost", cost)):
        object.__setattr__(p, name, v)
    return p


def _singleton_costs(problem: SdProblem) -> list[FloatArray]:
    """Cost of the singleton of each index of lists 1 and 2 (entry 0 = 0)."""
    t = problem.tuples
    single = (t > 0).sum(axis=1) == 1
    out = []
    for s in (0, 1):
        c = np.zeros(problem.sizes[s] + 1)
        k = single & (t[:, s] > 0)
        c[t[k, s]] = problem.cost[k]
        out.append(c)
    return out


def _singleton(problem: SdProblem, s: int, i: int) -> int:
    """Index of the singleton tuple of element ``i`` of list ``s`` (-1 for the dummy)."""
    if i == 0:
        return -1
    t = problem.tuples
    k = np.flatnonzero((t[:, s] == i) & ((t > 0).sum(axis=1) == 1))
    return int(k[0])


def _solve_2d(problem: SdProblem) -> IntArray:
    """Exact 2-D assignment with dummies on both lists (augmented ``linear_sum_assignment``)."""
    pairs = _pairs(problem)
    return _relaxed(problem, pairs, [])[1]


def _lagrangian(
    problem: SdProblem,
    max_iter: int,
    tol: float,
    u0: list[FloatArray] | None = None,
    patience: int = 5,
    recover_every: int = 3,
    min_alpha: float = 2.0**-7,
) -> tuple[float, IntArray, float, int]:
    """Relaxation loop from multipliers ``u0`` (zeros when None) of lists 3..S.

    Returns ``(upper bound, best feasible tuples, lower bound, iterations)``.
    """
    pairs = _pairs(problem)
    if u0 is None:
        u = [np.zeros(k + 1) for k in problem.sizes[2:]]
    else:
        u = [np.array(us, dtype=float) for us in u0]
    best_sel = sd_greedy(problem).selected
    ub = float(problem.cost[best_sel].sum())
    lb = -np.inf
    alpha, stall, it = 2.0, 0, 0
    sub_iter = max(3, max_iter // 10)
    while it < max_iter:
        it += 1
        phi, sel, chosen = _relaxed(problem, pairs, u)
        improved = lb == -np.inf or phi > lb + 1e-12 * max(1.0, abs(lb))
        if improved or it % recover_every == 0:
            rec = _recover(problem, chosen, sub_iter, tol, u)
            c = float(problem.cost[rec].sum())
            if c < ub:
                ub, best_sel = c, rec
        if improved:
            lb, stall = phi, 0
        else:
            stall += 1
            if stall >= patience:
                alpha, stall = alpha / 2.0, 0
        if ub - lb <= tol * max(abs(ub), 1e-12) or alpha < min_alpha:
            break
        g = [
            1.0 - np.bincount(problem.tuples[sel, s], minlength=k + 1)
            for s, k in enumerate(problem.sizes[2:], start=2)
        ]
        for gs in g:
            gs[0] = 0.0
        norm2 = sum(float(gs @ gs) for gs in g)
        if norm2 == 0.0:  # relaxed solution is feasible, hence optimal
            c = float(problem.cost[sel].sum())
            if c < ub:
                ub, best_sel = c, sel
            lb = max(lb, min(ub, phi))
            break
        step = alpha * max(ub - phi, 1e-9 * max(1.0, abs(ub))) / norm2
        for us, gs in zip(u, g, strict=True):
            us += step * gs
    return ub, best_sel, min(lb, ub), it


def sd_lagrangian(
    problem: SdProblem, max_iter: int = 100, tol: float = 1e-3, restarts: int = 1
) -> SdSolution:
    """S-D assignment by Lagrangian relaxation of lists 3..S (module notes).

    Parameters
    ----------
    problem : SdProblem with ``S >= 3`` lists
    max_iter : int
        Multiplier updates of the outer problem (the recovery problems get a quarter, >= 5).
    tol : float
        Stop when ``UB - LB <= tol · |UB|`` (relative duality gap).
    restarts : int
        While the gap stays open, solve again with the lists rotated by 1, 2, ... (up to this
        many times): the recovery then fixes pairs of other lists. The best solution and the
        best bound of all passes are kept (both stay valid). Default 1, chosen on the seeded
        problems of ``tests/tracking/test_sd_assignment.py``.

    Returns
    -------
    SdSolution
        ``status`` OPTIMAL when the gap closed to ``tol``, else GAP; never worse than
        :func:`sd_greedy` (the greedy solution is the first upper bound).
    """
    if problem.n_lists < 3:
        raise ValueError(f"problem: the relaxation needs S >= 3 lists, got {problem.n_lists}")
    if max_iter < 1 or not tol >= 0 or restarts < 0:
        raise ValueError(
            f"max_iter must be >= 1, tol >= 0, restarts >= 0; got {max_iter}, {tol}, {restarts}"
        )
    ub, sel, lb, it = _lagrangian(problem, max_iter, tol)
    closed = ub - lb <= tol * max(abs(ub), 1e-12)
    for shift in range(1, restarts + 1):
        if closed:
            break
        # the same problem with its lists rotated: other pairs are fixed by the recovery
        order = np.roll(np.arange(problem.n_lists), -shift)
        rot = _unchecked(problem.sizes[order], problem.tuples[:, order], problem.cost)
        ub2, sel2, lb2, it2 = _lagrangian(rot, max_iter, tol)
        it += it2
        lb = max(lb, lb2)
        if ub2 < ub:
            ub, sel = ub2, sel2
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
    max_iter: int = 100,
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


@dataclass(frozen=True, slots=True, eq=False)
class SdKBest:
    """Ranked S-D solutions, best first.

    Attributes
    ----------
    solutions : tuple of SdSolution
        In non-decreasing cost (exact solutions of Murty's partition cells).
    """

    solutions: tuple[SdSolution, ...]

    @property
    def cost(self) -> FloatArray:
        """(k,) costs."""
        return np.array([s.cost for s in self.solutions], dtype=float)


def sd_kbest(problem: SdProblem, k: int, *, time_limit_s: float | None = None) -> SdKBest:
    """The ``k`` best S-D solutions (fewer if fewer exist) by Murty's partitioning.

    A cell of the partition is a set of allowed tuples. The best solution of a cell
    (``sd_exact``) with chosen tuples ``τ_1..τ_r`` splits it into ``r`` cells: cell ``j``
    forbids ``τ_j`` and forces ``τ_1..τ_{j-1}`` (forcing = forbidding every other tuple that
    shares a real index with it), as in Murty (1968) with tuples in place of matrix cells.

    Parameters
    ----------
    problem : SdProblem
    k : int >= 1
    time_limit_s : float or None, per cell (milp)
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    allowed0 = np.ones(len(problem.tuples), dtype=bool)
    first = _milp(problem, allowed0, time_limit_s, "optimal (milp)")
    if first is None:
        return SdKBest(())
    real = problem.tuples > 0
    counter = 0
    heap: list[tuple[float, int, SdSolution, BoolArray]] = [(first.cost, 0, first, allowed0)]
    out: list[SdSolution] = []
    while heap and len(out) < k:
        _, _, sol, allowed = heapq.heappop(heap)
        out.append(sol)
        cell = allowed.copy()
        for tau in sol.selected.tolist():
            child = cell.copy()
            child[tau] = False
            found = _milp(problem, child, time_limit_s, "optimal in its Murty cell (milp)")
            if found is not None:
                counter += 1
                heapq.heappush(heap, (found.cost, counter, found, child))
            # force tau in the cells that follow
            clash = np.zeros(len(cell), dtype=bool)
            for s in np.flatnonzero(real[tau]).tolist():
                clash |= problem.tuples[:, s] == problem.tuples[tau, s]
            clash[tau] = False
            cell &= ~clash
    return SdKBest(tuple(out))
