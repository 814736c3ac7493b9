"""Multisensor fusion trackers on constructed cases (paper 3 readings)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from navtrack.estimation.kalman import ekf_update, gain_update, innovation_gain, kf_predict
from navtrack.estimation.models import wrap_angle
from navtrack.tracking.assignment import assign2d
from navtrack.tracking.gating import chi2_threshold, gate
from navtrack.tracking.jpda import association_weights, jpda_marginals
from navtrack.tracking.models import (
    FunctionMeasurement,
    RangeBearing,
    constant_velocity,
    linear_position,
    measure,
)
from navtrack.tracking.trackers import equivalent
from navtrack.tracking.trackers.equivalent import equivalent_measurement
from navtrack.tracking.trackers.multisensor import (
    ALGORITHMS,
    FusionConfig,
    MultiScans,
    fusion_step,
    joint_tuple_marginals,
    nonparametric_b,
    run_fusion,
    sd_gnn_tuples,
    sensor_terms,
    tuple_marginals,
)

SENSORS = [
    RangeBearing(np.diag([300.0**2, 0.03**2]), np.array([-500.0, -500.0])),
    RangeBearing(np.diag([200.0**2, 0.02**2]), np.array([0.0, 0.0])),
    RangeBearing(np.diag([100.0**2, 0.01**2]), np.array([-500.0, 500.0])),
]
MOTION = constant_velocity(2, 1.0)
X0 = np.array([[-29500.0, 400.0, 34500.0, -400.0]])
P0 = np.diag([300.0**2, 30.0**2, 300.0**2, 30.0**2])[None]


@pytest.fixture(params=["numpy", "compiled"])
def gauss_newton(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Run a test through each path of the equivalent measurement's Gauss-Newton loop: the
    NumPy loop, and the compiled range-bearing loop (skipped without numba)."""
    if request.param == "numpy":
        monkeypatch.setattr(equivalent, "compiled_gauss_newton", lambda: None)
    elif equivalent.compiled_gauss_newton() is None:
        pytest.skip("numba is not installed")
    return str(request.param)


def _one_target_scans(K: int, rng: np.random.Generator, t_offset: np.ndarray | None = None):
    t = np.repeat(np.arange(K, dtype=float)[:, None], 3, axis=1)
    if t_offset is not None:
        t = t + t_offset
    truth = np.stack([MOTION.f(X0[0], float(k)) for k in range(K)])  # (K, 4) at t = k
    z = np.empty((K, 3, 1, 2))
    for s, m in enumerate(SENSORS):
        at = np.stack([MOTION.f(X0[0], tk) for tk in t[:, s]])  # the target at the scan time
        z[:, s, 0] = m.h(at) + rng.standard_normal((K, 2)) * np.sqrt(np.diag(m.R))
        z[:, s, 0, 1] = wrap_angle(z[:, s, 0, 1])
    return truth, MultiScans(z, np.ones((K, 3, 1), bool), t)


def _stacked_ekf(x, P, z):
    """Centralised EKF oracle: one stacked (6-D) measurement, Jacobians at the prediction."""
    H = np.concatenate([m.jacobian(x) for m in SENSORS])
    R = np.zeros((6, 6))
    y = np.empty(6)
    for s, m in enumerate(SENSORS):
        R[2 * s : 2 * s + 2, 2 * s : 2 * s + 2] = m.R
        d = z[s] - m.h(x)
        y[2 * s : 2 * s + 2] = [d[0], wrap_angle(d[1])]
    S, K = innovation_gain(P, H, R)
    return gain_update(x, P, y, K, S)


def test_one_target_no_clutter_pd1_matches_centralised_ekf() -> None:
    """``parallel`` and ``sd_gnn`` equal the stacked EKF, ``sequential`` the per-sensor EKF
    chain, when every tuple is certain (P_D = 1, no gate, no clutter)."""
    truth, scans = _one_target_scans(20, np.random.default_rng(0))
    cfg = FusionConfig((1.0,) * 3, (1e-9,) * 3, gate_probability=1.0)
    x, P = X0[0].copy(), P0[0].copy()
    xs_c, xs_q = [], []
    xq, Pq = x.copy(), P.copy()
    for k in range(20):
        dt = 0.0 if k == 0 else 1.0
        xp, Pp = kf_predict(x, P, MOTION.F(dt), MOTION.Q(dt))
        x, P = _stacked_ekf(xp, Pp, scans.z[k, :, 0])
        xs_c.append(x)
        xq, Pq = kf_predict(xq, Pq, MOTION.F(dt), MOTION.Q(dt))
        for s, m in enumerate(SENSORS):
            u = ekf_update(xq, Pq, scans.z[k, s, 0], m)
            xq, Pq = u.x, u.P
        xs_q.append(xq)
    for alg in ("parallel", "sd_gnn"):
        r = run_fusion(alg, scans, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
        np.testing.assert_allclose(r.x[:, 0], np.array(xs_c), rtol=1e-9, atol=1e-6)
    r = run_fusion("sequential", scans, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
    np.testing.assert_allclose(r.x[:, 0], np.array(xs_q), rtol=1e-9, atol=1e-6)
    # the literal eqs. 24-32 mix single-sensor corrections: consistent, not identical
    lit = FusionConfig((1.0,) * 3, (1e-9,) * 3, gate_probability=1.0, false_per_gate=1.8)
    r = run_fusion("sdcmsjpda", scans, SENSORS, MOTION, X0, P0, lit, t0_s=0.0)
    err = np.hypot(*(r.x[:, 0, [0, 2]] - truth[:, [0, 2]]).T)
    err_c = np.hypot(*(np.array(xs_c)[:, [0, 2]] - truth[:, [0, 2]]).T)
    assert np.sqrt(np.mean(err[5:] ** 2)) < 3.0 * np.sqrt(np.mean(err_c[5:] ** 2))
    assert np.all(np.linalg.eigvalsh(r.P[:, 0]) > 0)


def test_single_sensor_sdcmsjpda_is_the_ekf() -> None:
    """With one sensor, b = 0 (P_D = P_G = 1) and one measurement, eq. 24 is the EKF update."""
    _, scans = _one_target_scans(5, np.random.default_rng(1))
    one = MultiScans(scans.z[:, 2:], scans.valid[:, 2:], scans.t_s[:, 2:])
    cfg = FusionConfig((1.0,), (1e-9,), gate_probability=1.0, false_per_gate=1.8)
    r = run_fusion("sdcmsjpda", one, SENSORS[2:], MOTION, X0, P0, cfg, t0_s=0.0)
    x, P = X0[0], P0[0]
    for k in range(5):
        dt = 0.0 if k == 0 else 1.0
        xp, Pp = kf_predict(x, P, MOTION.F(dt), MOTION.Q(dt))
        u = ekf_update(xp, Pp, one.z[k, 0, 0], SENSORS[2])
        x, P = u.x, u.P
    np.testing.assert_allclose(r.x[-1, 0], x, rtol=1e-9)
    np.testing.assert_allclose(r.P[-1, 0], P, rtol=1e-7)


def test_literal_sdcmsjpda_two_sensors_two_measurements_by_hand() -> None:
    """Eqs. 24-32 as printed on one target, two position sensors, one measurement each (dt =
    0: the prediction is the prior). Worked by hand: the single-sensor marginals, the four
    tuples' ``β(L) = β¹(l₁) β²(l₂)``, eq. 26's ``e_s = exp(-d²/2)`` and
    ``b = 2 m (1 - P_D P_G) / (γ P_D)`` (n_z = 2: ``(2π/γ) / π``), eq. 25's weights, eq.
    24's tuple estimates, and the covariance (31-32) as the moments of the mixture of the
    prediction (weight ``β(L) β₀(L)``) and the single-sensor updates (``β(L) w_s(L)``)."""
    sens = [linear_position(4, (0, 2), 50.0), linear_position(4, (0, 2), 100.0)]
    motion = constant_velocity(2, 1.0)
    x = np.array([0.0, 10.0, 0.0, -5.0])
    P = np.diag([100.0**2, 10.0**2, 80.0**2, 10.0**2])
    z = [np.array([[60.0, -30.0]]), np.array([[-90.0, 120.0]])]
    pd, pg, m, lam = 0.9, 0.99, 1.8, 1e-5
    cfg = FusionConfig((pd, pd), (lam, lam), pg, false_per_gate=m)
    gamma = -2.0 * np.log(1.0 - pg)  # chi-square(2) quantile
    b = 2.0 * m * (1.0 - pd * pg) / (gamma * pd)
    assert nonparametric_b(cfg, 2) == pytest.approx(b, rel=1e-12)
    assert b == pytest.approx(0.0473382, rel=1e-5)  # 3.6 * 0.109 / (9.21034 * 0.9)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    e, Ks, nus, Ss, beta1 = [], [], [], [], []
    for s, model in enumerate(sens):
        S = H @ P @ H.T + model.R
        nu = z[s][0] - H @ x
        d2 = nu @ np.linalg.solve(S, nu)
        g = pd * np.exp(-0.5 * d2) / (2 * np.pi * np.sqrt(np.linalg.det(S))) / lam
        beta1.append(g / (1.0 - pd * pg + g))  # single-sensor marginal of the detection
        e.append(np.exp(-0.5 * d2))
        Ks.append(P @ H.T @ np.linalg.inv(S))
        nus.append(nu)
        Ss.append(S)
    comps = []  # (weight, mean, covariance) of the mixture
    for l1, l2 in itertools.product((0, 1), repeat=2):
        bL = (beta1[0] if l1 else 1 - beta1[0]) * (beta1[1] if l2 else 1 - beta1[1])
        den = b + l1 * e[0] + l2 * e[1]
        comps.append((bL * b / den, x, P))  # eq. 28
        for s, used in enumerate((l1, l2)):
            if used:
                w = e[s] / den  # eq. 25
                comps.append((bL * w, x + Ks[s] @ nus[s], P - Ks[s] @ Ss[s] @ Ks[s].T))
    wsum = sum(c[0] for c in comps)
    assert wsum == pytest.approx(1.0)
    xm = sum(c[0] * c[1] for c in comps)
    Pm = sum(c[0] * (c[2] + np.outer(c[1] - xm, c[1] - xm)) for c in comps)
    xn, Pn, _ = fusion_step("sdcmsjpda", x[None], P[None], z, [0.0, 0.0], sens, motion, cfg)
    np.testing.assert_allclose(xn[0], xm, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(Pn[0], Pm, rtol=1e-10, atol=1e-6)
    # eq. 24 mixes the two sensors' corrections instead of fusing them: the estimate lies
    # between the prediction and the single-sensor updates, not at the stacked update
    xs, _, _ = fusion_step("parallel", x[None], P[None], z, [0.0, 0.0], sens, motion, cfg)
    assert np.linalg.norm(xn[0] - xs[0]) > 1.0
    with pytest.raises(ValueError, match="false_per_gate"):
        fusion_step("sdcmsjpda", x[None], P[None], z, [0.0, 0.0], sens, motion,
                    FusionConfig((pd, pd), (lam, lam), pg))  # fmt: skip


def _scaled(eps: float):
    """The three sensors with noise standard deviations scaled by ``eps``."""
    return [RangeBearing(eps**2 * m.R, m.sensor_xy) for m in SENSORS]


@pytest.mark.parametrize("seed", [0, 1])
def test_equivalent_measurement_update_is_the_centralised_ekf_to_first_order(
    seed: int, gauss_newton: str
) -> None:
    """One target, no clutter, P_D = 1, three sensors: ``sdcmsjpda`` (EKF update with the
    tuple's ML equivalent measurement) equals the stacked EKF (``parallel``, tested above
    against the oracle) up to the linearisation error, which shrinks with the noise."""
    cfg = FusionConfig((1.0,) * 3, (1e-9,) * 3, gate_probability=1.0)
    dev, rel = [], []
    for eps in (1.0, 0.1):
        sens = _scaled(eps)
        rng = np.random.default_rng(seed)
        K = 20
        truth = np.stack([MOTION.f(X0[0], float(k)) for k in range(K)])
        z = np.stack(
            [
                m.h(truth) + eps * rng.standard_normal((K, 2)) * np.sqrt(np.diag(SENSORS[s].R))
                for s, m in enumerate(sens)
            ],
            axis=1,
        )[:, :, None]
        t = np.repeat(np.arange(K, dtype=float)[:, None], 3, axis=1)
        scans = MultiScans(z, np.ones((K, 3, 1), bool), t)
        P0s = eps**2 * P0
        a = run_fusion("parallel", scans, sens, MOTION, X0, P0s, cfg, t0_s=0.0)
        b = run_fusion("sdcmsjpda_fused", scans, sens, MOTION, X0, P0s, cfg, t0_s=0.0)
        sd = np.sqrt(a.P[:, 0, [0, 2], [0, 2]])
        dev.append(np.max(np.abs(b.x[:, 0, [0, 2]] - a.x[:, 0, [0, 2]]) / sd))
        dP = np.abs(b.P[:, 0] - a.P[:, 0]).max(axis=(1, 2))
        rel.append(np.max(dP / np.abs(a.P[:, 0]).max(axis=(1, 2))))
    assert dev[0] < 0.1  # well inside one posterior standard deviation
    assert dev[1] < 0.2 * dev[0]  # second-order term: ~eps times smaller
    assert rel[0] < 0.05
    assert rel[1] < 0.2 * rel[0]


def test_equivalent_measurement_is_the_ml_fusion_of_the_tuple(gauss_newton: str) -> None:
    """Noise-free tuples give the true position exactly and the Cramér-Rao covariance
    ``(Σ J_sᵀ R_s⁻¹ J_s)⁻¹`` at it; with noise the fit equals an independent ML solver
    (``scipy.optimize.least_squares``) on the whitened residuals."""
    from scipy.optimize import least_squares

    rng = np.random.default_rng(4)
    pos = np.array([[-20000.0, 30000.0], [15000.0, 25000.0], [-3000.0, 40000.0]])
    x_true = np.zeros((3, 4))
    x_true[:, [0, 2]] = pos
    hit = np.array([[True, True, True], [True, False, True], [False, True, False]])
    z = np.stack([m.h(x_true) for m in SENSORS], axis=1)  # (3 tuples, 3 sensors, 2)
    x_ref = x_true[0] + np.array([800.0, 0.0, -600.0, 0.0])
    o, zeta, R_eq = equivalent_measurement(z, hit, SENSORS, x_ref, tol=1e-9)
    assert o.tolist() == [0, 2]
    np.testing.assert_allclose(zeta, pos, atol=1e-6)
    for i in range(3):
        info = sum(
            m.jacobian(x_true[i])[:, o].T @ np.linalg.inv(m.R) @ m.jacobian(x_true[i])[:, o]
            for s, m in enumerate(SENSORS)
            if hit[i, s]
        )
        np.testing.assert_allclose(R_eq[i], np.linalg.inv(info), rtol=1e-6)
    noisy = z + rng.standard_normal(z.shape) * np.array([200.0, 0.02])
    _, zeta_n, _ = equivalent_measurement(noisy, hit, SENSORS, x_ref, tol=1e-9)
    # the default tolerance (0.02 standard deviations per step) stops within 0.01 of one
    _, zeta_d, R_d = equivalent_measurement(noisy, hit, SENSORS, x_ref)
    d = zeta_d - zeta_n
    assert np.all(np.einsum("li,lij,lj->l", d, np.linalg.inv(R_d), d) < 0.01**2)
    for i in range(3):
        used = [s for s in range(3) if hit[i, s]]

        def resid(p, i=i, used=used):
            x = np.zeros(4)
            x[[0, 2]] = p
            out = []
            for s in used:
                d = noisy[i, s] - SENSORS[s].h(x)
                d[1] = wrap_angle(d[1])
                out.append(np.linalg.cholesky(np.linalg.inv(SENSORS[s].R)).T @ d)
            return np.concatenate(out)

        ref = least_squares(resid, x_ref[[0, 2]], xtol=1e-12, ftol=1e-12).x
        np.testing.assert_allclose(zeta_n[i], ref, atol=1e-3)


def _two_target_terms(seed: int):
    rng = np.random.default_rng(seed)
    xp = np.array([[-17000.0, 400.0, 22000.0, -400.0], [-16800.0, 296.0, 22100.0, -400.0]])
    Pp = np.broadcast_to(np.diag([400.0**2, 30.0**2, 400.0**2, 30.0**2]), (2, 4, 4))
    z = []
    for m in SENSORS:
        zt = m.h(xp) + rng.standard_normal((2, 2)) * np.sqrt(np.diag(m.R))
        zc = m.h(xp[:1]) + rng.uniform(-3, 3, (2, 2)) * np.sqrt(np.diag(m.R))
        z.append(np.concatenate([zt, zc]))
    lam = (1e-6, 2e-6, 4e-6)
    cfg = FusionConfig((0.8, 0.7, 0.9), lam, 0.99)
    return xp, Pp, z, cfg


@pytest.mark.parametrize("seed", range(3))
def test_tuple_marginals_equal_enumeration_of_eq21(seed: int) -> None:
    """β_t(L) from per-sensor JPDA marginals equals the explicit sum over S-D joint events."""
    xp, Pp, z, cfg = _two_target_terms(seed)
    terms = sensor_terms(xp, Pp, z, SENSORS, cfg)
    w = np.exp(terms.log_w)  # eq. 21 factors (S, T, M+1)
    target, L, beta = tuple_marginals(terms.beta)
    assert np.all(np.diff(target) >= 0)
    L0, b0 = L[target == 0], beta[target == 0]
    L1, b1 = L[target == 1], beta[target == 1]
    joint = np.zeros((len(L0), len(L1)))
    for a, b in itertools.product(range(len(L0)), range(len(L1))):
        if np.any((L0[a] > 0) & (L0[a] == L1[b])):
            continue  # a measurement of one sensor given to both targets
        joint[a, b] = np.prod(w[np.arange(3), 0, L0[a]]) * np.prod(w[np.arange(3), 1, L1[b]])
    joint /= joint.sum()
    np.testing.assert_allclose(b0, joint.sum(axis=1), atol=1e-12)
    np.testing.assert_allclose(b1, joint.sum(axis=0), atol=1e-12)
    # the per-sensor marginals themselves: jpda_marginals on association_weights
    m = SENSORS[0]
    S, _ = innovation_gain(Pp, m.jacobian(xp), m.R)
    g = gate(m.h(xp), S, z[0], chi2_threshold(0.99, 2), angle_mask=m.angle_mask)
    W = association_weights(g.log_likelihood(), g.valid, 0.8, 0.99, 1e-6)
    np.testing.assert_allclose(terms.beta[0], jpda_marginals(W).beta, atol=1e-12)


def _subset_ekf(x, P, z, hit):
    """Stacked EKF oracle over the sensors ``hit`` of one tuple (prediction if none)."""
    used = [s for s in range(3) if hit[s]]
    if not used:
        return x, P
    H = np.concatenate([SENSORS[s].jacobian(x) for s in used])
    R = np.zeros((2 * len(used), 2 * len(used)))
    y = np.empty(2 * len(used))
    for i, s in enumerate(used):
        R[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = SENSORS[s].R
        d = z[s] - SENSORS[s].h(x)
        y[2 * i : 2 * i + 2] = [d[0], wrap_angle(d[1])]
    S, K = innovation_gain(P, H, R)
    return gain_update(x, P, y, K, S)


@pytest.mark.parametrize("seed", range(2))
def test_two_target_parallel_step_is_the_mixture_over_enumerated_events(seed: int) -> None:
    """All targets' tuples in one batch: each target's posterior equals the moment-matched
    mixture, over its tuples, of the stacked EKF oracle weighted by the enumerated eq. 21."""
    xp, Pp, z, cfg = _two_target_terms(seed)
    x, P = xp.copy(), Pp.copy()  # zero time step: the prediction is the prior
    xn, Pn, _ = fusion_step("parallel", x, P, z, [0.0] * 3, SENSORS, MOTION, cfg)
    terms = sensor_terms(xp, Pp, z, SENSORS, cfg)
    target, L, beta = tuple_marginals(terms.beta)
    for t in range(2):
        comps = []
        for Lt, bt in zip(L[target == t], beta[target == t], strict=True):
            zt = [z[s][Lt[s] - 1] if Lt[s] > 0 else None for s in range(3)]
            comps.append((bt, *_subset_ekf(xp[t], Pp[t], zt, Lt > 0)))
        xm = sum(b * xc for b, xc, _ in comps)
        Pm = sum(b * (Pc + np.outer(xc - xm, xc - xm)) for b, xc, Pc in comps)
        np.testing.assert_allclose(xn[t], xm, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(Pn[t], Pm, rtol=1e-7, atol=1e-6)


def test_equivalent_measurement_not_converged_keeps_the_linearised_step(gauss_newton: str) -> None:
    """A target passing over sensor 1 (true range 150 m, measured range below zero): the
    Gauss-Newton fit of that single detection does not settle; the tuple keeps its first,
    prediction-linearised step."""
    x_ref = np.array([-450.0, 300.0, -360.0, -400.0])
    z = np.array([[[-250.0, 1.2], [0.0, 0.0], [0.0, 0.0]]])
    hit = np.array([[True, False, False]])
    _, z10, R10 = equivalent_measurement(z, hit, SENSORS, x_ref, iterations=10)
    _, z1, R1 = equivalent_measurement(z, hit, SENSORS, x_ref, iterations=1, tol=np.inf)
    np.testing.assert_allclose(z10, z1)
    np.testing.assert_allclose(R10, R1)


@pytest.mark.parametrize("seed", range(2))
def test_joint_tuple_likelihood_marginals_equal_enumeration(seed: int) -> None:
    """``sdcmsjpda_joint``: each joint event of the two targets weighted by the stacked
    Gaussian of every tuple's innovations (scipy, covariance ``H P Hᵀ + R`` over the tuple's
    sensors, cross-blocks included) times the detection / clutter factors; and with a tiny
    prediction covariance (no shared prediction error) the factorised marginals of eq. 15."""
    from scipy.stats import multivariate_normal

    xp, Pp, z, cfg = _two_target_terms(seed)
    terms = sensor_terms(xp, Pp, z, SENSORS, cfg)
    target, L, _ = tuple_marginals(terms.beta)
    beta = joint_tuple_marginals(Pp, target, L, terms, SENSORS, cfg)
    pd, lam = np.array(cfg.pd), np.array(cfg.clutter_density)

    def weight(t: int, Lt: np.ndarray) -> float:
        used = [s for s in range(3) if Lt[s] > 0]
        w = np.prod([pd[s] / lam[s] if Lt[s] else 1 - pd[s] * 0.99 for s in range(3)])
        if not used:
            return float(w)
        H = np.concatenate([SENSORS[s].jacobian(xp[t]) for s in used])
        R = np.zeros((2 * len(used),) * 2)
        nu = []
        for i, s in enumerate(used):
            R[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = SENSORS[s].R
            d = z[s][Lt[s] - 1] - SENSORS[s].h(xp[t])
            nu += [d[0], wrap_angle(d[1])]
        return float(w * multivariate_normal(np.zeros(len(nu)), H @ Pp[t] @ H.T + R).pdf(nu))

    L0, L1 = L[target == 0], L[target == 1]
    w0, w1 = [weight(0, x) for x in L0], [weight(1, x) for x in L1]
    joint = np.zeros((len(L0), len(L1)))
    for a, b in itertools.product(range(len(L0)), range(len(L1))):
        if not np.any((L0[a] > 0) & (L0[a] == L1[b])):
            joint[a, b] = w0[a] * w1[b]
    joint /= joint.sum()
    np.testing.assert_allclose(beta[target == 0], joint.sum(axis=1), rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(beta[target == 1], joint.sum(axis=0), rtol=1e-6, atol=1e-12)
    # no common prediction error: the joint likelihood is eq. 15's product
    tiny = Pp * 1e-8
    terms_t = sensor_terms(xp, tiny, z, SENSORS, FusionConfig(cfg.pd, cfg.clutter_density, 1.0))
    tt, Lt, bt = tuple_marginals(terms_t.beta)
    cfg1 = FusionConfig(cfg.pd, cfg.clutter_density, 1.0)
    np.testing.assert_allclose(joint_tuple_marginals(tiny, tt, Lt, terms_t, SENSORS, cfg1), bt,
                               rtol=1e-6, atol=1e-12)  # fmt: skip


@pytest.mark.parametrize("seed", range(3))
def test_sd_gnn_equals_per_sensor_2d_assignment(seed: int) -> None:
    """Additive tuple costs: the (S+1)-D optimum is the per-sensor 2-D optimum."""
    xp, Pp, z, cfg = _two_target_terms(seed)
    terms = sensor_terms(xp, Pp, z, SENSORS, cfg)
    L, _ = sd_gnn_tuples(terms, 10_000)
    for s in range(3):
        lw = terms.log_w[s, :, : len(z[s]) + 1]
        ref = assign2d(-lw[:, 1:], -lw[:, 0])
        np.testing.assert_array_equal(L[:, s], ref.track_to_meas + 1)


def test_mismatched_time_stamps() -> None:
    off = np.array([0.0, 0.3, 0.6])
    _, scans = _one_target_scans(30, np.random.default_rng(2), off)
    cfg = FusionConfig((0.97,) * 3, (1e-7,) * 3)
    for alg in ("parallel", "sdcmsjpda", "sd_gnn"):
        with pytest.raises(ValueError, match=r"scan 0: sensor 2 time stamp 0\.600000 s"):
            run_fusion(alg, scans, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
    r = run_fusion("sequential", scans, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
    # estimates are at the last sensor's time (k + 0.6 s)
    tr = np.stack([MOTION.f(X0[0], k + 0.6) for k in range(30)])
    err = np.hypot(*(r.x[:, 0, [0, 2]] - tr[:, [0, 2]]).T)
    assert np.sqrt(np.mean(err[10:] ** 2)) < 150.0
    back = MultiScans(scans.z, scans.valid, scans.t_s[::-1])
    with pytest.raises(ValueError, match="before"):
        run_fusion("sequential", back, SENSORS, MOTION, X0, P0, cfg)


def test_silent_sensor_is_counted_and_tracking_continues() -> None:
    truth, scans = _one_target_scans(60, np.random.default_rng(3))
    valid = scans.valid.copy()
    valid[10:50, 2] = False  # sensor 3 reports nothing for 40 scans
    silent = MultiScans(np.where(valid[..., None], scans.z, np.nan), valid, scans.t_s)
    cfg = FusionConfig((0.97,) * 3, (1e-7,) * 3, false_per_gate=1.8)
    for alg in ALGORITHMS:
        r = run_fusion(alg, silent, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
        np.testing.assert_array_equal(r.empty_scans, [0, 0, 40])
        np.testing.assert_array_equal(r.longest_silence, [0, 0, 40])
        err = np.hypot(*(r.x[:, 0, [0, 2]] - truth[:, [0, 2]]).T)
        assert np.sqrt(np.mean(err[10:] ** 2)) < 250.0, alg


def test_bad_configuration() -> None:
    with pytest.raises(ValueError, match=r"pd\[1\]"):
        FusionConfig((0.9, 1.5), (1e-6, 1e-6))
    with pytest.raises(ValueError, match="one value per sensor"):
        FusionConfig((0.9,), (1e-6, 1e-6))
    _, scans = _one_target_scans(3, np.random.default_rng(4))
    with pytest.raises(ValueError, match="3 sensors"):
        run_fusion(
            "parallel", scans, SENSORS[:2], MOTION, X0, P0, FusionConfig((0.9,) * 2, (1e-6,) * 2)
        )
    z = scans.z.copy()
    z[1, 0, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"z\[1, 0, 0\]"):
        MultiScans(z, scans.valid, scans.t_s)


def test_measure_stacks_the_sensors_models() -> None:
    """Range-bearing sensors of one convention are evaluated together; any other set one
    model at a time; both equal each model's own h and Jacobian."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(7, 4)) * 10_000.0
    north = RangeBearing(np.diag([100.0**2, 0.01**2]), np.array([300.0, -200.0]), from_north=True)
    hook = FunctionMeasurement(SENSORS[0].h, SENSORS[0].R, 4, SENSORS[0].jacobian)
    for models in (SENSORS, [SENSORS[0], north], [hook, SENSORS[1]]):
        z, H = measure(models, x)
        assert z.shape == (7, len(models), 2)
        assert H.shape == (7, len(models), 2, 4)
        for s, m in enumerate(models):
            np.testing.assert_allclose(z[:, s], m.h(x), rtol=1e-14)
            np.testing.assert_allclose(H[:, s], m.jacobian(x), rtol=1e-14)
    with pytest.raises(ValueError, match="one dim_z"):
        measure([SENSORS[0], linear_position(4, (0, 2, 1), 10.0)], x)


def test_equivalent_measurement_of_linear_sensors_is_the_information_mean() -> None:
    """Three observed components (the general solve, not the 2 x 2 closed form): linear
    position sensors fuse to the information-weighted mean in one step."""
    rng = np.random.default_rng(6)
    sig = [10.0, 20.0, 40.0]
    sensors = [linear_position(6, (0, 2, 4), s_) for s_ in sig]
    z = rng.normal(size=(5, 3, 3)) * 30.0
    hit = np.array([[1, 1, 1], [1, 0, 1], [0, 1, 0], [1, 1, 0], [0, 0, 1]], dtype=bool)
    o, zeta, R_eq = equivalent_measurement(z, hit, sensors, np.zeros(6))
    assert o.tolist() == [0, 2, 4]
    w = hit / np.square(sig)  # (tuples, sensors) information per axis
    np.testing.assert_allclose(zeta, np.einsum("ls,lsi->li", w, z) / w.sum(1)[:, None])
    np.testing.assert_allclose(R_eq, np.eye(3) / w.sum(1)[:, None, None])


def test_all_sensors_silent_for_a_while() -> None:
    """Scans where no sensor reports are predictions only, for every tracker."""
    truth, scans = _one_target_scans(40, np.random.default_rng(7))
    valid = scans.valid.copy()
    valid[15:20] = False
    quiet = MultiScans(np.where(valid[..., None], scans.z, np.nan), valid, scans.t_s)
    cfg = FusionConfig((0.97,) * 3, (1e-7,) * 3, false_per_gate=1.8)
    for alg in ALGORITHMS:
        r = run_fusion(alg, quiet, SENSORS, MOTION, X0, P0, cfg, t0_s=0.0)
        np.testing.assert_array_equal(r.longest_silence, [5, 5, 5])
        xp = MOTION.f(r.x[14, 0], 1.0)
        np.testing.assert_allclose(r.x[15, 0], xp, rtol=1e-12)  # prediction only
        assert np.all(np.diff(np.trace(r.P[14:20, 0], axis1=-2, axis2=-1)) > 0), alg
        err = np.hypot(*(r.x[:, 0, [0, 2]] - truth[:, [0, 2]]).T)
        assert np.sqrt(np.mean(err[25:] ** 2)) < 250.0, alg


@pytest.mark.parametrize(("position_index", "from_north"), [((0, 2), False), ((2, 0), True)])
def test_compiled_gauss_newton_equals_the_numpy_loop(
    position_index: tuple[int, int], from_north: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The compiled range-bearing loop and the NumPy loop of ``equivalent_measurement`` give
    the same equivalent measurements (rounding only) on noisy tuples of 1-3 detections, also
    with the position components in reverse order and bearings from north."""
    if equivalent.compiled_gauss_newton() is None:
        pytest.skip("numba is not installed")
    sensors = [RangeBearing(m.R, m.sensor_xy, position_index, 4, from_north) for m in SENSORS]
    rng = np.random.default_rng(11)
    x = np.zeros((200, 4))
    x[:, list(position_index)] = rng.uniform([-30000, 20000], [30000, 40000], (200, 2))
    z = measure(sensors, x)[0] + rng.standard_normal((200, 3, 2)) * np.array([200.0, 0.02])
    hit = rng.random((200, 3)) < 0.7
    hit[~hit.any(axis=1), 1] = True
    x_ref = x + rng.normal(0.0, 400.0, x.shape)
    compiled = equivalent.equivalent_measurement(z, hit, sensors, x_ref)
    monkeypatch.setattr(equivalent, "compiled_gauss_newton", lambda: None)
    plain = equivalent.equivalent_measurement(z, hit, sensors, x_ref)
    np.testing.assert_array_equal(compiled[0], plain[0])
    np.testing.assert_allclose(compiled[1], plain[1], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(compiled[2], plain[2], rtol=1e-9)
