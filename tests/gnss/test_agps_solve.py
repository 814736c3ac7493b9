"""The kernel additions made for the AGPS solvers: Gauss–Newton's gradient stopping rule and the
singularity test's determinant pre-screen (same decisions as the eigenvalue test)."""

from __future__ import annotations

import numpy as np

from navtrack.estimation.least_squares import LsqStatus, gauss_newton, singular_normal_matrices


def _eigen_decision(N: np.ndarray, rcond: float) -> np.ndarray:
    """The test as it was: eigenvalues of the unit-diagonal scaled matrix."""
    d = np.sqrt(np.einsum("bpp->bp", N))
    Ns = N / (d[:, :, None] * d[:, None, :])
    eig = np.linalg.eigvalsh(Ns)
    return eig[:, 0] <= rcond * eig[:, -1]


def test_singular_prescreen_decides_like_the_eigenvalues() -> None:
    rng = np.random.default_rng(0)
    for p in (2, 4, 5, 7):
        A = rng.normal(size=(3000, p + 2, p))
        # condition spread over 1e0..1e20: columns scaled, some nearly dependent
        A[:, :, -1] = A[:, :, 0] + 10.0 ** rng.uniform(-10, 0, size=(3000, 1)) * A[:, :, -1]
        A *= 10.0 ** rng.uniform(-3, 3, size=(3000, 1, p))
        N = np.einsum("bmp,bmq->bpq", A, A)
        # (at rcond near machine epsilon the eigenvalue itself is rounding: not compared)
        for rcond in (1e-12, 1e-9, 1e-6):
            ours = singular_normal_matrices(N, rcond)
            ref = _eigen_decision(N, rcond)
            assert ours.any()
            assert (~ours).any()
            np.testing.assert_array_equal(ours, ref)


def test_gauss_newton_gradient_rule_stops_after_the_step_from_a_flat_iterate() -> None:
    """y = exp(a t): the step from an iterate with ||J^T v|| <= gtol is the last one."""
    t = np.linspace(0.0, 1.0, 8)
    a_true = np.array([0.3, 1.2])
    y = np.exp(a_true[:, None] * t[None, :])

    def fun(x: np.ndarray, idx: np.ndarray):
        h = np.exp(x[:, :1] * t[None, :])
        J = (t[None, :] * h)[..., None]
        return y[idx] - h, J, np.ones_like(h), np.ones(h.shape, dtype=bool)

    x0 = np.zeros((2, 1))
    full = gauss_newton(fun, x0, max_iter=50, xtol=1e-14)
    # the gradient norms along the same iterates, by hand
    x = x0.copy()
    grads: list[list[float]] = [[], []]
    for _ in range(int(full.iterations.max())):
        v, J, _, _ = fun(x, np.arange(2))
        g = np.einsum("bmp,bm->bp", J, v)
        for b in range(2):
            grads[b].append(float(np.linalg.norm(g[b])))
        x = x + g / np.einsum("bmp,bmq->bpq", J, J)[:, :, 0]
    gtol = 1e-3
    res = gauss_newton(fun, x0, max_iter=50, xtol=0.0, gtol=gtol)
    for b in range(2):
        first_flat = next(k for k, gn in enumerate(grads[b]) if gn <= gtol)
        assert res.iterations[b] == first_flat + 1
        assert res.status[b] == LsqStatus.CONVERGED
    np.testing.assert_allclose(res.x[:, 0], a_true, atol=1e-4)
