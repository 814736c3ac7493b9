"""Pose trajectory: reconstructed attitude combined with GNSS positions (paper 6, eq. 9).

The paper interpolates the 1 Hz GPS positions linearly to the LIDAR sample times and pairs them
with the reconstructed attitude. :func:`pose_frame` does that on any attitude time base and
returns a solution frame that :func:`navtrack.io.solution.write_solution` writes as CSV or
Parquet (the attitude as extra columns); :func:`navtrack.io.positions.read_gnss_positions` reads
the GNSS positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray
from navtrack.attitude.quaternion import check_quaternions

__all__ = ["POSE_COLUMNS", "GnssPositions", "pose_frame"]

#: Attitude columns a pose frame adds to the solution columns (docs/vocabulary.md).
POSE_COLUMNS = ("qx", "qy", "qz", "qw", "roll_deg", "pitch_deg", "yaw_deg")


@dataclass(frozen=True, slots=True, eq=False)
class GnssPositions:
    """GNSS positions on their own clock (arrays read-only).

    Attributes
    ----------
    t_s : (k,) time stamps, s, strictly increasing
    xyz_m : (k, 3) ECEF positions, m
    source : str
    """

    t_s: FloatArray
    xyz_m: FloatArray
    source: str

    def __post_init__(self) -> None:
        freeze_arrays(self)


def pose_frame(
    t_s: ArrayLike,
    quat_xyzw: ArrayLike,
    gnss: GnssPositions | None = None,
    *,
    gnss_offset_s: float = 0.0,
    t0_gps_s: float = 0.0,
) -> dict[str, Any]:
    """A pose trajectory as a solution frame (time, position, attitude).

    Parameters
    ----------
    t_s : (n,) times of the attitudes (camera/reference clock), s
    quat_xyzw : (n, 4) attitudes body -> reference, scalar-last
    gnss : GnssPositions or None
        Positions, linearly interpolated to ``t_s`` (paper eq. 9); epochs outside the GNSS
        span get no position (``status`` ``no_position``).
    gnss_offset_s : float
        GNSS time of attitude time ``t``: ``t + gnss_offset_s``.
    t0_gps_s : float
        GPS time of ``t = 0`` for the ``t_gps_s`` column (0 when the recording has no absolute
        time; the calendar columns then read 1980-01-06).

    Returns
    -------
    dict of str to ndarray
        ``t_gps_s``, ``x_m``, ``y_m``, ``z_m`` (ECEF, NaN without a position), ``status``
        (``ok``, ``no_position``), ``qx, qy, qz, qw`` and ``roll_deg, pitch_deg, yaw_deg``
        (intrinsic z-y'-x'' Euler angles of the body -> reference rotation).
    """
    t = np.asarray(t_s, dtype=np.float64)
    q = check_quaternions(quat_xyzw, "quat_xyzw")
    if q.shape != (t.size, 4):
        raise ValueError(f"quat_xyzw: expected shape ({t.size}, 4), got {q.shape}")
    xyz = np.full((t.size, 3), np.nan)
    if gnss is not None:
        tg = t + gnss_offset_s
        inside = (tg >= gnss.t_s[0]) & (tg <= gnss.t_s[-1])
        for i in range(3):
            xyz[inside, i] = np.interp(tg[inside], gnss.t_s, gnss.xyz_m[:, i])
    status = np.where(np.all(np.isfinite(xyz), axis=1), "ok", "no_position")
    ypr = np.degrees(np.asarray(Rotation.from_quat(q).as_euler("ZYX")))
    return {
        "t_gps_s": t + t0_gps_s,
        "x_m": xyz[:, 0],
        "y_m": xyz[:, 1],
        "z_m": xyz[:, 2],
        "status": status,
        "qx": q[:, 0].copy(),
        "qy": q[:, 1].copy(),
        "qz": q[:, 2].copy(),
        "qw": q[:, 3].copy(),
        "roll_deg": ypr[:, 2],
        "pitch_deg": ypr[:, 1],
        "yaw_deg": ypr[:, 0],
    }
