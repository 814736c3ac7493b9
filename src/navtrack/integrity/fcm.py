"""RAIM by fuzzy clustering (method 2): QR parity matrix, full design matrix, fuzzy c-means.

Gu et al. (2019) identify several simultaneous pseudorange faults by clustering the columns of
the *full design matrix* ``F = [e_1 T_1, ..., e_n T_n, t]`` (:func:`full_design_matrix`):
``T`` is the ``(n-u) x n`` QR parity matrix of the geometry (``T B = 0``, ``T T^T = I``,
:func:`parity_matrix`), ``e`` the (negative) residuals and ``t = T e = sum_i e_i T_i`` the
parity vector. A faulty measurement's column ``e_i T_i`` is large and close to ``t``, so it
falls into the class of ``t``. :func:`fuzzy_cmeans` is the clustering (three classes: healthy,
suspect, gross error; Mahalanobis distance; initial centres at the maximum, minimum and middle
sample), :func:`gross_error_columns` the paper's rule naming the faulty columns, and
:func:`hierarchical_classes` the "hard" clustering it is compared with.

References
----------
S. Gu, J. Bei, C. Shi, Y. Dang, Z. Zheng, C. Cui, "RAIM algorithm based on fuzzy clustering
analysis", Computer Modeling in Engineering & Sciences 2019 (``shared/papers/2_raim_fuzzy_
clustering.txt``): sections 2 (FCM, eqs. 1-9), 3 (full design matrix, eqs. 18-31), 4 (steps),
5 (numeric example). J. C. Bezdek, *Pattern Recognition with Fuzzy Objective Function
Algorithms*, Plenum 1981 (FCM updates). T. J. Ross, *Fuzzy Logic with Engineering
Applications*, 3rd ed., 2010, eqs. 10.28-10.35 (the iteration scikit-fuzzy's ``cmeans`` runs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = [
    "FcmResult",
    "fcm_initial_centres",
    "full_design_matrix",
    "fuzzy_cmeans",
    "gross_error_columns",
    "hierarchical_classes",
    "mahalanobis_whitening",
    "parity_matrix",
]

_EPS = np.finfo(np.float64).eps


def parity_matrix(design: ArrayLike) -> FloatArray:
    """QR parity matrix ``T`` of a design matrix: ``T B = 0``, ``T T^T = I``.

    Parameters
    ----------
    design : array_like, shape (..., n, u)
        Design (geometry) matrix ``B`` of full column rank ``u < n`` (weighted, ``W^1/2 B``,
        for weighted least squares).

    Returns
    -------
    T : ndarray, shape (..., n-u, n)
        The last ``n-u`` columns of ``Q`` of the complete QR decomposition ``B = Q S``,
        transposed (the paper's ``Q_y``, eq. 28).
    """
    b = np.asarray(design, dtype=float)
    if b.ndim < 2 or b.shape[-2] <= b.shape[-1]:
        raise ValueError(f"design: expected shape (..., n, u) with n > u, got {b.shape}")
    q, _ = np.linalg.qr(b, mode="complete")
    return np.swapaxes(q[..., :, b.shape[-1] :], -1, -2)


def full_design_matrix(parity: ArrayLike, residuals: ArrayLike) -> FloatArray:
    """The full design matrix ``F = [e_1 T_1, ..., e_n T_n, t]`` (paper eq. 26).

    Parameters
    ----------
    parity : array_like, shape (..., n-u, n)
        Parity matrix ``T`` (:func:`parity_matrix`).
    residuals : array_like, shape (..., n)
        Residuals ``e`` (the paper's negative residuals; the sign does not change the classes).

    Returns
    -------
    F : ndarray, shape (..., n-u, n+1)
        Column ``i < n`` is ``e_i T_i``; the last column is the parity vector ``t = T e``.
    """
    t_mat = np.asarray(parity, dtype=float)
    e = np.asarray(residuals, dtype=float)
    if t_mat.ndim < 2 or e.shape[-1] != t_mat.shape[-1]:
        raise ValueError(f"parity, residuals: shapes {t_mat.shape} and {e.shape} do not match")
    if not np.all(np.isfinite(e)):
        raise ValueError("residuals: need finite values")
    cols = t_mat * e[..., None, :]
    return np.concatenate([cols, cols.sum(axis=-1, keepdims=True)], axis=-1)


def mahalanobis_whitening(samples: ArrayLike, cov: ArrayLike | None = None) -> FloatArray:
    """Samples mapped so that Euclidean distances between them are Mahalanobis distances.

    Parameters
    ----------
    samples : array_like, shape (N, q)
        ``N`` samples of ``q`` features (for RAIM: the ``n+1`` columns of the full design
        matrix, transposed).
    cov : array_like, shape (q, q), optional
        Covariance of the samples' distribution; default the sample covariance.

    Returns
    -------
    ndarray, shape (N, q)
        ``x C^-1/2`` (symmetric root through the eigen-decomposition, pseudo-inverse for a
        rank-deficient ``C``), so that ``|C^-1/2 (x - y)|^2 = (x - y)^T C^+ (x - y)``.

    Notes
    -----
    In RAIM the residuals are whitened (``W^1/2 v``) and ``T`` has orthonormal rows, so the
    fault-free covariance of a parity vector is ``T (I - H) T^T = I``: the Mahalanobis distance
    of the fault-free model is the Euclidean one. That reading reproduces all classes of the
    paper's example (section 5); the sample covariance of the ``n+1`` columns does not (it is
    dominated by the faulty columns themselves and masks them), see ``docs/integrity.md``.
    """
    x = np.asarray(samples, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2:
        raise ValueError(f"samples: expected shape (N >= 2, q), got {x.shape}")
    c = np.atleast_2d(np.cov(x, rowvar=False)) if cov is None else np.asarray(cov, dtype=float)
    if c.shape != (x.shape[1], x.shape[1]):
        raise ValueError(f"cov: expected shape {(x.shape[1], x.shape[1])}, got {c.shape}")
    lam, vec = np.linalg.eigh(c)
    keep = lam > lam.max(initial=0.0) * 1e-12
    inv_sqrt = np.where(keep, 1.0 / np.sqrt(np.where(keep, lam, 1.0)), 0.0)
    return np.asarray(((x @ vec) * inv_sqrt) @ vec.T, dtype=np.float64)


def fcm_initial_centres(samples: ArrayLike, valid: ArrayLike | None = None) -> IntArray:
    """Indices of the samples the paper starts the three centres at: the maximum, the minimum
    and the middle (median) sample by their norm.

    Parameters
    ----------
    samples : array_like, shape (..., N, q)
    valid : array_like of bool, shape (..., N), optional
        Samples that exist (padding of a batch is False).

    Returns
    -------
    ndarray of int, shape (..., 3)

    Notes
    -----
    The paper says only "the maximum, minimum and intermediate values are selected as cluster
    centers"; the samples are vectors, so they are ranked here by their Euclidean norm in the
    space they are clustered in (whitened: the Mahalanobis norm).
    """
    x = np.asarray(samples, dtype=float)
    ok = np.ones(x.shape[:-1], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    norm = np.where(ok, np.linalg.norm(x, axis=-1), np.inf)
    order = np.argsort(norm, axis=-1, kind="stable")
    n_ok = ok.sum(axis=-1, keepdims=True)
    top = np.take_along_axis(order, n_ok - 1, axis=-1)
    mid = np.take_along_axis(order, (n_ok - 1) // 2, axis=-1)
    return np.concatenate([top, order[..., :1], mid], axis=-1).astype(np.int64)


@dataclass(frozen=True, slots=True, eq=False)
class FcmResult:
    """Outcome of :func:`fuzzy_cmeans` (leading batch axes ``...`` of the samples).

    Attributes
    ----------
    u : ndarray, shape (..., c, N)
        Memberships, columns sum to 1 (0 for padding samples).
    u0 : ndarray, shape (..., c, N)
        Memberships from the initial centres (the start of the iteration).
    centres : ndarray, shape (..., c, q)
        Class centres (in the clustered, whitened space).
    classes : ndarray of int, shape (..., N)
        Class of largest membership per sample (-1 for padding).
    iterations : ndarray of int, shape (...)
    converged : ndarray of bool, shape (...)
        ``|u - u_prev| < tol`` reached within ``max_iter``.
    """

    u: FloatArray
    u0: FloatArray
    centres: FloatArray
    classes: IntArray
    iterations: IntArray
    converged: BoolArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _memberships(
    x: FloatArray, x2: FloatArray, centres: FloatArray, m: float, valid: FloatArray
) -> FloatArray:
    """FCM membership update (paper eq. 8): ``u_ik = 1 / sum_j (d_ik / d_jk)^(2/(m-1))``,
    distances floored at machine epsilon (as scikit-fuzzy)."""
    d2 = x2[..., None, :] - 2.0 * (centres @ np.swapaxes(x, -1, -2))
    d2 += np.sum(centres * centres, axis=-1)[..., None]
    np.maximum(d2, _EPS * _EPS, out=d2)
    p = 1.0 / d2 if m == 2.0 else d2 ** (-1.0 / (m - 1.0))
    p *= valid[..., None, :]
    return np.asarray(p / np.maximum(p.sum(axis=-2, keepdims=True), 1e-300))


def fuzzy_cmeans(
    samples: ArrayLike,
    c: int = 3,
    m: float = 2.0,
    *,
    valid: ArrayLike | None = None,
    init_centres: IntArray | None = None,
    tol: float = 1e-6,
    max_iter: int = 100,
    stop: str = "memberships",
) -> FcmResult:
    """Fuzzy c-means clustering (paper eqs. 1-9) from given initial centres, batched.

    Parameters
    ----------
    samples : array_like, shape (..., N, q)
        Samples to cluster (leading axes: independent problems, e.g. epochs), Euclidean metric
        (whiten with :func:`mahalanobis_whitening` for the paper's Mahalanobis distance).
    c : int
        Number of classes (paper: 3), ``2 <= c <= N``.
    m : float
        Weighting exponent, ``m > 1`` (paper: not given; 2 is Bezdek's common choice).
    valid : array_like of bool, shape (..., N), optional
        Samples that exist: padding (False) takes no part (zero-padded features are harmless).
    init_centres : ndarray of int, shape (..., c), optional
        Samples the centres start at (default: :func:`fcm_initial_centres` for ``c = 3``,
        else the ``c`` samples of largest norm).
    tol : float
        A problem stops when the Frobenius norm of its change is below ``tol``.
    max_iter : int
    stop : {"memberships", "centres"}
        What ``tol`` measures: the change of the membership matrix (Bezdek, scikit-fuzzy) or
        of the cluster centres (the paper's rule, section 3.2).

    Returns
    -------
    FcmResult

    Notes
    -----
    The iteration is Ross's (scikit-fuzzy ``cmeans``): memberships from the initial centres
    ("according to the distance as the initial membership coefficient", paper 5.2.2), then
    repeatedly centres ``c_i = sum_k u_ik^m x_k / sum_k u_ik^m`` and memberships from the
    distances, memberships and distances floored at machine epsilon. Problems of a batch
    stop independently (a converged problem is no longer updated), so a batch gives what each
    problem gives alone.
    """
    x = np.asarray(samples, dtype=float)
    ok, start = _checked_start(x, c, m, valid, init_centres, stop)
    w = ok.astype(float)
    x2 = np.sum(x * x, axis=-1)
    centres = np.take_along_axis(x, start[..., None], axis=-2)
    u0 = _memberships(x, x2, centres, m, w)
    u = np.maximum(u0, _EPS) * w[..., None, :]
    batch = x.shape[:-2]
    # flatten the batch axes; work on the problems still iterating only
    n_s, q = x.shape[-2:]
    xf, x2f, wf = x.reshape(-1, n_s, q), x2.reshape(-1, n_s), w.reshape(-1, n_s)
    uf = np.array(u.reshape(-1, c, n_s))
    cf = np.array(centres.reshape(-1, c, q))
    iterations, act = _iterate(xf, x2f, wf, uf, cf, m, tol, max_iter, stop)
    converged = np.ones(xf.shape[0], dtype=bool)
    converged[act] = False
    u = uf.reshape(u.shape)
    centres = cf.reshape(centres.shape)
    active = ~converged.reshape(batch)
    classes = np.where(ok, np.argmax(u, axis=-2), -1).astype(np.int64)
    return FcmResult(
        u=u,
        u0=u0,
        centres=centres,
        classes=classes,
        iterations=iterations.reshape(batch),
        converged=~active,
    )


def _checked_start(
    x: FloatArray,
    c: int,
    m: float,
    valid: ArrayLike | None,
    init_centres: IntArray | None,
    stop: str,
) -> tuple[BoolArray, IntArray]:
    """The checked arguments of :func:`fuzzy_cmeans`: the valid-sample mask and the samples
    the centres start at."""
    if x.ndim < 2:
        raise ValueError(f"samples: expected shape (..., N, q), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("samples: need finite values")
    ok = np.ones(x.shape[:-1], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    if ok.shape != x.shape[:-1]:
        raise ValueError(f"valid: expected shape {x.shape[:-1]}, got {ok.shape}")
    n_min = int(ok.sum(axis=-1).min(initial=x.shape[-2]))
    if not (isinstance(c, int | np.integer) and 2 <= c <= n_min):
        raise ValueError(f"c: expected an integer 2 <= c <= {n_min} (samples), got {c}")
    if not m > 1.0:
        raise ValueError(f"m: the weighting exponent must be > 1, got {m}")
    if stop not in ("memberships", "centres"):
        raise ValueError(f"stop: expected memberships or centres, got {stop!r}")
    if init_centres is None:
        if c == 3:
            init_centres = fcm_initial_centres(x, ok)
        else:
            norm = np.where(ok, np.linalg.norm(x, axis=-1), -np.inf)
            init_centres = np.argsort(-norm, axis=-1, kind="stable")[..., :c]
    start = np.asarray(init_centres, dtype=np.int64)
    if start.shape != (*x.shape[:-2], c):
        raise ValueError(f"init_centres: expected shape {(*x.shape[:-2], c)}, got {start.shape}")
    return ok, start


def _iterate(
    xs: FloatArray,
    x2s: FloatArray,
    ws: FloatArray,
    uf: FloatArray,
    cf: FloatArray,
    m: float,
    tol: float,
    max_iter: int,
    stop: str,
) -> tuple[IntArray, IntArray]:
    """The FCM iterations of flattened problems, updating memberships ``uf`` and centres
    ``cf`` in place; the iterations of each problem and those still not converged."""
    iterations = np.zeros(xs.shape[0], dtype=np.int64)
    act = np.arange(xs.shape[0])
    for _ in range(max_iter):
        if not act.size:
            break
        prev = uf[act]
        prev_c = cf[act]
        total = np.maximum(prev.sum(axis=-2, keepdims=True), 1e-300)
        um = (np.maximum(prev / total, _EPS) * ws[:, None, :]) ** m
        new_c = (um @ xs) / um.sum(axis=-1, keepdims=True)
        new_u = _memberships(xs, x2s, new_c, m, ws)
        cf[act], uf[act] = new_c, new_u
        iterations[act] += 1
        change = new_u - prev if stop == "memberships" else new_c - prev_c
        done = np.sqrt(np.sum(change**2, axis=(-2, -1))) < tol
        if done.any():
            act, xs, x2s, ws = act[~done], xs[~done], x2s[~done], ws[~done]
    return iterations, act


def gross_error_columns(classes: ArrayLike) -> BoolArray:
    """The paper's rule naming the faulty measurements from the classes of the columns of a
    full design matrix.

    Parameters
    ----------
    classes : array_like of int, shape (n+1,)
        Class of each column; the last column is the parity vector ``t``.

    Returns
    -------
    ndarray of bool, shape (n,)
        Measurements in the class of ``t`` (the gross-error class), and measurements alone in
        their class ("isolated data ... judged as gross error", paper 5.3.2), unless that
        single class holds more than half of the measurements.

    Notes
    -----
    A class of ``t`` holding most measurements means ``t`` is not dominated by a few columns
    (no identifiable gross error); then nothing is named, an outcome the paper does not
    discuss.
    """
    k = np.asarray(classes, dtype=np.int64)
    if k.ndim != 1 or k.size < 2 or k.min() < 0:
        raise ValueError(f"classes: expected shape (n+1,) of classes >= 0, n >= 1, got {k.shape}")
    sats, t_class = k[:-1], k[-1]
    counts = np.bincount(sats, minlength=int(k.max()) + 1)
    in_t = sats == t_class
    if in_t.sum() > sats.size // 2:
        in_t = np.zeros_like(in_t)
    alone = (counts[sats] == 1) & (sats != t_class) & (sats.size > 2)
    return np.asarray(in_t | alone)


def hierarchical_classes(
    samples: ArrayLike, n_classes: int = 2, method: str = "single"
) -> IntArray:
    """Hard (agglomerative) clustering of whitened samples, the paper's comparison (5.2.1).

    Parameters
    ----------
    samples : array_like, shape (N, q)
        Whitened samples (:func:`mahalanobis_whitening`), so Euclidean = Mahalanobis distance.
    n_classes : int
        Classes the dendrogram is cut into (paper: two, gross error and random error).
    method : str
        Linkage of :func:`scipy.cluster.hierarchy.linkage` (default ``single``, the default of
        MATLAB's ``linkage``; the paper names none).

    Returns
    -------
    ndarray of int, shape (N,)
        Class labels from 0.
    """
    # scipy.cluster: only this alternative to FCM needs it
    from scipy.cluster.hierarchy import fcluster, linkage

    x = np.asarray(samples, dtype=float)
    if n_classes < 2:
        raise ValueError(f"n_classes: expected >= 2, got {n_classes}")
    z = linkage(x, method=method, metric="euclidean")
    return np.asarray(fcluster(z, t=n_classes, criterion="maxclust") - 1, dtype=np.int64)
