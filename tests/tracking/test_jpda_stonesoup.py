"""Cross-check with Stone Soup's JPDA on the paper-3 crossing-targets scenario.

Reference: Stone Soup (dstl/Stone-Soup) ``JPDA`` with ``PDAHypothesiser`` and the mixture
reduction of its JPDA tutorial; scenario of Zhang, Xiong & He (ICMLC 2005): targets
X1 = [-29500, 400, 34500, -400], X2 = [-26250, 296, 34500, -400] (m, m/s), one range-bearing
sensor at the origin, sigma_r = 300 m, sigma_theta = 0.03 rad, Pd = 0.97, 1.8 clutter per scan.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from navtrack.tracking.jpda import JpdaConfig, jpda_step, jpda_step_batch
from navtrack.tracking.models import RangeBearing, constant_velocity
from navtrack.tracking.simulate import paper3_scenario, simulate_detections, simulate_truth

sys.path.insert(0, str(Path(__file__).parent))


def _scenario(n_steps: int, seed: int):
    sc = paper3_scenario()
    rng = np.random.default_rng(seed)
    mot = constant_velocity(2, 1.0, "continuous")
    rb = RangeBearing(np.diag([sc["sigma_r_m"] ** 2, sc["sigma_theta_rad"] ** 2]))
    truth = simulate_truth(mot, sc["x0"], n_steps + 1, 1.0, rng)
    lo, hi = np.array([0.0, -np.pi]), np.array([50_000.0, np.pi])
    det = simulate_detections(truth[1:], rb, sc["pd"], sc["clutter_rate"], lo, hi, rng)
    lam = sc["clutter_rate"] / np.prod(hi - lo)
    return sc, mot, rb, [det.scan(k) for k in range(n_steps)], lam


@pytest.mark.parametrize("seed", [1, 2])
def test_jpda_equals_stonesoup_on_crossing_targets(seed: int) -> None:
    pytest.importorskip("stonesoup")
    from stonesoup_ref import run_stonesoup_jpda

    # steps 25..36 contain the crossing (t = 31.25 s), where both tracks share measurements
    n = 36
    sc, mot, rb, scans, lam = _scenario(n, seed)
    P0 = np.tile(np.diag([500.0**2, 50.0**2, 500.0**2, 50.0**2]), (2, 1, 1))
    B, X, P = run_stonesoup_jpda(scans, sc["x0"], P0, 1.0, 300.0, 0.03, 0.97, lam, 0.99)
    cfg = JpdaConfig(pd=0.97, clutter_density=lam, gate_probability=0.99)
    x, Pk = sc["x0"], P0
    shared_steps = 0
    for k in range(n):
        st = jpda_step(x, Pk, scans[k], mot.F(1.0), mot.Q(1.0), rb, cfg)
        x, Pk = st.x, st.P
        # measured (seeds 1, 2): |d beta| <= 1.6e-13, |d x| <= 1.0e-10 m, |d P| <= 1.3e-8 m²
        # (P up to 2.5e5 m²); the tolerances leave a factor of ~100 for other platforms
        np.testing.assert_allclose(st.marginals.beta, B[k], rtol=0, atol=1e-11)
        np.testing.assert_allclose(x, X[k], rtol=0, atol=1e-8)
        np.testing.assert_allclose(Pk, P[k], rtol=0, atol=1e-6)
        shared_steps += int(((B[k][:, 1:] > 0).sum(axis=0) >= 2).any())
    assert shared_steps > 0  # the comparison did exercise joint (not per-track) association


def test_jpda_tracks_both_crossing_targets() -> None:
    # no Stone Soup needed: both tracks stay on their own targets through the crossing
    # (t = 31.25 s) and end consistent with their covariance
    n = 80
    sc, mot, rb, scans, lam = _scenario(n, 3)
    rng = np.random.default_rng(3)
    truth = simulate_truth(mot, sc["x0"], n + 1, 1.0, rng)  # same seed -> same truth
    cfg = JpdaConfig(pd=0.97, clutter_density=lam, gate_probability=0.99)
    x = sc["x0"]
    P = np.tile(np.diag([500.0**2, 50.0**2, 500.0**2, 50.0**2]), (2, 1, 1))
    for k in range(n):
        st = jpda_step(x, P, scans[k], mot.F(1.0), mot.Q(1.0), rb, cfg)
        x, P = st.x, st.P
        pos = truth[k + 1][:, [0, 2]]
        own = np.hypot(*(x[:, [0, 2]] - pos).T)
        other = np.hypot(*(x[:, [0, 2]] - pos[::-1]).T)
        if k >= 40:  # targets > 1 km apart again: no swap, no track on the other target
            assert np.all(own < other), (k, own, other)
    # final error within the 99.9 % ellipse of the track's own position covariance (chi²₂)
    e = x[:, [0, 2]] - truth[n][:, [0, 2]]
    Ppos = P[:, [0, 2]][:, :, [0, 2]]
    nees = np.einsum("ti,tij,tj->t", e, np.linalg.inv(Ppos), e)
    assert np.all(nees < 13.8), nees
    # and well below one range-bearing measurement's error at ~45 km (sigma_theta r ~ 1.4 km)
    assert np.all(np.hypot(*e.T) < 300.0), np.hypot(*e.T)


@pytest.mark.parametrize("max_events", [20_000, 1])
def test_batched_runs_equal_single_runs(max_events: int) -> None:
    runs = [_scenario(40, s) for s in (11, 12, 13)]
    sc, mot, rb, _, lam = runs[0]
    cfg = JpdaConfig(pd=0.97, clutter_density=lam, gate_probability=0.99)
    P0 = np.diag([500.0**2, 50.0**2, 500.0**2, 50.0**2])
    xs = [sc["x0"]] * 3
    Ps = [np.tile(P0, (2, 1, 1))] * 3
    xb, Pb = np.stack(xs), np.stack(Ps)
    for k in range(40):
        scans = [r[3][k] for r in runs]
        M = max(len(s) for s in scans)
        zb = np.full((3, M, 2), np.nan)
        vb = np.zeros((3, M), dtype=bool)
        for r, s in enumerate(scans):
            zb[r, : len(s)] = s
            vb[r, : len(s)] = True
        b = jpda_step_batch(xb, Pb, zb, vb, mot.F(1.0), mot.Q(1.0), rb, cfg, max_events)
        xb, Pb = b.x, b.P
        for r in range(3):
            st = jpda_step(xs[r], Ps[r], scans[r], mot.F(1.0), mot.Q(1.0), rb, cfg)
            xs[r], Ps[r] = st.x, st.P
            np.testing.assert_allclose(xb[r], st.x, rtol=1e-10, atol=1e-6)
            beta_r = b.marginals.beta.reshape(3, 2, M + 1)[r, :, : len(scans[r]) + 1]
            np.testing.assert_allclose(beta_r, st.marginals.beta, atol=1e-10)


def test_empty_scan_is_pure_prediction() -> None:
    sc, mot, rb, _, lam = _scenario(1, 0)
    cfg = JpdaConfig(pd=0.97, clutter_density=lam, gate_probability=0.99)
    P = np.tile(np.diag([500.0**2, 50.0**2, 500.0**2, 50.0**2]), (2, 1, 1))
    st = jpda_step(sc["x0"], P, np.zeros((0, 2)), mot.F(1.0), mot.Q(1.0), rb, cfg)
    np.testing.assert_array_equal(st.marginals.beta, np.ones((2, 1)))
    np.testing.assert_allclose(st.x, st.x_pred)
    np.testing.assert_allclose(st.P, st.P_pred)
