"""Timing and accuracy of ``navtrack ppp`` against RTKLIB 2.4.3 b34's static PPP, run live.

Same run, same inputs, RTKLIB with the options of ``tests/gnss/test_ppp.py``
(``pos1-posmode=ppp-static``, L1+L2, mask 15 deg, GPS, precise ephemeris, dual-frequency
ionosphere-free, estimated ZTD) plus phase wind-up (``pos1-posopt3``, as navtrack), and with
``--antex ATX`` both programs given the same antenna file (RTKLIB ``pos1-posopt1/2``,
``ant1-anttype=*``), alternating one whole process of each (the order swaps every
repeat), medians of ``--repeat`` runs after one warm-up of each:

* wall and CPU (user + system) time of ``python -m navtrack ppp OBS NAV --sp3 SP3 [--clk CLK]
  --out x.csv`` and of ``rnx2rtkp -k ppp.conf OBS NAV SP3 [CLK] -o x.pos``, and their ratio;
* per program, against the station's reference: the 3-D error at the last epoch, the median
  3-D error from 5 minutes on, and the share of the epochs from 5 and from 30 minutes on whose
  error lies inside the program's own formal 95 % ellipsoid (its full covariance);
* the two solutions' difference: median and last-epoch 3-D distance.

Cases: the shared SEPT (15 min, 1 s, CODE MGEX SP3) and ARL1 (1 h, 30 s, NGA SP3) stations;
``--data DIR`` adds the files of ``DIR`` that are present: the eight 3-hour sessions of NIST on
2023-01-01 (``NIST_HHh_3h.rnx``), each with WUM's 30 s clock file and with its 5-minute SP3
clocks, and 30 minutes of TLSE the same day (jtec/prx test data, not in the shared data; the
folder's README says how to fetch and cut them); ``--case NAME OBS NAV SP3 CLK X Y Z`` adds one
more (``-`` for no clock file). A markdown table of all cases ends the output.

Usage::

    PYTHONPATH=src python benchmarks/bench_ppp.py [--repeat 5] [--antex ATX] [--data DIR]
        [--case ...]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from navtrack.geodesy import ecef_to_enu, ecef_to_geodetic, enu_rotation
from navtrack.gnss.antex import read_antex
from navtrack.gnss.ppp import solve_ppp
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rinex_clock import read_clock
from navtrack.gnss.sp3 import read_sp3
from navtrack.io.rtklib import read_pos
from navtrack.io.solution import read_solution

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
CHI2_3DOF_95 = 7.814727903251178  # 95 % quantile of the chi-square with 3 degrees of freedom
RTKLIB_PPP_CONF = """\
pos1-posmode       =ppp-static
pos1-frequency     =l1+l2
pos1-elmask        =15
pos1-navsys        =1
pos1-sateph        =precise
pos1-ionoopt       =dual-freq
pos1-tropopt       =est-ztd
pos1-posopt3       =on
out-solformat      =xyz
"""
Case = tuple[Path, Path, Path, Path | None, tuple[float, float, float]]
"""Observations, navigation, SP3, clock file (or None) and reference position (ECEF, m)."""
CASES: dict[str, Case] = {
    "SEPT": (
        SHARED / "cssrlib_sept" / "SEPT078M.21O",
        SHARED / "cssrlib_sept" / "SEPT078M.21P",
        SHARED / "cssrlib_sept" / "COD0MGXFIN_20210780000_01D_05M_ORB.SP3",
        None,
        (-3962108.673, 3381309.574, 3668678.638),
    ),
    "ARL1": (
        SHARED / "gpstk_arl1" / "arlm200a.15o",
        SHARED / "gpstk_arl1" / "arlm2000.15n",
        SHARED / "gpstk_arl1" / "test_input_sp3_nav_2015_200.sp3",
        None,
        (-740289.9049, -5457071.7352, 3207245.5544),  # GPSTk's ARL.2012.0000 (docs/ppp.md)
    ),
}
NIST_REF = (-1288398.574, -4721696.936, 4078625.349)  # docs/ppp.md, references
TLSE_REF = (4627851.574, 119640.425, 4372993.792)


def data_cases(d: Path) -> dict[str, Case]:
    """The NIST sessions (30 s clock file and SP3 clocks) and TLSE of 2023-01-01 in ``d``."""
    nav = d / "BRDC00IGS_R_20230010000_01D_MN.rnx"
    sp3 = d / "WUM0MGXFIN_20230010000_01D_05M_ORB.SP3"
    clk = d / "WUM0MGXFIN_20230010000_01D_30S_CLK.CLK"
    cases: dict[str, Case] = {}
    for obs in sorted(d.glob("NIST_??h_3h.rnx")):
        cases[f"NIST {obs.name[5:8]}"] = (obs, nav, sp3, clk, NIST_REF)
        cases[f"NIST {obs.name[5:8]} SP3 clocks"] = (obs, nav, sp3, None, NIST_REF)
    if (d / "TLSE_30M.crx.gz").is_file():
        cases["TLSE"] = (d / "TLSE_30M.crx.gz", nav, sp3, clk, TLSE_REF)
    return cases


def _run(cmd: list[str]) -> tuple[float, float]:
    """Wall and CPU (user + system of the child) seconds of one process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env={**os.environ, "PYTHONPATH": "src"})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _commands(case: Case, tmp: Path, atx: Path | None) -> tuple[list[str], list[str]]:
    obs, nav, sp3, clk, _ = case
    navtrack = [sys.executable, "-m", "navtrack", "ppp", str(obs), str(nav), "--sp3", str(sp3)]
    navtrack += (["--clk", str(clk)] if clk else []) + (["--antex", str(atx)] if atx else [])
    navtrack += ["--out", str(tmp / "navtrack.csv")]
    conf = tmp / "ppp.conf"
    antenna = (
        f"pos1-posopt1       =on\npos1-posopt2       =on\nfile-satantfile    ={atx}\n"
        f"file-rcvantfile    ={atx}\nant1-anttype       =*\n"
    )
    conf.write_text(RTKLIB_PPP_CONF + (antenna if atx else ""))
    rtklib = ["rnx2rtkp", "-k", str(conf), str(obs), str(nav), str(sp3)]
    rtklib += ([str(clk)] if clk else []) + ["-o", str(tmp / "rtklib.pos")]
    return navtrack, rtklib


def _covariance_enu(pos: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """ENU covariances of RTKLIB's ECEF ``sdx sdy sdz sdxy sdyz sdzx`` (signed square roots)."""
    v = np.sign(sd) * sd**2
    cov = np.stack(
        [v[:, [0, 3, 5]], v[:, [3, 1, 4]], v[:, [5, 4, 2]]], axis=1
    )  # xx xy zx / xy yy yz / zx yz zz
    llh = ecef_to_geodetic(np.nanmedian(pos, axis=0))
    rot = enu_rotation(llh[0], llh[1])
    return np.einsum("ij,ejk,lk->eil", rot, cov, rot)


Scores = tuple[float, float, float, float]
"""Last 3-D error (m), median 3-D error from 5 minutes on (m), and the shares (%) of the epochs
from 5 and from 30 minutes on inside the program's own 95 % ellipsoid (NaN: too short)."""


def _scores(t: np.ndarray, pos: np.ndarray, cov: np.ndarray, ref: np.ndarray) -> Scores:
    enu = ecef_to_enu(pos, ref)
    after = t - t[0] >= 300.0
    inside = np.einsum("ei,eij,ej->e", enu, np.linalg.inv(cov), enu) <= CHI2_3DOF_95
    late = t - t[0] >= 1800.0
    e3 = np.linalg.norm(enu, axis=1)
    in_30 = 100.0 * float(np.mean(inside[late])) if late.any() else float("nan")
    return float(e3[-1]), float(np.median(e3[after])), 100.0 * float(np.mean(inside[after])), in_30


def _line(s: Scores) -> str:
    late = "" if np.isnan(s[3]) else f", from 30 min {s[3]:.0f} %"
    return f"last {s[0]:.3f} m, median from 5 min {s[1]:.3f} m, inside own 95 % {s[2]:.0f} %{late}"


def _compare(case: Case, tmp: Path, atx: Path | None) -> tuple[Scores, Scores]:
    obs_p, nav_p, sp3_p, clk_p, ref_t = case
    ref = np.asarray(ref_t, dtype=float)
    sp3 = read_sp3(sp3_p)
    res = solve_ppp(
        read_obs(obs_p),
        [read_nav(nav_p)],
        sp3.with_clock(read_clock(clk_p)) if clk_p else sp3,
        antex=read_antex(atx) if atx else None,
    )
    ok = res.updated
    ours = _scores(res.t_gps_s[ok], res.pos_m[ok], res.cov_enu_m2[ok], ref)
    print(f"  navtrack  {_line(ours)}")
    rp = read_pos(tmp / "rtklib.pos")
    r_pos = rp[["x_m", "y_m", "z_m"]].to_numpy(float)
    r_sd = rp[["sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m"]].to_numpy(float)
    r_t = rp["t_gps_s"].to_numpy(float)
    theirs = _scores(r_t, r_pos, _covariance_enu(r_pos, r_sd), ref)
    print(f"  RTKLIB    {_line(theirs)}")
    written = read_solution(tmp / "navtrack.csv")
    np.testing.assert_allclose(written["x_m"].to_numpy()[ok], res.pos_m[ok, 0], atol=1e-4)
    _, a, b = np.intersect1d(np.round(res.t_gps_s * 1e3), np.round(r_t * 1e3), return_indices=True)
    d = np.linalg.norm(res.pos_m[a] - r_pos[b], axis=1)
    print(f"  difference navtrack - RTKLIB: median {np.nanmedian(d):.3f} m, last {d[-1]:.3f} m")
    return ours, theirs


def _table(rows: list[tuple[str, Scores, Scores, float]]) -> None:
    """The markdown table of all cases (as in docs/ppp.md)."""
    print(
        "\n| case | navtrack error from 5 min, median (last) | navtrack inside 5 / 30 min "
        "| RTKLIB error from 5 min, median (last) | RTKLIB inside 5 / 30 min | CPU ratio |"
    )
    print("|---|---|---|---|---|---|")
    for name, ours, theirs, ratio in rows:
        cells = [
            f"{s[1]:.3f} ({s[0]:.3f}) m | {s[2]:.0f} % / "
            + ("–" if np.isnan(s[3]) else f"{s[3]:.0f} %")
            for s in (ours, theirs)
        ]
        print(f"| {name} | {cells[0]} | {cells[1]} | {ratio:.2f} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--case", nargs=8, action="append", default=[], metavar="ARG")
    ap.add_argument("--antex", type=Path, help="ANTEX file given to both programs")
    ap.add_argument("--data", type=Path, help="folder with the NIST/TLSE files of 2023-01-01")
    args = ap.parse_args(argv)
    cases = dict(CASES) | (data_cases(args.data) if args.data else {})
    for name, obs, nav, sp3, clk, x, y, z in args.case:
        cases[name] = (
            Path(obs),
            Path(nav),
            Path(sp3),
            None if clk == "-" else Path(clk),
            (float(x), float(y), float(z)),
        )
    if shutil.which("rnx2rtkp") is None:
        print("rnx2rtkp missing: nothing to compare", file=sys.stderr)
        return 1
    rows = []
    for name, case in cases.items():
        if not Path(case[0]).is_file():
            print(f"{name}: {case[0]} missing, skipped", file=sys.stderr)
            continue
        with tempfile.TemporaryDirectory() as d:
            tmp = Path(d)
            clk = f", clocks {Path(case[3]).name}" if case[3] else ""
            print(f"{name}{clk}: median of {args.repeat} alternating whole-process runs")
            ratio = _time_case(case, tmp, args.antex, args.repeat)
            rows.append((name, *_compare(case, tmp, args.antex), ratio))
    _table(rows)
    return 0


def _time_case(case: Case, tmp: Path, atx: Path | None, repeat: int) -> float:
    """Print the median wall and CPU times of both programs; return the CPU ratio."""
    nav_cmd, rtk_cmd = _commands(case, tmp, atx)
    _run(nav_cmd), _run(rtk_cmd)  # warm-up
    times: dict[str, list[tuple[float, float]]] = {"navtrack": [], "rtklib": []}
    for k in range(repeat):
        order = [("navtrack", nav_cmd), ("rtklib", rtk_cmd)][:: 1 if k % 2 == 0 else -1]
        for who, cmd in order:
            times[who].append(_run(cmd))
    med = {w: [statistics.median(v[i] for v in t) for i in (0, 1)] for w, t in times.items()}
    print(
        f"  wall navtrack {med['navtrack'][0]:.3f} s, RTKLIB {med['rtklib'][0]:.3f} s, "
        f"ratio {med['navtrack'][0] / med['rtklib'][0]:.2f}; CPU {med['navtrack'][1]:.3f} "
        f"s vs {med['rtklib'][1]:.3f} s, ratio {med['navtrack'][1] / med['rtklib'][1]:.2f}"
    )
    return float(med["navtrack"][1] / med["rtklib"][1])


if __name__ == "__main__":
    raise SystemExit(main())
