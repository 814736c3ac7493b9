"""The readers and commands the fuzz suite feeds, their seed files, and one mutant's outcome.

A *target* is a reader (or an in-process command) with the seed file whose damaged copies it
is given. :func:`run_mutant` writes one mutant next to the others (same suffix, so the format
follows) and runs the target on it in a worker process limited in added memory
(:data:`MEMORY_LIMIT_BYTES`) and time (:data:`TIME_LIMIT_S`); the outcome is one of

* ``error_line`` / ``error_file`` -- a :class:`~navtrack.errors.NavtrackError` (or a command's
  exit 2 with ``navtrack CMD: error: FILE[:LINE]: ...``) naming the file, with / without a line;
* ``ok_counted`` -- read, with the damaged records skipped and counted;
* ``ok`` -- read, nothing skipped (the damage left a valid file, or went unnoticed);
* the failures ``unnamed`` (an error not naming the file), ``crash`` (any other exception, or a
  command's exit 3), ``hang`` (over the time limit) and ``memory`` (over the memory limit).
"""

from __future__ import annotations

import contextlib
import io
import multiprocessing
import resource
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.pool import Pool
from pathlib import Path
from typing import Any

import numpy as np
from fuzz_mutations import OPERATORS

from navtrack.data import sample_path

REPO = Path(__file__).resolve().parents[2]
TEST_DATA = REPO / "tests" / "data"
MEMORY_LIMIT_BYTES = 3 * 2**30  # address space the worker may add to what it inherits
TIME_LIMIT_S = 30.0
FAILURES = ("unnamed", "crash", "hang", "memory")
OUTCOMES = ("error_line", "error_file", "ok_counted", "ok", *FAILURES)


@dataclass(frozen=True)
class Target:
    """One reader or command fed with damaged copies of ``seed``."""

    name: str
    seed: Callable[[Path], Path | None]  # the seed file (None: not available here)
    run: Callable[[Path], int]  # reads the file; returns the number of records skipped
    header_lines: Callable[[bytes], int]


def _until(marker: bytes) -> Callable[[bytes], int]:
    def header(data: bytes) -> int:
        for k, line in enumerate(data.splitlines()):
            if marker in line[:80] if marker != b"*" else line.startswith(b"*"):
                return k + (1 if marker != b"*" else 0)
        return 0

    return header


def _comments(data: bytes) -> int:
    lines = data.splitlines()
    return next((k for k, ln in enumerate(lines) if not ln.startswith(b"#")), len(lines))


def _csv_header(data: bytes) -> int:
    return 1


def _read_obs(path: Path) -> int:
    from navtrack.gnss.rinex.obs import read_obs

    return len(read_obs(path).skipped)


def _read_obs_lenient(path: Path) -> int:
    from navtrack.gnss.rinex.obs import read_obs

    return len(read_obs(path, lenient=True).skipped)


def _read_nav(path: Path) -> int:
    from navtrack.gnss.rinex.nav import read_nav

    return len(read_nav(path).skipped)


def _read_nav_lenient(path: Path) -> int:
    from navtrack.gnss.rinex.nav import read_nav

    return len(read_nav(path, lenient=True).skipped)


def _read_sp3(path: Path) -> int:
    from navtrack.gnss.sp3 import read_sp3

    return len(read_sp3(path).implausible)


def _read_android(path: Path) -> int:
    from navtrack.gnss.android import read_gnsslogger

    obs = read_gnsslogger(path)
    return sum(1 for s in obs.skipped if s.reason in ("unreadable row", "not a log record"))


def _read_android_lenient(path: Path) -> int:
    from navtrack.gnss.android import read_gnsslogger

    obs = read_gnsslogger(path, lenient=True)
    return sum(1 for s in obs.skipped if s.reason in ("unreadable row", "not a log record"))


def _read_tracks(fmt: str) -> Callable[[Path], int]:
    def run(path: Path) -> int:
        from navtrack.io.tracks import read_tracks

        det = read_tracks(path, fmt)
        return len(det.bad_lines) + det.n_reordered

    return run


def _read_table(path: Path) -> int:
    from navtrack.io.tables import read_table

    read_table(path)
    return 0


def _command(argv: Callable[[Path], list[str]]) -> Callable[[Path], int]:
    """A command run in-process through :func:`navtrack.cli.main`: exit 2 becomes the error it
    printed, 3 a crash."""

    def run(path: Path) -> int:
        from navtrack.cli import main

        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            try:
                code = main(argv(path))
            except SystemExit as exc:  # a refused command line (CommandLineExit, exit 2)
                code = exc.code if isinstance(exc.code, int) else 3
        if code in (0, 1):
            return 0
        raise CommandFailed(code, err.getvalue())

    return run


class CommandFailed(Exception):
    """A command's exit code other than 0/1, with what it printed on stderr."""

    def __init__(self, code: int, stderr: str) -> None:
        super().__init__(f"exit {code}: {stderr.strip()}")
        self.code = code
        self.stderr = stderr


def _sample(name: str) -> Callable[[Path], Path | None]:
    return lambda _: sample_path(name)


def _test_file(name: str) -> Callable[[Path], Path | None]:
    return lambda _: TEST_DATA / name


def _shared_head(relative: str, n_lines: int) -> Callable[[Path], Path | None]:
    """The first lines of a shared real data file (None without the shared data)."""

    def seed(tmp: Path) -> Path | None:
        import os

        root = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data"))
        src = root / relative
        if not src.is_file():
            return None
        out = tmp / f"seed_{src.name}"
        with src.open("rb") as fh:
            out.write_bytes(b"".join(fh.readline() for _ in range(n_lines)))
        return out

    return seed


def _ships_csv(tmp: Path) -> Path:
    rows = ["time,lat,lon,id,speed_mps,course_deg"]
    for k in range(40):
        for i in range(3):
            t = f"2020-01-01T00:{k // 6:02d}:{(k % 6) * 10:02d}Z"
            rows.append(f"{t},{50.0 + 0.02 * i + 1e-4 * k:.6f},{-1.0 + 2e-4 * k:.6f},s{i},3,45")
    out = tmp / "seed_ships.csv"
    out.write_text("\n".join(rows) + "\n")
    return out


def _series_csv(tmp: Path) -> Path:
    rng = np.random.default_rng(9)
    t = 0.5 * np.arange(60)
    y = np.cumsum(rng.normal(0, 0.01, 60)) + rng.normal(0, 0.003, 60)
    out = tmp / "seed_series.csv"
    out.write_text(
        "t_s,roll_deg\n" + "".join(f"{a:g},{b:.6f}\n" for a, b in zip(t, y, strict=True))
    )
    return out


_RINEX = _until(b"END OF HEADER")
TARGETS: dict[str, Target] = {
    t.name: t
    for t in (
        Target("rinex2_obs", _sample("07590920.05o"), _read_obs, _RINEX),
        Target("rinex3_obs", _sample("SEPT078M_120.21O"), _read_obs, _RINEX),
        Target("rinex3_obs_lenient", _sample("SEPT078M_120.21O"), _read_obs_lenient, _RINEX),
        Target("rinex2_nav_gps", _sample("07590920.05n"), _read_nav, _RINEX),
        Target("rinex2_nav_glonass", _test_file("brdc0320_cut.16l"), _read_nav, _RINEX),
        Target("rinex3_nav_mixed", _sample("SEPT078M.21P"), _read_nav, _RINEX),
        Target(
            "rinex3_nav_lenient",
            _test_file("BRDC00IGS_R_20230010000_01D_MN_cut.rnx"),
            _read_nav_lenient,
            _RINEX,
        ),
        Target(
            "sp3",
            _sample("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3"),
            _read_sp3,
            _until(b"*"),
        ),
        Target("android", _test_file("pixel10_gnsslogger_v3_cut.txt"), _read_android, _comments),
        Target(
            "android_lenient",
            _test_file("pixel10_gnsslogger_v3_cut.txt"),
            _read_android_lenient,
            _comments,
        ),
        Target("tracks_csv", _ships_csv, _read_tracks("csv"), _csv_header),
        Target(
            "tracks_ais",
            _shared_head("tracking/SolentAIS_20160112_130211.csv", 150),
            _read_tracks("ais"),
            _csv_header,
        ),
        Target(
            "tracks_opensky",
            _shared_head("tracking/OpenSky_Plane_States.csv", 150),
            _read_tracks("opensky"),
            _csv_header,
        ),
        Target("table_rtklib_pos", _test_file("sept078_gej_cut.pos"), _read_table, _comments),
        Target(
            "smooth_command",
            _series_csv,
            _command(lambda p: ["smooth", str(p), "--order", "0,1", "--robust", "off"]),
            _csv_header,
        ),
        Target(
            "track_command",
            _ships_csv,
            _command(lambda p: ["track", str(p), "--format", "csv"]),
            _csv_header,
        ),
    )
}


def mutate(seed: bytes, header: int, operator: str, seed_value: int) -> tuple[bytes, int | None]:
    """The mutant of ``seed`` made by ``operator`` with generator seed ``seed_value``."""
    rng = np.random.default_rng(seed_value)
    return OPERATORS[operator](seed, rng, header)


def _limit_worker() -> None:
    # the forked worker starts with the test process's address space (every library the
    # session has loaded), so the limit is counted from there, not from zero
    limit = _address_space_bytes() + MEMORY_LIMIT_BYTES
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _address_space_bytes() -> int:
    """This process's virtual memory size (``VmSize`` of ``/proc/self/status``), 0 if unknown."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    return 0


def _classify(target: str, path: str) -> tuple[str, str]:
    """Run a target on a file (in the worker) and name the outcome."""
    from navtrack.errors import NavtrackError

    try:
        skipped = TARGETS[target].run(Path(path))
    except NavtrackError as exc:
        if path not in str(exc):
            return "unnamed", str(exc)
        line = getattr(exc, "line", None)
        return ("error_line" if line is not None else "error_file"), str(exc)
    except CommandFailed as exc:
        first = exc.stderr.strip().splitlines()[0] if exc.stderr.strip() else ""
        if exc.code != 2:
            return "crash", first
        if not first.startswith("navtrack ") or f"error: {path}" not in first:
            return "unnamed", first
        return (
            "error_line" if first.startswith(f"{first.split(path)[0]}{path}:") else "error_file"
        ), first
    except MemoryError:
        return "memory", "MemoryError"
    except Exception as exc:
        return "crash", "".join(traceback.format_exception_only(exc)).strip() + (
            " @ "
            + traceback.extract_tb(exc.__traceback__)[-1].filename.rsplit("/", 2)[-1]
            + ":"
            + str(traceback.extract_tb(exc.__traceback__)[-1].lineno)
        )
    return ("ok_counted" if skipped else "ok"), ""


class Runner:
    """A worker process (fork) under the memory limit; restarted after a hang."""

    def __init__(self) -> None:
        self._ctx = multiprocessing.get_context("fork")
        self._pool: Pool | None = None

    def _get(self) -> Pool:
        if self._pool is None:
            self._pool = self._ctx.Pool(1, initializer=_limit_worker)
        return self._pool

    def run(self, target: str, path: Path) -> tuple[str, str]:
        pool = self._get()
        job = pool.apply_async(_classify, (target, str(path)))
        try:
            return job.get(timeout=TIME_LIMIT_S)
        except multiprocessing.TimeoutError:
            self.close()
            return "hang", f"no result within {TIME_LIMIT_S:g} s"

    def close(self) -> None:
        if self._pool is not None:
            self._pool.terminate()
            self._pool.join()
            self._pool = None

    def __enter__(self) -> Runner:
        return self

    def __exit__(self, *_: Any) -> None:
        self.close()


def run_mutant(
    runner: Runner, target: str, operator: str, seed_value: int, tmp: Path
) -> tuple[str, str, int | None]:
    """Outcome, message and damaged line of one mutant of a target's seed."""
    t = TARGETS[target]
    seed_path = t.seed(tmp)
    if seed_path is None:
        raise FileNotFoundError(f"seed of {target} not available")
    data = seed_path.read_bytes()
    mutant, line = mutate(data, t.header_lines(data), operator, seed_value)
    path = tmp / f"{target}_{operator}_{seed_value}{seed_path.suffix}"
    path.write_bytes(mutant)
    outcome, message = runner.run(target, path)
    return outcome, message, line
