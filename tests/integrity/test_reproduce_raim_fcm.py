"""``navtrack reproduce raim-fcm`` on reduced parameters (the full study is run by the CLI)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments import ReproduceOptions, get_experiment, reproduce
from navtrack.experiments import raim_fcm as exp
from navtrack.experiments.raim_fcm.study import raim_config
from navtrack.experiments.runner import run_generator
from navtrack.integrity.ism import DEFAULT_ISM_PATH


def test_registered_and_validated() -> None:
    assert get_experiment("raim-fcm") is exp.EXPERIMENT
    with pytest.raises(ValueError, match="stations"):
        exp.RaimFcmParams(stations=("NOWHERE",))
    with pytest.raises(ValueError, match="methods"):
        exp.RaimFcmParams(methods=("magic",))


def test_injection_on_arl1_detects_and_identifies_single_faults(gnss_data: Path) -> None:
    params = exp.RaimFcmParams(
        stations=("ARL1",), biases_m=(30.0,), fault_counts=(1,), trials_per_run=15,
        methods=("rtklib", "fde", "fcm"),
    )  # fmt: skip
    runs = [exp.injection_run(params, run_generator(3, i), str(gnss_data)) for i in range(2)]
    s = exp.summarize_study(params, runs)["ARL1"]
    assert 0.0 < s["variance_factor"] < 1.0
    fault = s["cases"]["k1_b30"]
    assert fault["fde"]["trials"] == 30
    assert fault["fde"]["identification"] >= 0.9
    assert s["cases"]["clean"]["fde"]["wrong_exclusion"] == 0.0
    for m in ("rtklib", "fde", "fcm"):
        for key in ("detection", "identification", "wrong_exclusion", "misleading_h"):
            assert 0.0 <= fault[m][key] <= 1.0


def test_reproduce_writes_results_and_figures(tmp_path: Path, gnss_data: Path) -> None:
    pytest.importorskip("matplotlib")
    params = exp.RaimFcmParams(
        stations=("ARL1",), biases_m=(20.0,), fault_counts=(2,), trials_per_run=5,
        methods=("fde", "fcm"),
    )  # fmt: skip
    reproduce(
        "raim-fcm",
        ReproduceOptions(out_dir=tmp_path, runs=1, params=params, progress=False, backend="loop"),
    )
    res = json.loads((tmp_path / "results.json").read_text())
    assert res["example"]["double"]["fcm_gross_errors"] == [4, 7]
    assert set(res["injection"]["ARL1"]["cases"]) == {"clean", "k2_b20"}
    prot = res["clean_protection"]["ARL1"]["fde"]
    assert prot["epochs"] == 120
    assert prot["bounded_h"] == 1.0
    assert (tmp_path / "fcm_memberships.png").stat().st_size > 0
    assert (tmp_path / "stanford_ARL1.png").stat().st_size > 0
    assert "Paper example" in (tmp_path / "tables.md").read_text()
    assert np.isfinite(prot["hpl_median_m"])


def test_whole_day_protection_on_the_bundled_sample(monkeypatch: pytest.MonkeyPatch) -> None:
    """The whole-day step on the bundled SEPT sample standing in for a day station: a station
    runs only when both files are among the inputs; every method gives a row per run with no
    misleading information on this clean file."""
    from navtrack.data import REFERENCE_XYZ_M, sample_path
    from navtrack.experiments.raim_fcm import wholeday

    obs, nav = sample_path("SEPT078M_120.21O"), sample_path("SEPT078M.21P")
    x, y, z = REFERENCE_XYZ_M["SEPT078M_120.21O"]
    ref = (float(x), float(y), float(z))
    monkeypatch.setattr(
        wholeday, "DAY_STATIONS", {"SEPT": wholeday.DayStation(obs.name, nav.name, "GE", ref)}
    )
    assert wholeday.whole_day_protection([obs], ["fde"]) == ({}, {})
    res, art = wholeday.whole_day_protection([obs, nav], ["fde", "araim"])
    assert set(res) == {"SEPT GE L1", "SEPT GE IF", "SEPT G L1", "SEPT G IF"}
    for d in res.values():
        for v in d.values():
            assert v["epochs"] == 120
            assert v["mi_h"] == 0
            assert v["mi_v"] == 0
    assert res["SEPT GE IF"]["araim"]["availability_v"] == 1.0
    eh, hpl, ev, vpl = art["SEPT_GE_IF"]["araim"]
    assert eh.shape == hpl.shape == ev.shape == vpl.shape == (120,)


def test_the_study_takes_its_error_model_from_an_ism_file(tmp_path: Path) -> None:
    """``--set ism=FILE``: every method of the study (and ARAIM's priors) uses the file's
    ISM; empty, the default one."""
    raised = tmp_path / "ism.toml"
    raised.write_text(DEFAULT_ISM_PATH.read_text().replace("p_sat = 1e-5", "p_sat = 1e-3"))
    params = exp.RaimFcmParams(ism=str(raised))
    for method in ("rtklib", "fde", "araim"):
        ism = raim_config(params, method, 0.05).ism
        assert ism is not None
        assert ism.constellations["G"].p_sat == 1e-3
    assert raim_config(exp.RaimFcmParams(), "araim", 0.05).ism is None


def test_the_example_states_the_fuzziness_limit_under_both_stopping_rules() -> None:
    """The reproduction's paper example scans the FCM exponent: both faults (4, 7) are named
    for m <= 2 and only 7 at 2.5 and 3, stopping on the memberships or on the centres; the
    table in tables.md says so."""
    ex = exp.paper_example(2.0, "centres")
    assert ex["double"]["fcm_gross_errors"] == [4, 7]
    named = {row["m"]: row for row in ex["fuzziness_scan"]}
    assert sorted(named) == [1.5, 2.0, 2.5, 3.0]
    for m, faulty in ((1.5, [4, 7]), (2.0, [4, 7]), (2.5, [7]), (3.0, [7])):
        for stop in ("memberships", "centres"):
            assert named[m][stop]["fcm_gross_errors"] == faulty
    md = exp.tables_markdown({"example": ex})
    assert "| 2.5 | [7] (" in md
    assert "| 2 | [4, 7] (" in md


def test_the_study_offers_the_centre_stopping_rule() -> None:
    """``--set fcm_stop=centres`` reaches every method's RAIM configuration; another value
    is refused by name."""
    params = exp.RaimFcmParams(fcm_stop="centres")
    assert raim_config(params, "fcm", 0.05).fcm_stop == "centres"
    assert raim_config(exp.RaimFcmParams(), "fcm", 0.05).fcm_stop == "memberships"
    with pytest.raises(ValueError, match="fcm_stop"):
        exp.RaimFcmParams(fcm_stop="labels")
