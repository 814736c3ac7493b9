"""Carrier-phase series of the ARI reproduction (paper 5, Tables 1–3 in the paper's regime).

Data: the GEONET 0759/3040 static baseline bundled with navtrack (always present) and the
shared Yamatogawa rover/master pair (skipped when ``shared/data`` is absent). Oracles: the RTK
status counts measured in ``docs/rtk.md`` (all 120 epochs of 0759/3040 fixed), the partition
property of the strips, and the agreement of the two VCE forms on the same strip.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments.ari.carrier import (
    RTK_RUNS,
    CarrierSeries,
    carrier_rows,
    carrier_series,
    carrier_sources,
    strip_bounds,
)
from navtrack.experiments.ari.regime_tables import regime_lines
from navtrack.experiments.contract import shared_data_dir


@pytest.mark.parametrize(("n", "length", "k"), [(193, 130, 1), (120, 130, 1), (400, 130, 3)])
def test_strips_partition_the_series(n: int, length: int, k: int) -> None:
    bounds = strip_bounds(n, length)
    assert len(bounds) == k
    assert bounds[0][0] == 0
    assert bounds[-1][1] == n
    assert all(a[1] == b[0] for a, b in itertools.pairwise(bounds))
    sizes = [b - a for a, b in bounds]
    assert max(sizes) - min(sizes) <= 1


def test_strip_bounds_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="strip_epochs"):
        strip_bounds(100, 0)


@pytest.fixture(scope="module")
def geonet() -> list[CarrierSeries]:
    run = next(r for r in RTK_RUNS if r.name == "geonet_0759_3040")
    return carrier_series(Path("unused"), run)


def test_geonet_baseline_series_is_fixed_at_every_epoch(geonet: list[CarrierSeries]) -> None:
    fixed, flt = geonet
    assert fixed.meta["rtk_status"] == {"fix": 120}
    assert flt.meta["rtk_status"] == {"float": 120}
    assert fixed.dt_s == pytest.approx(30.0)
    for series in geonet:
        for col, values in series.columns.items():
            assert values.size == 120
            assert np.all(np.isfinite(values))
            assert abs(float(np.mean(values))) < 1e-6  # about the mean
            # a static antenna: epoch positions within decimetres of their mean
            assert float(np.max(np.abs(values))) < 0.2, col
            assert np.all(series.sd_m[col] > 0)


def test_strip_fits_give_both_vce_forms_and_the_bic_ranking(geonet: list[CarrierSeries]) -> None:
    fixed = geonet[0]
    one = type(fixed)(
        fixed.source, fixed.dt_s, {"e_m": fixed.columns["e_m"]}, fixed.sd_m, fixed.meta
    )
    (row,) = carrier_rows([one], 130, robust_process=True)
    assert row["n"] == 120
    assert row["strip"] == 1
    ex, red, fo = row["exact"], row["paper_redundancy"], row["paper_forstner"]
    assert ex["status"] == "ok"
    assert red["order"] == fo["order"] == ex["order"]
    # same model, same series: the frequency-domain redundancies move sigma_n by edge effects only
    assert fo["sigma_n"] == pytest.approx(red["sigma_n"], rel=0.1)
    assert row["bic_top"][0][2] == 0.0
    assert not row["bic_52_minus_best"] < 0.0  # the chosen order is the best (or (5,2) absent)
    assert row["ls_sd_rms"] > 0
    text = "\n".join(regime_lines({"carrier": [row], "carrier_skipped": []}))
    for heading in ("### Table 1", "### Table 2", "### Table 3", "ARI(5,2) come out"):
        assert heading in text
    assert f"| {fixed.source} | 1 | e_m | ({ex['order'][0]},{ex['order'][1]}) |" in text
    assert "## Variance components: redundancy numbers against Förstner" in text


def test_shared_rover_pair_is_solved_or_skipped_with_a_reason() -> None:
    gnss = shared_data_dir() / "gnss"
    series, skipped = carrier_sources(gnss)
    if not (gnss / "gogps_yamatogawa").is_dir():
        assert any("yamatogawa" in s for s in skipped)
        pytest.skip("shared/data absent")
    assert not skipped
    rover = next(s for s in series if s.source == "yamatogawa fixed")
    # docs/rtk.md: 23 fixed epochs of the combined solution, the first 10 without a base
    assert rover.meta["rtk_status"]["fix"] == 23
    assert rover.dt_s == pytest.approx(1.0)
    assert rover.meta["epochs"] == 193
