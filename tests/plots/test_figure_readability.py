"""Figures a user can read (issue 9): the DOP panel, the skyplot, epochs without a solution,
smoothing and track figures naming their origin. Checked on the bundled RINEX 2 example,
whose last five epochs are rejected for GDOP above 30 (GDOP up to about 45)."""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from navtrack.data import sample_path
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, SppResult, solution_frame, solve_spp
from navtrack.plots.canvas import new_figure
from navtrack.plots.gnss import (
    DOP_CLIP,
    LABEL_SPACING_DEG,
    SolutionPlotData,
    enu_error_figure,
    sats_dop_figure,
    skyplot_figure,
    skyplot_tracks,
    solution_plot_data,
)

REF_LLH = (35.160867766, 139.613844940, 68.4545)  # tests/cli/test_pos.py, same station


@lru_cache(maxsize=1)
def _solved() -> tuple[SppResult, SolutionPlotData]:
    from navtrack.geodesy import geodetic_to_ecef

    res = solve_spp(
        read_obs(sample_path("07590920.05o")),
        [read_nav(sample_path("07590920.05n"))],
        config=SppConfig(),
    )
    ref = geodetic_to_ecef([math.radians(REF_LLH[0]), math.radians(REF_LLH[1]), REF_LLH[2]])
    return res, solution_plot_data(solution_frame(res), ref)


def test_dop_panel_is_clipped_with_the_threshold_drawn() -> None:
    res, data = _solved()
    assert int(res.status_counts()["high_dop"]) == 5
    fig = sats_dop_figure(data, max_gdop=30.0)
    top, bottom = fig.axes
    assert bottom.get_yscale() == "log"
    assert bottom.get_ylim() == pytest.approx((0.5, DOP_CLIP * 30.0))
    threshold = [ln for ln in bottom.get_lines() if "threshold" in str(ln.get_label())]
    assert len(threshold) == 1
    np.testing.assert_allclose(threshold[0].get_ydata(), 30.0)
    ticks = top.get_yticks()
    np.testing.assert_array_equal(ticks, np.round(ticks))  # satellite counts are integers
    # a near-singular epoch is drawn at the top edge, marked, not stretching the axis
    huge = solution_plot_data(
        {**{k: v for k, v in solution_frame(res).items()}, "gdop": np.full(len(res.t_gps_s), 1e6)},
        None,
    )
    fig = sats_dop_figure(huge, max_gdop=30.0)
    marks = [ln for ln in fig.axes[1].get_lines() if ln.get_marker() == "^"]
    assert marks
    assert np.all(marks[0].get_ydata() == DOP_CLIP * 30.0)
    assert fig.axes[1].get_ylim()[1] == DOP_CLIP * 30.0


def test_error_series_marks_epochs_without_a_solution() -> None:
    _, data = _solved()
    fig = enu_error_figure(data)
    for ax in fig.axes:
        marks = ax.collections[0].get_segments()
        np.testing.assert_allclose(sorted(m[0, 0] for m in marks), np.sort(data.t[~data.ok]))
    assert "no valid position (5)" in [t.get_text() for t in fig.axes[0].get_legend().texts]


def test_skyplot_legend_mask_ring_and_labels_apart() -> None:
    res, _ = _solved()
    tracks = skyplot_tracks(res.azel_rad, list(res.sats))
    fig = skyplot_figure(tracks, elmask_deg=15.0)
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().texts]
    assert legend == ["GPS", "elevation mask 15°"]
    ring = next(ln for ln in ax.get_lines() if ln.get_label() == "elevation mask 15°")
    np.testing.assert_allclose(ring.get_ydata(), 75.0)
    pts = [
        (
            t.get_position()[1] * math.sin(t.get_position()[0]),
            t.get_position()[1] * math.cos(t.get_position()[0]),
        )
        for t in ax.texts
    ]
    assert len(pts) == len(tracks)
    close = [
        (a, b) for a, b in itertools.combinations(pts, 2) if math.dist(a, b) <= LABEL_SPACING_DEG
    ]
    assert close == []


def test_smoothing_plot_names_t0_and_the_quantity() -> None:
    from navtrack.plots.ari import series_figure
    from navtrack.smoothing.ari import AriConfig, fit_ari, simulate_ari

    y, _ = simulate_ari(np.random.default_rng(4), 80, [-0.4], 1, 0.02, 0.01)
    t = 1300190400.0 + np.arange(80.0)
    fig = series_figure(t, fit_ari(y, AriConfig(order=(1, 1))), "z_m", "m", "t_gps_s")
    assert fig.axes[0].get_ylabel() == "z_m (m)"
    assert "t0 = first epoch (t_gps_s = 1300190400 s, 2021-03-19T12:00:00 GPST)" in (
        fig.axes[1].get_xlabel()
    )


def test_track_map_names_its_reference() -> None:
    from types import SimpleNamespace

    from navtrack.plots.tracks import tracks_figure

    res = SimpleNamespace(
        track_confirmed=np.array([True, True]), track_id=np.array([1, 1]), track_x=np.zeros((2, 4))
    )
    fig = tracks_figure(np.zeros((3, 2)), res, "t", ref_deg=(50.79117, -1.10867))
    assert "of the reference 50.79117°N 1.10867°W" in fig.axes[0].get_xlabel()
    fig = tracks_figure(np.zeros((3, 2)), res, "t", ref_deg=(math.nan, math.nan))
    assert "x_m/y_m frame" in fig.axes[0].get_xlabel()


def test_stanford_panels_share_axes_and_one_colour_scale(tmp_path) -> None:
    from navtrack.plots.integrity import stanford_axes, stanford_figure, stanford_figure_files

    rng = np.random.default_rng(3)
    small = tuple(np.abs(rng.normal(0, s, 300)) for s in (1.0, 4.0, 2.0, 6.0))
    large = tuple(np.abs(rng.normal(0, s, 500)) for s in (3.0, 12.0, 5.0, 20.0))
    fig = stanford_figure("X", {"a": small, "b": large})
    panels, bar = fig.axes[:4], fig.axes[4:]
    assert len(bar) == 1
    assert "epochs per cell" in bar[0].get_ylabel()
    # rows share their axes (the larger method's range), every panel the colour scale
    assert panels[0].get_xlim() == panels[1].get_xlim() == panels[0].get_ylim()
    assert panels[2].get_xlim() == panels[3].get_xlim()
    assert panels[0].get_xlim()[1] == pytest.approx(1.05 * max(large[0].max(), large[1].max()))
    norms = {p.collections[0].norm.vmax for p in panels}
    assert norms == {500.0}
    (path,) = stanford_figure_files({"X": {"a": small, "b": large}}, tmp_path)
    assert path.stat().st_size > 0
    ax = new_figure((4.0, 4.0)).subplots()
    mesh = stanford_axes(ax, small[0], small[1], "a", top_m=80.0, max_count=500)
    assert ax.get_xlim() == (0.0, 80.0)
    assert mesh.norm.vmax == 500.0


def test_many_tracks_get_distinct_colours_and_their_ids() -> None:
    from types import SimpleNamespace

    from navtrack.plots.tracks import track_colours, tracks_figure

    colours = track_colours(106)
    assert len({tuple(np.round(c, 3)) for c in colours}) == 106
    # neighbours in order differ strongly (the issue: 106 tracks on ~10 colours)
    assert np.min(np.abs(np.diff(colours[:, :3], axis=0)).sum(axis=1)) > 0.1
    ids = np.repeat(np.arange(106), 2)
    res = SimpleNamespace(track_confirmed=np.ones(212, bool), track_id=ids,
                          track_x=np.random.default_rng(0).normal(size=(212, 4)))  # fmt: skip
    ax = tracks_figure(np.zeros((3, 2)), res, "t").axes[0]
    assert len(ax.lines) == 107  # detections + one line per track
    assert {t.get_text() for t in ax.texts} == {str(k) for k in range(106)}


def test_rtk_figures_carry_the_date(tmp_path) -> None:
    from types import SimpleNamespace

    from navtrack.plots import rtk

    t = 1.3e9 + np.arange(5.0)
    assert rtk._title(t) == "RTK solution, 2021-03-17 07:06:40 – 07:06:44 GPST, 5 epochs"
    pos = np.random.default_rng(1).normal(size=(5, 3))
    result = SimpleNamespace(t_gps_s=t, status=np.zeros(5, int), pos_m=pos,
                             ratio=np.full(5, 4.0), n_sats=np.full(5, 8),
                             slip_mask=np.zeros((5, 3), bool))  # fmt: skip
    paths = rtk.plot_rtk(result, tmp_path)  # type: ignore[arg-type]
    assert [p.name for p in paths] == ["rtk_error.png", "rtk_ratio.png", "rtk_sats.png"]
