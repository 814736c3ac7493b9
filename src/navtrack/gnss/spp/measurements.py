"""Stage 3 of single point positioning: pseudoranges corrected for everything that does not
depend on the receiver position (RTKLIB ``prange``), usability masks and clock groups."""

from __future__ import annotations

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import C_MPS
from navtrack.gnss.corrections import ionofree
from navtrack.gnss.spp.config import ERR_CBIAS_M, SppConfig
from navtrack.gnss.spp.satellites import SatelliteStates
from navtrack.gnss.spp.signals import Pseudoranges

__all__ = ["Measurements", "corrected_measurements"]


class Measurements(Record):
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
        Satellite-side variance (m^2): URA^2 plus the code bias error
        :data:`~navtrack.gnss.spp.config.ERR_CBIAS_M` squared.
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
        iterate of :func:`~navtrack.gnss.spp.estimate.estimate_position`.
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
    usability masks and the clock groups (stage 3 of :func:`~navtrack.gnss.spp.solve_spp`).

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
        var_sat_m2=sv.var_m2 + ERR_CBIAS_M**2,
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
