"""Kalman, extended and unscented Kalman predict/update kernels, batched over leading axes.

Shapes: states ``x (..., n)``, covariances ``P (..., n, n)``, measurements ``z (..., m)``; the
leading axes ``...`` are any batch (tracks, particles, Monte Carlo runs) and broadcast against
each other and against the model matrices (``F (n, n)`` or ``(..., n, n)``). Inputs are never
written to. The EKF and UKF forms take any model with the methods of the protocols
:class:`~navtrack.estimation.models.MotionModel` and
:class:`~navtrack.estimation.models.MeasurementModel` (the tracking models of
:mod:`navtrack.tracking.models`, for instance).

References
----------
.. [1] Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
   Navigation*, Wiley 2001: KF eq. 5.2.3-1..5.2.3-17, Joseph form eq. 5.2.3-18, EKF section 10.3.
.. [2] S. J. Julier, J. K. Uhlmann, "Unscented filtering and nonlinear estimation", Proc. IEEE
   92(3), 2004 (scaled sigma points, alpha/beta/kappa); E. A. Wan, R. van der Merwe, "The
   unscented Kalman filter for nonlinear estimation", AS-SPCC 2000 (weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray
from navtrack.estimation.models import MeasurementModel, MotionModel, wrap_angle

__all__ = [
    "KalmanUpdate",
    "ekf_predict",
    "ekf_update",
    "gain_update",
    "innovation_gain",
    "kalman_gain",
    "kf_predict",
    "kf_update",
    "mahalanobis2",
    "sigma_points",
    "stacked_inverse",
    "ukf_predict",
    "ukf_update",
]


@dataclass(frozen=True, slots=True, eq=False)
class KalmanUpdate:
    """Result of a measurement update (all arrays read-only).

    Attributes
    ----------
    x : (..., n) posterior state
    P : (..., n, n) posterior covariance
    innovation : (..., m) ``z - h(x_pred)``, angle components wrapped to ``[-pi, pi)``
    S : (..., m, m) innovation covariance
    K : (..., n, m) gain
    """

    x: FloatArray
    P: FloatArray
    innovation: FloatArray
    S: FloatArray
    K: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def nis(self) -> FloatArray:
        """Normalised innovation squared ``yᵀ S⁻¹ y``, shape ``(...)``."""
        return mahalanobis2(self.innovation, self.S)


def _T(a: FloatArray) -> FloatArray:
    return np.swapaxes(a, -1, -2)


def _sym(P: FloatArray) -> FloatArray:
    return 0.5 * (P + _T(P))


def stacked_inverse(A: ArrayLike) -> FloatArray:
    """Inverses of stacked square matrices ``(..., n, n)``.

    ``n = 2`` (planar positions, range-bearing innovations) in closed form, the adjugate over
    the determinant: a few array operations instead of one LAPACK call per matrix, which is
    what large stacks of 2 x 2 matrices cost in ``numpy.linalg``; a symmetric matrix gets an
    exactly symmetric inverse. A singular matrix raises ``numpy.linalg.LinAlgError`` as
    ``numpy.linalg.inv`` does.
    """
    A = np.asarray(A, dtype=float)
    if A.shape[-1] != 2:
        return np.asarray(np.linalg.inv(A), dtype=float)
    a, b, c, d = A[..., 0, 0], A[..., 0, 1], A[..., 1, 0], A[..., 1, 1]
    det = a * d - b * c
    if (det == 0).any():
        raise np.linalg.LinAlgError("Singular matrix")
    out = np.empty_like(A)
    out[..., 0, 0] = d / det
    out[..., 0, 1] = -b / det
    out[..., 1, 0] = -c / det
    out[..., 1, 1] = a / det
    return out


def mahalanobis2(y: FloatArray, S: FloatArray) -> FloatArray:
    """Squared Mahalanobis distance ``yᵀ S⁻¹ y`` over leading axes."""
    y = np.asarray(y, dtype=float)
    sol = np.linalg.solve(S, y[..., None])[..., 0]
    return np.asarray(np.einsum("...i,...i->...", y, sol))


# ---------------------------------------------------------------------------------- predict


def kf_predict(
    x: ArrayLike, P: ArrayLike, F: ArrayLike, Q: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Linear prediction ``x' = F x``, ``P' = F P Fᵀ + Q`` (Bar-Shalom eq. 5.2.3-5, -7).

    Returns
    -------
    x : (..., n), P : (..., n, n)
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    F = np.asarray(F, dtype=float)
    if F.ndim == 2:  # one F for the batch: x Fᵀ, and P as rows of n² by F ⊗ F (one product)
        n = F.shape[0]
        FF = (F[:, None, :, None] * F[None, :, None, :]).reshape(n * n, n * n)
        xp = x @ F.T
        Pp = (P.reshape(*P.shape[:-2], n * n) @ FF.T).reshape(P.shape)
    else:
        xp = np.einsum("...ij,...j->...i", F, x)
        Pp = F @ P @ _T(F)
    return xp, _sym(Pp + np.asarray(Q, dtype=float))


def ekf_predict(
    x: ArrayLike, P: ArrayLike, model: MotionModel, dt: float
) -> tuple[FloatArray, FloatArray]:
    """Extended prediction ``x' = f(x)``, ``P' = J P Jᵀ + Q`` with ``J = ∂f/∂x`` at ``x``."""
    x = np.asarray(x, dtype=float)
    J = model.jacobian(x, dt)
    Pp = J @ np.asarray(P, dtype=float) @ _T(J) + model.Q(dt)
    return model.f(x, dt), _sym(Pp)


def sigma_points(
    x: FloatArray, P: FloatArray, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Scaled symmetric sigma points (Julier & Uhlmann 2004; Wan & van der Merwe 2000).

    Returns
    -------
    X : (..., 2n+1, n) sigma points
    wm, wc : (2n+1,) mean and covariance weights
    """
    n = x.shape[-1]
    lam = alpha * alpha * (n + kappa) - n
    if n + lam <= 0:
        raise ValueError(f"alpha²(n + kappa) must be > 0, got {n + lam}")
    L = np.linalg.cholesky((n + lam) * P)  # (..., n, n), columns are the offsets
    off = _T(L)  # (..., n, n) rows = offsets
    X = np.concatenate([x[..., None, :], x[..., None, :] + off, x[..., None, :] - off], axis=-2)
    wm = np.full(2 * n + 1, 0.5 / (n + lam))
    wc = wm.copy()
    wm[0] = lam / (n + lam)
    wc[0] = lam / (n + lam) + 1 - alpha * alpha + beta
    return X, wm, wc


def ukf_predict(
    x: ArrayLike,
    P: ArrayLike,
    model: MotionModel,
    dt: float,
    alpha: float = 1.0,
    beta: float = 2.0,
    kappa: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Unscented prediction through ``model.f``; returns ``(x, P)``."""
    x = np.asarray(x, dtype=float)
    X, wm, wc = sigma_points(x, np.asarray(P, dtype=float), alpha, beta, kappa)
    Y = model.f(X, dt)
    xp = np.einsum("k,...ki->...i", wm, Y)
    d = Y - xp[..., None, :]
    Pp = np.einsum("k,...ki,...kj->...ij", wc, d, d) + model.Q(dt)
    return xp, _sym(Pp)


# ----------------------------------------------------------------------------------- update


def _wrap(y: FloatArray, angle_mask: BoolArray | None) -> FloatArray:
    if angle_mask is None or not np.any(angle_mask):
        return y
    return np.where(angle_mask, wrap_angle(y), y)


def kalman_gain(PHt: ArrayLike, S: ArrayLike) -> FloatArray:
    """Gain ``K = P Hᵀ S⁻¹`` (Bar-Shalom eq. 5.2.3-11) by a solve on the symmetric ``S`` (for
    ``m = 2`` the product with :func:`stacked_inverse`, closed form).

    Parameters
    ----------
    PHt : (..., n, m)
        Cross covariance of state and measurement: ``P Hᵀ`` (KF/EKF) or ``P_xz`` (UKF).
    S : (..., m, m)
        Innovation covariance.

    Returns
    -------
    K : (..., n, m)
    """
    S = np.asarray(S, dtype=float)
    PHt = np.asarray(PHt, dtype=float)
    if S.shape[-1] == 2:
        return np.asarray(PHt @ stacked_inverse(S))
    # K = (S⁻¹ (P Hᵀ)ᵀ)ᵀ
    return _T(np.asarray(np.linalg.solve(S, _T(PHt)), dtype=float))


def innovation_gain(P: ArrayLike, H: ArrayLike, R: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Innovation covariance and gain of a linear(ised) measurement (Bar-Shalom eq. 5.2.3-9, -11).

    Parameters
    ----------
    P : (..., n, n) predicted covariance
    H : (m, n) or (..., m, n) measurement matrix (EKF: Jacobian at the prediction)
    R : (m, m) or (..., m, m) measurement noise covariance

    Returns
    -------
    S : (..., m, m) ``H P Hᵀ + R``, symmetrised
    K : (..., n, m) ``P Hᵀ S⁻¹``
    """
    P = np.asarray(P, dtype=float)
    H = np.asarray(H, dtype=float)
    if H.ndim == 2 and P.ndim > 2:  # one H for the batch: two products over all rows at once
        n, m = P.shape[-1], H.shape[0]
        PHt = (P.reshape(-1, n) @ H.T).reshape(*P.shape[:-1], m)
        HPHt = _T((_T(PHt).reshape(-1, n) @ H.T).reshape(*P.shape[:-2], m, m))
    else:
        PHt = P @ _T(H)
        HPHt = H @ PHt
    S = _sym(HPHt + np.asarray(R, dtype=float))
    return S, kalman_gain(PHt, S)


def gain_update(
    x: ArrayLike,
    P: ArrayLike,
    y: ArrayLike,
    K: ArrayLike,
    S: ArrayLike,
    *,
    symmetrize: bool = True,
) -> tuple[FloatArray, FloatArray]:
    """Posterior for a given gain: ``x + K y``, ``P - K S Kᵀ`` (Bar-Shalom eq. 5.2.3-12, -15).

    Parameters
    ----------
    x : (..., n), P : (..., n, n) prediction
    y : (..., m) innovation
    K : (..., n, m) gain, S : (..., m, m) innovation covariance (from :func:`innovation_gain`)
    symmetrize : bool
        Return ``(P + Pᵀ) / 2``; False for a term that enters a further sum (the PDA update
        symmetrises its total).

    Returns
    -------
    x : (..., n), P : (..., n, n)
    """
    K = np.asarray(K, dtype=float)
    Pn = np.asarray(P, dtype=float) - K @ np.asarray(S, dtype=float) @ _T(K)
    xn = _state_update(np.asarray(x, dtype=float), K, np.asarray(y, dtype=float))
    return xn, _sym(Pn) if symmetrize else Pn


def _state_update(x: FloatArray, K: FloatArray, y: FloatArray) -> FloatArray:
    return x + np.einsum("...ij,...j->...i", K, y)


def _update(
    x: FloatArray,
    P: FloatArray,
    y: FloatArray,
    K: FloatArray,
    S: FloatArray,
    H: FloatArray | None,
    R: FloatArray,
    joseph: bool,
) -> KalmanUpdate:
    if not joseph:
        xn, Pn = gain_update(x, P, y, K, S)
        return KalmanUpdate(xn, Pn, y, S, K)
    if H is None:
        raise ValueError("the Joseph form needs a measurement matrix (KF/EKF only)")
    xn = _state_update(x, K, y)
    IKH = np.eye(x.shape[-1]) - K @ H
    Pn = IKH @ P @ _T(IKH) + K @ R @ _T(K)
    return KalmanUpdate(xn, _sym(Pn), y, S, K)


def kf_update(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    *,
    joseph: bool = False,
    angle_mask: ArrayLike | None = None,
) -> KalmanUpdate:
    """Linear update (Bar-Shalom eq. 5.2.3-9..-17; Joseph form eq. 5.2.3-18 when ``joseph``).

    Parameters
    ----------
    x : (..., n), P : (..., n, n), z : (..., m)
    H : (m, n) or (..., m, n), R : (m, m) or (..., m, m)
    joseph : bool
        Use ``(I-KH) P (I-KH)ᵀ + K R Kᵀ``, which stays positive semi-definite under rounding.
    angle_mask : bool (m,) or None
        Innovation components wrapped to ``[-pi, pi)``.
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    H = np.asarray(H, dtype=float)
    R = np.asarray(R, dtype=float)
    mask = None if angle_mask is None else np.asarray(angle_mask, dtype=bool)
    y = _wrap(np.asarray(z, dtype=float) - np.einsum("...ij,...j->...i", H, x), mask)
    S, K = innovation_gain(P, H, R)
    return _update(x, P, y, K, S, H, R, joseph)


def ekf_update(
    x: ArrayLike, P: ArrayLike, z: ArrayLike, model: MeasurementModel, *, joseph: bool = False
) -> KalmanUpdate:
    """Extended update: ``h`` and its Jacobian evaluated at the prediction (Bar-Shalom 10.3)."""
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    H = model.jacobian(x)
    y = _wrap(np.asarray(z, dtype=float) - model.h(x), model.angle_mask)
    S, K = innovation_gain(P, H, model.R)
    return _update(x, P, y, K, S, H, model.R, joseph)


def ukf_update(
    x: ArrayLike,
    P: ArrayLike,
    z: ArrayLike,
    model: MeasurementModel,
    *,
    alpha: float = 1.0,
    beta: float = 2.0,
    kappa: float = 0.0,
) -> KalmanUpdate:
    """Unscented update (Wan & van der Merwe 2000, algorithm 3.1).

    Angle components of the predicted measurement are averaged as deviations from the central
    sigma point's image, wrapped, so a mean near ±pi is not torn apart.
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    X, wm, wc = sigma_points(x, P, alpha, beta, kappa)
    Z = model.h(X)  # (..., 2n+1, m)
    mask = model.angle_mask
    dZ0 = _wrap(Z - Z[..., :1, :], mask)
    zp = Z[..., 0, :] + np.einsum("k,...ki->...i", wm, dZ0)
    dZ = _wrap(Z - zp[..., None, :], mask)
    dX = X - x[..., None, :]
    S = _sym(np.einsum("k,...ki,...kj->...ij", wc, dZ, dZ) + model.R)
    Pxz = np.einsum("k,...ki,...kj->...ij", wc, dX, dZ)
    y = _wrap(np.asarray(z, dtype=float) - zp, mask)
    return _update(x, P, y, kalman_gain(Pxz, S), S, None, model.R, False)
