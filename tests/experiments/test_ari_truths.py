"""Synthetic truths of the ARI reproduction against paper 5's printed statistics.

Oracles: the printed sigma_x / sigma_n and r(h) of Tables 1, 3, 4, 5 (paper 5), and the
closed-form partial autocorrelations of an AR(2) (Box & Jenkins: pi_1 = rho_1 = a_1 / (1 - a_2),
pi_2 = a_2 for x_t = a_1 x_{t-1} + a_2 x_{t-2} + e_t).
"""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.experiments.ari import SYNTHETIC_CASES
from navtrack.experiments.ari.truths import (
    filtered_statistics,
    fit_published,
    pacf_to_phi,
    printed_columns,
    printed_truths,
)


def test_pacf_to_phi_matches_ar2_closed_form() -> None:
    a1, a2 = 0.9, -0.4
    phi = pacf_to_phi([a1 / (1 - a2), a2])
    np.testing.assert_allclose(phi, [-a1, -a2], atol=1e-12)  # paper sign


@pytest.mark.parametrize("case", SYNTHETIC_CASES, ids=lambda c: c.name)
def test_truths_reproduce_the_printed_statistics(case) -> None:  # type: ignore[no-untyped-def]
    # strips of the printed length; the 2000-epoch GPS flight shares the strip's truth
    n = 130 if case.name == "gps_flight" else case.n
    ratio, r = filtered_statistics(case.phi, case.d, case.sigma_n, case.sigma_e, n)
    assert case.printed_ratio is not None
    assert ratio == pytest.approx(case.printed_ratio, abs=0.05)
    k = len(case.printed_r)
    np.testing.assert_allclose(r[:k], case.printed_r, atol=0.05)


def test_fit_published_finds_the_aircraft_yaw_truth() -> None:
    # Table 5 yaw: sigma_n 0.0023, sigma_e 0.0005, sigma_x 0.0011 deg, r 0.86 0.57 0.29 0.09
    phi, se, cost = fit_published(
        2, 2, 0.0023, 0.0005, 3000, 0.0011 / 0.0023, (0.86, 0.57, 0.29, 0.09)
    )
    assert se == 0.0005
    assert cost < 1.0  # hundredths
    ratio, r = filtered_statistics(phi, 2, 0.0023, 0.0005, 3000)
    assert ratio == pytest.approx(0.0011 / 0.0023, abs=0.02)
    np.testing.assert_allclose(r, (0.86, 0.57, 0.29, 0.09), atol=0.02)


def test_every_printed_column_is_listed_with_the_range_its_rounding_allows() -> None:
    cols = printed_columns()
    # GPS X/Y/Z for two strip groups (Tables 1, 3), Shuttle and aircraft yaw/pitch/roll
    assert len(cols) == 12
    for col in cols:
        lo, hi = col["ratio_range"]
        assert lo < col["ratio"] < hi
    shuttle_pitch = next(c for c in cols if c["table"] == "Shuttle INS" and c["column"] == "pitch")
    # Table 4: sigma_x 0.0027, sigma_n 0.0048 deg, printed to 1e-4
    assert shuttle_pitch["ratio_range"] == pytest.approx([0.00265 / 0.00485, 0.00275 / 0.00475])


def test_printed_truths_match_shuttle_yaw_and_not_aircraft_pitch() -> None:
    cols = {(c["table"], c["column"]): c for c in printed_columns()}
    rows = printed_truths(
        [cols[("Shuttle INS", "yaw")], cols[("Aircraft INS", "pitch")]], n_starts=2
    )
    yaw, pitch = rows
    assert yaw["matched"]
    assert yaw["max_deviation"] < 0.01
    # Table 5 pitch: sigma_x / sigma_n = 0.37 with sigma_e / sigma_n = 0.37 is out of reach of
    # the stationary ARI(2,2): the closest model's ratio is above 0.5
    assert not pitch["matched"]
    assert pitch["worst"] == "sigma_x/sigma_n"
    assert pitch["ratio_truth"] > 0.5
