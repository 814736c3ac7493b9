"""Residual tests of the whitened least-squares problem of each epoch (the kernels of RAIM).

Everything works on ``g = W^1/2 B`` (rows of the design matrix scaled by ``1/sigma``) and
``y = W^1/2 v`` (residuals in sigmas), taken from
:class:`navtrack.gnss.spp.PositionEstimate`, over fixed ``(epochs, satellites)`` shapes with the
``used`` mask:

* :func:`chi2_test`: residual test ``y^T y > chi2_{1-pfa}(dof)``, ``dof = n - 3 - clocks``;
* :func:`normalised_residuals`: Baarda's w-test per satellite (:mod:`navtrack.estimation.robust`);
* :func:`wraim_levels`: weighted-RAIM slopes and horizontal/vertical protection levels.

References
----------
T. Walter, P. Enge, "Weighted RAIM for precision approach", ION GPS 1995, 1995-2004 (slopes,
``p_bias``, HPL/VPL). W. Baarda 1968 (w-test).
"""

from __future__ import annotations

from functools import lru_cache
from statistics import NormalDist

import numpy as np

from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.estimation.chi2 import chi2_threshold, noncentrality_bias
from navtrack.estimation.robust import redundancy_numbers, w_test
from navtrack.gnss.spp import PositionEstimate

__all__ = [
    "chi2_test",
    "chi2_thresholds",
    "n_params",
    "normal_inverse",
    "normal_quantile",
    "normalised_residuals",
    "safe_inverse",
    "whitened",
    "wraim_levels",
]


@lru_cache(maxsize=4096)
def normal_quantile(p: float) -> float:
    """Quantile of the standard normal distribution."""
    return NormalDist().inv_cdf(p)


def chi2_thresholds(pfa: float, dof: IntArray) -> FloatArray:
    """:func:`navtrack.estimation.chi2.chi2_threshold` of every element of ``dof``; NaN where
    ``dof < 1``."""
    flat = np.asarray(dof).ravel()
    out = np.array([chi2_threshold(pfa, int(k)) if k > 0 else np.nan for k in flat])
    return out.reshape(np.shape(dof))


def whitened(estimate: PositionEstimate) -> tuple[FloatArray, FloatArray, BoolArray]:
    """The whitened problem of each epoch of an estimate.

    Returns
    -------
    g : ndarray, shape (B, S, P)
        ``W^1/2 B``, zero rows where not used.
    y : ndarray, shape (B, S)
        ``W^1/2 v`` (residuals in sigmas), 0 where not used.
    used : ndarray of bool, shape (B, S)
    """
    used = estimate.used & (estimate.weights > 0)
    sw = np.sqrt(np.where(used, estimate.weights, 0.0))
    g = estimate.design * sw[..., None]
    y = np.where(used, np.nan_to_num(estimate.residuals_m) * sw, 0.0)
    return g, y, used


def n_params(g: FloatArray) -> IntArray:
    """Parameters touched by at least one measurement, per leading index."""
    return np.asarray((np.abs(g).sum(axis=-2) > 0).sum(axis=-1), dtype=np.int64)


def chi2_test(
    y: FloatArray, used: BoolArray, n_params: IntArray, pfa: float
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Chi-square test of the whitened residuals.

    Parameters
    ----------
    y : ndarray, shape (..., S)
        Whitened residuals (0 where not used).
    used : ndarray of bool, shape (..., S)
    n_params : ndarray of int, shape (...)
        Estimated parameters (3 + clocks with a satellite).
    pfa : float

    Returns
    -------
    stat : ndarray, shape (...)
        ``y^T y``, NaN where ``dof < 1``.
    threshold : ndarray, shape (...)
        ``chi2_{1-pfa}(dof)``, NaN where ``dof < 1``.
    dof : ndarray of int, shape (...)
        ``n - n_params``.
    """
    dof = used.sum(axis=-1) - n_params
    stat = np.where(dof > 0, np.sum(np.where(used, y, 0.0) ** 2, axis=-1), np.nan)
    return stat, chi2_thresholds(pfa, dof), dof.astype(np.int64)


def safe_inverse(n: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Inverses of a stack of symmetric matrices; NaN and ``True`` in the mask where singular
    (``|det| <= 1e-12 prod(diag)``)."""
    d = np.einsum("...pp->...p", n)
    with np.errstate(all="ignore"):
        singular = ~(np.abs(np.linalg.det(n)) > 1e-12 * np.prod(np.abs(d), axis=-1))
    n = np.where(singular[..., None, None], np.eye(n.shape[-1]), n)
    inv = np.linalg.inv(n)
    return np.where(singular[..., None, None], np.nan, inv), singular


def normal_inverse(g: FloatArray) -> FloatArray:
    """``(g^T g)^-1`` with zero rows/columns for parameters no measurement touches."""
    n = np.swapaxes(g, -1, -2) @ g  # matmul: einsum is slow on stacks of small matrices
    absent = np.einsum("...pp->...p", n) <= 0.0
    inv, _ = safe_inverse(n + np.eye(n.shape[-1]) * absent[..., None, :])
    return inv * ~absent[..., None, :] * ~absent[..., :, None]


def hat_diagonal(g: FloatArray, q: FloatArray) -> FloatArray:
    return np.sum((g @ q) * g, axis=-1)


def normalised_residuals(g: FloatArray, y: FloatArray, used: BoolArray) -> FloatArray:
    """Baarda's w-test statistic per satellite, ``w_i = y_i / sqrt(r_i)``.

    Parameters
    ----------
    g : ndarray, shape (..., S, P)
    y : ndarray, shape (..., S)
    used : ndarray of bool, shape (..., S)

    Returns
    -------
    ndarray, shape (..., S)
        NaN where not used or the satellite cannot be checked (redundancy ``r_i = 0``).
    """
    r = redundancy_numbers(hat_diagonal(g, normal_inverse(g)), 1.0)
    w = w_test(y, 1.0, np.where(r > 1e-9, r, np.nan))
    return np.where(used, w, np.nan)


def wraim_levels(
    g: FloatArray,
    used: BoolArray,
    enu_rotation: FloatArray,
    pfa: float,
    pmd: float,
) -> tuple[FloatArray, FloatArray]:
    """Weighted-RAIM horizontal and vertical protection levels.

    ``HPL = max_i HSlope_i p_bias``, ``HSlope_i = sqrt(A_e,i^2 + A_n,i^2) / sqrt(r_i)`` with
    ``A = R (g^T g)^-1 g^T`` (whitened position gains in east/north/up), ``r_i`` the redundancy
    numbers and ``p_bias`` the root of the non-centrality at which the chi-square test misses
    with ``pmd`` (Walter & Enge 1995, eqs. 9-13); likewise VPL with ``A_u``.

    Parameters
    ----------
    g : ndarray, shape (B, S, P)
    used : ndarray of bool, shape (B, S)
    enu_rotation : ndarray, shape (B, 3, 3)
    pfa, pmd : float

    Returns
    -------
    hpl_m, vpl_m : ndarray, shape (B,)
        NaN where the test is unavailable (``dof < 1``).
    """
    q = normal_inverse(g)
    a = enu_rotation @ q[:, :3, :] @ np.swapaxes(g, -1, -2)
    r = redundancy_numbers(hat_diagonal(g, q), 1.0)
    ok = used & (r > 1e-9)
    sr = np.sqrt(np.where(ok, r, 1.0))
    h = np.where(ok, np.hypot(a[:, 0], a[:, 1]) / sr, 0.0).max(axis=1, initial=0.0)
    v = np.where(ok, np.abs(a[:, 2]) / sr, 0.0).max(axis=1, initial=0.0)
    dof = used.sum(axis=1) - n_params(g)
    pb = np.array([noncentrality_bias(pfa, pmd, int(k)) if k > 0 else np.nan for k in dof])
    return h * pb, v * pb
