"""Map-like figure of detections and confirmed tracks (east/north, km)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._typing import ArrayLike, FloatArray, StrPath
from navtrack.geodesy import ecef_to_enu, geodetic_to_ecef
from navtrack.io.tracks import local_enu_to_geodetic
from navtrack.plots.canvas import figure_dir, new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["MAX_LABELLED_TRACKS", "plot_tracks", "track_colours", "tracks_figure"]

MAX_LABELLED_TRACKS = 200
"""Up to this many confirmed tracks, each is labelled with its id at its last state."""


def track_colours(n: int) -> FloatArray:
    """``n`` RGBA colours for tracks drawn together: hues of the ``turbo`` map stepped by the
    golden ratio, so that tracks next in order (often next in space) differ strongly and no
    two of a few hundred share a colour."""
    from matplotlib import colormaps

    hue = (np.arange(n) * 0.6180339887498949) % 1.0
    return np.asarray(colormaps["turbo"](0.05 + 0.9 * hue))


def plot_tracks(
    out_dir: StrPath,
    en: ArrayLike,
    result: Any,
    title: str = "",
    ref_deg: tuple[float, float] | None = None,
) -> Path:
    """Write ``tracks.png`` in ``out_dir``: detections (grey dots), confirmed tracks (lines).

    Parameters
    ----------
    out_dir : str or path-like
        Directory for the figure (created if missing).
    en : array-like, shape (n_detections, 2)
        Detections, east and north (m) in the local frame of the tracker.
    result : navtrack.tracking.trackers.tracker.TrackerResult
        Tracker output; the lines are ``track_x[:, 0]`` (east) against ``track_x[:, 2]``
        (north) of the rows of each confirmed ``track_id``.
    title : str, optional
        First line of the figure title (the second gives the number of confirmed tracks).
    ref_deg : (lat, lon), optional
        Latitude and longitude (deg) of the local frame's origin, written on the axes; NaN or
        None for detections given in the file's own x/y frame.

    Returns
    -------
    pathlib.Path
        The written ``tracks.png``.

    Raises
    ------
    ValueError
        ``en`` is not of shape (n, 2).
    OSError
        The directory or the file cannot be written (the message names it).
    MissingDependencyError
        matplotlib is not installed.
    """
    en = np.asarray(en, dtype=float)
    if en.ndim != 2 or en.shape[1] != 2:
        raise ValueError(f"en: expected shape (n_detections, 2), got {en.shape}")
    out = figure_dir(out_dir)
    return save_figure(tracks_figure(en, result, title, ref_deg), out / "tracks.png", dpi=130)


def tracks_figure(
    en: FloatArray, result: Any, title: str = "", ref_deg: tuple[float, float] | None = None
) -> Figure:
    """The figure :func:`plot_tracks` writes (same parameters, ``en`` checked)."""
    fig = new_figure((9.0, 8.0))
    ax = fig.subplots()
    ax.plot(en[:, 0] / 1e3, en[:, 1] / 1e3, ".", color="0.75", ms=1.5, label="detections")
    conf = np.asarray(result.track_confirmed)
    ids = np.asarray(result.track_id)
    x = np.asarray(result.track_x)
    confirmed_ids = np.unique(ids[conf])
    colours = track_colours(confirmed_ids.size)
    for k, tid in enumerate(confirmed_ids):
        sel = ids == tid
        ax.plot(x[sel, 0] / 1e3, x[sel, 2] / 1e3, "-", lw=0.9, color=colours[k])
        if confirmed_ids.size <= MAX_LABELLED_TRACKS:
            last = np.flatnonzero(sel)[-1]
            ax.annotate(
                str(tid), (x[last, 0] / 1e3, x[last, 2] / 1e3), fontsize=5, color=colours[k]
            )
    if ref_deg is not None and np.isfinite(ref_deg).all():
        lat, lon = ref_deg
        _latlon_grid(ax, en, lat, lon)
        origin = (
            f"of the reference {abs(lat):.5f}°{'N' if lat >= 0 else 'S'} "
            f"{abs(lon):.5f}°{'E' if lon >= 0 else 'W'} (tangent plane at height 0)"
        )
    else:
        origin = "(the file's x_m/y_m frame)"
    ax.set_xlabel(f"east (km) {origin}")
    ax.set_ylabel("north (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{title}\n{len(confirmed_ids)} confirmed tracks")
    ax.legend(loc="best", fontsize=8)
    return fig


def _latlon_grid(ax: Any, en: FloatArray, lat0: float, lon0: float) -> None:
    """Thin lines of constant latitude and longitude over the detections' extent, labelled in
    degrees at the lower and left edges (the tangent plane's east/north axes are not the
    meridians and parallels away from the reference)."""
    from matplotlib.ticker import MaxNLocator  # matplotlib: imported with the figure

    lo, hi = en.min(axis=0), en.max(axis=0)
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [lo[0], hi[1]], [hi[0], hi[1]]])
    ll = local_enu_to_geodetic(corners, lat0, lon0)
    lat_rng = (ll[:, 0].min(), ll[:, 0].max())
    lon_rng = (ll[:, 1].min(), ll[:, 1].max())
    ref = geodetic_to_ecef([np.radians(lat0), np.radians(lon0), 0.0])

    def en_km(lat: FloatArray, lon: FloatArray) -> FloatArray:
        llh = np.stack([np.radians(lat), np.radians(lon), np.zeros(lat.size)], axis=-1)
        return np.asarray(ecef_to_enu(geodetic_to_ecef(llh), ref)[:, :2]) / 1e3

    s = np.linspace(0.0, 1.0, 60)
    style = {"color": "0.55", "lw": 0.4, "ls": ":", "zorder": 0}
    for v in MaxNLocator(6).tick_values(*lat_rng):
        if lat_rng[0] <= v <= lat_rng[1]:
            p = en_km(np.full(s.size, v), lon_rng[0] + s * (lon_rng[1] - lon_rng[0]))
            ax.plot(p[:, 0], p[:, 1], **style)
            ax.annotate(f"{v:g}°", p[0], fontsize=6, color="0.4", ha="right", va="center")
    for v in MaxNLocator(6).tick_values(*lon_rng):
        if lon_rng[0] <= v <= lon_rng[1]:
            p = en_km(lat_rng[0] + s * (lat_rng[1] - lat_rng[0]), np.full(s.size, v))
            ax.plot(p[:, 0], p[:, 1], **style)
            ax.annotate(f"{v:g}°", p[0], fontsize=6, color="0.4", ha="center", va="top")
