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
from navtrack.experiments.ari.real import (
    RealSeries,
    broad_series,
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
    text = "\n".join(tables._table2_and_strips({"table2": t2}))
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
    src = broad_series(path)
    mask = src.meta["model_error"]["yaw_deg"]
    pitch = np.abs(src.columns["pitch_deg"])
    assert src.meta["euler_artefact_epochs"] >= 1
    assert np.all(pitch[mask] > 80.0)
    # far from the lock nothing is marked
    assert not np.any(mask[pitch < 70.0])


def test_strips_rms_recovers_sigma_n() -> None:
    rng = np.random.default_rng(6)
    y, _ = simulate_ari(rng, 1300, (-0.5,), 2, 0.02, 0.01)
    src = RealSeries("synthetic", np.arange(1300.0), {"e_m": y}, "m", 1.0)
    fits = {("synthetic", "e_m"): fit_ari(y, AriConfig(order=(1, 2), robust="off"))}
    strips = strip_rows([src], fits)
    assert len(strips) == 1
    assert len(strips[0]["sigma_n_strips"]) == 6
    assert strips[0]["rms_sigma_n"] == pytest.approx(0.02, rel=0.25)


def test_sarimax_skip_is_said() -> None:
    lines = tables.summary_lines({"sarimax_skipped": "statsmodels is not installed"})
    assert any("SARIMAX cross-check skipped" in ln for ln in lines)
