"""WGS-84 geodesy against published values and pymap3d (an independent implementation)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navtrack.geodesy import (
    azimuth_elevation,
    ecef_to_enu,
    ecef_to_geodetic,
    enu_rotation,
    geodetic_to_ecef,
)

# GEONET F5 coordinate of station 0759 and its ECEF given in shared/data/gnss/README.md
# (35.160867766 deg, 139.613844940 deg, 68.4545 m -> -3976219.258, 3382371.435, 3652511.347).
F5_0759_LLH = (35.160867766, 139.613844940, 68.4545)
F5_0759_XYZ = (-3976219.258, 3382371.435, 3652511.347)


def test_geodetic_to_ecef_matches_published_station_coordinate() -> None:
    lat, lon, h = F5_0759_LLH
    xyz = geodetic_to_ecef([np.radians(lat), np.radians(lon), h])
    np.testing.assert_allclose(xyz, F5_0759_XYZ, atol=2e-3)


def test_ecef_to_geodetic_matches_published_station_coordinate() -> None:
    llh = ecef_to_geodetic(F5_0759_XYZ)
    assert np.degrees(llh[0]) == pytest.approx(F5_0759_LLH[0], abs=2e-8)
    assert np.degrees(llh[1]) == pytest.approx(F5_0759_LLH[1], abs=2e-8)
    assert llh[2] == pytest.approx(F5_0759_LLH[2], abs=2e-3)


@settings(max_examples=200, deadline=None)
@given(
    lat=st.floats(-89.99, 89.99),
    lon=st.floats(-180, 180),
    h=st.floats(-500.0, 3.0e7),
)
def test_round_trip_from_ground_to_orbit(lat: float, lon: float, h: float) -> None:
    llh = np.array([np.radians(lat), np.radians(lon), h])
    back = ecef_to_geodetic(geodetic_to_ecef(llh))
    np.testing.assert_allclose(back[:2], llh[:2], atol=1e-11)
    assert back[2] == pytest.approx(h, abs=1e-4)


def test_against_pymap3d() -> None:
    pm = pytest.importorskip("pymap3d")
    rng = np.random.default_rng(7)
    lat = rng.uniform(-89, 89, 50)
    lon = rng.uniform(-180, 180, 50)
    h = rng.uniform(-100, 2.5e7, 50)
    xyz = geodetic_to_ecef(np.stack([np.radians(lat), np.radians(lon), h], axis=-1))
    np.testing.assert_allclose(xyz, np.stack(pm.geodetic2ecef(lat, lon, h), axis=-1), atol=1e-6)
    ref = np.array(F5_0759_XYZ)
    enu = ecef_to_enu(xyz, ref)
    ref_llh = ecef_to_geodetic(ref)
    expected = pm.ecef2enu(
        xyz[:, 0], xyz[:, 1], xyz[:, 2], np.degrees(ref_llh[0]), np.degrees(ref_llh[1]), ref_llh[2]
    )
    np.testing.assert_allclose(enu, np.stack(expected, axis=-1), atol=1e-6)
    azel = azimuth_elevation(xyz, ref)
    az, el, _ = pm.ecef2aer(
        xyz[:, 0], xyz[:, 1], xyz[:, 2], np.degrees(ref_llh[0]), np.degrees(ref_llh[1]), ref_llh[2]
    )
    np.testing.assert_allclose(np.degrees(azel[:, 1]), el, atol=1e-9)
    np.testing.assert_allclose(np.degrees(azel[:, 0]), az, atol=1e-9)


def test_enu_rotation_is_orthonormal_and_batched() -> None:
    rot = enu_rotation(np.radians([10.0, -45.0, 80.0]), np.radians([0.0, 120.0, -60.0]))
    assert rot.shape == (3, 3, 3)
    np.testing.assert_allclose(
        rot @ np.swapaxes(rot, -1, -2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-15
    )


def test_zenith_satellite_has_ninety_degrees_elevation() -> None:
    llh = np.array([np.radians(35.0), np.radians(139.0), 0.0])
    rcv = geodetic_to_ecef(llh)
    sat = geodetic_to_ecef(llh + np.array([0.0, 0.0, 20.2e6]))
    assert np.degrees(azimuth_elevation(sat, rcv)[1]) == pytest.approx(90.0, abs=1e-9)


def test_wrong_shape_names_the_parameter() -> None:
    with pytest.raises(ValueError, match="xyz"):
        ecef_to_geodetic([1.0, 2.0])


def test_check_near_surface() -> None:
    from navtrack.geodesy import check_near_surface

    # station SEPT (cssrlib xyz_ref) and a point on the polar axis: accepted
    sept = [-3962108.673, 3381309.574, 3668678.638]
    np.testing.assert_array_equal(check_near_surface(sept), sept)
    check_near_surface([0.0, 0.0, 6356752.3])
    # kilometres, degrees/metres, a non-finite value, a wrong shape: refused, naming the input
    for bad in (
        [-3962.1, 3381.3, 3668.7],
        [35.16, 139.61, 68.45],
        [np.nan, 0.0, 6.4e6],
        [6.4e6, 0.0],
    ):
        with pytest.raises(ValueError, match="ref"):
            check_near_surface(bad, "ref")
