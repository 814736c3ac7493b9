"""Timing of ``navtrack convert`` against RTKLIB 2.4.3 b34's ``convbin``, run live.

Same log, alternating one run of each (the order swaps every repeat), medians of ``--repeat``
runs after one warm-up of each: whole processes ``python -m navtrack convert LOG --out x.obs``
and ``convbin -r ubx -od -os -o x.obs -n x.nav LOG``, wall and CPU (user + system) time, and
the in-process time of :func:`navtrack.gnss.ubx.read_ubx` alone. Also printed: epochs, and the
largest difference between the two observation files at the codes convbin writes (0 when they
agree to the printed precision).

Usage::

    PYTHONPATH=src python benchmarks/bench_convert.py [--log FILE.ubx ...] [--repeat 7]

Default log: the bundled cut ``src/navtrack/data/gnss_imu_walk_cut.ubx``; give the whole
``data/walk_0827/gnss_1730.ubx`` of rtklibexplorer/GNSS_IMU (2 minutes at 4 Hz) for a longer one.
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
DEFAULT_LOG = REPO / "src" / "navtrack" / "data" / "gnss_imu_walk_cut.ubx"


def _run(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU (children's user + system) seconds of one whole process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _max_difference(ours: Path, theirs: Path) -> float:
    from navtrack.gnss.rinex.obs import read_obs

    a, b = read_obs(ours), read_obs(theirs)
    if not np.array_equal(a.t_gps_s, b.t_gps_s):
        return float("inf")
    cols = [a.sat_index(s) for s in b.sats]
    worst = 0.0
    for code in b.codes:
        x, y = a.code(code)[:, cols], b.code(code)
        has = np.array([code in b.header.obs_types[s[0]] for s in b.sats])
        x, y = x[:, has], y[:, has]
        if not np.array_equal(np.isnan(x), np.isnan(y)):
            return float("inf")
        ok = ~np.isnan(y)
        if ok.any():
            worst = max(worst, float(np.abs(x[ok] - y[ok]).max()))
    return worst


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--log", type=Path, nargs="+", default=[DEFAULT_LOG])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    convbin = shutil.which("convbin")
    env = dict(os.environ, PYTHONPATH=str(REPO / "src"))
    print(f"load average {os.getloadavg()[0]:.2f}")
    if convbin is None:
        print("convbin not installed (apt-get install rtklib): no ratio")
    from navtrack.gnss.ubx import read_ubx

    for log in args.log:
        with tempfile.TemporaryDirectory() as tmp:
            ours, theirs = Path(tmp, "n.obs"), Path(tmp, "c.obs")
            nt = [sys.executable, "-m", "navtrack", "convert", str(log), "--out", str(ours)]
            cb = [convbin or "convbin", "-r", "ubx", "-od", "-os", "-o", str(theirs)]
            cb += ["-n", str(Path(tmp, "c.nav")), str(log)]
            cases = {"navtrack": nt} | ({"convbin": cb} if convbin else {})
            times: dict[str, list[tuple[float, float]]] = {k: [] for k in cases}
            for cmd in cases.values():  # warm-up
                _run(cmd, env)
            for r in range(args.repeat):
                for name in list(cases) if r % 2 == 0 else list(cases)[::-1]:
                    times[name].append(_run(cases[name], env))
            inproc = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                log_data = read_ubx(log)
                inproc.append(time.perf_counter() - t0)
            n = len(log_data.obs.t_gps_s)
            print(f"\n{log.name}: {log.stat().st_size / 1e6:.2f} MB, {n} epochs")
            med = {
                k: [statistics.median(x[i] for x in v) for i in (0, 1)] for k, v in times.items()
            }
            for name, (wall, cpu) in med.items():
                print(f"  {name:<9} wall {wall:7.3f} s  cpu {cpu:7.3f} s")
            print(f"  read_ubx in-process {statistics.median(inproc):7.3f} s")
            if convbin:
                (w1, c1), (w2, c2) = med["navtrack"], med["convbin"]
                print(f"  ratio navtrack / convbin: wall {w1 / w2:.1f}, cpu {c1 / c2:.1f}")
                print(f"  largest value difference {_max_difference(ours, theirs):.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
