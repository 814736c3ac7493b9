"""2-D assignment with missed-detection costs and Murty's k best assignments.

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
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray

__all__ = [
    "Assignment",
    "KBest",
    "assign2d",
    "assignment_potentials",
    "augmented_cost",
    "linear_assignment",
    "murty",
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


def linear_assignment(A: FloatArray) -> tuple[IntArray, IntArray]:
    """``scipy.optimize.linear_sum_assignment`` that also takes an empty matrix (int64 rows and
    columns)."""
    if A.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    r, c = linear_sum_assignment(A)
    return r.astype(np.int64, copy=False), c.astype(np.int64, copy=False)


def assignment_potentials(
    A: FloatArray, rows: IntArray, cols: IntArray
) -> tuple[FloatArray, FloatArray]:
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
