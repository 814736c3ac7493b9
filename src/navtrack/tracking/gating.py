"""Validation gates: chi-square ellipsoids and a k-d tree pre-gate for many targets.

References
----------
.. [1] Y. Bar-Shalom, T. E. Fortmann, *Tracking and Data Association*, Academic Press 1988,
   section 2.3 (validation region ``νᵀ S⁻¹ ν <= gamma``, gate probability ``P_G``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray
from navtrack.estimation.chi2 import chi2_quantile_exact
from navtrack.estimation.models import wrap_angle

__all__ = ["Gate", "chi2_threshold", "gate", "kdtree_pregate"]


@lru_cache(maxsize=64)
def chi2_threshold(gate_probability: float, dim_z: int) -> float:
    """Gate size ``gamma`` with ``P(chi²_m <= gamma) = gate_probability``.

    Parameters
    ----------
    gate_probability : float
        ``P_G`` in (0, 1]; 1 gives ``inf`` (no gate).
    dim_z : int
        Measurement dimension ``m`` (degrees of freedom).

    Returns
    -------
    float
        ``gamma = 2 P^-1(m / 2, P_G)`` with ``P`` the regularised lower incomplete gamma
        function: the chi-square quantile :func:`navtrack.estimation.chi2.chi2_quantile_exact`.
    """
    if not 0.0 < gate_probability < 1.0:
        if gate_probability == 1.0:
            return float("inf")
        raise ValueError(f"gate_probability must be in (0, 1], got {gate_probability}")
    if dim_z < 1:
        raise ValueError(f"dim_z must be >= 1, got {dim_z}")
    return chi2_quantile_exact(gate_probability, dim_z)


@dataclass(frozen=True, slots=True, eq=False)
class Gate:
    """Track-to-measurement gating of one scan (arrays read-only).

    ``...`` are optional leading batch axes (independent problems: Monte Carlo runs,
    particles), as given to :func:`gate`.

    Attributes
    ----------
    innovation : (..., T, M, m) ``z_j - ẑ_t`` (angles wrapped)
    d2 : (..., T, M) squared Mahalanobis distance (``inf`` where not computed by the pre-gate)
    valid : (..., T, M) bool, ``d2 <= gamma``
    log_norm : (..., T) ``-0.5 (m log 2π + log det S_t)``, the log of the Gaussian's peak
    """

    innovation: FloatArray
    d2: FloatArray
    valid: BoolArray
    log_norm: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def log_likelihood(self) -> FloatArray:
        """``log N(z_j; ẑ_t, S_t)``, shape (..., T, M)."""
        return np.asarray(self.log_norm[..., None] - 0.5 * self.d2)


def gate(
    z_pred: ArrayLike,
    S: ArrayLike,
    z: ArrayLike,
    gamma: float,
    *,
    angle_mask: ArrayLike | None = None,
    candidates: BoolArray | None = None,
    pair_offset: ArrayLike | None = None,
) -> Gate:
    """Chi-square gate of every track against every measurement.

    Parameters
    ----------
    z_pred : (..., T, m) predicted measurements
    S : (..., T, m, m) innovation covariances (positive definite)
    z : (..., M, m) measurements (finite); without batch axes a flat array is read as (M, m)
    gamma : float
        Gate size (see :func:`chi2_threshold`); ``inf`` accepts everything.
    angle_mask : bool (m,) or None
    candidates : bool (..., T, M) or None
        Pairs to evaluate (from :func:`kdtree_pregate`); others get ``d2 = inf``.
    pair_offset : (..., T, M, m) or None
        Added to the prediction of each pair: the innovation is ``z_j - ẑ_t - offset_tj``
        (the tracker's time windows: the motion of track ``t`` between its prediction time
        and the time of detection ``j``).

    Raises
    ------
    ValueError
        Non-finite measurements, mismatched batch axes, or an ``S`` that is not positive
        definite.
    """
    zp = np.asarray(z_pred, dtype=float)
    S = np.asarray(S, dtype=float)
    m = zp.shape[-1]
    Z = np.asarray(z, dtype=float)
    Z = Z.reshape(-1, m) if zp.ndim == 2 else Z
    if Z.shape[:-2] != zp.shape[:-2] or Z.shape[-1] != m:
        raise ValueError(f"z: expected shape (..., M, {m}) like z_pred {zp.shape}, got {Z.shape}")
    if not np.isfinite(Z).all():
        raise ValueError("z: measurements must be finite")
    T, M = zp.shape[-2], Z.shape[-2]
    y = Z[..., None, :, :] - zp[..., :, None, :]
    if pair_offset is not None:
        y = y - np.asarray(pair_offset, dtype=float)
    if angle_mask is not None and np.any(angle_mask):
        am = np.flatnonzero(angle_mask)
        y[..., am] = wrap_angle(y[..., am])
    if m == 2:  # closed form (the common planar case): no LAPACK call per gate
        a, b, c = S[..., 0, 0], S[..., 1, 0], S[..., 1, 1]
        det = a * c - b * b
        if not ((a > 0) & (det > 0)).all():
            raise ValueError("S: innovation covariance not positive definite")
        log_det = np.log(det)
        y0, y1 = y[..., 0], y[..., 1]
        d2 = c[..., None] * y0 * y0 - 2.0 * b[..., None] * y0 * y1 + a[..., None] * y1 * y1
        d2 = d2 / det[..., None]
    else:
        try:
            L = np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            raise ValueError("S: innovation covariance not positive definite") from None
        log_det = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
        if T == 0 or M == 0:
            d2 = np.zeros(y.shape[:-1])
        else:
            # whitened innovations w = L⁻¹ y for every (t, j): one inverse per track, applied
            # to the track's M innovations by one stacked product
            w = y @ np.swapaxes(np.linalg.inv(L), -1, -2)
            d2 = np.einsum("...i,...i->...", w, w)
    log_norm = -0.5 * (m * np.log(2 * np.pi) + log_det)
    if candidates is not None:
        d2 = np.where(candidates, d2, np.inf)
    return Gate(y, d2, d2 <= gamma, log_norm)


def kdtree_pregate(
    z_pred: ArrayLike, S: ArrayLike, z: ArrayLike, gamma: float, margin: ArrayLike = 0.0
) -> BoolArray:
    """Coarse spatial pre-gate: pairs within the ball enclosing each track's gate ellipsoid.

    The ball radius is ``sqrt(gamma · λ_max(S_t)) + margin_t`` (``margin``: scalar or (T,),
    the largest ``|pair_offset|`` of the track given to :func:`gate`), so every pair inside the
    chi-square gate is a candidate (no false rejections). Measurements are put in a
    ``scipy.spatial.cKDTree``; the cost is ``O((T + M) log M)`` instead of ``O(T·M)``
    Mahalanobis distances. Only for measurement spaces without angles (Cartesian positions).

    Returns
    -------
    candidates : bool (T, M)
    """
    from scipy.spatial import cKDTree

    zp = np.asarray(z_pred, dtype=float)
    Z = np.asarray(z, dtype=float).reshape(-1, zp.shape[-1])
    S = np.asarray(S, dtype=float)
    T, M = zp.shape[0], Z.shape[0]
    out = np.zeros((T, M), dtype=bool)
    if T == 0 or M == 0:
        return out
    radius = np.sqrt(gamma * np.linalg.eigvalsh(S)[:, -1]) + np.asarray(margin, dtype=float)
    tree = cKDTree(Z)
    for t, idx in enumerate(tree.query_ball_point(zp, radius)):
        out[t, idx] = True
    return out
