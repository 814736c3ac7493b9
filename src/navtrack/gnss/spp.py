"""Single point positioning (SPP): weighted least squares on code pseudoranges, all epochs at once.

The batch driver :func:`solve_spp` builds ``(epochs, satellites)`` arrays — pseudoranges,
satellite states at transmission, group delays — and runs one batched Gauss–Newton
(:func:`navtrack.gnss.solve.gauss_newton`) over all epochs. The per-epoch model
(:func:`_Model.__call__`, the kernel) re-evaluates elevation mask, ionosphere, troposphere and
weights at every iterate, as RTKLIB's ``rescode`` does. Unknowns per epoch: ECEF position, the
receiver clock of the first clock group and one inter-system bias (ISB) per further group
(QZSS shares GPS's clock by default, as in RTKLIB 2.4.3). Each epoch ends with a ``status``:

=================== =====================================================================
``ok``              solved, passed the validity tests
``no_ephemeris``    satellites observed, but none has a usable ephemeris (nav file of another
                    day or system, all unhealthy)
``too_few_sats``    fewer usable satellites than unknowns (4 + one per extra clock group),
                    including epochs without any pseudorange of the selected systems
``singular_geometry`` normal matrix singular
``no_convergence``  Gauss–Newton did not converge in ``max_iter`` steps
``rejected_validity`` chi-square test of the weighted residuals failed
``high_dop``        GDOP above ``max_gdop``
=================== =====================================================================

References
----------
T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix E.6 (SPP estimator, variance model,
validation); E. D. Kaplan, C. J. Hegarty, *Understanding GPS/GNSS*, 3rd ed., 2017, 11.2 (WLS,
DOPs); J. Sanz Subirana et al., *GNSS Data Processing* vol. I, ESA TM-23, 2013, 6.1 (ISB).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from functools import lru_cache
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation

if TYPE_CHECKING:
    import pandas as pd

    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations


class SppStatus(IntEnum):
    """Per-epoch outcome of :func:`solve_spp` (names as the CLI prints them, lower case)."""

    OK = 0
    NO_EPHEMERIS = 1
    TOO_FEW_SATS = 2
    SINGULAR_GEOMETRY = 3
    NO_CONVERGENCE = 4
    REJECTED_VALIDITY = 5
    HIGH_DOP = 6


STATUS_NAMES = tuple(s.name.lower() for s in SppStatus)

# Pseudorange codes per system and logical band, in order of preference (RINEX 3 codes first,
# then RINEX 2). The logical band is the frequency (BeiDou B1I is band "2" in RINEX >= 3.03 and
# was written C1I in 3.02).
CODE_PRIORITY: Mapping[str, Mapping[str, tuple[str, ...]]] = MappingProxyType(
    {
        "G": {
            "1": ("C1C", "C1S", "C1L", "C1X", "C1P", "C1W", "C1Y", "C1M", "C1", "P1"),
            "2": ("C2W", "C2P", "C2Y", "C2L", "C2S", "C2X", "C2C", "C2D", "P2", "C2"),
            "5": ("C5Q", "C5X", "C5I", "C5"),
        },
        "J": {
            "1": ("C1C", "C1S", "C1L", "C1X", "C1Z", "C1"),
            "2": ("C2L", "C2S", "C2X", "C2"),
            "5": ("C5Q", "C5X", "C5I", "C5"),
        },
        "E": {
            "1": ("C1C", "C1X", "C1B", "C1Z", "C1A", "C1"),
            "5": ("C5Q", "C5X", "C5I", "C5"),
            "7": ("C7Q", "C7X", "C7I", "C7"),
        },
        "C": {
            "2": ("C2I", "C2X", "C2Q", "C1I", "C2"),
            "6": ("C6I", "C6X", "C6Q", "C6"),
            "7": ("C7I", "C7X", "C7Q", "C7"),
        },
        "R": {"1": ("C1C", "C1P", "C1", "P1"), "2": ("C2C", "C2P", "C2", "P2")},
        "I": {"5": ("C5A", "C5X", "C5")},
    }
)
PRIMARY_BAND = MappingProxyType({"G": "1", "J": "1", "E": "1", "R": "1", "C": "2", "I": "5"})
IONOFREE_BANDS = MappingProxyType(
    {"G": ("1", "2"), "J": ("1", "2"), "E": ("1", "7"), "R": ("1", "2"), "C": ("2", "6")}
)
DEFAULT_CLOCK_GROUP = MappingProxyType({"J": "G"})
"""Systems sharing another system's receiver clock (QZSS on GPS time, RTKLIB 2.4.3)."""


@dataclass(frozen=True, slots=True)
class SppConfig:
    """Options of :func:`solve_spp`; the defaults reproduce RTKLIB 2.4.3's single mode.

    Attributes
    ----------
    systems : str
        System letters to use (``"GREJC"``: all supported).
    elmask_deg : float
        Elevation cut-off (deg).
    weighting : {"rtklib", "elevation", "cn0", "equal"}
        Measurement variance model: ``rtklib`` is RTKLIB's
        ``f^2 a^2 (b^2 + b^2 / sin el) + URA^2 + var_iono + var_tropo + 0.3^2`` (``a = 100``,
        ``b = 0.003`` m, ``f`` 1.5 for GLONASS) — see ``shared/data/gnss/rtklib_spp/README.md``;
        ``elevation`` ``sigma0^2 (1 + 1 / sin^2 el)``; ``cn0`` ``sigma0^2 + C 10^(-C/N0 / 10)``
        with the SIGMA-epsilon constant ``C = 1.61e4 m^2 Hz`` of the C/A code (Hartinger &
        Brunner 1999) for tracking noise and ``sigma0`` for orbit, clock and atmosphere errors,
        falling back to ``elevation`` where C/N0 is missing; ``equal`` ``sigma0`` for all.
    iono : {"klobuchar", "ionofree", "off"}
        Broadcast Klobuchar (scaled by ``(f_L1/f)^2`` for other carriers), dual-frequency
        ionosphere-free combination (:data:`IONOFREE_BANDS`), or none.
    tropo : {"saastamoinen", "off"}
    max_gdop : float
        Epochs with a larger GDOP are rejected (RTKLIB ``pos2-rejgdop``).
    chi2_alpha : float
        Significance of the chi-square test of the weighted residuals (RTKLIB: 0.001); 0 turns
        the test off.
    max_iter : int
    xtol_m : float
        Gauss–Newton step-norm convergence threshold (RTKLIB: 1e-4 m).
    max_age_s : mapping of str to float, optional
        Ephemeris validity per system (default :data:`navtrack.gnss.ephemeris.MAX_AGE_S`).
    healthy_only : bool
        Skip satellites whose ephemeris is flagged unhealthy.
    galileo_nav : {"inav", "fnav", "any"}
    clock_groups : mapping of str to str
        System -> system whose clock it shares.
    sigma0_m : float
        Scale (m) of the ``elevation``, ``cn0`` and ``equal`` models: the zenith-level
        signal-in-space plus atmosphere error of broadcast-ephemeris SPP (1.5 m).
    max_ura_m : float
        Satellites with a larger broadcast URA are not used (RTKLIB: 300 m).
    tgd_systems : str
        Systems whose broadcast group delay (TGD/BGD) is applied to single-frequency
        pseudoranges. QZSS is left out by default: RTKLIB 2.4.3 b34's solutions of the shared
        SEPT file behave as if the QZSS TGD were zero (median distance to RTKLIB 0.16 m without,
        0.70 m with it; 3D RMS against the reference 1.43 m without, 2.03 m with), although
        IS-QZSS-PNT specifies it for L1C/A like GPS's. Add ``"J"`` to follow the ICD.
    sp3_needs_broadcast : bool
        With SP3 orbits, use only satellites that also have a valid broadcast ephemeris (RTKLIB
        2.4.3 removes the satellite clock with the broadcast clock before interpolating SP3 and
        drops satellites without one; navtrack uses the SP3 clock and keeps them by default).
    """

    systems: str = "GREJC"
    elmask_deg: float = 15.0
    weighting: str = "rtklib"
    iono: str = "klobuchar"
    tropo: str = "saastamoinen"
    max_gdop: float = 30.0
    chi2_alpha: float = 0.001
    max_iter: int = 10
    xtol_m: float = 1e-4
    max_age_s: Mapping[str, float] | None = None
    healthy_only: bool = True
    galileo_nav: str = "inav"
    clock_groups: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_CLOCK_GROUP))
    sigma0_m: float = 1.5
    max_ura_m: float = 300.0
    tgd_systems: str = "GECIR"
    sp3_needs_broadcast: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "clock_groups", MappingProxyType(dict(self.clock_groups)))
        if self.max_age_s is not None:
            object.__setattr__(self, "max_age_s", MappingProxyType(dict(self.max_age_s)))
        if self.weighting not in ("rtklib", "elevation", "cn0", "equal"):
            raise ValueError(
                f"weighting: expected rtklib, elevation, cn0 or equal, got {self.weighting!r}"
            )
        if self.iono not in ("klobuchar", "ionofree", "off"):
            raise ValueError(f"iono: expected klobuchar, ionofree or off, got {self.iono!r}")
        if self.tropo not in ("saastamoinen", "off"):
            raise ValueError(f"tropo: expected saastamoinen or off, got {self.tropo!r}")
        bad = set(self.systems) - set("GRECJI")
        if bad:
            raise ValueError(f"systems: unknown system letters {''.join(sorted(bad))!r}")
        if not 0.0 <= self.elmask_deg < 90.0:
            raise ValueError(f"elmask_deg: expected 0 <= mask < 90, got {self.elmask_deg}")
        if not 0.0 <= self.chi2_alpha < 1.0:
            raise ValueError(f"chi2_alpha: expected 0 <= alpha < 1, got {self.chi2_alpha}")


@dataclass(frozen=True, slots=True, eq=False)
class SppResult:
    """Single point positions of all epochs.

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Epoch time tags (receiver time, GPS s).
    sats : tuple of str, length S
        Satellite ids of the satellite axis.
    clock_groups : tuple of str
        Clock parameter names: the first is the receiver clock of that system, the others ISBs.
    pos_m : ndarray, shape (E, 3)
        ECEF position (m); NaN where ``status`` is not ``ok`` and no estimate exists.
    clock_m : ndarray, shape (E,)
        Receiver clock offset times c (m) of the first clock group.
    isb_m : ndarray, shape (E, G-1)
        Inter-system biases (m) of the other clock groups (NaN where the group had no satellite).
    cov : ndarray, shape (E, 3+G, 3+G)
        Covariance of ``(x, y, z, clock, isb...)`` (m^2).
    cov_enu_m2 : ndarray, shape (E, 3, 3)
        Position covariance rotated to local east/north/up.
    status : ndarray of int8, shape (E,)
        :class:`SppStatus`.
    used : ndarray of bool, shape (E, S)
        Satellites used in the final iterate.
    observed : ndarray of bool, shape (E, S)
        Satellites with a pseudorange of the selected systems.
    no_ephemeris : ndarray of bool, shape (E, S)
        Observed but without a usable (healthy, valid, in-window) ephemeris.
    residuals_m : ndarray, shape (E, S)
        Pseudorange residuals (observed minus computed, m) of the used satellites, NaN elsewhere.
    sigma_m : ndarray, shape (E, S)
        Measurement standard deviations used in the weights.
    azel_rad : ndarray, shape (E, S, 2)
        Azimuth and elevation at the solution.
    dop : ndarray, shape (E, 4)
        GDOP, PDOP, HDOP, VDOP of the used satellites (one clock, unit weights, as RTKLIB).
    chi2 : ndarray, shape (E,)
        Weighted sum of squared residuals.
    dof : ndarray of int, shape (E,)
        Redundancy.
    iterations : ndarray of int, shape (E,)
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    clock_groups: tuple[str, ...]
    pos_m: FloatArray
    clock_m: FloatArray
    isb_m: FloatArray
    cov: FloatArray
    cov_enu_m2: FloatArray
    status: np.ndarray
    used: BoolArray
    observed: BoolArray
    no_ephemeris: BoolArray
    residuals_m: FloatArray
    sigma_m: FloatArray
    azel_rad: FloatArray
    dop: FloatArray
    chi2: FloatArray
    dof: IntArray
    iterations: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def n_sats(self) -> IntArray:
        """Satellites used per epoch."""
        return self.used.sum(axis=1)

    @property
    def ok(self) -> BoolArray:
        return self.status == SppStatus.OK

    def status_counts(self) -> dict[str, int]:
        """Number of epochs per status name (all statuses, zeros included)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(SppStatus))
        return {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}


# --------------------------------------------------------------------------- chi-square
def _chi2_cdf(x: float, k: int) -> float:
    """Regularised lower incomplete gamma ``P(k/2, x/2)`` (series, Numerical Recipes 6.2)."""
    if x <= 0.0:
        return 0.0
    a, y = 0.5 * k, 0.5 * x
    if y < a + 1.0:
        term = total = 1.0 / a
        n = a
        for _ in range(10000):
            n += 1.0
            term *= y / n
            total += term
            if abs(term) < abs(total) * 1e-15:
                break
        return total * math.exp(-y + a * math.log(y) - math.lgamma(a))
    # continued fraction for the upper tail (modified Lentz)
    tiny = 1e-300
    b = y + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    for i in range(1, 10000):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < 1e-15:
            break
    return 1.0 - math.exp(-y + a * math.log(y) - math.lgamma(a)) * h


@lru_cache(maxsize=4096)
def chi2_quantile(p: float, k: int) -> float:
    """Quantile of the chi-square distribution with ``k`` degrees of freedom (bisection on the
    CDF; Wilson–Hilferty bracket). ``scipy.stats.chi2.ppf`` is the test oracle; this keeps scipy
    out of the command's start-up."""
    if not 0.0 < p < 1.0 or k < 1:
        raise ValueError(f"chi2_quantile: need 0 < p < 1 and k >= 1, got p={p}, k={k}")
    lo, hi = 0.0, max(10.0, k + 20.0 * math.sqrt(2.0 * k) + 50.0)
    while _chi2_cdf(hi, k) < p:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _chi2_cdf(mid, k) < p:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-10 * hi:
            break
    return 0.5 * (lo + hi)


# --------------------------------------------------------------------------- measurements
def select_pseudoranges(
    obs: Observations, sats: list[str], band_by_sys: Mapping[str, str]
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Pseudorange and C/N0 of one logical band per satellite, first available code per epoch.

    Returns
    -------
    pr_m : ndarray, shape (E, S)
    cn0_dbhz : ndarray, shape (E, S)
        Signal strength of the same signal (NaN where not recorded).
    code_index : ndarray of int, shape (E, S)
        Index into ``obs.codes`` of the code used (-1: none).
    """
    n_e = obs.t_gps_s.size
    pr = np.full((n_e, len(sats)), np.nan)
    cn0 = np.full((n_e, len(sats)), np.nan)
    used = np.full((n_e, len(sats)), -1, dtype=np.int64)
    codes = list(obs.codes)
    col = {s: i for i, s in enumerate(obs.sats)}
    for j, sat in enumerate(sats):
        sys = sat[0]
        band = band_by_sys.get(sys)
        if band is None:
            continue
        types = obs.header.obs_types.get(sys) if obs.header.obs_types else None
        for code in CODE_PRIORITY.get(sys, {}).get(band, ()):
            if code not in codes or (types and code not in types):
                continue
            k = codes.index(code)
            v = obs.values[:, col[sat], k]
            take = np.isfinite(v) & (v > 0) & np.isnan(pr[:, j])
            if not take.any():
                continue
            pr[take, j] = v[take]
            used[take, j] = k
            s_code = "S" + code[1:]
            if s_code in codes:
                cn0[take, j] = obs.values[take, col[sat], codes.index(s_code)]
    return pr, cn0, used


# --------------------------------------------------------------------------- kernel
@dataclass(eq=False)
class _Model:
    """The per-epoch pseudorange model evaluated for a batch of epochs (the SPP kernel)."""

    t_rx: FloatArray  # (E,)
    y: FloatArray  # (E, S) pseudorange corrected for satellite clock and group delay
    sat_pos: FloatArray  # (E, S, 3)
    base_valid: BoolArray  # (E, S)
    group: IntArray  # (S,) clock group index
    n_groups: int
    iono_scale: FloatArray  # (E, S) (f_L1/f)^2, 0 for iono-free
    var_sat: FloatArray  # (E, S) ephemeris variance + code bias variance
    var_fact: FloatArray  # (S,) system factor squared
    cn0: FloatArray  # (E, S)
    klob: FloatArray | None
    config: SppConfig
    ionofree: bool

    def geometry(self, x: FloatArray, idx: IntArray) -> dict[str, Any]:
        from navtrack.gnss.corrections import geometric_range

        rcv = x[:, :3]
        rs = self.sat_pos[idx]
        rho, los = geometric_range(rs, rcv[:, None, :])
        llh = ecef_to_geodetic(rcv)
        rot = enu_rotation(llh[:, 0], llh[:, 1])  # (b, 3, 3)
        enu = np.einsum("bij,bsj->bsi", rot, los)
        az = np.mod(np.arctan2(enu[..., 0], enu[..., 1]), 2.0 * np.pi)
        el = np.arcsin(np.clip(enu[..., 2], -1.0, 1.0))
        # inside the earth (start from the centre): no mask, no atmosphere (el = 90 deg)
        deep = np.linalg.norm(rcv, axis=1) < 1e6
        el = np.where(deep[:, None], np.pi / 2.0, el)
        return {"rho": rho, "los": los, "llh": llh, "az": az, "el": el, "deep": deep}

    def __call__(
        self, x: FloatArray, idx: IntArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        from navtrack.gnss.corrections import klobuchar_delay_m, saastamoinen_delay_m

        cfg = self.config
        g = self.geometry(x, idx)
        el, az, llh, deep = g["el"], g["az"], g["llh"], g["deep"]
        valid = self.base_valid[idx] & (el >= math.radians(cfg.elmask_deg))
        lat = llh[:, 0:1]
        lon = llh[:, 1:2]
        h = llh[:, 2:3]
        atm = ~deep[:, None]
        if cfg.iono == "klobuchar":
            iono_l1 = klobuchar_delay_m(self.t_rx[idx, None], lat, lon, az, el, self.klob)
            iono_l1 = np.where(atm, iono_l1, 0.0)
            iono = iono_l1 * self.iono_scale[idx]
            var_iono = (0.5 * iono_l1) ** 2
        elif cfg.iono == "ionofree":
            iono = np.zeros_like(el)
            var_iono = np.zeros_like(el)
        else:
            iono = np.zeros_like(el)
            var_iono = np.full_like(el, 5.0**2)
        if cfg.tropo == "saastamoinen":
            trop = np.where(atm, saastamoinen_delay_m(lat, h, el), 0.0)
            var_trop = (0.3 / (np.sin(el) + 0.1)) ** 2
        else:
            trop = np.zeros_like(el)
            var_trop = np.full_like(el, 3.0**2)
        b = idx.size
        n_s = self.group.size
        clk = x[:, 3 : 3 + self.n_groups]
        clock = clk[:, 0:1] + np.where(self.group > 0, clk[:, np.maximum(self.group, 0)], 0.0)
        v = self.y[idx] - (g["rho"] + clock + iono + trop)
        J = np.zeros((b, n_s, 3 + self.n_groups))
        J[..., :3] = -g["los"]
        J[..., 3] = 1.0
        if self.n_groups > 1:
            for k in range(1, self.n_groups):
                J[..., 3 + k] = (self.group == k).astype(float)
        sin_el = np.sin(el)
        if cfg.weighting == "rtklib":
            base = 100.0**2 * (0.003**2 + 0.003**2 / sin_el)
            if self.ionofree:
                base = base * 9.0
            var = self.var_fact * base + self.var_sat[idx] + var_iono + var_trop
        elif cfg.weighting == "elevation":
            var = cfg.sigma0_m**2 * (1.0 + 1.0 / sin_el**2)
        elif cfg.weighting == "cn0":
            c_n0 = self.cn0[idx]
            var = np.where(
                np.isfinite(c_n0),
                cfg.sigma0_m**2 + 1.61e4 * 10.0 ** (-np.nan_to_num(c_n0) / 10.0),
                cfg.sigma0_m**2 * (1.0 + 1.0 / sin_el**2),
            )
        else:
            var = np.full_like(el, cfg.sigma0_m**2)
        valid &= np.isfinite(v) & np.isfinite(var) & (var > 0)
        w = np.where(valid, 1.0 / np.where(valid, var, 1.0), 0.0)
        J = np.where(valid[..., None], J, 0.0)
        return np.where(valid, v, 0.0), J, w, valid


# --------------------------------------------------------------------------- driver
def _klobuchar_params(nav_iono: Mapping[str, Any] | None) -> FloatArray | None:
    if not nav_iono:
        return None
    for a, b in (("GPSA", "GPSB"), ("QZSA", "QZSB"), ("BDSA", "BDSB")):
        if a in nav_iono and b in nav_iono:
            p = np.concatenate(
                [np.asarray(nav_iono[a], float)[:4], np.asarray(nav_iono[b], float)[:4]]
            )
            if np.all(np.isfinite(p)) and np.any(p):
                return p
    return None


def _start_position(obs: Observations) -> FloatArray:
    xyz = getattr(obs.header, "approx_xyz_m", None)
    if xyz is not None:
        r = float(np.linalg.norm(xyz))
        if 6.0e6 < r < 6.6e6:
            return np.asarray(xyz, dtype=float)
    return np.zeros(3)


def dops(los_enu: FloatArray, used: BoolArray) -> FloatArray:
    """GDOP, PDOP, HDOP, VDOP with one receiver clock and unit weights.

    Parameters
    ----------
    los_enu : ndarray, shape (E, S, 3)
        Unit line-of-sight vectors in local east/north/up.
    used : ndarray of bool, shape (E, S)

    Returns
    -------
    ndarray, shape (E, 4)
        NaN where fewer than 4 satellites or singular.
    """
    n_e = los_enu.shape[0]
    H = np.concatenate([-los_enu, np.ones((*los_enu.shape[:2], 1))], axis=-1)
    H = np.where(used[..., None], H, 0.0)
    N = np.einsum("esi,esj->eij", H, H)
    out = np.full((n_e, 4), np.nan)
    ok = used.sum(axis=1) >= 4
    ok[ok] = np.abs(np.linalg.det(N[ok])) > 1e-12
    if ok.any():
        Q = np.linalg.inv(N[ok])
        d = np.einsum("eii->ei", Q)
        out[ok, 0] = np.sqrt(d.sum(axis=1))
        out[ok, 1] = np.sqrt(d[:, :3].sum(axis=1))
        out[ok, 2] = np.sqrt(d[:, :2].sum(axis=1))
        out[ok, 3] = np.sqrt(d[:, 2])
    return out


def solve_spp(
    obs: Observations,
    nav: Any | None = None,
    *,
    sp3: Any | None = None,
    config: SppConfig | None = None,
    x0_m: FloatArray | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> SppResult:
    """Single point positions of every epoch of an observation set.

    Parameters
    ----------
    obs : Observations
        RINEX or Android observations.
    nav : NavData or sequence of NavData, optional
        Broadcast navigation data (orbits and clocks unless ``sp3`` is given; group delays and
        Klobuchar parameters in any case).
    sp3 : Sp3, optional
        Precise orbits and clocks; then broadcast records only provide group delays.
    config : SppConfig, optional
    x0_m : ndarray, shape (3,), optional
        Start position (default: the header's approximate position when plausible, else the
        earth's centre).
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built tables (otherwise built from ``nav``).

    Returns
    -------
    SppResult
    """
    from navtrack.gnss import ephemeris as eph
    from navtrack.gnss.corrections import FREQ_L1_HZ, frequency_hz, ionofree, transmit_time
    from navtrack.gnss.solve import LsqStatus, gauss_newton

    cfg = config or SppConfig()
    navs: list[Any] = [] if nav is None else list(nav) if isinstance(nav, list | tuple) else [nav]
    if ephemeris is None:
        tables = eph.merge_tables([eph.ephemeris_tables(n) for n in navs]) if navs else {}
    else:
        tables = dict(ephemeris)
    if sp3 is None and not tables:
        raise ValueError("nav: no broadcast ephemerides and no SP3 given")
    klob = None
    for n in navs:
        klob = _klobuchar_params(getattr(n, "iono", None))
        if klob is not None:
            break

    orbit_systems = set(tables) if sp3 is None else {s[0] for s in sp3.sats}
    systems = [s for s in "GRECJI" if s in cfg.systems and s in obs.systems]
    sats = [s for s in obs.sats if s[0] in systems]
    t_rx = np.asarray(obs.t_gps_s, dtype=float)
    n_e, n_s = t_rx.size, len(sats)

    # measurements
    ionofree_mode = cfg.iono == "ionofree"
    if ionofree_mode:
        b1 = {s: IONOFREE_BANDS[s][0] for s in systems if s in IONOFREE_BANDS}
        b2 = {s: IONOFREE_BANDS[s][1] for s in systems if s in IONOFREE_BANDS}
        p1, cn0, _ = select_pseudoranges(obs, sats, b1)
        p2, _, _ = select_pseudoranges(obs, sats, b2)
    else:
        b1 = {s: PRIMARY_BAND[s] for s in systems}
        p1, cn0, _ = select_pseudoranges(obs, sats, b1)
        p2 = None
    observed = np.isfinite(p1) if p2 is None else np.isfinite(p1) & np.isfinite(p2)
    t_sv = np.where(observed, transmit_time(t_rx, p1), np.nan)

    # satellite states
    if sp3 is not None:
        states = eph.sp3_states(sp3, sats, t_sv)
    else:
        states = eph.broadcast_states(
            tables,
            sats,
            t_rx,
            t_sv,
            max_age_s=cfg.max_age_s,
            healthy_only=cfg.healthy_only,
            galileo_nav=cfg.galileo_nav,
        )
    # group delays, frequencies (from broadcast records; for SP3 the nearest record)
    sats_arr = np.array(sats, dtype=str)
    gd = np.zeros((n_e, n_s))
    scale = np.zeros((n_e, n_s))
    fact = np.ones(n_s)
    y = np.full((n_e, n_s), np.nan)
    for sys in systems:
        cols = np.flatnonzero(np.char.startswith(sats_arr, sys)) if n_s else np.array([], int)
        if cols.size == 0:
            continue
        table = tables.get(sys)
        if table is not None:
            if sp3 is None:
                idx = states.eph_index[:, cols]
            else:
                idx = eph.select_ephemeris(
                    table,
                    [sats[c] for c in cols],
                    t_rx,
                    max_age_s=1e9,
                    healthy_only=False,
                    galileo_nav=cfg.galileo_nav,
                )
        else:
            idx = np.full((n_e, cols.size), -1, dtype=np.int64)
        fnum = None
        if sys == "R" and table is not None:
            fn = table.get("freq_num")
            fnum = np.where(idx >= 0, fn[np.maximum(idx, 0)], np.nan)
        fact[cols] = 1.5**2 if sys == "R" else 1.0
        if ionofree_mode:
            ba, bb = IONOFREE_BANDS[sys]
            fa = frequency_hz(sys, ba, fnum)
            fb = frequency_hz(sys, bb, fnum)
            ga = eph.group_delay_s(table, idx, ba) if table is not None else 0.0
            gb = eph.group_delay_s(table, idx, bb) if table is not None else 0.0
            if p2 is None:  # pragma: no cover - set above in ionofree mode
                raise RuntimeError("ionofree: second-frequency pseudoranges missing")
            pc = ionofree(p1[:, cols], p2[:, cols], fa, fb)
            gdc = (fa**2 * ga - fb**2 * gb) / (fa**2 - fb**2)
            gd[:, cols] = gdc
            y[:, cols] = pc
        else:
            band = b1[sys]
            f = frequency_hz(sys, band, fnum)
            scale[:, cols] = (FREQ_L1_HZ / f) ** 2
            if table is not None and sys in cfg.tgd_systems:
                gd[:, cols] = eph.group_delay_s(table, idx, band)
            y[:, cols] = p1[:, cols]
    y = y + C_MPS * (states.clock_s - gd)
    if sp3 is not None and cfg.sp3_needs_broadcast:
        bc = eph.broadcast_states(
            tables,
            sats,
            t_rx,
            t_sv,
            max_age_s=cfg.max_age_s,
            healthy_only=False,
            galileo_nav=cfg.galileo_nav,
        )
        has_eph_bc = bc.valid
    else:
        has_eph_bc = np.ones((n_e, n_s), dtype=bool)
    var_sat = states.var_m2 + 0.3**2
    has_eph = states.valid & np.array([s[0] in orbit_systems for s in sats], dtype=bool)
    has_eph &= has_eph_bc
    base_valid = observed & has_eph & np.isfinite(y)
    if cfg.healthy_only:
        base_valid &= states.svh == 0
    base_valid &= states.var_m2 <= cfg.max_ura_m**2
    no_eph = observed & ~(has_eph & (states.svh == 0 if cfg.healthy_only else True))

    # clock groups
    group_sys: list[str] = []
    for s in systems:
        grp = cfg.clock_groups.get(s, s)
        grp = grp if grp in systems else s
        present = base_valid[:, [i for i, sat in enumerate(sats) if sat[0] == s]].any()
        if present and grp not in group_sys:
            group_sys.append(grp)
    group_sys.sort(key="GRECJI".index)
    if not group_sys:
        group_sys = [systems[0]] if systems else ["G"]
    gidx = {g: i for i, g in enumerate(group_sys)}
    group = np.array(
        [gidx.get(cfg.clock_groups.get(s[0], s[0]), gidx.get(s[0], 0)) for s in sats],
        dtype=np.int64,
    )
    n_groups = len(group_sys)

    model = _Model(
        t_rx=t_rx,
        y=y,
        sat_pos=states.pos_m,
        base_valid=base_valid,
        group=group,
        n_groups=n_groups,
        iono_scale=scale,
        var_sat=var_sat,
        var_fact=fact,
        cn0=cn0,
        klob=klob,
        config=cfg,
        ionofree=ionofree_mode,
    )
    x0 = np.zeros((n_e, 3 + n_groups))
    x0[:, :3] = _start_position(obs) if x0_m is None else np.asarray(x0_m, dtype=float)
    if n_s == 0:
        model.base_valid = np.zeros((n_e, 0), dtype=bool)
    lsq = gauss_newton(model, x0, max_iter=cfg.max_iter, xtol=cfg.xtol_m)

    # statuses
    status = np.full(n_e, SppStatus.OK, dtype=np.int8)
    status[lsq.status == LsqStatus.NO_CONVERGENCE] = SppStatus.NO_CONVERGENCE
    status[lsq.status == LsqStatus.SINGULAR] = SppStatus.SINGULAR_GEOMETRY
    status[lsq.status == LsqStatus.TOO_FEW_MEASUREMENTS] = SppStatus.TOO_FEW_SATS
    status[~base_valid.any(axis=1) & observed.any(axis=1)] = SppStatus.TOO_FEW_SATS
    status[observed.any(axis=1) & ~(has_eph & observed).any(axis=1)] = SppStatus.NO_EPHEMERIS
    status[~observed.any(axis=1)] = SppStatus.TOO_FEW_SATS

    x = lsq.x
    geo = model.geometry(x, np.arange(n_e))
    llh = geo["llh"]
    rot = enu_rotation(llh[:, 0], llh[:, 1])
    los_enu = np.einsum("eij,esj->esi", rot, geo["los"])
    dop = dops(los_enu, lsq.valid)
    conv = status == SppStatus.OK
    if cfg.chi2_alpha > 0:
        thr = np.array(
            [chi2_quantile(1.0 - cfg.chi2_alpha, int(k)) if k > 0 else np.inf for k in lsq.dof]
        )
        status[conv & (lsq.dof > 0) & (lsq.cost > thr)] = SppStatus.REJECTED_VALIDITY
    gdop = dop[:, 0]
    status[conv & (status == SppStatus.OK) & ~(gdop <= cfg.max_gdop)] = SppStatus.HIGH_DOP
    solved = np.isin(status, (SppStatus.OK, SppStatus.REJECTED_VALIDITY, SppStatus.HIGH_DOP))
    used = lsq.valid & solved[:, None]
    pos = np.where(solved[:, None], x[:, :3], np.nan)
    clock_m = np.where(solved, x[:, 3], np.nan)
    group_seen = np.stack([(lsq.valid & (group == k)).any(axis=1) for k in range(n_groups)], 1)
    isb = np.where(solved[:, None] & group_seen[:, 1:], x[:, 4:], np.nan)
    cov = lsq.cov
    cov_enu = np.einsum("eij,ejk,elk->eil", rot, cov[:, :3, :3], rot)
    cov_enu = np.where(solved[:, None, None], cov_enu, np.nan)
    azel = np.stack([geo["az"], geo["el"]], axis=-1)
    sigma = np.where(lsq.valid, 1.0 / np.sqrt(np.where(lsq.valid, lsq.weights, 1.0)), np.nan)
    return SppResult(
        t_gps_s=t_rx.copy(),
        sats=tuple(sats),
        clock_groups=tuple(group_sys),
        pos_m=pos,
        clock_m=clock_m,
        isb_m=isb,
        cov=cov,
        cov_enu_m2=cov_enu,
        status=status,
        used=used,
        observed=observed,
        no_ephemeris=no_eph,
        residuals_m=np.where(lsq.valid, lsq.residuals, np.nan),
        sigma_m=sigma,
        azel_rad=azel,
        dop=dop,
        chi2=lsq.cost.copy(),
        dof=lsq.dof.copy(),
        iterations=lsq.iterations.copy(),
    )


def subset_epochs(obs: Observations, epochs: slice | IntArray) -> Observations:
    """The observations of some epochs only (same satellites and codes)."""
    from navtrack.gnss.observations import Observations as Obs

    return Obs(
        path=obs.path,
        header=obs.header,
        t_gps_s=np.array(obs.t_gps_s[epochs]),
        epoch_flag=np.array(obs.epoch_flag[epochs]),
        clock_offset_s=np.array(obs.clock_offset_s[epochs]),
        sats=obs.sats,
        codes=obs.codes,
        values=np.array(obs.values[epochs]),
        lli=np.array(obs.lli[epochs]),
        ssi=np.array(obs.ssi[epochs]),
    )


def concatenate_results(parts: list[SppResult]) -> SppResult:
    """Join results of consecutive epoch blocks (same satellites); clock groups are aligned by
    name, ISBs and covariance entries of groups absent from a block are NaN."""
    if not parts:
        raise ValueError("parts: need at least one result")
    groups = [g for g in "GRECJI" if any(g in p.clock_groups for p in parts)]
    if parts[0].clock_groups and parts[0].clock_groups[0] in groups:
        first = parts[0].clock_groups[0]
        groups.remove(first)
        groups.insert(0, first)
    n_p = 3 + len(groups)

    def align(p: SppResult) -> tuple[FloatArray, FloatArray]:
        e = p.t_gps_s.size
        isb = np.full((e, len(groups) - 1), np.nan)
        cov = np.full((e, n_p, n_p), np.nan)
        src = [0, 1, 2] + [
            3 + p.clock_groups.index(g) if g in p.clock_groups else -1 for g in groups
        ]
        for i, si in enumerate(src):
            for j, sj in enumerate(src):
                if si >= 0 and sj >= 0:
                    cov[:, i, j] = p.cov[:, si, sj]
        for k, g in enumerate(groups[1:]):
            if g in p.clock_groups[1:]:
                isb[:, k] = p.isb_m[:, p.clock_groups.index(g) - 1]
        return isb, cov

    aligned = [align(p) for p in parts]

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    return SppResult(
        t_gps_s=cat("t_gps_s"),
        sats=parts[0].sats,
        clock_groups=tuple(groups),
        pos_m=cat("pos_m"),
        clock_m=cat("clock_m"),
        isb_m=np.concatenate([a[0] for a in aligned]),
        cov=np.concatenate([a[1] for a in aligned]),
        cov_enu_m2=cat("cov_enu_m2"),
        status=cat("status"),
        used=cat("used"),
        observed=cat("observed"),
        no_ephemeris=cat("no_ephemeris"),
        residuals_m=cat("residuals_m"),
        sigma_m=cat("sigma_m"),
        azel_rad=cat("azel_rad"),
        dop=cat("dop"),
        chi2=cat("chi2"),
        dof=cat("dof"),
        iterations=cat("iterations"),
    )


def solution_columns(result: SppResult) -> dict[str, np.ndarray]:
    """The solution as columns (plain arrays, no pandas), one row per epoch, all statuses.

    Columns: ``time_gps`` (ISO 8601 GPST, ms), ``week``, ``tow_s``, ``x_m``, ``y_m``, ``z_m``,
    ``lat_deg``, ``lon_deg``, ``h_m`` (ellipsoidal), ``clock_m``, ``sd_e_m``, ``sd_n_m``,
    ``sd_u_m`` (formal standard deviations), ``n_sats`` (used), ``pdop``, ``status`` (name),
    ``excluded`` (space-separated ids; empty until RAIM lands), then ``t_gps_s``, ``gdop``,
    ``hdop``, ``vdop`` and one ``isb_<sys>_m`` per further clock group. Positions are NaN
    where no estimate exists.
    """
    from navtrack.timescale import to_datetime64, week_tow

    week, tow = week_tow(result.t_gps_s)
    llh = ecef_to_geodetic(result.pos_m)
    sd = np.sqrt(np.einsum("eii->ei", result.cov_enu_m2))
    times = np.datetime_as_string(to_datetime64(result.t_gps_s), unit="ms")
    n = result.t_gps_s.size
    cols: dict[str, np.ndarray] = {
        "time_gps": times,
        "week": week,
        "tow_s": tow,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "lat_deg": np.degrees(llh[:, 0]),
        "lon_deg": np.degrees(llh[:, 1]),
        "h_m": llh[:, 2],
        "clock_m": result.clock_m,
        "sd_e_m": sd[:, 0],
        "sd_n_m": sd[:, 1],
        "sd_u_m": sd[:, 2],
        "n_sats": result.used.sum(axis=1) if result.used.size else np.zeros(n, np.int64),
        "pdop": result.dop[:, 1],
        "status": np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)],
        "excluded": np.full(n, "", dtype=object),
        "t_gps_s": result.t_gps_s,
        "gdop": result.dop[:, 0],
        "hdop": result.dop[:, 2],
        "vdop": result.dop[:, 3],
    }
    for k, g in enumerate(result.clock_groups[1:]):
        cols[f"isb_{g}_m"] = result.isb_m[:, k]
    return cols


def solution_table(result: SppResult) -> pd.DataFrame:
    """The solution as a pandas DataFrame with the columns of :func:`solution_columns` (the
    input of ``navtrack.io.solution.write_solution`` and ``navtrack.plots.gnss``)."""
    import pandas as pd

    return pd.DataFrame(solution_columns(result))
