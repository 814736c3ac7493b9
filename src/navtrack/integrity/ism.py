"""The error model behind every protection level: an integrity support message (ISM) and the
airborne error model of the ARAIM Airborne Algorithm Description Document (ADD) and RTCA
DO-229.

The pseudorange error of satellite ``i`` is modelled as a zero-mean Gaussian of variance
``sigma_i^2`` plus a bounded nominal bias ``b_i``:

* integrity: ``sigma_int^2 = sigma_URA^2 + sigma_tropo^2 + sigma_air^2 + sigma_iono^2``,
  bias ``b_nom``;
* accuracy and continuity: ``sigma_acc^2 = sigma_URE^2 + sigma_tropo^2 + sigma_air^2 +
  sigma_iono^2``, bias ``b_cont``;

with (elevation ``theta``)

* ``sigma_tropo = 0.12 m * 1.001 / sqrt(0.002001 + sin^2 theta)`` (DO-229 A.4.2.4);
* ``sigma_air^2 = sigma_mp^2 + sigma_noise^2``, ``sigma_mp = 0.13 + 0.53 exp(-theta / 10 deg)``
  and ``sigma_noise = a + b exp(-theta / c)`` (DO-229 J.2.4, airborne accuracy designator A:
  ``a = 0.15 m, b = 0.43 m, c = 6.9 deg``), times ``sqrt((f1^4 + f5^4)) / (f1^2 - f5^2)`` for
  the ionosphere-free combination (ADD);
* ``sigma_iono`` for a single frequency corrected by the broadcast Klobuchar model:
  DO-229 J.2.3, ``F_pp tau_vert`` with ``tau_vert`` 9 m, 4.5 m or 6 m for geomagnetic
  latitudes of the pierce point up to 20 deg, 20-55 deg and above (the standard's second
  term, a fifth of the Klobuchar delay, is smaller wherever the delay is below 45 m ``F_pp``
  and is left out); 0 for the ionosphere-free combination.

The ISM file (TOML, :func:`read_ism`) holds per constellation ``sigma_ura_m``,
``sigma_ure_m``, ``b_nom_m``, ``b_cont_m``, ``p_sat``, ``p_const``, ``mfd_sat_s``,
``mfd_const_s`` and the allocations of the ARAIM user algorithm; ``navtrack/data/ism_add.toml``
is the default, with the values of the ADD's baseline.

References
----------
EU-US Cooperation on Satellite Navigation, WG-C ARAIM Technical Subgroup, *ARAIM Airborne
Algorithm Description Document* v4.2 (2022) and Milestone 3 report (2016). RTCA DO-229E,
*MOPS for GPS/SBAS airborne equipment*, Appendix A and J. J. Blanch et al., "Baseline advanced
RAIM user algorithm and possible improvements", IEEE TAES 51(1), 2015.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from navtrack._typing import BoolArray, FloatArray
from navtrack.errors import NavtrackError

__all__ = [
    "DEFAULT_ISM_PATH",
    "ConstellationIsm",
    "ErrorModel",
    "Ism",
    "default_ism",
    "error_model",
    "read_ism",
]

DEFAULT_ISM_PATH = Path(__file__).resolve().parent.parent / "data" / "ism_add.toml"

_F1_HZ = 1575.42e6
_F5_HZ = 1176.45e6
IONOFREE_NOISE_FACTOR = math.sqrt(_F1_HZ**4 + _F5_HZ**4) / (_F1_HZ**2 - _F5_HZ**2)
"""Noise and multipath amplification of the L1/L5 ionosphere-free combination (2.59)."""


@dataclass(frozen=True, slots=True)
class ConstellationIsm:
    """ISM content of one constellation (ADD section 2.3).

    Attributes
    ----------
    sigma_ura_m : float
        Standard deviation of the clock and ephemeris error for integrity (m).
    sigma_ure_m : float
        The same for accuracy and continuity (m).
    b_nom_m : float
        Maximum nominal bias for integrity (m).
    b_cont_m : float
        Maximum nominal bias for accuracy and continuity (m).
    p_sat : float
        Prior probability of a fault of one satellite per approach.
    p_const : float
        Prior probability of a fault affecting the whole constellation.
    mfd_sat_s, mfd_const_s : float
        Mean fault durations (s), for the exposure-time multiplier ``1 + T_exp / MFD``.
    """

    sigma_ura_m: float
    sigma_ure_m: float
    b_nom_m: float
    b_cont_m: float
    p_sat: float
    p_const: float
    mfd_sat_s: float = 3600.0
    mfd_const_s: float = 3600.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"{f.name}: expected a finite number >= 0, got {v}")
        for name in ("p_sat", "p_const"):
            if getattr(self, name) >= 1.0:
                raise ValueError(f"{name}: expected a probability < 1, got {getattr(self, name)}")


@dataclass(frozen=True, slots=True)
class Ism:
    """Integrity support message and the allocations of the ARAIM user algorithm.

    Attributes
    ----------
    constellations : dict of str to ConstellationIsm
        Keyed by RINEX system letter (``G``, ``E``, ``C``, ``J``, ...). Satellites of other
        systems are outside the model: the integrity methods do not use them.
    phmi_v, phmi_h : float
        Integrity budget (per approach) of the vertical and horizontal protection levels
        (ADD: 9.8e-8 and 2e-9).
    pfa_v, pfa_h : float
        Continuity budget of false alerts (ADD: 3.9e-6 and 9e-8).
    p_thres : float
        Integrity risk of the fault modes left unmonitored (ADD: 8e-8).
    fc : float
        Fault consolidation: satellite modes inside a constellation mode are merged into it up
        to ``fc p_const`` (ADD: 0.01; 0 turns it off).
    t_exp_s, tta_s : float
        Exposure time and time to alert (LPV-200: 150 s and 6 s); the budgets are divided by
        the number of effective samples ``T_exp / TTA``.
    p_emt : float
        Fault modes of at least this prior define the effective monitor threshold (1e-5).
    tropo_sigma_m : float
        Zenith troposphere residual after the model (DO-229: 0.12 m).
    noise_a_m, noise_b_m, noise_c_deg : float
        Receiver noise ``a + b exp(-theta / c)`` (DO-229 AAD-A: 0.15, 0.43, 6.9).
    mp_a_m, mp_b_m, mp_c_deg : float
        Multipath ``a + b exp(-theta / c)`` (DO-229: 0.13, 0.53, 10).
    """

    constellations: dict[str, ConstellationIsm] = field(default_factory=dict)
    phmi_v: float = 9.8e-8
    phmi_h: float = 2e-9
    pfa_v: float = 3.9e-6
    pfa_h: float = 9e-8
    p_thres: float = 8e-8
    fc: float = 0.01
    t_exp_s: float = 150.0
    tta_s: float = 6.0
    p_emt: float = 1e-5
    tropo_sigma_m: float = 0.12
    noise_a_m: float = 0.15
    noise_b_m: float = 0.43
    noise_c_deg: float = 6.9
    mp_a_m: float = 0.13
    mp_b_m: float = 0.53
    mp_c_deg: float = 10.0

    def __post_init__(self) -> None:
        for name in ("phmi_v", "phmi_h", "pfa_v", "pfa_h", "p_thres", "p_emt"):
            v = getattr(self, name)
            if not 0.0 < v < 1.0:
                raise ValueError(f"{name}: expected a probability in (0, 1), got {v}")
        if not 0.0 <= self.fc < 1.0:
            raise ValueError(f"fc: expected a fraction in [0, 1), got {self.fc}")
        if not (self.t_exp_s > 0.0 and self.tta_s > 0.0):
            raise ValueError("t_exp_s, tta_s: expected positive times")

    @property
    def n_es(self) -> float:
        """Number of effective samples in the exposure time, ``T_exp / TTA``."""
        return self.t_exp_s / self.tta_s

    @property
    def systems(self) -> str:
        return "".join(self.constellations)


def _from_mapping(data: dict[str, Any], source: str) -> Ism:
    consts = data.pop("constellation", None)
    if not isinstance(consts, dict) or not consts:
        raise NavtrackError(f"{source}: no [constellation.X] table")
    known = {f.name for f in fields(Ism)} - {"constellations"}
    unknown = set(data) - known - {"format"}
    if unknown:
        raise NavtrackError(f"{source}: unknown key(s) {', '.join(sorted(unknown))}")
    cfields = {f.name for f in fields(ConstellationIsm)}
    parsed = {}
    for sys_, table in consts.items():
        if len(sys_) != 1 or not isinstance(table, dict):
            raise NavtrackError(f"{source}: [constellation.{sys_}]: expected a system letter")
        bad = set(table) - cfields
        if bad:
            raise NavtrackError(
                f"{source}: [constellation.{sys_}]: unknown key(s) {', '.join(sorted(bad))}"
            )
        try:
            parsed[sys_] = ConstellationIsm(**{k: float(v) for k, v in table.items()})
        except (TypeError, ValueError) as exc:
            raise NavtrackError(f"{source}: [constellation.{sys_}]: {exc}") from None
    try:
        return Ism(constellations=parsed, **{k: float(v) for k, v in data.items() if k in known})
    except (TypeError, ValueError) as exc:
        raise NavtrackError(f"{source}: {exc}") from None


def read_ism(path: str | Path) -> Ism:
    """Read an ISM file (TOML).

    Format: top-level keys of :class:`Ism` (all optional, the ADD values by default) and one
    table ``[constellation.X]`` per system letter with the keys of :class:`ConstellationIsm`
    (``mfd_*`` optional)::

        format = "navtrack-ism 1"
        phmi_v = 9.8e-8
        [constellation.G]
        sigma_ura_m = 0.75
        sigma_ure_m = 0.5
        b_nom_m = 0.5
        b_cont_m = 0.0
        p_sat = 1e-5
        p_const = 1e-8

    Raises
    ------
    NavtrackError
        Naming the file and the key for a syntax error, an unknown key or a bad value.
    """
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise NavtrackError(f"{p}: {exc}") from None
    except OSError as exc:
        raise NavtrackError(f"{p}: {exc.strerror}") from None
    return _from_mapping(data, str(p))


def default_ism() -> Ism:
    """The ISM of ``navtrack/data/ism_add.toml`` (the ADD baseline)."""
    return read_ism(DEFAULT_ISM_PATH)


@dataclass(frozen=True, slots=True, eq=False)
class ErrorModel:
    """Per-measurement error model of an epoch batch.

    Attributes
    ----------
    var_int_m2, var_acc_m2 : ndarray, shape (B, S)
        Integrity and accuracy variances (m^2); ``inf`` outside the model.
    b_int_m, b_acc_m : ndarray, shape (B, S)
        Nominal biases (m).
    covered : ndarray of bool, shape (S,)
        The satellite's system is in the ISM.
    """

    var_int_m2: FloatArray
    var_acc_m2: FloatArray
    b_int_m: FloatArray
    b_acc_m: FloatArray
    covered: BoolArray


def _klobuchar_sigma_m(
    az_rad: FloatArray, el_rad: FloatArray, lat_rad: FloatArray, lon_rad: FloatArray
) -> FloatArray:
    """DO-229 J.2.3 ``F_pp tau_vert`` of the broadcast Klobuchar correction (m)."""
    el_sc = el_rad / math.pi
    psi = 0.0137 / (el_sc + 0.11) - 0.022  # earth angle, semicircles (IS-GPS-200 20.3.3.5.2.5)
    phi_i = np.clip(lat_rad[..., None] / math.pi + psi * np.cos(az_rad), -0.416, 0.416)
    lam_i = lon_rad[..., None] / math.pi + psi * np.sin(az_rad) / np.cos(phi_i * math.pi)
    phi_m = np.abs(phi_i + 0.064 * np.cos((lam_i - 1.617) * math.pi)) * 180.0  # degrees
    f_pp = 1.0 + 16.0 * (0.53 - el_sc) ** 3
    tau = np.where(phi_m <= 20.0, 9.0, np.where(phi_m <= 55.0, 4.5, 6.0))
    return np.asarray(f_pp * tau, dtype=float)


def error_model(
    ism: Ism,
    sats: tuple[str, ...],
    azel_rad: FloatArray,
    llh_rad: FloatArray,
    ionofree: bool,
) -> ErrorModel:
    """Variances and nominal biases of the ISM and airborne model for an epoch batch.

    Parameters
    ----------
    ism : Ism
    sats : tuple of str, length S
    azel_rad : ndarray, shape (B, S, 2)
        Azimuth and elevation (rad).
    llh_rad : ndarray, shape (B, 2)
        Receiver geodetic latitude and longitude (rad).
    ionofree : bool
        Ionosphere-free combination (no ionosphere term, amplified noise and multipath) or a
        single frequency with the broadcast Klobuchar correction.

    Returns
    -------
    ErrorModel
    """
    systems = [s[0] for s in sats]
    covered = np.array([s in ism.constellations for s in systems], dtype=bool)

    def per_sat(name: str) -> FloatArray:
        return np.array(
            [
                getattr(ism.constellations[s], name) if s in ism.constellations else np.inf
                for s in systems
            ]
        )

    el = np.clip(azel_rad[..., 1], math.radians(1.0), math.pi / 2)
    el_deg = np.degrees(el)
    sin_el = np.sin(el)
    var_tropo = (ism.tropo_sigma_m * 1.001) ** 2 / (0.002001 + sin_el**2)
    mp = ism.mp_a_m + ism.mp_b_m * np.exp(-el_deg / ism.mp_c_deg)
    noise = ism.noise_a_m + ism.noise_b_m * np.exp(-el_deg / ism.noise_c_deg)
    var_air = mp**2 + noise**2
    if ionofree:
        var_air = var_air * IONOFREE_NOISE_FACTOR**2
        var_iono = np.zeros_like(var_air)
    else:
        var_iono = _klobuchar_sigma_m(azel_rad[..., 0], el, llh_rad[:, 0], llh_rad[:, 1]) ** 2
    common = var_tropo + var_air + var_iono
    ura = per_sat("sigma_ura_m")
    ure = per_sat("sigma_ure_m")
    with np.errstate(invalid="ignore"):
        var_int = np.where(covered, ura**2 + common, np.inf)
        var_acc = np.where(covered, ure**2 + common, np.inf)
    shape = var_int.shape
    return ErrorModel(
        var_int_m2=var_int,
        var_acc_m2=var_acc,
        b_int_m=np.broadcast_to(np.where(covered, per_sat("b_nom_m"), 0.0), shape).copy(),
        b_acc_m=np.broadcast_to(np.where(covered, per_sat("b_cont_m"), 0.0), shape).copy(),
        covered=covered,
    )
