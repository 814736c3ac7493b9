"""Single point positioning (SPP): weighted least squares on code pseudoranges, all epochs at once.

:func:`solve_spp` is a chain of named stages over ``(epochs, satellites)`` arrays with boolean
masks, in the order of RTKLIB's ``pntpos``:

1. :func:`code_pseudoranges` -> :class:`Pseudoranges`: the signals of the configuration;
2. :func:`satellite_states` -> :class:`SatelliteStates`: orbits, clocks, URA, health and group
   delays at transmission (``satposs``);
3. :func:`corrected_measurements` -> :class:`Measurements`: pseudoranges corrected for satellite
   clock and group delay (ionosphere-free if asked), usability masks, clock groups (``prange``);
4. :func:`estimate_position` -> :class:`Estimate`: one batched Gauss–Newton
   (:func:`navtrack.estimation.least_squares.gauss_newton`) whose per-epoch model (the kernel)
   re-evaluates elevation mask, ionosphere, troposphere and weights at every iterate, as RTKLIB's
   ``rescode`` does (``estpos``). It takes a per-(epoch, satellite) exclusion mask and a subset
   of epochs and returns residuals, design matrix, weights, state, covariance, redundancy,
   iterations and status: what fault detection and exclusion need (:func:`merge_estimates`
   puts the re-estimates of some epochs back into the estimate of all);
5. :func:`validate`: chi-square test of the weighted residuals and GDOP limit (``valsol``; the
   stage integrity monitoring replaces);
6. :func:`spp_result` -> :class:`SppResult`.

Blocks of :data:`CHUNK_EPOCHS` epochs bound the memory of long files. Unknowns per epoch: ECEF
position, the receiver clock of the first clock group and one inter-system bias (ISB) per
further group (QZSS shares GPS's clock by default, as in RTKLIB 2.4.3). Each epoch ends with a
``status``:

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

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from functools import lru_cache
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.geodesy import C_MPS, ecef_to_geodetic, enu_rotation

if TYPE_CHECKING:
    import pandas as pd

    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3
    from navtrack.integrity.raim import IntegrityResult, RaimConfig


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

CHUNK_EPOCHS = 3600
"""Epochs per block of :func:`solve_spp` (one hour at 1 Hz)."""

ProgressFn = Callable[[int, int], None]
"""``progress(epochs_done, epochs_total)``, called by :func:`solve_spp` after each block."""


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
        pseudoranges: all by default, as the ICDs specify (IS-GPS-200 20.3.3.3.3.2; IS-QZSS-PNT
        5.7.3, TGD for L1C/A like GPS's; Galileo OS SIS ICD 5.1.5; BDS-SIS-ICD 5.2.4.10).
        RTKLIB 2.4.3 b34 applies them too, but its ``gettgd`` (``pntpos.c``) takes the group
        delay of the *first* record of the satellite in the navigation data (sorted by
        transmission time by ``uniqnav``), not of the ephemeris ``seleph`` chose for the
        epoch: where that first record is a Galileo F/NAV one, its ``BGD(E5b,E1)`` field is 0
        and RTKLIB applies no group delay to the E1 pseudorange (SEPT078M.21P: E03, E08, E15 and
        others).
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
    tgd_systems: str = "GECIRJ"
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

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its constructor's keywords (the read-only mappings as dicts), so that a
        configuration travels to Dask workers."""
        fields: dict[str, Any] = {
            f.name: dict(v) if isinstance(v := getattr(self, f.name), Mapping) else v
            for f in dataclasses.fields(self)
        }
        return (functools.partial(type(self), **fields), ())


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
    integrity : IntegrityResult, optional
        Integrity monitoring of every epoch (:func:`navtrack.integrity.raim.monitor`) when
        :func:`solve_spp` ran with ``raim``.
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
    integrity: IntegrityResult | None = None

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

    def to_frame(self) -> pd.DataFrame:
        """The solution as a pandas DataFrame, one row per epoch: ``t_gps_s`` and the columns
        ``pos --out`` writes, as :func:`navtrack.io.solution.read_solution` reads them back."""
        from navtrack.io.solution import solution_table

        table = solution_table(solution_frame(self))
        table.insert(0, "t_gps_s", self.t_gps_s)
        return table


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


def observation_codes(config: SppConfig | None = None) -> frozenset[str]:
    """Every observation code single point positioning may take for a configuration: the
    pseudorange codes of its systems' bands (:data:`CODE_PRIORITY`), their signal strengths
    (:func:`code_pseudoranges`) and Dopplers (:func:`navtrack.gnss.velocity.doppler_velocity`).
    A reader given them (``read_obs(path, systems=..., codes=...)``) decodes nothing else."""
    cfg = config or SppConfig()
    codes: set[str] = set()
    for sys in cfg.systems:
        bands: tuple[str, ...] = ()
        if cfg.iono == "ionofree":
            bands = IONOFREE_BANDS.get(sys, ())
        elif sys in PRIMARY_BAND:
            bands = (PRIMARY_BAND[sys],)
        for band in bands:
            for code in CODE_PRIORITY.get(sys, {}).get(band, ()):
                codes.update((code, "S" + code[1:], "D" + code[1:]))
    return frozenset(codes)


# --------------------------------------------------------------------------- stage 1: signals
@dataclass(frozen=True, slots=True, eq=False)
class Pseudoranges:
    """Code pseudoranges of the configured signals (the selection part of RTKLIB's ``prange``).

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Epoch time tags (receiver time, GPS s).
    sats : tuple of str, length S
        Satellites of the selected systems present in the observations (the satellite axis of
        every later stage).
    systems : tuple of str
        Selected systems present in the observations, in ``GRECJI`` order.
    pr_m : ndarray, shape (E, S)
        Pseudorange (m) of the primary band (:data:`PRIMARY_BAND`), or of the first band of the
        ionosphere-free pair (:data:`IONOFREE_BANDS`); NaN where not observed.
    pr2_m : ndarray, shape (E, S), or None
        Pseudorange (m) of the second band of the ionosphere-free pair; None for single
        frequency.
    cn0_dbhz : ndarray, shape (E, S)
        C/N0 (dB-Hz) of the signal of ``pr_m``; NaN where not recorded.
    observed : ndarray of bool, shape (E, S)
        All pseudoranges the configuration needs are present.
    approx_xyz_m : ndarray, shape (3,)
        Start position of the estimation (ECEF, m): the header's approximate position when it is
        near the earth's surface, else the earth's centre.
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    systems: tuple[str, ...]
    pr_m: FloatArray
    pr2_m: FloatArray | None
    cn0_dbhz: FloatArray
    observed: BoolArray
    approx_xyz_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def code_pseudoranges(obs: Observations, config: SppConfig | None = None) -> Pseudoranges:
    """Select the pseudoranges the configuration uses (stage 1 of :func:`solve_spp`).

    Parameters
    ----------
    obs : Observations
        RINEX or Android observations.
    config : SppConfig, optional
        ``systems`` and ``iono`` (``ionofree`` selects two bands) are read.

    Returns
    -------
    Pseudoranges
    """
    cfg = config or SppConfig()
    systems = tuple(s for s in "GRECJI" if s in cfg.systems and s in obs.systems)
    sats = [s for s in obs.sats if s[0] in systems]
    p2: FloatArray | None = None
    if cfg.iono == "ionofree":
        b1 = {s: IONOFREE_BANDS[s][0] for s in systems if s in IONOFREE_BANDS}
        b2 = {s: IONOFREE_BANDS[s][1] for s in systems if s in IONOFREE_BANDS}
        p1, cn0, _ = select_pseudoranges(obs, sats, b1)
        p2, _, _ = select_pseudoranges(obs, sats, b2)
        observed = np.isfinite(p1) & np.isfinite(p2)
    else:
        p1, cn0, _ = select_pseudoranges(obs, sats, {s: PRIMARY_BAND[s] for s in systems})
        observed = np.isfinite(p1)
    return Pseudoranges(
        t_gps_s=np.array(obs.t_gps_s, dtype=float),
        sats=tuple(sats),
        systems=systems,
        pr_m=p1,
        pr2_m=p2,
        cn0_dbhz=cn0,
        observed=observed,
        approx_xyz_m=_start_position(obs),
    )


# --------------------------------------------------------------------------- stage 2: satellites
@dataclass(frozen=True, slots=True, eq=False)
class SatelliteStates:
    """Satellite states at signal transmission and the broadcast signal parameters (RTKLIB
    ``satposs`` with the group delays of ``prange``).

    Attributes
    ----------
    sats : tuple of str, length S
    pos_m : ndarray, shape (E, S, 3)
        ECEF position at transmission, in the earth-fixed frame of that time (m).
    clock_s : ndarray, shape (E, S)
        Satellite clock offset (s) with the relativistic term, without group delay.
    var_m2 : ndarray, shape (E, S)
        Signal-in-space range error variance (m^2): broadcast URA/SISA or SP3 accuracy.
    svh : ndarray of int, shape (E, S)
        Broadcast health (0 healthy, -1 no ephemeris).
    group_delay_s : ndarray, shape (E, S)
        Group delay (s) of the measured signal, subtracted from the satellite clock: TGD/BGD of
        the band for systems in ``tgd_systems``, the ionosphere-free combination of the two
        bands' delays with ``iono="ionofree"``, 0 otherwise.
    freq_hz : ndarray, shape (E, S)
        Carrier frequency (Hz) of ``Pseudoranges.pr_m`` (GLONASS channel from the ephemeris).
    freq2_hz : ndarray, shape (E, S), or None
        Carrier frequency (Hz) of ``Pseudoranges.pr2_m`` (ionosphere-free only).
    iono_scale : ndarray, shape (E, S)
        ``(f_L1 / f)^2`` that scales the L1 Klobuchar delay to the measured band; 0 for the
        ionosphere-free combination.
    var_factor : ndarray, shape (S,)
        Square of RTKLIB's system error factor (1.5 for GLONASS, 1 otherwise).
    valid : ndarray of bool, shape (E, S)
        An ephemeris (of an orbit source that covers the system, and broadcast as well when
        ``sp3_needs_broadcast``) was found and evaluated; health is in ``svh``.
    klobuchar : ndarray, shape (8,), or None
        Broadcast Klobuchar alpha0-3, beta0-3 of the first navigation file that has them.
    """

    sats: tuple[str, ...]
    pos_m: FloatArray
    clock_s: FloatArray
    var_m2: FloatArray
    svh: IntArray
    group_delay_s: FloatArray
    freq_hz: FloatArray
    freq2_hz: FloatArray | None
    iono_scale: FloatArray
    var_factor: FloatArray
    valid: BoolArray
    klobuchar: FloatArray | None

    def __post_init__(self) -> None:
        freeze_arrays(self)


def _nav_list(nav: NavData | Sequence[NavData] | None) -> list[NavData]:
    if nav is None:
        return []
    if isinstance(nav, Sequence):
        return list(nav)
    return [nav]


def navigation_tables(
    nav: NavData | Sequence[NavData] | None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> dict[str, EphemerisTable]:
    """Broadcast ephemeris tables per system: ``ephemeris`` when given, else merged from
    ``nav`` (build them once and pass them to every block of a long file)."""
    from navtrack.gnss import ephemeris as eph

    if ephemeris is not None:
        return dict(ephemeris)
    navs = _nav_list(nav)
    return eph.merge_tables([eph.ephemeris_tables(n) for n in navs]) if navs else {}


def satellite_states(
    pr: Pseudoranges,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
) -> SatelliteStates:
    """Satellite positions, clocks and group delays at transmission (stage 2 of
    :func:`solve_spp`).

    Parameters
    ----------
    pr : Pseudoranges
        The transmission time is ``t_rx - P / c`` (:func:`corrections.transmit_time`).
    nav : NavData or sequence of NavData, optional
        Broadcast navigation data: orbits and clocks unless ``sp3`` is given; group delays and
        Klobuchar parameters in any case.
    sp3 : Sp3, optional
        Precise orbits and clocks.
    config : SppConfig, optional
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built tables (:func:`navigation_tables`), otherwise built from ``nav``.

    Returns
    -------
    SatelliteStates

    Raises
    ------
    ValueError
        Neither broadcast ephemerides nor SP3 given.
    """
    from navtrack.gnss import ephemeris as eph
    from navtrack.gnss.corrections import FREQ_L1_HZ, frequency_hz, transmit_time

    cfg = config or SppConfig()
    tables = navigation_tables(nav, ephemeris)
    if sp3 is None and not tables:
        raise ValueError("nav: no broadcast ephemerides and no SP3 given")
    klob = None
    for n in _nav_list(nav):
        klob = _klobuchar_params(n.iono)
        if klob is not None:
            break
    sats = list(pr.sats)
    t_rx = pr.t_gps_s
    n_e, n_s = t_rx.size, len(sats)
    t_sv = np.where(pr.observed, transmit_time(t_rx, pr.pr_m), np.nan)
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
    ionofree_mode = cfg.iono == "ionofree"
    gd = np.zeros((n_e, n_s))
    scale = np.zeros((n_e, n_s))
    freq = np.full((n_e, n_s), np.nan)
    freq2 = np.full((n_e, n_s), np.nan) if ionofree_mode else None
    fact = np.ones(n_s)
    for sys in pr.systems:
        cols = np.flatnonzero([sat[0] == sys for sat in sats]).astype(int)
        if cols.size == 0:
            continue
        table = tables.get(sys)
        if table is None:
            idx = np.full((n_e, cols.size), -1, dtype=np.int64)
        elif sp3 is None:
            idx = states.eph_index[:, cols]
        else:  # group delays and GLONASS channels from the nearest broadcast record
            idx = eph.select_ephemeris(
                table,
                [sats[c] for c in cols],
                t_rx,
                max_age_s=1e9,
                healthy_only=False,
                galileo_nav=cfg.galileo_nav,
            )
        fnum = None
        if sys == "R" and table is not None:
            fnum = np.where(idx >= 0, table.get("freq_num")[np.maximum(idx, 0)], np.nan)
        fact[cols] = 1.5**2 if sys == "R" else 1.0
        if freq2 is not None:
            ba, bb = IONOFREE_BANDS[sys]
            fa = frequency_hz(sys, ba, fnum)
            fb = frequency_hz(sys, bb, fnum)
            ga = eph.group_delay_s(table, idx, ba) if table is not None else 0.0
            gb = eph.group_delay_s(table, idx, bb) if table is not None else 0.0
            gd[:, cols] = (fa**2 * ga - fb**2 * gb) / (fa**2 - fb**2)
            freq[:, cols] = fa
            freq2[:, cols] = fb
        else:
            band = PRIMARY_BAND[sys]
            f = frequency_hz(sys, band, fnum)
            scale[:, cols] = (FREQ_L1_HZ / f) ** 2
            freq[:, cols] = f
            if table is not None and sys in cfg.tgd_systems:
                gd[:, cols] = eph.group_delay_s(table, idx, band)
    orbit_systems = set(tables) if sp3 is None else {s[0] for s in sp3.sats}
    valid = states.valid & np.array([s[0] in orbit_systems for s in sats], dtype=bool)
    if sp3 is not None and cfg.sp3_needs_broadcast:
        valid &= eph.broadcast_states(
            tables,
            sats,
            t_rx,
            t_sv,
            max_age_s=cfg.max_age_s,
            healthy_only=False,
            galileo_nav=cfg.galileo_nav,
        ).valid
    return SatelliteStates(
        sats=pr.sats,
        pos_m=states.pos_m,
        clock_s=states.clock_s,
        var_m2=states.var_m2,
        svh=states.svh,
        group_delay_s=gd,
        freq_hz=freq,
        freq2_hz=freq2,
        iono_scale=scale,
        var_factor=fact,
        valid=valid,
        klobuchar=klob,
    )


# --------------------------------------------------------------------------- stage 3: measurements
@dataclass(frozen=True, slots=True, eq=False)
class Measurements:
    """Pseudoranges corrected for everything that does not depend on the receiver position, the
    inputs of the position-dependent model, and the masks (RTKLIB ``prange`` and the
    satellite-side terms of ``rescode``).

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Epoch time tags (receiver time, GPS s).
    sats : tuple of str, length S
    y_m : ndarray, shape (E, S)
        ``P + c (dt_sat - group delay)`` (m): pseudorange (ionosphere-free combination with
        ``iono="ionofree"``) corrected for satellite clock and group delay; NaN where missing.
    sat_pos_m : ndarray, shape (E, S, 3)
        Satellite position at transmission (ECEF, m).
    var_sat_m2 : ndarray, shape (E, S)
        Satellite-side variance (m^2): URA^2 plus RTKLIB's 0.3 m code bias error squared.
    var_factor : ndarray, shape (S,)
        Square of the system error factor of the ``rtklib`` weighting.
    iono_scale : ndarray, shape (E, S)
        ``(f_L1 / f)^2`` for the Klobuchar delay; 0 for the ionosphere-free combination.
    cn0_dbhz : ndarray, shape (E, S)
        C/N0 (dB-Hz) for the ``cn0`` weighting.
    klobuchar : ndarray, shape (8,), or None
        Broadcast Klobuchar parameters (None: the default set of
        :func:`corrections.klobuchar_delay_m`).
    ionofree : bool
        ``y_m`` is the ionosphere-free combination.
    observed : ndarray of bool, shape (E, S)
        The needed pseudoranges are present.
    has_ephemeris : ndarray of bool, shape (E, S)
        A usable ephemeris was evaluated (health not considered).
    no_ephemeris : ndarray of bool, shape (E, S)
        Observed, but without a usable (and, with ``healthy_only``, healthy) ephemeris.
    usable : ndarray of bool, shape (E, S)
        Candidates of the estimation: observed, finite ``y_m``, ephemeris usable (healthy with
        ``healthy_only``), URA within ``max_ura_m``; the elevation mask is applied at each
        iterate of :func:`estimate_position`.
    clock_groups : tuple of str, length G
        Receiver clock parameters: the first group's clock, then one ISB per further group.
    group : ndarray of int, shape (S,)
        Clock group index of each satellite.
    approx_xyz_m : ndarray, shape (3,)
        Default start position (ECEF, m).
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    y_m: FloatArray
    sat_pos_m: FloatArray
    var_sat_m2: FloatArray
    var_factor: FloatArray
    iono_scale: FloatArray
    cn0_dbhz: FloatArray
    klobuchar: FloatArray | None
    ionofree: bool
    observed: BoolArray
    has_ephemeris: BoolArray
    no_ephemeris: BoolArray
    usable: BoolArray
    clock_groups: tuple[str, ...]
    group: IntArray
    approx_xyz_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def n_params(self) -> int:
        """Unknowns per epoch: position (3) and one clock per clock group."""
        return 3 + len(self.clock_groups)


def corrected_measurements(
    pr: Pseudoranges, sv: SatelliteStates, config: SppConfig | None = None
) -> Measurements:
    """Apply satellite clock and group delay, form the ionosphere-free combination, set the
    usability masks and the clock groups (stage 3 of :func:`solve_spp`).

    Parameters
    ----------
    pr : Pseudoranges
    sv : SatelliteStates
        Of the same epochs and satellites as ``pr``.
    config : SppConfig, optional

    Returns
    -------
    Measurements
    """
    from navtrack.gnss.corrections import ionofree

    cfg = config or SppConfig()
    if sv.sats != pr.sats or sv.clock_s.shape != pr.pr_m.shape:
        raise ValueError("sv: satellite states of other epochs or satellites than pr")
    if pr.pr2_m is not None and sv.freq2_hz is not None:
        y = ionofree(pr.pr_m, pr.pr2_m, sv.freq_hz, sv.freq2_hz)
    elif pr.pr2_m is None and sv.freq2_hz is None:
        y = pr.pr_m
    else:
        raise ValueError("sv: computed for another ionosphere mode than pr")
    y = y + C_MPS * (sv.clock_s - sv.group_delay_s)
    healthy = sv.svh == 0 if cfg.healthy_only else np.ones_like(sv.valid)
    observed = pr.observed
    usable = observed & sv.valid & np.isfinite(y) & healthy & (sv.var_m2 <= cfg.max_ura_m**2)
    # clock groups: the systems with a usable satellite somewhere, QZSS on GPS's clock
    sats, systems = pr.sats, pr.systems
    group_sys: list[str] = []
    for s in systems:
        grp = cfg.clock_groups.get(s, s)
        grp = grp if grp in systems else s
        present = usable[:, [i for i, sat in enumerate(sats) if sat[0] == s]].any()
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
    return Measurements(
        t_gps_s=pr.t_gps_s,
        sats=pr.sats,
        y_m=y,
        sat_pos_m=sv.pos_m,
        var_sat_m2=sv.var_m2 + 0.3**2,
        var_factor=sv.var_factor,
        iono_scale=sv.iono_scale,
        cn0_dbhz=pr.cn0_dbhz,
        klobuchar=sv.klobuchar,
        ionofree=pr.pr2_m is not None,
        observed=observed,
        has_ephemeris=sv.valid,
        no_ephemeris=observed & ~(sv.valid & healthy),
        usable=usable,
        clock_groups=tuple(group_sys),
        group=group,
        approx_xyz_m=pr.approx_xyz_m,
    )


# --------------------------------------------------------------------------- kernel
class _Geometry(NamedTuple):
    """Receiver-satellite geometry of a batch ``(b, S)`` at the receiver positions ``(b, 3)``."""

    rho: FloatArray  # (b, S) geometric range with Sagnac term, m
    los: FloatArray  # (b, S, 3) unit line of sight, ECEF
    llh: FloatArray  # (b, 3) receiver latitude, longitude (rad), height (m)
    rot: FloatArray  # (b, 3, 3) ECEF -> ENU
    az: FloatArray  # (b, S) rad
    el: FloatArray  # (b, S) rad; 90 deg for receivers inside the earth
    deep: BoolArray  # (b,) receiver inside the earth (start at the centre)


@dataclass(frozen=True, slots=True, eq=False)
class _PseudorangeModel:
    """The per-epoch pseudorange model of a batch of epochs (the SPP kernel, RTKLIB ``rescode``):
    batch row ``b`` is measurement epoch ``epochs[b]``, candidates ``usable[b]``."""

    meas: Measurements
    config: SppConfig
    usable: BoolArray  # (B, S)
    epochs: IntArray  # (B,)

    def geometry(self, x: FloatArray, b: IntArray) -> _Geometry:
        from navtrack.gnss.corrections import geometric_range

        rcv = x[:, :3]
        rs = self.meas.sat_pos_m[self.epochs[b]]
        rho, los = geometric_range(rs, rcv[:, None, :])
        llh = ecef_to_geodetic(rcv)
        rot = enu_rotation(llh[:, 0], llh[:, 1])  # (b, 3, 3)
        enu = los @ np.swapaxes(rot, -1, -2)  # rot @ los per satellite
        az = np.mod(np.arctan2(enu[..., 0], enu[..., 1]), 2.0 * np.pi)
        el = np.arcsin(np.clip(enu[..., 2], -1.0, 1.0))
        # inside the earth (start from the centre): no mask, no atmosphere (el = 90 deg)
        deep = np.linalg.norm(rcv, axis=1) < 1e6
        el = np.where(deep[:, None], np.pi / 2.0, el)
        return _Geometry(rho, los, llh, rot, az, el, deep)

    def __call__(
        self, x: FloatArray, b: IntArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        from navtrack.gnss.corrections import klobuchar_delay_m, saastamoinen_delay_m

        cfg, m = self.config, self.meas
        e = self.epochs[b]
        g = self.geometry(x, b)
        el, az, llh, deep = g.el, g.az, g.llh, g.deep
        valid = self.usable[b] & (el >= math.radians(cfg.elmask_deg))
        lat = llh[:, 0:1]
        lon = llh[:, 1:2]
        h = llh[:, 2:3]
        atm = ~deep[:, None]
        if cfg.iono == "klobuchar":
            iono_l1 = klobuchar_delay_m(m.t_gps_s[e, None], lat, lon, az, el, m.klobuchar)
            iono_l1 = np.where(atm, iono_l1, 0.0)
            iono = iono_l1 * m.iono_scale[e]
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
        n_groups = len(m.clock_groups)
        clk = x[:, 3 : 3 + n_groups]
        clock = clk[:, 0:1] + np.where(m.group > 0, clk[:, np.maximum(m.group, 0)], 0.0)
        v = m.y_m[e] - (g.rho + clock + iono + trop)
        J = np.zeros((b.size, m.group.size, 3 + n_groups))
        J[..., :3] = -g.los
        J[..., 3] = 1.0
        for k in range(1, n_groups):
            J[..., 3 + k] = (m.group == k).astype(float)
        var = measurement_variance(
            el, m.var_sat_m2[e], m.var_factor, var_iono, var_trop, m.cn0_dbhz[e], cfg, m.ionofree
        )
        valid &= np.isfinite(v) & np.isfinite(var) & (var > 0)
        w = np.where(valid, 1.0 / np.where(valid, var, 1.0), 0.0)
        J = np.where(valid[..., None], J, 0.0)
        return np.where(valid, v, 0.0), J, w, valid


def measurement_variance(
    el_rad: FloatArray,
    var_sat_m2: FloatArray,
    var_factor: FloatArray,
    var_iono_m2: FloatArray,
    var_trop_m2: FloatArray,
    cn0_dbhz: FloatArray,
    config: SppConfig,
    ionofree: bool = False,
) -> FloatArray:
    """Pseudorange error variance (m^2) of the configured weighting model
    (:attr:`SppConfig.weighting`).

    Parameters
    ----------
    el_rad : ndarray, shape (B, S)
        Elevation (rad).
    var_sat_m2 : ndarray, shape (B, S)
        Satellite-side variance (URA^2 + code bias), ``rtklib`` only.
    var_factor : ndarray, shape (S,)
        System factor squared, ``rtklib`` only.
    var_iono_m2, var_trop_m2 : ndarray, shape (B, S)
        Variances of the ionosphere and troposphere corrections, ``rtklib`` only.
    cn0_dbhz : ndarray, shape (B, S)
        C/N0, ``cn0`` only (NaN: the ``elevation`` model).
    config : SppConfig
    ionofree : bool
        The ionosphere-free combination (``rtklib``: receiver term times 3^2).

    Returns
    -------
    ndarray, shape (B, S)

    References
    ----------
    RTKLIB 2.4.3 ``pntpos.c`` ``varerr`` and ``rescode``; Hartinger & Brunner 1999 (SIGMA-epsilon).
    """
    sin_el = np.sin(el_rad)
    if config.weighting == "rtklib":
        base = 100.0**2 * (0.003**2 + 0.003**2 / sin_el)
        if ionofree:
            base = base * 9.0
        return var_factor * base + var_sat_m2 + var_iono_m2 + var_trop_m2
    if config.weighting == "elevation":
        return config.sigma0_m**2 * (1.0 + 1.0 / sin_el**2)
    if config.weighting == "cn0":
        return np.where(
            np.isfinite(cn0_dbhz),
            config.sigma0_m**2 + 1.61e4 * 10.0 ** (-np.nan_to_num(cn0_dbhz) / 10.0),
            config.sigma0_m**2 * (1.0 + 1.0 / sin_el**2),
        )
    return np.full_like(el_rad, config.sigma0_m**2)


# --------------------------------------------------------------------------- stage 4: estimation
@dataclass(frozen=True, slots=True, eq=False)
class Estimate:
    """Weighted least-squares estimate of a batch of epochs with everything fault detection
    needs (RTKLIB ``estpos``).

    State per epoch: ``(x, y, z, clock, isb...)`` — ECEF position (m), receiver clock of the
    first clock group times c (m), one inter-system bias (m) per further clock group
    (``Measurements.clock_groups``); ``P = 3 + G``.

    Attributes
    ----------
    epochs : ndarray of int, shape (B,)
        Measurement epochs estimated (indices into ``Measurements.t_gps_s``).
    x : ndarray, shape (B, P)
        State at the last iterate (the start value where nothing could be solved).
    cov : ndarray, shape (B, P, P)
        Formal covariance ``(B^T W B)^-1`` (m^2), NaN where singular; zero rows/columns for
        clock groups without a used satellite.
    residuals_m : ndarray, shape (B, S)
        Observed minus computed pseudoranges at ``x`` (m), NaN where not used.
    design : ndarray, shape (B, S, P)
        Geometry (design) matrix ``B = dh/dx`` at ``x``: rows ``(-los, 1, isb indicators)``,
        zero where not used. A small state change ``dx`` changes the residuals by ``-B dx``.
    weights : ndarray, shape (B, S)
        ``1 / sigma^2`` (1/m^2) of :func:`measurement_variance` at ``x``, 0 where not used.
    used : ndarray of bool, shape (B, S)
        Satellites in the estimate (usable, above the elevation mask, not excluded).
    azel_rad : ndarray, shape (B, S, 2)
        Azimuth and elevation at ``x`` (rad).
    enu_rotation : ndarray, shape (B, 3, 3)
        ECEF to local east/north/up rotation at ``x``.
    dop : ndarray, shape (B, 4)
        GDOP, PDOP, HDOP, VDOP of the used satellites (:func:`dops`).
    chi2 : ndarray, shape (B,)
        Weighted sum of squared residuals ``v^T W v``.
    dof : ndarray of int, shape (B,)
        Redundancy: used satellites minus estimated parameters.
    iterations : ndarray of int, shape (B,)
        Gauss–Newton steps.
    status : ndarray of int8, shape (B,)
        :class:`SppStatus` of the estimation: ``ok``, ``no_ephemeris``, ``too_few_sats``,
        ``singular_geometry`` or ``no_convergence`` (the validity tests are
        :func:`validate`'s).
    """

    epochs: IntArray
    x: FloatArray
    cov: FloatArray
    residuals_m: FloatArray
    design: FloatArray
    weights: FloatArray
    used: BoolArray
    azel_rad: FloatArray
    enu_rotation: FloatArray
    dop: FloatArray
    chi2: FloatArray
    dof: IntArray
    iterations: IntArray
    status: Int8Array

    def __post_init__(self) -> None:
        freeze_arrays(self)


def estimate_position(
    meas: Measurements,
    config: SppConfig | None = None,
    *,
    epochs: IntArray | None = None,
    exclude: BoolArray | None = None,
    x0_m: FloatArray | None = None,
) -> Estimate:
    """Iterated weighted least squares of position and clocks (stage 4 of :func:`solve_spp`).

    Elevation mask, ionosphere, troposphere and weights are re-evaluated at every iterate, as
    RTKLIB's ``rescode`` does; all epochs iterate in one batched Gauss–Newton
    (:func:`navtrack.estimation.least_squares.gauss_newton`, step-norm threshold ``xtol_m``).

    Parameters
    ----------
    meas : Measurements
    config : SppConfig, optional
    epochs : ndarray of int, shape (B,), optional
        Measurement epochs to estimate (default: all ``E``); integrity monitoring re-estimates a
        subset with a new ``exclude``.
    exclude : ndarray of bool, shape (B, S), optional
        Satellites left out per estimated epoch (fault exclusion); excluding a satellite is the
        same as not having observed it.
    x0_m : ndarray, shape (3,), (B, 3) or (B, P), optional
        Start position (ECEF, m), or full start state; default ``meas.approx_xyz_m`` with zero
        clocks.

    Returns
    -------
    Estimate
    """
    from navtrack.estimation.least_squares import LsqStatus, gauss_newton

    cfg = config or SppConfig()
    n_e, n_s = meas.usable.shape
    if epochs is None:
        idx = np.arange(n_e)
        usable = meas.usable
    else:
        idx = np.asarray(epochs)
        if idx.ndim != 1 or idx.dtype.kind not in "iu":
            raise ValueError(f"epochs: expected a 1-D integer array, got {idx.dtype} {idx.shape}")
        if idx.size and (idx.min() < -n_e or idx.max() >= n_e):
            raise ValueError(f"epochs: indices outside the {n_e} measurement epochs")
        idx = np.where(idx < 0, idx + n_e, idx).astype(np.int64)
        usable = meas.usable[idx]
    if exclude is not None:
        ex = np.asarray(exclude)
        if ex.shape != (idx.size, n_s) or ex.dtype != bool:
            raise ValueError(f"exclude: expected a bool array of shape {(idx.size, n_s)}")
        usable = usable & ~ex
    n_p = meas.n_params
    x0 = np.zeros((idx.size, n_p))
    start = meas.approx_xyz_m if x0_m is None else np.asarray(x0_m, dtype=float)
    if start.shape == (idx.size, n_p):
        x0[:] = start
    elif start.shape in ((3,), (idx.size, 3)):
        x0[:, :3] = start
    else:
        raise ValueError(f"x0_m: expected shape (3,), {(idx.size, 3)} or {x0.shape}")
    model = _PseudorangeModel(meas, cfg, usable, idx)
    lsq = gauss_newton(model, x0, max_iter=cfg.max_iter, xtol=cfg.xtol_m)

    observed = meas.observed[idx].any(axis=1)
    status = np.full(idx.size, SppStatus.OK, dtype=np.int8)
    status[lsq.status == LsqStatus.NO_CONVERGENCE] = SppStatus.NO_CONVERGENCE
    status[lsq.status == LsqStatus.SINGULAR] = SppStatus.SINGULAR_GEOMETRY
    status[lsq.status == LsqStatus.TOO_FEW_MEASUREMENTS] = SppStatus.TOO_FEW_SATS
    status[~usable.any(axis=1) & observed] = SppStatus.TOO_FEW_SATS
    with_eph = (meas.has_ephemeris[idx] & meas.observed[idx]).any(axis=1)
    status[observed & ~with_eph] = SppStatus.NO_EPHEMERIS
    status[~observed] = SppStatus.TOO_FEW_SATS

    geo = model.geometry(lsq.x, np.arange(idx.size))
    los_enu = geo.los @ np.swapaxes(geo.rot, -1, -2)
    return Estimate(
        epochs=idx,
        x=lsq.x,
        cov=lsq.cov,
        residuals_m=lsq.residuals,
        design=lsq.jacobian,
        weights=lsq.weights,
        used=lsq.valid,
        azel_rad=np.stack([geo.az, geo.el], axis=-1),
        enu_rotation=geo.rot,
        dop=dops(los_enu, lsq.valid),
        chi2=lsq.cost,
        dof=lsq.dof,
        iterations=lsq.iterations,
        status=status,
    )


def merge_estimates(estimate: Estimate, update: Estimate) -> Estimate:
    """``estimate`` with the epochs of ``update`` replaced by ``update``'s rows (e.g. the
    re-estimates of fault exclusion on the failed epochs); ``update.epochs`` must be among
    ``estimate.epochs``.

    Parameters
    ----------
    estimate : Estimate
        Of epochs ``(B,)``.
    update : Estimate
        Of epochs ``(b,)`` of the same measurements (same satellites and parameters).

    Returns
    -------
    Estimate
        Of epochs ``(B,)``.
    """
    if (
        update.x.shape[1:] != estimate.x.shape[1:]
        or update.used.shape[1:] != estimate.used.shape[1:]
    ):
        raise ValueError("update: estimate of other satellites or parameters")
    order = np.argsort(estimate.epochs, kind="stable")
    at = np.searchsorted(estimate.epochs, update.epochs, sorter=order)
    rows = order[np.minimum(at, max(order.size - 1, 0))] if order.size else at
    if update.epochs.size and (
        not order.size or not np.array_equal(estimate.epochs[rows], update.epochs)
    ):
        raise ValueError("update: epochs that estimate does not have")
    fields = {}
    for name in Estimate.__dataclass_fields__:
        value = np.array(getattr(estimate, name))
        if name != "epochs":
            value[rows] = getattr(update, name)
        fields[name] = value
    return Estimate(**fields)


# --------------------------------------------------------------------------- stage 5: validation
def validate(estimate: Estimate, config: SppConfig | None = None) -> Int8Array:
    """Validity tests of the estimated epochs (stage 5 of :func:`solve_spp`, RTKLIB ``valsol``;
    the stage integrity monitoring replaces).

    An ``ok`` epoch becomes ``rejected_validity`` when its weighted residuals fail the
    chi-square test, ``v^T W v > chi2_{1 - alpha}(dof)`` (skipped for ``chi2_alpha = 0`` or
    ``dof = 0``), else ``high_dop`` when ``GDOP > max_gdop`` or GDOP is undefined.

    Parameters
    ----------
    estimate : Estimate
    config : SppConfig, optional
        ``chi2_alpha`` and ``max_gdop``.

    Returns
    -------
    ndarray of int8, shape (B,)
        :class:`SppStatus` per estimated epoch.

    References
    ----------
    RTKLIB 2.4.2 manual, appendix E.6 (E.6.33, E.6.34).
    """
    cfg = config or SppConfig()
    status = estimate.status.copy()
    conv = status == SppStatus.OK
    dof = estimate.dof
    if cfg.chi2_alpha > 0:
        thr = np.array(
            [chi2_quantile(1.0 - cfg.chi2_alpha, int(k)) if k > 0 else np.inf for k in dof]
        )
        status[conv & (dof > 0) & (estimate.chi2 > thr)] = SppStatus.REJECTED_VALIDITY
    gdop = estimate.dop[:, 0]
    status[conv & (status == SppStatus.OK) & ~(gdop <= cfg.max_gdop)] = SppStatus.HIGH_DOP
    return status


# --------------------------------------------------------------------------- result, driver
def spp_result(
    meas: Measurements,
    estimate: Estimate,
    status: Int8Array,
    integrity: IntegrityResult | None = None,
) -> SppResult:
    """Assemble the :class:`SppResult` of an estimate of all measurement epochs and the
    statuses of its validation (and its integrity monitoring): positions, clocks and
    covariances of the epochs whose status is ``ok``, ``rejected_validity`` or ``high_dop``,
    NaN elsewhere."""
    n_e = meas.t_gps_s.size
    if not np.array_equal(estimate.epochs, np.arange(n_e)) or np.shape(status) != (n_e,):
        raise ValueError("estimate, status: need all measurement epochs in order")
    x, rot, n_groups = estimate.x, estimate.enu_rotation, len(meas.clock_groups)
    solved = np.isin(status, (SppStatus.OK, SppStatus.REJECTED_VALIDITY, SppStatus.HIGH_DOP))
    valid = estimate.used
    group_seen = np.stack([(valid & (meas.group == k)).any(axis=1) for k in range(n_groups)], 1)
    cov_enu = np.einsum("eij,ejk,elk->eil", rot, estimate.cov[:, :3, :3], rot)
    w = estimate.weights
    return SppResult(
        t_gps_s=meas.t_gps_s.copy(),
        sats=meas.sats,
        clock_groups=meas.clock_groups,
        pos_m=np.where(solved[:, None], x[:, :3], np.nan),
        clock_m=np.where(solved, x[:, 3], np.nan),
        isb_m=np.where(solved[:, None] & group_seen[:, 1:], x[:, 4:], np.nan),
        cov=estimate.cov,
        cov_enu_m2=np.where(solved[:, None, None], cov_enu, np.nan),
        status=np.array(status, dtype=np.int8),
        used=valid & solved[:, None],
        observed=meas.observed,
        no_ephemeris=meas.no_ephemeris,
        residuals_m=estimate.residuals_m,
        sigma_m=np.where(valid, 1.0 / np.sqrt(np.where(valid, w, 1.0)), np.nan),
        azel_rad=estimate.azel_rad,
        dop=estimate.dop,
        chi2=estimate.chi2,
        dof=estimate.dof,
        iterations=estimate.iterations,
        integrity=integrity,
    )


def solve_spp(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    x0_m: FloatArray | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
    chunk_epochs: int = CHUNK_EPOCHS,
    progress: ProgressFn | None = None,
    raim: RaimConfig | None = None,
) -> SppResult:
    """Single point positions of every epoch of an observation set.

    Runs the stages :func:`code_pseudoranges` -> :func:`satellite_states` ->
    :func:`corrected_measurements` -> :func:`estimate_position` -> :func:`validate` ->
    :func:`spp_result` on blocks of ``chunk_epochs`` epochs (joined by
    :func:`concatenate_results`).

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
        Start position (ECEF, m; default: the header's approximate position when plausible,
        else the earth's centre).
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built tables (otherwise built from ``nav``).
    chunk_epochs : int
        Epochs per block: bounds the memory of the ``(epochs, satellites, unknowns)`` arrays.
        Clock groups are chosen per block (a system seen in one block only has a NaN ISB
        elsewhere).
    progress : callable, optional
        ``progress(epochs_done, epochs_total)``, called after each block.
    raim : RaimConfig, optional
        Integrity monitoring (:func:`navtrack.integrity.raim.monitor`) in place of
        :func:`validate`: detection, exclusion, protection levels (``SppResult.integrity``).

    Returns
    -------
    SppResult
    """
    if chunk_epochs < 1:
        raise ValueError(f"chunk_epochs: expected a positive number of epochs, got {chunk_epochs}")
    cfg = config or SppConfig()
    tables = navigation_tables(nav, ephemeris)
    n = obs.t_gps_s.size
    parts = []
    for a in range(0, max(n, 1), chunk_epochs):
        block = obs if n <= chunk_epochs else subset_epochs(obs, slice(a, a + chunk_epochs))
        pr = code_pseudoranges(block, cfg)
        sv = satellite_states(pr, nav, sp3=sp3, config=cfg, ephemeris=tables)
        meas = corrected_measurements(pr, sv, cfg)
        est = estimate_position(meas, cfg, x0_m=x0_m)
        if raim is None:
            parts.append(spp_result(meas, est, validate(est, cfg)))
        else:
            from navtrack.integrity.raim import monitor

            parts.append(spp_result(meas, *monitor(meas, est, cfg, raim)))
        if progress is not None:
            progress(min(a + chunk_epochs, n), n)
    return parts[0] if len(parts) == 1 else concatenate_results(parts)


def _klobuchar_params(nav_iono: Mapping[str, FloatArray]) -> FloatArray | None:
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
    N = np.swapaxes(H, -1, -2) @ H
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

    integrity = None
    if all(p.integrity is not None for p in parts):
        from navtrack.integrity.raim import concatenate_integrity

        integrity = concatenate_integrity([p.integrity for p in parts if p.integrity])
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
        integrity=integrity,
    )


# RTKLIB's covariance columns and the ECEF covariance element each one holds.
_RTKLIB_SD_COLUMNS = ("sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m")
_RTKLIB_SD_INDICES = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0))


def solution_frame(result: SppResult) -> dict[str, np.ndarray]:
    """The solution as a solution frame (plain arrays, no pandas), one row per epoch, all
    statuses: the input of :func:`navtrack.io.solution.write_solution`,
    :func:`navtrack.io.solution.solution_columns` (which derives ``time_gps``, ``week``,
    ``tow_s`` and the geodetic position) and :func:`navtrack.plots.gnss.plot_solution`.

    Columns: ``t_gps_s`` (GPS s), ``x_m``, ``y_m``, ``z_m`` (ECEF, m; NaN where no estimate
    exists), ``clock_m``, ``sd_e_m``, ``sd_n_m``, ``sd_u_m`` (formal standard deviations, m),
    ``n_sats`` (used), ``pdop``, ``status`` (name), ``excluded`` (space-separated ids of the
    satellites integrity monitoring excluded; empty without it), ``gdop``, ``hdop``, ``vdop``,
    the ECEF position covariance as RTKLIB writes it, ``sdx_m``, ``sdy_m``, ``sdz_m`` (standard
    deviations) and ``sdxy_m``, ``sdyz_m``, ``sdzx_m`` (signed square roots of the covariances,
    ``sign(c) sqrt(|c|)``), and one ``isb_<sys>_m`` per further clock group; with integrity
    monitoring also ``raim_status`` (name), ``hpl_m``, ``vpl_m``, ``test_stat`` and ``threshold``
    (:class:`navtrack.integrity.raim.IntegrityResult`).
    """
    sd = np.sqrt(np.einsum("eii->ei", result.cov_enu_m2))
    n = result.t_gps_s.size
    cols: dict[str, np.ndarray] = {
        "t_gps_s": result.t_gps_s,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "clock_m": result.clock_m,
        "sd_e_m": sd[:, 0],
        "sd_n_m": sd[:, 1],
        "sd_u_m": sd[:, 2],
        "n_sats": result.used.sum(axis=1) if result.used.size else np.zeros(n, np.int64),
        "pdop": result.dop[:, 1],
        "status": np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)],
        "excluded": np.full(n, "", dtype=object),
        "gdop": result.dop[:, 0],
        "hdop": result.dop[:, 2],
        "vdop": result.dop[:, 3],
    }
    c = result.cov
    for name, (i, j) in zip(_RTKLIB_SD_COLUMNS, _RTKLIB_SD_INDICES, strict=True):
        cols[name] = np.sign(c[:, i, j]) * np.sqrt(np.abs(c[:, i, j]))
    for k, g in enumerate(result.clock_groups[1:]):
        cols[f"isb_{g}_m"] = result.isb_m[:, k]
    if result.integrity is not None:
        from navtrack.integrity.raim import integrity_columns

        cols.update(integrity_columns(result.integrity, result.sats))
    return cols
