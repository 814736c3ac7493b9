"""Receiver autonomous integrity monitoring over all epochs of an SPP estimate.

Everything works on the whitened least-squares problem of each epoch — ``g = W^1/2 B`` (rows of
the design matrix scaled by ``1/sigma``) and ``y = W^1/2 v`` (residuals in sigmas) — taken from
:class:`navtrack.gnss.spp.Estimate`, over fixed ``(epochs, satellites)`` shapes with the
``used`` mask:

* :func:`chi2_test`: residual test ``y^T y > chi2_{1-pfa}(dof)``, ``dof = n - 3 - clocks``;
* :func:`normalised_residuals`: Baarda's w-test per satellite (:mod:`navtrack.estimation.robust`);
* :func:`wraim_levels`: weighted-RAIM slopes and horizontal/vertical protection levels;
* :func:`subset_solutions`: linearised re-solutions without given satellites (the fault
  hypotheses of exclusion and solution separation), by downdating the normal matrix;
* :func:`solution_separation`: ARAIM-style tests and protection levels over all hypotheses
  of one and two faulty satellites;
* :func:`monitor`: the stage that replaces :func:`navtrack.gnss.spp.validate` — detection,
  exclusion (``loo``: RTKLIB-like leave-one-out; ``fde``: iterative exclusion of the largest
  normalised residual; ``ss``: solution separation; ``fcm``: fuzzy clustering, paper 2),
  re-estimation without the excluded satellites and protection levels after exclusion.

References
----------
T. Walter, P. Enge, "Weighted RAIM for precision approach", ION GPS 1995, 1995-2004 (slopes,
``p_bias``, HPL/VPL). R. G. Brown, "A baseline GPS RAIM scheme and a note on the equivalence
of three RAIM methods", Navigation 39(3), 1992 (parity space). M. Joerger, F.-C. Chan, B.
Pervan, "Solution separation versus residual-based RAIM", Navigation 61(4), 2014; WG-C ARAIM
Technical Subgroup, *Milestone 3 report*, 2016, Annex (ARAIM user algorithm: separation
thresholds ``K_fa sigma_ss``, protection levels ``T_k + K_md sigma_k``). W. Baarda 1968 (w-test).
RTKLIB 2.4.3 ``pntpos.c`` ``raim_fde`` (leave-one-out). Gu et al. 2019 (:mod:`.fcm`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import IntEnum
from functools import lru_cache
from statistics import NormalDist
from typing import TYPE_CHECKING, Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.estimation.robust import redundancy_numbers, w_test

if TYPE_CHECKING:
    from navtrack.gnss.spp import Estimate, Measurements, SppConfig
    from navtrack.integrity.ism import ErrorModel, Ism

__all__ = [
    "METHODS",
    "STATUS_NAMES",
    "IntegrityResult",
    "RaimConfig",
    "RaimStatus",
    "Separation",
    "Subsets",
    "chi2_test",
    "concatenate_integrity",
    "fcm_exclusion",
    "integrity_columns",
    "monitor",
    "normalised_residuals",
    "pair_hypotheses",
    "solution_separation",
    "subset_solutions",
    "variance_factor",
    "whitened",
    "wraim_levels",
]

RaimMethod = Literal["chi2", "loo", "fde", "ss", "fcm", "araim"]
METHODS: tuple[str, ...] = ("chi2", "loo", "fde", "ss", "fcm", "araim")


class RaimStatus(IntEnum):
    """Per-epoch integrity outcome (printed in lower case)."""

    OK = 0
    """Tested: consistent, nothing excluded."""
    EXCLUDED = 1
    """A fault was detected, satellites were excluded and the rest passed the test."""
    ALERT = 2
    """A fault was detected and not removed (``chi2``, or exclusion failed)."""
    UNAVAILABLE = 3
    """Too few satellites to detect (``n < 3 + clocks + 1``), or to exclude after a
    detection (``n < 3 + clocks + 2``), or no solution."""


STATUS_NAMES = tuple(s.name.lower() for s in RaimStatus)


@dataclass(frozen=True, slots=True)
class RaimConfig:
    """Options of :func:`monitor`.

    Attributes
    ----------
    method : {"chi2", "loo", "fde", "ss", "fcm", "araim"}
        Detection only; RTKLIB-like leave-one-out single exclusion; iterative exclusion of the
        largest normalised residual; solution separation with up to ``max_faults``
        simultaneous faults; fuzzy c-means identification (paper 2); the ARAIM MHSS user
        algorithm (:mod:`.araim`, its own allocations from the ISM: ``pfa``/``pmd`` unused).
    pfa : float
        False-alarm probability of the detection test per epoch (default 1e-3, RTKLIB's
        chi-square significance in ``valsol``).
    pmd : float
        Missed-detection probability of the protection levels (default 1e-3, Walter & Enge's
        WRAIM example).
    max_exclusions : int
        Satellites ``fde`` and ``fcm`` may exclude in total (``loo``: 1; ``ss``: ``max_faults``).
    max_faults : int
        Largest fault hypothesis of ``ss`` (1 or 2).
    fcm_m : float
        FCM weighting exponent (Bezdek's 2; the paper gives none).
    fcm_tol : float
    fcm_max_iter : int
    fcm_stop : {"memberships", "centres"}
        FCM stopping rule: change of the memberships (Bezdek) or of the cluster centres (the
        paper's, section 3.2), both below ``fcm_tol``.
    ism : Ism, optional
        Integrity support message and error model behind every protection level
        (:mod:`.ism`); default :func:`.ism.default_ism` (the ADD baseline).
    variance_factor : float, optional
        Scale ``s^2`` of the measurement variances of the SPP weighting (``sigma^2 s^2``);
        default: estimated from the block of epochs by :func:`variance_factor`. RTKLIB's
        receiver model is conservative: ``s^2`` is 0.04-0.24 on the shared files, and with
        ``s^2 = 1`` the test misses faults of 10-20 m.
    """

    method: str = "fde"
    pfa: float = 1e-3
    pmd: float = 1e-3
    max_exclusions: int = 3
    max_faults: int = 2
    fcm_m: float = 2.0
    fcm_tol: float = 1e-6
    fcm_max_iter: int = 100
    fcm_stop: str = "memberships"
    ism: Ism | None = None
    variance_factor: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method: expected one of {', '.join(METHODS)}, got {self.method!r}")
        for name in ("pfa", "pmd"):
            v = getattr(self, name)
            if not 0.0 < v < 0.5:
                raise ValueError(f"{name}: expected a probability in (0, 0.5), got {v}")
        if self.max_exclusions < 1:
            raise ValueError(f"max_exclusions: expected >= 1, got {self.max_exclusions}")
        if self.max_faults not in (1, 2):
            raise ValueError(f"max_faults: expected 1 or 2, got {self.max_faults}")
        if self.fcm_stop not in ("memberships", "centres"):
            raise ValueError(f"fcm_stop: expected memberships or centres, got {self.fcm_stop!r}")
        if not self.fcm_m > 1.0:
            raise ValueError(f"fcm_m: the weighting exponent must be > 1, got {self.fcm_m}")
        vf = self.variance_factor
        if vf is not None and not (math.isfinite(vf) and vf > 0.0):
            raise ValueError(f"variance_factor: expected a positive number, got {vf}")


@dataclass(frozen=True, slots=True, eq=False)
class IntegrityResult:
    """Integrity of every epoch (after exclusion).

    Attributes
    ----------
    method : str
    status : ndarray of int8, shape (E,)
        :class:`RaimStatus`.
    excluded : ndarray of bool, shape (E, S)
        Satellites excluded.
    detected : ndarray of bool, shape (E,)
        The first test (all satellites) failed.
    test_stat : ndarray, shape (E,)
        Statistic of the final test (after exclusion): ``chi2`` of the whitened residuals, for
        ``ss`` the largest separation in units of its threshold times the threshold 1 (so the
        test fails above ``threshold``); NaN where unavailable.
    threshold : ndarray, shape (E,)
        Its threshold (``chi2_{1-pfa}(dof)``; ``ss``: 1).
    hpl_m, vpl_m : ndarray, shape (E,)
        Horizontal and vertical protection levels of the final solution (m) on the error
        model of the ISM; NaN where unavailable, ``inf`` where a used satellite is outside
        the model (or, ``araim``, the integrity budget is exhausted).
    emt_m : ndarray, shape (E,)
        ``araim``: effective monitor threshold (m); NaN for the other methods.
    """

    method: str
    status: Int8Array
    excluded: BoolArray
    detected: BoolArray
    test_stat: FloatArray
    threshold: FloatArray
    hpl_m: FloatArray
    vpl_m: FloatArray
    emt_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def status_counts(self) -> dict[str, int]:
        """Epochs per status name (zeros included)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(RaimStatus))
        return {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}

    def availability(self, hal_m: float = 40.0, val_m: float = 35.0) -> dict[str, float]:
        """Fractions of all epochs whose integrity supports an operation: ``vertical``
        (status ``ok`` or ``excluded``, ``HPL <= hal_m`` and ``VPL <= val_m``; LPV-200 with
        the defaults) and ``horizontal`` (``HPL <= hal_m`` only)."""
        n = max(self.status.size, 1)
        usable = (self.status == RaimStatus.OK) | (self.status == RaimStatus.EXCLUDED)
        with np.errstate(invalid="ignore"):
            h = usable & (self.hpl_m <= hal_m)
            v = h & (self.vpl_m <= val_m)
        return {"vertical": float(v.sum() / n), "horizontal": float(h.sum() / n)}


def concatenate_integrity(parts: list[IntegrityResult]) -> IntegrityResult:
    """Join the integrity of consecutive epoch blocks (same satellites and method)."""
    if not parts:
        raise ValueError("parts: need at least one result")
    cat = {
        name: np.concatenate([getattr(p, name) for p in parts])
        for name in IntegrityResult.__dataclass_fields__
        if name != "method"
    }
    return IntegrityResult(method=parts[0].method, **cat)


# --------------------------------------------------------------------------- thresholds
@lru_cache(maxsize=1024)
def _chi2_threshold(pfa: float, dof: int) -> float:
    from navtrack.gnss.spp import chi2_quantile

    return chi2_quantile(1.0 - pfa, dof)


def _ncx2_cdf(x: float, k: int, lam: float) -> float:
    """CDF of the non-central chi-square distribution, the Poisson mixture
    ``sum_j e^(-lam/2) (lam/2)^j / j! P(chi2_(k+2j) <= x)`` (Johnson, Kotz & Balakrishnan,
    *Continuous Univariate Distributions* vol. 2, 2nd ed., 29.2), with the central CDFs by the
    recursion ``P_(k+2j+2) = P_(k+2j) - (x/2)^(k/2+j) e^(-x/2) / Gamma(k/2+j+1)``, summed until
    the Poisson weights are below 1e-17 past their mode. ``scipy.stats.ncx2.cdf`` is the test
    oracle."""
    from navtrack.gnss.spp import _chi2_cdf

    half, a, y = 0.5 * lam, 0.5 * k, 0.5 * x
    p_j = _chi2_cdf(x, k)
    log_y = math.log(y) if y > 0 else -math.inf
    log_half = math.log(half) if half > 0 else -math.inf
    total = 0.0
    j = 0
    while True:
        w = math.exp(-half + j * log_half - math.lgamma(j + 1.0)) if half > 0 else float(j == 0)
        total += w * p_j
        if j > half + 1.0 and w < 1e-17:  # the remaining weights fall faster than 1/2 each
            return total
        p_j -= math.exp((a + j) * log_y - y - math.lgamma(a + j + 1.0)) if y > 0 else 0.0
        p_j = max(p_j, 0.0)
        j += 1


@lru_cache(maxsize=1024)
def _p_bias(pfa: float, pmd: float, dof: int) -> float:
    """``sqrt(lambda)``: the non-centrality at which a chi-square test of ``dof`` degrees and
    false-alarm ``pfa`` misses with probability ``pmd`` (Walter & Enge 1995), by bisection."""
    thr = _chi2_threshold(pfa, dof)
    lo, hi = 0.0, 1.0
    while _ncx2_cdf(thr, dof, hi) > pmd:
        hi *= 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _ncx2_cdf(thr, dof, mid) > pmd:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-8 * hi:
            break
    return math.sqrt(0.5 * (lo + hi))


@lru_cache(maxsize=4096)
def _normal_quantile(p: float) -> float:
    return NormalDist().inv_cdf(p)


# --------------------------------------------------------------------------- kernels
def whitened(estimate: Estimate) -> tuple[FloatArray, FloatArray, BoolArray]:
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


def _n_params(g: FloatArray) -> IntArray:
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
    flat = dof.ravel()
    thr = np.array([_chi2_threshold(pfa, int(k)) if k > 0 else np.nan for k in flat])
    return stat, thr.reshape(dof.shape), dof.astype(np.int64)


def _safe_inverse(n: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Inverses of a stack of symmetric matrices; NaN and ``True`` in the mask where singular
    (``|det| <= 1e-12 prod(diag)``)."""
    d = np.einsum("...pp->...p", n)
    with np.errstate(all="ignore"):
        singular = ~(np.abs(np.linalg.det(n)) > 1e-12 * np.prod(np.abs(d), axis=-1))
    n = np.where(singular[..., None, None], np.eye(n.shape[-1]), n)
    inv = np.linalg.inv(n)
    return np.where(singular[..., None, None], np.nan, inv), singular


def _normal_inverse(g: FloatArray) -> FloatArray:
    """``(g^T g)^-1`` with zero rows/columns for parameters no measurement touches."""
    n = np.swapaxes(g, -1, -2) @ g  # matmul: einsum is slow on stacks of small matrices
    absent = np.einsum("...pp->...p", n) <= 0.0
    inv, _ = _safe_inverse(n + np.eye(n.shape[-1]) * absent[..., None, :])
    return inv * ~absent[..., None, :] * ~absent[..., :, None]


def _hat_diagonal(g: FloatArray, q: FloatArray) -> FloatArray:
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
    r = redundancy_numbers(_hat_diagonal(g, _normal_inverse(g)), 1.0)
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
    q = _normal_inverse(g)
    a = enu_rotation @ q[:, :3, :] @ np.swapaxes(g, -1, -2)
    r = redundancy_numbers(_hat_diagonal(g, q), 1.0)
    ok = used & (r > 1e-9)
    sr = np.sqrt(np.where(ok, r, 1.0))
    h = np.where(ok, np.hypot(a[:, 0], a[:, 1]) / sr, 0.0).max(axis=1, initial=0.0)
    v = np.where(ok, np.abs(a[:, 2]) / sr, 0.0).max(axis=1, initial=0.0)
    dof = used.sum(axis=1) - _n_params(g)
    pb = np.array([_p_bias(pfa, pmd, int(k)) if k > 0 else np.nan for k in dof])
    return h * pb, v * pb


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
    cov, singular = _safe_inverse(nk + np.eye(n_p) * absent[..., None, :])
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
    q0 = _normal_inverse(g)
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
            np.array([_normal_quantile(1.0 - config.pfa / (4.0 * h)) for h in n_h]),
            np.array([_normal_quantile(1.0 - config.pfa / (4.0 * h)) for h in n_h]),
            np.array([_normal_quantile(1.0 - config.pfa / (2.0 * h)) for h in n_h]),
        ],
        axis=-1,
    )
    thr = k_fa[:, None, :] * s_ss
    ratio = np.where(sub.valid, np.max(np.abs(d_enu) / thr, axis=-1), 0.0)
    k_md = _normal_quantile(1.0 - config.pmd)
    k_ff = _normal_quantile(1.0 - config.pmd / 2.0)
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
    from navtrack.integrity.fcm import full_design_matrix, fuzzy_cmeans, gross_error_columns
    from navtrack.integrity.fcm import parity_matrix as qr_parity

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


# --------------------------------------------------------------------------- bounded levels
def _model_spread(
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


def _gain_all(g: FloatArray, scale: FloatArray, rot: FloatArray) -> FloatArray:
    """East/north/up gains (m per m) of the weighted least squares of whitened ``g`` (rows
    ``scale_j B_j``): ``R (g^T g)^-1 g^T diag(scale)``, shape (B, 3, S)."""
    q = _normal_inverse(g)
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
    ``sigma_q, b_q`` from :func:`_model_spread`, ``sigma_h = sqrt(sigma_e^2 + sigma_n^2)``,
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
    sig, b = _model_spread(_gain_all(g, scale, rot), used, model)
    k_md = _normal_quantile(1.0 - pmd)
    k_ff = _normal_quantile(1.0 - pmd / 2.0)
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
    subset's gains under the integrity model (:func:`_model_spread`); ``HPL = sqrt(PL_e^2 +
    PL_n^2)``. Gains are formed ``block`` epochs at a time.

    Returns
    -------
    hpl_m, vpl_m : ndarray, shape (B,)
        NaN where the separation is unavailable.
    """
    sub = sep.subsets
    sig0, b0 = _model_spread(_gain_all(g, scale, rot), used, model)
    k_md = _normal_quantile(1.0 - pmd)
    k_ff = _normal_quantile(1.0 - pmd / 2.0)
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
        sig, b = _model_spread(gain, used[r], model_rows(model, r))
        pk = np.where(sub.valid[r][..., None], sep.threshold_m[r] + k_md * sig + b, 0.0)
        pl[r] = np.maximum(pl[r], pk.max(axis=1))
    ok = sep.available
    return np.where(ok, np.hypot(pl[:, 0], pl[:, 1]), np.nan), np.where(ok, pl[:, 2], np.nan)


def model_rows(model: ErrorModel, rows: slice | IntArray) -> ErrorModel:
    """The error model of some epochs."""
    from navtrack.integrity.ism import ErrorModel

    return ErrorModel(
        var_int_m2=model.var_int_m2[rows],
        var_acc_m2=model.var_acc_m2[rows],
        b_int_m=model.b_int_m[rows],
        b_acc_m=model.b_acc_m[rows],
        covered=model.covered,
    )


# --------------------------------------------------------------------------- the stage
def variance_factor(estimate: Estimate) -> float:
    """A-posteriori variance factor of the weighting model over a block of epochs.

    ``s^2 = median_e(chi2_e / chi2_0.5(dof_e))`` over the solved epochs with ``dof >= 1``: the
    median is the estimator's robustness (faulty epochs, fewer than half, do not inflate it);
    dividing by the median of each epoch's chi-square distribution makes it unbiased for a
    correct model (``s^2 = 1``). 1 where no epoch has redundancy.

    Parameters
    ----------
    estimate : Estimate

    Returns
    -------
    float
    """
    from navtrack.gnss.spp import SppStatus, chi2_quantile

    ok = (estimate.status == SppStatus.OK) & (estimate.dof >= 1) & np.isfinite(estimate.chi2)
    if not ok.any():
        return 1.0
    med = np.array([chi2_quantile(0.5, int(k)) for k in estimate.dof[ok]])
    s2 = float(np.median(estimate.chi2[ok] / med))
    return s2 if s2 > 0.0 else 1.0


def _test(
    est: Estimate, pfa: float, s2: float
) -> tuple[FloatArray, FloatArray, IntArray, FloatArray, FloatArray, BoolArray]:
    g, y, used = whitened(est)
    scale = 1.0 / math.sqrt(s2)
    g, y = g * scale, y * scale
    stat, thr, dof = chi2_test(y, used, _n_params(g), pfa)
    return stat, thr, dof, g, y, used


def monitor(
    meas: Measurements,
    estimate: Estimate,
    config: SppConfig,
    raim: RaimConfig,
) -> tuple[Estimate, Int8Array, IntegrityResult]:
    """Integrity monitoring of an estimate of all epochs: the stage that replaces
    :func:`navtrack.gnss.spp.validate` when RAIM is on.

    Parameters
    ----------
    meas : Measurements
    estimate : Estimate
        Of all measurement epochs (:func:`navtrack.gnss.spp.estimate_position`).
    config : SppConfig
        For the re-estimation and the GDOP limit (its ``chi2_alpha`` is replaced by
        ``raim.pfa``).
    raim : RaimConfig
        With ``variance_factor`` None, the factor is estimated from ``estimate``
        (:func:`variance_factor`).

    Returns
    -------
    estimate : Estimate
        With the epochs that excluded satellites re-estimated without them
        (:func:`navtrack.gnss.spp.merge_estimates`).
    status : ndarray of int8, shape (E,)
        :class:`navtrack.gnss.spp.SppStatus`: ``rejected_validity`` for ``alert`` epochs, the
        GDOP test as :func:`navtrack.gnss.spp.validate`.
    integrity : IntegrityResult
    """
    from navtrack.gnss.spp import SppStatus, estimate_position, merge_estimates, validate
    from navtrack.integrity.araim import araim_model
    from navtrack.integrity.ism import default_ism

    ism = raim.ism if raim.ism is not None else default_ism()
    if raim.method == "araim":
        return _monitor_araim(meas, estimate, config, ism)
    solved = estimate.status == SppStatus.OK
    s2 = variance_factor(estimate) if raim.variance_factor is None else raim.variance_factor
    stat, thr, dof, g, y, used = _test(estimate, raim.pfa, s2)
    avail = solved & (dof >= 1)
    detected = avail & (stat > thr)
    n_excl_max = {"chi2": 0, "loo": 1, "fde": raim.max_exclusions, "fcm": raim.max_exclusions}
    n_epochs, n_sats = used.shape
    excluded = np.zeros((n_epochs, n_sats), dtype=bool)
    est = estimate
    cannot = np.zeros(n_epochs, dtype=bool)  # detected with too few satellites to exclude

    def reestimate(rows: IntArray) -> None:
        nonlocal est
        if rows.size:
            sub = estimate_position(
                meas, config, epochs=est.epochs[rows], exclude=excluded[rows], x0_m=est.x[rows]
            )
            est = merge_estimates(est, sub)

    if raim.method == "ss":
        sep = solution_separation(g, y, used, est.enu_rotation, raim)
        detected = solved & sep.available & sep.detected
        avail = solved & sep.available
        rows = np.flatnonzero(detected)
        if rows.size:
            s = sep.subsets
            ok_k = s.valid[rows] & (s.chi2[rows] <= _threshold_array(raim.pfa, s.dof[rows]))
            size = (s.members[rows] >= 0).sum(axis=-1)
            # smallest consistent hypothesis, then smallest residual
            score = np.where(ok_k, size * 1e12 + s.chi2[rows], np.inf)
            best = np.argmin(score, axis=1)
            found = np.isfinite(score[np.arange(rows.size), best])
            mem = s.members[rows, best]
            for j in range(2):
                r_ok = found & (mem[:, j] >= 0)
                excluded[rows[r_ok], mem[r_ok, j]] = True
            cannot[rows[~found]] = True
            reestimate(rows[found])
    elif n_excl_max[raim.method]:
        fail = detected.copy()
        for _ in range(n_excl_max[raim.method]):
            n_used = used.sum(axis=1)
            can = fail & (n_used - _n_params(g) >= 2)
            cannot |= fail & ~can
            rows = np.flatnonzero(can)
            if not rows.size:
                break
            pick = _pick_exclusion(raim, g[rows], y[rows], used[rows])
            none = ~pick.any(axis=1)
            cannot[rows[none]] = True
            rows, pick = rows[~none], pick[~none]
            excluded[rows] |= pick
            reestimate(rows)
            stat, thr, dof, g, y, used = _test(est, raim.pfa, s2)
            fail = np.zeros(n_epochs, dtype=bool)
            fail[rows] = (dof[rows] >= 1) & (stat[rows] > thr[rows])
            if raim.method == "loo":
                break

    stat, thr, dof, g, y, used = _test(est, raim.pfa, s2)
    model = araim_model(meas, est, ism)
    scale = np.sqrt(np.where(used, est.weights, 0.0) / s2)
    rot = est.enu_rotation
    status = np.full(n_epochs, RaimStatus.UNAVAILABLE, dtype=np.int8)
    if raim.method == "ss":
        final_fail = sep.detected.copy()
        hpl, vpl = bounded_separation_levels(sep, g, used, scale, rot, model, raim.pmd)
        avail_ss = sep.available.copy()
        stat = np.where(sep.available, sep.ratio.max(axis=1, initial=0.0), np.nan)
        rows = np.flatnonzero(excluded.any(axis=1))
        if rows.size:  # after exclusion: the hypotheses of the remaining satellites
            sep_r = solution_separation(g[rows], y[rows], used[rows], est.enu_rotation[rows], raim)
            final_fail[rows], avail_ss[rows] = sep_r.detected, sep_r.available
            hpl[rows], vpl[rows] = bounded_separation_levels(
                sep_r,
                g[rows],
                used[rows],
                scale[rows],
                rot[rows],
                model_rows(model, rows),
                raim.pmd,
            )
            stat[rows] = np.where(sep_r.available, sep_r.ratio.max(axis=1, initial=0.0), np.nan)
        thr = np.where(avail_ss, 1.0, np.nan)
    else:
        final_fail = (dof >= 1) & (stat > thr)
        hpl, vpl = bounded_wraim_levels(g, used, scale, rot, model, raim.pfa, raim.pmd)
    any_excl = excluded.any(axis=1)
    status[avail & ~detected] = RaimStatus.OK
    status[avail & detected] = RaimStatus.ALERT
    status[avail & detected & any_excl & ~final_fail] = RaimStatus.EXCLUDED
    status[avail & detected & cannot & ~any_excl] = RaimStatus.UNAVAILABLE
    unavailable = status == RaimStatus.UNAVAILABLE
    spp_status = validate(est, replace(config, chi2_alpha=0.0))
    spp_status[(spp_status == SppStatus.OK) & (status == RaimStatus.ALERT)] = (
        SppStatus.REJECTED_VALIDITY
    )
    return (
        est,
        spp_status,
        IntegrityResult(
            method=raim.method,
            status=status,
            excluded=excluded,
            detected=detected,
            test_stat=np.where(unavailable, np.nan, stat),
            threshold=np.where(unavailable, np.nan, thr),
            hpl_m=np.where(unavailable | ~solved, np.nan, hpl),
            vpl_m=np.where(unavailable | ~solved, np.nan, vpl),
            emt_m=np.full(n_epochs, np.nan),
        ),
    )


def _monitor_araim(
    meas: Measurements, estimate: Estimate, config: SppConfig, ism: Ism
) -> tuple[Estimate, Int8Array, IntegrityResult]:
    """``monitor`` for ``araim``: MHSS on the ISM (:func:`.araim.araim`), the reported
    position the fault-free (or post-exclusion) solution with the integrity weights."""
    from navtrack.gnss.spp import SppStatus, validate
    from navtrack.integrity.araim import araim, araim_model

    solved = estimate.status == SppStatus.OK
    res = araim(estimate, meas.sats, araim_model(meas, estimate, ism), ism)
    used = estimate.used & ~res.excluded & res.in_model[None, :]
    v = np.nan_to_num(estimate.residuals_m) - (estimate.design @ res.dx[..., None])[..., 0]
    est = replace(
        estimate,
        x=estimate.x + res.dx,
        residuals_m=np.where(used, v, np.nan),
        used=used,
        design=estimate.design * used[..., None],
        weights=np.where(used, estimate.weights, 0.0),
    )
    avail = solved & res.available
    status = np.full(used.shape[0], RaimStatus.UNAVAILABLE, dtype=np.int8)
    any_excl = res.excluded.any(axis=1)
    status[avail & ~res.detected] = RaimStatus.OK
    status[avail & res.detected] = RaimStatus.ALERT
    status[avail & res.detected & any_excl & res.ok] = RaimStatus.EXCLUDED
    unavailable = status == RaimStatus.UNAVAILABLE
    spp_status = validate(est, replace(config, chi2_alpha=0.0))
    spp_status[(spp_status == SppStatus.OK) & (status == RaimStatus.ALERT)] = (
        SppStatus.REJECTED_VALIDITY
    )
    keep = ~unavailable
    return (
        est,
        spp_status,
        IntegrityResult(
            method="araim",
            status=status,
            excluded=res.excluded,
            detected=res.detected & solved,
            test_stat=np.where(keep, res.ratio, np.nan),
            threshold=np.where(keep, 1.0, np.nan),
            hpl_m=np.where(keep, res.hpl_m, np.nan),
            vpl_m=np.where(keep, res.vpl_m, np.nan),
            emt_m=np.where(keep, res.emt_m, np.nan),
        ),
    )


def _threshold_array(pfa: float, dof: IntArray) -> FloatArray:
    flat = np.asarray(dof).ravel()
    out = np.array([_chi2_threshold(pfa, int(k)) if k > 0 else np.nan for k in flat])
    return out.reshape(np.shape(dof))


def _pick_exclusion(raim: RaimConfig, g: FloatArray, y: FloatArray, used: BoolArray) -> BoolArray:
    """Satellites to exclude in one round of ``loo``, ``fde`` or ``fcm`` (epochs that failed)."""
    pick = np.zeros(used.shape, dtype=bool)
    rows = np.arange(used.shape[0])
    if raim.method == "fde":
        w = np.abs(normalised_residuals(g, y, used))
        w = np.where(np.isfinite(w), w, -1.0)
        j = np.argmax(w, axis=1)
        pick[rows, j] = w[rows, j] >= 0
    elif raim.method == "loo":
        members = pair_hypotheses(used, 1)
        sub = subset_solutions(g, y, used, members)
        ok_k = sub.valid & (sub.chi2 <= _threshold_array(raim.pfa, sub.dof))
        score = np.where(ok_k, sub.chi2, np.inf)
        best = np.argmin(score, axis=1)
        found = np.isfinite(score[rows, best])
        pick[rows[found], members[rows[found], best[found], 0]] = True
    else:
        pick = fcm_exclusion(g, y, used, raim)
        # never leave fewer than P + 1 satellites
        room = used.sum(axis=1) - _n_params(g) - 1
        pick &= (np.cumsum(pick, axis=1) <= room[:, None]) & (pick.sum(axis=1) <= room)[:, None]
    return pick


def integrity_columns(integrity: IntegrityResult, sats: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Solution-frame columns of an integrity result: ``raim_status`` (name), ``excluded``
    (space-separated satellite ids), ``hpl_m``, ``vpl_m``, ``test_stat``, ``threshold``,
    ``emt_m``."""
    names = np.array(STATUS_NAMES, dtype=object)[integrity.status.astype(np.int64)]
    ids = np.array(sats, dtype=object)
    excluded = np.array([" ".join(ids[row]) for row in integrity.excluded], dtype=object)
    return {
        "raim_status": names,
        "excluded": excluded,
        "hpl_m": integrity.hpl_m,
        "vpl_m": integrity.vpl_m,
        "test_stat": integrity.test_stat,
        "threshold": integrity.threshold,
        "emt_m": integrity.emt_m,
    }
