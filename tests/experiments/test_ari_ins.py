"""Navigation-grade INS attitude series of the ARI reproduction (paper 5, Tables 4–5 regime).

Data: the pyins car's GNSS velocities (``shared/data/trajectory/pyins_gnss``; skipped when
absent). Oracles: the heading of the velocity vector at the 1 Hz samples (the spline passes
through them), the perfect initial alignment, and the LN-200 data sheet's angle random walk
(0.07 °/√h: an attitude step of 0.07 / 60 · √0.1 = 3.69e-4 ° over 0.1 s).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from navtrack.experiments.ari.ins import INS_COLUMNS, ins_rows, ins_series, vehicle_attitude
from navtrack.experiments.contract import shared_data_dir

GNSS_CSV = shared_data_dir() / "trajectory" / "pyins_gnss" / "gnss.csv"
pytestmark = pytest.mark.skipif(not GNSS_CSV.exists(), reason="shared/data absent")


def test_vehicle_heading_is_the_velocity_direction_at_the_gnss_epochs() -> None:
    t, q = vehicle_attitude(GNSS_CSV, 10.0)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.allclose(np.diff(t), 0.1)
    df = pd.read_csv(GNSS_CSV)
    fast = np.hypot(df["VN"].to_numpy(), df["VE"].to_numpy()) > 5.0
    yaw = Rotation.from_quat(q).as_euler("ZYX")[:, 0]
    checked = 0
    for k in np.flatnonzero(fast)[::25]:
        j = int(np.argmin(np.abs(t - df["time"].iloc[k])))
        if abs(t[j] - df["time"].iloc[k]) > 5e-3:
            continue
        expect = math.atan2(df["VE"].iloc[k], df["VN"].iloc[k])
        diff = (yaw[j] - expect + math.pi) % (2 * math.pi) - math.pi
        # the grid epoch is within 5 ms of the GNSS epoch: < 0.1 deg at the car's turn rates
        assert abs(diff) < 2e-3
        checked += 1
    assert checked > 10


def test_ins_error_starts_at_zero_and_steps_like_the_angle_random_walk() -> None:
    series = ins_series(GNSS_CSV, np.random.default_rng(3))
    two_s, ten_hz = series
    assert two_s.dt_s == 2.0
    assert ten_hz.dt_s == 0.1
    assert ten_hz.columns["yaw_deg"].size == 3000  # the central 5 min
    assert two_s.error_deg["roll_deg"][0] == pytest.approx(0.0, abs=1e-9)  # perfect alignment
    arw_step = 0.07 / 60.0 * math.sqrt(0.1)
    step = np.sqrt(np.mean(np.diff(ten_hz.error_deg["yaw_deg"]) ** 2))
    assert step == pytest.approx(arw_step, rel=0.1)
    for col in INS_COLUMNS:
        err = two_s.error_deg[col]
        # 1 deg/h bias over the 13 min drive, plus the random walk: tenths of a degree at most
        assert float(np.max(np.abs(err))) < 0.5


def test_ins_rows_fit_the_column_and_its_motion_alone() -> None:
    two_s = ins_series(GNSS_CSV, np.random.default_rng(3), readouts=((2.0, 200),))[0]
    one = dataclasses.replace(
        two_s,
        columns={"pitch_deg": two_s.columns["pitch_deg"]},
        error_deg={"pitch_deg": two_s.error_deg["pitch_deg"]},
    )
    (row,) = ins_rows([one], robust_process=True)
    assert row["n"] == 200
    assert row["exact"]["status"] == "ok"
    assert row["paper_forstner"]["order"] == row["exact"]["order"]
    assert row["truth"]["status"] in ("ok", "boundary")
    assert "truth_deg" not in row["meta"]
    assert row["error_step_rms_deg"] > 0
