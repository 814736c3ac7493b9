"""Range corrections: Sagnac against an exact rotation, Klobuchar closed-form cases from
IS-GPS-200 20.3.3.5.2.5, Saastamoinen zenith values, ionosphere-free combination."""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.geodesy import C_MPS, OMEGA_E_RAD_S, geodetic_to_ecef
from navtrack.gnss.corrections import (
    KLOBUCHAR_DEFAULT,
    frequency_hz,
    geometric_range,
    ionofree,
    klobuchar_delay_m,
    saastamoinen_delay_m,
    transmit_time,
)


def test_sagnac_matches_rotating_the_satellite() -> None:
    """First-order Sagnac term vs the exact light-time solution: rotate the transmit-time
    satellite position by Omega_e tau into the reception frame and iterate tau."""
    rng = np.random.default_rng(1)
    rcv = geodetic_to_ecef([np.radians(35.3), np.radians(139.5), 60.0])
    for _ in range(20):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if d @ rcv < 0:
            d = -d
        sat = rcv + 2.2e7 * d
        rho, los = geometric_range(sat, rcv)
        tau = np.linalg.norm(sat - rcv) / C_MPS
        for _ in range(5):
            a = OMEGA_E_RAD_S * tau
            rot = np.array(
                [[np.cos(a), np.sin(a), 0.0], [-np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]]
            )
            exact = np.linalg.norm(rot @ sat - rcv)
            tau = exact / C_MPS
        assert rho == pytest.approx(exact, abs=2e-3)
        np.testing.assert_allclose(np.linalg.norm(los), 1.0)
    # the term itself is tens of metres at most
    assert abs(rho - np.linalg.norm(sat - rcv)) < 40.0


def test_transmit_time_broadcasts_over_satellites() -> None:
    t = transmit_time(np.array([100.0, 101.0]), np.array([[C_MPS * 0.07, np.nan]] * 2))
    np.testing.assert_allclose(t[:, 0], [99.93, 100.93])
    assert np.isnan(t[:, 1]).all()


def test_klobuchar_closed_form_peak_and_night() -> None:
    """alpha = (a0, 0, 0, 0), beta = (b0, 0, 0, 0), zenith, receiver at longitude 0: the pierce
    point is overhead (psi cos A shifts latitude only), local time = GPS time of day. At 14:00
    (x = 0) the delay is F (5 ns + a0) c with F = 1 + 16 (0.53 - 0.5)^3; at night F 5 ns c."""
    a0, b0 = 2.0e-8, 1.0e5
    p = np.array([a0, 0.0, 0.0, 0.0, b0, 0.0, 0.0, 0.0])
    f = 1.0 + 16.0 * 0.03**3
    peak = klobuchar_delay_m(50400.0, 0.3, 0.0, 0.0, np.pi / 2, p)
    assert peak == pytest.approx(f * (5e-9 + a0) * C_MPS, rel=1e-12)
    night = klobuchar_delay_m(3 * 3600.0, 0.3, 0.0, 0.0, np.pi / 2, p)
    assert night == pytest.approx(f * 5e-9 * C_MPS, rel=1e-12)
    # half a period after the peak: x = 2 pi (t - 50400) / PER, cosine series to 4th order
    t = 50400.0 + 0.2 * b0 / (2 * np.pi)
    x = 0.2
    mid = klobuchar_delay_m(t, 0.3, 0.0, 0.0, np.pi / 2, p)
    assert mid == pytest.approx(f * (5e-9 + a0 * (1 - x**2 / 2 + x**4 / 24)) * C_MPS, rel=1e-12)
    # PER floor 72000 s and AMP floor 0
    low = np.array([-1e-6, 0.0, 0.0, 0.0, 1e3, 0.0, 0.0, 0.0])
    assert klobuchar_delay_m(50400.0, 0.3, 0.0, 0.0, np.pi / 2, low) == pytest.approx(
        f * 5e-9 * C_MPS
    )


def test_klobuchar_geometry_and_defaults() -> None:
    el = np.radians([5.0, 15.0, 30.0, 60.0, 90.0])
    d = klobuchar_delay_m(45000.0, np.radians(35.0), np.radians(139.0), 0.0, el, None)
    assert np.all(np.diff(d) < 0)  # obliquity: larger delays at low elevation
    assert 1.0 < d[-1] < 30.0
    assert d[0] / d[-1] == pytest.approx(1 + 16 * (0.53 - 5 / 180) ** 3, rel=0.2)
    zero = klobuchar_delay_m(45000.0, 0.6, 2.4, 0.0, 1.0, np.zeros(8))
    dflt = klobuchar_delay_m(45000.0, 0.6, 2.4, 0.0, 1.0, KLOBUCHAR_DEFAULT)
    assert zero == dflt
    assert klobuchar_delay_m(45000.0, 0.6, 2.4, 0.0, -0.1, None) == 0.0
    with pytest.raises(ValueError, match="params"):
        klobuchar_delay_m(0.0, 0.0, 0.0, 0.0, 1.0, np.zeros(7))


def test_saastamoinen_zenith_and_mapping() -> None:
    """Sea level, standard atmosphere (1013.25 hPa, 15 degC), RH 0: zenith hydrostatic delay
    0.0022768 x 1013.25 / (1 - 0.00266 cos 2 phi) m, i.e. 2.3070 m at 45 deg (Saastamoinen
    1972; Davis et al. 1985 eq. for the zenith hydrostatic delay)."""
    z = saastamoinen_delay_m(np.radians(45.0), 0.0, np.pi / 2, humidity=0.0)
    assert z == pytest.approx(2.3070, abs=1e-4)
    z_eq = saastamoinen_delay_m(0.0, 0.0, np.pi / 2, humidity=0.0)
    assert z_eq == pytest.approx(0.0022768 * 1013.25 / (1 - 0.00266), rel=1e-12)
    wet = saastamoinen_delay_m(np.radians(45.0), 0.0, np.pi / 2, humidity=0.7) - z
    assert 0.05 < wet < 0.2  # wet delay at 15 degC, 70 % humidity: ~0.1 m
    el = np.radians(30.0)
    assert saastamoinen_delay_m(0.7, 100.0, el) == pytest.approx(
        saastamoinen_delay_m(0.7, 100.0, np.pi / 2) / np.sin(el), rel=1e-12
    )
    h = np.array([-200.0, 2000.0, 2.0e4])
    out = saastamoinen_delay_m(0.7, h, 0.5)
    assert out[0] == 0.0
    assert out[2] == 0.0
    assert 1.5 < out[1] < 4.0
    assert saastamoinen_delay_m(0.7, 10.0, -0.01) == 0.0


def test_ionofree_removes_first_order_ionosphere() -> None:
    f1, f2 = frequency_hz("G", "1"), frequency_hz("G", "2")
    rho, iono_l1 = 2.1e7, 7.5
    p1 = rho + iono_l1
    p2 = rho + iono_l1 * (f1 / f2) ** 2
    assert ionofree(p1, p2, f1, f2) == pytest.approx(rho, abs=1e-6)


def test_frequencies() -> None:
    assert frequency_hz("E", "5") == 1176.45e6
    assert frequency_hz("C", "2") == 1561.098e6
    np.testing.assert_allclose(
        frequency_hz("R", "1", [-7, 0, 6]), [1598.0625e6, 1602.0e6, 1605.375e6]
    )
    with pytest.raises(ValueError, match="band"):
        frequency_hz("G", "7")
