"""Protection levels on the error model of the integrity support message (:mod:`.ism`): the
position error a test leaves, bounded with the ISM's per-satellite sigmas and biases."""

from __future__ import annotations

import math

import numpy as np

from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.integrity.ism import ErrorModel
from navtrack.integrity.residuals import normal_inverse, normal_quantile, wraim_levels
from navtrack.integrity.separation import Separation

__all__ = ["bounded_separation_levels", "bounded_wraim_levels", "model_rows", "model_spread"]


def model_spread(
    gain: FloatArray, used: BoolArray, model: ErrorModel
) -> tuple[FloatArray, FloatArray]:
    """Standard deviation and nominal bias of position errors under the ISM model.

    ``sigma_q^2 = sum_j S_qj^2 sigma_int,j^2``, ``b_q = sum_j |S_qj| b_nom,j`` for position
    gains ``S`` (m per m of pseudorange error) of the satellites used; ``inf`` where a used
    satellite is outside the model.

    Parameters
    ----------
    gain : ndarray, shape (B, ..., 3, S)
    used : ndarray of bool, shape (B, S)
    model : ErrorModel

    Returns
    -------
    sigma, bias : ndarray, shape (B, ..., 3)
    """
    extra = gain.ndim - 3
    idx = (slice(None),) + (None,) * extra + (None, slice(None))
    finite = np.isfinite(model.var_int_m2)
    var = np.where(used & finite, model.var_int_m2, 0.0)[idx]
    b = np.where(used, model.b_int_m, 0.0)[idx]
    sigma = np.sqrt(np.sum(gain**2 * var, axis=-1))
    bias = np.sum(np.abs(gain) * b, axis=-1)
    outside = np.asarray((used & ~finite).any(axis=1))[(slice(None),) + (None,) * (extra + 1)]
    return np.where(outside, np.inf, sigma), np.where(outside, np.inf, bias)


def gain_all(g: FloatArray, scale: FloatArray, rot: FloatArray) -> FloatArray:
    """East/north/up gains (m per m) of the weighted least squares of whitened ``g`` (rows
    ``scale_j B_j``): ``R (g^T g)^-1 g^T diag(scale)``, shape (B, 3, S)."""
    q = normal_inverse(g)
    return rot @ q[:, :3, :] @ np.swapaxes(g, -1, -2) * scale[:, None, :]


def bounded_wraim_levels(
    g: FloatArray,
    used: BoolArray,
    scale: FloatArray,
    rot: FloatArray,
    model: ErrorModel,
    pfa: float,
    pmd: float,
) -> tuple[FloatArray, FloatArray]:
    """Weighted-RAIM protection levels on the ISM error model (``chi2``, ``loo``, ``fde``,
    ``fcm``).

    The detection test (and so the slopes and ``p_bias`` of :func:`wraim_levels`) uses the
    SPP weights; the position error it leaves is bounded with the integrity model:
    ``VPL = max(K_ff sigma_u, VSlope_max p_bias + K_md sigma_u) + b_u`` and
    ``HPL = max(K_h sigma_h, HSlope_max p_bias + K_md sigma_h) + b_h`` with
    ``sigma_q, b_q`` from :func:`model_spread`, ``sigma_h = sqrt(sigma_e^2 + sigma_n^2)``,
    ``b_h = sqrt(b_e^2 + b_n^2)``, ``K_md = Q^-1(pmd)``, ``K_ff = Q^-1(pmd / 2)`` and
    ``K_h = sqrt(-2 ln pmd)`` (the radial tail ``exp(-K^2 / 2)`` of a 2-D Gaussian of largest
    axis ``<= sigma_h``).

    Parameters
    ----------
    g, used : whitened problem (shapes (B, S, P), (B, S))
    scale : ndarray, shape (B, S)
        Whitening of each pseudorange (``g = scale B``), 1/m.
    rot : ndarray, shape (B, 3, 3)
    model : ErrorModel
    pfa, pmd : float

    Returns
    -------
    hpl_m, vpl_m : ndarray, shape (B,)
    """
    fault_h, fault_v = wraim_levels(g, used, rot, pfa, pmd)
    sig, b = model_spread(gain_all(g, scale, rot), used, model)
    k_md = normal_quantile(1.0 - pmd)
    k_ff = normal_quantile(1.0 - pmd / 2.0)
    k_h = math.sqrt(-2.0 * math.log(pmd))
    s_h = np.hypot(sig[:, 0], sig[:, 1])
    vpl = np.maximum(k_ff * sig[:, 2], fault_v + k_md * sig[:, 2]) + b[:, 2]
    hpl = np.maximum(k_h * s_h, fault_h + k_md * s_h) + np.hypot(b[:, 0], b[:, 1])
    return hpl, vpl


def bounded_separation_levels(
    sep: Separation,
    g: FloatArray,
    used: BoolArray,
    scale: FloatArray,
    rot: FloatArray,
    model: ErrorModel,
    pmd: float,
    block: int = 128,
) -> tuple[FloatArray, FloatArray]:
    """Solution-separation protection levels on the ISM error model (``ss``):
    ``PL_q = max(K_ff sigma_0q + b_0q, max_k T_kq + K_md sigma_kq + b_kq)`` with the
    thresholds ``T_kq`` of the test (:func:`solution_separation`) and ``sigma, b`` of each
    subset's gains under the integrity model (:func:`model_spread`); ``HPL = sqrt(PL_e^2 +
    PL_n^2)``. Gains are formed ``block`` epochs at a time.

    Returns
    -------
    hpl_m, vpl_m : ndarray, shape (B,)
        NaN where the separation is unavailable.
    """
    sub = sep.subsets
    sig0, b0 = model_spread(gain_all(g, scale, rot), used, model)
    k_md = normal_quantile(1.0 - pmd)
    k_ff = normal_quantile(1.0 - pmd / 2.0)
    pl = k_ff * sig0 + b0
    n_s = used.shape[1]
    sat_axis = np.arange(n_s)
    for a in range(0, used.shape[0], block):
        r = slice(a, a + block)
        m = sub.members[r]
        left = ((sat_axis == m[..., :1]) | (sat_axis == m[..., 1:])) & (m[..., :1] >= 0)
        keep = used[r, None, :] & ~left  # (b, H, S)
        gk = g[r, None] * keep[..., None]
        gain = rot[r][:, None] @ sub.cov[r][..., :3, :] @ np.swapaxes(gk, -1, -2)
        gain = gain * scale[r][:, None, None, :]
        sig, b = model_spread(gain, used[r], model_rows(model, r))
        pk = np.where(sub.valid[r][..., None], sep.threshold_m[r] + k_md * sig + b, 0.0)
        pl[r] = np.maximum(pl[r], pk.max(axis=1))
    ok = sep.available
    return np.where(ok, np.hypot(pl[:, 0], pl[:, 1]), np.nan), np.where(ok, pl[:, 2], np.nan)


def model_rows(model: ErrorModel, rows: slice | IntArray) -> ErrorModel:
    """The error model of some epochs."""
    return ErrorModel(
        var_int_m2=model.var_int_m2[rows],
        var_acc_m2=model.var_acc_m2[rows],
        b_int_m=model.b_int_m[rows],
        b_acc_m=model.b_acc_m[rows],
        covered=model.covered,
    )
