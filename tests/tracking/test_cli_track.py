"""``navtrack track`` end to end on a small generated CSV with known ids."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from navtrack.cli import main


def test_track_command_generic_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(0)
    lines = ["time,lat,lon,id,alt_m"]
    for k in range(40):
        for i in range(3):
            lat = 50.0 + 0.05 * i + 1e-4 * k + rng.normal(0, 1e-5)
            lon = -1.0 + 2e-4 * k + rng.normal(0, 1e-5)
            lines.append(f"2020-01-01T00:{k // 6:02d}:{(k % 6) * 10:02d}Z,{lat},{lon},s{i},0")
    lines.append("2020-01-01T00:00:05Z,50.0,54.8,s0,0")  # far outlier, reported and skipped
    f = tmp_path / "ships.csv"
    f.write_text("\n".join(lines) + "\n")
    out = tmp_path / "tracks.csv"
    pytest.importorskip("matplotlib")
    plots = tmp_path / "plots"
    assert (
        main(
            [
                "track",
                str(f),
                "--format",
                "csv",
                "--out",
                str(out),
                "--report-s",
                "10",
                "--plot",
                str(plots),
            ]
        )
        == 0
    )
    assert (plots / "tracks.png").stat().st_size > 1000
    text = capsys.readouterr().out
    assert "bad rows skipped" in text
    assert "MOTA" in text
    mota = float(next(ln for ln in text.splitlines() if ln.startswith("MOTA")).split()[-1])
    assert mota > 0.8
    assert "id switches" in text
    import pandas as pd

    df = pd.read_csv(out)
    assert {"time", "track_id", "x_m", "y_m", "lat_deg", "lon_deg"} <= set(df.columns)
    assert df.loc[df.confirmed, "track_id"].nunique() == 3


def test_track_command_reports_missing_columns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "bad.csv"
    f.write_text("when,lat,lon\n2020-01-01T00:00:00Z,50,-1\n")
    assert main(["track", str(f), "--format", "csv"]) == 2
    assert "navtrack track: error: " + f"{f}:1: missing column" in capsys.readouterr().err


@pytest.mark.parametrize("option", ["--report-s", "--match-m", "--max-range-km", "--max-time-days"])
@pytest.mark.parametrize("value", ["0", "-5", "nan"])
def test_track_cli_refuses_non_positive_settings(
    tmp_path: Path, option: str, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "--report-s 0" silently fell back to the default and a negative value gave an
    # empty scoring grid; now the command stops and names the option.
    f = tmp_path / "d.csv"
    f.write_text("time,x_m,y_m\n2020-01-01T00:00:00Z,0,0\n")
    with pytest.raises(SystemExit, match=option) as info:
        main(["track", str(f), "--format", "csv", option, value])
    assert info.value.code == 2
    assert f"navtrack track: error: {option} must be" in capsys.readouterr().err


def _ships(k_last: int, extra: str = "") -> str:
    """Two ids 10 s apart for ``k_last`` + 1 reports, generic CSV layout."""
    rows = ["time,lat,lon,id"]
    for k in range(k_last + 1):
        for i in range(2):
            t = f"2020-01-01T00:{k // 6:02d}:{(k % 6) * 10:02d}Z"
            rows.append(f"{t},{50.0 + 0.05 * i + 1e-4 * k},{-1.0 + 2e-4 * k},s{i}")
    return "\n".join(rows) + "\n" + extra


def test_track_command_scores_a_one_minute_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 9, failure 3: a file shorter than a minute had no track at its one scoring frame and
    # scorer raised "cannot reshape array of size 0"; now every truth object is a miss
    f = tmp_path / "short.csv"
    f.write_text(_ships(5))  # 50 s: one scoring frame of 60 s, at the first report
    assert main(["track", str(f), "--format", "csv", "--report-s", "60"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"truth objects / matches / misses / false +2 0 2 0\n", text)


def test_track_command_skips_a_century_old_row_and_bounds_the_grid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 9, failure 1: one row dated 1920 made the report grid span a century (hang, GBs)
    f = tmp_path / "ships.csv"
    f.write_text(_ships(12, "1920-01-01T00:00:30Z,50.0,-1.0,s0\n"))
    assert main(["track", str(f), "--format", "csv", "--report-s", "60"]) == 0
    text = capsys.readouterr().out
    assert "time more than 30 days from the median time: 1" in text
    assert "3 frames every 60 s" in text
    # with the time check off, the grid size is refused before it is allocated
    with pytest.raises(SystemExit, match=r"--report-s 60 .* more than 1000000") as info:
        main(["track", str(f), "--format", "csv", "--max-time-days", "1e6", "--report-s", "60"])
    assert info.value.code == 2
    assert "navtrack track: error: --report-s 60 " in capsys.readouterr().err


def test_track_progress_bar_counts_the_tracked_detections(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import io
    import sys

    import numpy as np

    from navtrack.cli.track import PROGRESS_MIN_DETECTIONS, _progress
    from navtrack.tracking.trackers.tracker import TrackerConfig, run_tracker

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    n = PROGRESS_MIN_DETECTIONS
    t = np.repeat(np.arange(n // 5, dtype=float), 5)  # five targets reporting every second
    z = np.column_stack([np.tile(np.arange(5) * 1e4, n // 5) + 10 * t, np.zeros(n)])
    steps: list[int] = []
    run_tracker(t, z, TrackerConfig(), progress=steps.append)
    assert sum(steps) == n
    assert min(steps) > 0
    err = Terminal()
    monkeypatch.setattr(sys, "stderr", err)
    with _progress(n, quiet=False) as progress:
        assert progress is not None
        for k in steps:
            progress(k)
    assert f"tracking:   0%|          | 0/{n} " in err.getvalue()  # total = detections
    quiet = Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    with _progress(n, quiet=True) as progress:
        assert progress is None
    assert quiet.getvalue() == ""


def _fleet(n_ids: int = 3, n_reports: int = 40, speed_col: float | None = None) -> str:
    """Ships 0.05° apart moving north-east, a report every 10 s, generic CSV layout."""
    rows = ["time,lat,lon,id" + (",speed_mps,course_deg" if speed_col is not None else "")]
    for k in range(n_reports):
        t = f"2020-01-01T00:{k // 6:02d}:{(k % 6) * 10:02d}Z"
        for i in range(n_ids):
            row = f"{t},{50.0 + 0.05 * i + 1e-4 * k},{-1.0 + 2e-4 * k},s{i}"
            if speed_col is not None:
                row += f",{speed_col},54.0"
            rows.append(row)
    return "\n".join(rows) + "\n"


def test_track_model_options_are_used_printed_and_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    f = tmp_path / "fleet.csv"
    f.write_text(_fleet())
    out = tmp_path / "tracks.csv"
    argv = ["track", str(f), "--format", "csv", "--preset", "ships", "--motion", "cv"]
    argv += ["--q", "0.02", "--sigma-m", "30", "--pd", "0.8", "--clutter-density", "2e-7"]
    argv += ["--confirm", "4/600", "--max-coast-s", "120", "--gate-prob", "0.999"]
    assert main([*argv, "--out", str(out), "--report-s", "10"]) == 0
    text = capsys.readouterr().out
    lines = dict(re.split(r"\s{2,}", ln, maxsplit=1) for ln in text.splitlines() if "  " in ln)
    assert lines["preset"] == "ships"
    assert lines["motion"] == "cv"
    assert lines["q (m^2/s^3)"] == "0.02"
    assert lines["sigma (m)"] == "30.0"
    assert lines["pd"] == "0.8"
    assert lines["clutter density (1/m^2)"] == "2e-07"
    assert lines["confirm (M/W s)"] == "4/600"
    assert lines["max coast (s)"] == "120.0"
    assert lines["gate probability"] == "0.999"
    meta = json.loads(Path(f"{out}.json").read_text())
    assert meta["q (m^2/s^3)"] == "0.02"
    assert meta["confirm (M/W s)"] == "4/600"
    assert meta["associator"] == "gnn"
    pytest.importorskip("pyarrow")
    import pandas as pd

    pq = tmp_path / "tracks.parquet"
    assert main([*argv, "--out", str(pq), "--report-s", "10"]) == 0
    assert json.loads(pd.read_parquet(pq).attrs["navtrack"]) == meta


def test_track_auto_is_the_default_and_reports_what_it_chose(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "fleet.csv"
    f.write_text(_fleet(n_reports=60))
    assert main(["track", str(f), "--format", "csv", "--report-s", "10"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"^preset +auto$", text, re.M)
    assert re.search(r"^auto: report interval p50/p95 \(s\) +10\.0 10\.0$", text, re.M)
    assert "HOTA" in text
    mota = float(next(ln for ln in text.splitlines() if ln.startswith("MOTA")).split()[-1])
    assert mota > 0.8
    # imm over a preset's single model: quiet q from the manoeuvring one
    assert (
        main(["track", str(f), "--format", "csv", "--preset", "aircraft", "--motion", "imm"]) == 0
    )
    assert re.search(r"^q \(m\^2/s\^3\) +0\.3,300$", capsys.readouterr().out, re.M)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--confirm", "three"], "--confirm takes M/W"),
        (["--confirm", "1/60"], "M >= 2"),
        (["--motion", "imm", "--q", "1,2,3"], "--motion imm takes --q QUIET,MANOEUVRING"),
        (["--motion", "cv", "--q", "1,2"], "--motion cv takes one --q value"),
        (["--q", "fast"], "--q takes numbers"),
        (["--pd", "1.5"], "--pd must be in \\(0, 1\\)"),
        (["--gate-prob", "0"], "--gate-prob must be in"),
        (["--sigma-m", "-3"], "--sigma-m must be a positive number"),
    ],
)
def test_track_refuses_bad_model_options(tmp_path: Path, argv: list[str], message: str) -> None:
    f = tmp_path / "fleet.csv"
    f.write_text(_fleet(n_reports=5))
    with pytest.raises(SystemExit, match=message):
        main(["track", str(f), "--format", "csv", "--preset", "ships", *argv])


def test_track_warns_with_counts_on_suspicious_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # every report at one time
    f = tmp_path / "one_time.csv"
    rows = ["time,lat,lon,id"] + [
        f"2020-01-01T00:00:00Z,{50 + 0.01 * i},-1.0,s{i}" for i in range(5)
    ]
    f.write_text("\n".join(rows) + "\n")
    assert main(["track", str(f), "--format", "csv"]) == 0
    err = capsys.readouterr().err
    assert "all 5 reports have the same time" in err
    # one id at one time at two positions (two pairs, ids s0 and s1)
    f = tmp_path / "dup.csv"
    text = _fleet(n_reports=30)
    text += "2020-01-01T00:00:10Z,50.3,-1.0,s0\n2020-01-01T00:01:10Z,50.4,-1.0,s1\n"
    f.write_text(text)
    assert main(["track", str(f), "--format", "csv"]) == 0
    err = capsys.readouterr().err
    assert "2 report pairs of 2 ids at one time differ in position" in err
    # a speed column in knots where m/s is expected: the ships move 1.812 m/s (11.12 m north
    # and 14.31 m east in 10 s), the column says 1.812 kn / (1852/3600) = 3.522 "m/s"
    f = tmp_path / "knots.csv"
    f.write_text(_fleet(n_reports=30, speed_col=1.812 * 3600 / 1852))
    assert main(["track", str(f), "--format", "csv"]) == 0
    err = capsys.readouterr().err
    assert "implausible speeds" in err
    assert "knots read as m/s" in err
    assert "1.94" in err
    assert "median of 87 moving reports; 87 differ" in err  # 29 intervals x 3 ids


def test_track_reports_rows_thousands_of_km_apart_with_counts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    def fleets(n_near: int, n_far: int) -> str:
        # ``n_near`` ships in the Channel, ``n_far`` off the Canaries (about 2600 km away)
        text = _fleet(n_ids=n_near, n_reports=30)
        for k in range(30):
            t = f"2020-01-01T00:{k // 6:02d}:{(k % 6) * 10:02d}Z"
            text += "".join(
                f"{t},{28.0 + 0.05 * i + 1e-4 * k},{-15.0 + 2e-4 * k},f{i}\n" for i in range(n_far)
            )
        return text

    f = tmp_path / "far.csv"
    f.write_text(fleets(3, 2))  # the far minority is skipped, counted and named
    assert main(["track", str(f), "--format", "csv"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"bad rows skipped +60\n", text)
    assert "position more than 1000 km from the median position: 60" in text
    assert re.search(r"ids / confirmed tracks +3 / 3\n", text)
    # two equal fleets: the median lies between them and every row is skipped, said so
    f.write_text(fleets(2, 2))
    assert main(["track", str(f), "--format", "csv"]) == 1
    text = capsys.readouterr().out
    assert "position more than 1000 km from the median position: 120" in text
    assert "no usable detections: all 120 rows were skipped" in text
    assert "--max-range-km" in text
    # a range limit beyond the spread tracks both fleets
    assert main(["track", str(f), "--format", "csv", "--max-range-km", "5000"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"bad rows skipped +0\n", text)
    assert re.search(r"ids / confirmed tracks +4 / 4\n", text)


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("SolentAIS_20160112_130211.csv", "ais"),
        ("OpenSky_Plane_States.csv", "opensky"),
        ("UAV_Rot.csv", "csv"),
    ],
)
def test_the_layout_is_read_from_the_header(shared_data: Path, name: str, expected: str) -> None:
    from navtrack.io.tracks import detect_format

    assert detect_format(shared_data / "tracking" / name) == expected


def test_track_maps_a_files_own_column_names(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The shared UAV log names its columns latitude/longitude/altitude (m): without a map the
    error names the missing columns; with ``--columns`` the one aircraft is tracked."""
    uav = str(shared_data / "tracking" / "UAV_Rot.csv")
    assert main(["track", uav, "--quiet"]) == 2
    assert "need columns lat, lon" in capsys.readouterr().err
    columns = "lat=latitude,lon=longitude,alt_m=altitude (m)"
    assert main(["track", uav, "--columns", columns, "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "format     csv (from the header" in out
    assert re.search(r"detections +965\n", out)
    assert re.search(r"tracks started / confirmed +1 / 1\n", out)
    assert main(["track", uav, "--columns", "lat=latitude,lon=longitud"]) == 2
    assert "missing column(s) ['longitud']" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="latt not among"):
        main(["track", uav, "--columns", "latt=latitude"])
    with pytest.raises(SystemExit, match="expected NAME=COLUMN"):
        main(["track", uav, "--columns", "latitude"])
    with pytest.raises(SystemExit, match="applies to --format csv"):
        main(["track", uav, "--format", "ais", "--columns", "lat=latitude"])


def test_track_example_runs_on_the_bundled_ais_cut(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["track", "--example", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "format     ais (from the header" in out
    assert re.search(r"detections +4320\n", out)
    assert re.search(r"ids +79\n", out)
    mota = float(re.search(r"MOTA +([-0-9.]+)", out).group(1))  # type: ignore[union-attr]
    assert 0.2 < mota <= 1.0  # scored against the hidden MMSIs


def test_track_file_has_exact_positions_speeds_and_a_track_table(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The OpenSky file spans 470 km: lat/lon written from the state must map back onto the
    # state (the exact inverse of the tangent plane); speed and course are the state's velocity
    # in each track's own north/east and agree with the transponders' reported heading; JPDA's
    # soft updates below 1/2 have rows; every track has one row in the table with its end.
    import json

    import pandas as pd

    from navtrack.geodesy import ecef_to_enu, geodetic_to_ecef

    src = shared_data / "tracking" / "OpenSky_Plane_States.csv"
    out = tmp_path / "t.csv"
    assert main(["track", str(src), "--associator", "jpda", "--quiet", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert re.search(r"IDF1 \(IDP, IDR\) +0\.\d+ \(0\.\d+, 0\.\d+\)", text)
    df = pd.read_csv(out)
    meta = json.loads(Path(f"{out}.json").read_text())
    lat0, lon0 = np.radians(meta["reference_lat_deg"]), np.radians(meta["reference_lon_deg"])
    n = len(df)
    xyz = geodetic_to_ecef(
        np.stack([np.radians(df.lat_deg), np.radians(df.lon_deg), np.zeros(n)], axis=1)
    )
    en = ecef_to_enu(xyz, geodetic_to_ecef([lat0, lon0, 0.0]))[:, :2]
    assert np.hypot(df.x_m, df.y_m).max() > 200e3  # far from the reference: a real test
    assert np.hypot(en[:, 0] - df.x_m, en[:, 1] - df.y_m).max() < 1e-3
    # course against the reported heading of the aircraft nearest each confirmed row
    raw = pd.read_csv(src)
    conf = df[df.confirmed & (df.speed_mps > 50)]
    epoch = pd.Timestamp("1970-01-01", tz="UTC")
    t_row = (pd.to_datetime(conf.time) - epoch).dt.total_seconds().to_numpy()
    diffs = []
    for k in range(0, len(conf), 25):
        same = raw[np.abs(raw.time - t_row[k]) < 0.5]
        d = np.hypot(same.lat - conf.lat_deg.iloc[k], same.lon - conf.lon_deg.iloc[k])
        heading = same.heading.to_numpy()[np.argmin(d.to_numpy())]
        diffs.append((conf.course_deg.iloc[k] - heading + 180) % 360 - 180)
    assert np.median(np.abs(diffs)) < 3.0
    assert (df.p_update < 0.5).any()
    assert (df.p_update > 0).all()
    assert np.isfinite(df.alt_m[df.confirmed]).mean() > 0.9
    table = pd.read_csv(tmp_path / "t.tracks.csv")
    assert table.track_id.is_unique
    started_m = re.search(r"tracks started / confirmed +(\d+)", text)
    continued_m = re.search(r"tracks continuing an ended track +(\d+)", text)
    assert started_m
    assert continued_m
    started, continued = int(started_m.group(1)), int(continued_m.group(1))
    assert len(table) == started - continued  # a continuing track keeps the ended one's row
    assert set(table.end_reason) <= {"coast", "covariance", "unconfirmed", "end_of_data"}
    assert {"coast", "end_of_data"} <= set(table.end_reason)
