"""Fault exclusion: the satellites each exclusion method removes in one round from the epochs
whose test failed (``fde``: largest normalised residual; ``loo``: RTKLIB-like leave-one-out;
``fcm``: fuzzy clustering of paper 2, :mod:`.fcm`).

References
----------
RTKLIB 2.4.3 ``pntpos.c`` ``raim_fde`` (leave-one-out). Gu et al. 2019 (:mod:`.fcm`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from navtrack._typing import BoolArray, FloatArray
from navtrack.integrity.fcm import full_design_matrix, fuzzy_cmeans, gross_error_columns
from navtrack.integrity.fcm import parity_matrix as qr_parity
from navtrack.integrity.residuals import chi2_thresholds, n_params, normalised_residuals
from navtrack.integrity.separation import pair_hypotheses, subset_solutions

if TYPE_CHECKING:
    from navtrack.integrity.raim import RaimConfig

__all__ = ["fcm_exclusion", "fcm_pick", "largest_residual_pick", "leave_one_out_pick"]


def fcm_exclusion(g: FloatArray, y: FloatArray, used: BoolArray, config: RaimConfig) -> BoolArray:
    """Satellites the fuzzy clustering of paper 2 names as gross errors, per epoch.

    For each epoch: parity matrix of the whitened design (:func:`.fcm.parity_matrix`), full
    design matrix of the whitened residuals; then one FCM over all epochs (batched, each epoch
    padded to the largest) with three classes from the maximum, minimum
    and middle column (Mahalanobis distance of the fault-free parity space, which is the
    Euclidean one here, :func:`.fcm.mahalanobis_whitening`), and the paper's rule
    (:func:`.fcm.gross_error_columns`).

    Parameters
    ----------
    g, y, used : whitened problem, shapes (B, S, P), (B, S), (B, S)
    config : RaimConfig
        ``fcm_m``, ``fcm_tol``, ``fcm_max_iter``.

    Returns
    -------
    ndarray of bool, shape (B, S)
        Empty rows where the epoch has fewer than ``P + 2`` satellites.
    """
    out = np.zeros(used.shape, dtype=bool)
    rows, mats, cols_of = [], [], []
    for b in range(used.shape[0]):
        cols = np.flatnonzero(used[b])
        gb = g[b][cols]
        gb = gb[:, np.abs(gb).sum(axis=0) > 0]
        if cols.size < gb.shape[1] + 2:
            continue
        rows.append(b)
        cols_of.append(cols)
        mats.append(full_design_matrix(qr_parity(gb), -y[b, cols]).T)
    if not rows:
        return out
    n_max = max(f.shape[0] for f in mats)
    q_max = max(f.shape[1] for f in mats)
    x = np.zeros((len(rows), n_max, q_max))
    valid = np.zeros((len(rows), n_max), dtype=bool)
    for i, f in enumerate(mats):
        x[i, : f.shape[0], : f.shape[1]] = f
        valid[i, : f.shape[0]] = True
    res = fuzzy_cmeans(
        x,
        3,
        config.fcm_m,
        valid=valid,
        tol=config.fcm_tol,
        max_iter=config.fcm_max_iter,
        stop=config.fcm_stop,
    )
    for i, (b, cols) in enumerate(zip(rows, cols_of, strict=True)):
        out[b, cols] = gross_error_columns(res.classes[i, : cols.size + 1])
    return out


def largest_residual_pick(
    g: FloatArray, y: FloatArray, used: BoolArray, raim: RaimConfig
) -> BoolArray:
    """``fde``: the satellite of the largest absolute normalised residual of each epoch."""
    pick = np.zeros(used.shape, dtype=bool)
    rows = np.arange(used.shape[0])
    w = np.abs(normalised_residuals(g, y, used))
    w = np.where(np.isfinite(w), w, -1.0)
    j = np.argmax(w, axis=1)
    pick[rows, j] = w[rows, j] >= 0
    return pick


def leave_one_out_pick(
    g: FloatArray, y: FloatArray, used: BoolArray, raim: RaimConfig
) -> BoolArray:
    """``loo``: of the subsets without one satellite that pass the test, the one of smallest
    residual (RTKLIB ``raim_fde``); nothing where none passes."""
    pick = np.zeros(used.shape, dtype=bool)
    rows = np.arange(used.shape[0])
    members = pair_hypotheses(used, 1)
    sub = subset_solutions(g, y, used, members)
    ok_k = sub.valid & (sub.chi2 <= chi2_thresholds(raim.pfa, sub.dof))
    score = np.where(ok_k, sub.chi2, np.inf)
    best = np.argmin(score, axis=1)
    found = np.isfinite(score[rows, best])
    pick[rows[found], members[rows[found], best[found], 0]] = True
    return pick


def fcm_pick(g: FloatArray, y: FloatArray, used: BoolArray, raim: RaimConfig) -> BoolArray:
    """``fcm``: the gross errors of :func:`fcm_exclusion`, never leaving fewer than ``P + 1``
    satellites."""
    pick = fcm_exclusion(g, y, used, raim)
    room = used.sum(axis=1) - n_params(g) - 1
    return pick & (np.cumsum(pick, axis=1) <= room[:, None]) & (pick.sum(axis=1) <= room)[:, None]
