"""GNSS positions for a pose trajectory, read from a receiver log or a solution table."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from navtrack import geodesy
from navtrack._typing import StrPath
from navtrack.attitude.trajectory import GnssPositions
from navtrack.errors import FileFormatError
from navtrack.io.tables import read_table

__all__ = ["read_gnss_positions"]


def read_gnss_positions(path: StrPath) -> GnssPositions:
    """GNSS positions from a table file.

    Parameters
    ----------
    path : str or path-like
        A CSV with ``time`` (s), ``lat``, ``lon`` (deg, WGS-84) and ``alt`` (m, ellipsoidal) —
        the pyins receiver log — or any table :func:`navtrack.io.tables.read_table` reads with
        ``t_gps_s`` and ``x_m, y_m, z_m`` (navtrack solutions, RTKLIB ``.pos``).

    Returns
    -------
    GnssPositions
        Rows with a finite position, in time order.

    Raises
    ------
    FileFormatError
        Neither column set present, or time stamps not increasing (the file is named).
    """
    p = Path(path)
    df = read_table(p)
    cols = set(df.columns)
    if {"time", "lat", "lon", "alt"} <= cols:
        t = df["time"].to_numpy(dtype=float)
        llh = np.column_stack(
            [
                np.radians(df["lat"].to_numpy(dtype=float)),
                np.radians(df["lon"].to_numpy(dtype=float)),
                df["alt"].to_numpy(dtype=float),
            ]
        )
        xyz = np.asarray(geodesy.geodetic_to_ecef(llh), dtype=np.float64)
    elif {"t_gps_s", "x_m", "y_m", "z_m"} <= cols:
        t = df["t_gps_s"].to_numpy(dtype=float)
        xyz = df[["x_m", "y_m", "z_m"]].to_numpy(dtype=float)
    else:
        raise FileFormatError(
            p,
            None,
            "no GNSS positions: expected columns time, lat, lon, alt or t_gps_s, x_m, y_m, z_m",
        )
    ok = np.isfinite(t) & np.all(np.isfinite(xyz), axis=1)
    t, xyz = t[ok], xyz[ok]
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise FileFormatError(p, None, "GNSS time stamps must increase strictly (two or more rows)")
    return GnssPositions(t, xyz, p.name)
