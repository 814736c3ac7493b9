"""No misleading information on multi-GNSS data the error model was not chosen on: 20 min of
the IGS station TLSE on 2024-01-01 (GPS + Galileo + BeiDou, 30 s; a cut of jtec/prx's test
data, tests/data/README.md), judged against the IGS daily SINEX coordinate of the station."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments.raim_fcm import wholeday
from navtrack.integrity.raim import METHODS

DATA = Path(__file__).resolve().parents[1] / "data"

#: IGS0OPSSNX_20240010000_01D_01D_SOL.SNX marker of TLSE (10003M009) plus the 1.053 m antenna
#: height of the RINEX header along the ellipsoidal up (docs/integrity.md).
TLSE_2024_ARP_M = (4627852.3659, 119640.4029, 4372994.4955)


def test_no_method_misleads_on_tlse_multi_gnss(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every method, all systems and GPS alone, L1 and ionosphere-free: no epoch reported
    ``ok`` or ``excluded`` has its error above its HPL or VPL; ARAIM multi-GNSS
    ionosphere-free keeps VPL <= 35 m (LPV-200) on every epoch."""
    pytest.importorskip("hatanaka")
    obs = DATA / "TLSE00FRA_R_20240011800_01H_30S_MO_cut.crx.gz"
    nav = DATA / "BRDC00IGS_R_20240010000_01D_MN_cut.rnx.gz"
    station = wholeday.DayStation(obs.name, nav.name, "GEC", TLSE_2024_ARP_M)
    monkeypatch.setattr(wholeday, "DAY_STATIONS", {"TLSE": station})
    res, art = wholeday.whole_day_protection([obs, nav], list(METHODS))
    assert set(res) == {"TLSE GEC L1", "TLSE GEC IF", "TLSE G L1", "TLSE G IF"}
    for run in res.values():
        assert set(run) == set(METHODS)
        for v in run.values():
            assert v["epochs"] == 40
            assert v["statuses"]["ok"] + v["statuses"]["excluded"] == 40
            assert (v["mi_h"], v["mi_v"]) == (0, 0)
    araim = res["TLSE GEC IF"]["araim"]
    assert araim["vpl_le_val"] == 1.0
    assert araim["availability_v"] == 1.0
    eh, hpl, ev, vpl = art["TLSE_GEC_IF"]["araim"]
    assert np.all(eh < hpl)
    assert np.all(ev < vpl)
