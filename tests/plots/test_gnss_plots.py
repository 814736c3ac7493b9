"""Solution figures and skyplot on real data.

Oracles: the ARL1 reference position and RTKLIB's error table in
``shared/data/gnss/rtklib_spp/README.md`` (3D RMS 2.71 m, horizontal 1.13 m, vertical 2.46 m for
``arl1_gps``), pymap3d for ENU and azimuth/elevation, and the NGA SP3 orbits of the same hour
for real satellite tracks. The figures are checked by reading back the drawn Line2D data.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("matplotlib")

from navtrack.io.rtklib import read_pos, to_solution_frame
from navtrack.plots.gnss import (
    enu_error_figure,
    horizontal_figure,
    plot_solution,
    sats_dop_figure,
    skyplot,
    skyplot_figure,
    skyplot_tracks,
    solution_plot_data,
)

# shared/data/gnss/README.md, section 2 (RINEX header APPROX POSITION, GPSTk's test reference).
ARL1_REF = np.array([-740289.9180, -5457071.7340, 3207245.5420])
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def arl1(gnss_data: Path) -> pd.DataFrame:
    df = to_solution_frame(read_pos(gnss_data / "rtklib_spp" / "arl1_gps.pos"))
    df["pdop"] = np.linspace(1.5, 2.5, len(df))
    df["hdop"] = np.linspace(0.8, 1.1, len(df))
    df.loc[7, "status"] = "no_convergence"
    return df


@pytest.fixture(scope="module")
def sp3_azel(gnss_data: Path) -> tuple[np.ndarray, list[str]]:
    """Azimuth/elevation of every SP3 satellite seen from ARL1, first 13 epochs (1 h)."""
    pymap3d = pytest.importorskip("pymap3d")
    epochs: list[dict[str, np.ndarray]] = []
    for line in (gnss_data / "gpstk_arl1" / "test_input_sp3_nav_2015_200.sp3").open():
        if line.startswith("*"):
            if len(epochs) == 13:
                break
            epochs.append({})
        elif line.startswith("P") and epochs:
            sat = "G" + line[2:4].replace(" ", "0")
            epochs[-1][sat] = np.array([float(line[4:18]), float(line[18:32]), float(line[32:46])])
    sats = sorted(epochs[0])
    lat, lon, h = pymap3d.ecef2geodetic(*ARL1_REF)
    azel = np.full((len(epochs), len(sats), 2), np.nan)
    for i, ep in enumerate(epochs):
        for j, sat in enumerate(sats):
            if sat in ep:
                az, el, _ = pymap3d.ecef2aer(*(ep[sat] * 1e3), lat, lon, h)
                azel[i, j] = np.radians([az, el])
    return azel, sats


def test_enu_errors_reproduce_rtklib_table(arl1: pd.DataFrame) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    data = solution_plot_data(arl1, ARL1_REF)
    assert data.ref_is_given
    assert data.ok.sum() == len(arl1) - 1
    assert np.isnan(data.enu_m[7]).all()
    lat, lon, h = pymap3d.ecef2geodetic(*ARL1_REF)
    ok = data.ok
    e, n, u = pymap3d.ecef2enu(arl1["x_m"][ok], arl1["y_m"][ok], arl1["z_m"][ok], lat, lon, h)
    np.testing.assert_allclose(data.enu_m[ok], np.stack([e, n, u], -1), atol=1e-6)
    # RTKLIB README table, arl1_gps (all 120 epochs; one is marked failed here, so 0.03 m slack).
    rms3 = np.sqrt(np.nanmean(np.sum(data.enu_m**2, axis=1)))
    assert rms3 == pytest.approx(2.71, abs=0.03)
    assert np.sqrt(np.nanmean(data.horizontal_m**2)) == pytest.approx(1.13, abs=0.03)
    # One hour at 30 s: the time axis is in minutes.
    assert data.t_unit == "min"
    np.testing.assert_allclose(data.t, (arl1["t_gps_s"] - arl1["t_gps_s"][0]) / 60.0)


def test_figures_draw_the_data(arl1: pd.DataFrame) -> None:
    data = solution_plot_data(arl1, ARL1_REF)
    fig = enu_error_figure(data)
    for k, ax in enumerate(fig.axes):
        line = ax.get_lines()[0]
        np.testing.assert_array_equal(line.get_xdata(), data.t)
        np.testing.assert_array_equal(line.get_ydata(), data.enu_m[:, k])
    fig = horizontal_figure(data)
    pts = fig.axes[0].get_lines()[0]
    np.testing.assert_array_equal(pts.get_xdata(), data.enu_m[data.ok, 0])
    np.testing.assert_array_equal(pts.get_ydata(), data.enu_m[data.ok, 1])
    circle = fig.axes[0].get_lines()[2]
    r = np.hypot(circle.get_xdata(), circle.get_ydata())
    np.testing.assert_allclose(r, np.percentile(data.horizontal_m[data.ok], 95))
    fig = sats_dop_figure(data)
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_ydata(), arl1["n_sats"])
    assert data.dop_names == ("pdop", "hdop")
    np.testing.assert_array_equal(fig.axes[1].get_lines()[0].get_ydata(), arl1["pdop"])
    np.testing.assert_array_equal(fig.axes[1].get_lines()[1].get_ydata(), arl1["hdop"])


def test_no_reference_uses_median(arl1: pd.DataFrame) -> None:
    data = solution_plot_data(arl1)
    assert not data.ref_is_given
    ok = arl1["status"] == "ok"
    np.testing.assert_array_equal(
        data.ref_xyz_m, np.median(arl1.loc[ok, ["x_m", "y_m", "z_m"]].to_numpy(), axis=0)
    )


def _assert_png(path: Path) -> None:
    import matplotlib.image

    raw = path.read_bytes()
    assert raw[:8] == PNG_SIGNATURE
    assert len(raw) > 10_000
    img = matplotlib.image.imread(path)
    assert img.shape[0] > 300
    assert img.shape[1] > 300
    assert img.std() > 0.01  # not a blank canvas


def test_plot_solution_writes_pngs(arl1, sp3_azel, tmp_path: Path) -> None:
    paths = plot_solution(arl1, tmp_path / "plots", ref_xyz_m=ARL1_REF, azel=sp3_azel)
    assert [p.name for p in paths] == [
        "enu_error.png",
        "horizontal.png",
        "sats_dop.png",
        "skyplot.png",
    ]
    for p in paths:
        _assert_png(p)
    minimal = {k: arl1[k].to_numpy() for k in ("t_gps_s", "x_m", "y_m", "z_m", "status")}
    paths = plot_solution(minimal, tmp_path / "minimal")
    assert [p.name for p in paths] == ["enu_error.png", "horizontal.png"]


def test_skyplot_tracks_from_sp3(sp3_azel, tmp_path: Path) -> None:
    azel, sats = sp3_azel
    tracks = skyplot_tracks(azel, sats)
    above = [s for j, s in enumerate(sats) if (azel[:, j, 1] >= 0).any()]
    assert [t.sat for t in tracks] == above
    assert 8 <= len(tracks) <= 16  # a GPS sky over one hour
    for tr in tracks:
        j = sats.index(tr.sat)
        vis = azel[:, j, 1] >= 0
        np.testing.assert_allclose(tr.zenith_deg[vis], 90 - np.degrees(azel[vis, j, 1]))
        assert np.isnan(tr.zenith_deg[~vis]).all()
    fig = skyplot_figure(tracks)
    lines = fig.axes[0].get_lines()
    assert len(lines) == len(tracks)
    for line, tr in zip(lines, tracks, strict=True):
        np.testing.assert_array_equal(line.get_xdata(), tr.az_rad)
        np.testing.assert_array_equal(line.get_ydata(), tr.zenith_deg)
    _assert_png(skyplot(azel, sats, tmp_path / "sky.png"))


def test_bad_inputs(arl1, sp3_azel, tmp_path: Path) -> None:
    azel, sats = sp3_azel
    with pytest.raises(ValueError, match="ref_xyz_m"):
        solution_plot_data(arl1, [30.38, -97.73, 217.6])  # lat/lon/h, not ECEF
    with pytest.raises(ValueError, match="ref_xyz_m"):
        solution_plot_data(arl1, ARL1_REF / 1000.0)  # kilometres
    with pytest.raises(ValueError, match="radians"):
        skyplot_tracks(np.degrees(azel), sats)
    with pytest.raises(ValueError, match="sats"):
        skyplot_tracks(azel, sats[:-1])
    with pytest.raises(ValueError, match="status"):
        solution_plot_data(arl1.drop(columns=["status"]))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(NotADirectoryError, match="file"):
        plot_solution(arl1, blocker)
