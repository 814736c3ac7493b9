"""Issue 32's table for any report files: navtrack untuned beside a Stone Soup tracker tuned
on half of each file.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python benchmarks/eval_track_files.py
[FILE | KIND:FILE | opensky | solent ...] [--associators gnn,jpda] [--no-peer] [--md OUT.md]``.

For every file:

- ``navtrack track FILE --associator A --quiet`` (the command as a user runs it, no tuning
  flag) on the whole file, GNN and JPDA: the first table;
- the file is split in time at the middle of its span and the second half written in the
  generic csv layout (``time, id, lat, lon, alt_m, speed_mps, course_deg``); ``navtrack track``
  runs on that file as on any other (it never sees the first half);
- Stone Soup's tracker (:mod:`bench_track_stonesoup`: CV model, GNN or JPDA, its
  ``MultiMeasurementInitiator`` and ``UpdateTimeDeleter``) searches its grid
  (``bench_track_stonesoup.GRID``, per kind of file) on the first half by HOTA, and its best
  setting tracks the second half: the second table, beside navtrack on the same half, scored
  by the command's rule (:mod:`navtrack.tracking.scoring`, the same frames and truth).

KIND is a key of ``bench_track_stonesoup.GRID`` (``ships``, ``aircraft`` for ADS-B at ~10 s,
``adsb`` for ADS-B at 1-5 s); without it the kind follows from the file (:func:`kind_of`).
Cells: MOTA / HOTA / IDF1 / id switches / confirmed tracks : true ids.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

import bench_track_stonesoup as peer
from navtrack.io.tracks import TrackDetections, read_tracks
from navtrack.timescale import gps_to_utc, to_datetime64
from navtrack.tracking.scoring import Scores

SUMMARY_KEYS = {
    "mota": r"^MOTA\s+(\S+)",
    "hota": r"^HOTA \(DetA, AssA\)\s+(\S+)",
    "idf1": r"^IDF1 \(IDP, IDR\)\s+(\S+)",
    "switches": r"^id switches\s+(\S+)",
    "ids_tracks": r"^ids / confirmed tracks\s+(\d+) / (\d+)",
}


def kind_of(det: TrackDetections) -> str:
    """Stone Soup's grid for a file: ``ships`` below a median reported speed of 25 m/s (the
    threshold of navtrack's ``auto`` families), else ``adsb`` when the ids report every 5 s
    or faster at the median, else ``aircraft``."""
    speed = np.nanmedian(det.speed_mps) if np.isfinite(det.speed_mps).any() else 0.0
    if speed < 25.0:
        return "ships"
    df = pd.DataFrame({"t": det.t_gps_s, "id": det.id}).sort_values(["id", "t"])
    step = df.groupby("id")["t"].diff()
    return "adsb" if float(step[step > 0].median()) <= 5.0 else "aircraft"


def second_half_csv(det: TrackDetections, path: Path) -> Path:
    """The reports at or after the middle of the file's span, written in the generic layout."""
    mid = 0.5 * (det.t_gps_s[0] + det.t_gps_s[-1])
    k = det.t_gps_s >= mid
    utc = pd.to_datetime(to_datetime64(gps_to_utc(det.t_gps_s[k])))
    cols = {"time": utc.strftime("%Y-%m-%dT%H:%M:%S.%fZ"), "id": det.id[k]}
    if det.geodetic:
        cols |= {"lat": det.lat_deg[k], "lon": det.lon_deg[k]}
    else:
        cols |= {"x_m": det.x_m[k], "y_m": det.y_m[k]}
    for name in ("alt_m", "speed_mps", "course_deg"):
        values = getattr(det, name)[k]
        if np.isfinite(values).any():
            cols[name] = values
    pd.DataFrame(cols).to_csv(path, index=False, float_format="%.8f")
    return path


def navtrack_track(path: Path, associator: str) -> tuple[str, float]:
    """One cell from ``navtrack track PATH --associator A --quiet``, and its wall time."""
    clock = time.perf_counter()
    cmd = [sys.executable, "-m", "navtrack", "track", str(path), "--associator", associator]
    out = subprocess.run([*cmd, "--quiet"], capture_output=True, text=True, check=False)
    elapsed = time.perf_counter() - clock
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({out.returncode}):\n{out.stderr}")
    found = {}
    for key, pattern in SUMMARY_KEYS.items():
        m = re.search(pattern, out.stdout, flags=re.MULTILINE)
        if m is None:
            raise SystemExit(f"{' '.join(cmd)}: no '{pattern}' line in the summary")
        found[key] = m.groups()
    ids, tracks = found["ids_tracks"]
    cell = (
        f"{float(found['mota'][0]):.3f} / {float(found['hota'][0]):.3f} / "
        f"{float(found['idf1'][0]):.3f} / {found['switches'][0]} / {tracks}:{ids}"
    )
    return cell, elapsed


def peer_cell(s: Scores) -> str:
    return f"{s.mota:.3f} / {s.hota:.3f} / {s.idf1:.3f} / {s.id_switches} / {s.n_tracks}:{s.n_ids}"


def tuned_peer(
    path: Path, h2: Path, kind: str, associator: str, setting: dict | None = None
) -> tuple[str, str, float]:
    """Stone Soup tuned on the first half of ``path`` by HOTA (or at ``setting``, not
    searched) and scored on the second half as written to ``h2`` (the file ``navtrack
    track`` reads, so that both see the same reports and truth): the cell, the chosen
    setting with the first half's grid, and the second half's tracking time."""
    if setting is None:
        best, lines = peer.tune_on_first_half(peer.load(path, None)["h1"], kind, associator)
    else:
        best, lines = setting, "given with --peer-setting, not searched"
    scores, elapsed = peer.score_stonesoup(
        peer.load(h2, None, split=False)["all"],
        associator,
        best,
        peer.FIXED[kind],
        peer.SCAN_S[kind],
    )
    return peer_cell(scores), f"q={best['q']:g}, delete {best['delete_s']:g} s; {lines}", elapsed


def evaluate(
    name: str,
    path: Path,
    kind: str,
    associators: list[str],
    with_peer: bool,
    setting: dict | None = None,
) -> dict:
    """Every cell of one file."""
    row: dict = {"file": name, "kind": kind}
    with tempfile.TemporaryDirectory() as tmp:
        h2 = second_half_csv(read_tracks(path), Path(tmp) / f"{path.stem}_h2.csv")
        for a in associators:
            row[f"navtrack {a}"], row[f"navtrack {a} s"] = navtrack_track(path, a)
            row[f"navtrack {a} h2"], row[f"navtrack {a} h2 s"] = navtrack_track(h2, a)
            print(
                f"  navtrack {a}: {row[f'navtrack {a}']}; h2 {row[f'navtrack {a} h2']}", flush=True
            )
            if with_peer:
                cell, grid, elapsed = tuned_peer(path, h2, kind, a, setting)
                row[f"stonesoup {a} h2"], row[f"stonesoup {a} grid"] = cell, grid
                row[f"stonesoup {a} h2 s"] = elapsed
                print(f"  Stone Soup {a}: {cell} ({grid}; h2 {elapsed:.0f} s)", flush=True)
    return row


def tables(rows: list[dict], associators: list[str], with_peer: bool) -> str:
    """The two markdown tables (whole files; second halves beside the tuned peer)."""
    out = ["Whole file, `navtrack track FILE [--associator jpda]`, no other flag:", ""]
    head = ["recording", *(f"navtrack {a.upper()}" for a in associators)]
    out += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += [
        "| " + " | ".join([r["file"], *(r[f"navtrack {a}"] for a in associators)]) + " |"
        for r in rows
    ]
    out += ["", "Second half (navtrack untuned on it; Stone Soup tuned on the first half):", ""]
    cols = [f"navtrack {a} h2" for a in associators]
    if with_peer:
        cols += [f"stonesoup {a} h2" for a in associators]
    head = ["recording", *(c.replace(" h2", "").replace("stonesoup", "Stone Soup") for c in cols)]
    out += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join([r["file"], *(r[c] for c in cols)]) + " |" for r in rows]
    if with_peer:
        out += ["", "Stone Soup's choice on the first half (HOTA over its grid):", ""]
        out += [f"- {r['file']} {a}: {r[f'stonesoup {a} grid']}" for r in rows for a in associators]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", help="FILE, KIND:FILE, or a shared file: opensky, solent")
    ap.add_argument("--associators", default="gnn,jpda")
    ap.add_argument("--no-peer", action="store_true", help="navtrack's cells only")
    ap.add_argument("--md", type=Path, help="also write the tables to this markdown file")
    ap.add_argument(
        "--peer-setting",
        metavar="Q,DELETE_S",
        help="run Stone Soup at this q (m^2/s^3) and deletion time (s) instead of searching "
        "its grid on the first half",
    )
    a = ap.parse_args(argv)
    associators = a.associators.split(",")
    with_peer = not a.no_peer and peer.stonesoup_installed()
    setting = None
    if a.peer_setting:
        q, delete_s = (float(v) for v in a.peer_setting.split(","))
        setting = {"q": q, "delete_s": delete_s}
    rows = []
    for item in a.files:
        if item in peer.FILES:
            path, _fmt, kind = peer.FILES[item]
        else:
            kind, _, rest = (
                item.rpartition(":") if item.split(":")[0] in peer.GRID else ("", "", item)
            )
            path = Path(rest)
            kind = kind or kind_of(read_tracks(path))
        print(f"{path.name} ({kind})", flush=True)
        rows.append(evaluate(path.name, path, kind, associators, with_peer, setting))
    text = tables(rows, associators, with_peer)
    print("\n" + text)
    if a.md:
        a.md.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
