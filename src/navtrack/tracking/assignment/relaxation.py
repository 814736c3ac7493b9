"""S-D assignment (``S >= 3`` lists) by Lagrangian relaxation, with recovery and local search.

The problem and its exact and greedy solvers: :mod:`navtrack.tracking.assignment.problem`.

**Relaxation** (Deb et al. 1997, section III; Poore & Rijavec 1993). The constraints of lists
3..S are moved into the objective with multipliers ``u_s (n_s + 1)`` (``u_s[0] = 0``), reduced
costs ``c - Σ_s u_s[i_s]`` (:func:`reduced_costs`). What remains is a 2-D assignment of lists 1
and 2 with dummies: pair ``(i_1, i_2)`` costs the least reduced cost of its tuples
(:func:`pair_costs`), and the tuples with ``i_1 = i_2 = 0`` are free (taken when their reduced
cost is negative). Its optimum plus ``Σ u`` is a lower bound (:func:`relaxed_dual`); the
multipliers climb it by subgradient steps ``u += α (UB - LB) g / |g|²`` (Polyak step, ``α``
halved after ``patience`` iterations without progress, Held, Wolfe & Crowder 1974) with
``g = 1 - (times each index is used)``; each iteration is a few vectorised passes over the
tuple arrays and one ``linear_sum_assignment``.

**Recovery** (Deb et al. 1997, section IV, in its sequential form; :func:`recover`). A
feasible solution is recovered (when the bound improved, and every ``recover_every``
iterations) from the pairs the 2-D solution chose: they are fixed as partial tuples and list
3, 4, ..., S is joined to them by one 2-D assignment each, costed by the least reduced cost
over the lists not yet joined; a partial tuple may also be dissolved into its singletons, so
every step is feasible; a pass recovers from each set of pairs once. Every recovered solution
is then improved by the local search (:mod:`navtrack.tracking.assignment.local_search`). The
best feasible cost is the upper bound; ``UB - LB`` is the duality gap reported.

**Passes over list orders** (:func:`list_orders`). While the gap stays open the problem is
solved again with its lists reordered (other lists relaxed, other pairs fixed): the ``S``
rotations, and for ``S >= 5`` also the orders keeping each other pair of lists; the
recoveries differ, and that, with the local search, is what brings the sparse S = 4, 5
problems within 1 % of the optimum (``benchmarks/bench_sd_assignment.py``). A later pass starts
where the best bound so far stands: the lists it relaxes keep their multipliers, and the two
lists that were kept get theirs from the dual of that bound's 2-D problem
(:func:`kept_multipliers`: potentials of the augmented assignment by Bellman-Ford on its
residual graph), so together they are a dual of the whole problem and the pass climbs on from
there with a smaller step factor (:data:`WARM_STEP_FACTOR`) instead of starting again at zero.

**Defaults**: :data:`MAX_ITER` multiplier updates per pass; every rotation for S <= 4, every
pair of lists for S >= 5; recovery every 3 iterations; step factor 2 for the first pass and
:data:`WARM_STEP_FACTOR` for the warm-started ones. How they were chosen and judged:
docs/multisensor.md, "S-D relaxation defaults".

**Cost**: on the 4-list benchmark problems (~4400 tuples) a solve is ~180 multiplier updates,
~60 recoveries and as many local searches; the variation (its 2-D assignments), the recovery
and the updates take most of the time. What does not change during a solve is built once per
list order (:func:`~navtrack.tracking.assignment.tables.relaxation_tables`), so each step is a
few array operations on the tuples concerned. The last list of a recovery needs no minimum (a
prefix and ``i_S`` fix one tuple). With numba installed the pair costs run compiled
(:func:`~navtrack.tracking.assignment.kernels.pair_loop`); :func:`pair_costs`' NumPy path is
its twin for an installation without numba, with the same numbers (tested).

References
----------
.. [1] S. Deb, M. Yeddanapudi, K. Pattipati, Y. Bar-Shalom, "A generalized S-D assignment
   algorithm for multisensor-multitarget state estimation", IEEE T-AES 33(2), 1997.
.. [2] A. B. Poore, N. Rijavec, "A Lagrangian relaxation algorithm for multidimensional
   assignment problems arising from multitarget tracking", SIAM J. Optim. 3(3), 1993.
.. [3] M. Held, P. Wolfe, H. P. Crowder, "Validation of subgradient optimization", Math.
   Programming 6, 1974 (Polyak step with a halving step factor).
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np

from navtrack._typing import FloatArray, IntArray
from navtrack.tracking.assignment import kernels
from navtrack.tracking.assignment.local_search import improve
from navtrack.tracking.assignment.problem import (
    SdMethod,
    SdProblem,
    SdSolution,
    SdStatus,
    sd_exact,
    sd_greedy,
)
from navtrack.tracking.assignment.tables import RelaxationTables, relaxation_tables, run_starts
from navtrack.tracking.assignment.two_d import assignment_potentials, linear_assignment

__all__ = [
    "MAX_ITER",
    "WARM_STEP_FACTOR",
    "kept_multipliers",
    "list_orders",
    "pair_costs",
    "recover",
    "reduced_costs",
    "relaxation_solution",
    "relaxed_dual",
    "sd_assign",
    "sd_lagrangian",
]


def _ranges(start: IntArray, length: IntArray) -> IntArray:
    """The ranges ``start[i] .. start[i] + length[i] - 1``, concatenated."""
    return np.arange(int(length.sum())) + np.repeat(start - (np.cumsum(length) - length), length)


def reduced_costs(
    prep: RelaxationTables, u: FloatArray, idx: IntArray | None = None, first: int = 0
) -> FloatArray:
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


def pair_costs(
    prep: RelaxationTables, u: FloatArray
) -> tuple[FloatArray, FloatArray, IntArray, FloatArray]:
    """The relaxed problem for the multipliers ``u`` (L,) of lists 3..S.

    Returns ``(reduced costs (K,), least reduced cost per pair (G,), the first tuple (in pair
    order) reaching it, the augmented 2-D matrix)``: the pair groups' ``dual_matrix`` with the
    pairs' costs filled in. With numba the reduced costs and the pairs' least ones come from
    one compiled pass over the tuples (:func:`~navtrack.tracking.assignment.kernels.
    pair_loop`), the same numbers; without it, the NumPy path here (its twin).
    """
    kernel = kernels.compiled_pairs()
    if kernel is not None:
        red, mins, best = kernel(prep.cost, prep.uidx, u, prep.groups.order, prep.groups.starts)
    else:
        red = reduced_costs(prep, u)
        rs = red[prep.groups.order]
        mins = np.minimum.reduceat(rs, prep.groups.starts)
        pos = np.flatnonzero(rs <= mins[prep.groups.group_sorted])
        best = prep.groups.order[pos[run_starts(prep.groups.group_sorted[pos])]]
    A = prep.groups.dual_matrix.copy()
    A.flat[prep.groups.cell_flat] = mins[prep.groups.cell_group]
    return red, mins, best, A


def relaxed_dual(prep: RelaxationTables, u: FloatArray) -> tuple[float, IntArray, IntArray]:
    """Optimum of the relaxed problem for the multipliers ``u`` (L,) of lists 3..S.

    Each pair's cost is the least reduced cost ``c - Σ_s u_s[i_s]`` of its tuples (one
    ``minimum.reduceat`` over the tuples sorted by pair); the 2-D problem with dummies is one
    ``linear_sum_assignment`` on the ``(n_1 + n_2) × (n_2 + n_1)`` augmented matrix.

    Returns ``(lower bound, selected tuples, chosen groups other than (0, 0))``.
    """
    red, mins, best, A = pair_costs(prep, u)
    r, c = linear_assignment(A)
    chosen = prep.groups.cell_lookup[r, c]
    chosen = np.sort(chosen[chosen >= 0])
    sel = best[chosen]
    lb = float(mins[chosen].sum() + u.sum())
    neg = prep.groups.free[
        red[prep.groups.free] < 0
    ]  # tuples of the pair (0, 0) are free in the relaxation
    return lb + float(red[neg].sum()), np.concatenate([sel, neg]), chosen


def kept_multipliers(prep: RelaxationTables, u: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Multipliers of lists 1 and 2 (each with the dummy's 0 first) that complete ``u`` to a
    dual of the whole problem: the LP dual of the relaxed 2-D problem with dummies.

    From the augmented matrix's potentials ``(a, b)``: ``v_1[i] = a[i] + b[n_2 + i]`` and
    ``v_2[j] = b[j] + a[n_1 + j]`` meet ``v_1[i] + v_2[j] <= m(i, j)``, ``v_1[i] <= m(i, 0)``,
    ``v_2[j] <= m(0, j)`` (the dummy block is 0) and sum to the 2-D optimum.
    """
    A = pair_costs(prep, u)[3]
    a, b = assignment_potentials(A, *linear_assignment(A))
    n1, n2 = int(prep.sizes[0]), int(prep.sizes[1])
    return np.r_[0.0, a[:n1] + b[n2:]], np.r_[0.0, b[:n2] + a[n1:]]


def recover(prep: RelaxationTables, chosen: IntArray, u: FloatArray) -> IntArray:
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
    prefix[:, :2] = prep.groups.pair[chosen]
    dissolve = (
        prep.elements.singleton_cost[0, prefix[:, 0]]
        + prep.elements.singleton_cost[1, prefix[:, 1]]
    )
    lut = np.full(len(prep.groups.starts), -1, dtype=np.int64)
    lut[chosen] = np.arange(1, P + 1)
    if prep.groups.zero_group >= 0:
        lut[prep.groups.zero_group] = 0  # prefix 0: nothing fixed yet
    # the tuples of the fixed pairs and of (0, 0), in runs of equal (pair, i_3)
    runs = _ranges(prep.runs.group_seg[:-1][lut >= 0], np.diff(prep.runs.group_seg)[lut >= 0])
    lo = prep.runs.seg_starts[runs]
    length = prep.runs.seg_starts[runs + 1] - lo
    idx = prep.runs.seg_order[_ranges(lo, length)]
    pid = lut[prep.groups.group[idx]]  # prefix of each of these tuples
    out: list[IntArray] = []
    for k in range(2, S):
        width = int(n[k]) + 1
        key = pid * width + t[idx, k]
        flat = np.full((P + 1) * width, np.inf)
        if k == S - 1:  # one tuple per key
            flat[key] = cost[idx]
        elif k == 2:  # least reduced cost over each run
            first = np.cumsum(length) - length
            mins = np.minimum.reduceat(reduced_costs(prep, u, idx, 1), first)
            flat[pid[first] * width + prep.runs.seg_elem[runs]] = mins
        else:
            red = reduced_costs(prep, u, idx, k - 1)
            o = np.lexsort((red, key))
            ko = key[o]
            head = run_starts(ko)
            flat[ko[head]] = red[o[head]]
        M = flat.reshape(P + 1, width)
        nk = width - 1
        use_dis = dissolve < M[1:, 0]
        A = np.full((P + nk, nk + P), np.inf)
        A[:P, :nk] = M[1:, 1:]
        A.flat[nk + (P + nk + 1) * np.arange(P)] = np.minimum(M[1:, 0], dissolve)
        A.flat[(P + nk) * P + (P + nk + 1) * np.arange(nk)] = M[0, 1:]
        A[P:, nk:] = 0.0
        c = linear_assignment(A)[1]  # the rows in order: the P prefixes, then the list-k elements
        pc, ec = c[:P], c[P:]
        miss = pc >= nk
        joined = np.flatnonzero(~miss)
        stay = np.flatnonzero(miss & ~use_dis)
        new_i = ec[ec < nk]  # list-k elements starting a prefix of their own
        ent_r = np.concatenate([joined, stay, np.full(new_i.size, -1)]) + 1
        ent_c = np.concatenate([pc[joined] + 1, np.zeros(stay.size, dtype=np.int64), new_i + 1])
        dis = prefix[miss & use_dis]
        out.append(prep.elements.singleton[np.nonzero(dis)[1], dis[dis > 0]])
        if k == S - 1:
            arg = np.full(flat.size, -1, dtype=np.int64)
            arg[key] = idx
            out.append(arg[ent_r * width + ent_c])
            break
        prefix = np.vstack([np.zeros((1, S), dtype=np.int64), prefix])[ent_r]
        prefix[:, k] = ent_c
        dissolve = np.concatenate([[0.0], dissolve])[ent_r] + prep.elements.singleton_cost[k, ent_c]
        P = ent_r.size
        new = np.full(flat.size, -1, dtype=np.int64)
        new[0] = 0
        new[ent_r * width + ent_c] = np.arange(1, P + 1)
        pid = new[key]
        idx, pid = idx[pid >= 0], pid[pid >= 0]
    return np.concatenate(out)


def _solve_2d(problem: SdProblem) -> IntArray:
    """Exact 2-D assignment with dummies on both lists (augmented ``linear_sum_assignment``)."""
    return relaxed_dual(relaxation_tables(problem), np.zeros(0))[1]


def _relaxation_pass(
    prep: RelaxationTables,
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

    ``seen`` maps each solution already polished by :func:`~navtrack.tracking.assignment.
    local_search.improve` (sorted tuple indices) to its result: the local search is
    deterministic, so it runs once per solution, across the rotated passes too (they share
    the tuple order). A pass recovers from each set of pairs once (a set fixed again would
    give the same recovery).

    Returns ``(upper bound, best feasible tuples, lower bound, iterations, multipliers of the
    lower bound)``.
    """

    def polished(sel: IntArray) -> IntArray:
        key = np.sort(sel).tobytes()
        if key not in seen:
            seen[key] = improve(prep, sel)
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
        phi, sel, chosen = relaxed_dual(prep, u)
        improved = lb == -np.inf or phi > lb + 1e-12 * max(1.0, abs(lb))
        fixed = chosen.tobytes()
        if (improved or it % recover_every == 0) and fixed not in tried:
            tried.add(fixed)
            rec = polished(recover(prep, chosen, u))
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


#: Step factor ``α`` of the warm-started passes (the first pass starts at 2); how it was chosen:
#: docs/multisensor.md, "S-D relaxation defaults".
WARM_STEP_FACTOR = 0.5


def list_orders(S: int) -> list[IntArray]:
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


#: Multiplier updates per pass of :func:`sd_lagrangian`; how it was chosen: docs/multisensor.md,
#: "S-D relaxation defaults".
MAX_ITER = 45


def sd_lagrangian(
    problem: SdProblem, max_iter: int = MAX_ITER, tol: float = 1e-3, restarts: int | None = None
) -> SdSolution:
    """S-D assignment by Lagrangian relaxation of lists 3..S (module notes).

    Parameters
    ----------
    problem : SdProblem with ``S >= 3`` lists
    max_iter : int
        Multiplier updates per pass (default :data:`MAX_ITER`).
    tol : float
        Stop when ``UB - LB <= tol · |UB|`` (relative duality gap).
    restarts : int, optional
        While the gap stays open, solve again with other lists kept in the 2-D subproblem (up
        to this many times, at most ``C(S, 2) - 1``; :func:`list_orders`), each pass warm-started
        at the best bound so far (module notes); the best solution and bound of all passes are
        kept. Default: every rotation for ``S <= 4`` (``S - 1``), every pair of lists for
        ``S >= 5`` (``C(S, 2) - 1``).

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
        return relaxation_solution(
            problem, problem.tuples[:0, 0], 0.0, 0, SdStatus.OPTIMAL, "empty"
        )
    seen: dict[bytes, IntArray] = {}  # polished solutions, shared by the passes
    greedy = sd_greedy(problem).selected
    mult = [np.zeros(int(k) + 1) for k in problem.sizes]  # per list, the dummy's 0 first
    ub, sel, lb, it = np.inf, greedy, -np.inf, 0
    for n_pass, order in enumerate(list_orders(S)[: min(restarts, pairs - 1) + 1]):
        # the same problem with its lists reordered: other pairs are fixed by the recovery
        prep = relaxation_tables(problem, order)
        u0 = np.concatenate([mult[k] for k in order[2:]])
        alpha = 2.0 if n_pass == 0 else WARM_STEP_FACTOR
        ub2, sel2, lb2, it2, u = _relaxation_pass(prep, max_iter, tol, greedy, seen, u0, alpha)
        it += it2
        if ub2 < ub:
            ub, sel = ub2, sel2
        if ub - min(max(lb, lb2), ub) <= tol * max(abs(ub), 1e-12):
            lb = max(lb, lb2)
            break
        if lb2 > lb:
            lb = lb2
            split = np.cumsum(prep.sizes[2:-1] + 1)
            for k, uk in zip(order[2:], np.split(u, split), strict=True):
                mult[k] = uk
            mult[order[0]], mult[order[1]] = kept_multipliers(prep, u)
    lb = min(lb, ub)
    closed = ub - lb <= tol * max(abs(ub), 1e-12)
    status = SdStatus.OPTIMAL if closed else SdStatus.GAP
    rel = (ub - lb) / max(abs(ub), 1e-12)
    msg = f"relative duality gap {rel:.2e} after {it} iterations"
    return relaxation_solution(problem, sel, lb, it, status, msg)


def relaxation_solution(
    problem: SdProblem, selected: IntArray, lb: float, it: int, status: SdStatus, message: str
) -> SdSolution:
    """The :class:`~navtrack.tracking.assignment.problem.SdSolution` of a relaxation: the tuples
    ``selected``, lower bound ``lb``, ``it`` multiplier updates."""
    return SdSolution.from_selection(
        problem,
        selected,
        lower_bound=lb,
        iterations=it,
        method=SdMethod.LAGRANGIAN,
        status=status,
        message=message,
    )


def sd_assign(
    problem: SdProblem,
    method: str = "auto",
    *,
    max_exact_tuples: int = 5000,
    max_iter: int = MAX_ITER,
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
        return SdSolution.from_selection(
            problem,
            sel,
            lower_bound=float(problem.cost[sel].sum()),
            iterations=0,
            method=SdMethod.EXACT,
            status=SdStatus.OPTIMAL,
            message="optimal (2-D)",
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
        message = f"exact solver not used ({why}); Lagrangian relaxation: {lr.message}"
        return replace(lr, status=SdStatus.TOO_LARGE, message=message)
    return sd_lagrangian(problem, max_iter, tol)


# --------------------------------------------------------------------------------------------
# k-best S-D solutions (Murty's partitioning with exact or relaxed cells)
