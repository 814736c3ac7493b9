"""Timing of ``navtrack rtk`` against RTKLIB 2.4.3 b34's ``rnx2rtkp -p 2``, run live, and of
LAMBDA on a 20-ambiguity problem.

Same run, same inputs (the yamatogawa walking u-blox rover against its master, L1, GPS,
elevation mask 15 deg, base at the master's header position), alternating one run of each (the
order swaps every repeat), medians of ``--repeat`` runs after one warm-up of each:

* whole processes: ``python -m navtrack rtk ... --out x.csv`` and ``rnx2rtkp ... -o x.pos``,
  forward and combined (``--direction combined`` / ``-c``), wall and CPU (user + system) time;
* in-process navtrack CPU time (reading the three files and solving, no interpreter start-up
  or imports) beside RTKLIB's whole-process CPU time;
* the agreement of each navtrack run with the RTKLIB run of the same direction: fixed epochs of
  both, median distance where both are fixed, float median distance;
* LAMBDA (:func:`navtrack.gnss.ambiguity.resolve_ambiguities`) on a seeded 20-ambiguity
  problem, median of 200 calls.

Usage::

    PYTHONPATH=src python benchmarks/bench_rtk.py [--repeat 7]
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

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
YAMA = SHARED / "gogps_yamatogawa"
ROVER, BASE, NAV = (
    YAMA / "yamatogawa_rover.obs",
    YAMA / "yamatogawa_master.obs",
    YAMA / "brdc0060.10n",
)
BASE_XYZ = ("-3749943.5172", "3683398.2394", "3600629.5295")


def _run(cmd: list[str]) -> tuple[float, float]:
    """Wall and CPU (user + system of the child) seconds of one process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env={**os.environ, "PYTHONPATH": "src"})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _commands(tmp: Path, combined: bool) -> tuple[list[str], list[str]]:
    nav = [
        sys.executable,
        "-m",
        "navtrack",
        "rtk",
        str(ROVER),
        str(BASE),
        str(NAV),
        "--base-pos",
        *BASE_XYZ,
        "--out",
        str(tmp / "navtrack.csv"),
    ]
    rtk = ["rnx2rtkp", "-p", "2", "-f", "1", "-m", "15", "-e", "-t", "-r", *BASE_XYZ]
    if combined:
        nav += ["--direction", "combined"]
        rtk.append("-c")
    rtk += [str(ROVER), str(NAV), str(BASE), "-o", str(tmp / "rtklib.pos")]
    return nav, rtk


def _in_process(direction: str):  # type: ignore[no-untyped-def]
    from navtrack.gnss.relative import RtkConfig, solve_relative
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs

    t0 = time.process_time()
    res = solve_relative(
        read_obs(ROVER),
        read_obs(BASE),
        [read_nav(NAV)],
        np.array([float(v) for v in BASE_XYZ]),
        RtkConfig(direction=direction),
    )
    return time.process_time() - t0, res


def _agreement(res, pos_file: Path) -> str:  # type: ignore[no-untyped-def]
    from navtrack.io.rtklib import read_pos

    ref = read_pos(pos_file)
    kr = np.round(ref["t_gps_s"].to_numpy() * 1e3).astype(np.int64)
    kn = np.round(res.t_gps_s * 1e3).astype(np.int64)
    _, a, b = np.intersect1d(kn, kr, return_indices=True)
    q = ref["q"].to_numpy()[b]
    st = res.status[a]
    d = np.linalg.norm(res.pos_m[a] - ref[["x_m", "y_m", "z_m"]].to_numpy()[b], axis=1)
    both = (q == 1) & (st == 0)
    flt = (q == 2) & (st == 1)
    med = f"{np.median(d[both]) * 100:.1f} cm" if both.any() else "-"
    return (
        f"fixed navtrack {int((st == 0).sum())}, RTKLIB {int((q == 1).sum())}, both "
        f"{int(both.sum())} (median {med}, >10 cm {int((d[both] > 0.1).sum())}); float median "
        f"{np.median(d[flt]) * 100:.1f} cm over {int(flt.sum())}"
    )


def _lambda_time() -> float:
    from navtrack.gnss.ambiguity import resolve_ambiguities

    rng = np.random.default_rng(5)
    n = 20
    A = rng.normal(size=(n, n)) + 3.0 * rng.normal(size=(n, 1))
    Q = 1e-2 * (A @ A.T / n + 1e-3 * np.eye(n))
    a = rng.integers(-50, 50, size=n) + np.linalg.cholesky(Q) @ rng.normal(size=n)
    resolve_ambiguities(a, Q)
    times = []
    for _ in range(200):
        t0 = time.perf_counter()
        resolve_ambiguities(a, Q)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    if shutil.which("rnx2rtkp") is None or not ROVER.is_file():
        print("rnx2rtkp or the yamatogawa data missing: nothing to compare", file=sys.stderr)
        return 1
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for combined in (False, True):
            label = "combined" if combined else "forward"
            nav_cmd, rtk_cmd = _commands(tmp, combined)
            _run(nav_cmd), _run(rtk_cmd)  # warm-up (numba cache, page cache)
            times: dict[str, list[tuple[float, float]]] = {"navtrack": [], "rtklib": []}
            inproc: list[float] = []
            for i in range(args.repeat):
                order = [("navtrack", nav_cmd), ("rtklib", rtk_cmd)]
                for name, cmd in order if i % 2 == 0 else order[::-1]:
                    times[name].append(_run(cmd))
                t, res = _in_process(label)
                inproc.append(t)
            nw = statistics.median(w for w, _ in times["navtrack"])
            nc = statistics.median(c for _, c in times["navtrack"])
            rw = statistics.median(w for w, _ in times["rtklib"])
            rc = statistics.median(c for _, c in times["rtklib"])
            ip = statistics.median(inproc)
            print(f"{label}: process wall navtrack {nw:.3f} s, RTKLIB {rw:.3f} s, {nw / rw:.2f}x")
            print(f"{label}: process CPU  navtrack {nc:.3f} s, RTKLIB {rc:.3f} s, {nc / rc:.2f}x")
            print(
                f"{label}: in-process CPU navtrack {ip:.3f} s (read, solve), {ip / rc:.2f}x RTKLIB"
            )
            print(f"{label}: {_agreement(res, tmp / 'rtklib.pos')}")
    print(f"LAMBDA 20 ambiguities: median {_lambda_time() * 1e3:.3f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
