"""Carrier-phase relative positioning (RTK) of a rover against a base at a known position.

Stages, as RTKLIB's ``rtkpos`` chains them, over ``(epochs, satellites, frequencies)`` arrays:

1. :func:`receiver_signals` (:mod:`navtrack.gnss.rtk_signals`) — per receiver, the SPP
   stages of :mod:`navtrack.gnss.spp` (``code_pseudoranges`` -> ``satellite_states`` ->
   ``corrected_measurements`` -> ``estimate_position``) give the satellite states, the
   corrected code, the single point position; carrier phase (m), Doppler and loss-of-lock
   indicators of the same signals are added on the same axes.
2. :func:`common_epochs` — each rover epoch paired with the latest base epoch (a base tag up
   to ``sync_s`` after the rover's counts as the same epoch, receivers tag milliseconds off
   the grid), used up to ``max_age_s`` old (RTKLIB ``maxage``): a 1 Hz rover runs against a
   5 or 30 s base, the age in the output and its satellite clock drift in the variance.
3. :func:`detect_slips` — cycle slips from the loss-of-lock indicator, the Doppler-predicted
   phase change and (dual frequency) the geometry-free combination, per receiver, batched
   over all epochs and satellites.
4. :func:`solve_relative` (:mod:`navtrack.gnss.rtk_filter`) — a Kalman filter over the
   common epochs on the rover position and the single-differenced ambiguities (cycles) with
   double-differenced code and carrier observations (one reference satellite per system and
   frequency), then integer fixing of the double-differenced ambiguities by LAMBDA
   (:mod:`navtrack.gnss.ambiguity`) with the ratio test and partial fixing, validated
   (:class:`FixRejection`), and the position conditioned on the fixed integers.

Kinematic rovers: the position is a white process (re-initialised at the single point
solution with a 30 m standard deviation at every epoch, RTKLIB's ``dynamics off``), the
ambiguities a random walk. Static rovers: the position has no process noise, so the filter
is the recursive form of the batch least-squares solution of all epochs so far (for a linear
model both give the same estimate).

References
----------
Teunissen, P.J.G., Montenbruck, O. (eds.) (2017). Springer Handbook of GNSS, ch. 26 (RTK),
eq. 26.11-26.14 (double differences), 23.4 (ambiguity resolution).
Takasu, T. (2013). RTKLIB ver. 2.4.2 Manual, appendix E.7 (relative positioning: state,
measurement model, variances), E.7.6 (cycle slips).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import check_near_surface, ecef_to_geodetic, enu_rotation
from navtrack.gnss.rtk_config import (
    AFTER_RATIO_TEST,
    QUALITY,
    REJECTION_NAMES,
    STATUS_NAMES,
    FixRejection,
    RelativeInputError,
    RtkConfig,
    RtkStatus,
)
from navtrack.gnss.rtk_filter import (
    Baseline,
    FilterOutput,
    combine_directions,
    epoch_inputs,
    reverse_epochs,
    reverse_output,
    run_filter,
)
from navtrack.gnss.rtk_signals import (
    SECOND_BANDS,
    ReceiverSignals,
    Slips,
    carrier_bands,
    common_epochs,
    detect_slips,
    receiver_signals,
)
from navtrack.gnss.spp import navigation_tables

if TYPE_CHECKING:
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3
    from navtrack.gnss.spp import ProgressFn

__all__ = [
    "AFTER_RATIO_TEST",
    "QUALITY",
    "REJECTION_NAMES",
    "STATUS_NAMES",
    "FixRejection",
    "ReceiverSignals",
    "RelativeInputError",
    "RtkConfig",
    "RtkResult",
    "RtkStatus",
    "Slips",
    "common_epochs",
    "detect_slips",
    "receiver_signals",
    "solution_frame",
    "solve_relative",
]


@dataclass(frozen=True, slots=True, eq=False)
class RtkResult:
    """Relative positions of every rover epoch.

    Attributes
    ----------
    t_gps_s : ndarray, shape (E,)
        Rover epochs.
    sats : tuple of str, length S
        Satellites common to rover and base.
    pos_m : ndarray, shape (E, 3)
        Rover position (ECEF, m): fixed where ``status`` is ``fix``, float, DGNSS or single
        point otherwise; NaN for ``no_solution``.
    float_pos_m : ndarray, shape (E, 3)
        Float solution (NaN where none).
    sd_enu_m : ndarray, shape (E, 3)
        Formal standard deviation of ``pos_m`` in east, north, up (m).
    status : ndarray of int8, shape (E,)
        :class:`RtkStatus`.
    ratio : ndarray, shape (E,)
        Ratio-test value of the epoch's ambiguity search (NaN when none ran).
    n_sats : ndarray of int, shape (E,)
        Satellites in the double differences (references included).
    n_fixed : ndarray of int, shape (E,)
        Integer ambiguity combinations fixed.
    slips : mapping of str to int
        Slips flagged per detector, rover and base together.
    slip_mask : ndarray of bool, shape (E, S)
        A slip reset an ambiguity of that satellite at that epoch.
    age_s : ndarray, shape (E,)
        Age of the base observations used (rover minus base time, s; NaN without a base).
    fix_rejected : ndarray of int8, shape (E,)
        :class:`FixRejection`: why an epoch with phase double differences was not fixed (0
        where fixed or without phase).
    n_rover_epochs, n_base_epochs, n_common_epochs : int
    warnings : tuple of str
        Input problems found (base position far from the base's own SPP, a system without
        carrier phase, different rates).
    base_spp_distance_m : float
        Distance of the given base position from the median SPP of the base observations.
    """

    t_gps_s: FloatArray
    sats: tuple[str, ...]
    pos_m: FloatArray
    float_pos_m: FloatArray
    sd_enu_m: FloatArray
    status: np.ndarray
    ratio: FloatArray
    n_sats: IntArray
    n_fixed: IntArray
    slips: Mapping[str, int]
    slip_mask: BoolArray
    age_s: FloatArray
    fix_rejected: np.ndarray
    n_rover_epochs: int
    n_base_epochs: int
    n_common_epochs: int
    warnings: tuple[str, ...]
    base_spp_distance_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "slips", MappingProxyType(dict(self.slips)))
        freeze_arrays(self)

    def status_counts(self) -> dict[str, int]:
        """Epochs per status name (all statuses, zeros included)."""
        return {n: int(np.sum(self.status == i)) for i, n in enumerate(STATUS_NAMES)}

    def rejection_counts(self) -> dict[str, int]:
        """Epochs left float, per :class:`FixRejection` reason."""
        return {
            n: int(np.sum(self.fix_rejected == i))
            for i, n in enumerate(REJECTION_NAMES)
            if i != FixRejection.NONE
        }

    @property
    def quality(self) -> IntArray:
        """RTKLIB solution quality per epoch (:data:`QUALITY`)."""
        q = np.array([QUALITY[i] for i in range(len(RtkStatus))], dtype=np.int64)
        return q[self.status.astype(np.int64)]


def solve_relative(
    rover_obs: Observations,
    base_obs: Observations,
    nav: NavData | Sequence[NavData] | None,
    base_xyz_m: FloatArray,
    config: RtkConfig | None = None,
    *,
    sp3: Sp3 | None = None,
    base_warn_m: float = 100.0,
    progress: ProgressFn | None = None,
) -> RtkResult:
    """Relative (RTK) positions of every rover epoch against a base at a known position.

    Parameters
    ----------
    rover_obs, base_obs : Observations
    nav : NavData or sequence of NavData
        Broadcast navigation data (orbits and clocks unless ``sp3`` is given).
    base_xyz_m : array-like, shape (3,)
        Base antenna position (ECEF, m).
    config : RtkConfig, optional
    sp3 : Sp3, optional
    base_warn_m : float
        Warn when ``base_xyz_m`` is farther than this from the base's own median SPP.
    progress : callable, optional
        ``progress(epochs_done, epochs_total)`` every 100 epochs of each filter pass.

    Returns
    -------
    RtkResult

    Raises
    ------
    RelativeInputError
        No common epochs or no common satellites of the configured systems.
    ValueError
        ``base_xyz_m`` not a point near the earth's surface.
    """
    cfg = config or RtkConfig()
    base_xyz = check_near_surface(base_xyz_m, "base_xyz_m")
    tables = navigation_tables(nav)
    second = _second_bands(rover_obs, base_obs)
    rover = receiver_signals(rover_obs, nav, cfg, sp3=sp3, ephemeris=tables, second_bands=second)
    base = receiver_signals(base_obs, nav, cfg, sp3=sp3, ephemeris=tables, second_bands=second)
    pair = _pair(rover, base, base_xyz, cfg)
    warnings = _input_warnings(pair, cfg)
    if cfg.frequencies == 2:
        systems = list(dict.fromkeys(x[0] for x in pair.sats))
        warnings += _second_band_warnings(rover_obs, base_obs, second, systems)
    dist = float(np.linalg.norm(np.nanmedian(base.spp_pos_m, axis=0) - base_xyz))
    if dist > base_warn_m:
        warnings.insert(
            0,
            f"base position is {dist:.1f} m from the single point solution of the base "
            f"observations {base_obs.path!r}: check --base-pos",
        )
    ep = epoch_inputs(pair, cfg)
    if cfg.direction == "forward":
        out = run_filter(ep, cfg, progress)
    else:
        out = reverse_output(run_filter(reverse_epochs(ep), cfg, progress))
        if cfg.direction == "combined":
            out = combine_directions(run_filter(ep, cfg, progress), out)
    return _result(pair, out, warnings, dist)


def _second_bands(rover: Observations, base: Observations) -> dict[str, str]:
    """The second frequency of each system: the first band of :data:`SECOND_BANDS` in which
    both receivers hold carrier phase."""
    out = {}
    for system, bands in SECOND_BANDS.items():
        at_base = carrier_bands(base, system, bands)
        both = [b for b in carrier_bands(rover, system, bands) if b in at_base]
        if both:
            out[system] = both[0]
    return out


def _pair(
    rover: ReceiverSignals, base: ReceiverSignals, base_xyz: FloatArray, cfg: RtkConfig
) -> Baseline:
    """The common epochs and satellites of rover and base, and their slips."""
    names = f"rover {rover.path!r} and base {base.path!r}"
    ir, ib, age = common_epochs(
        rover.t_gps_s, base.t_gps_s, sync_s=cfg.sync_s, max_age_s=cfg.max_age_s
    )
    if ir.size == 0:
        raise RelativeInputError(
            f"{names}: no common epochs (no base epoch up to {cfg.max_age_s:g} s before a rover "
            "epoch)"
        )
    common = [s for s in rover.sats if s in base.sats]
    if not common:
        raise RelativeInputError(f"{names}: no common satellites of the systems {cfg.systems}")
    pair = Baseline(
        rover=rover,
        base=base,
        base_xyz_m=base_xyz,
        rover_idx=ir,
        base_idx=ib,
        age_s=age,
        rover_cols=np.array([rover.sats.index(s) for s in common], dtype=np.int64),
        base_cols=np.array([base.sats.index(s) for s in common], dtype=np.int64),
        slips_rover=detect_slips(rover, cfg),
        slips_base=detect_slips(base, cfg),
    )
    return pair


def _input_warnings(pair: Baseline, cfg: RtkConfig) -> list[str]:
    out = []
    rover, base = pair.rover, pair.base
    n_r, n_b, n_c = rover.t_gps_s.size, base.t_gps_s.size, pair.rover_idx.size
    if n_c < n_r:
        out.append(
            f"rover {n_r} and base {n_b} epochs: {n_r - n_c} rover epochs without a base epoch "
            f"up to {cfg.max_age_s:g} s before them (no_base); {n_c} common epochs used"
        )
    sats = pair.sats
    for s in dict.fromkeys(x[0] for x in sats):
        cols = [i for i, x in enumerate(sats) if x[0] == s]
        for who, sig, js in (("rover", rover, pair.rover_cols), ("base", base, pair.base_cols)):
            if not np.isfinite(sig.phase_cyc[:, js[cols], 0]).any():
                out.append(f"system {s}: no carrier phase in the {who} {sig.path!r}: code only")
    return out


def _second_band_warnings(
    rover: Observations, base: Observations, second: Mapping[str, str], systems: Sequence[str]
) -> list[str]:
    """A warning for each system of ``systems`` without a second band carried by both
    receivers, naming the second bands each one does carry."""
    out = []
    for s in systems:
        if s in second or s not in SECOND_BANDS:
            continue
        held = {
            who: carrier_bands(obs, s, SECOND_BANDS[s])
            for who, obs in (("rover", rover), ("base", base))
        }
        named = ", ".join(f"{who} {'/'.join(b) if b else 'none'}" for who, b in held.items())
        out.append(
            f"system {s}: no second band with carrier phase in both receivers (bands "
            f"{'/'.join(SECOND_BANDS[s])}; {named}): first frequency only"
        )
    return out


def _result(pair: Baseline, out: FilterOutput, warnings: list[str], dist: float) -> RtkResult:
    rover, ir = pair.rover, pair.rover_idx
    n_e, n_s = rover.t_gps_s.size, pair.rover_cols.size

    def spread(values: np.ndarray, fill: float | int, shape: tuple[int, ...] = ()) -> np.ndarray:
        full = np.full((n_e, *shape), fill, dtype=values.dtype)
        full[ir] = values
        return full

    spp_ok = np.all(np.isfinite(rover.spp_pos_m), axis=1)
    status = np.where(spp_ok, RtkStatus.NO_BASE, RtkStatus.NO_SOLUTION).astype(np.int8)
    status[ir] = out.status
    pos = np.where(spp_ok[:, None], rover.spp_pos_m, np.nan)
    pos[ir] = np.where(np.isfinite(out.pos), out.pos, pos[ir])
    llh = ecef_to_geodetic(np.where(np.isfinite(pos), pos, 6.4e6))
    rot = enu_rotation(llh[:, 0], llh[:, 1])
    cov = spread(out.cov, np.nan, (3, 3))
    counts = {k: v + pair.slips_base.counts()[k] for k, v in pair.slips_rover.counts().items()}
    counts["ambiguity_resets"] = int(out.slip.sum())
    return RtkResult(
        t_gps_s=rover.t_gps_s.copy(),
        sats=pair.sats,
        pos_m=pos,
        float_pos_m=spread(out.float_pos, np.nan, (3,)),
        sd_enu_m=np.sqrt(np.abs(np.einsum("eij,ejk,eik->ei", rot, cov, rot))),
        status=status,
        ratio=spread(out.ratio, np.nan),
        n_sats=spread(out.n_sats, 0),
        n_fixed=spread(out.n_fixed, 0),
        slips=counts,
        slip_mask=spread(out.slip, False, (n_s,)),
        age_s=spread(pair.age_s, np.nan),
        fix_rejected=spread(out.rejected, 0),
        n_rover_epochs=n_e,
        n_base_epochs=pair.base.t_gps_s.size,
        n_common_epochs=ir.size,
        warnings=tuple(warnings),
        base_spp_distance_m=dist,
    )


def solution_frame(result: RtkResult) -> dict[str, np.ndarray]:
    """The solution as a solution frame (:func:`navtrack.io.solution.write_solution`): the
    SPP columns ``t_gps_s``, ``x_m``, ``y_m``, ``z_m``, ``sd_e_m``, ``sd_n_m``, ``sd_u_m``,
    ``n_sats``, ``status`` (name), ``excluded`` (empty), then ``quality`` (RTKLIB Q),
    ``ratio``, ``n_fixed``, ``age_s`` (age of the base observations) and ``fix_rejected``
    (why a float epoch was not fixed, :class:`FixRejection` name; empty otherwise)."""
    names = np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)]
    reasons = np.array(["", *REJECTION_NAMES[1:]], dtype=object)
    return {
        "t_gps_s": result.t_gps_s,
        "x_m": result.pos_m[:, 0],
        "y_m": result.pos_m[:, 1],
        "z_m": result.pos_m[:, 2],
        "sd_e_m": result.sd_enu_m[:, 0],
        "sd_n_m": result.sd_enu_m[:, 1],
        "sd_u_m": result.sd_enu_m[:, 2],
        "n_sats": result.n_sats,
        "status": names,
        "excluded": np.full(result.t_gps_s.size, "", dtype=object),
        "quality": result.quality,
        "ratio": result.ratio,
        "n_fixed": result.n_fixed,
        "age_s": result.age_s,
        "fix_rejected": reasons[result.fix_rejected.astype(np.int64)],
    }
