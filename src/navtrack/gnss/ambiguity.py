"""Integer ambiguity resolution: the LAMBDA method (decorrelation and search), ratio test,
partial fixing, and the conditional update of the other parameters on the fixed integers.

The float ambiguities ``a_hat`` with covariance ``Q`` are transformed by an integer,
unimodular matrix ``Z`` into ``z_hat = Z^T a_hat`` whose covariance ``Q_z = Z^T Q Z`` is nearly
diagonal (integer Gauss transformations and permutations of the ``L^T D L`` factors); the
integer least-squares problem ``min_z (z_hat - z)^T Q_z^-1 (z_hat - z)`` is then solved by a
depth-first search of the shrinking ellipsoid, enumerating each level around its conditional
estimate in zig-zag order.

The kernels are scalar recursions over at most a few tens of ambiguities, one source run two
ways: compiled by numba on NumPy arrays for problems of :data:`COMPILE_MIN_AMBIGUITIES` or more
when numba is installed (extra ``speed``; 20 ambiguities in well under a millisecond),
interpreted on Python lists otherwise (a fraction of a millisecond for the handful of a
single-system L1 rover, about 20 ms for 20 ambiguities).

References
----------
Teunissen, P.J.G. (1995). The least-squares ambiguity decorrelation adjustment: a method for
fast GPS integer ambiguity estimation. Journal of Geodesy 70, 65-82.
de Jonge, P., Tiberius, C. (1996). The LAMBDA method for integer ambiguity estimation:
implementation aspects. LGR-Series 12, Delft University of Technology (sections 3.3-3.5:
``L^T D L`` factorisation, reduction by integer Gauss transformations and permutations, search).
Teunissen, P.J.G. (1998). Success probability of integer GPS ambiguity rounding and
bootstrapping. Journal of Geodesy 72, 606-612 (bootstrapped success rate, eq. 7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._numba import HAVE_NUMBA, jit
from navtrack._typing import FloatArray, IntArray

__all__ = [
    "COMPILE_MIN_AMBIGUITIES",
    "HAVE_NUMBA",
    "AmbiguityConfig",
    "AmbiguityResult",
    "FixStatus",
    "bootstrap_success_rate",
    "condition_on_fix",
    "decorrelate",
    "integer_search",
    "ltdl",
    "resolve_ambiguities",
]


class FixStatus(IntEnum):
    """Outcome of :func:`resolve_ambiguities` (printed by lower-case name)."""

    FIXED = 0
    PARTIAL = 1
    RATIO_FAILED = 2
    TOO_FEW = 3


@dataclass(frozen=True, slots=True)
class AmbiguityConfig:
    """Options of :func:`resolve_ambiguities`.

    Attributes
    ----------
    ratio_threshold : float
        Validation: accept the best candidate when ``s2 / s1 >= ratio_threshold`` (squared
        norms of the second best and the best). 3.0 is RTKLIB 2.4.3's default ``thresar``.
    partial : bool
        When the full set fails the ratio test, fix the subset of the decorrelated
        ambiguities whose bootstrapped success rate reaches ``min_success_rate`` (the best
        determined ones, last in the conditioning order) and test that subset.
    min_success_rate : float
        Bootstrapped success rate the partial subset must reach (Teunissen 1998; 0.999 is a
        common choice in the partial ambiguity resolution literature).
    min_fixed : int
        Fewest ambiguities to fix (fewer: status ``too_few``).
    """

    ratio_threshold: float = 3.0
    partial: bool = False
    min_success_rate: float = 0.999
    min_fixed: int = 2

    def __post_init__(self) -> None:
        if not self.ratio_threshold >= 1.0:
            raise ValueError(f"ratio_threshold: expected >= 1, got {self.ratio_threshold}")
        if not 0.0 < self.min_success_rate < 1.0:
            raise ValueError(f"min_success_rate: expected in (0, 1), got {self.min_success_rate}")
        if self.min_fixed < 1:
            raise ValueError(f"min_fixed: expected >= 1, got {self.min_fixed}")


@dataclass(frozen=True, slots=True, eq=False)
class AmbiguityResult:
    """Integer fix of a float ambiguity vector.

    Attributes
    ----------
    status : FixStatus
    ratio : float
        ``s2 / s1`` of the tested set (NaN when no search ran; inf when ``s1 = 0``).
    n_fixed : int
        Fixed integer combinations ``k`` (``n`` for a full fix, 0 when nothing is fixed).
    Z : ndarray of int, shape (k, n)
        The fixed integer combinations ``z = Z a`` of the ambiguities (rows of the
        decorrelating transformation; the identity for a full fix).
    z : ndarray of int, shape (k,)
        Their integer values.
    a_fixed : ndarray, shape (n,)
        Integer ambiguities of a full fix; NaN unless ``status`` is ``fixed``.
    """

    status: FixStatus
    ratio: float
    n_fixed: int
    Z: IntArray
    z: IntArray
    a_fixed: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def accepted(self) -> bool:
        """A full or partial fix passed the ratio test."""
        return self.status in (FixStatus.FIXED, FixStatus.PARTIAL)


# The kernels index ``M[i][j]`` and write into buffers the caller allocates, so that the same
# source runs compiled on NumPy arrays (numba) and interpreted on Python lists (whose element
# access is several times faster than NumPy's from Python).


def _ltdl_py(q: Any, L: Any, D: Any) -> bool:
    n = len(D)
    for i in range(n - 1, -1, -1):
        d = q[i][i]
        if not d > 0.0:
            return False
        D[i] = d
        s = math.sqrt(d)
        Li = L[i]
        qi = q[i]
        for j in range(i + 1):
            Li[j] = qi[j] / s
        for j in range(i):
            lij = Li[j]
            qj = q[j]
            for k in range(j + 1):
                qj[k] -= Li[k] * lij
        lii = Li[i]
        for j in range(i + 1):
            Li[j] /= lii
    return True


def _reduce_py(L: Any, D: Any, Zt: Any) -> None:
    """Reduction on ``L``, ``D`` and the transpose ``Zt`` of ``Z`` (row ``j`` is column ``j``)."""
    n = len(D)
    j = n - 2
    sw = n - 1  # columns j <= sw were touched by a permutation since their Gauss step
    while j >= 0:
        if j <= sw:
            for i in range(j + 1, n):
                mu = math.floor(L[i][j] + 0.5)
                if mu != 0:
                    for k in range(i, n):
                        L[k][j] -= mu * L[k][i]
                    zi = Zt[i]
                    zj = Zt[j]
                    for k in range(n):
                        zj[k] -= mu * zi[k]
        delta = D[j] + L[j + 1][j] ** 2 * D[j + 1]
        if delta + 1e-6 < D[j + 1]:
            eta = D[j] / delta
            lam = D[j + 1] * L[j + 1][j] / delta
            D[j] = eta * D[j + 1]
            D[j + 1] = delta
            Lj = L[j]
            Lj1 = L[j + 1]
            for k in range(j):
                a0 = Lj[k]
                a1 = Lj1[k]
                Lj[k] = -Lj1[j] * a0 + a1
                Lj1[k] = eta * a0 + lam * a1
            Lj1[j] = lam
            for k in range(j + 2, n):
                t = L[k][j]
                L[k][j] = L[k][j + 1]
                L[k][j + 1] = t
            zj = Zt[j]
            zj1 = Zt[j + 1]
            for k in range(n):
                t = zj[k]
                zj[k] = zj1[k]
                zj1[k] = t
            sw = j
            j = n - 2
        else:
            j -= 1


def _search_py(
    a: Any, L: Any, D: Any, zc: Any, z: Any, step: Any, dist: Any, cands: Any, sq: Any
) -> None:
    """Search into ``cands (m, n)`` and ``sq (m,)`` (unsorted; ``sq`` starts at infinity);
    ``zc``, ``z``, ``step`` (n) and ``dist`` (n + 1) are work buffers."""
    n = len(a)
    m = len(sq)
    found = 0
    max_dist = math.inf
    k = n - 1
    zc[k] = a[k]
    z[k] = math.floor(a[k] + 0.5)
    y = zc[k] - z[k]
    step[k] = 1.0 if y > 0 else -1.0
    while True:
        new = dist[k] + y * y / D[k]
        if new < max_dist:
            if k > 0:
                k -= 1
                dist[k] = new
                s = a[k]
                for j in range(k + 1, n):
                    s -= L[j][k] * (zc[j] - z[j])
                zc[k] = s
                z[k] = math.floor(s + 0.5)
                y = s - z[k]
                step[k] = 1.0 if y > 0 else -1.0
                continue
            worst = 0
            for i in range(m):
                if sq[i] > sq[worst]:
                    worst = i
            sq[worst] = new
            cw = cands[worst]
            for i in range(n):
                cw[i] = z[i]
            found += 1
            if found >= m:
                max_dist = sq[0]
                for i in range(m):
                    if sq[i] > max_dist:
                        max_dist = sq[i]
            z[0] += step[0]
            y = zc[0] - z[0]
            step[0] = -step[0] - (1.0 if step[0] > 0 else -1.0)
        else:
            if k == n - 1:
                break
            k += 1
            z[k] += step[k]
            y = zc[k] - z[k]
            step[k] = -step[k] - (1.0 if step[k] > 0 else -1.0)


def _buffers(compiled: bool, *shapes: tuple[int, ...], fill: float = 0.0) -> list[Any]:
    """Zero (or ``fill``) buffers: NumPy arrays for the compiled kernels, lists otherwise."""
    if compiled:
        return [np.full(shape, fill) for shape in shapes]
    out: list[Any] = []
    for shape in shapes:
        if len(shape) == 1:
            out.append([fill] * shape[0])
        else:
            out.append([[fill] * shape[1] for _ in range(shape[0])])
    return out


_COMPILED: dict[str, Any] = {}


COMPILE_MIN_AMBIGUITIES = 10
"""Problems of this many ambiguities or more run compiled (numba is imported on the first such
problem, about a second); smaller ones run interpreted (well under a millisecond each)."""


def _kernel(name: str, n: int) -> tuple[Any, bool]:
    """The kernel ``name`` (``ltdl``, ``reduce``, ``search``) for ``n`` ambiguities and whether
    it is compiled."""
    py = {"ltdl": _ltdl_py, "reduce": _reduce_py, "search": _search_py}[name]
    if not HAVE_NUMBA or n < COMPILE_MIN_AMBIGUITIES:
        return py, False
    if name not in _COMPILED:
        _COMPILED[name] = jit(py) or py
    return _COMPILED[name], _COMPILED[name] is not py


def ltdl(Q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``Q = L^T D L`` with ``L`` unit lower triangular (de Jonge & Tiberius 1996, sec. 3.3).

    Parameters
    ----------
    Q : ndarray, shape (n, n)
        Symmetric positive definite covariance (cycles^2).

    Returns
    -------
    L : ndarray, shape (n, n)
        Unit lower triangular factor.
    D : ndarray, shape (n,)
        ``D[i]`` is the variance of ambiguity ``i`` conditioned on ``i+1 .. n-1``.

    Raises
    ------
    ValueError
        ``Q`` is not square or not positive definite.
    """
    A = np.ascontiguousarray(Q, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"Q: expected a square matrix, got shape {A.shape}")
    n = A.shape[0]
    fn, compiled = _kernel("ltdl", n)
    q = A.copy() if compiled else A.tolist()
    L, D = _buffers(compiled, (n, n), (n,))
    if not fn(q, L, D):
        raise ValueError("Q: not positive definite")
    return np.asarray(L, dtype=float), np.asarray(D, dtype=float)


def decorrelate(Q: FloatArray) -> tuple[IntArray, FloatArray, FloatArray]:
    """Integer decorrelation (reduction) of a covariance (de Jonge & Tiberius 1996, sec. 3.4).

    Integer Gauss transformations make ``|L[i, j]| <= 1/2``; neighbours ``j, j+1`` are
    permuted whenever that lowers ``D[j+1]`` (``delta = D[j] + L[j+1, j]^2 D[j+1] < D[j+1]``)
    and the sweep restarts from the end, until no permutation is left.

    Parameters
    ----------
    Q : ndarray, shape (n, n)

    Returns
    -------
    Z : ndarray of int64, shape (n, n)
        Unimodular transformation: ``z = Z^T a``, ``Q_z = Z^T Q Z = L^T D L``.
    L, D
        Factors of ``Q_z`` as returned by :func:`ltdl`.
    """
    L0, D0 = ltdl(Q)
    n = D0.size
    fn, compiled = _kernel("reduce", n)
    L: Any
    D: Any
    Zt: Any
    if compiled:
        L, D, Zt = L0, D0, np.eye(n)
    else:
        L, D, Zt = L0.tolist(), D0.tolist(), np.eye(n).tolist()
    fn(L, D, Zt)
    Z = np.rint(np.asarray(Zt, dtype=float).T).astype(np.int64)
    return Z, np.asarray(L, dtype=float), np.asarray(D, dtype=float)


def integer_search(
    z_hat: FloatArray, L: FloatArray, D: FloatArray, n_cands: int = 2
) -> tuple[IntArray, FloatArray]:
    """The ``n_cands`` integer vectors nearest to ``z_hat`` in the metric ``(L^T D L)^-1``
    (de Jonge & Tiberius 1996, sec. 3.5: depth-first search, shrinking ellipsoid, zig-zag
    enumeration around the conditional estimates).

    Parameters
    ----------
    z_hat : ndarray, shape (n,)
        Float ambiguities (cycles), preferably decorrelated.
    L : ndarray, shape (n, n)
    D : ndarray, shape (n,)
        ``L^T D L`` factors of their covariance (:func:`ltdl` or :func:`decorrelate`).
    n_cands : int
        Candidates to return.

    Returns
    -------
    cands : ndarray of int64, shape (n_cands, n)
        Best first.
    sq_norms : ndarray, shape (n_cands,)
        ``(z_hat - z)^T Q^-1 (z_hat - z)`` of each candidate, ascending.

    Notes
    -----
    Conditional estimate of level ``k`` given the integers ``z_{k+1..n-1}``:
    ``zc_k = z_hat_k - sum_{j>k} L[j, k] (zc_j - z_j)``, whose squared distance adds
    ``(zc_k - z_k)^2 / D[k]`` (from ``Q^-1 = L^-1 D^-1 L^-T``).
    """
    a = np.ascontiguousarray(z_hat, dtype=float)
    if n_cands < 1:
        raise ValueError(f"n_cands: expected >= 1, got {n_cands}")
    if a.size == 0:
        return np.zeros((n_cands, 0), dtype=np.int64), np.zeros(n_cands)
    n = a.size
    fn, compiled = _kernel("search", n)
    zc, z, step, dist, cands = _buffers(compiled, (n,), (n,), (n,), (n + 1,), (n_cands, n))
    (sq,) = _buffers(compiled, (n_cands,), fill=math.inf)
    if compiled:
        fn(a, np.ascontiguousarray(L), np.ascontiguousarray(D), zc, z, step, dist, cands, sq)
    else:
        fn(a.tolist(), np.asarray(L).tolist(), np.asarray(D).tolist(), zc, z, step, dist, cands, sq)
    sq_a = np.asarray(sq, dtype=float)
    order = np.argsort(sq_a, kind="stable")
    return np.rint(np.asarray(cands, dtype=float)[order]).astype(np.int64), sq_a[order]


def bootstrap_success_rate(D: FloatArray) -> float:
    """Success probability of integer bootstrapping, ``prod_i (2 Phi(1 / (2 sqrt(D_i))) - 1)``
    (Teunissen 1998, eq. 7), a lower bound of the integer least-squares success rate."""
    p = 1.0
    for d in D:
        p *= math.erf(1.0 / (2.0 * math.sqrt(2.0 * float(d))))
    return p


def _ratio(sq: FloatArray) -> float:
    if sq.size < 2:
        return math.nan
    return math.inf if sq[0] <= 0.0 else float(sq[1] / sq[0])


def resolve_ambiguities(
    a_hat: FloatArray, Q: FloatArray, config: AmbiguityConfig | None = None
) -> AmbiguityResult:
    """Fix float ambiguities to integers by LAMBDA, validated by the ratio test, with partial
    fixing of the best-determined decorrelated subset when the full set fails.

    Parameters
    ----------
    a_hat : ndarray, shape (n,)
        Float ambiguities (cycles).
    Q : ndarray, shape (n, n)
        Their covariance (cycles^2).
    config : AmbiguityConfig, optional

    Returns
    -------
    AmbiguityResult

    Notes
    -----
    Partial fixing: after the reduction the conditional variances ``D`` of the decorrelated
    ambiguities are (nearly) sorted, the smallest last. The subset ``k .. n-1`` with the smallest
    ``k`` whose bootstrapped success rate reaches ``min_success_rate`` is searched with its own
    factors (the trailing block of ``L``, ``D`` factorises the covariance of that subset) and
    validated by the same ratio test.
    """
    cfg = config or AmbiguityConfig()
    a = np.asarray(a_hat, dtype=float)
    n = a.size
    if np.shape(Q) != (n, n):
        raise ValueError(f"Q: expected shape {(n, n)}, got {np.shape(Q)}")
    empty = AmbiguityResult(
        FixStatus.TOO_FEW,
        math.nan,
        0,
        np.zeros((0, n), dtype=np.int64),
        np.zeros(0, dtype=np.int64),
        np.full(n, np.nan),
    )
    if n < cfg.min_fixed:
        return empty
    Z, L, D = decorrelate(Q)
    z_hat = Z.T @ a
    cands, sq = integer_search(z_hat, L, D, 2)
    ratio = _ratio(sq)
    if ratio >= cfg.ratio_threshold:
        a_fix = np.rint(np.linalg.solve(Z.T.astype(float), cands[0].astype(float)))
        return AmbiguityResult(
            FixStatus.FIXED, ratio, n, np.eye(n, dtype=np.int64), a_fix.astype(np.int64), a_fix
        )
    if cfg.partial:
        k = n - 1
        while k > 0 and bootstrap_success_rate(D[k - 1 :]) >= cfg.min_success_rate:
            k -= 1
        if bootstrap_success_rate(D[k:]) < cfg.min_success_rate:
            k += 1
        if n - k >= cfg.min_fixed and k > 0:
            c_sub, sq_sub = integer_search(z_hat[k:], L[k:, k:], D[k:], 2)
            r_sub = _ratio(sq_sub)
            if r_sub >= cfg.ratio_threshold:
                return AmbiguityResult(
                    FixStatus.PARTIAL, r_sub, n - k, Z.T[k:].copy(), c_sub[0], np.full(n, np.nan)
                )
    return AmbiguityResult(
        FixStatus.RATIO_FAILED,
        ratio,
        0,
        np.zeros((0, n), dtype=np.int64),
        np.zeros(0, dtype=np.int64),
        np.full(n, np.nan),
    )


def condition_on_fix(
    x: FloatArray, P: FloatArray, A: FloatArray, fix: AmbiguityResult
) -> tuple[FloatArray, FloatArray]:
    """State and covariance conditioned on the fixed integer combinations (Teunissen 1995,
    eq. 5: ``x_fix = x - P_xz P_zz^-1 (z_hat - z)``, ``P_fix = P - P_xz P_zz^-1 P_zx`` with
    ``z_hat = Z A x``).

    Parameters
    ----------
    x : ndarray, shape (m,)
        Float state.
    P : ndarray, shape (m, m)
    A : ndarray, shape (n, m)
        The ambiguities (cycles) of ``fix`` as linear functions of the state, ``a = A x``
        (a selection matrix, or double differences of single-differenced ambiguities).
    fix : AmbiguityResult
        An accepted fix of ``A x``.

    Returns
    -------
    x_fix : ndarray, shape (m,)
    P_fix : ndarray, shape (m, m)
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    if fix.n_fixed == 0:
        return x.copy(), P.copy()
    T = fix.Z.astype(float) @ np.asarray(A, dtype=float)
    Pxz = P @ T.T
    Pzz = T @ Pxz
    G = np.linalg.solve(Pzz, Pxz.T).T
    x_fix = x - G @ (T @ x - fix.z)
    P_fix = P - G @ Pxz.T
    return x_fix, 0.5 * (P_fix + P_fix.T)
