"""Fix rate, wrong fixes and time to first fix of ``navtrack rtk`` beside RTKLIB 2.4.3's
``rnx2rtkp`` on the same baselines, run live.

Cases (all in ``shared/data/gnss``):

* ``yamatogawa``: the walking u-blox rover against its 1 Hz master, L1 GPS, kinematic,
  forward and combined; also with the master thinned to 5 s and 30 s (a CORS-rate base:
  the rover's 1 Hz epochs use base observations up to 30 s old). Reference: RTKLIB's
  combined fixed solution with the 1 Hz master (stored with the data); epochs RTKLIB left
  float are compared with its float position and listed.
* ``gsi0759``: GEONET 0759 against 3040 (3.3 km, 30 s, L1+L2, geodetic receivers) solved
  kinematically (every epoch on its own) and statically; kinematic also against 3040 thinned
  to 60 s with base observations used up to 60 s old (both programs), L1 and L1+L2.
  Reference: the station coordinate of the data README.

* ``mosaic``: MatRTKLIB's static pair of two Septentrio mosaic-X5 receivers (1 m apart, 1 Hz,
  5 min, GPS/Galileo/BeiDou/QZSS L1+L2), forward; also with the base thinned to 5 s and 30 s.
  Reference: the rover coordinate published with the data. ``mosaic2018``: MatRTKLIB's earlier
  static pair (a 1 Hz rover against a Trimble NetR9 base 7 m away, 10 min), forward L1+L2.
  Both from ``--data`` (default ``../data_r30``, see its README); skipped when absent.

* ``ublox``: the geofis/ppk pair of two u-blox ZED-F9P receivers (static rover 1.2 km from
  the base, 15 s, 4 h, GPS/Galileo/BeiDou/QZSS), L1 and L1+L2. Reference: RTKLIB's static
  solution of the whole session against the same base position.
* ``decimated``: a 1 Hz rover against a real geodetic base decimated to CORS rates (no public
  CORS file overlapping a public u-blox rover log was found): the MatRTKLIB 2018 rover against
  its Trimble NetR9 base at 1, 5 and 30 s (L1), and the ZED-F9P pair with its base thinned from
  15 to 30 s (L1+L2); both programs read the same decimated file.
* ``glonass``: on the three low-cost pairs, the GLONASS code inter-frequency bias between the
  receivers (:func:`glonass_code_bias`), GLONASS alone in the float solution, and the other
  systems without and with GLONASS beside RTKLIB.
* ``rtcm``: GLONASS and the other MSM7 of the RDSD NTRIP recording read as ``convbin`` reads
  them (:func:`rtcm_against_convbin`).

RTKLIB's systems are set through ``pos1-navsys``: this build's ``-sys`` option turns on every
system whatever its letters.

A wrong fix is a fixed epoch more than ``--wrong-m`` (0.10 m) from the reference. Time to first
fix is the time from the first common epoch to the first fixed one (forward runs).

``--evidence``: the yamatogawa combined fix at 05:59:54 GPST (RTKLIB float there) shown right
by its integers (:func:`evidence_055954`).

Usage::

    PYTHONPATH=src python benchmarks/eval_rtk_fixes.py [--set min_fix_sats=3 ...] [--evidence]
        [--data DIR] [--only NAME]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.geodesy import C_MPS, geodetic_to_ecef
from navtrack.gnss.relative import RtkConfig, RtkStatus, solve_relative
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rtcm import read_rtcm
from navtrack.gnss.rtk_filter import satellite_geometry
from navtrack.gnss.rtk_signals import common_epochs, receiver_signals
from navtrack.io.rtklib import read_pos
from navtrack.timescale import parse_gpst

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
YAMA = SHARED / "gogps_yamatogawa"
GSI = SHARED / "rtklib_gsi0759"
YAMA_BASE = (-3749943.5172, 3683398.2394, 3600629.5295)
GSI_BASE = (-3978241.958, 3382840.234, 3649900.853)  # 3040, as RTKLIB's own tests hold it
GSI_REF = (-3976219.188, 3382371.606, 3652511.143)  # 0759, shared data README
EXTRA = Path(os.environ.get("NAVTRACK_RTK_DATA", REPO.parent / "data_r30"))
MOSAIC = "matrtklib_static"
MOSAIC_2018 = "matrtklib_static_2023"  # the folder is named after the commit year
UBLOX = "geofis_ppk_2022"
NTRIP_RECORDING = "geofis_ppk_2021/20210809-111055-rtcm3-base-corrections.rtcm3"
RTKLIB_NAVSYS = {"G": 1, "R": 4, "E": 8, "J": 16, "C": 32}  # RTKLIB's pos1-navsys bits
UBLOX_BASE = (2078720.6329, -5683487.5402, 2007608.6397)  # the base file's header position
GLONASS_CHANNEL_HZ = 0.5625e6  # G1 channel spacing, GLONASS ICD 3.3.1.4
GLONASS_G1_HZ = 1602e6


def llh_file(path: Path) -> tuple[float, float, float]:
    """ECEF of a MatRTKLIB ``*_position.txt`` (latitude, longitude in degrees, height in m)."""
    lat, lon, h = (float(v) for v in path.read_text().split()[:3])
    x, y, z = geodetic_to_ecef([np.radians(lat), np.radians(lon), h])
    return (float(x), float(y), float(z))


def thin_rinex2(src: Path, dst: Path, step_s: int) -> Path:
    """A RINEX 2 observation file keeping the epochs whose time of day is a multiple of
    ``step_s`` (to the second), records copied unchanged."""
    lines = src.read_text().splitlines(keepends=True)
    end = next(i for i, ln in enumerate(lines) if "END OF HEADER" in ln) + 1
    n_types = next(int(ln[:6]) for ln in lines[:end] if "# / TYPES OF OBSERV" in ln)
    out = lines[:end]
    i = end
    while i < len(lines):
        head = lines[i]
        flag, n = int(head[28]), int(head[29:32])
        n_list = (n - 1) // 12 if flag <= 1 else 0
        n_rec = n * ((n_types + 4) // 5) if flag <= 1 else n
        block = lines[i : i + 1 + n_list + n_rec]
        i += 1 + n_list + n_rec
        if flag > 1:  # event records (their time fields may be blank)
            out.extend(block)
            continue
        sod = int(head[10:12]) * 3600 + int(head[13:15]) * 60 + round(float(head[15:26]))
        if sod % step_s == 0:
            out.extend(block)
    dst.write_text("".join(out))
    return dst


def thin_rinex3(src: Path, dst: Path, step_s: int) -> Path:
    """A RINEX 3 observation file keeping the epochs whose time of day is a multiple of
    ``step_s`` (to the second), records copied unchanged."""
    out: list[str] = []
    keep = True
    in_header = True
    for line in src.read_text().splitlines(keepends=True):
        if in_header:
            out.append(line)
            in_header = "END OF HEADER" not in line
            continue
        if line.startswith(">"):
            flag = int(line[31])
            if flag <= 1:
                sod = int(line[13:15]) * 3600 + int(line[16:18]) * 60 + round(float(line[18:29]))
                keep = sod % step_s == 0
            else:
                keep = True  # event records are kept with their lines
        if keep:
            out.append(line)
    dst.write_text("".join(out))
    return dst


def _rtklib(rover: Path, base: Path, nav: Path, base_xyz: tuple, opts: list[str], out: Path):  # type: ignore[no-untyped-def]
    conf = out.with_suffix(".conf")  # the base age limit has no command-line option
    age = next((o.split("=")[1] for o in opts if o.startswith("maxage=")), "30")
    text = f"pos2-maxage        ={age}\n"
    opts = [o for o in opts if not o.startswith("maxage=")]
    if "-sys" in opts:  # rnx2rtkp 2.4.3 b34's -sys turns on every system whatever its letters
        k = opts.index("-sys")
        mask = sum(RTKLIB_NAVSYS[c] for c in opts[k + 1].split(","))
        text += f"pos1-navsys        ={mask}\n"
        opts = opts[:k] + opts[k + 2 :]
    conf.write_text(text)
    cmd = ["rnx2rtkp", "-k", str(conf), *opts]
    cmd += ["-m", "15", "-e"]
    cmd += ["-r", *(f"{v:.4f}" for v in base_xyz)]
    cmd += [str(rover), str(nav), str(base), "-o", str(out)]
    subprocess.run(cmd, check=True, capture_output=True)
    return read_pos(out)


def _stats(
    t: np.ndarray, fixed: np.ndarray, err: np.ndarray, q_ref: np.ndarray, wrong_m: float
) -> str:
    """Fix rate, wrong fixes (checked against a fixed reference), fixes the reference cannot
    check (it is float there), time to first fix."""
    n = t.size
    ttff = f"{t[fixed][0] - t[0]:.0f} s" if fixed.any() else "never"
    checked = fixed & (q_ref == 1) & np.isfinite(err)
    e = err[checked]
    return (
        f"fixed {int(fixed.sum()):4d}/{n} ({100 * fixed.sum() / max(n, 1):5.1f} %), wrong "
        f"{int((e > wrong_m).sum())} of {int(checked.sum())} checked (max "
        f"{e.max() if e.size else float('nan'):.3f} m), unchecked {int((fixed & ~checked).sum())}"
        f", TTFF {ttff}"
    )


def _ref_errors(t: np.ndarray, pos: np.ndarray, ref) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    """3-D distance to a reference solution at the same tags (NaN elsewhere), and its Q."""
    if isinstance(ref, tuple):
        return np.linalg.norm(pos - np.asarray(ref), axis=1), np.ones(t.size, dtype=int)
    kr = np.round(ref["t_gps_s"].to_numpy() * 1e3).astype(np.int64)
    kn = np.round(t * 1e3).astype(np.int64)
    _, a, b = np.intersect1d(kn, kr, return_indices=True)
    err = np.full(t.size, np.nan)
    q = np.zeros(t.size, dtype=int)
    err[a] = np.linalg.norm(pos[a] - ref[["x_m", "y_m", "z_m"]].to_numpy()[b], axis=1)
    q[a] = ref["q"].to_numpy()[b]
    return err, q


def _case(
    name: str,
    files: tuple[Path, Path, Path, tuple[float, float, float]],
    cfg: RtkConfig,
    rtk_opts: list[str],
    ref: Any,
    wrong_m: float,
    tmp: Path,
) -> tuple[Any, np.ndarray]:
    """One baseline through both programs: ``files`` are rover, base, navigation and the base
    position; ``ref`` a reference point or RTKLIB solution. Returns navtrack's result and the
    distance of each of its epochs from the reference."""
    rover, base, nav, base_xyz = files
    res = solve_relative(
        read_obs(rover), read_obs(base), [read_nav(nav)], np.asarray(base_xyz), cfg
    )
    common = np.isfinite(res.age_s)
    t = res.t_gps_s[common]
    err, q_ref = _ref_errors(res.t_gps_s, res.pos_m, ref)
    fixed = res.status == RtkStatus.FIX
    print(f"{name:<34} navtrack {_stats(t, fixed[common], err[common], q_ref[common], wrong_m)}")
    refused = {k: v for k, v in res.rejection_counts().items() if v}
    print(f"{'':<34}   not fixed, by reason: {refused}")
    if not isinstance(ref, tuple):
        vs_float = fixed & (q_ref == 2)
        for k in np.flatnonzero(vs_float):
            print(
                f"{'':<34}   unchecked fix at {res.t_gps_s[k] % 86400:.0f} s of day: "
                f"{err[k]:.3f} m from the reference's float"
            )
    pos = _rtklib(rover, base, nav, base_xyz, rtk_opts, tmp / f"{name}.pos")
    tr = pos["t_gps_s"].to_numpy()
    err_r, q_r = _ref_errors(tr, pos[["x_m", "y_m", "z_m"]].to_numpy(), ref)
    fixed_r = pos["q"].to_numpy() == 1
    print(f"{'':<34} RTKLIB   {_stats(tr, fixed_r, err_r, q_r, wrong_m)}")
    return res, err


def _by_age(res: Any, err: np.ndarray) -> None:
    """navtrack's fixes grouped by the age of the base observations: count and 3-D error
    median / 95 % / max."""
    fixed = res.status == RtkStatus.FIX
    for lo, hi, label in (
        (0, 0.5, "0 s"),
        (0.5, 10.5, "1-10 s"),
        (10.5, 20.5, "11-20 s"),
        (20.5, 30, "21-29 s"),
    ):
        m = fixed & (res.age_s >= lo) & (res.age_s < hi)
        if m.any():
            e = err[m]
            print(
                f"{'':<34}   base age {label:>7}: {int(m.sum()):4d} fixes, error "
                f"{np.median(e):.3f} / {np.percentile(e, 95):.3f} / {e.max():.3f} m"
            )


def evidence_055954() -> None:
    """The yamatogawa combined fix at 05:59:54 GPST that RTKLIB leaves float: its double-
    differenced integers beside those of the backward fixes at 05:59:50-53 (which agree with
    RTKLIB's fixed solution), the slips flagged on those satellites at :54, and the position
    against the walk extrapolated from RTKLIB's fixes at :52 and :53."""
    from navtrack.gnss import rtk_filter
    from navtrack.gnss.relative import detect_slips, receiver_signals

    calls: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    condition = rtk_filter.condition_on_fix

    def recording(x: Any, P: Any, A: Any, fix: Any) -> Any:
        calls.append((x[:3].copy(), A[:, 3:].copy(), fix.a_fixed.copy()))
        return condition(x, P, A, fix)

    rover, master = (
        read_obs(YAMA / "yamatogawa_rover.obs"),
        read_obs(YAMA / "yamatogawa_master.obs"),
    )
    nav = [read_nav(YAMA / "brdc0060.10n")]
    cfg = RtkConfig(systems="G", direction="backward")
    rtk_filter.condition_on_fix = recording
    try:
        res = solve_relative(rover, master, nav, np.asarray(YAMA_BASE), cfg)
    finally:
        rtk_filter.condition_on_fix = condition
    sod = np.round(res.t_gps_s % 86400).astype(int)
    used: set[str] = set()
    for x, A, a_fixed in calls:
        k = np.flatnonzero(np.all(np.abs(res.float_pos_m - x) < 1e-6, axis=1))
        if k.size == 0 or not 21590 <= sod[k[0]] <= 21594 or res.status[k[0]] != RtkStatus.FIX:
            continue
        pairs = {}
        for row, n in zip(A, a_fixed, strict=True):
            other, ref = res.sats[int(np.argmax(row))], res.sats[int(np.argmin(row))]
            pairs[f"{other}-{ref}"] = int(n)
            used |= {other, ref}
        print(f"backward fix at {sod[k[0]]} s of day: DD integers {pairs}")
    for who, obs in (("rover", rover), ("master", master)):
        sig = receiver_signals(obs, nav, cfg)
        slips = detect_slips(sig, cfg).any[:, :, 0]
        row = int(np.flatnonzero(np.round(sig.t_gps_s % 86400) == 21594)[0])
        hit = [s for j, s in enumerate(sig.sats) if slips[row, j] and s in used]
        print(f"{who}: slips flagged at 21594 s on the fixed satellites: {hit or 'none'}")
    rtklib = read_pos(YAMA / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    xyz = rtklib[["x_m", "y_m", "z_m"]].to_numpy()
    r_sod = np.round(rtklib["t_gps_s"].to_numpy() % 86400).astype(int)
    at = {s: xyz[np.flatnonzero(r_sod == s)[0]] for s in (21592, 21593, 21594)}
    walk = 2 * at[21593] - at[21592]
    comb = solve_relative(
        rover, master, nav, np.asarray(YAMA_BASE), RtkConfig(systems="G", direction="combined")
    )
    fix = comb.pos_m[np.flatnonzero(np.round(comb.t_gps_s % 86400) == 21594)[0]]
    print(
        f"at 21594 s: navtrack's fix {np.linalg.norm(fix - walk):.2f} m and RTKLIB's float "
        f"{np.linalg.norm(at[21594] - walk):.2f} m from the walk extrapolated from RTKLIB's "
        f"fixes at 21592 and 21593 s (steps of 0.5-1.0 m/s); fix to RTKLIB float "
        f"{np.linalg.norm(fix - at[21594]):.2f} m"
    )


def _yamatogawa(base_cfg: RtkConfig, wrong_m: float, tmp: Path) -> None:
    ref = read_pos(YAMA / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    rover, master, nav = (
        YAMA / "yamatogawa_rover.obs",
        YAMA / "yamatogawa_master.obs",
        YAMA / "brdc0060.10n",
    )
    kin = ["-p", "2", "-f", "1", "-t"]
    for step in (1, 5, 30):
        base = master if step == 1 else thin_rinex2(master, tmp / f"master_{step}s.obs", step)
        for direction, opt in (("forward", []), ("combined", ["-c"])):
            cfg = dataclasses.replace(base_cfg, systems="G", direction=direction)
            _case(
                f"yamatogawa {step} s base {direction}",
                (rover, base, nav, YAMA_BASE),
                cfg,
                kin + opt,
                ref,
                wrong_m,
                tmp,
            )


def _geonet(base_cfg: RtkConfig, wrong_m: float, tmp: Path) -> None:
    g_rover, g_nav = GSI / "07590920.05o", GSI / "07590920.05n"
    g_base = REPO / "src/navtrack/data/30400920.05o"
    for mode, p_opt in (("kinematic", "2"), ("static", "3")):
        cfg = dataclasses.replace(base_cfg, systems="G", mode=mode, frequencies=2)
        _case(
            f"gsi0759 L1+L2 {mode}",
            (g_rover, g_base, g_nav, GSI_BASE),
            cfg,
            ["-p", p_opt, "-f", "2"],
            GSI_REF,
            wrong_m,
            tmp,
        )
    thin = thin_rinex2(g_base, tmp / "3040_60s.obs", 60)
    for freq in (1, 2):
        cfg = dataclasses.replace(base_cfg, systems="G", frequencies=freq, max_age_s=60.0)
        _case(
            f"gsi0759 L{'1+L2' if freq == 2 else '1'} kinematic 60 s base",
            (g_rover, thin, g_nav, GSI_BASE),
            cfg,
            ["-p", "2", "-f", str(freq), "maxage=60"],
            GSI_REF,
            wrong_m,
            tmp,
        )


def _mosaic(base_cfg: RtkConfig, wrong_m: float, tmp: Path, data: Path) -> None:
    """The MatRTKLIB static pairs, kinematic processing (every epoch its own position),
    GPS + Galileo + BeiDou + QZSS, L1+L2, against the published rover coordinate."""
    opts = ["-p", "2", "-f", "2", "-sys", "G,E,J,C"]
    cfg = dataclasses.replace(base_cfg, frequencies=2)
    d = data / MOSAIC
    if d.is_dir():
        files = (d / "rover.obs", d / "base.obs", d / "base.nav")
        base_xyz, ref = llh_file(d / "base_position.txt"), llh_file(d / "rover_position.txt")
        for step in (1, 5, 30):
            base = (
                files[1] if step == 1 else thin_rinex3(files[1], tmp / f"mosaic_{step}s.obs", step)
            )
            res, err = _case(
                f"mosaic-X5 pair {step} s base",
                (files[0], base, files[2], base_xyz),
                cfg,
                opts,
                ref,
                wrong_m,
                tmp,
            )
            if step == 30:
                _by_age(res, err)
    d = data / MOSAIC_2018
    if d.is_dir():
        files = (d / "rover_1Hz.obs", d / "base.obs", d / "base.nav")
        base_xyz, ref = llh_file(d / "base_position.txt"), llh_file(d / "rover_mean_position.txt")
        for freq in (1, 2):
            _case(
                f"MatRTKLIB 2018 pair L{'1+L2' if freq == 2 else '1'}",
                (*files, base_xyz),
                dataclasses.replace(cfg, frequencies=freq),
                ["-p", "2", "-f", str(freq), "-sys", "G,E,J,C"],
                ref,
                wrong_m,
                tmp,
            )


def _ublox_files(data: Path) -> tuple[Path, Path, Path] | None:
    d = data / UBLOX
    if not d.is_dir():
        return None
    return (
        d / "rover_2022-02-25_13-26-06_GNSS-1.obs",
        d / "base_2022-02-25_00-00-00_GNSS-1.obs",
        d / "base_2022-02-25_00-00-00_GNSS-1.nav",
    )


def _ublox_reference(files: tuple[Path, Path, Path], tmp: Path) -> tuple[float, float, float]:
    """The rover's static position: RTKLIB's static L1+L2 solution of the whole 4 h session
    (its last epoch), against the same base position."""
    pos = _rtklib(*files, UBLOX_BASE, ["-p", "3", "-f", "2", "-sys", "G,E,C,J"], tmp / "ref.pos")
    x = pos[["x_m", "y_m", "z_m"]].to_numpy()[-1]
    return float(x[0]), float(x[1]), float(x[2])


def _ublox(base_cfg: RtkConfig, wrong_m: float, tmp: Path, data: Path) -> None:
    """The u-blox ZED-F9P pair of geofis/ppk (static rover 1.2 km from the base, 15 s, 4 h),
    kinematic, GPS + Galileo + BeiDou + QZSS, L1 and L1+L2."""
    files = _ublox_files(data)
    if files is None:
        return
    ref = _ublox_reference(files, tmp)
    for freq in (1, 2):
        _case(
            f"u-blox F9P pair L{'1+L2' if freq == 2 else '1'}",
            (*files, UBLOX_BASE),
            dataclasses.replace(base_cfg, frequencies=freq),
            ["-p", "2", "-f", str(freq), "-sys", "G,E,C,J"],
            ref,
            wrong_m,
            tmp,
        )


def _decimated(base_cfg: RtkConfig, wrong_m: float, tmp: Path, data: Path) -> None:
    """A 1 Hz rover against a real geodetic base thinned to CORS rates (decimated here, not a
    CORS file): the MatRTKLIB 2018 rover against its Trimble NetR9 base at 1, 5 and 30 s,
    GPS + Galileo + BeiDou + QZSS L1 (the pair fixes at L1 alone); and the u-blox F9P pair
    (15 s) with its base thinned to 30 s, L1+L2. Both programs read the same thinned file and
    use base observations up to 30 s old (RTKLIB ``maxage``, navtrack ``max_age_s``)."""
    d = data / MOSAIC_2018
    if d.is_dir():
        rover, base, nav = d / "rover_1Hz.obs", d / "base.obs", d / "base.nav"
        base_xyz, ref = llh_file(d / "base_position.txt"), llh_file(d / "rover_mean_position.txt")
        for step in (1, 5, 30):
            thinned = base if step == 1 else thin_rinex3(base, tmp / f"netr9_{step}s.obs", step)
            res, err = _case(
                f"2018 pair L1, NetR9 {step} s" + (" (decim.)" if step > 1 else ""),
                (rover, thinned, nav, base_xyz),
                dataclasses.replace(base_cfg, frequencies=1),
                ["-p", "2", "-f", "1", "-sys", "G,E,J,C"],
                ref,
                wrong_m,
                tmp,
            )
            if step == 30:
                _by_age(res, err)
    files = _ublox_files(data)
    if files is not None:
        thinned = thin_rinex3(files[1], tmp / "f9p_base_30s.obs", 30)
        _by_age(
            *_case(
                "u-blox F9P pair L1+L2, 30 s base (decim.)",
                (files[0], thinned, files[2], UBLOX_BASE),
                dataclasses.replace(base_cfg, frequencies=2),
                ["-p", "2", "-f", "2", "-sys", "G,E,C,J"],
                _ublox_reference(files, tmp),
                wrong_m,
                tmp,
            )
        )


def _pairs(data: Path, tmp: Path) -> list[tuple[str, tuple[Path, Path, Path], Any, Any, int]]:
    """The low-cost pairs with GLONASS L1/L2: name, files, base position, rover reference and
    the frequencies at which the other four systems fix (the 2018 pair: L1 alone)."""
    out = []
    d = data / MOSAIC
    if d.is_dir():
        files = (d / "rover.obs", d / "base.obs", d / "base.nav")
        out.append(
            (
                "mosaic-X5 pair",
                files,
                llh_file(d / "base_position.txt"),
                llh_file(d / "rover_position.txt"),
                2,
            )
        )
    d = data / MOSAIC_2018
    if d.is_dir():
        files = (d / "rover_1Hz.obs", d / "base.obs", d / "base.nav")
        out.append(
            (
                "2018 pair (vs NetR9)",
                files,
                llh_file(d / "base_position.txt"),
                llh_file(d / "rover_mean_position.txt"),
                1,
            )
        )
    files_u = _ublox_files(data)
    if files_u is not None:
        out.append(("u-blox F9P pair", files_u, UBLOX_BASE, _ublox_reference(files_u, tmp), 2))
    return out


def glonass_code_bias(
    rover: Path, base: Path, nav: Path, base_xyz: Any, ref_xyz: Any
) -> list[tuple[float, float, float, int]]:
    """The GLONASS code inter-frequency bias between two receivers, per band: the slope
    (m per channel number) of the single-differenced code residuals at the known positions,
    elevation above the mask, each epoch's median over satellites removed (the receiver
    clocks), then the median of each satellite; its standard error from the scatter of the
    satellites about the line (a satellite's multipath is correlated over the whole session,
    so satellites, not epochs, are the independent samples), the RMS of that scatter (m) and
    the number of satellites."""
    cfg = RtkConfig(systems="R", frequencies=2)
    navd = [read_nav(nav)]
    sig = [receiver_signals(read_obs(p), navd, cfg, second_bands={"R": "2"}) for p in (rover, base)]
    ir, ib, _ = common_epochs(sig[0].t_gps_s, sig[1].t_gps_s, max_age_s=0.5)
    sats = [s for s in sig[0].sats if s in sig[1].sats]
    cols = [[x.sats.index(s) for s in sats] for x in sig]
    res = []
    for x, idx, c, at in zip(sig, (ir, ib), cols, (ref_xyz, base_xyz), strict=True):
        pos = np.broadcast_to(np.asarray(at, dtype=float), (idx.size, 3))
        rho, _, el = satellite_geometry(x.sat_pos_m[idx][:, c], pos)
        low = (el < np.radians(cfg.elmask_deg))[..., None]
        res.append(np.where(low, np.nan, x.code_m[idx][:, c] - rho[..., None]))
    sd = res[0] - res[1]
    freq = C_MPS / sig[0].wavelength_m[cols[0], 0]
    k = np.round((freq - GLONASS_G1_HZ) / GLONASS_CHANNEL_HZ)
    out = []
    for f in range(2):
        y = sd[:, :, f]
        kk = np.where(np.isfinite(y), k[None, :], np.nan)
        y, kk = y - np.nanmedian(y, 1, keepdims=True), kk - np.nanmedian(kk, 1, keepdims=True)
        seen = np.isfinite(y).sum(0) >= 10
        ys, ks = np.nanmedian(y[:, seen], 0), np.nanmedian(kk[:, seen], 0)
        ks = ks - ks.mean()
        beta = float((ys * ks).sum() / (ks**2).sum())
        r = ys - ys.mean() - beta * ks
        se = float(np.sqrt((r**2).sum() / max(r.size - 2, 1) / (ks**2).sum()))
        out.append((beta, se, float(np.sqrt(np.mean(r**2))), int(seen.sum())))
    return out


def _float_errors(res: Any, ref: Any) -> str:
    err = np.linalg.norm(res.pos_m - np.asarray(ref), axis=1)
    fl = err[res.status == RtkStatus.FLOAT]
    if not fl.size:
        return "no float epoch"
    return (
        f"float {fl.size} epochs, 3-D error median {np.median(fl):.3f} m, 95 % "
        f"{np.percentile(fl, 95):.3f} m"
    )


def _glonass(base_cfg: RtkConfig, wrong_m: float, tmp: Path, data: Path) -> None:
    """GLONASS on the low-cost pairs: its code inter-frequency bias between the receivers,
    GLONASS alone in the float solution (the integer search never sees it), and the four
    other systems with and without GLONASS beside RTKLIB (which fixes GLONASS ambiguities by
    default, ``pos2-gloarmode=on``)."""
    for name, files, base_xyz, ref, n_f in _pairs(data, tmp):
        for band, (beta, se, rms, n) in zip(
            ("G1", "G2"), glonass_code_bias(*files, base_xyz, ref), strict=True
        ):
            print(
                f"{name:<34} code IFB {band}: {beta:+.3f} ± {se:.3f} m per channel number, "
                f"scatter of the satellites' medians {rms:.2f} m ({n} satellites)"
            )
        for freq in (1, 2):
            res = solve_relative(
                read_obs(files[0]),
                read_obs(files[1]),
                [read_nav(files[2])],
                np.asarray(base_xyz),
                dataclasses.replace(base_cfg, systems="R", frequencies=freq),
            )
            label = "L1+L2" if freq == 2 else "L1"
            print(f"{name:<34} GLONASS alone {label}: {_float_errors(res, ref)}")
        for systems, opt in (("GECJ", "G,E,C,J"), ("GECJR", "G,E,C,J,R")):
            _case(
                f"{name} {systems} L{'1+L2' if n_f == 2 else '1'}",
                (*files, base_xyz),
                dataclasses.replace(base_cfg, systems=systems, frequencies=n_f),
                ["-p", "2", "-f", str(n_f), "-sys", opt],
                ref,
                wrong_m,
                tmp,
            )


def rtcm_against_convbin(data: Path, tmp: Path) -> None:
    """The NTRIP recording of the CORS station RDSD (MSM7 of GPS, GLONASS, Galileo, BeiDou)
    read by navtrack and by ``convbin -r rtcm3``: epochs, and per system and code the values
    both hold, those only one holds and the largest difference (convbin prints 0.001)."""
    path = data / NTRIP_RECORDING
    if not path.is_file():
        return
    out = tmp / "rdsd.obs"
    cmd = ["convbin", "-r", "rtcm3", "-tr", "2021/08/09", "15:10:00", "-o", str(out), str(path)]
    subprocess.run(cmd, check=True, capture_output=True)
    ref = read_obs(out)
    log = read_rtcm(path, parse_gpst("2021-08-09T15:10:00"))
    obs = log.obs
    same = np.array_equal(np.round(obs.t_gps_s, 3), np.round(ref.t_gps_s, 3))
    print(
        f"RDSD NTRIP recording: navtrack {obs.t_gps_s.size} epochs, convbin "
        f"{ref.t_gps_s.size}, same tags {same}"
    )
    for code in ref.codes:
        for system in "GREC":
            sats = [x for x in ref.sats if x[0] == system and x in obs.sats]
            if not sats or code not in obs.codes:
                continue
            a = obs.values[:, [obs.sats.index(x) for x in sats], obs.codes.index(code)]
            b = ref.values[:, [ref.sats.index(x) for x in sats], ref.codes.index(code)]
            both = np.isfinite(a) & np.isfinite(b)
            if both.any():
                print(
                    f"  {system} {code}: {int(both.sum())} values, only navtrack "
                    f"{int((np.isfinite(a) & ~np.isfinite(b)).sum())}, only convbin "
                    f"{int((~np.isfinite(a) & np.isfinite(b)).sum())}, max difference "
                    f"{np.abs(a - b)[both].max():.4f}"
                )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wrong-m", type=float, default=0.10)
    ap.add_argument("--evidence", action="store_true", help="only the evidence on the 05:59:54 fix")
    ap.add_argument(
        "--set", action="append", default=[], metavar="K=V", help="RtkConfig field (number)"
    )
    ap.add_argument("--data", type=Path, default=EXTRA, help="folder of the MatRTKLIB pairs")
    ap.add_argument(
        "--only",
        choices=("yamatogawa", "gsi0759", "mosaic", "ublox", "decimated", "glonass", "rtcm"),
        help="one group of cases",
    )
    args = ap.parse_args(argv)
    if shutil.which("rnx2rtkp") is None or not YAMA.is_dir():
        print("rnx2rtkp or the shared data missing: nothing to compare", file=sys.stderr)
        return 1
    if args.evidence:
        evidence_055954()
        return 0
    over = {k: type(getattr(RtkConfig(), k))(v) for k, v in (s.split("=") for s in args.set)}
    base_cfg = dataclasses.replace(RtkConfig(), **over)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if args.only in (None, "yamatogawa"):
            _yamatogawa(base_cfg, args.wrong_m, tmp)
        if args.only in (None, "gsi0759"):
            _geonet(base_cfg, args.wrong_m, tmp)
        if args.only in (None, "mosaic"):
            _mosaic(base_cfg, args.wrong_m, tmp, args.data)
        if args.only in (None, "ublox"):
            _ublox(base_cfg, args.wrong_m, tmp, args.data)
        if args.only in (None, "decimated"):
            _decimated(base_cfg, args.wrong_m, tmp, args.data)
        if args.only in (None, "glonass"):
            _glonass(base_cfg, args.wrong_m, tmp, args.data)
        if args.only in (None, "rtcm"):
            rtcm_against_convbin(args.data, tmp)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
