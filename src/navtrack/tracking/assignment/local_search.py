"""Local search from a feasible S-D solution: tuple insertions and dimension-wise variation.

Every solution the relaxation recovers is improved here (:func:`improve`) before it is compared
with the best so far: tuple insertions (:func:`insert_tuples`: a tuple displaces the chosen
tuples it overlaps, their other elements fall back to singletons; all gains evaluated at once)
alternating with dimension-wise variation (:func:`vary`, Karapetyan & Gutin 2011: cut every
chosen tuple between two sides of the lists and re-pair the parts by an exact 2-D assignment;
every one of the ``2^(S-1) - 1`` splits of the lists, not only one list against the rest).

With numba installed (extra ``speed``) the insertions and the split matrices run compiled
(:mod:`~navtrack.tracking.assignment.kernels`); the NumPy passes here are their twins for an
installation without numba, with the same results (tested).

References
----------
D. Karapetyan, G. Gutin, "Local search heuristics for the multidimensional assignment
problem", J. Heuristics 17(3), 2011 (dimension-wise variation).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from navtrack._typing import FloatArray, IntArray
from navtrack.tracking.assignment import kernels
from navtrack.tracking.assignment.tables import RelaxationTables, list_splits, lookup
from navtrack.tracking.assignment.two_d import linear_assignment

__all__ = ["SplitProblem", "improve", "insert_tuples", "split_problems", "vary"]

SplitProblem = tuple[FloatArray, IntArray, IntArray, IntArray]
"""``(A, both, alone_a, alone_b)`` of one split (:func:`split_problems`)."""


def improve(prep: RelaxationTables, sel: IntArray, max_rounds: int = 50) -> IntArray:
    """Local search from the feasible ``sel``: insertions (:func:`insert_tuples`), then one round of
    dimension-wise variation (:func:`vary`), until a round lowers the cost no more."""
    for _ in range(max_rounds):
        sel = insert_tuples(prep, sel)
        cost = float(prep.cost[sel].sum())
        sel = vary(prep, sel)
        if float(prep.cost[sel].sum()) >= cost - 1e-9 * max(1.0, abs(cost)):
            break
    return sel


def insert_tuples(
    prep: RelaxationTables, sel: IntArray, max_passes: int = 1000, batch: int = 32
) -> IntArray:
    """Tuple insertions while one lowers the cost.

    Inserting tuple ``σ`` displaces the chosen tuples sharing a real element with it; their
    other elements fall back to their singletons. Its gain, for all candidate ``σ`` at once:
    ``c(σ) - s(σ) - Σ_τ (c(τ) - s(τ))`` over the distinct displaced ``τ``, ``s`` = cost of a
    tuple's elements as singletons. Insertions displacing disjoint sets gain independently,
    so each pass makes up to ``batch`` of them, best first; a candidate holding a dummy
    counts as overlapping every other such candidate, so a pass inserts at most one of those.

    With numba the same passes run compiled, one candidate at a time (:func:`~navtrack.
    tracking.assignment.kernels.insert_loop`); the NumPy passes here are its twin.
    """
    kernel = kernels.compiled_insert()
    if kernel is not None:
        width = prep.elements.singleton.shape[1]
        return kernel(
            np.array(sel, dtype=np.int64),  # writable: one compiled signature
            prep.cost,
            prep.elements.gainful,
            prep.elements.excess,
            prep.elements.elem,
            prep.elements.singleton.ravel(),
            width,
            max_passes,
            batch,
        )
    c, elem, single = prep.cost, prep.elements.elem, prep.elements.singleton.ravel()
    cand, cand_elem, w = prep.elements.gainful, prep.elements.gainful_elem, prep.elements.excess
    base = w[cand]
    S = elem.shape[1]
    dummy = prep.elements.singleton.shape[1] * np.arange(S)  # flat indices of the dummies
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


def vary(prep: RelaxationTables, sel: IntArray) -> IntArray:
    """One round of dimension-wise variation (Karapetyan & Gutin 2011) on ``sel``.

    For each split of the lists into two sides (:func:`~navtrack.tracking.assignment.tables.
    list_splits`) in turn, every chosen tuple is
    cut into its part on one side and its part on the other; the parts are re-paired by one
    exact 2-D assignment with dummies (a part may stand alone when that tuple exists), which
    never costs more than the current pairing. After a split that lowers the cost, the next
    ones cut the new solution.
    """
    sides = list_splits(prep.tuples.shape[1])
    current = float(prep.cost[sel].sum())
    done = 0
    while done < len(sides):
        for problem in split_problems(prep, sel, sides[done:]):
            done += 1
            if problem is None:
                continue
            A, both, alone_a, alone_b = problem
            R, C = both.shape
            r, c = linear_assignment(A)
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


def split_problems(
    prep: RelaxationTables, sel: IntArray, sides: IntArray
) -> Iterator[SplitProblem | None]:
    """For each split in ``sides`` (rows of :func:`~navtrack.tracking.assignment.tables.
    list_splits`), the 2-D problem re-pairing the parts of the chosen tuples ``sel``, None when
    one side holds no real element.

    Each is ``(A, both, alone_a, alone_b)``: the augmented ``(R + C) × (C + R)`` matrix of the
    ``R`` side-1 parts and ``C`` side-2 parts, the tuple joining each pair of parts (-1 none,
    cost inf), and each part's tuple on its own (its dummy entry). With numba all splits are
    built by one compiled call (:func:`~navtrack.tracking.assignment.kernels.split_loop`), the
    same matrices; the NumPy loop here is its twin.
    """
    part = (
        prep.tuples[sel] * prep.index.radix
    )  # (r, S) each list's share of the chosen tuples' keys
    kernel = kernels.compiled_splits()
    if kernel is not None:
        args = prep.index.table, prep.index.keys, prep.index.key_tuple, prep.cost_inf
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
        both = lookup(prep.index, a[:, None] + b[None, :])  # keys add: the parts are disjoint
        alone_a, alone_b = lookup(prep.index, a), lookup(prep.index, b)
        A = np.full((R + C, C + R), np.inf)
        A[:R, :C] = cost[both]  # the index -1 (no such tuple) picks inf
        A.flat[C + (R + C + 1) * np.arange(R)] = cost[alone_a]
        A.flat[(R + C) * R + (R + C + 1) * np.arange(C)] = cost[alone_b]
        A[R:, C:] = 0.0
        yield A, both, alone_a, alone_b
