"""Solution file speed: navtrack's RTKLIB reader and NMEA/GPX writers against peers.

* ``read_pos`` (all columns, times parsed, lines validated) vs ``pandas.read_csv`` with a
  whitespace separator and ``%`` comments (no validation, no time parsing: a lower bound);
* NMEA GGA: ``write_solution(..., ".nmea")`` vs per-row ``pynmea2.GGA(...).render()`` with the
  same field formatting done in Python (the usual way to write GGA with pynmea2);
* GPX: ``write_solution(..., ".gpx")`` vs ``gpxpy`` (track points appended, ``to_xml()``).

Inputs: RTKLIB's SEPT GPS+Galileo+QZSS solution (900 epochs, 1 Hz) and the same lines repeated
96 times (86 400 epochs, one day at 1 Hz). Medians of ``--runs`` runs. Run from the repository
root::

    PYTHONPATH=src python benchmarks/bench_io.py [--runs 5]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from navtrack import timescale
from navtrack.io.rtklib import read_pos, to_solution_frame
from navtrack.io.solution import solution_columns, write_solution

REPO = Path(__file__).resolve().parents[1]
GNSS = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"
SEPT = GNSS / "rtklib_spp" / "sept078_gej.pos"


def _median_s(fn: Callable[[], object], runs: int) -> float:
    fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _pandas_read(path: Path) -> object:
    import pandas as pd

    return pd.read_csv(path, comment="%", sep=r"\s+", header=None)


def _pynmea2_gga(sol: dict, path: Path) -> None:
    import pynmea2

    cols = solution_columns(sol)
    utc = timescale.gps_to_utc(np.asarray(sol["t_gps_s"]))
    lines = []
    for i in range(len(utc)):
        tod = utc[i] % 86400.0
        lat, lon = cols["lat_deg"][i], cols["lon_deg"][i]
        la, lo = abs(lat), abs(lon)
        fields = (
            f"{int(tod // 3600):02d}{int(tod % 3600 // 60):02d}{tod % 60:05.2f}",
            f"{int(la):02d}{(la - int(la)) * 60:09.6f}",
            "N" if lat >= 0 else "S",
            f"{int(lo):03d}{(lo - int(lo)) * 60:09.6f}",
            "E" if lon >= 0 else "W",
            "1",
            f"{int(cols['n_sats'][i]):02d}",
            "",
            f"{cols['h_m'][i]:.3f}",
            "M",
            "0.0",
            "M",
            "",
            "",
        )
        lines.append(pynmea2.GGA("GP", "GGA", fields).render() + "\r\n")
    path.write_text("".join(lines))


def _gpxpy(sol: dict, path: Path) -> None:
    import gpxpy.gpx

    cols = solution_columns(sol)
    utc = timescale.gps_to_utc(np.asarray(sol["t_gps_s"]))
    epoch = dt.datetime(1980, 1, 6, tzinfo=dt.UTC)
    gpx = gpxpy.gpx.GPX()
    track = gpxpy.gpx.GPXTrack()
    seg = gpxpy.gpx.GPXTrackSegment()
    gpx.tracks.append(track)
    track.segments.append(seg)
    for i in range(len(utc)):
        seg.points.append(
            gpxpy.gpx.GPXTrackPoint(
                float(cols["lat_deg"][i]),
                float(cols["lon_deg"][i]),
                elevation=float(cols["h_m"][i]),
                time=epoch + dt.timedelta(seconds=float(utc[i])),
            )
        )
    path.write_text(gpx.to_xml())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs per measurement (median)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmpdir = Path(tmp)
        day = tmpdir / "day.pos"
        text = SEPT.read_text().splitlines(keepends=True)
        head = [ln for ln in text if ln.startswith("%")]
        body = [ln for ln in text if not ln.startswith("%")]
        day.write_text("".join(head + body * 96))
        print(f"{'task':<34}{'epochs':>8}{'navtrack s':>12}{'peer s':>10}{'ratio':>8}  peer")
        for name, path in (("sept078_gej.pos", SEPT), ("one day (x96)", day)):
            pos = read_pos(path)
            sol = {k: pos_col.to_numpy() for k, pos_col in to_solution_frame(pos).items()}
            n = len(pos)
            rows = [
                (
                    f"read_pos {name}",
                    _median_s(lambda p=path: read_pos(p), args.runs),
                    _median_s(lambda p=path: _pandas_read(p), args.runs),
                    "pandas.read_csv (no checks)",
                ),
                (
                    f"NMEA GGA {name}",
                    _median_s(lambda s=sol: write_solution(s, tmpdir / "a.nmea"), args.runs),
                    _median_s(lambda s=sol: _pynmea2_gga(s, tmpdir / "b.nmea"), args.runs),
                    "pynmea2 render",
                ),
                (
                    f"GPX {name}",
                    _median_s(lambda s=sol: write_solution(s, tmpdir / "a.gpx"), args.runs),
                    _median_s(lambda s=sol: _gpxpy(s, tmpdir / "b.gpx"), args.runs),
                    "gpxpy to_xml",
                ),
            ]
            for task, ours, peer, peer_name in rows:
                print(f"{task:<34}{n:>8}{ours:>12.4f}{peer:>10.4f}{ours / peer:>8.2f}  {peer_name}")


if __name__ == "__main__":
    main()
