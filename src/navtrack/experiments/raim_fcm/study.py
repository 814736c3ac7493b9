"""Fault-injection study on the shared real data: every RAIM method on the same faulty epochs.

One Monte Carlo run draws, per station, fault count ``k`` and bias ``b``, ``trials_per_run``
distinct solved epochs and ``k`` of each epoch's used satellites, adds ``+-b`` (random sign) to
their pseudoranges, re-estimates those epochs and runs every method on them
(:func:`navtrack.integrity.raim.monitor`). Clean epochs (no bias) measure false alarms and
wrong exclusions. The variance factor of the weighting model is estimated once per station from
its clean solution (:func:`navtrack.integrity.raim.variance_factor`); ``rtklib`` is the
RTKLIB-like baseline: leave-one-out on RTKLIB's own variances (factor 1), RTKLIB 2.4.3's
``raim_fde`` after its chi-square test with ``alpha = 0.001``.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from navtrack._typing import FloatArray, IntArray
from navtrack.geodesy import ecef_to_enu
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import (
    Measurements,
    PositionEstimate,
    SppConfig,
    SppStatus,
    code_pseudoranges,
    corrected_measurements,
    estimate_position,
    satellite_states,
)
from navtrack.integrity.ism import Ism, read_ism
from navtrack.integrity.raim import RaimConfig, RaimStatus, monitor, variance_factor
from navtrack.io.rtklib import read_pos

__all__ = [
    "STATIONS",
    "RaimFcmParams",
    "Station",
    "StationData",
    "injection_run",
    "raim_config",
    "rtklib_live_raim",
    "station_data",
    "summarize_study",
]


class Station(NamedTuple):
    """A shared data set with a surveyed position (``shared/data/gnss/README.md``)."""

    obs: str
    nav: str
    systems: str
    ref_xyz_m: tuple[float, float, float]


#: The stations of the study (paths relative to the shared data's ``gnss`` folder).
STATIONS: dict[str, Station] = {
    "SEPT": Station(
        "cssrlib_sept/SEPT078M.21O",
        "cssrlib_sept/SEPT078M.21P",
        "GEJ",
        (-3962108.673, 3381309.574, 3668678.638),
    ),
    "ARL1": Station(
        "gpstk_arl1/arlm200a.15o",
        "gpstk_arl1/arlm2000.15n",
        "G",
        (-740289.918, -5457071.734, 3207245.542),
    ),
    "0759": Station(
        "rtklib_gsi0759/07590920.05o",
        "rtklib_gsi0759/07590920.05n",
        "G",
        (-3976219.188, 3382371.606, 3652511.143),
    ),
    "YAMATOGAWA": Station(
        "gogps_yamatogawa/yamatogawa_master.obs",
        "gogps_yamatogawa/brdc0060.10n",
        "G",
        (-3749943.5172, 3683398.2394, 3600629.5295),
    ),
}

METHODS = ("rtklib", "chi2", "loo", "fde", "ss", "fcm", "araim")


@dataclass(frozen=True, slots=True)
class RaimFcmParams:
    """Parameters of ``navtrack reproduce raim-fcm``.

    Attributes
    ----------
    stations : tuple of str
        Keys of :data:`STATIONS`.
    biases_m : tuple of float
        Injected pseudorange faults (m; issue 10: 3, 5, 10, 15, 20, 30, 50).
    fault_counts : tuple of int
        Simultaneous faulty satellites (1, 2, 3).
    trials_per_run : int
        Faulty epochs per station, count and bias in one run (distinct epochs).
    methods : tuple of str
        ``rtklib`` (baseline) and the :data:`navtrack.integrity.raim.METHODS`.
    pfa, pmd : float
        As :class:`navtrack.integrity.raim.RaimConfig`.
    fcm_m : float
        FCM weighting exponent.
    fcm_stop : {"memberships", "centres"}
        FCM stopping rule: the change of the memberships (Bezdek, the default) or of the
        cluster centres (the paper's section 3.2).
    iono : {"klobuchar", "ionofree"}
        Ionosphere handling of the stations' SPP (:class:`navtrack.gnss.spp.SppConfig`); the
        injected fault is added to the pseudorange the solution uses (the ionosphere-free
        combination with ``ionofree``). The RTKLIB live comparison stays on L1.
    ism : str
        Integrity support message file of every method's error model and of ARAIM's priors
        (:func:`navtrack.integrity.ism.read_ism`); empty: the default (the ADD baseline).
    """

    stations: tuple[str, ...] = ("SEPT", "ARL1", "0759", "YAMATOGAWA")
    biases_m: tuple[float, ...] = (3.0, 5.0, 10.0, 15.0, 20.0, 30.0, 50.0)
    fault_counts: tuple[int, ...] = (1, 2, 3)
    trials_per_run: int = 40
    methods: tuple[str, ...] = METHODS
    pfa: float = 1e-3
    pmd: float = 1e-3
    fcm_m: float = 2.0
    fcm_stop: str = "memberships"
    iono: str = "klobuchar"
    ism: str = ""

    def __post_init__(self) -> None:
        if self.iono not in ("klobuchar", "ionofree"):
            raise ValueError(f"iono: expected klobuchar or ionofree, got {self.iono!r}")
        if self.fcm_stop not in ("memberships", "centres"):
            raise ValueError(f"fcm_stop: expected memberships or centres, got {self.fcm_stop!r}")
        bad = [s for s in self.stations if s not in STATIONS]
        if bad:
            raise ValueError(f"stations: unknown {bad}; expected some of {sorted(STATIONS)}")
        bad = [m for m in self.methods if m not in METHODS]
        if bad:
            raise ValueError(f"methods: unknown {bad}; expected some of {METHODS}")
        if self.trials_per_run < 1:
            raise ValueError(f"trials_per_run: expected >= 1, got {self.trials_per_run}")
        if any(k < 1 for k in self.fault_counts):
            raise ValueError(f"fault_counts: expected >= 1, got {self.fault_counts}")
        if any(not b > 0 for b in self.biases_m):
            raise ValueError(f"biases_m: expected positive biases, got {self.biases_m}")


@dataclass(frozen=True, slots=True, eq=False)
class StationData:
    """A station's measurements, clean estimate and variance factor."""

    name: str
    meas: Measurements
    config: SppConfig
    clean: PositionEstimate
    variance_factor: float
    ref_xyz_m: np.ndarray


@lru_cache(maxsize=8)
def station_data(gnss_dir: str, name: str, iono: str = "klobuchar") -> StationData:
    """Read and solve a station once per process (cached)."""
    st = STATIONS[name]
    obs = read_obs(Path(gnss_dir) / st.obs)
    nav = read_nav(Path(gnss_dir) / st.nav)
    cfg = SppConfig(systems=st.systems, iono=iono)
    pr = code_pseudoranges(obs, cfg)
    meas = corrected_measurements(pr, satellite_states(pr, [nav], config=cfg), cfg)
    clean = estimate_position(meas, cfg)
    return StationData(
        name, meas, cfg, clean, variance_factor(clean), np.asarray(st.ref_xyz_m, dtype=float)
    )


def raim_config(params: RaimFcmParams, method: str, s2: float) -> RaimConfig:
    """The RAIM configuration of a study method (``rtklib``: navtrack's ``loo`` with RTKLIB's
    unit variance factor) with the study's ``pfa``, ``pmd``, FCM exponent and stopping rule and
    the station's variance factor ``s2``."""
    ism = _read_ism(params.ism) if params.ism else None
    if method == "rtklib":
        return RaimConfig("loo", pfa=params.pfa, pmd=params.pmd, variance_factor=1.0, ism=ism)
    return RaimConfig(
        method,
        pfa=params.pfa,
        pmd=params.pmd,
        fcm_m=params.fcm_m,
        fcm_stop=params.fcm_stop,
        variance_factor=s2,
        ism=ism,
    )


@lru_cache(maxsize=4)
def _read_ism(path: str) -> Ism:
    return read_ism(path)


def _trial_outcomes(
    data: StationData,
    est: PositionEstimate,
    meas: Measurements,
    fault: np.ndarray,
    raim: RaimConfig,
) -> dict[str, Any]:
    """Counts and per-trial errors and protection levels of one method on a batch of epochs."""
    final, _, integ = monitor(meas, est, data.config, raim)
    enu = ecef_to_enu(final.x[:, :3], data.ref_xyz_m)
    err_h = np.hypot(enu[:, 0], enu[:, 1])
    err_v = np.abs(enu[:, 2])
    faulty = fault.any(axis=1)
    excl = integ.excluded
    usable = (integ.status == RaimStatus.OK) | (integ.status == RaimStatus.EXCLUDED)
    return {
        "trials": int(fault.shape[0]),
        "detected": int(integ.detected.sum()),
        "identified": int(np.sum(np.all(excl == fault, axis=1) & faulty)),
        "wrong_exclusion": int(np.sum((excl & ~fault).any(axis=1))),
        "any_exclusion": int(np.sum(excl.any(axis=1))),
        "alert": int(np.sum(integ.status == RaimStatus.ALERT)),
        "unavailable": int(np.sum(integ.status == RaimStatus.UNAVAILABLE)),
        "hmi_h": int(np.sum(usable & (err_h > integ.hpl_m))),
        "hmi_v": int(np.sum(usable & (err_v > integ.vpl_m))),
        "err_h_m": err_h.tolist(),
        "err_3d_m": np.linalg.norm(enu, axis=1).tolist(),
        "hpl_m": integ.hpl_m.tolist(),
        "vpl_m": integ.vpl_m.tolist(),
        "err_v_m": err_v.tolist(),
        "usable": usable.tolist(),
    }


def injection_run(params: RaimFcmParams, rng: np.random.Generator, gnss_dir: str) -> dict[str, Any]:
    """One Monte Carlo run of the study: ``{station: {"clean": {method: outcome}, "k{k}_b{b}":
    {method: outcome}}}`` with the counts of :func:`_trial_outcomes`."""
    out: dict[str, Any] = {}
    for name in params.stations:
        data = station_data(gnss_dir, name, params.iono)
        meas, clean = data.meas, data.clean
        solved = np.flatnonzero((clean.status == SppStatus.OK) & (clean.dof >= 1))
        n = min(params.trials_per_run, solved.size)
        st: dict[str, Any] = {}
        cases = [(0, 0.0)] + [(k, b) for k in params.fault_counts for b in params.biases_m]
        for k, b in cases:
            ep = np.sort(rng.choice(solved, size=n, replace=False))
            fault = np.zeros((n, meas.y_m.shape[1]), dtype=bool)
            sign = np.zeros((n, meas.y_m.shape[1]))
            for i, e in enumerate(ep):
                cand = np.flatnonzero(clean.used[e])
                pick = rng.choice(cand, size=min(k, cand.size), replace=False)
                fault[i, pick] = True
                sign[i, pick] = rng.choice([-1.0, 1.0], size=pick.size)
            y = np.array(meas.y_m)
            y[ep] += b * sign
            mf = meas.replace(y_m=y)
            est = estimate_position(mf, data.config, epochs=ep, x0_m=clean.x[ep])
            key = "clean" if k == 0 else f"k{k}_b{b:g}"
            st[key] = {
                m: _trial_outcomes(
                    data, est, mf, fault, raim_config(params, m, data.variance_factor)
                )
                for m in params.methods
            }
        st["variance_factor"] = data.variance_factor
        out[name] = st
    return out


_COUNTS = ("trials", "detected", "identified", "wrong_exclusion", "any_exclusion", "alert",
           "unavailable", "hmi_h", "hmi_v")  # fmt: skip


def summarize_study(params: RaimFcmParams, runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Rates (fractions) per station, case and method over all runs.

    Returns
    -------
    dict
        ``{station: {"variance_factor": s2, "cases": {case: {method: {"trials", "detection",
        "identification", "wrong_exclusion", "exclusion", "alert", "unavailable",
        "misleading_h", "misleading_v", "err_h_p95_m", "err_3d_median_m", "hpl_median_m"}}}}}``;
        for ``clean`` the detection rate is the false-alarm rate.
    """
    out: dict[str, Any] = {}
    for name in params.stations:
        present = [r[name] for r in runs if name in r]
        if not present:
            continue
        cases: dict[str, Any] = {}
        for case in present[0]:
            if case == "variance_factor":
                continue
            cases[case] = {}
            for m in params.methods:
                parts = [r[case][m] for r in present]
                c = {k: sum(p[k] for p in parts) for k in _COUNTS}
                t = max(c["trials"], 1)
                err_h = np.concatenate([p["err_h_m"] for p in parts])
                err_3d = np.concatenate([p["err_3d_m"] for p in parts])
                hpl = np.concatenate([p["hpl_m"] for p in parts]).astype(float)
                cases[case][m] = {
                    "trials": c["trials"],
                    "detection": c["detected"] / t,
                    "identification": c["identified"] / t,
                    "wrong_exclusion": c["wrong_exclusion"] / t,
                    "exclusion": c["any_exclusion"] / t,
                    "alert": c["alert"] / t,
                    "unavailable": c["unavailable"] / t,
                    "misleading_h": c["hmi_h"] / t,
                    "misleading_v": c["hmi_v"] / t,
                    "err_h_p95_m": float(np.percentile(err_h, 95)),
                    "err_3d_median_m": float(np.median(err_3d)),
                    "hpl_median_m": float(np.nanmedian(hpl)) if np.isfinite(hpl).any() else None,
                }
        out[name] = {"variance_factor": present[0]["variance_factor"], "cases": cases}
    return out


def _biased_rinex2(lines: list[str], code: str, faults: dict[tuple[int, str], float]) -> str:
    """A RINEX 2 observation file with ``faults[(epoch, sat)]`` metres added to the ``code``
    pseudorange (F14.3 fields of 16 columns, 5 per line)."""
    types: list[str] = []
    out = list(lines)
    i = 0
    while "END OF HEADER" not in out[i]:
        if "# / TYPES OF OBSERV" in out[i]:
            types += out[i][6:60].split()
        i += 1
    per_sat = (len(types) + 4) // 5
    col = types.index(code)
    i += 1
    epoch = -1
    while i < len(out):
        head = out[i]
        if not head.strip():
            i += 1
            continue
        epoch += 1
        n = int(head[29:32])
        sats = head[32:68]
        j = i + 1
        while len(sats) < 3 * n:  # continuation lines of the satellite list
            sats += out[j][32:68]
            j += 1
        names = [sats[3 * k : 3 * k + 3].replace(" ", "0") for k in range(n)]
        for k, sat in enumerate(names):
            bias = faults.get((epoch, sat))
            if bias:
                li = j + k * per_sat + col // 5
                c0 = 16 * (col % 5)
                text = out[li].rstrip("\n").ljust(80)
                value = float(text[c0 : c0 + 14]) + bias
                out[li] = text[:c0] + f"{value:14.3f}" + text[c0 + 14 :].rstrip() + "\n"
        i = j + n * per_sat
    return "".join(out)


def _rtklib_used(stat_path: Path) -> dict[int, set[str]]:
    """Satellites RTKLIB used per epoch, keyed by the rounded time of week: its residual
    status file has a ``$SAT`` record for each valid satellite (``ssat.vs``) only."""
    used: dict[int, set[str]] = {}
    for line in stat_path.read_text().splitlines():
        if line.startswith("$SAT"):
            f = line.split(",")
            used.setdefault(round(float(f[2])), set()).add(f[3])
    return used


def _run_rnx2rtkp(exe: str, conf: Path, obs: Path, nav: Path, pos: Path) -> dict[int, set[str]]:
    cmd = [exe, "-k", str(conf), str(obs), str(nav), "-o", str(pos)]
    subprocess.run(cmd, check=True, capture_output=True)
    return _rtklib_used(Path(str(pos) + ".stat"))


def rtklib_live_raim(
    params: RaimFcmParams,
    rng: np.random.Generator,
    gnss_dir: str,
    work_dir: Path,
    biases_m: tuple[float, ...] = (10.0, 15.0, 20.0),
    station: str = "ARL1",
) -> dict[str, Any]:
    """RTKLIB's RAIM FDE (live ``rnx2rtkp``, ``spp_gps_raim.conf``) and navtrack's ``fde`` on
    the same single faults: one satellite per epoch biased in every epoch of a faulty copy of
    the RINEX 2 file, one copy per bias.

    Returns
    -------
    dict
        ``{bias: {"rtklib": {...}, "fde": {...}}}`` with ``trials``, ``identification``,
        ``wrong_exclusion``, ``exclusion``, ``err_h_p95_m``.
    """
    exe = shutil.which("rnx2rtkp")
    if exe is None:
        return {"skipped": "rnx2rtkp not on PATH"}
    st = STATIONS[station]
    data = station_data(gnss_dir, station)
    conf_src = Path(gnss_dir) / "rtklib_spp" / "conf" / "spp_gps_raim.conf"
    conf = work_dir / "spp_gps_raim_residuals.conf"
    conf.write_text(
        conf_src.read_text().replace("out-outstat        =off", "out-outstat        =residual")
    )
    lines = (Path(gnss_dir) / st.obs).read_text().splitlines(keepends=True)
    meas, clean = data.meas, data.clean
    n_e = meas.y_m.shape[0]
    nav = Path(gnss_dir) / st.nav
    clean_used = _run_rnx2rtkp(exe, conf, Path(gnss_dir) / st.obs, nav, work_dir / "clean.pos")
    out: dict[str, Any] = {}
    for b in biases_m:
        pick = np.array([rng.choice(np.flatnonzero(clean.used[e])) for e in range(n_e)])
        sign = rng.choice([-1.0, 1.0], size=n_e)
        faults = {(e, meas.sats[pick[e]]): b * sign[e] for e in range(n_e)}
        obs_path = work_dir / f"{station}_bias{b:g}.obs"
        obs_path.write_text(_biased_rinex2(lines, "C1", faults))
        pos = work_dir / f"{station}_bias{b:g}.pos"
        used = _run_rnx2rtkp(exe, conf, obs_path, nav, pos)
        sol = read_pos(pos)
        tows = sorted(clean_used)
        if len(tows) != n_e or sorted(used) != tows or len(sol) != n_e:
            return {"skipped": f"RTKLIB solved {len(sol)} of {n_e} epochs"}
        rows: dict[str, list[tuple[set[str], float]]] = {"rtklib": [], "fde": []}
        enu = ecef_to_enu(sol[["x_m", "y_m", "z_m"]].to_numpy(), data.ref_xyz_m)
        for k, tow in enumerate(tows):
            excl = clean_used[tow] - used[tow]
            rows["rtklib"].append((excl, float(np.hypot(enu[k, 0], enu[k, 1]))))
        rows["fde"] = _fde_rows(params, data, pick, b * sign)
        truth = [{meas.sats[pick[e]]} for e in range(n_e)]
        out[f"{b:g}"] = {name: _single_fault_rates(r, truth) for name, r in rows.items()}
    return out


def _fde_rows(
    params: RaimFcmParams, data: StationData, pick: IntArray, bias_m: FloatArray
) -> list[tuple[set[str], float]]:
    """navtrack ``fde`` on one fault per epoch (satellite ``pick[e]``, bias ``bias_m[e]``):
    the satellites excluded and the horizontal error of each epoch."""
    meas, n_e = data.meas, data.meas.y_m.shape[0]
    fault = np.zeros(meas.y_m.shape, dtype=bool)
    fault[np.arange(n_e), pick] = True
    mf = meas.replace(y_m=np.array(meas.y_m) + bias_m[:, None] * fault)
    est = estimate_position(mf, data.config, x0_m=data.clean.x)
    cfg = raim_config(params, "fde", data.variance_factor)
    final, _, integ = monitor(mf, est, data.config, cfg)
    enu = ecef_to_enu(final.x[:, :3], data.ref_xyz_m)
    return [
        (
            {meas.sats[j] for j in np.flatnonzero(integ.excluded[e])},
            float(np.hypot(enu[e, 0], enu[e, 1])),
        )
        for e in range(n_e)
    ]


def _single_fault_rates(r: list[tuple[set[str], float]], truth: list[set[str]]) -> dict[str, Any]:
    """Identification, wrong exclusion, exclusion and 95th percentile horizontal error of
    single-fault trials (excluded set and error per trial, against the faulty satellite)."""
    pairs = list(zip(r, truth, strict=True))
    return {
        "trials": len(r),
        "identification": float(np.mean([x == t for (x, _), t in pairs])),
        "wrong_exclusion": float(np.mean([bool(x - t) for (x, _), t in pairs])),
        "exclusion": float(np.mean([bool(x) for x, _ in r])),
        "err_h_p95_m": float(np.percentile([h for _, h in r], 95)),
    }
