"""BROAD trials (Berlin Robust Orientation Estimation Assessment Dataset): IMU and optical truth.

One reader for every part of navtrack that uses a BROAD ``.mat`` trial (the ARI reproduction's
orientation series, the attitude reconstruction). The file holds the IMU samples and the
synchronised, aligned optical (motion capture) orientation on one time base.

References
----------
D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD — A Benchmark for Robust Inertial Orientation
Estimation", Data 6(7), 2021, https://doi.org/10.3390/data6070072 (data licence CC BY 4.0).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, StrPath
from navtrack.errors import FileFormatError

__all__ = ["BroadTrial", "read_broad"]

_KEYS = ("imu_gyr", "opt_quat", "sampling_rate", "movement")


@dataclass(frozen=True, slots=True, eq=False)
class BroadTrial:
    """One BROAD trial (arrays read-only).

    Attributes
    ----------
    name : str
        Trial name (file stem, e.g. ``07_undisturbed_fast_rotation_B``).
    t_s : ndarray, shape (n,)
        Sample times, s from the first sample (``k / sampling_rate``).
    gyr_rad_s : ndarray, shape (n, 3)
        Angular rate, rad/s, IMU body frame.
    opt_quat_wxyz : ndarray, shape (n, 4)
        Optical orientation as the file stores it: **scalar-first** ``[w, x, y, z]``, rotating
        body (IMU) vectors into the ENU reference frame; NaN rows where tracking was lost.
    movement : ndarray of bool, shape (n,)
        Samples of the movement phase (BROAD's error metrics use only these).
    rate_hz : float
        Sampling rate (285.714 Hz).
    """

    name: str
    t_s: FloatArray
    gyr_rad_s: FloatArray
    opt_quat_wxyz: FloatArray
    movement: BoolArray
    rate_hz: float

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def opt_quat_xyzw(self) -> FloatArray:
        """The optical orientation **scalar-last** ``[x, y, z, w]`` (scipy's order), NaN kept."""
        return self.opt_quat_wxyz[:, [1, 2, 3, 0]]


def read_broad(path: StrPath) -> BroadTrial:
    """Read a BROAD trial ``.mat`` file (MATLAB v5, ``scipy.io.loadmat``).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    BroadTrial

    Raises
    ------
    FileFormatError
        The file is not a MATLAB file or lacks one of ``imu_gyr``, ``opt_quat``,
        ``sampling_rate``, ``movement``, or their shapes disagree (the message names them).
    """
    p = Path(path)
    try:
        mat = scipy.io.loadmat(p, squeeze_me=True)
    except (ValueError, TypeError, NotImplementedError) as exc:
        raise FileFormatError(p, None, f"not a MATLAB v5 BROAD trial: {exc}") from None
    missing = [k for k in _KEYS if k not in mat]
    if missing:
        raise FileFormatError(p, None, f"BROAD trial lacks {', '.join(missing)}")
    gyr = np.asarray(mat["imu_gyr"], dtype=np.float64)
    quat = np.asarray(mat["opt_quat"], dtype=np.float64)
    movement = np.asarray(mat["movement"]).astype(bool)
    n = gyr.shape[0]
    if gyr.shape != (n, 3) or quat.shape != (n, 4) or movement.shape != (n,):
        raise FileFormatError(
            p,
            None,
            f"BROAD shapes disagree: imu_gyr {gyr.shape}, opt_quat {quat.shape}, "
            f"movement {movement.shape}",
        )
    rate = float(mat["sampling_rate"])
    if not rate > 0:
        raise FileFormatError(p, None, f"sampling_rate must be > 0, got {rate}")
    t_s = np.arange(n, dtype=np.float64) / rate
    return BroadTrial(p.stem, t_s, gyr, quat, movement, rate)
