"""Solid Earth tide (IERS 2010 step 1) and the Sun/Moon positions it needs."""

from __future__ import annotations

import numpy as np

from navtrack.gnss.tides import solid_tide_m, sun_moon_ecef_m
from navtrack.timescale import calendar_gps_seconds

# DEHANTTIDEINEL test cases of the IERS Conventions 2010 software (station, Sun, Moon ECEF m,
# and the displacement of the full model, steps 1 and 2)
IERS_CASES = [
    (
        (4075578.385, 931852.890, 4801570.154),
        (137859926952.015, 54228127881.4350, 23509422341.6960),
        (-179996231.920342, -312468450.131567, -169288918.592160),
        (0.07700420357108125891, 0.06304056321824967613, 0.05516568152597246810),
    ),
    (
        (1112189.660, -4842955.026, 3985352.284),
        (-54537460436.2357, 130244288385.279, 56463429031.5996),
        (300396716.912, 243238281.451, 120548075.939),
        (-0.02036831479592075833, 0.05658254776225972449, -0.07597679676871742227),
    ),
]


def test_step_1_is_the_iers_displacement_to_the_step_2_corrections() -> None:
    """Step 2 (frequency-dependent Love numbers) changes the displacement by at most about
    13 mm radially; step 1 alone is within 1 cm of the full model in each component."""
    for station, sun, moon, expected in IERS_CASES:
        got = solid_tide_m(np.array(station), np.array(sun), np.array(moon))
        np.testing.assert_allclose(got, expected, atol=0.01)
        assert np.linalg.norm(got - expected) > 1e-4  # step 2 is really left out


def test_sun_at_the_march_equinox_of_2021() -> None:
    """Equinox 2021-03-20 09:37 UTC (USNO): the Sun crosses the equator; the equation of time is
    -7.5 min, so it stands over 37.6 deg east (local noon 12:07.5 UTC at longitude 0)."""
    t = calendar_gps_seconds(2021, 3, 20, 9, 37, 0.0) + 18.0
    sun, _ = sun_moon_ecef_m(np.array([t]))
    lat = np.degrees(np.arcsin(sun[0, 2] / np.linalg.norm(sun[0])))
    lon = np.degrees(np.arctan2(sun[0, 1], sun[0, 0]))
    assert abs(lat) < 0.05
    assert abs(lon - 37.6) < 0.3
    assert abs(np.linalg.norm(sun[0]) / 1.496e11 - 0.996) < 0.002  # 0.996 au in late March


def test_moon_at_new_and_full_moon() -> None:
    """New moon 2021-03-13 10:21 UTC, full moon 2021-03-28 18:48 UTC (USNO): the Sun-Moon angle
    is within the Moon's ecliptic latitude (at most 5.15 deg) of 0 and 180 deg."""
    for day, hh, mm, angle in ((13, 10, 21, 0.0), (28, 18, 48, 180.0)):
        t = calendar_gps_seconds(2021, 3, day, hh, mm, 0.0) + 18.0
        sun, moon = sun_moon_ecef_m(np.array([t]))
        cos = sun[0] @ moon[0] / np.linalg.norm(sun[0]) / np.linalg.norm(moon[0])
        assert abs(np.degrees(np.arccos(cos)) - angle) < 5.3
        assert 356e6 < np.linalg.norm(moon[0]) < 407e6


def test_tide_over_a_day_has_the_expected_size() -> None:
    """At SEPT (35 deg N) the vertical tide spans a few decimetres over a day, horizontal
    centimetres."""
    station = np.array([-3962108.673, 3381309.574, 3668678.638])
    t = calendar_gps_seconds(2021, 3, 19, 0, 0, 0.0) + 900.0 * np.arange(96, dtype=np.float64)
    d = solid_tide_m(station, *sun_moon_ecef_m(t))
    up = d @ (station / np.linalg.norm(station))
    assert 0.15 < np.ptp(up) < 0.6
    horizontal = np.linalg.norm(d - up[:, None] * station / np.linalg.norm(station), axis=1)
    assert horizontal.max() < 0.1
