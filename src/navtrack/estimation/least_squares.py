"""Batched nonlinear least-squares kernels: Gauss–Newton and Marquardt.

Both solvers work on a *batch* of independent problems (one per epoch): parameters ``x (B, P)``,
measurements ``(B, M)`` with a boolean ``valid`` mask, weights ``(B, M)``. The caller supplies the
model as a function of the current estimates of the epochs still iterating, so that measurement
selection (elevation mask) and corrections can follow the estimate, as single point positioning
needs. Outcomes (converged, too few measurements, singular normal matrix, no convergence) are a
per-epoch ``status`` — never exceptions.

Conventions: ``fun(x, idx)`` returns ``(v, J, w, valid)`` for the epochs ``idx`` with
``v = y - h(x)`` the residuals (observed minus computed), ``J = dh/dx`` the Jacobian of the model,
``w = 1/sigma^2`` the weights and ``valid`` the measurements to use. The weighted least-squares
step is ``dx = (J^T W J)^-1 J^T W v``.

A parameter that no valid measurement touches (a zero column of ``J``, e.g. the inter-system bias
of a system with no satellite at that epoch) is held at its current value and does not count in
the redundancy, like RTKLIB's zero pseudo-observations for absent systems.

References
----------
P. J. G. Teunissen, *Adjustment Theory*, Delft Univ. Press 2003, ch. 4 (Gauss–Newton);
D. W. Marquardt, "An algorithm for least-squares estimation of nonlinear parameters",
J. SIAM 11(2), 1963; J.-z. Li, "Two satellites positioning algorithm based on AGPS system with two
clock bias", ICCET 2010, V2-417 (Marquardt steps 1–6 with adaptive growth factor).
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum
from typing import NamedTuple

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray

ModelFn = Callable[[FloatArray, IntArray], tuple[FloatArray, FloatArray, FloatArray, BoolArray]]
"""``fun(x (b, P), idx (b,)) -> (v (b, M), J (b, M, P), w (b, M), valid (b, M))``."""


class LsqStatus(IntEnum):
    """Per-epoch outcome of a batched least-squares solve."""

    CONVERGED = 0
    TOO_FEW_MEASUREMENTS = 1
    SINGULAR = 2
    NO_CONVERGENCE = 3


class LsqResult(Record):
    """Result of a batched least-squares solve.

    Attributes
    ----------
    x : ndarray, shape (B, P)
        Estimates (the last iterate for epochs that did not converge; the start value where the
        problem was singular or under-determined at the first iteration).
    cov : ndarray, shape (B, P, P)
        Covariance ``(J^T W J)^-1`` at the estimate (a posteriori scaling is left to the caller);
        NaN where singular. Rows/columns of unobserved parameters are zero.
    residuals : ndarray, shape (B, M)
        Residuals ``y - h(x)`` at the estimate, NaN where not valid.
    jacobian : ndarray, shape (B, M, P)
        Design (geometry) matrix ``J = dh/dx`` at the estimate, zero rows where not valid: a
        small change ``dx`` of the estimate changes the residuals by ``-J dx``.
    valid : ndarray of bool, shape (B, M)
        Measurements used at the estimate.
    weights : ndarray, shape (B, M)
        Weights at the estimate (0 where not valid).
    cost : ndarray, shape (B,)
        Weighted sum of squared residuals at the estimate.
    dof : ndarray of int, shape (B,)
        Redundancy: valid measurements minus observed parameters.
    iterations : ndarray of int, shape (B,)
        Iterations used (model evaluations with a step for Gauss–Newton, accepted plus rejected
        trial steps for Marquardt).
    accepted : ndarray of int, shape (B,)
        Steps that moved the estimate (all of Gauss–Newton's; Marquardt's accepted trials).
    status : ndarray of int8, shape (B,)
        :class:`LsqStatus` values.
    """

    x: FloatArray
    cov: FloatArray
    residuals: FloatArray
    jacobian: FloatArray
    valid: BoolArray
    weights: FloatArray
    cost: FloatArray
    dof: IntArray
    iterations: IntArray
    accepted: IntArray
    status: np.ndarray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _normal_equations(
    v: FloatArray, J: FloatArray, w: FloatArray, valid: BoolArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Normal matrix ``N = J^T W J`` (b, P, P), right side ``J^T W v`` (b, P), observed columns."""
    wv = np.where(valid, w, 0.0)
    Jw = J * wv[..., None]
    Jwt = np.swapaxes(Jw, -1, -2)
    N = Jwt @ J  # matmul: several times faster than einsum on stacks of small matrices
    g = (Jwt @ np.where(valid, v, 0.0)[..., None])[..., 0]
    observed = np.einsum("bpp->bp", N) > 0.0
    return N, g, observed


def _regularise(N: FloatArray, observed: BoolArray) -> FloatArray:
    """Put 1 on the diagonal of unobserved parameters so that their step is zero."""
    N = N.copy()
    idx = np.arange(N.shape[-1])
    N[:, idx, idx] += ~observed
    return N


def singular_normal_matrices(N: FloatArray, rcond: float) -> BoolArray:
    """Normal matrices whose scaled condition is worse than ``1/rcond``.

    The scaled matrix has a unit diagonal, so its largest eigenvalue is at most ``P`` and its
    smallest at least ``det / P^(P-1)``: a determinant above ``rcond P^P`` proves it regular
    without an eigen-decomposition (the batched LU is several times cheaper); only the others
    are decided by their eigenvalues. The decisions are those of the eigenvalue test, except
    where ``rcond`` is within rounding of machine epsilon and the eigenvalue is itself noise.
    """
    d = np.sqrt(np.einsum("bpp->bp", N))
    with np.errstate(divide="ignore", invalid="ignore"):
        Ns = N / (d[:, :, None] * d[:, None, :])
    ok = np.isfinite(Ns).all(axis=(1, 2))
    bad = ~ok
    if ok.any():
        n_p = N.shape[-1]
        idx = np.flatnonzero(ok)
        unsure = idx[~(np.linalg.det(Ns[idx]) > rcond * float(n_p) ** n_p)]
        if unsure.size:
            eig = np.linalg.eigvalsh(Ns[unsure])
            bad[unsure] = eig[:, 0] <= rcond * eig[:, -1]
    return bad


def _check(x0: FloatArray) -> FloatArray:
    x0 = np.array(x0, dtype=float)
    if x0.ndim != 2:
        raise ValueError(f"x0: expected shape (B, P), got {x0.shape}")
    return x0


def _finish(
    fun: ModelFn,
    x: FloatArray,
    iterations: IntArray,
    status: np.ndarray,
    rcond: float,
    accepted: IntArray | None = None,
) -> LsqResult:
    """Evaluate residuals, covariance and cost at the final estimates."""
    B, P = x.shape
    idx = np.arange(B)
    v, J, w, valid = fun(x, idx)
    N, _, observed = _normal_equations(v, J, w, valid)
    Nr = _regularise(N, observed)
    cov = np.full((B, P, P), np.nan)
    sing = singular_normal_matrices(Nr, rcond)
    good = ~sing
    if good.any():
        inv = np.linalg.inv(Nr[good])
        mask = observed[good]
        inv *= mask[:, :, None] & mask[:, None, :]
        cov[good] = inv
    n_valid = valid.sum(axis=1)
    dof = (n_valid - observed.sum(axis=1)).astype(np.int64)
    w0 = np.where(valid, w, 0.0)
    res = np.where(valid, v, np.nan)
    cost = np.einsum("bm,bm->b", w0, np.where(valid, v, 0.0) ** 2)
    status = status.copy()
    status[(status == LsqStatus.CONVERGED) & sing] = LsqStatus.SINGULAR
    return LsqResult(
        x=x,
        cov=cov,
        residuals=res,
        jacobian=np.where(valid[..., None], J, 0.0),
        valid=valid,
        weights=w0,
        cost=cost,
        dof=dof,
        iterations=iterations,
        accepted=iterations if accepted is None else accepted,
        status=status,
    )


def gauss_newton(
    fun: ModelFn,
    x0: FloatArray,
    *,
    max_iter: int = 10,
    xtol: float = 1e-4,
    min_measurements: int | None = None,
    rcond: float = 1e-12,
    gtol: float | None = None,
) -> LsqResult:
    """Batched (weighted) Gauss–Newton iteration.

    Each epoch iterates ``x <- x + (J^T W J)^-1 J^T W v`` until the step norm is below ``xtol``
    (RTKLIB's ``estpos`` criterion, 1e-4 in the units of ``x``) or ``max_iter`` steps were taken.
    With ``gtol``, an epoch also stops after the step taken from an iterate whose gradient norm
    ``||J^T W v||`` is at most ``gtol`` (the stopping rule of Li (2010) step 6 with ``mu = 0``).
    Epochs leave the batch as they converge or fail.

    Parameters
    ----------
    fun : callable
        The model, see the module docstring (:data:`ModelFn`).
    x0 : ndarray, shape (B, P)
        Start values.
    max_iter : int
        Maximum number of steps per epoch.
    xtol : float
        Convergence threshold on the Euclidean norm of the step.
    min_measurements : int, optional
        Minimum number of valid measurements; default: the number of observed parameters.
    rcond : float
        A normal matrix (scaled to unit diagonal) whose smallest eigenvalue is below ``rcond``
        times its largest is singular.
    gtol : float, optional
        Gradient-norm stopping threshold (units of ``J^T W v``); None: step norm only.

    Returns
    -------
    LsqResult
    """
    x = _check(x0)
    B, _ = x.shape
    status = np.full(B, LsqStatus.NO_CONVERGENCE, dtype=np.int8)
    iterations = np.zeros(B, dtype=np.int64)
    active = np.arange(B)
    for _ in range(max_iter):
        if active.size == 0:
            break
        v, J, w, valid = fun(x[active], active)
        N, g, observed = _normal_equations(v, J, w, valid)
        n_valid = valid.sum(axis=1)
        need = observed.sum(axis=1) if min_measurements is None else min_measurements
        few = n_valid < np.maximum(need, 1)
        Nr = _regularise(N, observed)
        sing = ~few & singular_normal_matrices(Nr, rcond)
        status[active[few]] = LsqStatus.TOO_FEW_MEASUREMENTS
        status[active[sing]] = LsqStatus.SINGULAR
        go = ~(few | sing)
        if not go.any():
            active = active[go]
            break
        dx = np.linalg.solve(Nr[go], g[go][..., None])[..., 0]
        ids = active[go]
        x[ids] += dx
        iterations[ids] += 1
        done = np.linalg.norm(dx, axis=1) < xtol
        if gtol is not None:
            done |= np.linalg.norm(g[go], axis=1) <= gtol
        status[ids[done]] = LsqStatus.CONVERGED
        active = ids[~done]
    return _finish(fun, x, iterations, status, rcond)


def marquardt(
    fun: ModelFn,
    x0: FloatArray,
    *,
    mu0: float = 0.1,
    beta: float = 10.0,
    eps: float = 0.1,
    max_iter: int = 100,
    xtol: float = 1e-10,
    rcond: float = 1e-12,
) -> LsqResult:
    """Batched Marquardt (Levenberg–Marquardt) with the adaptive growth factor of Li (2010).

    With ``F(x) = sum w f^2`` the objective and ``g = J^T W f`` its half gradient, each epoch runs
    the steps of Li (2010), section III:

    1. ``k = 1``, ``mu = mu0``; evaluate ``F(x_1)``;
    2. evaluate ``f(x_k)`` and ``A_k = J(x_k)``;
    3. solve ``(A^T W A + mu I) d = -A^T W f``; trial ``x' = x_k + d``;
    4. if ``F(x') < F(x_k)`` go to 6, else to 5;
    5. if ``||A^T W f|| <= eps`` stop with ``x_k``; else ``mu <- beta mu`` and go to 3;
    6. if ``||A^T W f|| <= eps`` stop with ``x'``; else ``mu <- mu / beta``, ``k <- k + 1``,
       go to 2.

    Here ``f = h(x) - y = -v``; the step is the same as Gauss–Newton's for ``mu = 0``. The
    measurement selection (``valid``) is that of the start point and kept fixed, so that ``F`` is
    comparable between iterates.

    Parameters
    ----------
    fun : callable
        The model, see :data:`ModelFn`.
    x0 : ndarray, shape (B, P)
        Start values.
    mu0, beta, eps : float
        Initial damping ``mu_1``, growth factor ``beta`` and gradient tolerance ``epsilon``; the
        defaults are the paper's ``mu_1 = 0.1, beta = 10, epsilon = 0.1``.
    max_iter : int
        Maximum number of trial steps per epoch (the paper has no limit).
    xtol : float
        Safeguard not in the paper: an epoch also stops (converged) when its trial step is
        shorter than ``xtol`` — in floating point ``F`` cannot decrease any more, and ``mu``
        would grow without end while ``||A^T W f||`` stays above a too small ``eps``.
    rcond : float
        Singularity threshold of the undamped normal matrix used for the covariance.

    Returns
    -------
    LsqResult
        ``iterations`` counts trial steps (accepted or not).

    References
    ----------
    J.-z. Li, ICCET 2010, section III steps 1–6 and eq. (8); the reading of the extracted text
    (``mu_1 = 0.1``, ``beta = 10``, ``epsilon = 0.1``) is that of ``shared/papers/README.md``.
    """
    if beta <= 1.0:
        raise ValueError(f"beta: growth factor must be > 1, got {beta}")
    x = _check(x0)
    _, _, _, valid0 = fun(x, np.arange(x.shape[0]))
    valid0 = valid0.copy()

    def model(xb: FloatArray, idx: IntArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        v, J, w, _ = fun(xb, idx)
        vm = valid0[idx]
        return np.where(vm, v, 0.0), J * vm[..., None], np.where(vm, w, 0.0)

    damping = _Damping(mu0=mu0, beta=beta, eps=eps, max_iter=max_iter, xtol=xtol)
    status, iterations, accepted = _marquardt_steps(model, x, valid0, damping)

    def final(
        xb: FloatArray, idx: IntArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        v_, J_, w_, _ = fun(xb, idx)
        return v_, J_, w_, valid0[idx]

    return _finish(final, x, iterations, status, rcond, accepted)


class _Damping(NamedTuple):
    """The settings of :func:`marquardt`'s damping and stopping rules."""

    mu0: float
    beta: float
    eps: float
    max_iter: int
    xtol: float


def _marquardt_steps(
    model: Callable[[FloatArray, IntArray], tuple[FloatArray, FloatArray, FloatArray]],
    x: FloatArray,
    valid0: BoolArray,
    damping: _Damping,
) -> tuple[Int8Array, IntArray, IntArray]:
    """Steps 1-6 of :func:`marquardt` on every epoch at once; ``x`` is updated in place.

    Returns the status, the trial steps and the accepted steps of every epoch."""
    B, P = x.shape
    idx_all = np.arange(B)
    status = np.full(B, LsqStatus.NO_CONVERGENCE, dtype=np.int8)
    iterations = np.zeros(B, dtype=np.int64)
    accepted = np.zeros(B, dtype=np.int64)
    n_valid = valid0.sum(axis=1)
    mu = np.full(B, float(damping.mu0))
    active = idx_all.copy()
    v, J, w = model(x, active)
    F = np.einsum("bm,bm->b", w, v**2)
    _, _gJ, observed = _normal_equations(v, J, w, valid0)
    few = n_valid < np.maximum(observed.sum(axis=1), 1)
    status[few] = LsqStatus.TOO_FEW_MEASUREMENTS
    keep = ~few
    active, F, v, J, w = active[keep], F[keep], v[keep], J[keep], w[keep]
    eye = np.eye(P)
    while active.size:
        N, g, observed = _normal_equations(v, J, w, valid0[active])
        gnorm = np.linalg.norm(g, axis=1)
        Nr = _regularise(N, observed) + mu[active, None, None] * eye
        d = np.linalg.solve(Nr, g[..., None])[..., 0]
        xt = x[active] + d
        iterations[active] += 1
        vt, Jt, wt = model(xt, active)
        Ft = np.einsum("bm,bm->b", wt, vt**2)
        better = Ft < F
        small = (gnorm <= damping.eps) | (np.linalg.norm(d, axis=1) < damping.xtol)
        # step 6: accept; stop if the gradient at x_k was already small
        acc = active[better]
        x[acc] = xt[better]
        accepted[acc] += 1
        status[acc[small[better]]] = LsqStatus.CONVERGED
        mu[acc] /= damping.beta
        # step 5: reject; stop at x_k if its gradient is small, else grow mu
        rej = active[~better]
        status[rej[small[~better]]] = LsqStatus.CONVERGED
        mu[rej] *= damping.beta
        cont = ~small & (iterations[active] < damping.max_iter)
        # for accepted steps the model at the new point is the trial evaluation
        v = np.where(better[:, None], vt, v)[cont]
        J = np.where(better[:, None, None], Jt, J)[cont]
        w = np.where(better[:, None], wt, w)[cont]
        F = np.where(better, Ft, F)[cont]
        active = active[cont]
    return status, iterations, accepted
