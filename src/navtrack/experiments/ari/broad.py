"""BROAD orientation as ARI series, and what explains the gross-error flags on it.

BROAD's optical (motion-capture) orientation at 285.7 Hz is decimated (the reproduction keeps
every 10th sample: 28.6 Hz, near the paper's 10 Hz INS) and written as three series by
:mod:`navtrack.smoothing.attitude`: by default the rotation-vector path of the body-frame
increments (no singularity), or the paper's yaw/pitch/roll (``form="euler"``, singular near
``|pitch| = 90 deg``; epochs of Euler artefacts are then marked as model errors).

Each series carries, per epoch, the causes that can explain a flag without the ARI model
(:data:`FLAG_CAUSES`), found from data the fit does not see — the full-rate optical samples
and the IMU gyroscope:

* ``gap_edge`` — within :data:`GAP_EDGE_EPOCHS` epochs of a missing sample (optical tracking
  lost or regained);
* ``optical_spike`` — the sample departs from the midpoint of its two full-rate neighbours
  (3.5 ms either side) by more than :data:`SPIKE_FACTOR` times the trial's median departure:
  a measurement outlier;
* ``fast_motion`` — the gyroscope's rate change across the sample, or the optical rotation
  from or to the neighbouring sample, is in the trial's top :data:`FAST_QUANTILE` — real
  motion an ARI model with one constant ``sigma_e`` does not follow.

How the thresholds were chosen (trial 07, fast rotation) and judged (trial 02, slow rotation):
``docs/ari.md``, method notes, "What explains a flag".
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._typing import BoolArray, FloatArray
from navtrack.experiments.ari.series import RealSeries
from navtrack.io.broad import read_broad
from navtrack.smoothing.attitude import (
    ATTITUDE_COLUMNS,
    ATTITUDE_FORMS,
    AttitudeForm,
    euler_artefacts,
    euler_path,
    increment_path,
)

__all__ = [
    "FAST_QUANTILE",
    "FLAG_CAUSES",
    "GAP_EDGE_EPOCHS",
    "SPIKE_FACTOR",
    "broad_series",
    "flag_causes",
]

#: Causes of :func:`flag_causes`, in the order they are reported.
FLAG_CAUSES = ("gap_edge", "optical_spike", "fast_motion")

#: A flag this many epochs or fewer from a missing sample is at a gap edge.
GAP_EDGE_EPOCHS = 2

#: A sample further than this multiple of the trial's median from the midpoint of its
#: full-rate neighbours is an optical spike.
SPIKE_FACTOR = 5.0

#: Rate changes and rotations per sample above this quantile of the trial are fast motion.
FAST_QUANTILE = 0.9


def flag_causes(
    quat_xyzw: FloatArray, gyr_rad_s: FloatArray, decimate: int
) -> tuple[dict[str, BoolArray], dict[str, float]]:
    """Per decimated epoch, the causes of :data:`FLAG_CAUSES` that hold there.

    Parameters
    ----------
    quat_xyzw : ndarray, shape (N, 4)
        Full-rate optical orientation (scalar-last, NaN rows missing).
    gyr_rad_s : ndarray, shape (N, 3)
        Full-rate gyroscope (rad/s, body frame).
    decimate : int
        The series keeps samples ``0, decimate, 2 decimate, ...``.

    Returns
    -------
    causes : dict of str to ndarray of bool, shape (n,)
        ``n = ceil(N / decimate)`` epochs.
    levels : dict of str to float
        The thresholds actually used (deg, deg/s per sample).
    """
    big_n = quat_xyzw.shape[0]
    ok_full = np.all(np.isfinite(quat_xyzw), axis=1)
    idx = np.arange(0, big_n, decimate)
    n = idx.size
    ok = ok_full[idx]
    missing = ~ok
    gap = np.zeros(n, dtype=bool)
    for shift in range(-GAP_EDGE_EPOCHS, GAP_EDGE_EPOCHS + 1):
        lo, hi = max(shift, 0), n + min(shift, 0)
        gap[lo:hi] |= missing[lo - shift : hi - shift]
    gap &= ok

    # departure of each kept sample from the midpoint of its full-rate neighbours
    spike_deg = np.full(n, np.nan)
    inner = (idx > 0) & (idx < big_n - 1)
    cand = np.flatnonzero(inner & ok)
    j = idx[cand]
    both = ok_full[j - 1] & ok_full[j + 1]
    cand, j = cand[both], j[both]
    if cand.size:
        prev = Rotation.from_quat(quat_xyzw[j - 1])
        half = Rotation.from_rotvec(
            0.5 * (prev.inv() * Rotation.from_quat(quat_xyzw[j + 1])).as_rotvec()
        )
        mid = prev * half
        spike_deg[cand] = np.degrees((mid.inv() * Rotation.from_quat(quat_xyzw[j])).magnitude())
    spike_level = SPIKE_FACTOR * float(np.nanmedian(spike_deg)) if cand.size else np.inf
    spike = np.nan_to_num(spike_deg, nan=0.0) > spike_level

    # gyroscope rate change across the sample, optical rotation from / to the neighbours
    w = gyr_rad_s[idx]
    rate_change = np.full(n, np.nan)
    rate_change[1:-1] = np.degrees(np.linalg.norm(w[2:] - w[:-2], axis=1)) / 2.0
    seen = np.flatnonzero(ok)
    step = np.full(n, np.nan)
    if seen.size > 1:
        rot = Rotation.from_quat(quat_xyzw[idx[seen]])
        step[seen[1:]] = np.degrees((rot[:-1].inv() * rot[1:]).magnitude())
    step_either = np.fmax(step, np.concatenate([step[1:], [np.nan]]))
    rate_level = float(np.nanquantile(rate_change, FAST_QUANTILE))
    step_level = float(np.nanquantile(step, FAST_QUANTILE))
    fast = (np.nan_to_num(rate_change) > rate_level) | (np.nan_to_num(step_either) > step_level)
    causes = {"gap_edge": gap, "optical_spike": spike & ok, "fast_motion": fast & ok}
    levels = {
        "optical_spike_deg": spike_level,
        "fast_rate_change_dps_per_sample": rate_level,
        "fast_rotation_deg_per_sample": step_level,
    }
    return causes, levels


def broad_series(path: Path, *, decimate: int = 1, form: AttitudeForm = "rotvec") -> RealSeries:
    """A BROAD trial's optical orientation as three ARI series (deg).

    Parameters
    ----------
    path : Path
        BROAD trial ``.mat`` file (``opt_quat`` scalar-first, NaN where tracking was lost).
    decimate : int
        Keep every ``decimate``-th sample.
    form : {"rotvec", "euler"}
        ``"rotvec"`` (default): :func:`~navtrack.smoothing.attitude.increment_path`, columns
        ``rotvec_x_deg rotvec_y_deg rotvec_z_deg`` (body axes) — no singularity, so a flag is
        motion or an outlier, not the representation. ``"euler"``: yaw, pitch, roll (intrinsic
        z-y'-x'', unwrapped) as the paper smooths them; Euler artefacts near gimbal lock are
        marked as model errors (``meta["model_error"]``, yaw and roll).

    Returns
    -------
    RealSeries
        ``meta`` holds ``form``, ``max_pitch_deg``, ``rotation_deg_per_sample_p99``, the
        per-epoch ``flag_causes`` (:func:`flag_causes`) and their ``cause_levels``.
    """
    if form not in ATTITUDE_FORMS:
        raise ValueError(f"form: expected one of {ATTITUDE_FORMS}, got {form!r}")
    if decimate < 1:
        raise ValueError(f"decimate: expected >= 1, got {decimate}")
    trial = read_broad(path)
    quat_full = trial.opt_quat_xyzw
    quat = quat_full[::decimate]
    ypr = euler_path(quat)
    values = increment_path(quat) if form == "rotvec" else ypr
    cols = {name: np.degrees(values[:, k]) for k, name in enumerate(ATTITUDE_COLUMNS[form])}
    dt = decimate / trial.rate_hz
    t_s = np.arange(quat.shape[0], dtype=np.float64) * dt
    artefact, step = euler_artefacts(quat)
    causes, levels = flag_causes(quat_full, trial.gyr_rad_s, decimate)
    meta: dict[str, Any] = {
        "form": form,
        "path": str(path),
        "decimate": decimate,
        "kinematic": True,
        "max_pitch_deg": float(np.degrees(np.nanmax(np.abs(ypr[:, 1])))),
        "rotation_deg_per_sample_p99": float(np.degrees(np.nanpercentile(step, 99))),
        "flag_causes": causes,
        "cause_levels": levels,
    }
    if form == "euler":
        meta["euler_artefact_epochs"] = int(np.count_nonzero(artefact))
        meta["model_error"] = {"yaw_deg": artefact, "roll_deg": artefact}
    return RealSeries(f"BROAD {path.stem}", t_s, cols, "deg", dt, meta=meta)
