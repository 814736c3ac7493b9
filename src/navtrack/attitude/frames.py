"""Earth-fixed and inertial frames of the attitude chain (paper 6, eq. 3).

The paper propagates the gyro in an Earth-centred inertial frame: the WGS-84 (ECEF) frame frozen
at the time of the first camera fix ``t0``. A camera fix gives the attitude in the Earth-fixed
frame, ``E R_C``; the IMU attitude in the inertial frame is (eq. 3)
``M R_I = M R_C (E R_C)⁻¹ E R_I(t)``, where ``E R_I(t)`` is the Earth's rotation since ``t0``.
In navtrack's convention (quaternions rotate body vectors into the reference frame, see
:mod:`navtrack.attitude.quaternion`) that chain reads

``q_I_b(t) = R_z(Ω (t - t0)) ⊗ q_E_loc ⊗ q_loc_c(t) ⊗ q_c_b``

with ``q_E_loc`` the local east/north/up frame in ECEF, ``q_loc_c`` the camera fix and ``q_c_b``
the known camera-IMU mounting. A gyro fixed to the ground measures the Earth rate,
``Ω = 7.2921151467e-5 rad/s`` (15.04 °/h); without the chain a 200 s sequence drifts by
``Ω · 200 s ≈ 0.84°`` about the Earth's axis.

References
----------
.. [1] ALHAT flash-LIDAR field test 1, trajectory reconstruction (paper 6): "The inertial
   frame" and eq. 3.
.. [2] NIMA TR8350.2, WGS-84 (the Earth rate ``OMEGA_E_RAD_S``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._typing import ArrayLike, FloatArray
from navtrack.geodesy import OMEGA_E_RAD_S, enu_rotation

__all__ = ["earth_rate_enu", "earth_rotation", "enu_to_ecef", "from_inertial", "to_inertial"]


def earth_rate_enu(lat_rad: float) -> FloatArray:
    """The Earth's rotation rate in the local east/north/up frame, ``(3,)`` rad/s:
    ``Ω [0, cos φ, sin φ]``."""
    return OMEGA_E_RAD_S * np.array([0.0, np.cos(lat_rad), np.sin(lat_rad)])


def earth_rotation(t_s: ArrayLike, t0_s: float) -> Rotation:
    """ECEF -> inertial rotations at ``t_s``: the Earth turned by ``Ω (t - t0)`` about its axis
    since the inertial frame was frozen at ``t0`` (``E R_I(t)`` of eq. 3, as a body -> reference
    rotation with the ECEF frame as body)."""
    t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
    angle = OMEGA_E_RAD_S * (t - t0_s)
    return Rotation.from_rotvec(angle[:, None] * np.array([0.0, 0.0, 1.0]))


def enu_to_ecef(lat_rad: float, lon_rad: float) -> Rotation:
    """The local east/north/up frame at (``lat_rad``, ``lon_rad``) as a rotation ENU -> ECEF."""
    return Rotation.from_matrix(np.asarray(enu_rotation(lat_rad, lon_rad)).T)


def to_inertial(
    t_s: ArrayLike,
    quat_local_xyzw: ArrayLike,
    t0_s: float,
    lat_rad: float,
    lon_rad: float,
    mount: Rotation | None = None,
) -> FloatArray:
    """Attitudes in the local Earth-fixed frame -> IMU attitudes in the inertial frame (eq. 3).

    Parameters
    ----------
    t_s : (m,) times of the attitudes, s
    quat_local_xyzw : (m, 4) attitudes (camera -> local ENU), scalar-last
    t0_s : float
        Time at which the inertial frame coincides with ECEF (the first camera fix).
    lat_rad, lon_rad : float
        Origin of the local ENU frame.
    mount : Rotation or None
        IMU -> camera rotation (``M R_C`` of eq. 3, known); identity when ``None``.

    Returns
    -------
    (m, 4) IMU -> inertial attitudes, scalar-last
    """
    q = Rotation.from_quat(np.asarray(quat_local_xyzw, dtype=np.float64).reshape(-1, 4))
    chain = earth_rotation(t_s, t0_s) * enu_to_ecef(lat_rad, lon_rad) * q
    if mount is not None:
        chain = chain * mount
    return np.asarray(chain.as_quat(), dtype=np.float64)


def from_inertial(
    t_s: ArrayLike,
    quat_inertial_xyzw: ArrayLike,
    t0_s: float,
    lat_rad: float,
    lon_rad: float,
    mount: Rotation | None = None,
) -> FloatArray:
    """The inverse of :func:`to_inertial`: IMU -> inertial attitudes back to camera -> local
    ENU attitudes at ``t_s``, shape ``(m, 4)``."""
    q = Rotation.from_quat(np.asarray(quat_inertial_xyzw, dtype=np.float64).reshape(-1, 4))
    chain = (earth_rotation(t_s, t0_s) * enu_to_ecef(lat_rad, lon_rad)).inv() * q
    if mount is not None:
        chain = chain * mount.inv()
    return np.asarray(chain.as_quat(), dtype=np.float64)
