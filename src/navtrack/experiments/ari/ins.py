"""Navigation-grade INS attitude series of the ARI reproduction: paper 5's Tables 4–5 regime.

The paper smooths the attitude angles registered by an INS: the Space Shuttle's every 2 s
(Table 4, ARI(6,1)) and a Falcon jet's Litton LTN-72 at 10 Hz (Table 5, ARI(2,2)). The
like-for-like series here (:func:`ins_series`): a navigation-grade strapdown gyro triad
(:data:`navtrack.attitude.imu_sim.LN200`: 1 °/h bias, 0.07 °/√h angle random walk, 100 ppm
scale factor, 400 Hz) simulated on real vehicle motion and integrated to attitude from a
perfect initial alignment, read out as yaw / pitch / roll (the paper's angles, degrees) every
2 s and at 10 Hz. :func:`ins_rows` fits every column as the carrier-phase strips are fitted
(:func:`navtrack.experiments.ari.carrier.strip_fits`).

The real motion (:func:`vehicle_attitude`): the pyins car's 1 Hz GNSS velocities
(``shared/data/trajectory/pyins_gnss/gnss.csv``): heading ``atan2(v_E, v_N)``, pitch the
flight-path angle ``atan2(-v_D, v_H)``, roll the coordinated-turn bank ``atan(v_H psi' / g)``
(what an aircraft flying that path would bank; a car does not), over the span the car moves
(horizontal speed above ``min_speed_mps``; heading is undefined at rest), interpolated to the
gyro rate by cubic splines. The reference frame (local north/east/down) is treated as inertial:
an INS compensates the Earth and transport rates in its mechanisation, and they are not what
the paper's series show.

Limits: the motion carries no content above the GNSS rate's 0.5 Hz (the spline is smooth
between the 1 Hz samples), and gyro integration adds no white reading noise: the attitude
error of a strapdown INS is the integral of the gyro errors (angle random walk integrated, a
random walk; bias, a drift), which the ARI model assigns to its process, not to ``sigma_n``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from navtrack._typing import FloatArray
from navtrack.attitude.imu_sim import LN200, integrate_rates, simulate_gyro
from navtrack.errors import FileFormatError
from navtrack.experiments.ari.carrier import strip_fits

__all__ = [
    "INS_COLUMNS",
    "INS_DESCRIPTION",
    "INS_READOUTS",
    "InsSeries",
    "ins_rows",
    "ins_series",
    "vehicle_attitude",
]

#: What the INS series are, for the tables.
INS_DESCRIPTION = (
    "A navigation-grade strapdown gyro triad (`navtrack.attitude.imu_sim.LN200`: 1 °/h bias, "
    "0.07 °/√h angle random walk, 100 ppm scale factor, 400 Hz) simulated on real vehicle "
    "motion (the pyins car's 1 Hz GNSS velocities: heading, flight-path pitch, coordinated-turn "
    "bank; splined to 400 Hz) and integrated to attitude from a perfect alignment; yaw / pitch "
    "/ roll read out every 2 s (the Shuttle's interval; the whole drive) and at 10 Hz (the "
    "aircraft's; the central 3000 epochs). Each column: order by BIC with the exact-likelihood "
    "estimator, the paper's estimator at that order (both VCE forms); *motion alone*: the same "
    "fit on the true angles at the same epochs (the control: what the car's motion alone "
    "gives); *INS error step*: RMS of the epoch-to-epoch change of the true INS error (a white "
    "reading noise σn would show as √2 σn there)."
)

#: The paper's attitude angles (degrees).
INS_COLUMNS = ("yaw_deg", "pitch_deg", "roll_deg")

_G_MPS2 = 9.80665


@dataclass(frozen=True, slots=True)
class InsSeries:
    """Attitude angles read out from a simulated INS at one interval.

    Attributes
    ----------
    source : str
    dt_s : float
    columns : dict of str to ndarray (n,)
        ``yaw_deg``, ``pitch_deg``, ``roll_deg`` (yaw unwrapped).
    error_deg : dict of str to ndarray (n,)
        INS minus true angle at the same epochs.
    meta : dict
    """

    source: str
    dt_s: float
    columns: dict[str, FloatArray]
    error_deg: dict[str, FloatArray]
    meta: dict[str, Any]


def vehicle_attitude(
    path: Path, rate_hz: float, min_speed_mps: float = 2.0
) -> tuple[FloatArray, FloatArray]:
    """True attitude of the pyins car at ``rate_hz``: times ``(n,)`` s and body -> NED
    quaternions ``(n, 4)`` scalar-last (see the module notes)."""
    df = pd.read_csv(path)
    missing = [c for c in ("time", "VN", "VE", "VD") if c not in df.columns]
    if missing:
        raise FileFormatError(path, None, f"no column {', '.join(missing)}")
    t = df["time"].to_numpy(dtype=float)
    vn, ve, vd = (df[c].to_numpy(dtype=float) for c in ("VN", "VE", "VD"))
    vh = np.hypot(vn, ve)
    moving = np.flatnonzero(vh > min_speed_mps)
    if moving.size < 10:
        raise ValueError(f"{path}: fewer than 10 epochs faster than {min_speed_mps} m/s")
    span = slice(int(moving[0]), int(moving[-1]) + 1)
    t, vn, ve, vd, vh = t[span], vn[span], ve[span], vd[span], vh[span]
    fast = vh > min_speed_mps
    # heading where it is defined, interpolated over the slow epochs in between
    heading = np.interp(t, t[fast], np.unwrap(np.arctan2(ve[fast], vn[fast])))
    pitch = np.arctan2(-vd, np.maximum(vh, min_speed_mps))
    t_out = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz)) + 1) / rate_hz
    psi = CubicSpline(t, heading)
    speed = np.interp(t_out, t, vh)
    roll = np.arctan(speed * psi(t_out, 1) / _G_MPS2)
    euler = np.column_stack([psi(t_out), CubicSpline(t, pitch)(t_out), roll])
    return t_out, np.asarray(Rotation.from_euler("ZYX", euler).as_quat(), dtype=np.float64)


def _angles_deg(q_xyzw: FloatArray) -> FloatArray:
    """Yaw, pitch, roll ``(n, 3)`` in degrees of body -> NED quaternions, yaw unwrapped."""
    ang = np.asarray(Rotation.from_quat(q_xyzw).as_euler("ZYX"), dtype=np.float64)
    ang[:, 0] = np.unwrap(ang[:, 0])
    return np.degrees(ang)


#: Readout intervals (s) and the most epochs kept (the central part of the drive): the
#: Shuttle's 2 s (the whole drive, 389 epochs, within its strips' 120–800) and the aircraft's
#: 10 Hz (the central 3000 epochs, 5 min, as the paper analyses the central part of the flight).
INS_READOUTS: tuple[tuple[float, int], ...] = ((2.0, 800), (0.1, 3000))


def ins_series(
    path: Path,
    rng: np.random.Generator,
    readouts: tuple[tuple[float, int], ...] = INS_READOUTS,
    min_speed_mps: float = 2.0,
) -> list[InsSeries]:
    """The INS attitude of :func:`vehicle_attitude` read out at each ``(interval_s, max_epochs)``
    of ``readouts`` (one gyro recording, integrated once; the central ``max_epochs`` kept; see
    the module notes). Each series carries the true angles at the same epochs in
    ``meta["truth_deg"]`` (the control: the motion alone)."""
    t, truth = vehicle_attitude(path, LN200.rate_hz, min_speed_mps)
    record = simulate_gyro(t, truth, LN200, rng)
    ins = integrate_rates(t, record.gyr_rad_s, truth[0])
    ins_deg, true_deg = _angles_deg(ins), _angles_deg(truth)
    out = []
    for dt, max_epochs in readouts:
        step = round(dt * LN200.rate_hz)
        if step < 1 or not math.isclose(step / LN200.rate_hz, dt, rel_tol=1e-9):
            raise ValueError(f"readouts: {dt} s is not a multiple of the gyro interval")
        idx = np.arange(0, t.size, step)
        if idx.size > max_epochs:
            first = (idx.size - max_epochs) // 2
            idx = idx[first : first + max_epochs]
        label = f"{dt:g} s" if dt >= 1 else f"{1 / dt:g} Hz"
        out.append(
            InsSeries(
                f"LN-200 INS on pyins car, {label}",
                dt,
                {c: ins_deg[idx, k] for k, c in enumerate(INS_COLUMNS)},
                {c: ins_deg[idx, k] - true_deg[idx, k] for k, c in enumerate(INS_COLUMNS)},
                {
                    "gyro": LN200.name,
                    "bias_deg_h": LN200.bias_deg_h,
                    "arw_deg_sqrt_h": LN200.arw_deg_sqrt_h,
                    "scale_factor_ppm": LN200.scale_factor * 1e6,
                    "gyro_rate_hz": LN200.rate_hz,
                    "drive_s": float(t[-1] - t[0]),
                    "span_s": [float(t[idx[0]] - t[0]), float(t[idx[-1]] - t[0])],
                    "truth_deg": {c: true_deg[idx, k] for k, c in enumerate(INS_COLUMNS)},
                    "drawn_bias_deg_h": [
                        float(b) * 180 / math.pi * 3600 for b in record.bias_rad_s
                    ],
                },
            )
        )
    return out


def ins_rows(series: list[InsSeries], robust_process: bool) -> list[dict[str, Any]]:
    """Every column of every INS series fitted whole (:func:`strip_fits`), and the true
    motion alone at the same epochs (the control, exact estimator only: ``truth``); with the
    RMS of the true INS error and of its epoch-to-epoch steps."""
    rows = []
    for src in series:
        for col, values in src.columns.items():
            err = src.error_deg[col]
            t0 = time.perf_counter()
            fits = strip_fits(values, robust_process)
            control = strip_fits(src.meta["truth_deg"][col], robust_process, paper=False)
            rows.append(
                {
                    "source": src.source,
                    "column": col,
                    "n": int(values.size),
                    "dt_s": src.dt_s,
                    "robust_process": robust_process,
                    "error_rms_deg": float(np.sqrt(np.mean((err - err.mean()) ** 2))),
                    "error_step_rms_deg": float(np.sqrt(np.mean(np.diff(err) ** 2))),
                    "meta": {k: v for k, v in src.meta.items() if k != "truth_deg"},
                    **fits,
                    "truth": control["exact"],
                    "seconds": time.perf_counter() - t0,
                }
            )
    return rows
