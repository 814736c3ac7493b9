"""Figures of positioning solutions: ENU errors, horizontal scatter, satellites/DOP, skyplot.

Each figure is built in two steps: a pure NumPy function computes exactly the arrays that are
drawn (:func:`solution_plot_data`, :func:`skyplot_tracks`), and a figure function draws them
(:func:`enu_error_figure`, :func:`horizontal_figure`, :func:`sats_dop_figure`,
:func:`skyplot_figure`). :func:`plot_solution` and :func:`skyplot` write PNG files.

matplotlib (extra ``plot``) is imported only when a figure is drawn, and figures are drawn on
their own Agg canvas (no pyplot, no global backend change), so the functions are safe in scripts,
servers and notebooks alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from os import fspath
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from navtrack import geodesy, timescale
from navtrack._frozen import readonly_copy
from navtrack._typing import ArrayLike, BoolArray, FloatArray, StrPath
from navtrack.gnss.accuracy import enu_error_stats, error_stats
from navtrack.io.solution import ok_mask
from navtrack.plots.canvas import figure_dir, new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from matplotlib.projections.polar import PolarAxes

__all__ = [
    "SkyTrack",
    "SolutionPlotData",
    "check_reference",
    "enu_error_figure",
    "horizontal_figure",
    "plot_solution",
    "sats_dop_figure",
    "skyplot",
    "skyplot_figure",
    "skyplot_tracks",
    "solution_plot_data",
]

_DOP_COLUMNS = ("gdop", "pdop", "hdop", "vdop")
#: Top of the DOP axis as a multiple of the GDOP rejection threshold.
DOP_CLIP = 2.0
_SYSTEM_COLOURS = {
    "G": "tab:blue",
    "R": "tab:red",
    "E": "tab:green",
    "C": "tab:orange",
    "J": "tab:purple",
    "S": "tab:gray",
    "I": "tab:brown",
}


@dataclass(frozen=True, slots=True, eq=False)
class SolutionPlotData:
    """The arrays the solution figures draw.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Epoch times on the figure's axis: time since ``t0_gps_s`` in ``t_unit``.
    t_unit : {"s", "min", "h"}
        Unit of ``t`` (chosen from the span of the data).
    t0_gps_s : float
        GPS seconds of the first epoch.
    enu_m : ndarray, shape (n, 3)
        East, north, up of solution minus reference (m) in the local frame at the reference;
        NaN where the epoch has no valid position.
    ok : ndarray of bool, shape (n,)
        Epochs with a valid position.
    ref_xyz_m : ndarray, shape (3,)
        The reference position (ECEF, m).
    ref_is_given : bool
        True when the reference was given; False when it is the component-wise median of the
        valid ECEF positions (the figures then show deviations, not errors).
    n_sats : ndarray, shape (n,)
        Satellites used per epoch (NaN where unknown); all NaN if the frame has no ``n_sats``.
    dop_names : tuple of str
        Names of the DOP columns present (subset of gdop, pdop, hdop, vdop).
    dops : ndarray, shape (n, len(dop_names))
        Their values, NaN where unknown.
    """

    t: FloatArray
    t_unit: str
    t0_gps_s: float
    enu_m: FloatArray
    ok: BoolArray
    ref_xyz_m: FloatArray
    ref_is_given: bool
    n_sats: FloatArray
    dop_names: tuple[str, ...]
    dops: FloatArray

    def __post_init__(self) -> None:
        for name in ("t", "enu_m", "ok", "ref_xyz_m", "n_sats", "dops"):
            object.__setattr__(self, name, readonly_copy(getattr(self, name)))

    @property
    def horizontal_m(self) -> FloatArray:
        """Horizontal error ``hypot(e, n)`` (m), shape (n,)."""
        return np.asarray(np.hypot(self.enu_m[:, 0], self.enu_m[:, 1]))

    @property
    def t0_label(self) -> str:
        """ISO 8601 GPST time of the first epoch (to the second)."""
        return str(np.datetime_as_string(timescale.to_datetime64(self.t0_gps_s), unit="s"))


def check_reference(ref_xyz_m: ArrayLike) -> FloatArray:
    """A reference position as a float array of shape (3,), refusing implausible values
    (:func:`navtrack.geodesy.check_near_surface`).

    Raises
    ------
    ValueError
        Not three finite numbers, or not a point near the earth's surface in ECEF metres
        (e.g. latitude/longitude in degrees, or kilometres).
    """
    return geodesy.check_near_surface(ref_xyz_m, "ref_xyz_m")


def _time_axis(t_gps_s: FloatArray) -> tuple[FloatArray, str]:
    span = float(t_gps_s[-1] - t_gps_s[0]) if t_gps_s.size else 0.0
    if span > 3 * 3600.0:
        return (t_gps_s - t_gps_s[0]) / 3600.0, "h"
    if span > 600.0:
        return (t_gps_s - t_gps_s[0]) / 60.0, "min"
    return t_gps_s - (t_gps_s[0] if t_gps_s.size else 0.0), "s"


def solution_plot_data(
    df: Any, ref_xyz_m: ArrayLike | None = None, *, ok_status: object = "ok"
) -> SolutionPlotData:
    """Compute the arrays drawn by the solution figures.

    Parameters
    ----------
    df : pandas.DataFrame or mapping of str to array-like
        Solution frame (``t_gps_s``, ``x_m``, ``y_m``, ``z_m``, ``status``; optional
        ``n_sats`` and DOP columns ``gdop``, ``pdop``, ``hdop``, ``vdop``), n >= 1 rows.
    ref_xyz_m : array-like, shape (3,), optional
        Reference position (ECEF, m). Without it, deviations from the median valid position are
        drawn.
    ok_status : object, default "ok"
        ``status`` value of a valid epoch (as in :func:`navtrack.io.solution.write_solution`).

    Returns
    -------
    SolutionPlotData

    Raises
    ------
    ValueError
        Missing columns, no rows, or an implausible reference (see :func:`check_reference`).
    """
    keys = {str(k) for k in df}
    missing = [c for c in ("t_gps_s", "x_m", "y_m", "z_m", "status") if c not in keys]
    if missing:
        raise ValueError(f"df: solution frame lacks the columns {', '.join(missing)}")
    t = np.asarray(df["t_gps_s"], dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError("df: solution frame has no rows")
    xyz = np.stack([np.asarray(df[c], dtype=float) for c in ("x_m", "y_m", "z_m")], axis=-1)
    ok = ok_mask(df["status"], ok_status) & np.isfinite(xyz).all(axis=1)
    if ref_xyz_m is not None:
        ref = check_reference(ref_xyz_m)
    elif ok.any():
        ref = np.median(xyz[ok], axis=0)
    else:
        ref = np.array([geodesy.WGS84_A_M, 0.0, 0.0])
    enu = geodesy.ecef_to_enu(np.where(ok[:, None], xyz, np.nan), ref)
    axis, unit = _time_axis(t)
    n_sats = np.asarray(df["n_sats"], dtype=float) if "n_sats" in keys else np.full(t.size, np.nan)
    dop_names = tuple(c for c in _DOP_COLUMNS if c in keys)
    dops = (
        np.stack([np.asarray(df[c], dtype=float) for c in dop_names], axis=-1)
        if dop_names
        else np.zeros((t.size, 0))
    )
    return SolutionPlotData(
        t=axis,
        t_unit=unit,
        t0_gps_s=float(t[0]),
        enu_m=enu,
        ok=ok,
        ref_xyz_m=ref,
        ref_is_given=ref_xyz_m is not None,
        n_sats=n_sats,
        dop_names=dop_names,
        dops=dops,
    )


@dataclass(frozen=True, slots=True, eq=False)
class SkyTrack:
    """One satellite's path on the skyplot.

    Attributes
    ----------
    sat : str
        Satellite id (``G05``).
    az_rad : ndarray, shape (epochs,)
        Azimuth (rad, clockwise from north); NaN where not visible.
    zenith_deg : ndarray, shape (epochs,)
        Radius on the plot: 90 - elevation (deg); NaN where not visible or below the horizon.
    """

    sat: str
    az_rad: FloatArray
    zenith_deg: FloatArray

    def __post_init__(self) -> None:
        object.__setattr__(self, "az_rad", readonly_copy(self.az_rad))
        object.__setattr__(self, "zenith_deg", readonly_copy(self.zenith_deg))


def skyplot_tracks(azel_rad: ArrayLike, sats: Sequence[str]) -> list[SkyTrack]:
    """Skyplot tracks of the satellites seen at least once above the horizon.

    Parameters
    ----------
    azel_rad : array-like, shape (epochs, sats, 2)
        Azimuth and elevation (rad); NaN where the satellite is not visible.
    sats : sequence of str, length sats
        Satellite ids of the second axis.

    Returns
    -------
    list of SkyTrack
        In the order of ``sats``; satellites never above the horizon are left out.

    Raises
    ------
    ValueError
        Wrong shape, ``sats`` of the wrong length, or angles outside the radian ranges
        (degrees given by mistake).
    """
    azel = np.asarray(azel_rad, dtype=float)
    if azel.ndim != 3 or azel.shape[-1] != 2:
        raise ValueError(f"azel_rad: expected shape (epochs, sats, 2), got {azel.shape}")
    if len(sats) != azel.shape[1]:
        raise ValueError(f"sats: {len(sats)} ids for {azel.shape[1]} satellites in azel_rad")
    az, el = azel[..., 0], azel[..., 1]
    with np.errstate(invalid="ignore"):
        if np.any(np.abs(el) > np.pi / 2 + 1e-9) or np.any(np.abs(az) > 2 * np.pi + 1e-9):
            raise ValueError(
                "azel_rad: angles beyond pi/2 (elevation) or 2 pi (azimuth); expected radians"
            )
        visible = np.isfinite(az) & np.isfinite(el) & (el >= 0.0)
    tracks = []
    for j, sat in enumerate(sats):
        if not visible[:, j].any():
            continue
        tracks.append(
            SkyTrack(
                sat=str(sat),
                az_rad=np.where(visible[:, j], np.mod(az[:, j], 2 * np.pi), np.nan),
                zenith_deg=np.where(visible[:, j], 90.0 - np.degrees(el[:, j]), np.nan),
            )
        )
    return tracks


# --------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------


def _what(data: SolutionPlotData) -> str:
    return "error" if data.ref_is_given else "deviation from median position"


def enu_error_figure(data: SolutionPlotData) -> Figure:
    """East, north and up error (or deviation) against time, one panel each.

    Each panel holds one line with x = ``data.t`` and y = ``data.enu_m[:, k]`` (NaN gaps at
    failed epochs).
    """
    stats = enu_error_stats(data.enu_m)
    fig = new_figure((8.0, 6.5))
    axes = fig.subplots(3, 1, sharex=True)
    bad_t = data.t[~data.ok]
    for k, (ax, name) in enumerate(zip(axes, ("East", "North", "Up"), strict=True)):
        ax.plot(data.t, data.enu_m[:, k], lw=0.8, color=("C0", "C1", "C2")[k])
        ax.axhline(0.0, color="k", lw=0.5)
        if bad_t.size:  # a tick along the bottom edge at each epoch without a solution
            ax.vlines(
                bad_t,
                0.0,
                0.06,
                transform=ax.get_xaxis_transform(),
                color="C3",
                lw=1.2,
                label=f"no valid position ({bad_t.size})",
            )
            if k == 0:
                ax.legend(loc="upper left", fontsize="x-small")
        ax.set_ylabel(f"{name} (m)")
        ax.set_title(f"{name}: RMS {stats[name.lower()].rms_m:.2f} m", fontsize="small", loc="left")
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel(f"time since {data.t0_label} GPST ({data.t_unit})")
    n_bad = int((~data.ok).sum())
    fig.suptitle(
        f"ENU {_what(data)}: 3D RMS {stats['3D'].rms_m:.2f} m, "
        f"{int(data.ok.sum())} epochs" + (f" ({n_bad} without a valid position)" if n_bad else "")
    )
    return fig


def horizontal_figure(data: SolutionPlotData) -> Figure:
    """North against east error of the valid epochs (first line), the reference at the origin
    (second line) and the circle holding 95 % of the horizontal errors (third line)."""
    fig = new_figure((6.5, 6.5))
    ax = fig.subplots()
    e, n = data.enu_m[data.ok, 0], data.enu_m[data.ok, 1]
    ax.plot(e, n, ls="none", marker=".", ms=3, alpha=0.6, label="solution")
    ax.plot(
        [0.0],
        [0.0],
        ls="none",
        marker="+",
        ms=14,
        mew=2,
        color="k",
        label="reference" if data.ref_is_given else "median position",
    )
    h = data.horizontal_m[data.ok]
    h_stats = error_stats(h)
    r95 = h_stats.p95_m
    ang = np.linspace(0.0, 2 * np.pi, 181)
    ax.plot(r95 * np.cos(ang), r95 * np.sin(ang), color="C3", lw=1, label=f"95 %: {r95:.2f} m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("East (m)")
    ax.set_ylabel("North (m)")
    ax.grid(True, lw=0.3)
    ax.legend(loc="upper right", fontsize="small")
    ax.set_title(f"Horizontal {_what(data)}: RMS {h_stats.rms_m:.2f} m, {h.size} epochs")
    return fig


def sats_dop_figure(data: SolutionPlotData, max_gdop: float | None = None) -> Figure:
    """Satellites used (top panel, one line, integer ticks) and each DOP (bottom panel, one
    line per name in ``data.dop_names``) against time.

    The DOP axis is logarithmic and clipped to ``[0.5, DOP_CLIP * max_gdop]`` (``[0.5, 50]``
    without a threshold), so that the usual values of 1-3 stay readable next to a few
    near-singular epochs; values above the top are drawn as triangles on the top edge. The GDOP
    rejection threshold ``max_gdop`` (RTKLIB ``pos2-rejgdop``), when given, is a dashed line.
    """
    from matplotlib.ticker import FixedLocator, MaxNLocator, NullLocator  # optional (extra plot)

    fig = new_figure((8.0, 5.5))
    top, bottom = fig.subplots(2, 1, sharex=True)
    top.plot(data.t, data.n_sats, drawstyle="steps-post", lw=1, color="C0")
    top.set_ylabel("satellites used")
    top.yaxis.set_major_locator(MaxNLocator(integer=True))
    top.grid(True, lw=0.3)
    y_max = DOP_CLIP * (max_gdop if max_gdop is not None else 25.0)
    for k, name in enumerate(data.dop_names):
        (line,) = bottom.plot(data.t, np.minimum(data.dops[:, k], y_max), lw=1, label=name.upper())
        above = data.dops[:, k] > y_max
        if above.any():
            bottom.plot(
                data.t[above],
                np.full(int(above.sum()), y_max),
                "^",
                ms=4,
                color=line.get_color(),
                clip_on=False,
            )
    if max_gdop is not None:
        bottom.axhline(
            max_gdop, color="k", ls="--", lw=0.8, label=f"GDOP rejection threshold {max_gdop:g}"
        )
    bottom.set_yscale("log")
    bottom.set_ylim(0.5, y_max)
    ticks = [t for t in (0.5, 1, 2, 3, 5, 10, 20, 30, 50, 100) if t <= y_max]
    bottom.yaxis.set_major_locator(FixedLocator(ticks))
    bottom.yaxis.set_minor_locator(NullLocator())
    bottom.set_yticklabels([f"{t:g}" for t in ticks])
    bottom.set_ylabel("DOP (log scale)")
    if data.dop_names:
        bottom.legend(loc="center left", fontsize="small", ncols=3)
    else:
        bottom.text(0.5, 0.5, "no DOP in the solution", ha="center", transform=bottom.transAxes)
    bottom.grid(True, lw=0.3)
    bottom.set_xlabel(f"time since {data.t0_label} GPST ({data.t_unit})")
    fig.suptitle("Satellites and dilution of precision")
    return fig


def skyplot_figure(tracks: Sequence[SkyTrack], elmask_deg: float | None = None) -> Figure:
    """Polar skyplot: north up, azimuth clockwise, zenith at the centre, horizon at the rim;
    one line per track (x = azimuth in rad, y = 90 - elevation in deg), coloured by system,
    with a legend of the systems and, when given, the elevation mask as a dashed ring.

    Each satellite id is written at the first point of its track (its end, else its start,
    middle or quarter points) farther than :data:`LABEL_SPACING_DEG` from every label already
    written, so that labels of neighbouring tracks do not overlap.
    """
    fig = new_figure((6.5, 6.5))
    ax = cast("PolarAxes", fig.add_subplot(projection="polar"))
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    placed: list[tuple[float, float]] = []
    systems: dict[str, str] = {}
    for tr in tracks:
        colour = _SYSTEM_COLOURS.get(tr.sat[:1], "k")
        systems.setdefault(tr.sat[:1], colour)
        ax.plot(tr.az_rad, tr.zenith_deg, lw=1.2, color=colour)
        k = _label_point(tr, placed)
        placed.append(_planar(tr.az_rad[k], tr.zenith_deg[k]))
        ax.text(tr.az_rad[k], tr.zenith_deg[k], tr.sat, fontsize=7, color=colour)
    from matplotlib.lines import Line2D  # optional dependency (extra navtrack[plot])

    # legend entries drawn apart from the axes' lines (one line per track stays the rule)
    handles: list[Any] = [
        Line2D([], [], color=c, lw=2, label=_SYSTEM_NAMES.get(sys, sys))
        for sys, c in systems.items()
    ]
    if elmask_deg is not None:
        ang = np.linspace(0.0, 2 * np.pi, 361)
        handles += ax.plot(
            ang,
            np.full(ang.size, 90.0 - elmask_deg),
            "k--",
            lw=0.8,
            label=f"elevation mask {elmask_deg:g}°",
        )
    if handles:
        ax.legend(handles=handles, loc="upper right", bbox_to_anchor=(1.12, 1.1), fontsize=7)
    ax.set_ylim(0.0, 90.0)
    ax.set_yticks([0, 15, 30, 45, 60, 75, 90])
    ax.set_yticklabels(["90°", "75°", "60°", "45°", "30°", "15°", "0°"], fontsize=7)
    ax.set_title(f"Skyplot, {len(tracks)} satellites (elevation on the radius)")
    return fig


#: Smallest distance between two satellite labels of a skyplot (degrees of zenith angle).
LABEL_SPACING_DEG = 12.0
_SYSTEM_NAMES = {
    "G": "GPS",
    "R": "GLONASS",
    "E": "Galileo",
    "C": "BeiDou",
    "J": "QZSS",
    "S": "SBAS",
    "I": "NavIC",
}


def _planar(az_rad: float, zenith_deg: float) -> tuple[float, float]:
    return zenith_deg * float(np.sin(az_rad)), zenith_deg * float(np.cos(az_rad))


def _label_point(track: SkyTrack, placed: list[tuple[float, float]]) -> int:
    """Index of the track point where its label goes (see :func:`skyplot_figure`)."""
    idx = np.flatnonzero(np.isfinite(track.zenith_deg))
    n = idx.size
    for k in (idx[-1], idx[0], idx[n // 2], idx[n // 4], idx[(3 * n) // 4]):
        x, y = _planar(track.az_rad[k], track.zenith_deg[k])
        if all(math.hypot(x - a, y - b) > LABEL_SPACING_DEG for a, b in placed):
            return int(k)
    return int(idx[-1])


# --------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------


def plot_solution(
    df: Any,
    out_dir: StrPath,
    *,
    ref_xyz_m: ArrayLike | None = None,
    azel: tuple[ArrayLike, Sequence[str]] | None = None,
    ok_status: object = "ok",
    max_gdop: float | None = None,
    elmask_deg: float | None = None,
) -> list[Path]:
    """Write the solution figures as PNG files.

    Parameters
    ----------
    df : pandas.DataFrame or mapping of str to array-like
        Solution frame (see :func:`solution_plot_data`).
    out_dir : str or path-like
        Directory for the figures (created if missing).
    ref_xyz_m : array-like, shape (3,), optional
        Reference position (ECEF, m); without it the figures show deviations from the median.
    azel : (azel_rad, sats), optional
        Azimuth/elevation ``(epochs, sats, 2)`` in rad and the satellite ids, for a skyplot.
    ok_status : object, default "ok"
        ``status`` value of a valid epoch.
    max_gdop : float, optional
        GDOP rejection threshold of the solution, drawn on the DOP panel.
    elmask_deg : float, optional
        Elevation mask of the solution (deg), drawn as a ring on the skyplot.

    Returns
    -------
    list of pathlib.Path
        ``enu_error.png``, ``horizontal.png``, ``sats_dop.png`` (when the frame has ``n_sats``
        or a DOP column) and ``skyplot.png`` (when ``azel`` is given), in that order.

    Raises
    ------
    ValueError
        Bad columns or reference (see :func:`solution_plot_data`) or bad ``azel``.
    OSError
        The directory or a file cannot be written (the message names it).
    MissingDependencyError
        matplotlib is not installed.
    """
    data = solution_plot_data(df, ref_xyz_m, ok_status=ok_status)
    tracks = skyplot_tracks(*azel) if azel is not None else None
    d = figure_dir(out_dir)
    paths = [
        save_figure(enu_error_figure(data), d / "enu_error.png"),
        save_figure(horizontal_figure(data), d / "horizontal.png"),
    ]
    if data.dop_names or np.isfinite(data.n_sats).any():
        paths.append(save_figure(sats_dop_figure(data, max_gdop), d / "sats_dop.png"))
    if tracks is not None:
        paths.append(save_figure(skyplot_figure(tracks, elmask_deg), d / "skyplot.png"))
    return paths


def skyplot(azel_rad: ArrayLike, sats: Sequence[str], path: StrPath) -> Path:
    """Write a skyplot PNG.

    Parameters
    ----------
    azel_rad : array-like, shape (epochs, sats, 2)
        Azimuth and elevation (rad), NaN where the satellite is not visible.
    sats : sequence of str
        Satellite ids of the second axis of ``azel_rad``.
    path : str or path-like
        Output PNG file.

    Returns
    -------
    pathlib.Path
    """
    p = Path(path)
    if not p.parent.is_dir():
        raise FileNotFoundError(
            2, f"cannot write plot: directory {fspath(p.parent)!r} does not exist", fspath(p)
        )
    return save_figure(skyplot_figure(skyplot_tracks(azel_rad, sats)), p)
