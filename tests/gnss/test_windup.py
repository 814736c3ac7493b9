"""Carrier phase wind-up (Wu et al. 1993): hand-worked geometries and the one-cycle-per-turn
property."""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.gnss.windup import phase_windup_cyc, windup_angle_cyc

R_EARTH = 6378137.0
R_GPS = 26_560_000.0
AU = 1.496e11


def _overhead(sun_dir: list[float]) -> float:
    """Wind-up of a satellite straight above a receiver at latitude 0, longitude 0."""
    sat = np.array([[[R_GPS, 0.0, 0.0]]])
    sun = np.array([sun_dir]) * AU
    return float(phase_windup_cyc(sat, np.array([R_EARTH, 0.0, 0.0]), sun)[0, 0])


def test_hand_worked_overhead_geometries() -> None:
    """Receiver at (R, 0, 0): x north = +Z, y west = -Y; k = -X. Satellite axes z = -X,
    y = z x (Sun - sat), x = y x z.

    Sun towards +Z: y_s = +Y, x_s = +Z; D_sat = Z - (-X x Y) = 2Z, D_rcv = Z + (-X x -Y) = 2Z:
    aligned, 0 cycles. Sun towards +Y: y_s = -Z, x_s = +Y; D_sat = Y - (-X x -Z) = 2Y,
    D_rcv = 2Z; 90 deg and k . (D_sat x D_rcv) = -X . 4X < 0: -1/4 cycle.
    """
    assert _overhead([0.0, 0.0, 1.0]) == pytest.approx(0.0, abs=1e-9)
    assert _overhead([0.0, 1.0, 0.0]) == pytest.approx(-0.25, abs=1e-6)


def test_one_cycle_per_turn_of_the_receiver_antenna() -> None:
    """Turning the receiving antenna about the line of sight turns the phase with it: angle /
    360 deg cycles, one whole cycle after a full turn."""
    k = np.array([0.0, 0.0, -1.0])  # satellite at zenith, signal going down
    sat_x, sat_y = np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0])  # z = x x y down
    turn = np.linspace(0.0, 2.0 * np.pi, 73)
    rcv_x = np.stack([np.cos(turn), np.sin(turn), np.zeros_like(turn)], axis=1)
    rcv_y = np.stack([-np.sin(turn), np.cos(turn), np.zeros_like(turn)], axis=1)
    w = np.unwrap(windup_angle_cyc(k, sat_x, sat_y, rcv_x, rcv_y), period=1.0)
    np.testing.assert_allclose(np.abs(w - w[0]), turn / (2.0 * np.pi), atol=1e-9)


def test_satellite_yaw_turn_accumulates_one_cycle() -> None:
    """The Sun circling a satellite overhead turns its body once about the line of sight:
    the continuous wind-up ends one whole cycle from where it started, the raw angle stays in
    [-0.5, 0.5] only at the first epoch."""
    n = 97
    ang = np.linspace(0.0, 2.0 * np.pi, n)
    sun = AU * np.stack([np.zeros(n), np.cos(ang), np.sin(ang)], axis=1)
    sat = np.broadcast_to([R_GPS, 0.0, 0.0], (n, 1, 3))
    w = phase_windup_cyc(sat, np.array([R_EARTH, 0.0, 0.0]), sun)[:, 0]
    assert abs(w[-1] - w[0]) == pytest.approx(1.0, abs=1e-9)
    assert np.all(np.abs(np.diff(w)) < 0.02)  # no whole-cycle jumps between epochs


def test_missing_satellite_positions_stay_missing() -> None:
    sat = np.array([[[R_GPS, 0.0, 0.0]], [[np.nan, np.nan, np.nan]], [[R_GPS, 1e5, 0.0]]])
    sun = np.array([[0.0, 0.0, AU]] * 3)
    w = phase_windup_cyc(sat, np.array([R_EARTH, 0.0, 0.0]), sun)
    assert np.isnan(w[1, 0])
    assert np.isfinite(w[[0, 2], 0]).all()
