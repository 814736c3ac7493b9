"""Attitude and trajectory reconstruction (paper 6: ALHAT field test trajectory reconstruction).

Conventions: quaternions scalar-last ``[x, y, z, w]`` (scipy's order), rotating body vectors into
the reference frame; gyro rates in the body frame, propagation by right-multiplication; errors in
the reference frame (:mod:`navtrack.attitude.quaternion` states the mapping to the paper's Wertz
conventions).

Modules:

* :mod:`~navtrack.attitude.quaternion` — delta angles, truncated-series and closed-form
  propagation, error and correction quaternions;
* :mod:`~navtrack.attitude.wahba` — SVD attitude from target rays inside seeded RANSAC;
* :mod:`~navtrack.attitude.frames` — the Earth-rate frame chain (eq. 3);
* :mod:`~navtrack.attitude.imu_sim` — simulated gyros (LN-200 class) on a truth attitude;
* :mod:`~navtrack.attitude.simulate` — camera sightings of surveyed targets from a truth;
* :mod:`~navtrack.attitude.calibration` — least-squares gyro bias/scale/misalignment and timing;
* :mod:`~navtrack.attitude.smoother` — error-state Kalman filter and RTS smoother;
* :mod:`~navtrack.attitude.reconstruct` — the chain of the four estimates on one recording;
* :mod:`~navtrack.attitude.trajectory` — pose trajectory with GNSS positions.
"""

from __future__ import annotations

from navtrack.attitude.calibration import (
    CalibrationConfig,
    GyroCalibration,
    calibrate_gyro,
    calibrated_propagation,
    corrected_rates,
)
from navtrack.attitude.imu_sim import (
    LN200,
    GyroRecord,
    GyroSpec,
    body_rates,
    integrate_rates,
    simulate_gyro,
)
from navtrack.attitude.quaternion import (
    Propagation,
    attitude_errors,
    check_quaternions,
    correction_quaternion,
    delta_angles,
    delta_quaternions,
    from_scalar_first,
    interpolate_attitude,
    propagate,
)
from navtrack.attitude.reconstruct import (
    ESTIMATES,
    AttitudeEstimate,
    Reconstruction,
    ReconstructionConfig,
    reconstruct,
)
from navtrack.attitude.simulate import CameraSimConfig, Sightings, simulate_sightings
from navtrack.attitude.smoother import SmootherConfig, SmootherResult, smooth_attitude
from navtrack.attitude.trajectory import GnssPositions, pose_frame
from navtrack.attitude.wahba import (
    AttitudeFix,
    CameraFixes,
    FixStatus,
    RansacConfig,
    ransac_attitude,
    solve_fixes,
    svd_attitude,
)

__all__ = [
    "ESTIMATES",
    "LN200",
    "AttitudeEstimate",
    "AttitudeFix",
    "CalibrationConfig",
    "CameraFixes",
    "CameraSimConfig",
    "FixStatus",
    "GnssPositions",
    "GyroCalibration",
    "GyroRecord",
    "GyroSpec",
    "Propagation",
    "RansacConfig",
    "Reconstruction",
    "ReconstructionConfig",
    "Sightings",
    "SmootherConfig",
    "SmootherResult",
    "attitude_errors",
    "body_rates",
    "calibrate_gyro",
    "calibrated_propagation",
    "check_quaternions",
    "corrected_rates",
    "correction_quaternion",
    "delta_angles",
    "delta_quaternions",
    "from_scalar_first",
    "integrate_rates",
    "interpolate_attitude",
    "pose_frame",
    "propagate",
    "ransac_attitude",
    "reconstruct",
    "simulate_gyro",
    "simulate_sightings",
    "smooth_attitude",
    "solve_fixes",
    "svd_attitude",
]
