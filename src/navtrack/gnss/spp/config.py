"""Configuration, statuses and constants of single point positioning (:mod:`navtrack.gnss.spp`).

The error terms of RTKLIB's ``pntpos.c`` (``ERR_ION``, ``ERR_TROP``, ``ERR_SAAS``,
``ERR_BRDCI``, ``ERR_CBIAS``, ``EFACT_GLO``) and of its default options (``eratio``, ``err``)
are named here; :func:`navtrack.gnss.spp.model.measurement_variance` combines them.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from enum import IntEnum
from types import MappingProxyType
from typing import Any

from navtrack._record import Record

__all__ = [
    "CHUNK_EPOCHS",
    "CODE_PHASE_RATIO",
    "CODE_PRIORITY",
    "DEFAULT_CLOCK_GROUP",
    "EFACT_GLO",
    "ERR_BRDCI",
    "ERR_CBIAS_M",
    "ERR_CODE_M",
    "ERR_ION_M",
    "ERR_SAAS_M",
    "ERR_TROP_M",
    "IONOFREE_BANDS",
    "IONOFREE_NOISE_FACTOR",
    "PRIMARY_BAND",
    "SIGMA_EPSILON_C_M2HZ",
    "STATUS_NAMES",
    "ProgressFn",
    "SppConfig",
    "SppStatus",
]

# RTKLIB 2.4.3 pntpos.c error model (m unless stated)
ERR_ION_M = 5.0
"""Ionosphere error (m) when no ionosphere correction is applied (``ERR_ION``)."""
ERR_TROP_M = 3.0
"""Troposphere error (m) when no troposphere correction is applied (``ERR_TROP``)."""
ERR_SAAS_M = 0.3
"""Zenith error (m) of the Saastamoinen model, scaled by ``1 / (sin el + 0.1)`` (``ERR_SAAS``)."""
ERR_BRDCI = 0.5
"""Error of the broadcast (Klobuchar) ionosphere model as a fraction of the delay
(``ERR_BRDCI``)."""
ERR_CBIAS_M = 0.3
"""Code bias error (m) added to every satellite's variance (``ERR_CBIAS``)."""
EFACT_GLO = 1.5
"""System error factor of GLONASS (``EFACT_GLO``; 1 for the other systems, ``EFACT_GPS``)."""
CODE_PHASE_RATIO = 100.0
"""Ratio of code to carrier-phase error (RTKLIB option ``pos2-eratio1``, default 100)."""
ERR_CODE_M = 0.003
"""Carrier-phase error terms ``a`` and ``b`` (m) of ``a + b / sin el`` (RTKLIB options
``stats-errphase`` and ``stats-errphaseel``, default 0.003)."""
IONOFREE_NOISE_FACTOR = 3.0
"""Noise amplification of the ionosphere-free combination in RTKLIB's ``varerr`` (its
variance is multiplied by ``3^2``)."""
SIGMA_EPSILON_C_M2HZ = 1.61e4
"""Tracking-noise constant ``C`` (m^2 Hz) of the SIGMA-epsilon model ``C 10^(-C/N0 / 10)`` for
the C/A code (Hartinger & Brunner 1999)."""


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
"""Epochs per block of :func:`navtrack.gnss.spp.solve_spp` (one hour at 1 Hz)."""

ProgressFn = Callable[[int, int], None]
"""``progress(epochs_done, epochs_total)``, called by :func:`solve_spp` after each block."""


class SppConfig(Record, eq=True):
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
    clock_groups: Mapping[str, str] = DEFAULT_CLOCK_GROUP
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
            name: dict(v) if isinstance(v := getattr(self, name), Mapping) else v
            for name in self.record_fields
        }
        return (functools.partial(type(self), **fields), ())
