"""Accuracy statistics of position errors: mean, RMS and 95th percentile.

One definition shared by the ``navtrack pos`` summary and the solution figures, so the numbers
printed and the numbers drawn agree.

References
----------
The 95 % error is the accuracy measure of the GPS SPS Performance Standard (5th ed., 2020,
section 3.8); the percentile is the linear interpolation of the order statistics (Hyndman &
Fan, "Sample quantiles in statistical packages", Am. Stat. 50(4), 1996, definition 7, the
``numpy.percentile`` default).
"""

from __future__ import annotations

import numpy as np

from navtrack._record import Record
from navtrack._typing import ArrayLike

__all__ = ["ErrorStats", "enu_error_stats", "error_stats"]


class ErrorStats(Record, eq=True):
    """Statistics of one error quantity over the finite values of a series.

    Attributes
    ----------
    n : int
        Number of finite values used (NaN and infinite values are left out and not counted).
    mean_m : float
        Mean of the (signed) values (m); NaN when ``n == 0``.
    rms_m : float
        Root mean square (m); NaN when ``n == 0``.
    p95_m : float
        95th percentile of the absolute values (m); NaN when ``n == 0``.
    """

    n: int
    mean_m: float
    rms_m: float
    p95_m: float


def error_stats(err_m: ArrayLike) -> ErrorStats:
    """Mean, RMS and 95th percentile of the absolute value of an error series.

    Parameters
    ----------
    err_m : array-like, shape (n,)
        Errors (m), signed (e.g. up) or non-negative (horizontal, 3D). Non-finite values
        (failed epochs) are left out; ``ErrorStats.n`` says how many were used.

    Returns
    -------
    ErrorStats
    """
    x = np.asarray(err_m, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size == 0:
        nan = float("nan")
        return ErrorStats(0, nan, nan, nan)
    return ErrorStats(
        n=int(x.size),
        mean_m=float(np.mean(x)),
        rms_m=float(np.sqrt(np.mean(x**2))),
        p95_m=float(np.percentile(np.abs(x), 95)),
    )


def enu_error_stats(enu_m: ArrayLike) -> dict[str, ErrorStats]:
    """Error statistics of east, north, up, horizontal and 3D errors.

    Parameters
    ----------
    enu_m : array-like, shape (n, 3)
        East, north, up errors (m) of the solution minus the reference in the local frame of the
        reference; rows with a non-finite component are left out of every statistic.

    Returns
    -------
    dict of str to ErrorStats
        Keys ``east``, ``north``, ``up`` (signed components), ``horizontal``
        (``hypot(e, n)``) and ``3D`` (Euclidean norm).

    Raises
    ------
    ValueError
        ``enu_m`` is not of shape (n, 3).
    """
    enu = np.asarray(enu_m, dtype=float)
    if enu.ndim != 2 or enu.shape[1] != 3:
        raise ValueError(f"enu_m: expected shape (n, 3), got {enu.shape}")
    enu = enu[np.isfinite(enu).all(axis=1)]
    return {
        "east": error_stats(enu[:, 0]),
        "north": error_stats(enu[:, 1]),
        "up": error_stats(enu[:, 2]),
        "horizontal": error_stats(np.hypot(enu[:, 0], enu[:, 1])),
        "3D": error_stats(np.linalg.norm(enu, axis=1)),
    }
