"""The numba kernels of the S-D relaxation and local search, and their compiled forms.

numba is optional (extra ``speed``), and the S-D solvers serve user paths without it (the
``sd_gnn`` tracker of ``navtrack reproduce sdcmsjpda``, :func:`~navtrack.tracking.assignment.
sd_assign`), so each kernel here has a NumPy twin that runs when numba is absent; the tests check
that both give the same numbers, bit for bit:

========================  ==================================================================
compiled (this module)    NumPy twin
========================  ==================================================================
:func:`pair_loop`         :func:`navtrack.tracking.assignment.relaxation.pair_costs`
:func:`insert_loop`       :func:`navtrack.tracking.assignment.local_search.insert_tuples`
:func:`split_loop`        :func:`navtrack.tracking.assignment.local_search.split_problems`
========================  ==================================================================

The loops are plain Python over scalars (what numba compiles well); :func:`compiled_pairs`,
:func:`compiled_insert` and :func:`compiled_splits` return them compiled, or None without numba.
The callers look them up through this module at each call, so a test may replace them.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np

from navtrack._numba import jit
from navtrack._typing import FloatArray, IntArray
from navtrack.tracking.assignment.tables import list_splits, tiny_tables

__all__ = [
    "compile_kernels",
    "compiled_insert",
    "compiled_pairs",
    "compiled_splits",
    "insert_loop",
    "pair_loop",
    "split_loop",
]


def pair_loop(
    cost: FloatArray, uidx: IntArray, u: FloatArray, order: IntArray, starts: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """:func:`~navtrack.tracking.assignment.relaxation.pair_costs`' reduced costs (summed in
    :func:`~navtrack.tracking.assignment.relaxation.reduced_costs`' order), least reduced
    cost per pair and the first tuple reaching it, in scalar loops for numba
    (:func:`compiled_pairs`)."""
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
def compiled_pairs() -> Callable[..., tuple[FloatArray, FloatArray, IntArray]] | None:
    """:func:`pair_loop` compiled by numba (on the first call, for the read-only arrays of the
    relaxation tables and a writable ``u``), or None without numba."""
    kernel = jit(pair_loop)
    if kernel is None:
        return None
    tiny = tiny_tables()
    kernel(tiny.cost, tiny.uidx, np.zeros(2), tiny.groups.order, tiny.groups.starts)
    return kernel


def insert_loop(
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
    """The passes of :func:`~navtrack.tracking.assignment.local_search.insert_tuples` in scalar
    loops, for numba (:func:`compiled_insert`): the same gains, subtracted in the same order,
    the same choices and the same order of the result.

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


@lru_cache(maxsize=1)
def compiled_insert() -> Callable[..., IntArray] | None:
    """:func:`insert_loop` compiled by numba, or None without numba (the insertions then run
    their NumPy passes). Compiled on the first call for the argument types the insertions pass
    (a writable ``sel``, the read-only relaxation tables): about a second, a tenth of that when
    loaded from numba's disk cache."""
    kernel = jit(insert_loop)
    if kernel is None:
        return None
    tiny = tiny_tables()
    width = tiny.elements.singleton.shape[1]
    args = (
        tiny.cost,
        tiny.elements.gainful,
        tiny.elements.excess,
        tiny.elements.elem,
        tiny.elements.singleton.ravel(),
    )
    kernel(np.arange(3), *args, width, 1, 1)  # compiled here, for the types _insert passes
    return kernel


def compile_kernels() -> None:
    """Compile the relaxation's numba kernels now (nothing to do without numba), so that no
    timed solve pays for it."""
    compiled_insert()
    compiled_splits()
    compiled_pairs()


def split_loop(
    part: IntArray,
    sides: IntArray,
    table: IntArray,
    keys: IntArray,
    key_tuple: IntArray,
    cost_inf: FloatArray,
) -> tuple[FloatArray, IntArray, IntArray, IntArray, IntArray]:
    """The matrices of :func:`~navtrack.tracking.assignment.local_search.split_problems` for all
    ``sides`` in scalar loops, for numba (:func:`compiled_splits`); keys looked up as
    :func:`~navtrack.tracking.assignment.tables.lookup` does.

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
def compiled_splits() -> (
    Callable[..., tuple[FloatArray, IntArray, IntArray, IntArray, IntArray]] | None
):
    """:func:`split_loop` compiled by numba, or None without numba (the split matrices are then
    built with NumPy). Compiled on the first call for the argument types the local search
    passes, with the dense key table and without."""
    kernel = jit(split_loop)
    if kernel is None:
        return None
    for size in (1, 0):  # a dense key table and none (the sorted keys)
        tiny = tiny_tables()
        table = tiny.index.table[: size * tiny.index.table.size]
        kernel(
            tiny.tuples[:1] * tiny.index.radix,
            list_splits(3),
            table,
            tiny.index.keys,
            tiny.index.key_tuple,
            tiny.cost_inf,
        )
    return kernel
