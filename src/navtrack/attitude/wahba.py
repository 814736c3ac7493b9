"""Camera attitude from target rays: SVD solution of Wahba's problem inside seeded RANSAC.

A fix pairs unit rays ``v_i`` to surveyed targets measured in the camera (body) frame with the
rays ``w_i`` from the camera position to the same targets in the reference frame; the attitude
``R`` (body -> reference) minimises ``Σ a_i |w_i - R v_i|²``.

References
----------
.. [1] ALHAT field test 1 (paper 6), "Solving for the camera attitude": eq. 2
   ``Wᵀ = R Vᵀ`` solved by ``R = A Bᵀ`` from the SVD ``A Σ Bᵀ`` of ``WᵀV``; RANSAC on three
   points with a projection-error threshold, then the estimate from the remaining points.
.. [2] G. Wahba, "A least squares estimate of satellite attitude", SIAM Review 7(3), 1965;
   F. L. Markley, "Attitude determination using vector observations and the singular value
   decomposition", J. Astronaut. Sci. 36(3), 1988 (the ``det`` correction to a proper rotation).
.. [3] M. A. Fischler, R. C. Bolles, "Random sample consensus", Comm. ACM 24(6), 1981 (trial
   count ``N = log(1 - p) / log(1 - (1 - ε)^s)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = [
    "AttitudeFix",
    "CameraFixes",
    "FixStatus",
    "RansacConfig",
    "ransac_attitude",
    "ransac_trials",
    "ray_residuals",
    "solve_fixes",
    "svd_attitude",
]


class FixStatus(IntEnum):
    """Outcome of one camera attitude fix."""

    OK = 0
    TOO_FEW_RAYS = 1  # fewer than three rays
    DEGENERATE = 2  # the rays (or every sample / the inliers) are parallel: attitude undetermined
    NO_CONSENSUS = 3  # no sample gathered three inliers

    def __str__(self) -> str:
        return self.name.lower()


def ransac_trials(outlier_fraction: float, confidence: float = 0.999, sample: int = 3) -> int:
    """RANSAC trials that draw one outlier-free sample with probability ``confidence``
    (Fischler & Bolles 1981): ``ceil(log(1 - p) / log(1 - (1 - ε)^s))``."""
    if not 0 <= outlier_fraction < 1 or not 0 < confidence < 1:
        raise ValueError(
            f"outlier_fraction in [0, 1) and confidence in (0, 1) expected, got "
            f"{outlier_fraction}, {confidence}"
        )
    good = (1.0 - outlier_fraction) ** sample
    if good >= 1.0:
        return 1
    return math.ceil(math.log(1.0 - confidence) / math.log(1.0 - good))


@dataclass(frozen=True, slots=True)
class RansacConfig:
    """RANSAC around the SVD attitude.

    Attributes
    ----------
    threshold_rad : float
        A ray is an inlier when the angle between ``w_i`` and ``R v_i`` is below this. Default
        3e-3 rad: three times a ray noise of 1 mrad (about one pixel of a 60° camera 1024
        pixels wide, the noise the reproduction simulates). The paper states a "predetermined
        threshold" without its value.
    trials : int
        Most three-ray samples solved (default 52 = :func:`ransac_trials` for 50 % outliers at
        99.9 % confidence; the paper gives no count). All are drawn up front (the generator's
        state after a fix does not depend on the data).
    confidence : float
        Adaptive stop: once the best sample's inlier fraction ``1 - ε`` is known, solving stops
        after ``ransac_trials(ε, confidence)`` samples (at most ``trials``).
    chunk : int
        Samples solved per batched SVD between checks of the adaptive stop.
    degenerate_tol : float
        A sample (or an inlier set) is degenerate when the second singular value of its
        attitude profile matrix is below ``degenerate_tol`` times the first: the rays are
        (nearly) parallel and the rotation about them is undetermined.
    refine : int
        Refits on the inliers, each re-selecting the inliers with the refitted attitude.
    """

    threshold_rad: float = 5e-3
    trials: int = 52
    confidence: float = 0.999
    chunk: int = 16
    degenerate_tol: float = 1e-3
    refine: int = 2

    def __post_init__(self) -> None:
        if not self.threshold_rad > 0:
            raise ValueError(f"threshold_rad must be > 0, got {self.threshold_rad}")
        if self.trials < 1 or self.refine < 0:
            raise ValueError(
                f"trials >= 1 and refine >= 0 expected, got {self.trials}, {self.refine}"
            )
        if not 0 < self.degenerate_tol < 1:
            raise ValueError(f"degenerate_tol must be in (0, 1), got {self.degenerate_tol}")


@dataclass(frozen=True, slots=True, eq=False)
class AttitudeFix:
    """One camera attitude fix (arrays read-only).

    Attributes
    ----------
    quat : ndarray, shape (4,)
        Attitude, body -> reference, scalar-last; NaN unless ``status`` is ``ok``.
    inliers : ndarray of bool, shape (n,)
        Rays consistent with ``quat`` within the threshold.
    residuals_rad : ndarray, shape (n,)
        Angle between ``w_i`` and ``R v_i`` of every ray, rad (NaN without an attitude).
    status : FixStatus
    rms_rad : float
        RMS residual of the inliers, rad.
    sigma_rad : float
        Standard deviation of each attitude component implied by the inlier residuals:
        per-axis ray noise ``σ = rms / √2`` and ``σ · sqrt(3 / (2 n_in))`` for rays spread
        over all directions (``Σ (I - w wᵀ) ≈ (2 n / 3) I``), rad.
    n_inliers : int
    """

    quat: FloatArray
    inliers: BoolArray
    residuals_rad: FloatArray
    status: FixStatus
    rms_rad: float
    sigma_rad: float
    n_inliers: int

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _unit_rays(a: ArrayLike, name: str) -> FloatArray:
    r = np.asarray(a, dtype=np.float64)
    if r.ndim != 2 or r.shape[1] != 3:
        raise ValueError(f"{name}: expected shape (n, 3), got {r.shape}")
    norm = np.linalg.norm(r, axis=1)
    bad = ~np.isfinite(norm) | (norm == 0)
    if np.any(bad):
        raise ValueError(f"{name}: ray {int(np.flatnonzero(bad)[0])} is zero or not finite")
    return r / norm[:, None]


def svd_attitude(
    v_body: ArrayLike, w_ref: ArrayLike, weights: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Least-squares rotation ``R`` with ``w_i ≈ R v_i``, batched: ``R = A diag(1, 1, d) Bᵀ``.

    Parameters
    ----------
    v_body : (..., n, 3) unit rays in the body (camera) frame
    w_ref : (..., n, 3) unit rays in the reference frame
    weights : (..., n) or None
        Non-negative weights ``a_i`` (0 drops a ray).

    Returns
    -------
    R : (..., 3, 3) rotation matrices, body -> reference
    s : (..., 3) singular values of ``WᵀV`` (descending), for degeneracy checks

    Notes
    -----
    ``A Σ Bᵀ`` is the SVD of ``Σ a_i w_i v_iᵀ`` (the paper's ``WᵀV``). The paper's ``R = A Bᵀ``
    can be a reflection (``det = -1``) for noisy or coplanar rays; ``d = det(A) det(B)`` makes
    it the nearest proper rotation (Markley 1988).
    """
    v = np.asarray(v_body, dtype=np.float64)
    w = np.asarray(w_ref, dtype=np.float64)
    if weights is not None:
        w = w * np.asarray(weights, dtype=np.float64)[..., None]
    M = np.swapaxes(w, -1, -2) @ v  # Σ a_i w_i v_iᵀ
    A, s, Bt = np.linalg.svd(M)
    R = A @ Bt
    d = np.linalg.det(R)  # ±1: det(A) det(Bᵀ)
    R -= (1.0 - d)[..., None, None] * A[..., :, 2:3] * Bt[..., 2:3, :]
    return R, s


def ray_residuals(R: FloatArray, v_body: FloatArray, w_ref: FloatArray) -> FloatArray:
    """Angles between ``w_i`` and ``R v_i`` (rad); ``R (..., 3, 3)``, rays ``(n, 3)`` ->
    ``(..., n)``."""
    chord = np.einsum("...ij,nj->...ni", R, v_body) - w_ref
    half = 0.5 * np.sqrt(np.einsum("...i,...i->...", chord, chord))
    return np.asarray(2.0 * np.arcsin(np.minimum(half, 1.0)))  # unit rays: chord = 2 sin(angle/2)


def ransac_attitude(
    v_body: ArrayLike,
    w_ref: ArrayLike,
    rng: np.random.Generator,
    config: RansacConfig | None = None,
) -> AttitudeFix:
    """Camera attitude from target rays by SVD inside RANSAC (paper 6).

    Parameters
    ----------
    v_body : (n, 3) rays to the targets in the camera frame (normalised here)
    w_ref : (n, 3) rays from the camera position to the surveyed targets, reference frame
    rng : numpy.random.Generator
        Draws the three-ray samples.
    config : RansacConfig or None

    Returns
    -------
    AttitudeFix
        ``too_few_rays`` for ``n < 3``; ``degenerate`` when every sample and the inlier set
        have (nearly) parallel rays; ``no_consensus`` when no sample explains three rays.

    Notes
    -----
    Samples are solved ``config.chunk`` at a time (one batched SVD each) until the adaptive
    trial count is reached; the sample with the most inliers wins, ties broken by the smaller
    sum of inlier residuals. The winner is refitted
    on its inliers (``config.refine`` times, re-selecting the inliers each time). Rays of
    targets on a line are coplanar, not parallel, unless the camera is on that line too: two
    non-parallel rays fix the attitude, so only parallel rays are degenerate.
    """
    cfg = RansacConfig() if config is None else config
    v = _unit_rays(v_body, "v_body")
    w = _unit_rays(w_ref, "w_ref")
    if v.shape != w.shape:
        raise ValueError(f"v_body and w_ref must have the same shape, got {v.shape}, {w.shape}")
    n = v.shape[0]
    if n < 3:
        return _failed(n, FixStatus.TOO_FEW_RAYS)
    idx = np.argpartition(rng.random((cfg.trials, n)), 2, axis=1)[:, :3]
    best_score, Rb, inliers, any_usable = -1.0, np.eye(3), np.zeros(n, bool), False
    done, needed = 0, cfg.trials
    while done < needed:
        R, s = svd_attitude(v[idx[done : done + cfg.chunk]], w[idx[done : done + cfg.chunk]])
        done += R.shape[0]
        usable = s[:, 1] > cfg.degenerate_tol * s[:, 0]
        if not np.any(usable):
            continue
        any_usable = True
        res = ray_residuals(R[usable], v, w)
        inl = res < cfg.threshold_rad
        count = inl.sum(axis=1)
        # most inliers, then the smallest sum of inlier residuals
        score = count - np.where(inl, res, 0.0).sum(axis=1) / (n * cfg.threshold_rad + 1.0)
        b = int(np.argmax(score))
        if score[b] > best_score:
            best_score, Rb, inliers = float(score[b]), R[usable][b], inl[b]
            if inliers.sum() >= 3:  # adaptive trial count (Hartley & Zisserman, alg. 4.5)
                needed = min(cfg.trials, ransac_trials(1.0 - inliers.sum() / n, cfg.confidence))
    if not any_usable:
        return _failed(n, FixStatus.DEGENERATE)
    if inliers.sum() < 3:
        return _failed(n, FixStatus.NO_CONSENSUS)
    for _ in range(cfg.refine):
        Rf, sf = svd_attitude(v[inliers], w[inliers])
        if not sf[1] > cfg.degenerate_tol * sf[0]:
            return _failed(n, FixStatus.DEGENERATE)
        new = ray_residuals(Rf, v, w) < cfg.threshold_rad
        Rb = Rf
        if np.array_equal(new, inliers) or new.sum() < 3:
            break
        inliers = new
    residuals = ray_residuals(Rb, v, w)
    n_in = int(inliers.sum())
    rms = float(np.sqrt(np.mean(residuals[inliers] ** 2)))
    quat = _matrix_to_quat(Rb)
    return AttitudeFix(
        quat, inliers, residuals, FixStatus.OK, rms, rms * math.sqrt(0.75 / n_in), n_in
    )


def _matrix_to_quat(R: FloatArray) -> FloatArray:
    """Scalar-last unit quaternion of a proper rotation matrix (Shepperd's method: the largest
    of ``w², x², y², z²`` taken from the diagonal, the rest from off-diagonal sums). The same
    as ``Rotation.from_matrix(R).as_quat()`` up to sign, at a fraction of its cost for one
    matrix; the tests hold it to scipy."""
    d = (R[0, 0], R[1, 1], R[2, 2])
    tr = d[0] + d[1] + d[2]
    k = int(np.argmax((d[0], d[1], d[2], tr)))
    if k == 3:
        w = 0.5 * math.sqrt(max(1.0 + tr, 0.0))
        f = 0.25 / w
        q = ((R[2, 1] - R[1, 2]) * f, (R[0, 2] - R[2, 0]) * f, (R[1, 0] - R[0, 1]) * f, w)
    else:
        i, j, m = k, (k + 1) % 3, (k + 2) % 3
        c = [0.0, 0.0, 0.0]
        c[i] = 0.5 * math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[m, m], 0.0))
        f = 0.25 / c[i]
        c[j] = (R[j, i] + R[i, j]) * f
        c[m] = (R[m, i] + R[i, m]) * f
        q = (c[0], c[1], c[2], (R[m, j] - R[j, m]) * f)
    out = np.array(q, dtype=np.float64)
    return out / np.linalg.norm(out) * (1.0 if out[3] >= 0 else -1.0)


def _failed(n: int, status: FixStatus) -> AttitudeFix:
    return AttitudeFix(
        np.full(4, np.nan), np.zeros(n, bool), np.full(n, np.nan), status, math.nan, math.nan, 0
    )


@dataclass(frozen=True, slots=True, eq=False)
class CameraFixes:
    """Attitude fixes of a sequence of images (fixed shapes; arrays read-only).

    Attributes
    ----------
    quat : (m, 4) attitudes, body -> reference, scalar-last; NaN where ``status`` is not ok
    status : (m,) int8 :class:`FixStatus` values
    sigma_rad : (m,) per-axis attitude standard deviation (:class:`AttitudeFix`), rad
    n_rays : (m,) rays present in each image
    inliers : (m, n_targets) bool
    residuals_rad : (m, n_targets) ray residuals (NaN for absent rays)
    """

    quat: FloatArray
    status: npt.NDArray[np.int8]
    sigma_rad: FloatArray
    n_rays: IntArray
    inliers: BoolArray
    residuals_rad: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def ok(self) -> BoolArray:
        """Images with an attitude."""
        return np.asarray(self.status == FixStatus.OK)

    def status_counts(self) -> dict[str, int]:
        """Images per status name."""
        return {str(s): int(np.count_nonzero(self.status == s)) for s in FixStatus}


def solve_fixes(
    v_body: ArrayLike,
    w_ref: ArrayLike,
    visible: ArrayLike,
    rng: np.random.Generator,
    config: RansacConfig | None = None,
    *,
    min_rays: int = 3,
) -> CameraFixes:
    """:func:`ransac_attitude` for every image of a sequence.

    Parameters
    ----------
    v_body : (m, n, 3) rays per image, camera frame (absent rays may hold anything)
    w_ref : (n, 3) or (m, n, 3) reference rays to the targets
    visible : (m, n) bool, rays present
    rng : numpy.random.Generator
    config : RansacConfig or None
    min_rays : int
        Images with fewer rays are ``too_few_rays`` (paper: six or more targets).
    """
    v = np.asarray(v_body, dtype=np.float64)
    vis = np.asarray(visible, dtype=bool)
    m, n = vis.shape
    w = np.broadcast_to(np.asarray(w_ref, dtype=np.float64), (m, n, 3))
    if v.shape != (m, n, 3):
        raise ValueError(f"v_body: expected shape {(m, n, 3)}, got {v.shape}")
    quat = np.full((m, 4), np.nan)
    status = np.full(m, int(FixStatus.TOO_FEW_RAYS), np.int8)
    sigma = np.full(m, np.nan)
    inliers = np.zeros((m, n), bool)
    residuals = np.full((m, n), np.nan)
    n_rays = vis.sum(axis=1).astype(np.int64)
    for i in range(m):
        if n_rays[i] < max(3, min_rays):
            continue
        sel = np.flatnonzero(vis[i])
        fix = ransac_attitude(v[i, sel], w[i, sel], rng, config)
        status[i] = int(fix.status)
        if fix.status == FixStatus.OK:
            quat[i] = fix.quat
            sigma[i] = fix.sigma_rad
            inliers[i, sel] = fix.inliers
            residuals[i, sel] = fix.residuals_rad
    return CameraFixes(quat, status, sigma, n_rays, inliers, residuals)
