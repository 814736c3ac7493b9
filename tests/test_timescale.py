"""Time scales: GPS seconds, weeks, leap seconds and the RINEX time systems."""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.timescale import (
    calendar_gps_seconds,
    from_week_tow,
    gps_seconds,
    gps_to_utc,
    leap_seconds,
    to_datetime64,
    to_gps,
    utc_to_gps,
    week_tow,
)


def test_week_and_tow_of_known_dates() -> None:
    # IS-GPS-200: week 0 starts 1980-01-06; the first rollover (week 1024) was 1999-08-22 and
    # the second (week 2048) 2019-04-07.
    week, tow = week_tow(gps_seconds(["1999-08-22T00:00:00", "2019-04-07T00:00:00"]))
    assert week.tolist() == [1024, 2048]
    assert tow.tolist() == [0.0, 0.0]
    # The SEPT file starts 2021-03-19 12:00:00 GPST = GPS week 2149, tow 475200 (Friday 12:00);
    # the SP3 header of the same day gives week 2149 and 432000 s for 00:00.
    week, tow = week_tow(gps_seconds("2021-03-19T12:00:00"))
    assert (int(week), float(tow)) == (2149, 475200.0)


def test_calendar_fast_path_equals_datetime64_path() -> None:
    expected = gps_seconds("2005-04-02T00:48:00.004")
    assert calendar_gps_seconds(2005, 4, 2, 0, 48, 0.004) == pytest.approx(
        float(expected), abs=1e-9
    )


def test_round_trips() -> None:
    t = np.array([0.0, 1.5e9, 1300000123.456])
    np.testing.assert_allclose(gps_seconds(to_datetime64(t)), t, atol=1e-9)
    week, tow = week_tow(t)
    np.testing.assert_allclose(from_week_tow(week, tow), t)
    np.testing.assert_allclose(utc_to_gps(gps_to_utc(t)), t)


def test_leap_seconds_from_iers_bulletin_c() -> None:
    # GPST - UTC: 13 s in 2005, 17 s in 2016 (until 2016-12-31), 18 s since 2017-01-01 00:00 UTC.
    t = gps_seconds(["2005-04-02T00:00:00", "2016-08-22T21:46:13", "2021-03-19T12:00:00"])
    assert leap_seconds(t).tolist() == [13.0, 17.0, 18.0]
    # The leap second of 2017-01-01 takes effect at 00:00:00 UTC = 00:00:18 GPST.
    edge = gps_seconds(["2017-01-01T00:00:17", "2017-01-01T00:00:18"])
    assert leap_seconds(edge).tolist() == [17.0, 18.0]


def test_time_systems() -> None:
    t = float(gps_seconds("2021-03-19T12:00:00"))
    assert float(to_gps(t, "GAL")) == t
    assert float(to_gps(t, "BDT")) == t + 14.0
    assert float(to_gps(t, "UTC")) == t + 18.0
    # RINEX GLO time tags are UTC(SU), not GLONASST = UTC + 3 h (RINEX 3.05 section 6.1).
    assert float(to_gps(t, "GLO")) == t + 18.0
    with pytest.raises(ValueError, match="time_system"):
        to_gps(t, "XYZ")
