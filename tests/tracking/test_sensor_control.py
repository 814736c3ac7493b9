"""Foveal gain rules of paper 4 and the quadrature of the expected posterior variance.

Oracles: the linear-Gaussian (Kalman) posterior variance ``P R / (c² P + R)`` where the arctan is
linear (small gain); the scale invariance of the one-scan problem (the optimal ``c sqrt(P)`` does
not depend on ``P``); rule (1)'s printed branch ``log10(R)/8 - 0.4`` and switch R = 0.0146 (the
small-R exponent -0.630 is not legible in the paper; it is inferred from continuity there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from navtrack.tracking.trackers.sensor_control import (
    configure,
    expected_posterior_variance,
    foveal_gain,
    gain_exponent,
    optimal_gain,
    so_gain,
)


def test_rule1_printed_branch_above_the_switch():
    assert gain_exponent(0.05) == pytest.approx(math.log10(0.05) / 8 - 0.4)
    assert gain_exponent(0.0146) == pytest.approx(math.log10(0.0146) / 8 - 0.4)
    assert float(foveal_gain(0.1, 0.05)) == pytest.approx(0.1 ** (math.log10(0.05) / 8 - 0.4))


def test_rule1_small_noise_branch_is_continuous_at_the_switch():
    # the exponent below R = 0.0146 is inferred: the printed branch's value at the switch
    below, above = gain_exponent(0.0146 * (1 - 1e-9)), gain_exponent(0.0146)
    assert below == pytest.approx(above, abs=2e-3)
    assert gain_exponent(0.001) == below


def test_posterior_variance_quadrature_matches_kalman_in_the_linear_regime():
    P, R, c = 1.0, 0.05, 0.02  # |c u| < 0.15: arctan linear to 0.7 %
    v = expected_posterior_variance([c], P, R)[0]
    assert v == pytest.approx(P * R / (c * c * P + R), rel=2e-3)


def test_optimal_gain_scales_as_inverse_sd():
    k = [optimal_gain(P, 0.05) * math.sqrt(P) for P in (0.02, 0.5, 4.0)]
    assert max(k) - min(k) < 2e-3 * k[0]


def test_rule1_is_near_optimal_at_the_paper_noise():
    R = 0.05
    for P in (0.01, 0.1, 1.0):
        c_opt = optimal_gain(P, R)
        v = expected_posterior_variance([c_opt, float(foveal_gain(P, R))], P, R)
        assert v[0] <= v[1] < 1.05 * v[0]


def test_so_gain_reduces_to_spread_law_and_follows_the_optimum():
    R = 0.05
    a = gain_exponent(R)
    assert float(so_gain(2.0, 0.25, 0.25, R)) == pytest.approx((0.12 * (2.0 + 0.9) ** 2) ** a)
    for D, P in ((1.0, 0.2), (4.0, 0.5)):
        c_opt = optimal_gain(P, R, offset=[-D / 2, D / 2])
        assert abs(math.log(float(so_gain(D, P, P, R)) / c_opt)) < 0.3


def test_so_gain_near_three_target_optimum():
    # three targets at -D/2, 0, D/2 (the SO case of the reproduction): for spreads up to 4 m the
    # rule's summed expected posterior variance is within 10 % of the quadrature optimum's
    R = 0.05
    for D, P in ((2.0, 0.2), (4.0, 1.0)):
        off = [-D / 2, 0.0, D / 2]
        c_opt = optimal_gain(P, R, offset=off)
        v_opt, v_rule = expected_posterior_variance([c_opt, float(so_gain(D, P, P, R))], P, R, off)
        assert v_opt <= v_rule < 1.10 * v_opt


def test_configure_rules():
    x = np.array([[[0.0, 1.0], [2.0, 1.0], [5.0, 1.0]]])
    P = np.tile(np.eye(2), (1, 3, 1, 1))
    P[0, 1, 0, 0] = 3.0
    c, d, t = configure("wo", x, P, 0.05, 1)
    assert t[0] == 1
    assert d[0] == 2.0
    assert c[0] == pytest.approx(float(foveal_gain(3.0, 0.05)))
    for k, expect in ((1, 0), (2, 1), (3, 2), (4, 0)):
        assert configure("to", x, P, 0.05, k)[2][0] == expect
    c, d, t = configure("so", x, P, 0.05, 1)
    assert d[0] == 2.5
    assert t[0] == -1
    assert c[0] == pytest.approx(float(so_gain(5.0, 1.0, 1.0, 0.05)))


def test_bad_input():
    with pytest.raises(ValueError, match="R"):
        gain_exponent(0.0)
    with pytest.raises(ValueError, match="R"):
        so_gain(1.0, 1.0, 1.0, -1.0)
    with pytest.raises(ValueError, match="P"):
        foveal_gain(0.0, 0.05)
    with pytest.raises(ValueError, match="rule"):
        configure("xx", np.zeros((1, 2, 2)), np.tile(np.eye(2), (1, 2, 1, 1)), 0.05, 1)  # type: ignore[arg-type]
