"""Index tables of an S-D problem, built once per list order and read by every step of a solve.

:func:`relaxation_tables` sorts and indexes the tuples of an :class:`~navtrack.tracking.
assignment.problem.SdProblem` for the relaxation (:mod:`~navtrack.tracking.assignment.
relaxation`), its recovery and the local search (:mod:`~navtrack.tracking.assignment.
local_search`), so that each step is a few array operations on the tuples concerned. The tables
come in four groups, each a frozen record built by keyword: the (list 1, list 2) pairs of the
2-D subproblem (:class:`PairGroups`), the runs of equal (pair, ``i_3``) of the recovery
(:class:`RecoveryRuns`), the tuple keys (:class:`KeyIndex`) and the per-element tables of the
insertions (:class:`ElementTables`).

Notation: ``K`` tuples, ``S`` lists, ``G`` (list 1, list 2) pairs ("groups") among the tuples,
``L = Σ_{s >= 3} (n_s + 1)`` multipliers. Element ``i`` of list ``s`` has the flat index
``s · W + i`` in the ``(S, W = max n + 1)`` element tables.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cache

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.tracking.assignment.problem import SdProblem

__all__ = [
    "DENSE_TABLE_MAX",
    "ElementTables",
    "KeyIndex",
    "PairGroups",
    "RecoveryRuns",
    "RelaxationTables",
    "list_splits",
    "lookup",
    "relaxation_tables",
    "run_starts",
    "tiny_tables",
]

#: Largest key space ``Π (n_s + 1)`` looked up in a dense table (16 MB of int64); larger
#: problems look their tuple keys up by binary search in the sorted keys.
DENSE_TABLE_MAX = 1 << 21


@dataclass(frozen=True, slots=True, eq=False)
class PairGroups:
    """The tuples grouped by their (list 1, list 2) pair: the 2-D subproblem's cells."""

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
    free: IntArray  # tuples of the pair (0, 0)

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class RecoveryRuns:
    """The tuples in runs of equal (pair, ``i_3``), the order the recovery reads them in."""

    seg_order: IntArray  # (K,) tuples sorted by group, then by i_3 (stable)
    seg_starts: IntArray  # (G3 + 1,) starts of the runs of equal (group, i_3) in it, and K
    seg_elem: IntArray  # (G3,) i_3 of each run
    group_seg: IntArray  # (G + 1,) first run of each group, and G3

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class KeyIndex:
    """Tuple keys ``Σ_s i_s radix_s`` and where to find the tuple of a key (:func:`lookup`)."""

    radix: IntArray  # (S,) mixed-radix weights of the tuple key
    keys: IntArray  # (K,) sorted tuple keys
    key_tuple: IntArray  # (K,) tuple of each sorted key
    table: IntArray  # (Π (n_s + 1),) tuple of each key, -1 = none; empty when too large

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class ElementTables:
    """Per-element tables of the insertions: flat element indices, singletons, excess costs."""

    elem: IntArray  # (K, S) flat element index of each tuple's entries
    singleton: IntArray  # (S, W) singleton tuple of each element, -1 for the dummy
    singleton_cost: FloatArray  # (S, W) its cost, 0 for the dummy
    excess: FloatArray  # (K + 1,) cost less that of the elements as singletons; 0 for -1
    gainful: IntArray  # tuples cheaper than their elements as singletons
    gainful_elem: IntArray  # (S, gainful) their flat element indices

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class RelaxationTables:
    """Everything a solve of one problem in one list order reads (arrays read-only)."""

    tuples: IntArray  # (K, S) in the list order of the solve
    cost: FloatArray  # (K,)
    cost_inf: FloatArray  # (K + 1,) the costs and inf, picked by the tuple index -1 (none)
    sizes: IntArray  # (S,) in the list order of the solve
    uidx: IntArray  # (S - 2, K) multiplier of each tuple's index in lists 3..S
    dummies: IntArray  # (S - 2,) positions of the dummies' multipliers (held at 0)
    groups: PairGroups
    runs: RecoveryRuns
    index: KeyIndex
    elements: ElementTables

    def __post_init__(self) -> None:
        freeze_arrays(self)


def run_starts(k: IntArray) -> BoolArray:
    """Where a run of equal values of the sorted ``k`` starts."""
    first = np.ones(k.size, dtype=bool)
    first[1:] = k[1:] != k[:-1]
    return first


def _pair_groups(t: IntArray, n: IntArray) -> PairGroups:
    K = t.shape[0]
    n1, n2 = int(n[0]), int(n[1])
    pkey = t[:, 0] * (n2 + 1) + t[:, 1]
    order = np.argsort(pkey, kind="stable")
    ks = pkey[order]
    first = run_starts(ks)
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
    return PairGroups(
        order=order,
        starts=starts,
        group_sorted=group_sorted,
        group=group,
        pair=np.column_stack([i1, i2]),
        dual_matrix=dual_matrix,
        cell_flat=cell_flat,
        cell_group=cell_group,
        cell_lookup=cell_lookup,
        zero_group=int(zero[0]) if zero.size else -1,
        free=np.flatnonzero(pkey == 0),
    )


def _recovery_runs(t: IntArray, n: IntArray, groups: PairGroups) -> RecoveryRuns:
    K, S = t.shape
    group = groups.group
    third = t[:, 2] if S > 2 else np.zeros(K, dtype=np.int64)
    seg_order = np.lexsort((third, group))
    seg_key = (group * (int(n[2:3].sum()) + 1) + third)[seg_order]
    seg_starts = np.flatnonzero(run_starts(seg_key))
    n_groups = len(groups.starts)
    return RecoveryRuns(
        seg_order=seg_order,
        seg_starts=np.append(seg_starts, K),
        seg_elem=third[seg_order[seg_starts]],
        group_seg=np.searchsorted(group[seg_order[seg_starts]], np.arange(n_groups + 1)),
    )


def _key_index(t: IntArray, n: IntArray) -> KeyIndex:
    radix = np.r_[1, np.cumprod(n[:-1] + 1)]
    key = t @ radix
    korder = np.argsort(key)
    span = int(np.prod(n + 1))
    table = np.full(span if span <= DENSE_TABLE_MAX else 0, -1, dtype=np.int64)
    if table.size:
        table[key] = np.arange(t.shape[0])
    return KeyIndex(radix=radix, keys=key[korder], key_tuple=korder, table=table)


def _element_tables(t: IntArray, n: IntArray, c: FloatArray) -> ElementTables:
    S = t.shape[1]
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
    return ElementTables(
        elem=elem,
        singleton=singleton,
        singleton_cost=singleton_cost,
        excess=np.append(c - split_cost, 0.0),
        gainful=gainful,
        gainful_elem=np.ascontiguousarray(elem[gainful].T),
    )


def relaxation_tables(problem: SdProblem, order: IntArray | None = None) -> RelaxationTables:
    """The tables of ``problem`` with its lists taken in ``order`` (a permutation of
    ``0..S-1``; None = as given): lists ``order[0]`` and ``order[1]`` form the 2-D subproblem,
    the others are relaxed. Reordering the lists of a valid problem leaves it valid, so the
    permuted tuples are not checked again."""
    t, n, c = problem.tuples, problem.sizes, problem.cost
    if order is not None:
        t, n = t[:, order], n[order]
    groups = _pair_groups(t, n)
    off = np.r_[0, np.cumsum(n[2:] + 1)][:-1]
    return RelaxationTables(
        tuples=t,
        cost=c,
        cost_inf=np.append(c, np.inf),
        sizes=n,
        uidx=np.ascontiguousarray((t[:, 2:] + off).T),
        dummies=off,
        groups=groups,
        runs=_recovery_runs(t, n, groups),
        index=_key_index(t, n),
        elements=_element_tables(t, n, c),
    )


def lookup(index: KeyIndex, key: IntArray) -> IntArray:
    """Tuple with each key (any shape), -1 where there is none."""
    if index.table.size:
        return index.table[key]
    pos = np.minimum(np.searchsorted(index.keys, key), max(len(index.keys) - 1, 0))
    if len(index.keys) == 0:
        return np.full(np.shape(key), -1, dtype=np.int64)
    return np.where(index.keys[pos] == key, index.key_tuple[pos], -1)


def tiny_tables() -> RelaxationTables:
    """The tables of a 3-list problem of one element each, to compile kernels on."""
    tuples = np.vstack([np.eye(3), np.ones(3)]).astype(np.int64)
    return relaxation_tables(SdProblem(np.ones(3, dtype=np.int64), tuples, -np.eye(4)[3]))


@cache
def list_splits(S: int) -> IntArray:
    """The ``2^(S-1) - 1`` splits of ``S`` lists into two non-empty sides, as 0/1 rows marking
    the side that holds list 1 (the dimension-wise variation cuts at every one of them, not
    only at one list: docs/multisensor.md, "S-D relaxation defaults")."""
    rows = [m for m in itertools.product((0, 1), repeat=S) if m[0] == 1 and 0 in m]
    out = np.array(rows, dtype=np.int64).reshape(-1, S)
    out.flags.writeable = False  # shared by every call (cached)
    return out
