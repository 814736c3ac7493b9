"""Whole-process timing of ``navtrack pos`` on the shared data vs RTKLIB 2.4.3's ``rnx2rtkp``.

Each run starts a fresh Python process (start-up, imports, read, solve, write a CSV), like the
stored RTKLIB wall times (mean of 20 hyperfine runs on this machine, from
``shared/data/gnss/rtklib_spp/README.md``; RTKLIB is not installed here, so the ratio is against
those stored numbers). Prints the median of ``--repeat`` runs, the ratio navtrack / RTKLIB, and
an in-process breakdown (imports, read obs, read nav, solve, write) from one extra run.

Usage::

    PYTHONPATH=src python benchmarks/bench_pos.py [--repeat 5] [--only sept078_gej] [--accuracy]

``--accuracy`` also prints, per run, the epochs solved and 3D RMS against the reference next to
RTKLIB's, and the median / max per-epoch distance to RTKLIB's own solution (in-process).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
REFERENCE = json.loads((REPO / "tests" / "data" / "rtklib_spp_reference.json").read_text())

PHASES = r"""
import sys, time
t0 = time.perf_counter()
import numpy
t1 = time.perf_counter()
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.spp import SppConfig, solution_columns, solve_spp
from navtrack.io.solution import write_solution
t2 = time.perf_counter()
obs = read_obs(sys.argv[1]); t3 = time.perf_counter()
navs = [read_nav(p) for p in sys.argv[3:]]; t4 = time.perf_counter()
res = solve_spp(obs, navs, config=SppConfig(systems=sys.argv[2])); t5 = time.perf_counter()
write_solution(solution_columns(res), sys.argv[0] + ".csv"); t6 = time.perf_counter()
print(f"numpy {t1-t0:.3f}  imports {t2-t1:.3f}  read obs {t3-t2:.3f}  read nav {t4-t3:.3f}  "
      f"solve {t5-t4:.3f}  write {t6-t5:.3f}")
"""


def _command(run: dict, out: Path) -> list[str]:
    cmd = [sys.executable, "-m", "navtrack", "pos", str(SHARED / run["obs"])]
    cmd += [str(SHARED / p) for p in run["nav"]]
    if run.get("sp3"):
        cmd += ["--sp3", str(SHARED / run["sp3"])]
    cmd += ["--systems", run["systems"], "--out", str(out), "--no-progress"]
    return cmd


def accuracy(names: list[str]) -> None:
    import numpy as np

    from navtrack.geodesy import ecef_to_enu
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.sp3 import read_sp3
    from navtrack.gnss.spp import SppConfig, solve_spp
    from navtrack.io.rtklib import read_pos

    print(
        f"{'run':<24} {'solved':>7} {'RTKLIB':>6} {'RMS3D':>6} {'RTKLIB':>6} "
        f"{'med d':>6} {'max d':>6}  (m; d = distance to RTKLIB's solution)"
    )
    for name in names:
        run = REFERENCE["runs"][name]
        obs = read_obs(SHARED / run["obs"])
        navs = [read_nav(SHARED / p) for p in run["nav"]]
        sp3 = read_sp3(SHARED / run["sp3"]) if run.get("sp3") else None
        variants = [("", SppConfig(systems=run["systems"]))]
        if sp3 is not None:
            variants.append(
                (" (RTKLIB rule)", SppConfig(systems=run["systems"], sp3_needs_broadcast=True))
            )
        rtk = read_pos(SHARED / "rtklib_spp" / f"{name}.pos")
        t_rtk = rtk["t_gps_s"].to_numpy()
        xyz_rtk = rtk[["x_m", "y_m", "z_m"]].to_numpy()
        for label, cfg in variants:
            res = solve_spp(obs, navs, sp3=sp3, config=cfg)
            ok = res.status == 0
            if "ref_xyz_m" in run:
                ref = np.asarray(run["ref_xyz_m"])
            else:
                traj = read_pos(SHARED / run["ref_pos"])
                k = np.searchsorted(traj["t_gps_s"].to_numpy(), res.t_gps_s[ok] - 0.1)
                ref = traj[["x_m", "y_m", "z_m"]].to_numpy()[k]
            rms = float(np.sqrt(np.mean(np.sum(ecef_to_enu(res.pos_m[ok], ref) ** 2, axis=1))))
            i = np.clip(np.searchsorted(res.t_gps_s, t_rtk - 0.1), 0, res.t_gps_s.size - 1)
            d = np.linalg.norm(res.pos_m[i] - xyz_rtk, axis=1)
            print(
                f"{name + label:<24} {int(ok.sum()):>7} {run['solved']:>6} {rms:6.2f} "
                f"{run['rms_3d_m']:6.2f} {np.nanmedian(d):6.3f} {np.nanmax(d):6.3f}"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--only", nargs="*", help="run names (default: all with an RTKLIB time)")
    ap.add_argument("--accuracy", action="store_true", help="also print the accuracy table")
    args = ap.parse_args()
    if args.accuracy:
        accuracy(args.only or list(REFERENCE["runs"]))
        print()
    env = dict(os.environ, PYTHONPATH=str(REPO / "src"))
    names = args.only or [n for n, r in REFERENCE["runs"].items() if r.get("wall_s")]
    print(f"{'run':<24} {'navtrack s':>10} {'RTKLIB s':>9} {'ratio':>6}   breakdown (s)")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "sol.csv"
        for name in names:
            run = REFERENCE["runs"][name]
            cmd = _command(run, out)
            subprocess.run(cmd, env=env, check=True, capture_output=True)  # warm the disk cache
            times = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                subprocess.run(cmd, env=env, check=True, capture_output=True)
                times.append(time.perf_counter() - t0)
            med = statistics.median(times)
            rtk = run.get("wall_s")
            ratio = f"{med / rtk:6.2f}" if rtk else "     -"
            script = Path(tmp) / "phases.py"
            script.write_text(PHASES)
            phases = ""
            if not run.get("sp3"):
                phases = subprocess.run(
                    [
                        sys.executable,
                        str(script),
                        str(SHARED / run["obs"]),
                        run["systems"],
                        *[str(SHARED / p) for p in run["nav"]],
                    ],
                    env=env,
                    check=True,
                    capture_output=True,
                    text=True,
                ).stdout.strip()
            rtk_s = f"{rtk:9.3f}" if rtk else "        -"
            print(f"{name:<24} {med:10.3f} {rtk_s} {ratio}   {phases}")


if __name__ == "__main__":
    main()
