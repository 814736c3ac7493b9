"""Fault hypotheses and solution separation: re-solutions of each epoch without one or two
satellites, by downdating the normal matrix, and the ARAIM-style separation tests and protection
levels over them.

References
----------
M. Joerger, F.-C. Chan, B. Pervan, "Solution separation versus residual-based RAIM",
Navigation 61(4), 2014; WG-C ARAIM Technical Subgroup, *Milestone 3 report*, 2016, Annex
(ARAIM user algorithm: separation thresholds ``K_fa sigma_ss``, protection levels
``T_k + K_md sigma_k``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.integrity.residuals import normal_inverse, normal_quantile, safe_inverse

if TYPE_CHECKING:
    from navtrack.integrity.raim import RaimConfig

__all__ = ["Separation", "Subsets", "pair_hypotheses", "solution_separation", "subset_solutions"]


@dataclass(frozen=True, slots=True, eq=False)
class Subsets:
    """Linearised solutions of an epoch batch without the satellites of each hypothesis.

    Attributes
    ----------
    members : ndarray of int, shape (B, H, 2)
        Satellite indices of each hypothesis (``-1``: none; single faults have one).
    valid : ndarray of bool, shape (B, H)
        Hypothesis applies (its satellites are used and enough remain, ``dof >= 1``).
    dx : ndarray, shape (B, H, P)
        Change of the state from the all-in-view solution (m).
    cov : ndarray, shape (B, H, P, P)
        Covariance of the subset solution (m^2).
    chi2 : ndarray, shape (B, H)
        Whitened residual sum of squares of the subset solution.
    dof : ndarray of int, shape (B, H)
    """

    members: IntArray
    valid: BoolArray
    dx: FloatArray
    cov: FloatArray
    chi2: FloatArray
    dof: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def pair_hypotheses(used: BoolArray, max_faults: int) -> IntArray:
    """Fault hypotheses of one (and two) used satellites per epoch.

    Parameters
    ----------
    used : ndarray of bool, shape (B, S)
    max_faults : {1, 2}

    Returns
    -------
    ndarray of int, shape (B, H, 2)
        Satellite indices, ``-1`` padding: first the ``n_max`` singles, then the pairs of the
        epoch's used satellites (``H = n_max + n_max (n_max - 1) / 2``, ``n_max`` the most
        satellites of an epoch).
    """
    order = np.argsort(~used, axis=1, kind="stable")
    n = used.sum(axis=1)
    n_max = int(n.max(initial=0))
    cols = order[:, :n_max]
    pos = np.arange(n_max)
    real = pos[None, :] < n[:, None]
    singles = np.stack([np.where(real, cols, -1), np.full(cols.shape, -1)], axis=-1)
    if max_faults == 1 or n_max < 2:
        return singles
    a, b = np.triu_indices(n_max, k=1)
    ok = real[:, b]
    pairs = np.stack([np.where(ok, cols[:, a], -1), np.where(ok, cols[:, b], -1)], axis=-1)
    return np.concatenate([singles, pairs], axis=1)


def subset_solutions(g: FloatArray, y: FloatArray, used: BoolArray, members: IntArray) -> Subsets:
    """Re-solve each epoch without the satellites of each hypothesis (one Gauss–Newton step
    from the all-in-view solution, exact for the linearised model).

    The normal matrix of a subset is the all-in-view one minus the rows left out
    (``N_k = N - sum_{j in k} g_j g_j^T``, ``b_k = -sum_{j in k} g_j y_j`` since ``g^T y = 0``
    at the solution), so no ``(hypotheses x satellites)`` system is formed.

    Parameters
    ----------
    g : ndarray, shape (B, S, P)
    y : ndarray, shape (B, S)
    used : ndarray of bool, shape (B, S)
    members : ndarray of int, shape (B, H, 2)
        From :func:`pair_hypotheses` (or any satellite indices, ``-1`` for none).

    Returns
    -------
    Subsets
    """
    n_b, n_s, n_p = g.shape
    rows = np.arange(n_b)[:, None, None]
    m = np.maximum(members, 0)
    real = members >= 0
    gj = g[rows, m] * real[..., None]  # (B, H, 2, P)
    yj = y[rows, m] * real
    n_all = np.swapaxes(g, 1, 2) @ g
    nk = n_all[:, None] - np.swapaxes(gj, 2, 3) @ gj
    b = (np.swapaxes(g, 1, 2) @ y[..., None])[:, None, :, 0] - (
        np.swapaxes(gj, 2, 3) @ yj[..., None]
    )[..., 0]
    absent = np.einsum("bhpp->bhp", nk) <= 1e-12
    cov, singular = safe_inverse(nk + np.eye(n_p) * absent[..., None, :])
    cov = (
        np.where(singular[..., None, None], 0.0, cov)
        * ~absent[..., None, :]
        * ~absent[..., :, None]
    )
    dx = (cov @ b[..., None])[..., 0]
    sat_axis = np.arange(n_s)
    left_out = ((sat_axis == m[..., 0, None]) & real[..., 0, None]) | (
        (sat_axis == m[..., 1, None]) & real[..., 1, None]
    )
    keep = used[:, None, :] & ~left_out
    res = y[:, None, :] - dx @ np.swapaxes(g, 1, 2)
    chi2 = np.sum(np.where(keep, res, 0.0) ** 2, axis=-1)
    dof = keep.sum(axis=-1) - (~absent).sum(axis=-1)
    valid = real.any(axis=-1) & (dof >= 1) & np.all(~real | used[rows, m], axis=-1) & ~singular
    return Subsets(members=members, valid=valid, dx=dx, cov=cov, chi2=chi2, dof=dof)


@dataclass(frozen=True, slots=True, eq=False)
class Separation:
    """Solution-separation tests of an epoch batch.

    Attributes
    ----------
    subsets : Subsets
    ratio : ndarray, shape (B, H)
        Largest ``|dx_q| / T_kq`` over east, north, up (> 1: the hypothesis' test fails).
    threshold_m : ndarray, shape (B, H, 3)
        ``T_kq`` (east, north, up; m).
    detected : ndarray of bool, shape (B,)
    hpl_m, vpl_m : ndarray, shape (B,)
        ``max(K_ff sigma_0, max_k T_k + K_md sigma_k)`` per axis; horizontal as the root sum
        of squares of east and north.
    available : ndarray of bool, shape (B,)
        At least one hypothesis per used satellite applies.
    """

    subsets: Subsets
    ratio: FloatArray
    threshold_m: FloatArray
    detected: BoolArray
    hpl_m: FloatArray
    vpl_m: FloatArray
    available: BoolArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def solution_separation(
    g: FloatArray,
    y: FloatArray,
    used: BoolArray,
    enu_rotation: FloatArray,
    config: RaimConfig,
) -> Separation:
    """ARAIM-style solution separation over all hypotheses of one and two faulty satellites.

    For hypothesis ``k`` the separation ``dx_k`` (east/north/up) is tested against
    ``T_kq = K_fa sigma_ss,kq`` with ``sigma_ss^2 = diag(R (P_k - P_0) R^T)``,
    ``K_fa = Q^-1(pfa / (4 H))`` for each of east and north and ``Q^-1(pfa / (2 H))`` for up
    (half of ``pfa`` to the horizontal, half to the vertical, two-sided, split over the ``H``
    hypotheses). Protection levels ``PL_q = max(K_ff sigma_0q, max_k T_kq + K_md sigma_kq)``
    with ``K_md = Q^-1(pmd)`` and ``K_ff = Q^-1(pmd / 2)``; ``HPL = sqrt(PL_e^2 + PL_n^2)``.

    Parameters
    ----------
    g, y, used : whitened problem (:func:`whitened`), shapes (B, S, P), (B, S), (B, S)
    enu_rotation : ndarray, shape (B, 3, 3)
    config : RaimConfig
        ``pfa``, ``pmd``, ``max_faults``.

    Returns
    -------
    Separation

    Notes
    -----
    The fault priors and the integrity-risk allocation of the ARAIM algorithm are replaced by
    one ``pmd`` for every hypothesis (a bound that does not weigh hypotheses by probability).
    """
    members = pair_hypotheses(used, config.max_faults)
    sub = subset_solutions(g, y, used, members)
    q0 = normal_inverse(g)
    r = enu_rotation
    rt = np.swapaxes(r, 1, 2)
    d_enu = sub.dx[..., :3] @ rt
    c_k = r[:, None] @ sub.cov[..., :3, :3] @ rt[:, None]
    c_0 = r @ q0[:, :3, :3] @ rt
    s_k = np.sqrt(np.maximum(np.einsum("bhii->bhi", c_k), 0.0))
    s_0 = np.sqrt(np.maximum(np.einsum("bii->bi", c_0), 0.0))
    s_ss = np.sqrt(np.maximum(np.einsum("bhii->bhi", c_k - c_0[:, None]), 1e-18))
    n_h = np.maximum(sub.valid.sum(axis=1), 1)
    k_fa = np.stack(
        [
            np.array([normal_quantile(1.0 - config.pfa / (4.0 * h)) for h in n_h]),
            np.array([normal_quantile(1.0 - config.pfa / (4.0 * h)) for h in n_h]),
            np.array([normal_quantile(1.0 - config.pfa / (2.0 * h)) for h in n_h]),
        ],
        axis=-1,
    )
    thr = k_fa[:, None, :] * s_ss
    ratio = np.where(sub.valid, np.max(np.abs(d_enu) / thr, axis=-1), 0.0)
    k_md = normal_quantile(1.0 - config.pmd)
    k_ff = normal_quantile(1.0 - config.pmd / 2.0)
    pl_k = np.where(sub.valid[..., None], thr + k_md * s_k, 0.0).max(axis=1)
    pl = np.maximum(k_ff * s_0, pl_k)
    single = members[..., 1] < 0
    covered = np.zeros(used.shape, dtype=bool)
    rows = np.arange(used.shape[0])[:, None]
    np.logical_or.at(
        covered,
        (rows.repeat(members.shape[1], 1), np.maximum(members[..., 0], 0)),
        sub.valid & single,
    )
    available = np.all(covered | ~used, axis=1) & (used.sum(axis=1) > 0)
    return Separation(
        subsets=sub,
        ratio=ratio,
        threshold_m=thr,
        detected=available & np.any(ratio > 1.0, axis=1),
        hpl_m=np.where(available, np.hypot(pl[:, 0], pl[:, 1]), np.nan),
        vpl_m=np.where(available, pl[:, 2], np.nan),
        available=available,
    )
