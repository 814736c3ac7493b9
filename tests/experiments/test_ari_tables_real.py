"""Paper Tables 1 and 2 on real series, Euler-angle artefacts, stated omissions.

Oracles: the trace of a covariance is invariant under rotation (RTKLIB's ECEF ``sdx sdy sdz``
against the ENU standard deviations of Table 2); a rotation about a fixed axis through
gimbal lock written as quaternions (where Euler yaw/roll must jump while the body turns
smoothly); known synthetic sigma_n for the strips.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments.ari import tables
from navtrack.experiments.ari.broad import broad_series, flag_causes
from navtrack.experiments.ari.real import (
    RealSeries,
    real_data_rows,
    solution_series,
    strip_rows,
    table2_rows,
)
from navtrack.smoothing.ari import AriConfig, fit_ari, simulate_ari


def test_table2_single_epoch_sd_keeps_the_ecef_trace(gnss_data: Path) -> None:
    path = gnss_data / "rtklib_spp" / "gsi0759_gps.pos"
    src = solution_series(path)
    ls = src.meta["ls_sd_rms_m"]
    raw = np.loadtxt(
        [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("%")],
        usecols=(7, 8, 9),
        dtype=float,
    )
    trace_ecef = float(np.mean(np.sum(raw**2, axis=1)))
    assert ls["e_m"] ** 2 + ls["n_m"] ** 2 + ls["u_m"] ** 2 == pytest.approx(trace_ecef, rel=1e-3)
    rows, _ = real_data_rows([src], AriConfig(order=(1, 1)))
    t2 = table2_rows(rows)
    assert [r["column"] for r in t2] == ["e_m", "n_m", "u_m"]
    assert all(r["ls_sd_rms"] > 0 and r["sigma_n"] > 0 for r in t2)
    assert all(r["paper"] is not None for r in rows)
    text = "\n".join(tables.table2_and_strip_lines({"table2": t2}))
    assert "Table 2" in text
    assert "gsi0759_gps.pos" in text


def test_euler_artefacts_marked_only_near_gimbal_lock(tmp_path: Path) -> None:
    scipy_io = pytest.importorskip("scipy.io")
    from scipy.spatial.transform import Rotation

    t = np.linspace(0.0, 1.0, 400)
    # pitch swept through 90 deg about the body y axis while yawing slowly: a smooth motion
    # whose yaw/roll representation jumps at the lock
    rot = Rotation.from_euler("ZYX", np.column_stack([0.3 * t, np.zeros_like(t), 0 * t])) * (
        Rotation.from_rotvec(np.outer(np.radians(60 + 60 * t), [0.0, 1.0, 0.0]))
    )
    quat = rot.as_quat()[:, [3, 0, 1, 2]]  # scalar first, as BROAD
    path = tmp_path / "lock.mat"
    trial = {"opt_quat": quat, "sampling_rate": 100.0}
    trial |= {"imu_gyr": np.zeros((t.size, 3)), "movement": np.ones(t.size)}  # BROAD's keys
    scipy_io.savemat(path, trial)
    src = broad_series(path, form="euler")
    mask = src.meta["model_error"]["yaw_deg"]
    pitch = np.abs(src.columns["pitch_deg"])
    assert src.meta["euler_artefact_epochs"] >= 1
    assert np.all(pitch[mask] > 80.0)
    # far from the lock nothing is marked
    assert not np.any(mask[pitch < 70.0])
    # the rotation-vector path of the same motion has no artefacts: no model errors at all
    assert "model_error" not in broad_series(path).meta


def _savemat_trial(path: Path, quat_xyzw: np.ndarray, rate_hz: float) -> None:
    scipy_io = pytest.importorskip("scipy.io")
    n = quat_xyzw.shape[0]
    trial = {"opt_quat": quat_xyzw[:, [3, 0, 1, 2]], "sampling_rate": rate_hz}
    trial |= {"imu_gyr": np.zeros((n, 3)), "movement": np.ones(n)}  # BROAD's keys
    scipy_io.savemat(path, trial)


def test_rotvec_path_is_the_angle_through_gimbal_lock(tmp_path: Path) -> None:
    from scipy.spatial.transform import Rotation

    # a turn about the body y axis from 60 to 120 deg of pitch: the Euler angles pass the
    # lock (yaw and roll jump by 180 deg), the turn itself is one angle growing linearly
    angle = np.linspace(60.0, 120.0, 301)
    rot = Rotation.from_rotvec(np.outer(np.radians(angle), [0.0, 1.0, 0.0]))
    path = tmp_path / "turn.mat"
    _savemat_trial(path, rot.as_quat(), 100.0)
    euler = broad_series(path, form="euler")
    assert np.nanmax(np.abs(np.diff(euler.columns["yaw_deg"]))) > 90.0
    src = broad_series(path)
    assert list(src.columns) == ["rotvec_x_deg", "rotvec_y_deg", "rotvec_z_deg"]
    np.testing.assert_allclose(src.columns["rotvec_y_deg"], angle - angle[0], atol=1e-9)
    np.testing.assert_allclose(src.columns["rotvec_x_deg"], 0.0, atol=1e-9)
    np.testing.assert_allclose(src.columns["rotvec_z_deg"], 0.0, atol=1e-9)


def test_flag_causes_find_a_spike_and_a_gap_edge() -> None:
    from scipy.spatial.transform import Rotation

    big_n, dec = 2000, 10
    t = np.arange(big_n) / 100.0
    rng = np.random.default_rng(2)
    rot = Rotation.from_rotvec(
        np.column_stack([0.3 * np.sin(t), 0.2 * t, np.zeros(big_n)])
    ) * Rotation.from_rotvec(np.radians(0.01) * rng.standard_normal((big_n, 3)))
    quat = rot.as_quat()
    quat[10 * 50] = (rot[10 * 50] * Rotation.from_rotvec([0.0, 0.0, np.radians(2.0)])).as_quat()
    quat[10 * 120 : 10 * 123 + 1] = np.nan  # tracking lost for epochs 120..123
    causes, levels = flag_causes(quat, np.zeros((big_n, 3)), dec)
    assert causes["optical_spike"][50]
    assert np.count_nonzero(causes["optical_spike"]) <= 0.15 * big_n / dec
    assert np.array_equal(np.flatnonzero(causes["gap_edge"]), [118, 119, 124, 125])
    assert levels["optical_spike_deg"] > 0.0


def test_strips_rms_recovers_sigma_n() -> None:
    rng = np.random.default_rng(6)
    y, _ = simulate_ari(rng, 1300, (-0.5,), 2, 0.02, 0.01)
    src = RealSeries("synthetic", np.arange(1300.0), {"e_m": y}, "m", 1.0)
    fits = {("synthetic", "e_m"): fit_ari(y, AriConfig(order=(1, 2), robust="off"))}
    strips = strip_rows([src], fits)
    assert len(strips) == 1
    assert len(strips[0]["sigma_n_strips"]) == 6
    assert strips[0]["rms_sigma_n"] == pytest.approx(0.02, rel=0.25)
    # the paper's estimator on the same strips
    assert len(strips[0]["paper_sigma_n_strips"]) == 6
    assert strips[0]["paper_rms_sigma_n"] == pytest.approx(0.02, rel=0.25)
    text = "\n".join(tables.table2_and_strip_lines({"strips": strips}))
    assert "| paper Table 1 (printed) | X | (5,2) | ~130 |" in text  # the printed row first
    assert "| synthetic | e_m | (1,2) | 130 |" in text


def test_table2_has_the_printed_rows_and_both_estimators() -> None:
    row = {"source": "RTKLIB x", "column": "e_m", "sigma_n": 0.02, "paper_sigma_n": 0.03}
    row |= {"ls_sd_rms": 0.5, "ratio": 0.04, "paper_ratio": 0.06}
    text = "\n".join(tables.table2_and_strip_lines({"table2": [row]}))
    # paper: ARI 0.021 m against the adjustment's 0.022 m (strips 3,4,5, X)
    assert "| paper, strips 3,4,5 (printed) | X | – | 0.021 | 0.022 | – | 0.955 |" in text
    assert "| RTKLIB x | e_m | 0.02 | 0.03 | 0.5 | 0.04 | 0.06 |" in text


def test_sarimax_skip_is_said() -> None:
    results = {"sarimax_skipped": "statsmodels is not installed", "sarimax": []}
    lines = tables.summary_lines(results)
    assert any("SARIMAX cross-check skipped" in ln for ln in lines)
    results |= {"runs": 0, "seed": 0, "backend": "serial", "synthetic": {}, "real": []}
    results["parameters"] = {"identifiable_crb": 0.1, "robust": "danish"}
    text = tables.tables_markdown(results)
    assert "**SARIMAX cross-check skipped:** statsmodels is not installed" in text


def test_attitude_rows_in_parallel_equal_serial_and_are_tabled(tmp_path: Path) -> None:
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(4)
    n = 3000  # 300 epochs after decimation by 10
    t = np.arange(n) / 100.0
    turn = Rotation.from_rotvec(np.column_stack([0.4 * np.sin(0.5 * t), 0.1 * t, 0.2 * t]))
    rot = turn * Rotation.from_rotvec(np.radians(0.05) * rng.standard_normal((n, 3)))
    quat = rot.as_quat()
    quat[10 * 150] = (rot[10 * 150] * Rotation.from_rotvec([np.radians(3.0), 0, 0])).as_quat()
    path = tmp_path / "trial.mat"
    _savemat_trial(path, quat, 100.0)
    src = broad_series(path, decimate=10)
    cfg = AriConfig(order=(1, 2))
    serial, _ = real_data_rows([src], cfg)
    strips: list[dict] = []
    parallel, _ = real_data_rows([src], cfg, workers=2, strips=strips)
    assert [r["sigma_n"] for r in parallel] == [r["sigma_n"] for r in serial]
    x = serial[0]
    assert x["column"] == "rotvec_x_deg"
    # the 3-deg spike about body x is flagged there and explained by the full-rate samples
    assert x["flags_explained"]["by_cause"]["optical_spike"] >= 1
    assert x["robust_process"] is not None  # a moving platform, both estimators
    assert x["robust_process"]["paper"]["n_process"] > 0
    euler = broad_series(path, decimate=10, form="euler")
    before, _ = real_data_rows([euler], cfg, further=False)
    assert all(r["paper"] is None and r["robust_process"] is None for r in before)
    text = "\n".join(tables.flag_and_process_lines(serial, before))
    assert "| BROAD trial | rotvec_x_deg |" in text
    assert "| BROAD trial | yaw_deg |" in text
    assert "## Robust treatment of the process equations (3)" in text
