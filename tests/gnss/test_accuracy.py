"""Accuracy statistics (navtrack.gnss.accuracy)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navtrack.gnss.accuracy import enu_error_stats, error_stats


def test_error_stats_hand_computed() -> None:
    # errors 1..20 m: mean 10.5, RMS sqrt(sum k^2 / 20) = sqrt(2870 / 20), and the definition-7
    # 95th percentile (Hyndman & Fan 1996) at position 1 + 0.95 * 19 = 19.05 -> 19.05 m.
    s = error_stats(np.arange(1.0, 21.0))
    assert s.n == 20
    assert s.mean_m == pytest.approx(10.5)
    assert s.rms_m == pytest.approx(math.sqrt(2870 / 20))
    assert s.p95_m == pytest.approx(19.05)


def test_error_stats_signed_and_nan() -> None:
    # signed errors: the mean keeps the sign, the percentile is of |x|; NaN epochs are left out
    s = error_stats([-3.0, -3.0, -3.0, -3.0, np.nan])
    assert (s.n, s.mean_m, s.rms_m, s.p95_m) == (4, -3.0, 3.0, 3.0)
    empty = error_stats([np.nan])
    assert empty.n == 0
    assert math.isnan(empty.rms_m)
    assert math.isnan(empty.p95_m)


def test_enu_error_stats_components() -> None:
    # (3, 4, 12): horizontal 5, 3D 13 (Pythagorean quadruple); the NaN row is left out
    st = enu_error_stats([[3.0, 4.0, 12.0], [3.0, 4.0, -12.0], [np.nan, 0.0, 0.0]])
    assert st["horizontal"].n == 2
    assert st["horizontal"].rms_m == pytest.approx(5.0)
    assert st["3D"].mean_m == pytest.approx(13.0)
    assert st["up"].mean_m == pytest.approx(0.0)
    assert st["up"].rms_m == pytest.approx(12.0)
    assert st["east"].mean_m == pytest.approx(3.0)
    with pytest.raises(ValueError, match="enu_m"):
        enu_error_stats(np.zeros((4, 2)))
