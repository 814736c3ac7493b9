"""Tracking performance metrics: RMSE, OSPA, GOSPA (with switching), CLEAR-MOT, purity.

References
----------
.. [1] D. Schuhmacher, B.-T. Vo, B.-N. Vo, "A consistent metric for performance evaluation of
   multi-object filters", IEEE T-SP 56(8), 2008 (OSPA).
.. [2] A. S. Rahmathullah, Á. F. García-Fernández, L. Svensson, "Generalized optimal sub-pattern
   assignment metric", FUSION 2017 (GOSPA, alpha = 2 decomposition).
.. [3] Á. F. García-Fernández, A. S. Rahmathullah, L. Svensson, "A metric on the space of finite
   sets of trajectories for evaluation of multi-target tracking algorithms", IEEE T-SP 68, 2020
   (switching cost).
.. [4] K. Bernardin, R. Stiefelhagen, "Evaluating multiple object tracking performance: the
   CLEAR MOT metrics", EURASIP J. Image and Video Processing, 2008.
.. [5] J. Luiten, A. Ošep, P. Dendorfer, P. Torr, A. Geiger, L. Leal-Taixé, B. Leibe, "HOTA: a
   higher order metric for evaluating multi-object tracking", IJCV 129, 2021.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import ConvexHull, Delaunay, QhullError

from navtrack._typing import ArrayLike, FloatArray, IntArray

__all__ = [
    "ClearMot",
    "GospaResult",
    "Hota",
    "IdScores",
    "clear_mot",
    "gospa",
    "gospa_sequence",
    "hota",
    "id_scores",
    "ignored_hypotheses",
    "interpolate_truth",
    "ospa",
    "outside_coverage",
    "rmse",
    "truth_gaps",
]


def rmse(estimate: ArrayLike, truth: ArrayLike, axis: int = 0) -> FloatArray:
    """Root mean square error over ``axis`` (default: runs) of the Euclidean error norm.

    ``estimate, truth : (R, K, d)`` -> ``(K,)`` for the default axis.
    """
    e = np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float)
    return np.asarray(np.sqrt(np.mean(np.sum(e * e, axis=-1), axis=axis)))


def _points(A: ArrayLike) -> FloatArray:
    a = np.asarray(A, dtype=float)
    return a.reshape(a.shape[0], -1) if a.size else np.zeros((0, 1))


def _dist(X: FloatArray, Y: FloatArray) -> FloatArray:
    """Euclidean distances ``(n, m)`` between the rows of ``X (n, d)`` and ``Y (m, d)``."""
    from scipy.spatial.distance import cdist

    return np.asarray(cdist(X, Y))


def ospa(X: ArrayLike, Y: ArrayLike, c: float, p: float = 2.0) -> float:
    """OSPA distance (order ``p``, cut-off ``c``) between point sets ``X (n, d)``, ``Y (m, d)``."""
    X = _points(X)
    Y = _points(Y)
    n, m = len(X), len(Y)
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return float(c)
    D = np.minimum(_dist(X, Y), c) ** p
    r, col = linear_sum_assignment(D)
    total = D[r, col].sum() + c**p * abs(n - m)
    return float((total / max(n, m)) ** (1.0 / p))


@dataclass(frozen=True, slots=True)
class GospaResult:
    """GOSPA (alpha = 2) and its parts; ``distance = (loc + missed + false + switch)^(1/p)``.

    ``localisation``, ``missed``, ``false`` and ``switching`` are the p-th-power terms.
    """

    distance: float
    localisation: float
    missed: float
    false: float
    switching: float
    n_missed: int
    n_false: int
    n_switches: float


def _frame_rows(
    tf: np.ndarray, hf: np.ndarray, frames: np.ndarray
) -> list[tuple[IntArray, IntArray]]:
    """Rows of the truth and of the hypotheses in each of ``frames``, in increasing order."""
    t_order = np.argsort(tf, kind="stable")
    h_order = np.argsort(hf, kind="stable")
    t_lo = np.searchsorted(tf[t_order], frames, side="left")
    t_hi = np.searchsorted(tf[t_order], frames, side="right")
    h_lo = np.searchsorted(hf[h_order], frames, side="left")
    h_hi = np.searchsorted(hf[h_order], frames, side="right")
    return [(t_order[a:b], h_order[c:d]) for a, b, c, d in zip(t_lo, t_hi, h_lo, h_hi, strict=True)]


def _gospa_assign(X: FloatArray, Y: FloatArray, c: float, p: float) -> tuple[IntArray, float]:
    """Truth-to-estimate assignment (``-1`` = missed) and its localisation term."""
    n = len(X)
    a = np.full(n, -1, dtype=np.int64)
    if n == 0 or len(Y) == 0:
        return a, 0.0
    D = _dist(X, Y) ** p
    # assigning costs d^p, leaving both unassigned costs c^p/2 + c^p/2 = c^p
    cost = np.where(c**p > D, D, c**p)
    r, col = linear_sum_assignment(cost)
    ok = D[r, col] < c**p
    a[r[ok]] = col[ok]
    return a, float(D[r[ok], col[ok]].sum())


def gospa(X: ArrayLike, Y: ArrayLike, c: float, p: float = 2.0) -> GospaResult:
    """GOSPA with ``alpha = 2`` between truth ``X (n, d)`` and estimates ``Y (m, d)``."""
    X = _points(X)
    Y = _points(Y)
    a, loc = _gospa_assign(X, Y, c, p)
    n_ass = int((a >= 0).sum())
    nm, nf = len(X) - n_ass, len(Y) - n_ass
    miss, false = c**p / 2 * nm, c**p / 2 * nf
    return GospaResult((loc + miss + false) ** (1 / p), loc, miss, false, 0.0, nm, nf, 0.0)


def gospa_sequence(
    truth: list[ArrayLike],
    truth_ids: list[ArrayLike],
    estimates: list[ArrayLike],
    estimate_ids: list[ArrayLike],
    c: float,
    p: float = 2.0,
    switching_cost: float = 0.0,
) -> GospaResult:
    """GOSPA summed over a sequence of steps, plus a switching term.

    Per step the GOSPA assignment is solved; a truth whose assigned estimate id changes between
    consecutive steps where it exists costs ``switching_cost^p`` (half of it when it changes
    from or to unassigned), the switching term of García-Fernández et al. (2020) evaluated on the
    per-step optimal assignments (an upper bound of their LP metric).

    Parameters
    ----------
    truth, estimates : per step, (n_k, d) and (m_k, d)
    truth_ids, estimate_ids : per step, (n_k,) and (m_k,) identities
    """
    loc = miss = false = 0.0
    nm = nf = 0
    sw = 0.0
    prev: dict[object, object] = {}
    for X, tid, Y, yid in zip(truth, truth_ids, estimates, estimate_ids, strict=True):
        X = _points(X)
        Y = _points(Y)
        a, lk = _gospa_assign(X, Y, c, p)
        loc += lk
        n_ass = int((a >= 0).sum())
        nm += len(X) - n_ass
        nf += len(Y) - n_ass
        yid_arr = np.asarray(yid)
        cur: dict[object, object] = {}
        for i, t in enumerate(np.asarray(tid).tolist()):
            cur[t] = None if a[i] < 0 else yid_arr[a[i]].item()
            if t in prev and prev[t] != cur[t]:
                sw += 0.5 if (prev[t] is None or cur[t] is None) else 1.0
        prev = cur
    miss, false = c**p / 2 * nm, c**p / 2 * nf
    swt = switching_cost**p * sw
    total = (loc + miss + false + swt) ** (1 / p)
    return GospaResult(total, loc, miss, false, swt, nm, nf, sw)


@dataclass(frozen=True, slots=True)
class ClearMot:
    """CLEAR-MOT scores (Bernardin & Stiefelhagen 2008) and track purity.

    Attributes
    ----------
    mota : 1 - (misses + false positives + id switches) / ground-truth objects
    motp : mean distance of matched pairs, m
    n_truth, n_matches, n_misses, n_false, id_switches, fragmentations : counts over frames
    purity : matched frames of each track with its dominant truth id / matched frames
    n_tracks : distinct hypothesis ids ever matched or reported
    """

    mota: float
    motp: float
    n_truth: int
    n_matches: int
    n_misses: int
    n_false: int
    id_switches: int
    fragmentations: int
    purity: float
    n_tracks: int


def clear_mot(
    truth_frame: ArrayLike,
    truth_id: ArrayLike,
    truth_pos: ArrayLike,
    hyp_frame: ArrayLike,
    hyp_id: ArrayLike,
    hyp_pos: ArrayLike,
    threshold: float,
) -> ClearMot:
    """CLEAR-MOT over frames given as flat arrays.

    Per frame: each object's last correspondence (made in the latest frame where the object
    was matched, so also across frames where it was missed) is kept while its hypothesis is
    present within ``threshold``; the remaining objects and hypotheses are matched by a
    minimum-distance assignment with the same threshold. This is the reading of py-motmetrics
    (``MOTAccumulator.update``), which the tests check equal counts against. A truth object
    matched to a hypothesis different from its last one counts an id switch; a truth
    trajectory going from matched to unmatched and back counts a fragmentation.

    Parameters
    ----------
    truth_frame (N,), truth_id (N,), truth_pos (N, d)
    hyp_frame (H,), hyp_id (H,), hyp_pos (H, d)
    threshold : float, m
    """
    tf = np.asarray(truth_frame)
    tid = np.asarray(truth_id)
    tp = _points(truth_pos)  # (N, d); (0, 1) when empty: distances need both sides non-empty
    hf = np.asarray(hyp_frame)
    hid = np.asarray(hyp_id)
    hp = _points(hyp_pos)
    last_match: dict[object, object] = {}
    was_tracked: dict[object, bool] = {}
    pair_counts: dict[tuple[object, object], int] = {}
    n_truth = n_match = n_miss = n_false = n_sw = n_frag = 0
    dist_sum = 0.0
    for ti, hi in _frame_rows(tf, hf, np.union1d(tf, hf)):
        T_ids = tid[ti].tolist()
        H_ids = hid[hi].tolist()
        D = _dist(tp[ti], hp[hi]) if len(ti) and len(hi) else np.zeros((len(ti), len(hi)))
        match = _match_frame(T_ids, H_ids, D, last_match, threshold)
        for a, t in enumerate(T_ids):
            if a in match:
                h = H_ids[match[a]]
                if t in last_match and last_match[t] != h:
                    n_sw += 1
                if was_tracked.get(t) is False and t in last_match:
                    n_frag += 1
                last_match[t] = h
                was_tracked[t] = True
                dist_sum += float(D[a, match[a]])
                pair_counts[(t, h)] = pair_counts.get((t, h), 0) + 1
            elif t in was_tracked:
                was_tracked[t] = False
        n_truth += len(T_ids)
        n_match += len(match)
        n_miss += len(T_ids) - len(match)
        n_false += len(H_ids) - len(match)
    return ClearMot(
        1.0 - (n_miss + n_false + n_sw) / n_truth if n_truth else float("nan"),
        dist_sum / n_match if n_match else float("nan"),
        n_truth,
        n_match,
        n_miss,
        n_false,
        n_sw,
        n_frag,
        _purity(pair_counts),
        len(np.unique(hid)) if len(hid) else 0,
    )


def _match_frame(
    T_ids: list, H_ids: list, D: FloatArray, last_match: dict[object, object], threshold: float
) -> dict[int, int]:
    """CLEAR-MOT matching of one frame: truth row -> hypothesis row. Each object's last
    correspondence is kept while its hypothesis is present within ``threshold``; the rest are
    matched by a minimum-distance assignment with the same threshold."""
    match: dict[int, int] = {}
    h_pos = {h: k for k, h in enumerate(H_ids)}
    used_h: set[int] = set()
    for a, t in enumerate(T_ids):  # keep each object's last correspondence
        h = last_match.get(t)
        if h is not None and h in h_pos and h_pos[h] not in used_h:
            b = h_pos[h]
            if D[a, b] <= threshold:
                match[a] = b
                used_h.add(b)
    free_t = [a for a in range(len(T_ids)) if a not in match]
    free_h = [b for b in range(len(H_ids)) if b not in used_h]
    if free_t and free_h:
        sub = D[np.ix_(free_t, free_h)]
        cost = np.where(sub <= threshold, sub, 1e12)
        r, c = linear_sum_assignment(cost)
        for i, j in zip(r, c, strict=True):
            if sub[i, j] <= threshold:
                match[free_t[i]] = free_h[j]
    return match


def _purity(pair_counts: dict[tuple[object, object], int]) -> float:
    """Share of the matches of each track that went to its most frequent truth id, pooled."""
    per_track: dict[object, list[int]] = {}
    for (_, h), cnt in pair_counts.items():
        per_track.setdefault(h, []).append(cnt)
    matched = sum(sum(v) for v in per_track.values())
    return sum(max(v) for v in per_track.values()) / matched if matched else float("nan")


@dataclass(frozen=True, slots=True)
class Hota:
    """HOTA and its parts (Luiten et al. 2021), averaged over the localisation thresholds.

    Attributes
    ----------
    hota : mean over ``alpha`` of ``sqrt(DetA_alpha · AssA_alpha)``
    det_a, ass_a, loc_a : detection accuracy ``TP / (TP + FN + FP)``, association accuracy
        (mean over true positives of ``TPA / (TPA + FNA + FPA)`` of their pair of ids),
        localisation accuracy (mean similarity of the true positives), each averaged over
        ``alpha``
    alphas : (A,) thresholds; hota_alpha, det_a_alpha, ass_a_alpha : (A,) per threshold
    """

    hota: float
    det_a: float
    ass_a: float
    loc_a: float
    alphas: tuple[float, ...]
    hota_alpha: tuple[float, ...]
    det_a_alpha: tuple[float, ...]
    ass_a_alpha: tuple[float, ...]


def hota(
    truth_frame: ArrayLike,
    truth_id: ArrayLike,
    truth_pos: ArrayLike,
    hyp_frame: ArrayLike,
    hyp_id: ArrayLike,
    hyp_pos: ArrayLike,
    threshold: float,
) -> Hota:
    """HOTA over frames given as flat arrays (as :func:`clear_mot`), for point objects.

    The similarity of a truth and a hypothesis at distance ``d`` is ``max(0, 1 - d /
    threshold)`` (1 at the same point, 0 from ``threshold`` on), the point analogue of the
    paper's IoU. For each ``alpha`` in 0.05, 0.10, ..., 0.95 a pair is a true positive when it
    is matched in its frame with similarity ``>= alpha``. The matching in a frame maximises
    the similarity weighted by the ids' global alignment (the paper's section 6: pairs whose
    ids are often together are preferred), where the global alignment of a truth id ``g`` and
    a hypothesis id ``k`` is ``P / (n_g + n_k - P)``, ``n`` the frames each is present in and
    ``P`` their summed frame-wise soft overlap ``S_gk / (Σ_k' S_gk' + Σ_g' S_g'k - S_gk)``.
    The association accuracy of a true positive of ``(g, k)`` is ``TPA / (TPA + FNA + FPA)``
    with ``TPA`` the true positives of that pair over the sequence and ``FNA``, ``FPA`` the
    other frames of ``g`` and of ``k`` (eq. 9-10 of the paper).

    Parameters
    ----------
    truth_frame (N,), truth_id (N,), truth_pos (N, d)
    hyp_frame (H,), hyp_id (H,), hyp_pos (H, d)
    threshold : float, m
    """
    if not threshold > 0:
        raise ValueError(f"threshold must be > 0, got {threshold}")
    tf = np.asarray(truth_frame)
    hf = np.asarray(hyp_frame)
    tp = _points(truth_pos)
    hp = _points(hyp_pos)
    g_names, g = np.unique(np.asarray(truth_id), return_inverse=True)
    k_names, k = np.unique(np.asarray(hyp_id), return_inverse=True)
    G, K = g_names.size, k_names.size
    alphas = np.arange(1, 20) / 20.0
    per_frame = []
    for ti, hi in _frame_rows(tf, hf, np.union1d(tf, hf)):
        S = (
            np.maximum(0.0, 1.0 - _dist(tp[ti], hp[hi]) / threshold)
            if ti.size and hi.size
            else np.zeros((ti.size, hi.size))
        )
        per_frame.append((g[ti], k[hi], S))
    n_g = np.bincount(g, minlength=G).astype(float)
    n_k = np.bincount(k, minlength=K).astype(float)
    align = _hota_alignment(per_frame, n_g, n_k)
    TP, loc, pair_tp = _hota_true_positives(per_frame, align, alphas)
    n_truth, n_hyp = float(tf.size), float(hf.size)
    FN, FP = n_truth - TP, n_hyp - TP
    det_a = TP / np.maximum(TP + FN + FP, 1.0)
    ass = pair_tp / np.maximum(n_g[None, :, None] + n_k[None, None, :] - pair_tp, 1.0)
    ass_a = (pair_tp * ass).sum(axis=(1, 2)) / np.maximum(TP, 1.0)
    loc_a = np.where(TP > 0, loc / np.maximum(TP, 1.0), 1.0)
    h = np.sqrt(det_a * ass_a)
    return Hota(
        float(h.mean()),
        float(det_a.mean()),
        float(ass_a.mean()),
        float(loc_a.mean()),
        tuple(float(a) for a in alphas),
        tuple(float(v) for v in h),
        tuple(float(v) for v in det_a),
        tuple(float(v) for v in ass_a),
    )


def _hota_alignment(per_frame: list, n_g: FloatArray, n_k: FloatArray) -> FloatArray:
    """Global alignment ``P / (n_g + n_k - P)`` of every truth id and hypothesis id, ``P``
    their summed frame-wise soft overlap (:func:`hota`)."""
    P = np.zeros((n_g.size, n_k.size))
    for gi, ki, S in per_frame:
        if S.size:
            denom = S.sum(axis=1, keepdims=True) + S.sum(axis=0, keepdims=True) - S
            soft = np.divide(S, denom, out=np.zeros_like(S), where=denom > np.finfo(float).eps)
            np.add.at(P, (gi[:, None], ki[None, :]), soft)
    return P / np.maximum(n_g[:, None] + n_k[None, :] - P, np.finfo(float).eps)


def _hota_true_positives(
    per_frame: list, align: FloatArray, alphas: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per ``alpha``: true positives, their summed similarity, and the true positives of each
    (truth id, hypothesis id) pair, the matching of a frame maximising the aligned similarity."""
    A = alphas.size
    TP = np.zeros(A)
    loc = np.zeros(A)
    pair_tp = np.zeros((A, *align.shape))
    for gi, ki, S in per_frame:
        if not S.size:
            continue
        r, c = linear_sum_assignment(-(align[np.ix_(gi, ki)] * S))
        s_rc = S[r, c]
        for a, alpha in enumerate(alphas):
            ok = s_rc >= alpha - np.finfo(float).eps
            TP[a] += ok.sum()
            loc[a] += s_rc[ok].sum()
            np.add.at(pair_tp[a], (gi[r[ok]], ki[c[ok]]), 1.0)
    return TP, loc, pair_tp


@dataclass(frozen=True, slots=True)
class IdScores:
    """Identity scores of Ristani et al. (2016): the truth ids and hypothesis ids matched
    one to one over the whole sequence so as to agree on the most frames.

    Attributes
    ----------
    idf1, idp, idr : ``2 IDTP / (truth + hypothesis points)``, ``IDTP / hypothesis points``,
        ``IDTP / truth points``
    idtp : frames where a truth id and its matched hypothesis id lie within the threshold
    n_truth, n_hyp : truth and hypothesis points (id, frame)
    """

    idf1: float
    idp: float
    idr: float
    idtp: int
    n_truth: int
    n_hyp: int


def id_scores(
    truth_frame: ArrayLike,
    truth_id: ArrayLike,
    truth_pos: ArrayLike,
    hyp_frame: ArrayLike,
    hyp_id: ArrayLike,
    hyp_pos: ArrayLike,
    threshold: float,
) -> IdScores:
    """IDF1, IDP and IDR (Ristani et al. 2016, "Performance measures and a data set for
    multi-target, multi-camera tracking", ECCV workshops).

    For every pair (truth id, hypothesis id) the frames in which both are present within
    ``threshold`` of each other are counted; a one-to-one matching of the ids maximises the
    summed counts (IDTP, :func:`scipy.optimize.linear_sum_assignment`). Arguments as for
    :func:`clear_mot`.
    """
    tf = np.asarray(truth_frame)
    hf = np.asarray(hyp_frame)
    tp = _points(truth_pos)
    hp = _points(hyp_pos)
    g_names, g = np.unique(np.asarray(truth_id), return_inverse=True)
    h_names, h = np.unique(np.asarray(hyp_id), return_inverse=True)
    counts = np.zeros((g_names.size, h_names.size))
    for ti, hi in _frame_rows(tf, hf, np.intersect1d(tf, hf)):
        near = _dist(tp[ti], hp[hi]) <= threshold
        gi, hj = np.nonzero(near)
        np.add.at(counts, (g[ti][gi], h[hi][hj]), 1.0)
    rows, cols = linear_sum_assignment(counts, maximize=True)
    idtp = int(counts[rows, cols].sum())
    n_t, n_h = int(tf.size), int(hf.size)
    return IdScores(
        2 * idtp / (n_t + n_h) if n_t + n_h else float("nan"),
        idtp / n_h if n_h else float("nan"),
        idtp / n_t if n_t else float("nan"),
        idtp,
        n_t,
        n_h,
    )


def _bracket(
    ft: FloatArray, tk: FloatArray, pk: FloatArray
) -> tuple[np.ndarray, np.ndarray, FloatArray, FloatArray]:
    """For frame times ``ft`` and one id's sorted report times ``tk`` / positions ``pk``:
    whether a report falls on the frame time, whether two reports bracket it, the length of
    that bracket (s) and the linear interpolation in it."""
    j = np.searchsorted(tk, ft, side="right")  # tk[j-1] <= ft < tk[j]
    exact = (j >= 1) & (tk[np.clip(j - 1, 0, None)] == ft)
    inside = (j >= 1) & (j < tk.size)
    lo = np.clip(j - 1, 0, tk.size - 1)
    hi = np.clip(j, 0, tk.size - 1)
    gap = tk[hi] - tk[lo]
    w = np.where(gap > 0, (ft - tk[lo]) / np.where(gap > 0, gap, 1.0), 0.0)
    w = np.where(exact, 0.0, w)[:, None]
    return exact, inside, gap, (1 - w) * pk[lo] + w * pk[hi]


def _per_id(
    frame_times: ArrayLike,
    t: ArrayLike,
    ids: ArrayLike,
    pos: ArrayLike,
    present: Callable[[np.ndarray, np.ndarray, FloatArray], np.ndarray],
) -> tuple[IntArray, np.ndarray, FloatArray]:
    """Interpolated positions of each id at the frame times where ``present(exact, inside,
    gap)`` holds (:func:`_bracket`), flat over (frame, id) pairs."""
    ft = np.asarray(frame_times, dtype=float)
    t = np.asarray(t, dtype=float)
    ids = np.asarray(ids)
    pos = np.asarray(pos, dtype=float)
    out_f: list[IntArray] = []
    out_i: list[np.ndarray] = []
    out_p: list[FloatArray] = []
    for u in np.unique(ids):
        k = np.flatnonzero(ids == u)
        k = k[np.argsort(t[k], kind="stable")]
        exact, inside, gap, p = _bracket(ft, t[k], pos[k])
        ok = present(exact, inside, gap)
        if not ok.any():
            continue
        f = np.flatnonzero(ok)
        out_f.append(f)
        out_i.append(np.full(f.size, u, dtype=ids.dtype))
        out_p.append(p[ok])
    if not out_f:
        return np.zeros(0, np.int64), np.zeros(0, ids.dtype), np.zeros((0, pos.shape[-1]))
    return (np.concatenate(out_f).astype(np.int64), np.concatenate(out_i), np.concatenate(out_p))


def interpolate_truth(
    frame_times: ArrayLike, t: ArrayLike, ids: ArrayLike, pos: ArrayLike, max_gap_s: float
) -> tuple[IntArray, np.ndarray, FloatArray]:
    """True positions of each id at frame times, linear between the id's own reports.

    An id is present at a frame time when two consecutive reports of it bracket that time and
    are at most ``max_gap_s`` apart (or a report falls exactly on it).

    Parameters
    ----------
    frame_times : (F,) s; t : (N,) report times, s; ids : (N,); pos : (N, d)

    Returns
    -------
    frame (K,) int, id (K,), position (K, d), flat over (frame, id) pairs present
    """
    return _per_id(
        frame_times,
        t,
        ids,
        pos,
        lambda exact, inside, gap: exact | (inside & (gap <= max_gap_s)),
    )


def truth_gaps(
    frame_times: ArrayLike,
    t: ArrayLike,
    ids: ArrayLike,
    pos: ArrayLike,
    max_gap_s: float,
    longest_gap_s: float,
) -> tuple[IntArray, np.ndarray, FloatArray]:
    """Where each id was between two of its reports more than ``max_gap_s`` and at most
    ``longest_gap_s`` apart (linear between them): the frames :func:`interpolate_truth` leaves
    out inside the id's own reporting gaps. Same arguments and returns."""
    return _per_id(
        frame_times,
        t,
        ids,
        pos,
        lambda exact, inside, gap: ~exact & inside & (gap > max_gap_s) & (gap <= longest_gap_s),
    )


def outside_coverage(points: ArrayLike, reports: ArrayLike) -> np.ndarray:
    """Which of ``points (P, 2)`` lie outside the convex hull of ``reports (N, 2)`` (the area
    a recording covers; all outside when the reports span no area)."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    r = np.unique(np.asarray(reports, dtype=float).reshape(-1, 2), axis=0)
    try:
        hull = Delaunay(r[ConvexHull(r).vertices])
    except (QhullError, ValueError, IndexError):
        return np.ones(p.shape[0], dtype=bool)
    return np.asarray(hull.find_simplex(p) < 0)


def ignored_hypotheses(
    tf: ArrayLike,
    tpos: ArrayLike,
    gf: ArrayLike,
    gpos: ArrayLike,
    hf: ArrayLike,
    hpos: ArrayLike,
    threshold: float,
    outside: ArrayLike | None = None,
) -> np.ndarray:
    """Hypotheses left out of the scores: those that match an ignored true position (a
    don't-care object, as TrackEval removes tracker boxes on MOTChallenge's distractors
    before scoring), and those flagged ``outside`` that match no true position.

    In each frame the hypotheses ``hf, hpos`` are matched one-to-one to the true positions
    ``tf, tpos`` and the ignored ones ``gf, gpos`` together (fewest total distance among the
    assignments with the most pairs within ``threshold``).

    Returns
    -------
    (H,) bool, True for the hypotheses to leave out of the scores
    """
    tf, gf, hf = (np.asarray(a, dtype=np.int64) for a in (tf, gf, hf))
    tpos, gpos, hpos = (np.asarray(a, dtype=float) for a in (tpos, gpos, hpos))
    out = np.zeros(hf.size, dtype=bool) if outside is None else np.asarray(outside, dtype=bool)
    out = out.copy()
    frames = np.intersect1d(np.union1d(gf, hf[out]), hf)
    if frames.size == 0:
        return out
    allf = np.r_[tf, gf]
    allpos = np.concatenate([tpos.reshape(-1, hpos.shape[-1]), gpos], axis=0)
    for rows, hyp in _frame_rows(allf, hf, frames):
        if rows.size == 0:
            continue
        d = _dist(allpos[rows], hpos[hyp])
        ok = d <= threshold
        # a pair within the threshold always beats leaving both unmatched
        cost = np.where(ok, d, threshold * (1.0 + d.size))
        r, c = linear_sum_assignment(cost)
        r, c = r[ok[r, c]], c[ok[r, c]]
        out[hyp[c[rows[r] < tf.size]]] = False  # matched to a true position: scored
        out[hyp[c[rows[r] >= tf.size]]] = True
    return out
