"""Whole-process timing of ``navtrack pos`` against RTKLIB 2.4.3 b34's ``rnx2rtkp``, run live.

Both programs run in the same benchmark run, on the same inputs, as whole processes (start-up,
reading, solving, writing a solution file: navtrack a CSV, RTKLIB its ``.pos``), alternating one
run of each (the order swaps every repeat) with ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and
``MKL_NUM_THREADS`` set to ``--threads`` (default 1) for both processes. RTKLIB uses the option
files of the stored references (``shared/data/gnss/rtklib_spp/conf``), and each of its outputs is
checked against the stored reference ``.pos`` (same records, line endings and the header lines
naming program and input paths aside), so the timed peer is the one the accuracy comparisons use.

Printed, all from timings of this run (median of ``--repeat`` runs after one warm-up of each):

* per case: navtrack s, RTKLIB s, ratio navtrack / RTKLIB, for the wall time and, beside it, the
  CPU time (user + system) of the processes, which a busy machine disturbs less;
* fixed cost + per-epoch cost of both, the intercept and slope of a least-squares line through
  the medians at cuts of the 900-epoch SEPT file (``--cuts``), and navtrack's fixed cost less
  the time of ``python -c "import numpy"`` run in turn with both programs at every cut (the
  issue's bar is numpy's import + 40 ms);
* the import floor: ``python -c "import numpy"`` and ``python -c "import navtrack.gnss.spp"``.

Needs ``rnx2rtkp`` on the PATH (``apt-get install rtklib``) and the shared data
(``NAVTRACK_SHARED_DATA`` or ``../shared/data``); cases whose inputs are missing are skipped.

``--day OBS NAV`` adds a 24 h RINEX 3 station and its navigation file (any daily pair from a
public archive, e.g. an IGS/MGEX ``*_01D_30S_MO.rnx`` with ``BRDC00IGS_R_*_01D_MN.rnx``): cases
``day_gps``, ``day_gej`` (GPS + Galileo + QZSS, RTKLIB's ``spp_gej`` options) and ``day_1h_gps``
(its first 120 epochs). No stored RTKLIB reference exists for it; RTKLIB's output is not checked.

Usage::

    PYTHONPATH=src python benchmarks/bench_pos.py [--repeat 7] [--only sept078_gej ...]
        [--cuts 50 100 200 450 900] [--threads 1] [--accuracy] [--day OBS NAV]
        [--instructions] [--compare TREE]

``--compare TREE`` runs the ``navtrack pos`` of another source tree (e.g. ``git worktree add
/tmp/before COMMIT``) in the same rounds as this one's at the cuts, and prints its line too:
the fixed cost before and after a change, measured under the same load.

``--accuracy`` also prints, per run, the epochs solved and 3D RMS against the reference next to
RTKLIB's, and the median / max per-epoch distance to RTKLIB's own solution (in-process).

``--instructions`` (needs ``valgrind``) counts the instructions each process executes
(callgrind's ``Ir``): ``python -c "import numpy"``, ``navtrack pos`` on the first epoch of the
SEPT file (GPS) and ``navtrack --help``. Counts do not depend on what else the machine runs, so
they measure the fixed cost where timings cannot (a machine shared by many jobs): the fixed
cost is printed as a fraction of numpy's import and, scaled by numpy's median wall time of this
run, in ms.
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
REFERENCE = json.loads((REPO / "tests" / "data" / "rtklib_spp_reference.json").read_text())
CONF = SHARED / "rtklib_spp" / "conf"
BUNDLED = REPO / "src" / "navtrack" / "data"
SEPT_OBS = SHARED / "cssrlib_sept" / "SEPT078M.21O"
SEPT_NAV = SHARED / "cssrlib_sept" / "SEPT078M.21P"
THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
HEADER_NAMING_RUN = ("% program", "% inp file")


@dataclass(frozen=True)
class Case:
    """One input set solved by both programs.

    Attributes
    ----------
    name : str
        Name of the stored RTKLIB reference, ``rtklib_spp/<name>.pos``.
    obs, nav : Path
        RINEX observation and navigation files.
    systems : str
        navtrack ``--systems`` (the RTKLIB option file selects the same systems).
    conf : str
        RTKLIB option file ``rtklib_spp/conf/<conf>.conf``.
    """

    name: str
    obs: Path
    nav: Path
    systems: str
    conf: str

    def navtrack(self, out: Path, obs: Path | None = None) -> list[str]:
        """Command line of ``navtrack pos`` writing ``out`` (on ``obs`` instead of the case's)."""
        return [
            sys.executable,
            "-m",
            "navtrack",
            "pos",
            str(obs or self.obs),
            str(self.nav),
            "--systems",
            self.systems,
            "--out",
            str(out),
            "--no-progress",
        ]

    def rtklib(self, out: Path, obs: Path | None = None) -> list[str]:
        """Command line of ``rnx2rtkp`` writing ``out`` (on ``obs`` instead of the case's)."""
        conf = CONF / f"{self.conf}.conf"
        return ["rnx2rtkp", "-k", str(conf), str(obs or self.obs), str(self.nav), "-o", str(out)]

    def available(self) -> bool:
        """True when the inputs and the RTKLIB option file exist."""
        return self.obs.is_file() and self.nav.is_file() and (CONF / f"{self.conf}.conf").is_file()

    def epochs(self) -> int:
        """Epoch records of the observation file (from the stored reference when there is one)."""
        if self.name in REFERENCE["runs"]:
            return int(REFERENCE["runs"][self.name]["epochs"])
        with self.obs.open() as f:
            return sum(line.startswith(">") for line in f)


CASES = (
    Case("sept078_gej", SEPT_OBS, SEPT_NAV, "GEJ", "spp_gej"),
    Case("sept078_gps", SEPT_OBS, SEPT_NAV, "G", "spp_gps"),
    Case("gsi0759_gps", BUNDLED / "07590920.05o", BUNDLED / "07590920.05n", "G", "spp_gps"),
    Case(
        "arl1_gps",
        SHARED / "gpstk_arl1" / "arlm200a.15o",
        SHARED / "gpstk_arl1" / "arlm2000.15n",
        "G",
        "spp_gps",
    ),
)


@dataclass(frozen=True)
class Timing:
    """Medians of the runs of one command.

    Attributes
    ----------
    wall_s : float
        Wall time of the whole process, s.
    cpu_s : float
        User + system CPU time of the process, s (less sensitive than the wall time to other
        processes competing for the cores).
    """

    wall_s: float
    cpu_s: float


def _time_once(cmd: Sequence[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU (user + system) time of one whole process, s (raises if it fails)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu


def time_pair(
    a: Sequence[str], b: Sequence[str], env: dict[str, str], repeat: int
) -> tuple[Timing, Timing]:
    """Median times of two commands run alternately (:func:`time_alternating`)."""
    ta, tb = time_alternating([(a, env), (b, env)], repeat)
    return ta, tb


def time_alternating(
    runs: Sequence[tuple[Sequence[str], dict[str, str]]], repeat: int
) -> list[Timing]:
    """Median times of commands (each with its environment) run in turn.

    One untimed warm-up run of each (disk cache), then ``repeat`` rounds of one run of each;
    the order inside a round is reversed every other round, so that no command always runs
    right after the same other one.
    """
    for cmd, env in runs:
        _time_once(cmd, env)
    times: list[list[tuple[float, float]]] = [[] for _ in runs]
    order = list(range(len(runs)))
    for k in range(repeat):
        for i in order if k % 2 == 0 else order[::-1]:
            times[i].append(_time_once(*runs[i]))
    return [_median(t) for t in times]


def _median(runs: Sequence[tuple[float, float]]) -> Timing:
    """Medians of (wall, cpu) pairs."""
    return Timing(statistics.median(w for w, _ in runs), statistics.median(c for _, c in runs))


def _records(path: Path) -> list[str]:
    """Lines of a ``.pos`` file without line-ending differences or the run-naming header lines."""
    lines = path.read_text().replace("\r", "").splitlines()
    return [line for line in lines if not line.startswith(HEADER_NAMING_RUN)]


def matches_reference(case: Case, out: Path) -> str:
    """``"yes"``/``"NO"`` whether RTKLIB's output equals the stored reference, ``"-"`` if none."""
    ref = SHARED / "rtklib_spp" / f"{case.name}.pos"
    if not ref.is_file():
        return "-"
    return "yes" if _records(out) == _records(ref) else "NO"


def cut_rinex3(src: Path, n_epochs: int, dst: Path) -> None:
    """Write the header and the first ``n_epochs`` epoch records of a RINEX 3 observation file."""
    out: list[str] = []
    seen = 0
    in_header = True
    with src.open() as f:
        for line in f:
            if in_header:
                in_header = "END OF HEADER" not in line
            elif line.startswith(">"):
                seen += 1
                if seen > n_epochs:
                    break
            out.append(line)
    dst.write_text("".join(out))


HEAD = "navtrack s  RTKLIB s  ratio   cpu: navtrack  RTKLIB  ratio"


def _row(a: Timing, b: Timing) -> str:
    """Wall times, their ratio a / b, CPU times and their ratio."""
    return (
        f"{a.wall_s:10.3f} {b.wall_s:9.3f} {a.wall_s / b.wall_s:6.2f}        "
        f"{a.cpu_s:8.3f} {b.cpu_s:7.3f} {a.cpu_s / b.cpu_s:6.2f}"
    )


def bench_cases(cases: Sequence[Case], env: dict[str, str], repeat: int, tmp: Path) -> None:
    print(f"{'case':<14} {'epochs':>6} {HEAD}  pos = ref")
    for case in cases:
        nt_out, rtk_out = tmp / f"{case.name}.csv", tmp / f"{case.name}.pos"
        t_nt, t_rtk = time_pair(case.navtrack(nt_out), case.rtklib(rtk_out), env, repeat)
        epochs = case.epochs()
        print(
            f"{case.name:<14} {epochs:>6} {_row(t_nt, t_rtk)}  {matches_reference(case, rtk_out)}",
            flush=True,
        )


def bench_cuts(
    case: Case,
    cuts: Sequence[int],
    env: dict[str, str],
    repeat: int,
    tmp: Path,
    compare: Path | None = None,
) -> None:
    """Fixed cost + cost per epoch of both programs (a least-squares line through the medians
    at the cuts), and navtrack's fixed cost beyond ``python -c "import numpy"``, which runs in
    turn with the two programs at every cut (issue 33's bar: numpy's import + 40 ms). With
    ``compare`` (another source tree, e.g. a checkout of an earlier commit), its ``navtrack
    pos`` runs in the same rounds and gets the same line."""
    print(f"\nfixed cost + per epoch: {case.name} cut to the first N epochs")
    print(f"{'N':>6} {HEAD}   import numpy s" + ("   compare s" if compare else ""))
    numpy = [sys.executable, "-c", "import numpy"]
    other = None if compare is None else dict(env, PYTHONPATH=str(compare / "src"))
    lines: dict[str, list[Timing]] = {"navtrack": [], "RTKLIB": [], "numpy": [], "compare": []}
    for n in cuts:
        obs = tmp / f"cut_{n}.21O"
        cut_rinex3(case.obs, n, obs)
        runs = [
            (case.navtrack(tmp / "cut.csv", obs), env),
            (case.rtklib(tmp / "cut.pos", obs), env),
            (numpy, env),
        ]
        if other is not None:
            runs.append((case.navtrack(tmp / "cut_compare.csv", obs), other))
        timings = time_alternating(runs, repeat)
        for key, timing in zip(lines, timings, strict=False):
            lines[key].append(timing)
        extra = f"   {timings[3].wall_s:9.3f}" if other is not None else ""
        print(
            f"{n:>6} {_row(timings[0], timings[1])}   {timings[2].wall_s:8.3f}{extra}", flush=True
        )
    np_wall = statistics.median(v.wall_s for v in lines["numpy"])
    np_cpu = statistics.median(v.cpu_s for v in lines["numpy"])
    for label in ("navtrack", "RTKLIB", "compare"):
        t = lines[label]
        if not t:
            continue
        # least-squares line: intercept = fixed cost, slope = cost per epoch
        w1, w0 = statistics.linear_regression(cuts, [v.wall_s for v in t])
        c1, c0 = statistics.linear_regression(cuts, [v.cpu_s for v in t])
        print(
            f"{label:<9} wall: fixed {w0 * 1e3:7.1f} ms + {w1 * 1e6:6.1f} us per epoch; "
            f"cpu: fixed {c0 * 1e3:7.1f} ms + {c1 * 1e6:6.1f} us per epoch"
        )
        if label != "RTKLIB":
            print(
                f'{"":<9} fixed cost beyond python -c "import numpy" ({np_wall * 1e3:.1f} ms '
                f"wall, {np_cpu * 1e3:.1f} ms cpu; median over the cuts): wall "
                f"{(w0 - np_wall) * 1e3:+.1f} ms, cpu {(c0 - np_cpu) * 1e3:+.1f} ms (bar: +40 ms)"
            )


def bench_import_floor(env: dict[str, str], repeat: int) -> None:
    print("\nimport floor (whole process)      wall s   cpu s")
    numpy = [sys.executable, "-c", "import numpy"]
    spp = [sys.executable, "-c", "import navtrack.gnss.spp"]
    t_np, t_spp = time_pair(numpy, spp, env, repeat)
    print(f'python -c "import numpy"             {t_np.wall_s:6.3f}  {t_np.cpu_s:6.3f}')
    print(f'python -c "import navtrack.gnss.spp" {t_spp.wall_s:6.3f}  {t_spp.cpu_s:6.3f}')


def _instructions(cmd: Sequence[str], env: dict[str, str]) -> int:
    """Instructions executed by one whole process (callgrind ``Ir``)."""
    proc = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *cmd],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return int(proc.stderr.rsplit("Collected :", 1)[1].split()[0])


def bench_instructions(env: dict[str, str], repeat: int, tmp: Path) -> None:
    """Fixed cost of ``navtrack pos`` from instruction counts (module notes)."""
    obs = tmp / "cut_1.21O"
    cut_rinex3(SEPT_OBS, 1, obs)
    numpy = [sys.executable, "-c", "import numpy"]
    pos = CASES[1].navtrack(tmp / "one.csv", obs)
    helps = [sys.executable, "-m", "navtrack", "--help"]
    _time_once(numpy, env)
    t_np = _median([_time_once(numpy, env) for _ in range(repeat)])
    n_np = _instructions(numpy, env)
    print("\ninstructions (callgrind Ir)       Ir           over numpy  ~ms over numpy")
    print(f'python -c "import numpy"       {n_np:13,d}')
    for label, cmd in (("navtrack pos, 1 epoch", pos), ("navtrack --help", helps)):
        n = _instructions(cmd, env)
        extra = (n - n_np) / n_np
        print(f"{label:<30} {n:13,d}  {extra:+9.1%}  {extra * t_np.wall_s * 1e3:+8.1f}")
    print(f"(ms: the fraction times numpy's median wall time of this run, {t_np.wall_s:.3f} s)")


def _best_of(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``repeat`` calls of ``fn`` after one untimed call, s."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _count_lines(path: Path) -> int:
    """The floor of any reader: read the file and count its lines."""
    with path.open("rb") as f:
        return f.read().count(b"\n")


def bench_reader(paths: Sequence[Path], repeat: int) -> None:
    """In-process read rate of ``read_obs`` against reading the file and counting its lines."""
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.spp import SppConfig, observation_codes

    print("\nobservation reader (in process)      MB   read_obs s   MB/s  newline scan MB/s  ratio")
    for path in paths:
        mb = path.stat().st_size / 1e6
        t_scan = _best_of(lambda p=path: _count_lines(p), repeat)
        reads = (
            ("C1C of G and E", lambda p=path: read_obs(p, systems="GE", codes=("C1C",))),
            ("pos GEJ's codes", lambda p=path: read_obs(
                p, systems="GEJ", codes=observation_codes(SppConfig(systems="GEJ"))
            )),
            ("everything", lambda p=path: read_obs(p)),
        )  # fmt: skip
        for label, read in reads:
            t = _best_of(read, repeat)
            print(
                f"{path.name[:18]:<18} {label:<16} {mb:5.1f} {t:10.3f} {mb / t:8.0f} "
                f"{mb / t_scan:13.0f} {t / t_scan:10.1f}",
                flush=True,
            )


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
    ap.add_argument("--repeat", type=int, default=7, help="timed runs of each program per case")
    ap.add_argument("--only", nargs="*", help="case names (default: all whose inputs exist)")
    ap.add_argument(
        "--cuts", nargs="*", type=int, default=[50, 100, 200, 450, 900], help="SEPT epoch counts"
    )
    ap.add_argument("--threads", default="1", help="BLAS/OpenMP threads of both processes")
    ap.add_argument("--accuracy", action="store_true", help="also print the accuracy table")
    ap.add_argument(
        "--day", nargs=2, type=Path, metavar=("OBS", "NAV"), help="a 24 h RINEX 3 station"
    )
    ap.add_argument(
        "--instructions", action="store_true", help="also the fixed cost in instructions"
    )
    ap.add_argument(
        "--compare",
        type=Path,
        metavar="TREE",
        help="another source tree (e.g. a checkout of an earlier commit) whose navtrack pos "
        "runs in turn with this one at the cuts",
    )
    args = ap.parse_args()
    if args.accuracy:
        accuracy(args.only or list(REFERENCE["runs"]))
        print()
    if shutil.which("rnx2rtkp") is None:
        sys.exit("rnx2rtkp not found: apt-get install rtklib (see benchmarks/README.md)")
    # byte-compiled as pip leaves an installed package: where PYTHONDONTWRITEBYTECODE is set, a
    # source tree is otherwise compiled again by every process (~80 ms of the fixed cost here)
    for tree in (REPO, *([args.compare] if args.compare else [])):
        compileall.compile_dir(tree / "src" / "navtrack", quiet=1)
    env = dict(os.environ, PYTHONPATH=str(REPO / "src"))
    env.update(dict.fromkeys(THREAD_VARS, args.threads))
    version = subprocess.run(
        ["dpkg-query", "-W", "-f", "${Version}", "rtklib"], capture_output=True, text=True
    ).stdout
    print(
        f"RTKLIB {version or '(version unknown)'} ({shutil.which('rnx2rtkp')}); "
        f"{', '.join(THREAD_VARS)} = {args.threads} for both; "
        f"median of {args.repeat} alternating runs each; navtrack byte-compiled; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        day: list[Case] = []
        if args.day:
            obs, nav = args.day
            hour = Path(tmp) / "day_1h.rnx"
            cut_rinex3(obs, 120, hour)
            day = [
                Case("day_gps", obs, nav, "G", "spp_gps"),
                Case("day_gej", obs, nav, "GEJ", "spp_gej"),
                Case("day_1h_gps", hour, nav, "G", "spp_gps"),
            ]
        cases = [c for c in (*CASES, *day) if not args.only or c.name in args.only]
        missing = [c.name for c in cases if not c.available()]
        if missing:
            print(f"skipped (inputs not found): {', '.join(missing)}")
        bench_cases([c for c in cases if c.available()], env, args.repeat, Path(tmp))
        if args.cuts and CASES[0].available():
            bench_cuts(CASES[0], args.cuts, env, args.repeat, Path(tmp), args.compare)
        bench_import_floor(env, args.repeat)
        bench_reader([p for p in (SEPT_OBS, *(args.day or [])[:1]) if p.is_file()], args.repeat)
        if args.instructions and shutil.which("valgrind") and SEPT_OBS.is_file():
            bench_instructions(env, args.repeat, Path(tmp))


if __name__ == "__main__":
    main()
