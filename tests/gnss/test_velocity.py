"""Doppler velocity against independent truths: a static station (velocity 0) and the finite
differences of RTKLIB's RTK trajectory of a moving receiver (shared/data/gnss, README there)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.data import sample_path
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, SppStatus, solve_spp
from navtrack.gnss.velocity import DopplerVelocity, doppler_velocity
from navtrack.io.rtklib import read_pos

GPS = SppConfig(systems="G")


def _velocity(obs_path: Path, nav_path: Path) -> tuple[DopplerVelocity, np.ndarray, np.ndarray]:
    obs, nav = read_obs(obs_path), [read_nav(nav_path)]
    res = solve_spp(obs, nav, config=GPS)
    return doppler_velocity(obs, res, nav, config=GPS), res.status == SppStatus.OK, res.t_gps_s


def test_static_station_velocity_is_zero(gnss_data: Path) -> None:
    """ARL1 (GPSTk's static station, D1 Doppler): every component within a few cm/s rms of 0
    (measured 3, 2, 7 mm/s east, north, up); the one epoch with 3 Doppler satellites is NaN."""
    vel, ok, _ = _velocity(
        gnss_data / "gpstk_arl1" / "arlm200a.15o", gnss_data / "gpstk_arl1" / "arlm2000.15n"
    )
    v = vel.vel_enu_mps[ok]
    have = np.isfinite(v[:, 0])
    assert have.sum() == ok.sum() - 1
    assert np.all(vel.n_doppler[ok][~have] < 4)
    rms = np.sqrt(np.mean(v[have] ** 2, axis=0))
    assert np.all(rms < 0.02), rms


def test_moving_receiver_against_rtk_trajectory(gnss_data: Path) -> None:
    """Yamatogawa rover (a walk, up to 1.3 m/s): Doppler velocity against central differences
    of RTKLIB's RTK positions at the same epochs (their own noise and the 1 s steps limit the
    agreement: measured 0.22 m/s rms per axis)."""
    d = gnss_data / "gogps_yamatogawa"
    vel, ok, t = _velocity(d / "yamatogawa_rover.obs", d / "yamatogawa_rover.nav")
    ref = read_pos(d / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    tr = ref["t_gps_s"].to_numpy()
    xyz = ref[["x_m", "y_m", "z_m"]].to_numpy()
    v_ref = (xyz[2:] - xyz[:-2]) / (tr[2:] - tr[:-2])[:, None]
    t_mid = tr[1:-1]
    k = np.clip(np.searchsorted(t_mid, t), 0, t_mid.size - 1)
    match = ok & (np.abs(t_mid[k] - t) < 0.01)
    assert match.sum() > 150
    diff = vel.vel_mps[match] - v_ref[k[match]]
    assert np.all(np.sqrt(np.mean(diff**2, axis=0)) < 0.3)
    speed = np.linalg.norm(v_ref[k[match]], axis=1)
    assert speed.max() > 1.0  # the test would pass a zero velocity otherwise
    assert np.corrcoef(np.linalg.norm(vel.vel_mps[match], axis=1), speed)[0, 1] > 0.7


def test_no_doppler_gives_nan() -> None:
    """0759 has no Doppler observations: velocity NaN at every epoch, no error."""
    vel, _, _ = _velocity(sample_path("07590920.05o"), sample_path("07590920.05n"))
    assert np.isnan(vel.vel_mps).all()
    assert (vel.n_doppler == 0).all()


def test_result_of_other_satellites_refused() -> None:
    obs, nav = read_obs(sample_path("SEPT078M_120.21O")), [read_nav(sample_path("SEPT078M.21P"))]
    res = solve_spp(obs, nav, config=GPS)
    with pytest.raises(ValueError, match="result"):
        doppler_velocity(obs, res, nav, config=SppConfig(systems="GE"))
