"""Joint probabilistic data association: marginals, clusters, PDA update.

Association weights
    For track ``t`` and measurement ``j`` inside its gate,
    ``W[t, j+1] = P_D · N(z_j; ẑ_t, S_t) / λ``;
    the missed-detection weight is ``W[t, 0] = 1 - P_D · P_G``; pairs outside the gate have
    weight 0. A joint event (each track takes one measurement or none, each measurement used at
    most once) has probability proportional to the product of its tracks' weights
    (Bar-Shalom & Fortmann 1988, eq. 9.2.4-x, parametric JPDA with Poisson clutter of spatial
    density ``λ``; the same weights as Stone Soup's ``PDAHypothesiser``). The marginal
    ``beta[t, j]`` is the probability that track ``t`` took option ``j`` (0 = none).

Exact marginals by variable elimination over measurements
    Tracks of one cluster are put in a bandwidth-reducing order (reverse Cuthill–McKee on the
    track-conflict graph). A forward pass carries, for every subset of the *active*
    measurements (taken by an earlier track and still gateable by a later one), the summed
    weight of all partial events of the earlier tracks that use exactly that subset; a backward
    pass carries the summed weight of the later tracks' events avoiding a subset. The message
    is a tensor with one axis of length 2 per active measurement; a measurement no later track
    can take is summed out, one not yet seen is appended. The marginal of (t, j) is one
    contraction of forward and backward messages. Measurements gated by one track only never
    enter the messages (they are folded into that track's "no shared measurement" option).
    Cost ``O(T · m_t · 2^a)`` for ``a`` the largest active set: this is the structure exploited
    by the efficient hypothesis management of Maskell et al. (2004) and Horridge & Maskell
    (2006), written as dense tensor contractions instead of a tree of nodes.

Small clusters
    A cluster that shares a single measurement (a report inside the gates of several moored
    ships) has closed-form marginals, computed for all such clusters of a scan at once
    (``_one_shared``); a cluster of at most ``DENSE_EVENTS`` joint events is enumerated densely
    (:func:`jpda_marginals_batch`). Both are exact, like the elimination, and cheaper for these
    shapes.

k-best approximation
    When ``a`` would exceed ``JpdaConfig.max_exact_bits`` the cluster's events are the ``k`` most
    probable ones from Murty's algorithm (costs ``-log W``). The neglected mass ``R`` is bounded
    by ``min(prod_t sum_j W[t, j] - found, n_rest · w_k)`` (``w_k`` the weight of the ``k``-th
    event, ``n_rest <= prod_t (1 + gated_t) - k``), and every marginal is then within
    ``R / (found + R)`` of the exact one; that bound is reported per track.

References
----------
.. [1] Y. Bar-Shalom, T. E. Fortmann, *Tracking and Data Association*, Academic Press 1988,
   chapter 9 (JPDA) and section 6.4 (PDA update, eq. 6.4.1-x: combined innovation and the
   spread-of-innovations term).
.. [2] T. E. Fortmann, Y. Bar-Shalom, M. Scheffe, "Sonar tracking of multiple targets using
   joint probabilistic data association", IEEE J. Oceanic Eng. 8(3), 1983.
.. [3] S. Maskell, M. Briers, R. Wright, "Fast mutual exclusion", Proc. SPIE 5428, 2004;
   P. Horridge, S. Maskell, "Real-time tracking of hundreds of targets with efficient exact
   JPDAF implementation", FUSION 2006.
.. [4] K. G. Murty 1968 (see :mod:`navtrack.tracking.assignment`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum
from functools import lru_cache
from math import comb, perm

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.kalman import gain_update, innovation_gain, kf_predict
from navtrack.estimation.models import MeasurementModel
from navtrack.tracking.assignment import murty
from navtrack.tracking.gating import chi2_threshold, gate

__all__ = [
    "JpdaConfig",
    "JpdaMarginals",
    "JpdaMethod",
    "JpdaStep",
    "association_weights",
    "clusters",
    "joint_events",
    "jpda_marginals",
    "jpda_marginals_batch",
    "jpda_step",
    "jpda_step_batch",
    "n_joint_events",
    "pda_update",
]


class JpdaMethod(IntEnum):
    """How a track's marginals were computed (``JpdaMarginals.method``)."""

    PDA = 0  # track alone in its cluster: single-track PDA in closed form (exact)
    EXACT = 1  # exact joint association (enumeration or variable elimination)
    KBEST = 2  # the k most probable joint events (Murty), with an error bound


@dataclass(frozen=True, slots=True)
class JpdaConfig:
    """JPDA parameters.

    Attributes
    ----------
    pd : float
        Detection probability ``P_D`` in (0, 1].
    clutter_density : float
        Spatial density of false measurements ``λ`` (per unit measurement volume, e.g. per m²
        or per m·rad), > 0.
    gate_probability : float
        ``P_G``; the gate is the chi-square ellipsoid of this probability (1 = no gate).
    max_exact_bits : int
        Largest active-measurement set for exact marginals (tensor of ``2**bits`` floats).
        Default 20 (8 MB per message).
    k_best : int
        Number of joint events used above that limit.
    """

    pd: float = 0.9
    clutter_density: float = 1e-6
    gate_probability: float = 0.99
    max_exact_bits: int = 20
    k_best: int = 1000

    def __post_init__(self) -> None:
        if not 0.0 < self.pd <= 1.0:
            raise ValueError(f"pd must be in (0, 1], got {self.pd}")
        if not (np.isfinite(self.clutter_density) and self.clutter_density > 0):
            raise ValueError(f"clutter_density must be finite and > 0, got {self.clutter_density}")
        if not 0.0 < self.gate_probability <= 1.0:
            raise ValueError(f"gate_probability must be in (0, 1], got {self.gate_probability}")
        if not 1 <= self.max_exact_bits <= 30:
            raise ValueError(f"max_exact_bits must be in 1..30, got {self.max_exact_bits}")
        if self.k_best < 1:
            raise ValueError(f"k_best must be >= 1, got {self.k_best}")


@dataclass(frozen=True, slots=True, eq=False)
class JpdaMarginals:
    """Marginal association probabilities of one scan (arrays read-only).

    Attributes
    ----------
    beta : (T, M+1)
        ``beta[t, 0]`` probability that track ``t`` took no measurement, ``beta[t, j+1]`` that it
        took measurement ``j``. Rows sum to 1; column sums (``j >= 1``) are <= 1.
    cluster : (T,) int
        Cluster label of each track (tracks sharing no measurement, directly or through others,
        are in different clusters).
    method : (T,) int8
        :class:`JpdaMethod`: 0 track alone in its cluster (PDA, exact), 1 exact joint
        association, 2 k-best.
    error_bound : (T,)
        Bound on ``|beta - beta_exact|`` for every entry of the row (0 where exact).
    n_events : (T,) int
        Joint events summed for the track's cluster (``-1`` = exact, not enumerated one by one).
    """

    beta: FloatArray
    cluster: IntArray
    method: np.ndarray
    error_bound: FloatArray
    n_events: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def association_weights(
    log_likelihood: ArrayLike,
    valid: ArrayLike,
    pd: float,
    gate_probability: float,
    clutter_density: float,
) -> FloatArray:
    """Weights ``W (..., T, M+1)`` as in the module notes, each row scaled to max 1.

    Row scaling multiplies every joint event by the same factor, so marginals are unchanged
    and products of many tracks stay in floating-point range.
    """
    ll = np.asarray(log_likelihood, dtype=float)
    ok = np.asarray(valid, dtype=bool)
    logw = np.full((*ll.shape[:-1], ll.shape[-1] + 1), -np.inf)
    logw[..., 0] = np.log1p(-pd * gate_probability) if pd * gate_probability < 1 else -np.inf
    logw[..., 1:] = np.where(ok, ll + np.log(pd) - np.log(clutter_density), -np.inf)
    mx = logw.max(axis=-1, keepdims=True)
    mx = np.where(np.isfinite(mx), mx, 0.0)
    return np.asarray(np.exp(logw - mx))


def clusters(W: ArrayLike) -> tuple[int, IntArray]:
    """Connected components of tracks linked by shared gated measurements.

    Returns ``(n_clusters, label (T,))``, labels numbered in order of first track.
    """
    G = np.asarray(W)[:, 1:] > 0
    T, M = G.shape
    if T == 0:
        return 0, np.zeros(0, dtype=np.int64)
    # a track gating nothing is alone; the components are found among the gating tracks only
    # (a scan of real data gates a few of its many tracks)
    rows = np.flatnonzero(G.any(axis=1))
    Gr = G[rows]
    first = np.arange(T)  # first track of each track's component
    if rows.size > 256:
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        t, j = np.nonzero(Gr)
        n = rows.size + M
        A = coo_matrix((np.ones(t.size), (t, rows.size + j)), shape=(n, n))
        _, lab = connected_components(A, directed=False)
        lab = lab[: rows.size]
        lowest = np.full(lab.max() + 1, rows.size)
        np.minimum.at(lowest, lab, np.arange(rows.size))
        first[rows] = rows[lowest[lab]]
    elif rows.size:
        Gi = Gr.astype(np.int64)
        R = (Gi @ Gi.T > 0) | np.eye(rows.size, dtype=bool)
        while True:  # transitive closure by repeated squaring
            Ri = R.astype(np.int64)
            R2 = (Ri @ Ri) > 0
            if np.array_equal(R2, R):
                break
            R = R2
        first[rows] = rows[np.argmax(R, axis=1)]
    root = first == np.arange(T)  # the first track of its component
    return int(np.count_nonzero(root)), (np.cumsum(root) - 1)[first].astype(np.int64)


def jpda_marginals(W: ArrayLike, config: JpdaConfig | None = None) -> JpdaMarginals:
    """Marginal association probabilities from weights ``W (T, M+1)`` (column 0 = missed).

    Tracks are split into clusters; a track alone is solved in closed form (PDA), a cluster is
    solved exactly if its active set fits ``config.max_exact_bits``, else by Murty k-best.
    """
    cfg = config or JpdaConfig()
    W = np.asarray(W, dtype=float)
    if W.ndim != 2 or W.shape[1] < 1:
        raise ValueError(f"W must be (T, M+1), got shape {W.shape}")
    if np.any(~np.isfinite(W)) or np.any(W < 0):
        raise ValueError("W must be finite and >= 0")
    T = W.shape[0]
    beta = np.zeros_like(W)
    method = np.full(T, JpdaMethod.PDA, dtype=np.int8)
    err = np.zeros(T)
    n_events = np.full(T, -1, dtype=np.int64)
    gated = W[:, 1:] > 0
    if T == 0 or gated.sum(axis=0).max(initial=0) <= 1:
        # no measurement shared: every track is its own cluster (PDA)
        s = W.sum(axis=1, keepdims=True)
        if np.any(s <= 0):
            raise ValueError(f"track {int(np.flatnonzero(s <= 0)[0])}: all weights are zero")
        return JpdaMarginals(W / s, np.arange(T, dtype=np.int64), method, err, n_events)
    n_cl, lab = clusters(W)
    size = np.bincount(lab, minlength=n_cl)
    single = size[lab] == 1
    if single.any():  # tracks alone in their cluster: PDA in closed form, all at once
        s = W[single].sum(axis=1, keepdims=True)
        if np.any(s <= 0):
            raise ValueError("a track has all association weights zero")
        beta[single] = W[single] / s
    done = _one_shared(W, gated, lab, size, beta)
    method[done] = JpdaMethod.EXACT
    order = np.argsort(lab, kind="stable")
    rest = np.flatnonzero((size > 1) & ~np.bincount(lab[done], minlength=n_cl).astype(bool))
    bounds = np.searchsorted(lab[order], rest)
    for c, b0 in zip(rest, bounds, strict=True):
        tr = order[b0 : b0 + size[c]]
        cols = np.flatnonzero(gated[tr].any(axis=0))
        Wc = W[np.ix_(tr, np.concatenate([[0], cols + 1]))]
        if n_joint_events(tr.size, cols.size) <= DENSE_EVENTS:
            # small cluster: dense enumeration of its joint events is cheapest
            bc = jpda_marginals_batch(Wc)
            method[tr] = JpdaMethod.EXACT
            beta[tr, 0] = bc[:, 0]
            beta[np.ix_(tr, cols + 1)] = bc[:, 1:]
            continue
        plan = _order_and_sets(Wc[:, 1:] > 0)
        if _max_active(plan[2]) <= cfg.max_exact_bits:
            bc = _exact(Wc, plan)
            method[tr] = JpdaMethod.EXACT
        else:
            bc, bound, nev = _kbest(Wc, cfg.k_best)
            method[tr] = JpdaMethod.KBEST
            err[tr] = bound
            n_events[tr] = nev
        beta[tr, 0] = bc[:, 0]
        beta[np.ix_(tr, cols + 1)] = bc[:, 1:]
    return JpdaMarginals(beta, lab, method, err, n_events)


def _one_shared(
    W: FloatArray, gated: BoolArray, lab: IntArray, size: IntArray, beta: FloatArray
) -> BoolArray:
    """Exact marginals, all at once, of the clusters that share a single measurement.

    In such a cluster every track gates the shared measurement ``s`` and maybe private ones.
    With ``w0_t`` the weight of track ``t``'s options that leave ``s`` free (missed and its
    private measurements) and ``r_t = W[t, s] / w0_t``, the joint events are "nobody takes
    ``s``" (weight ``prod w0``) and "``t`` takes ``s``" (``r_t prod w0``), so
    ``beta[t, s] = r_t / (1 + sum r)``, and the rest of track ``t``'s probability is split over
    its other options in proportion to their weights (no other track competes for them).
    Harbour scans are mostly such clusters: one report inside the gates of several moored ships.
    Clusters with a ``w0_t = 0`` (``P_D P_G = 1`` and nothing private) are left to the general
    method. Writes ``beta``'s rows of the solved tracks; returns them as a (T,) mask.
    """
    shared = gated.sum(axis=0) >= 2
    n_cl = size.size
    col_cluster = lab[np.argmax(gated[:, shared], axis=0)]
    one = (size > 1) & (np.bincount(col_cluster, minlength=n_cl) == 1)
    done = one[lab]
    if not done.any():
        return done
    t = np.flatnonzero(done)
    other = np.where(shared, 0.0, W[t, 1:])  # private measurements (0 outside the gate)
    w0 = W[t, 0] + other.sum(axis=1)
    bad = np.bincount(lab[t], w0 <= 0, minlength=n_cl) > 0
    if bad.any():
        keep = ~bad[lab[t]]
        done[t[~keep]] = False
        t, other, w0 = t[keep], other[keep], w0[keep]
    s = np.argmax(gated[t] & shared, axis=1)
    r = W[t, 1 + s] / w0
    b = r / (1.0 + np.bincount(lab[t], r, minlength=n_cl))[lab[t]]
    scale = (1.0 - b) / w0
    beta[t, 0] = W[t, 0] * scale
    beta[t, 1:] = other * scale[:, None]
    beta[t, 1 + s] = b
    return done


# ------------------------------------------------------------------ exact: tensor elimination

DENSE_EVENTS = 2500  # joint events up to which a cluster is enumerated (faster than elimination)
SMALL_ACTIVE = 6  # shared measurements of a cluster up to which its tracks are not reordered


def _order_and_sets(G: BoolArray) -> tuple[IntArray, IntArray, list[list[int]]]:
    """Track order, shared-measurement columns and, per ordered track, its shared columns."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    shared = np.flatnonzero(G.sum(axis=0) >= 2)
    Gs = G[:, shared]
    if G.shape[0] <= 4 or shared.size <= SMALL_ACTIVE:
        # any order is as good for so few tracks, and with so few shared measurements no order
        # makes the messages larger than 2**SMALL_ACTIVE entries
        order = np.arange(G.shape[0])
    else:
        conflict = (Gs.astype(np.int64) @ Gs.T.astype(np.int64)) > 0
        order = np.asarray(reverse_cuthill_mckee(csr_matrix(conflict), symmetric_mode=True))
    per = [[int(j) for j in Gs[t].nonzero()[0]] for t in order]
    return order.astype(np.int64), shared.astype(np.int64), per


def _max_active(per: list[list[int]]) -> int:
    last: dict[int, int] = {}
    for i, js in enumerate(per):
        for j in js:
            last[j] = i
    active: set[int] = set()
    best = 0
    for i, js in enumerate(per):
        active.update(js)
        best = max(best, len(active))
        active = {j for j in active if last[j] > i}
    return best


def _exact(W: FloatArray, plan: tuple[IntArray, IntArray, list[list[int]]]) -> FloatArray:
    """Exact marginals of one cluster (see module notes); ``plan`` from ``_order_and_sets``."""
    T = W.shape[0]
    G = W[:, 1:] > 0
    order, shared, per = plan
    is_shared = np.zeros(G.shape[1], dtype=bool)
    is_shared[shared] = True
    # weight of the options that do not touch shared measurements (miss + private measurements)
    Wo = W[order]
    w0 = Wo[:, 0] + np.where(is_shared, 0.0, Wo[:, 1:]).sum(axis=1)
    last: dict[int, int] = {}
    for i, js in enumerate(per):
        for j in js:
            last[j] = i

    # forward pass; F_exp[i] is the message before track i, over axes U_i
    axes: list[int] = []
    F: FloatArray = np.ones(())
    F_exp: list[FloatArray] = []
    U: list[list[int]] = []
    n_new: list[int] = []
    for i in range(T):
        new = [j for j in per[i] if j not in axes]
        if new:
            Fe = np.zeros(F.shape + (2,) * len(new))
            Fe[(...,) + (0,) * len(new)] = F
            F = Fe
            axes = axes + new
        F_exp.append(F)
        U.append(axes)
        n_new.append(len(new))
        Gn = w0[i] * F
        for j in per[i]:
            a = axes.index(j)
            w = Wo[i, 1 + shared[j]]
            _h(Gn, a, 1)[...] += w * _h(F, a, 0)
        dead = [a for a, j in enumerate(axes) if last[j] == i]
        if dead:
            Gn = Gn.sum(axis=tuple(dead))
            axes = [j for j in axes if last[j] != i]
        F = Gn
    Z = float(F)
    if not Z > 0:
        raise ValueError("JPDA cluster has zero total weight (every joint event impossible)")

    # backward pass with marginals
    out = np.zeros((T, W.shape[1]))
    B: FloatArray = np.ones(())
    for i in range(T - 1, -1, -1):
        Ui = U[i]
        dead = [a for a, j in enumerate(Ui) if last[j] == i]
        Bb = np.expand_dims(B, tuple(dead)) if dead else B
        Bb = np.ascontiguousarray(np.broadcast_to(Bb, (2,) * len(Ui)))
        Fi = F_exp[i]
        m0 = w0[i] * _dot(Fi, Bb)
        row = out[order[i]]
        for j in per[i]:
            a = Ui.index(j)
            w = Wo[i, 1 + shared[j]]
            row[1 + shared[j]] = w * _dot(_h(Fi, a, 0), _h(Bb, a, 1))
        # split the no-shared option into miss and private measurements
        if w0[i] > 0:
            scale = m0 / w0[i]
            row[0] = Wo[i, 0] * scale
            priv = ~is_shared & G[order[i]]
            row[1:][priv] = Wo[i, 1:][priv] * scale
        # message for the earlier tracks, then drop this track's new axes (bit 0)
        Bn = w0[i] * np.array(Bb)
        for j in per[i]:
            a = Ui.index(j)
            w = Wo[i, 1 + shared[j]]
            _h(Bn, a, 0)[...] += w * _h(Bb, a, 1)
        k = n_new[i]
        B = Bn[(...,) + (0,) * k] if k else Bn
    return out / Z


def _dot(a: FloatArray, b: FloatArray) -> float:
    """Sum of the elementwise product of two equal-shape tensors.

    ``np.einsum`` rather than ``np.vdot``: BLAS ``ddot`` goes multithreaded on these long
    vectors, and on a busy machine OpenBLAS's spinning threads slow it down many times over;
    einsum's own loop is single-threaded and as fast here.
    """
    a2 = a.reshape(-1, a.shape[-1]) if a.ndim else a.reshape(1, 1)
    b2 = b.reshape(-1, b.shape[-1]) if b.ndim else b.reshape(1, 1)
    return float(np.einsum("ij,ij->", a2, b2))


def _h(A: FloatArray, axis: int, v: int) -> FloatArray:
    """View of the C-contiguous ``(2, 2, ...)`` tensor ``A`` at index ``v`` of ``axis``, as a
    3-D ``(2**axis, 2, rest)`` reshape (numpy iterates that far faster than a 20-D view)."""
    return A.reshape(1 << axis, 2, -1)[:, v]


# ------------------------------------------------------------------------------- k-best


def _kbest(W: FloatArray, k: int) -> tuple[FloatArray, float, int]:
    with np.errstate(divide="ignore"):
        L = -np.log(W)
    T = W.shape[0]
    miss = L[:, 0]
    if not np.all(np.isfinite(miss)):
        # pd*Pg == 1: "missed" is impossible; forbid it with a huge finite cost
        miss = np.where(np.isfinite(miss), miss, 1e300)
    kb = murty(L[:, 1:], miss, k)
    w = np.exp(-kb.cost)
    w = np.where(kb.cost >= 1e299, 0.0, w)
    found = float(w.sum())
    beta = np.zeros_like(W)
    rows = np.arange(T)
    for a, we in zip(kb.track_to_meas, w, strict=True):
        beta[rows, a + 1] += we
    n_total = float(np.prod((W > 0).sum(axis=1).astype(float)))
    n_rest = max(n_total - len(w), 0.0)
    ub_total = float(np.prod(W.sum(axis=1)))
    rest = min(max(ub_total - found, 0.0), n_rest * float(w[-1])) if len(w) >= k else 0.0
    return beta / found, rest / (found + rest), len(w)


# ------------------------------------------------------------------------------- PDA update


def pda_update(
    x: ArrayLike,
    P: ArrayLike,
    innovation: ArrayLike,
    S: ArrayLike,
    K: ArrayLike,
    beta: ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """PDA state update from marginal association probabilities (Bar-Shalom & Fortmann 6.4).

    ``x⁺ = x + K ν̄`` with ``ν̄ = Σ_j β_j ν_j``;
    ``P⁺ = β_0 P + (1 - β_0)(P - K S Kᵀ) + K (Σ_j β_j ν_j ν_jᵀ - ν̄ ν̄ᵀ) Kᵀ``; the Kalman terms
    ``x + K ν̄`` and ``P - K S Kᵀ`` come from :func:`navtrack.estimation.kalman.gain_update`.
    Equals the moment-matched mixture of the per-hypothesis Kalman posteriors (all sharing one
    gain).

    Parameters
    ----------
    x : (..., T, n), P : (..., T, n, n)
    innovation : (..., T, M, m) ``z_j - ẑ_t`` (angles wrapped)
    S : (..., T, m, m), K : (..., T, n, m)
    beta : (..., T, M+1) marginals, column 0 = missed

    Returns
    -------
    x : (..., T, n), P : (..., T, n, n)
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    y = np.asarray(innovation, dtype=float)
    S = np.asarray(S, dtype=float)
    K = np.asarray(K, dtype=float)
    b = np.asarray(beta, dtype=float)
    bj = b[..., 1:]
    nu = np.einsum("...j,...ji->...i", bj, y)
    spread = np.einsum("...j,...ji,...jk->...ik", bj, y, y) - nu[..., :, None] * nu[..., None, :]
    xn, Pc = gain_update(x, P, nu, K, S, symmetrize=False)
    Kt = np.swapaxes(K, -1, -2)
    b0 = b[..., 0, None, None]
    Pn = b0 * P + (1 - b0) * Pc + K @ spread @ Kt
    return xn, 0.5 * (Pn + np.swapaxes(Pn, -1, -2))


@dataclass(frozen=True, slots=True, eq=False)
class JpdaStep:
    """One JPDA filter step for a fixed set of tracks (arrays read-only).

    Attributes
    ----------
    x : (T, n) posterior states; P : (T, n, n) posterior covariances
    x_pred : (T, n), P_pred : (T, n, n) predictions
    marginals : JpdaMarginals of the scan
    """

    x: FloatArray
    P: FloatArray
    x_pred: FloatArray
    P_pred: FloatArray
    marginals: JpdaMarginals

    def __post_init__(self) -> None:
        freeze_arrays(self)


def jpda_step(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    F: ArrayLike,
    Q: ArrayLike,
    model: MeasurementModel,
    config: JpdaConfig,
) -> JpdaStep:
    """Predict, gate, associate (JPDA) and update ``T`` tracks with one scan.

    Linear prediction ``(F, Q)``; the measurement model may be nonlinear (EKF linearisation at
    the prediction, angle innovations wrapped). This is the JPDAF of Bar-Shalom & Fortmann
    (1988, ch. 9) with the weights of :func:`association_weights`; the same pipeline as
    :func:`jpda_step_batch`, with the marginals of :func:`jpda_marginals`.

    Parameters
    ----------
    x : (T, n), P : (T, n, n), z : (M, m) measurements of the scan
    F, Q : (n, n) motion model over the step
    model : measurement model (``h``, ``jacobian``, ``R``, ``angle_mask``, ``dim_z``)
    config : JpdaConfig
    """

    def marginals(W: FloatArray) -> tuple[FloatArray, JpdaMarginals]:
        jm = jpda_marginals(W, config)
        return jm.beta, jm

    return _jpda_pipeline(x, P, z, None, F, Q, model, config, marginals)


def _jpda_pipeline(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    valid: BoolArray | None,
    F: ArrayLike,
    Q: ArrayLike,
    model: MeasurementModel,
    config: JpdaConfig,
    marginals: Callable[[FloatArray], tuple[FloatArray, JpdaMarginals]],
) -> JpdaStep:
    """The JPDA filter step over any leading batch axes of ``x (..., T, n)``, ``z (..., M, m)``.

    Kalman prediction, EKF innovation covariance and gain (:mod:`navtrack.estimation.kalman`),
    chi-square gate, :func:`association_weights` (pairs with ``valid`` False get weight 0),
    ``marginals(W) -> (beta, JpdaMarginals)``, :func:`pda_update`.
    """
    xp, Pp = kf_predict(x, P, F, Q)
    S, K = innovation_gain(Pp, model.jacobian(xp), model.R)
    gamma = chi2_threshold(config.gate_probability, model.dim_z)
    g = gate(model.h(xp), S, z, gamma, angle_mask=model.angle_mask)
    ok = g.valid if valid is None else g.valid & valid[..., None, :]
    W = association_weights(
        g.log_likelihood(), ok, config.pd, config.gate_probability, config.clutter_density
    )
    beta, jm = marginals(W)
    xn, Pn = pda_update(xp, Pp, g.innovation, S, K, beta)
    return JpdaStep(xn, Pn, xp, Pp, jm)


def n_joint_events(n_tracks: int, n_meas: int) -> int:
    """Number of joint events of ``n_tracks`` tracks and ``n_meas`` measurements,
    ``sum_k C(T, k) · M! / (M - k)!`` (the rows of :func:`joint_events`)."""
    return sum(comb(n_tracks, k) * perm(n_meas, k) for k in range(min(n_tracks, n_meas) + 1))


@lru_cache(maxsize=256)
def joint_events(n_tracks: int, n_meas: int) -> IntArray:
    """Every joint event of ``n_tracks`` tracks and ``n_meas`` measurements.

    Returns ``E (n_events, n_tracks)`` with ``E[e, t]`` in ``0..n_meas`` (0 = no measurement,
    ``j`` = measurement ``j - 1``), no measurement used twice. The count is
    ``sum_k C(T, k) · M! / (M - k)!``.
    """
    events = np.zeros((1, 0), dtype=np.int64)
    for _ in range(n_tracks):
        parts = [np.column_stack([events, np.zeros(len(events), dtype=np.int64)])]
        for j in range(1, n_meas + 1):
            free = ~(events == j).any(axis=1)
            e = events[free]
            parts.append(np.column_stack([e, np.full(len(e), j, dtype=np.int64)]))
        events = np.concatenate(parts)
    events.setflags(write=False)
    return events


def jpda_marginals_batch(W: ArrayLike, events: IntArray | None = None) -> FloatArray:
    """Exact marginals for a batch of small problems by dense enumeration.

    For many small, equally shaped problems (particles of a joint multitarget particle filter,
    Monte Carlo runs with few targets) one vectorised pass over the joint events beats a call
    per problem. Pairs outside the gate simply have weight 0.

    Parameters
    ----------
    W : (..., T, M+1) weights, column 0 = missed (see :func:`association_weights`)
    events : joint events ``(n_events, T)``; None = all of them, :func:`joint_events`
        (with its event-to-pair indicator, both computed once per ``(T, M)``)

    Returns
    -------
    beta : (..., T, M+1)
    """
    W = np.asarray(W, dtype=float)
    if W.ndim < 2 or not np.isfinite(W).all() or (W < 0).any():
        raise ValueError("W must be a finite, non-negative (..., T, M+1) array")
    T, M1 = W.shape[-2:]
    if events is None:
        E, onehot = joint_events(T, M1 - 1), _event_indicator(T, M1 - 1)
    else:
        E = np.asarray(events)
        onehot = _indicator(E, M1)
    p = np.prod(W[..., np.arange(T), E], axis=-1)  # (..., n_events)
    Z = p.sum(axis=-1, keepdims=True)
    if (Z <= 0).any():
        raise ValueError("a problem of the batch has zero total weight")
    return np.asarray((p / Z) @ onehot.reshape(len(E), T * M1)).reshape(*W.shape[:-2], T, M1)


def _indicator(E: IntArray, n_cols: int) -> FloatArray:
    """``I[e, t, j] = 1`` where event ``e`` gives track ``t`` column ``j`` (``(n_events, T,
    n_cols)``)."""
    n, T = E.shape
    onehot = np.zeros((n, T, n_cols))
    onehot[np.arange(n)[:, None], np.arange(T), E] = 1.0
    return onehot


@lru_cache(maxsize=256)
def _event_indicator(n_tracks: int, n_meas: int) -> FloatArray:
    """:func:`_indicator` of :func:`joint_events` ``(n_tracks, n_meas)`` (read-only)."""
    onehot = _indicator(joint_events(n_tracks, n_meas), n_meas + 1)
    onehot.setflags(write=False)
    return onehot


def jpda_step_batch(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    valid: ArrayLike,
    F: ArrayLike,
    Q: ArrayLike,
    model: MeasurementModel,
    config: JpdaConfig,
    max_events: int = 20_000,
) -> JpdaStep:
    """:func:`jpda_step` for ``R`` independent problems at once (Monte Carlo runs, particles).

    Prediction, gating and the PDA update are vectorised over the batch; the marginals come from
    one dense enumeration (:func:`jpda_marginals_batch`) when the number of joint events is at
    most ``max_events``, else from :func:`jpda_marginals` per problem.

    Parameters
    ----------
    x : (R, T, n), P : (R, T, n, n)
    z : (R, M, m) measurements padded to a common ``M``; ``valid`` (R, M) marks the real ones
    F, Q : (n, n); model : measurement model; config : JpdaConfig

    Returns
    -------
    JpdaStep with batched arrays; ``marginals.beta`` is (R, T, M+1) and the other marginal
    fields describe the flattened ``R·T`` tracks.
    """
    Z = np.asarray(z, dtype=float)
    ok = np.asarray(valid, dtype=bool)
    R_, T = np.shape(x)[:2]
    M = Z.shape[1]
    Zf = np.where(ok[..., None], Z, 0.0)
    if not np.all(np.isfinite(Zf)):
        raise ValueError("z: valid measurements must be finite")
    n_ev = n_joint_events(T, M)

    def marginals(W: FloatArray) -> tuple[FloatArray, JpdaMarginals]:
        if n_ev <= max_events:
            beta = jpda_marginals_batch(W)
            return beta, JpdaMarginals(
                beta.reshape(R_ * T, M + 1),
                np.repeat(np.arange(R_), T).astype(np.int64),
                np.full(R_ * T, JpdaMethod.EXACT, dtype=np.int8),
                np.zeros(R_ * T),
                np.full(R_ * T, n_ev),
            )
        parts = [jpda_marginals(W[r], config) for r in range(R_)]
        beta = np.stack([p.beta for p in parts])
        return beta, JpdaMarginals(
            beta.reshape(R_ * T, M + 1),
            np.concatenate([p.cluster + r * T for r, p in enumerate(parts)]),
            np.concatenate([p.method for p in parts]),
            np.concatenate([p.error_bound for p in parts]),
            np.concatenate([p.n_events for p in parts]),
        )

    return _jpda_pipeline(x, P, Zf, ok, F, Q, model, config, marginals)
