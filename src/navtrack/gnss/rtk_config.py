"""Options, statuses and reasons of carrier-phase relative positioning
(:func:`navtrack.gnss.relative.solve_relative`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from types import MappingProxyType

from navtrack.errors import NavtrackError
from navtrack.gnss.ambiguity import AmbiguityConfig

__all__ = [
    "AFTER_RATIO_TEST",
    "FLOAT_POSITION_TEST",
    "MAX_AGE_AR_S",
    "MIN_SUCCESS_RATE",
    "QUALITY",
    "REJECTION_NAMES",
    "STATUS_NAMES",
    "SYSTEMS",
    "FixRejection",
    "RelativeInputError",
    "RtkConfig",
    "RtkStatus",
]

MAX_AGE_AR_S = 30.0
"""Default :attr:`RtkConfig.max_age_ar_s` (s): oldest base observations ambiguity resolution
uses, equal to the default :attr:`RtkConfig.max_age_s` (RTKLIB ``maxage``). Chosen on the
MatRTKLIB 2018 1 Hz rover against its Trimble NetR9 base decimated to 30 s (10 s allowed 190
fixes of 601, RTKLIB 514; 30 s: 501, none wrong); judged on the u-blox ZED-F9P pair with its base
decimated to 30 s, the mosaic-X5 pair against 30 s, the yamatogawa rover against its master
thinned to 30 s and GEONET 0759 against 3040 thinned to 60 s (``docs/rtk.md``, "Base age")."""

MIN_SUCCESS_RATE = 0.5
"""Default :attr:`RtkConfig.min_success_rate`: a full fix more likely wrong than right by the
float covariance's own bootstrapped success rate is refused. The yamatogawa rover against its
master thinned to 30 s showed the need (its 11 backward fixes, ratios 3-51, wrong where they can
be checked, have success rates below 0.2); the value 0.5 is the even-odds point, not fitted;
judged on the yamatogawa 1 s and 5 s runs, GEONET 0759/3040 and the MatRTKLIB mosaic-X5 pair
(``docs/rtk.md``, "Fix validation")."""

FLOAT_POSITION_TEST = False
"""Default :attr:`RtkConfig.float_position_test`: off. On the static mosaic-X5 pair of
MatRTKLIB (1 m baseline, L1+L2) it refused 285 of the 301 fixes, all right to 5 mm, because
the float position sat 0.1-0.25 m from the truth, far outside its formal covariance (code
multipath is correlated over minutes, the filter treats it as white); it never refused a fix
on the yamatogawa or GEONET runs (``docs/rtk.md``, "Fix validation")."""

SYSTEMS = "GRECJ"
"""Systems :func:`~navtrack.gnss.relative.solve_relative` differences (GLONASS float only)."""


class RtkStatus(IntEnum):
    """Per-epoch outcome of :func:`~navtrack.gnss.relative.solve_relative` (printed by
    lower-case name)."""

    FIX = 0
    FLOAT = 1
    DGNSS = 2
    SINGLE = 3
    NO_BASE = 4
    NO_SOLUTION = 5


STATUS_NAMES = tuple(s.name.lower() for s in RtkStatus)


class FixRejection(IntEnum):
    """Why an epoch with carrier-phase double differences was not fixed (it stays float).

    Before the integer search: ``too_few_satellites``: fewer than ``min_fix_sats`` satellites
    (reference included) with fixable ambiguities above the elevation mask for ambiguity
    resolution; ``base_age``: the base observations are older than ``max_age_ar_s``. After it:
    ``ratio_test``: the best candidate fails the ratio test (full and, with partial fixing,
    partial set); ``success_rate``: a full fix whose bootstrapped success rate (Teunissen 1998,
    from the float covariance alone) is below ``min_success_rate``. After the ratio test
    accepted a fix:
    ``residuals``: the phase double differences at the fixed state fail the chi-square test;
    ``float_position``: the fixed position lies outside the float position's confidence region
    (only with ``float_position_test``);
    ``directions_disagree``: ``combined`` forward and backward fixes farther apart than 4
    standard deviations.
    """

    NONE = 0
    RESIDUALS = 1
    FLOAT_POSITION = 2
    DIRECTIONS_DISAGREE = 3
    RATIO_TEST = 4
    TOO_FEW_SATELLITES = 5
    BASE_AGE = 6
    SUCCESS_RATE = 7


AFTER_RATIO_TEST = frozenset(
    {FixRejection.RESIDUALS, FixRejection.FLOAT_POSITION, FixRejection.DIRECTIONS_DISAGREE}
)
"""The :class:`FixRejection` reasons that refuse a fix the ratio test had accepted."""


REJECTION_NAMES = tuple(r.name.lower() for r in FixRejection)

QUALITY: Mapping[int, int] = MappingProxyType(
    {
        RtkStatus.FIX: 1,
        RtkStatus.FLOAT: 2,
        RtkStatus.DGNSS: 4,
        RtkStatus.SINGLE: 5,
        RtkStatus.NO_BASE: 5,
        RtkStatus.NO_SOLUTION: 0,
    }
)
"""RTKLIB's solution quality ``Q`` of each status (1 fix, 2 float, 4 DGNSS, 5 single; 6 is
PPP, :mod:`navtrack.gnss.ppp`). ``no_base`` epochs carry the single point position."""


class RelativeInputError(NavtrackError, ValueError):
    """Rover and base observations that cannot be differenced (no common epochs or
    satellites); the message names both files."""


@dataclass(frozen=True, slots=True)
class RtkConfig:
    """Options of :func:`~navtrack.gnss.relative.solve_relative`; defaults after RTKLIB
    2.4.3's ``rnx2rtkp``.

    Attributes
    ----------
    mode : str
        ``kinematic`` or ``static``.
    systems : str
        Systems to difference. GLONASS (``R``) is used in the float solution only: its FDMA
        carriers differ per satellite, so its double-differenced ambiguities are not integers
        unless the receivers' inter-frequency biases are known; they are not estimated (the
        phase biases are absorbed by the float single-differenced ambiguities, the code biases
        of unlike receivers stay in the code residuals).
    frequencies : int
        1 (L1/E1/B1) or 2 (adds L2/E5b/B3 where both receivers track it).
    elmask_deg : float
        Elevation mask at the rover (deg).
    min_sats : int
        Fewest satellites in the double differences (reference included) for a relative
        solution.
    sigma_phase_m : tuple of float
        ``(a, b)`` of the undifferenced carrier-phase variance ``a^2 + b^2 / sin^2(el)``
        (m; RTKLIB ``err`` 0.003, 0.003).
    code_phase_ratio : float
        Code to phase standard deviation ratio (RTKLIB ``eratio`` 100).
    sigma_pos0_m : float
        Standard deviation of the kinematic position at each epoch and of the start position
        (RTKLIB: 30 m).
    sigma_amb0_m : float
        Standard deviation of a (re-)initialised ambiguity (m; RTKLIB ``std[0]`` 30).
    q_amb_cyc : float
        Random walk of the ambiguities (cycles / sqrt(s); RTKLIB ``prn[0]`` 1e-4).
    slip_doppler_cyc : float
        Slip when the phase change departs from the Doppler prediction by more than this
        (cycles; after removing the epoch's median, the receiver clock). 0 disables.
    slip_gf_m : float
        Slip when the geometry-free combination jumps by more than this (m; RTKLIB
        ``thresslip`` 0.05).
    max_outage : int
        A satellite unseen for more than this many epochs restarts its ambiguity (RTKLIB
        ``maxout`` 5).
    max_age_s : float
        Base observations are used for rover epochs up to this much later (s; RTKLIB
        ``maxage`` 30).
    sync_s : float
        A base epoch tagged up to this much after a rover epoch is the same epoch (s).
    clock_stability : float
        Satellite clock stability (s/s, RTKLIB ``stats-clkstab`` 5e-12): the single
        difference of a base observation ``age`` seconds old gains ``(c stability age)^2`` of
        variance.
    elmask_ar_deg : float
        Elevation mask of ambiguity resolution (deg): satellites below
        ``max(elmask_deg, elmask_ar_deg)`` stay float (RTKLIB ``elmaskar``, default 0: the
        position mask).
    min_fix_sats : int
        Fewest satellites (reference included) with fixable ambiguities for an integer search
        (RTKLIB demo5 ``minfixsats`` 4); fewer: ``too_few_satellites``.
    min_success_rate : float
        Fewest bootstrapped success rate of a full fix (:data:`MIN_SUCCESS_RATE`): a float
        covariance too wide for the integers to be determined refuses the fix whatever the
        ratio (a partial fix already holds its subset to ``ambiguity.min_success_rate``).
    max_age_ar_s : float
        Ambiguity resolution only at epochs whose base observations are at most this old (s;
        older ones stay float, ``base_age``; :data:`MAX_AGE_AR_S`). The error of a base
        observation used late grows by about 1 mm per second of age and satellite
        (ionosphere, broadcast clock and orbit drift): fixes from a 20-30 s old base err a few
        centimetres more than those from a fresh one (``docs/rtk.md``, "Base age"); 10 keeps
        only the younger ones.
    hold : bool
        Fix-and-hold (RTKLIB ``fix-and-hold``): after a validated fix the float state is updated
        with the fixed double-differenced ambiguities as measurements of variance
        ``hold_var_cyc2``, so the next epochs start from them.
    hold_var_cyc2 : float
        Variance of the held ambiguities (cycles^2; RTKLIB ``varholdamb`` 0.001).
    fix_test_p : float
        False-alarm probability of the tests a fix passes after the ratio test
        (:class:`FixRejection`): the chi-square of the phase double-difference residuals at the
        fixed state, and (``float_position_test``) of the fixed position's departure from the
        float one in the float covariance (3 degrees of freedom).
    float_position_test : bool
        Refuse a fix outside the float position's confidence region
        (:data:`FLOAT_POSITION_TEST`: off; the float covariance is optimistic wherever code
        errors are correlated in time).
    ambiguity : AmbiguityConfig
        Ratio test and partial fixing (:func:`navtrack.gnss.ambiguity.resolve_ambiguities`).
    fix : bool
        Resolve integer ambiguities (False: float solution only).
    direction : str
        ``forward`` (real-time order), ``backward``, or ``combined``: both filters joined
        epoch by epoch (RTKLIB ``-c``): the better status wins; equal statuses are averaged
        with their covariances; two fixed solutions that disagree by more than 4 standard
        deviations of their difference fall back to the combined float solution.
    """

    mode: str = "kinematic"
    systems: str = "GECJ"
    frequencies: int = 1
    elmask_deg: float = 15.0
    min_sats: int = 4
    sigma_phase_m: tuple[float, float] = (0.003, 0.003)
    code_phase_ratio: float = 100.0
    sigma_pos0_m: float = 30.0
    sigma_amb0_m: float = 30.0
    q_amb_cyc: float = 1e-4
    slip_doppler_cyc: float = 5.0
    slip_gf_m: float = 0.05
    max_outage: int = 5
    max_age_s: float = 30.0
    sync_s: float = 0.025
    clock_stability: float = 5e-12
    elmask_ar_deg: float = 0.0
    min_fix_sats: int = 4
    max_age_ar_s: float = MAX_AGE_AR_S
    min_success_rate: float = MIN_SUCCESS_RATE
    hold: bool = False
    hold_var_cyc2: float = 0.001
    fix_test_p: float = 1e-3
    float_position_test: bool = FLOAT_POSITION_TEST
    ambiguity: AmbiguityConfig = field(default_factory=AmbiguityConfig)
    fix: bool = True
    direction: str = "forward"

    def __post_init__(self) -> None:
        if self.mode not in ("kinematic", "static"):
            raise ValueError(f"mode: expected 'kinematic' or 'static', got {self.mode!r}")
        if self.frequencies not in (1, 2):
            raise ValueError(f"frequencies: expected 1 or 2, got {self.frequencies}")
        unknown = set(self.systems) - set(SYSTEMS)
        if unknown or not self.systems:
            raise ValueError(f"systems: expected letters of {SYSTEMS!r}, got {self.systems!r}")
        if self.direction not in ("forward", "backward", "combined"):
            raise ValueError(
                f"direction: expected 'forward', 'backward' or 'combined', got {self.direction!r}"
            )
        if self.max_outage < 0:
            raise ValueError(f"max_outage: expected >= 0, got {self.max_outage}")
        if not 0.0 <= self.min_success_rate < 1.0:
            raise ValueError(f"min_success_rate: expected in [0, 1), got {self.min_success_rate}")
        if not 0.0 < self.fix_test_p < 1.0:
            raise ValueError(f"fix_test_p: expected in (0, 1), got {self.fix_test_p}")
        if self.min_fix_sats < 2:
            raise ValueError(f"min_fix_sats: expected >= 2, got {self.min_fix_sats}")
        for name in (
            "max_age_s",
            "sync_s",
            "clock_stability",
            "elmask_ar_deg",
            "hold_var_cyc2",
            "max_age_ar_s",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name}: expected a finite number >= 0, got {value}")
        if self.min_sats < 2:
            raise ValueError(f"min_sats: expected >= 2, got {self.min_sats}")
