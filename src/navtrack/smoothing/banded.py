"""Banded symmetric positive definite algebra for the ARI Gauss–Markov model.

Kernels, each O(n) in time and memory for a fixed half-bandwidth ``m``:

* :func:`cholesky_solve_banded` — banded Cholesky with the log-determinant of the matrix and
  the factor: compiled loops with numba (about twice LAPACK's speed for these narrow bands,
  where ``pbtrf`` runs its unblocked code, two BLAS calls per column), else LAPACK
  ``pbtrf``/``pbtrs`` via :func:`scipy.linalg.cholesky_banded` /
  :func:`scipy.linalg.cho_solve_banded`.
* :func:`inverse_band_from_factor` — the band of the inverse ("selected inversion") without
  forming it: Takahashi's recursion on the factor, or :func:`inverse_band` (odd–even block
  recursion on the matrix).
* :func:`add_convolution_band` — the normal matrix of convolution (process) equations.
* :func:`centred_convolution` — the process residuals of a series far from zero, without
  cancellation.
* :func:`weighted_band_sums` — weighted sums along shifted diagonals of that band (the
  expected process moments of the estimation).
* :func:`band_to_dense` — the dense matrix, for tests and small problems only.

Storage is LAPACK's *upper* banded form: ``ab[m + i - j, j] = N[i, j]`` for ``i <= j <= i + m``.
The band of the inverse is returned by diagonal offset: ``zb[l, t] = Z[t, t + l]`` (``Z = N^-1``),
``l = 0..width``; entries past the end of the matrix are NaN.

Compiled kernels and their twins: each ``*_loop`` function (:func:`cholesky_loop`,
:func:`solve_refined_loop`, :func:`takahashi_loop`, :func:`band_sums_loop`,
:func:`centred_convolution_loop`, :func:`add_convolution_band_loop`) is the plain-Python source
that numba compiles when installed (extra ``speed``); without numba the public functions above
take vectorised NumPy or LAPACK paths instead, and the tests check both against each other and
against dense algebra.
"""

from __future__ import annotations

from contextlib import AbstractContextManager, nullcontext
from typing import Any

import numpy as np
import scipy.linalg

from navtrack._numba import jit, numba_module
from navtrack._typing import FloatArray

_numba: Any = numba_module()  # optional accelerator; everything works without it

__all__ = [
    "HAVE_NUMBA",
    "add_convolution_band",
    "add_convolution_band_loop",
    "band_matvec",
    "band_sums_loop",
    "band_to_dense",
    "centred_convolution",
    "centred_convolution_loop",
    "cholesky_loop",
    "cholesky_solve_banded",
    "inverse_band",
    "inverse_band_from_factor",
    "single_threaded_blas",
    "solve_refined_loop",
    "takahashi_loop",
    "weighted_band_sums",
]

#: True when the compiled Takahashi recursion (numba) is available.
HAVE_NUMBA = _numba is not None


def single_threaded_blas() -> AbstractContextManager[Any]:
    """BLAS/LAPACK limited to one thread inside the ``with`` block (threadpoolctl, extra ``speed``).

    The banded systems here are a few elements wide and the vector products short-lived: a
    multithreaded BLAS only adds synchronisation, and on a busy 2-core machine OpenBLAS's
    spinning threads made a 1e5-epoch ARI(2,2) fit 2.3x slower (0.99 s against 0.42 s). Without
    threadpoolctl installed this is a no-op.
    """
    try:
        from threadpoolctl import threadpool_limits  # optional (extra speed)
    except ImportError:
        return nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def band_to_dense(ab: FloatArray) -> FloatArray:
    """Dense symmetric matrix ``(n, n)`` from upper banded storage ``ab`` ``(m + 1, n)``."""
    m = ab.shape[0] - 1
    n = ab.shape[1]
    dense = np.zeros((n, n))
    for lag in range(m + 1):
        vals = ab[m - lag, lag:]
        idx = np.arange(n - lag)
        dense[idx, idx + lag] = vals
        dense[idx + lag, idx] = vals
    return dense


def band_matvec(ab: FloatArray, x: FloatArray) -> FloatArray:
    """``N x`` for symmetric ``N`` in upper banded storage ``ab`` ``(m + 1, n)``."""
    m = ab.shape[0] - 1
    n = ab.shape[1]
    out = ab[m] * x
    for lag in range(1, m + 1):
        if lag >= n:
            break
        band = ab[m - lag, lag:]  # N[t, t + lag], t = 0..n-lag-1
        out[: n - lag] += band * x[lag:]
        out[lag:] += band * x[: n - lag]
    return out


def cholesky_solve_banded(
    ab: FloatArray, rhs: FloatArray, *, refine: int = 1
) -> tuple[FloatArray, float, FloatArray]:
    """Solve ``N x = rhs`` for banded SPD ``N``; also return ``log det N`` and the factor.

    ``refine`` steps of iterative refinement (residual ``rhs - N x`` re-solved with the same
    factor) follow the Cholesky solve: the normal matrices of integrated (ARI) processes are
    ill-conditioned, and without refinement the filtered series — and the likelihood through
    its residuals — carry round-off large enough to stall the optimiser.

    Parameters
    ----------
    ab : ndarray, shape (m + 1, n)
        Upper banded storage of ``N``.
    rhs : ndarray, shape (n,)

    Returns
    -------
    x : ndarray, shape (n,)
    logdet : float
        ``log det N = 2 sum(log diag(U))`` with ``N = U^T U``.
    factor : ndarray, shape (m + 1, n)
        ``U`` in upper banded storage, for :func:`inverse_band_from_factor`.

    Raises
    ------
    numpy.linalg.LinAlgError
        When ``N`` is not numerically positive definite.
    """
    if _cholesky is not None:
        ut, failed = _cholesky(np.ascontiguousarray(ab))
        if failed >= 0:
            raise np.linalg.LinAlgError(f"{failed + 1}-th leading minor not positive definite")
        x = _solve_refined(ab, ut, np.ascontiguousarray(rhs, dtype=np.float64), int(refine))
        cb = ut.T  # (m + 1, n) in Fortran order, as LAPACK returns it
    else:
        cb = scipy.linalg.cholesky_banded(ab, lower=False, check_finite=False)
        x = scipy.linalg.cho_solve_banded((cb, False), rhs, check_finite=False)
        for _ in range(refine):
            x = x + scipy.linalg.cho_solve_banded(
                (cb, False), rhs - band_matvec(ab, x), check_finite=False
            )
    logdet = 2.0 * float(np.sum(np.log(cb[-1])))
    return x, logdet, cb


def cholesky_loop(ab: FloatArray) -> tuple[FloatArray, int]:
    # U^T U = N column by column; ut[j, m + i - j] = U[i, j] (the transpose of LAPACK's upper
    # band, so that a column of U is contiguous). Within column j the entries follow each
    # other: U[i, j] is final once the updates of the rows above it are in, and then updates
    # the rows below (right-looking inside the column: m short independent updates instead of
    # one long dependent sum per entry). Every entry still receives its updates in the order
    # of ascending row, as in LAPACK's pbtf2, and is scaled by the reciprocal of the pivot.
    m = ab.shape[0] - 1
    n = ab.shape[1]
    ut = np.zeros((n, m + 1))
    rinv = np.empty(n)
    col = np.empty(m + 1)
    for j in range(n):
        t0 = max(0, m - j)
        for t in range(t0, m + 1):
            col[t] = ab[t, j]
        for t in range(t0, m):
            i = j - m + t
            u = col[t] * rinv[i]
            ut[j, t] = u
            for t2 in range(t + 1, m):
                col[t2] -= ut[j - m + t2, m - t2 + t] * u
            col[m] -= u * u
        if not col[m] > 0.0:
            return ut, j
        diag = np.sqrt(col[m])
        ut[j, m] = diag
        rinv[j] = 1.0 / diag
    return ut, -1


def solve_refined_loop(ab: FloatArray, ut: FloatArray, rhs: FloatArray, refine: int) -> FloatArray:
    # U^T z = r forwards, U dx = z backwards, x += dx; r = rhs - N x for the refinement steps
    n = ut.shape[0]
    m = ut.shape[1] - 1
    x = np.zeros(n)
    r = rhs.copy()
    z = np.empty(n)
    for step in range(refine + 1):
        if step:
            for j in range(n):
                acc = ab[m, j] * x[j]
                for lag in range(1, min(j, m) + 1):
                    acc += ab[m - lag, j] * x[j - lag]
                for lag in range(1, min(n - 1 - j, m) + 1):
                    acc += ab[m - lag, j + lag] * x[j + lag]
                r[j] = rhs[j] - acc
        for j in range(n):
            acc = r[j]
            for k in range(max(0, j - m), j):
                acc -= ut[j, m + k - j] * z[k]
            z[j] = acc / ut[j, m]
        for i in range(n - 1, -1, -1):
            acc = z[i]
            for j in range(min(n - 1, i + m), i, -1):
                acc -= ut[j, m + i - j] * z[j]
            z[i] = acc / ut[i, m]
        for i in range(n):
            x[i] += z[i]
    return x


_cholesky: Any = jit(cholesky_loop)
_solve_refined: Any = jit(solve_refined_loop)


def inverse_band_from_factor(
    cb: FloatArray, width: int | None = None, *, method: str = "auto", ab: FloatArray | None = None
) -> FloatArray:
    """Band of ``N^-1`` from the banded Cholesky factor ``U`` of ``N = U^T U``.

    Parameters
    ----------
    cb : ndarray, shape (m + 1, n)
        Upper banded storage of ``U`` (:func:`scipy.linalg.cholesky_banded`, ``lower=False``).
    width : int, optional
        Largest diagonal offset wanted (default ``m``).
    method : {"auto", "takahashi", "cyclic"}
        ``takahashi``: the sequential recursion on ``U`` (compiled with numba, O(n m width));
        ``cyclic``: the vectorised odd–even block recursion (:func:`inverse_band`, needs ``ab``);
        ``auto``: ``takahashi`` when numba is installed.
    ab : ndarray, optional
        The matrix itself, for ``method="cyclic"``.

    Notes
    -----
    With ``N = U^T U``, ``U Z = U^-T`` is lower triangular with diagonal ``1 / U_ii``, so for
    ``j >= i``: ``Z_ij = (delta_ij / U_ii - sum_{k=i+1}^{i+m} U_ik Z_kj) / U_ii``
    (Takahashi, Fagan & Chen 1973; Hutchinson & de Hoog 1985). Going backwards over ``i``, and
    within row ``i`` from ``j = i + width`` down to ``j = i``, every ``Z_kj`` needed lies in
    the band already computed.
    """
    m = cb.shape[0] - 1
    width = m if width is None else int(width)
    if width < 0:
        raise ValueError(f"width must be >= 0, got {width}")
    if method == "auto":
        method = "takahashi" if _numba is not None else "cyclic"
    if method == "takahashi":
        # cb as LAPACK returns it (Fortran order): the columns the recursion walks are contiguous
        zb: FloatArray = _takahashi(cb, max(width, m))
        return zb[: width + 1]
    if method == "cyclic":
        if ab is None:
            raise ValueError("method='cyclic' needs the matrix ab")
        return inverse_band(ab, width)
    raise ValueError(f"method must be 'auto', 'takahashi' or 'cyclic', got {method!r}")


def takahashi_loop(cb: FloatArray, width: int) -> FloatArray:
    # Row i of Z needs rows i+1..i+width only: they live in a ring buffer of rows (cache
    # friendly), and the off-diagonal entries of row i, which are independent of each other,
    # are accumulated together (k outer, j inner) instead of one dependent sum at a time.
    # Every sum runs over k ascending, as in the textbook recursion: same rounding.
    m = cb.shape[0] - 1
    n = cb.shape[1]
    w1 = width + 1
    size = 1
    while size < w1:
        size *= 2
    mask = size - 1
    ring = np.zeros((size, w1))  # ring[t & mask, l] = Z[t, t + l]
    zb = np.empty((w1, n))
    acc = np.zeros(w1)
    for i in range(n - 1, -1, -1):
        uii = cb[m, i]
        kmax = min(i + m, n - 1)
        jmax = min(i + width, n - 1)
        for lag in range(w1):
            acc[lag] = 0.0
        for k in range(i + 1, kmax + 1):
            u = cb[m + i - k, k]
            for j in range(i + 1, k):  # Z[k, j] = Z[j, k], j < k
                acc[j - i] += u * ring[j & mask, k - j]
            rk = k & mask
            for j in range(k, jmax + 1):  # Z[k, j], j >= k
                acc[j - i] += u * ring[rk, j - k]
        ri = i & mask
        for lag in range(1, jmax - i + 1):
            ring[ri, lag] = -acc[lag] / uii
        diag = 0.0
        for k in range(i + 1, kmax + 1):
            diag += cb[m + i - k, k] * ring[ri, k - i]
        ring[ri, 0] = (1.0 / uii - diag) / uii
        for lag in range(jmax - i + 1, w1):
            ring[ri, lag] = np.nan
        for lag in range(w1):
            zb[lag, i] = ring[ri, lag]
    return zb


_takahashi: Any = jit(takahashi_loop) or takahashi_loop


def band_sums_loop(zb: FloatArray, v: FloatArray, m: int) -> FloatArray:
    # one pass over the band (all (m + 1)(m + 2)/2 sums together); each sum still runs over s
    # ascending, so the rounding is that of one sum at a time
    ns = v.size
    out = np.zeros((m + 1, m + 1))
    for s in range(ns):
        vs = v[s]
        for b in range(m + 1):
            start = m - b + s
            for a in range(b + 1):
                out[a, b] += vs * zb[b - a, start]
    for b in range(m + 1):
        for a in range(b):
            out[b, a] = out[a, b]
    return out


_band_sums: Any = jit(band_sums_loop)


def centred_convolution_loop(c: FloatArray, x: FloatArray) -> FloatArray:
    m = c.size - 1
    ns = x.size - m
    csum = 0.0
    for i in range(m + 1):
        csum += c[i]
    e = np.empty(ns)
    for s in range(ns):
        xs = x[s + m]
        acc = csum * xs
        for i in range(1, m + 1):
            acc += c[i] * (x[s + m - i] - xs)
        e[s] = acc
    return e


_centred_convolution: Any = jit(centred_convolution_loop)


def centred_convolution(c: FloatArray, x: FloatArray) -> FloatArray:
    """``e_s = sum_i c_i x_{s-i}`` for ``s = m..n-1`` ``(n - m,)``, summed as
    ``c(1) x_s + sum_{i>=1} c_i (x_{s-i} - x_s)`` (``c(1) = sum_i c_i``).

    For a series far from zero with ``c(1)`` near 0 (the process equations of an integrated
    series) the differences of neighbouring values are exact and nothing is lost to
    cancellation. One compiled pass with numba, else ``m`` vectorised passes; the same
    operations in the same order either way (identical rounding).
    """
    m = c.size - 1
    n = x.size
    if n <= m:
        return np.zeros(0)
    c64 = np.ascontiguousarray(c, dtype=np.float64)
    x64 = np.ascontiguousarray(x, dtype=np.float64)
    if _centred_convolution is not None:
        return np.asarray(_centred_convolution(c64, x64))
    csum = 0.0
    for i in range(m + 1):
        csum += float(c64[i])
    xs = x64[m:]
    e = csum * xs
    for i in range(1, m + 1):
        e += c64[i] * (x64[m - i : n - i] - xs)
    return np.asarray(e, dtype=np.float64)


def add_convolution_band_loop(ab: FloatArray, c: FloatArray, vs: FloatArray) -> None:
    m = c.size - 1
    ns = vs.size
    for i in range(m + 1):
        for i2 in range(i + 1):
            cc = c[i] * c[i2]
            row = m - (i - i2)
            off = m - i2
            for s in range(ns):
                ab[row, off + s] += vs[s] * cc


_add_convolution_band: Any = jit(add_convolution_band_loop)


def add_convolution_band(ab: FloatArray, c: FloatArray, vs: FloatArray) -> None:
    """Add ``sum_s vs_s a_s a_s^T`` to the upper band ``ab`` ``(m + 1, n)`` in place, where
    ``a_s`` has ``c_i`` at column ``s - i`` (``s = m..n-1``, ``m = len(c) - 1``): the normal
    matrix of the equations ``sum_i c_i x_{s-i}`` with weights ``vs`` ``(n - m,)``.

    The same sums in the same order with or without numba (identical rounding).
    """
    m = c.size - 1
    n = ab.shape[1]
    if ab.shape[0] != m + 1 or vs.size != n - m:
        raise ValueError(f"ab {ab.shape}, c ({c.size},) and vs ({vs.size},) do not match")
    if _add_convolution_band is not None:
        _add_convolution_band(ab, np.ascontiguousarray(c, dtype=np.float64), vs)
        return
    for i in range(m + 1):
        for i2 in range(i + 1):
            lag = i - i2
            ab[m - lag, m - i2 : n - i2] += vs * (c[i] * c[i2])


def weighted_band_sums(zb: FloatArray, v: FloatArray, m: int) -> FloatArray:
    """``S[a, b] = sum_s v_s Z[s - a, s - b]`` for ``s = m..m + len(v) - 1``, ``a, b = 0..m``.

    Parameters
    ----------
    zb : ndarray, shape (width + 1, n)
        Band of a symmetric ``Z`` by diagonal offset (``width >= m``), as returned by
        :func:`inverse_band_from_factor`.
    v : ndarray, shape (n - m,)
        Weights.
    m : int

    Returns
    -------
    S : ndarray, shape (m + 1, m + 1), symmetric

    Notes
    -----
    ``S[a, b]`` depends on ``|a - b|`` and ``max(a, b)`` only: ``(m + 1)(m + 2)/2`` weighted
    sums along shifted diagonals (compiled loop with numba, else one ``numpy.dot`` each).
    """
    ns = v.size
    if zb.shape[0] <= m or ns + m > zb.shape[1]:
        raise ValueError(f"zb of shape {zb.shape} does not hold offsets 0..{m} for {ns} sums")
    if _band_sums is not None:
        return np.asarray(_band_sums(zb, np.ascontiguousarray(v, dtype=np.float64), m))
    out = np.empty((m + 1, m + 1))
    for b in range(m + 1):
        start = m - b
        for a in range(b + 1):
            out[a, b] = out[b, a] = float(np.dot(v, zb[b - a, start : start + ns]))
    return out


def inverse_band(ab: FloatArray, width: int | None = None) -> FloatArray:
    """Band of the inverse of a banded SPD matrix by selected inversion.

    Parameters
    ----------
    ab : ndarray, shape (m + 1, n)
        Upper banded storage of ``N``.
    width : int, optional
        Largest diagonal offset wanted (default ``m``); any ``width >= 0`` works.

    Returns
    -------
    zb : ndarray, shape (width + 1, n)
        ``zb[l, t] = (N^-1)[t, t + l]``; NaN where ``t + l >= n``.

    Notes
    -----
    ``N`` is viewed as block tridiagonal with blocks of size ``b = max(m, width, 1)``; the block
    Takahashi recursion (Takahashi, Fagan & Chen 1973; for band matrices Hutchinson & de Hoog
    1985) gives exactly the blocks of ``Z = N^-1`` on the block-tridiagonal pattern, hence every
    entry with ``|i - j| <= b``. The elimination is done in odd–even (cyclic-reduction) order:
    eliminating the odd blocks leaves the Schur complement on the even blocks, again block
    tridiagonal; recursing on it yields the even blocks of ``Z``, and the odd blocks follow
    from Takahashi's identities ``Z_oe = -D_o^-1 N_oe Z_ee`` and
    ``Z_oo = D_o^-1 - Z_oe N_eo D_o^-1``. Each level is one batched NumPy step over all
    blocks, so the whole inversion is O(n b^2) work in O(log n) vectorised levels instead of an
    O(n) Python loop. The matrix is padded with identity blocks to a whole number of blocks.

    References
    ----------
    K. Takahashi, J. Fagan, M.-S. Chen, "Formation of a sparse bus impedance matrix and its
    application to short circuit study", 8th PICA Conference, 1973.
    M. F. Hutchinson, F. R. de Hoog, "Smoothing noisy data with spline functions",
    Numer. Math. 47, 99–106, 1985.
    """
    m = ab.shape[0] - 1
    n = ab.shape[1]
    width = m if width is None else int(width)
    if width < 0:
        raise ValueError(f"width must be >= 0, got {width}")
    b = max(m, width, 1)
    nblocks = -(-n // b)
    diag_blocks, off_blocks = _to_blocks(ab, b, nblocks)
    zd, zo = _block_tridiagonal_inverse(diag_blocks, off_blocks)
    return _from_blocks(zd, zo, n, b, width)


def _to_blocks(ab: FloatArray, b: int, nblocks: int) -> tuple[FloatArray, FloatArray]:
    """Diagonal blocks ``(K, b, b)`` and super-diagonal blocks ``(K - 1, b, b)`` of ``N``."""
    m = ab.shape[0] - 1
    n = ab.shape[1]
    size = nblocks * b
    # Diagonal of the padding is 1 (identity blocks, decoupled from the matrix).
    full = np.zeros((m + 1, size))
    full[:, :n] = ab
    full[m, n:] = 1.0
    grid = full.reshape(m + 1, nblocks, b)
    rows, cols = np.meshgrid(np.arange(b), np.arange(b), indexing="ij")
    # diagonal blocks: entry (r, c) is N[kb + r, kb + c], stored at lag |c - r| in column max(r, c)
    lag = np.abs(cols - rows)
    vals = grid[np.clip(m - lag, 0, m), :, np.maximum(rows, cols)]  # (b, b, K)
    diag_blocks = np.where((lag <= m)[:, :, None], vals, 0.0).transpose(2, 0, 1).copy()
    # off block k: entry (r, c) is N[kb + r, (k+1)b + c], lag b + c - r, column of block k + 1
    lag = b + cols - rows
    vals = grid[np.clip(m - lag, 0, m), 1:, cols]  # (b, b, K - 1)
    off_blocks = np.where((lag <= m)[:, :, None], vals, 0.0).transpose(2, 0, 1).copy()
    return diag_blocks, off_blocks


def _block_tridiagonal_inverse(
    diag_blocks: FloatArray, off_blocks: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Selected inverse of an SPD block-tridiagonal matrix.

    ``diag_blocks[k] = N_kk`` ``(K, b, b)``, ``off_blocks[k] = N_{k,k+1}`` ``(K - 1, b, b)``.
    Returns ``(Z_kk, Z_{k,k+1})`` of the same shapes.
    """
    nblocks, b, _ = diag_blocks.shape
    if nblocks == 1:
        return _spd_inv(diag_blocks), np.zeros((0, b, b))
    if nblocks * b <= 64:
        return _dense_inverse(diag_blocks, off_blocks)
    pad = nblocks % 2
    if pad:
        eye = np.broadcast_to(np.eye(b), (1, b, b))
        diag_blocks = np.concatenate([diag_blocks, eye])
        off_blocks = np.concatenate([off_blocks, np.zeros((1, b, b))])
    half = diag_blocks.shape[0] // 2
    even = diag_blocks[0::2]
    odd_inv = np.linalg.inv(diag_blocks[1::2])
    left = off_blocks[0::2]  # N[2j, 2j+1]
    right = np.zeros((half, b, b))  # N[2j+1, 2j+2], zero for the last odd block
    right[: half - 1] = off_blocks[1::2]
    lo = left @ odd_inv  # N[2j,2j+1] D_o^-1
    ro = odd_inv @ right  # D_o^-1 N[2j+1,2j+2]
    lo_t = lo.transpose(0, 2, 1).copy()
    # Schur complement on the even blocks.
    schur_diag = even - lo @ left.transpose(0, 2, 1)
    schur_diag[1:] -= right[:-1].transpose(0, 2, 1) @ ro[:-1]
    schur_off = -(lo[:-1] @ right[:-1])
    ze, ze_off = _block_tridiagonal_inverse(schur_diag, schur_off)
    # Back substitution for the odd blocks (Takahashi identities).
    ze_next = np.empty((half, b, b))
    ze_next[: half - 1] = ze[1:]
    ze_next[half - 1] = 0.0
    ze_off_full = np.empty((half, b, b))
    ze_off_full[: half - 1] = ze_off
    ze_off_full[half - 1] = 0.0
    z_o_prev = lo_t @ ze  # -Z[2j+1, 2j]
    z_o_prev += ro @ ze_off_full.transpose(0, 2, 1)
    z_o_next = lo_t @ ze_off_full  # -Z[2j+1, 2j+2]
    z_o_next += ro @ ze_next
    z_oo = odd_inv + z_o_prev @ lo
    z_oo += z_o_next @ ro.transpose(0, 2, 1)
    np.negative(z_o_prev, out=z_o_prev)
    np.negative(z_o_next, out=z_o_next)
    zd = np.empty_like(diag_blocks)
    zd[0::2] = ze
    zd[1::2] = z_oo
    zo = np.empty((2 * half - 1, b, b))
    zo[0::2] = np.swapaxes(z_o_prev, 1, 2)
    zo[1::2] = z_o_next[: half - 1]
    if pad:
        return zd[:-1], zo[:-1]
    return zd, zo


def _dense_inverse(
    diag_blocks: FloatArray, off_blocks: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Small systems: invert the assembled matrix directly (fewer NumPy calls)."""
    nblocks, b, _ = diag_blocks.shape
    size = nblocks * b
    dense = np.zeros((size, size))
    for k in range(nblocks):
        dense[k * b : (k + 1) * b, k * b : (k + 1) * b] = diag_blocks[k]
    for k in range(nblocks - 1):
        dense[k * b : (k + 1) * b, (k + 1) * b : (k + 2) * b] = off_blocks[k]
        dense[(k + 1) * b : (k + 2) * b, k * b : (k + 1) * b] = off_blocks[k].T
    inv = np.linalg.inv(dense)
    zd = np.stack([inv[k * b : (k + 1) * b, k * b : (k + 1) * b] for k in range(nblocks)])
    zo = np.stack([inv[k * b : (k + 1) * b, (k + 1) * b : (k + 2) * b] for k in range(nblocks - 1)])
    return 0.5 * (zd + np.swapaxes(zd, 1, 2)), zo


def _spd_inv(blocks: FloatArray) -> FloatArray:
    inv = np.asarray(np.linalg.inv(blocks), dtype=np.float64)
    return 0.5 * (inv + np.swapaxes(inv, 1, 2))


def _from_blocks(zd: FloatArray, zo: FloatArray, n: int, b: int, width: int) -> FloatArray:
    nblocks = zd.shape[0]
    zb = np.full((width + 1, n), np.nan)
    for lag in range(width + 1):
        row = np.empty(nblocks * b)
        for r in range(b):
            c = r + lag
            if c < b:
                row[r::b] = zd[:, r, c]
            else:
                vals = np.full(nblocks, np.nan)
                vals[: nblocks - 1] = zo[:, r, c - b]
                row[r::b] = vals
        zb[lag, : n - lag] = row[: n - lag]
    return zb
