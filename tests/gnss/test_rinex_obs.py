"""RINEX observation reader: the shared real files, their traps, crafted edge cases, bad input,
and a value-by-value cross-check against georinex 1.16.2.

Reference counts (epochs, satellites, codes, spans) come from ``shared/data/gnss/README.md``,
written when the data were selected (RTKLIB 2.4.3 b34 and an independent parser read every file);
values of individual fields are checked against the text of the file itself (line numbers given).
"""

from __future__ import annotations

import gzip
import json
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rinex.obs_fields import decode_fields
from navtrack.timescale import calendar_gps_seconds, gps_seconds

# --------------------------------------------------------------------------- shared files

# (relative path, epochs, distinct satellites, (min, max) satellites per epoch, codes per system,
#  first epoch, last epoch (GPST), interval s): shared/data/gnss/README.md sections 1-4.
SHARED = {
    "0759": (
        "rtklib_gsi0759/07590920.05o",
        120,
        11,
        (7, 9),
        {"G": ("L1", "C1", "L2", "P2")},
        "2005-04-02T00:00:00",
        "2005-04-02T00:59:30.005",
        30.0,
    ),
    "ARL1": (
        "gpstk_arl1/arlm200a.15o",
        120,
        11,
        (8, 11),
        {"G": ("L1", "L2", "C1", "C2", "P1", "P2", "D1", "D2", "S1", "S2")},
        "2015-07-19T00:00:00",
        "2015-07-19T00:59:30",
        30.0,
    ),
    "SEPT": (
        "cssrlib_sept/SEPT078M.21O",
        900,
        26,
        (23, 26),
        {
            "G": tuple(
                [
                    "C1C",
                    "L1C",
                    "S1C",
                    "C1W",
                    "S1W",
                    "C2W",
                    "L2W",
                    "S2W",
                    "C2L",
                    "L2L",
                    "S2L",
                    "C5Q",
                    "L5Q",
                    "S5Q",
                ]
            ),
            "E": tuple(
                ["C1C", "L1C", "S1C", "C5Q", "L5Q", "S5Q", "C7Q", "L7Q", "S7Q", "C8Q", "L8Q", "S8Q"]
            ),
            "J": tuple(["C1C", "L1C", "S1C", "C2L", "L2L", "S2L", "C5Q", "L5Q", "S5Q"]),
        },
        "2021-03-19T12:00:00",
        "2021-03-19T12:14:59",
        1.0,
    ),
    "yamatogawa_rover": (
        "gogps_yamatogawa/yamatogawa_rover.obs",
        203,
        None,
        (8, 10),
        {"G": ("C1", "L1", "S1", "D1")},
        "2010-01-06T05:57:03",
        "2010-01-06T06:00:26",
        None,
    ),
    "yamatogawa_master": (
        "gogps_yamatogawa/yamatogawa_master.obs",
        193,
        9,
        (9, 9),
        {"G": ("C1", "P2", "L1", "L2", "S1", "S2")},
        "2010-01-06T05:57:14",
        "2010-01-06T06:00:26",
        None,
    ),
}


def _tracked(obs: Observations) -> np.ndarray:
    """Satellites with at least one value, per epoch."""
    return np.isfinite(obs.values).any(axis=2).sum(axis=1)


@pytest.mark.parametrize("name", SHARED)
def test_shared_file_counts(gnss_data: Path, name: str) -> None:
    rel, n_epochs, n_sats, (lo, hi), codes, first, last, interval = SHARED[name]
    obs = read_obs(gnss_data / rel)
    assert len(obs.t_gps_s) == n_epochs
    if n_sats is not None:
        assert len(obs.sats) == n_sats
    tracked = _tracked(obs)
    assert tracked.min() == lo
    assert tracked.max() == hi
    assert dict(obs.header.obs_types) == codes
    assert obs.systems == "".join(codes)
    np.testing.assert_allclose(obs.t_gps_s[[0, -1]], gps_seconds([first, last]), atol=1e-6)
    assert obs.header.interval_s == interval
    assert obs.skipped == ()
    assert np.all(np.diff(obs.t_gps_s) > 0)
    if interval:
        assert np.allclose(np.round(np.diff(obs.t_gps_s)), interval)
    summary = json.loads(json.dumps(obs.summary()))  # JSON-serialisable as it is
    assert summary["n_epochs"] == n_epochs
    assert summary["sats_per_system"] == {s: sum(sat[0] == s for sat in obs.sats) for s in codes}
    assert summary["warnings"] == []


def test_yamatogawa_rover_sats(gnss_data: Path) -> None:
    # README: 8-10 GPS satellites; the epoch records list G02 G04 G05 G07 G10 G12 G13 G17 G23
    # (first epoch, line 13) plus others later.
    obs = read_obs(gnss_data / "gogps_yamatogawa/yamatogawa_rover.obs")
    first = [s for k, s in enumerate(obs.sats) if np.isfinite(obs.values[0, k]).any()]
    assert first == ["G02", "G04", "G05", "G07", "G10", "G12", "G13", "G17", "G23"]


def test_header_metadata(gnss_data: Path) -> None:
    # README section 1/2/3 and the header lines of each file.
    h = read_obs(gnss_data / "rtklib_gsi0759/07590920.05o").header
    assert (h.version, h.system, h.marker) == (2.10, "G", "0759")
    assert "TRIMBLE 5700" in h.receiver
    assert "TRM29659.00" in h.antenna
    np.testing.assert_array_equal(h.approx_xyz_m, [-3976219.5082, 3382372.5671, 3652512.9849])
    np.testing.assert_array_equal(h.antenna_delta_hen_m, [0.0, 0.0, 0.0])
    assert h.time_system == "GPS"
    h = read_obs(gnss_data / "gpstk_arl1/arlm200a.15o").header
    assert (h.version, h.marker, h.marker_number) == (2.11, "ARL1", "85408")
    assert "ITT MSN SAASM" in h.receiver
    h = read_obs(gnss_data / "cssrlib_sept/SEPT078M.21O").header
    assert (h.version, h.system, h.marker) == (3.04, "M", "SEPT")
    assert "SEPT MOSAIC-X5" in h.receiver
    assert "4.12.1" in h.receiver
    assert "JAVRINGANT_DM" in h.antenna
    assert h.last_obs_gps_s == pytest.approx(gps_seconds("2021-03-19T12:14:59"))


def test_0759_splices_and_off_grid_time_tags(gnss_data: Path) -> None:
    """README section 1: flag-4 'RINEX FILE SPLICE' comment records in the data section, and
    time tags 0-5 ms after the 30 s grid (00:48:00.004, 00:59:30.005)."""
    obs = read_obs(gnss_data / "rtklib_gsi0759/07590920.05o")
    assert [e.flag for e in obs.events] == [4, 4, 4]
    # The event records sit at lines 855, 1058 and 1090 of the file, one COMMENT each.
    assert [e.line for e in obs.events] == [855, 1058, 1090]
    for e in obs.events:
        assert len(e.records) == 1
        assert e.records[0].startswith("RINEX FILE SPLICE")
        assert e.records[0].endswith("COMMENT")
        assert np.isnan(e.t_gps_s)  # the splice records carry no time
    assert obs.summary()["events_by_flag"] == {"4": 3}
    off = obs.t_gps_s - np.round(obs.t_gps_s / 30.0) * 30.0
    assert off.min() >= -1e-7
    assert off.max() == pytest.approx(0.005, abs=1e-6)
    t = calendar_gps_seconds(2005, 4, 2, 0, 48, 0.004)
    k = int(np.argmin(np.abs(obs.t_gps_s - t)))
    assert obs.t_gps_s[k] == pytest.approx(t, abs=1e-6)
    # Line 857, the epoch after the first splice: 8 satellites G01 G04 G07 G11 G19 G20 G24 G28,
    # line 858: G01 L1 = 1600872.379, C1 = 25881667.680, L2 = 1244701.260 LLI 4, P2 = 25881665.610.
    listed = [s for j, s in enumerate(obs.sats) if np.isfinite(obs.values[k, j]).any()]
    assert listed == ["G01", "G04", "G07", "G11", "G19", "G20", "G24", "G28"]
    g01 = obs.sat_index("G01")
    np.testing.assert_array_equal(
        obs.values[k, g01], [1600872.379, 25881667.680, 1244701.260, 25881665.610]
    )
    np.testing.assert_array_equal(obs.lli[k, g01], [-1, -1, 4, 4])
    assert obs.summary()["last_epoch"] == "2005-04-02T00:59:30.005"


def test_lli_ssi_and_values_as_printed(gnss_data: Path) -> None:
    # yamatogawa_rover.obs lines 13-14: epoch 2010-01-06 05:57:03, first satellite G02:
    # "  21128675.686 7     -7818.26327        45.000 7      2781.846 7"
    obs = read_obs(gnss_data / "gogps_yamatogawa/yamatogawa_rover.obs")
    g02 = obs.sat_index("G02")
    np.testing.assert_array_equal(obs.values[0, g02], [21128675.686, -7818.263, 45.0, 2781.846])
    np.testing.assert_array_equal(obs.lli[0, g02], [-1, 2, -1, -1])
    np.testing.assert_array_equal(obs.ssi[0, g02], [7, 7, 7, 7])
    # SEPT078M.21O line 34: "E01  27530612.397 5 144674360.16505": C1C 27530612.397, LLI
    # blank, SSI 5; L1C 144674360.165, LLI 0, SSI 5.
    obs = read_obs(gnss_data / "cssrlib_sept/SEPT078M.21O")
    e01 = obs.sat_index("E01")
    assert obs.code("C1C")[0, e01] == 27530612.397
    assert obs.code("L1C")[0, e01] == 144674360.165
    k = obs.codes.index("L1C")
    assert (obs.lli[0, e01, k], obs.ssi[0, e01, k]) == (0, 5)
    assert (obs.lli[0, e01, 0], obs.ssi[0, e01, 0]) == (-1, 5)


def test_zero_means_missing(gnss_data: Path) -> None:
    """RINEX 2.11 table A2: missing observations are written as 0.0 or blanks. ARL1 writes C2
    as 0.000 for satellites without L2C (line 17: G02 "0.000" in the C2 column)."""
    obs = read_obs(gnss_data / "gpstk_arl1/arlm200a.15o")
    g02 = obs.sat_index("G02")
    assert np.isnan(obs.code("C2")[0, g02])
    assert obs.code("C1")[0, g02] == 21276226.827
    assert obs.code("P1")[0, g02] == 21276226.702
    assert not (obs.values == 0.0).any()


def test_sept_galileo_and_qzss_codes(gnss_data: Path) -> None:
    """README section 3: Galileo C1C/C5Q/C7Q/C8Q, QZSS C2L, no Doppler; codes of one system are
    NaN for the others."""
    obs = read_obs(gnss_data / "cssrlib_sept/SEPT078M.21O")
    gal = np.array([s[0] == "E" for s in obs.sats])
    gps = np.array([s[0] == "G" for s in obs.sats])
    qzs = np.array([s[0] == "J" for s in obs.sats])
    assert not any(c.startswith("D") for c in obs.codes)
    for c in ("C1C", "C5Q", "C7Q", "C8Q"):
        assert np.isfinite(obs.code(c)[:, gal]).any()
    for c in ("C7Q", "C8Q"):
        assert np.isnan(obs.code(c)[:, gps | qzs]).all()
    assert np.isnan(obs.code("C1W")[:, gal | qzs]).all()
    assert np.isfinite(obs.code("C2L")[:, qzs]).any()
    # Galileo E1 pseudoranges of a terrestrial receiver: 23 000-30 000 km.
    pr = obs.code("C1C")[:, gal]
    assert np.nanmin(pr) > 2.2e7
    assert np.nanmax(pr) < 3.0e7


def test_bundled_samples(gnss_data: Path) -> None:
    cut = read_obs(sample_path("SEPT078M_120.21O"))
    full = read_obs(gnss_data / "cssrlib_sept/SEPT078M.21O")
    assert len(cut.t_gps_s) == 120
    assert cut.summary()["last_epoch"] == "2021-03-19T12:01:59.000"
    assert cut.summary()["warnings"] == []
    cols = [full.sat_index(s) for s in cut.sats]
    assert cut.codes == full.codes
    np.testing.assert_array_equal(cut.values, full.values[:120][:, cols])
    np.testing.assert_array_equal(cut.lli, full.lli[:120][:, cols])
    bundled = read_obs(sample_path("07590920.05o"))
    shared = read_obs(gnss_data / "rtklib_gsi0759/07590920.05o")
    np.testing.assert_array_equal(bundled.values, shared.values)


def test_wrong_time_of_last_obs_is_reported(tmp_path: Path) -> None:
    """A cut file that kept its parent's TIME OF LAST OBS (12:14:59 instead of 12:01:59): the
    data decide, the summary warns."""
    text = sample_path("SEPT078M_120.21O").read_text()
    wrong = text.replace(
        "  2021     3    19    12     1    59.0000000     GPS         TIME OF LAST OBS",
        "  2021     3    19    12    14    59.0000000     GPS         TIME OF LAST OBS",
    )
    assert wrong != text
    path = tmp_path / "cut.21O"
    path.write_text(wrong)
    obs = read_obs(path)
    assert obs.t_gps_s[-1] == gps_seconds("2021-03-19T12:01:59")
    assert obs.header.last_obs_gps_s == gps_seconds("2021-03-19T12:14:59")
    warnings_ = obs.summary()["warnings"]
    assert len(warnings_) == 1
    assert "TIME OF LAST OBS" in warnings_[0]


# --------------------------------------------------------------------- compressed input


def _same(a: Observations, b: Observations) -> None:
    assert a.sats == b.sats
    assert a.codes == b.codes
    np.testing.assert_array_equal(a.t_gps_s, b.t_gps_s)
    np.testing.assert_array_equal(a.values, b.values)
    np.testing.assert_array_equal(a.lli, b.lli)
    np.testing.assert_array_equal(a.ssi, b.ssi)
    np.testing.assert_array_equal(a.clock_offset_s, b.clock_offset_s)


@pytest.mark.parametrize("name", ["07590920.05o", "SEPT078M_120.21O"])
def test_gzip_and_hatanaka_input(tmp_path: Path, name: str) -> None:
    hatanaka = pytest.importorskip("hatanaka")
    src = sample_path(name)
    plain = read_obs(src)
    gz = tmp_path / (name + ".gz")
    gz.write_bytes(gzip.compress(src.read_bytes()))
    _same(read_obs(gz), plain)
    for compression, suffix in (("none", ".crx"), ("gz", ".crx.gz"), ("Z", ".crx.Z")):
        crx = tmp_path / (name + suffix)
        crx.write_bytes(hatanaka.compress(src.read_bytes(), compression=compression))
        got = read_obs(crx)
        _same(got, plain)
        assert len(got.events) == len(plain.events)


# ------------------------------------------------------------------------- crafted files


def _h(content: str, label: str) -> str:
    return f"{content:<60}{label}"


def _v2_epoch(t: tuple, flag: int, sats: list[str], clock: float | None = None) -> list[str]:
    y, mo, d, h, mi, s = t
    head = f" {y % 100:02d} {mo:2d} {d:2d} {h:2d} {mi:2d}{s:11.7f}  {flag:1d}{len(sats):3d}"
    rows = []
    for k in range(0, max(len(sats), 1), 12):
        ids = "".join(sats[k : k + 12])
        start = head if k == 0 else " " * 32
        line = f"{start}{ids:<36}"
        if k == 0 and clock is not None:
            line += f"{clock:12.9f}"
        rows.append(line.rstrip())
    return rows


def _field(v: float | None, lli: str = " ", ssi: str = " ") -> str:
    return (" " * 14 if v is None else f"{v:14.3f}") + lli + ssi


def _v2_header(codes: list[str], system: str = "G", extra: Sequence[str] = ()) -> list[str]:
    rows = [
        _h(f"{'2.11':>9}{'':11}{'OBSERVATION DATA':<20}{system:<20}", "RINEX VERSION / TYPE"),
        _h("CRAFTED", "MARKER NAME"),
    ]
    for k in range(0, len(codes), 9):
        lead = f"{len(codes):6d}" if k == 0 else " " * 6
        rows.append(_h(lead + "".join(f"{c:>6}" for c in codes[k : k + 9]), "# / TYPES OF OBSERV"))
    rows += list(extra)
    rows.append(_h("", "END OF HEADER"))
    return rows


def _v2_records(values: np.ndarray, lli: str = " ", ssi: str = " ") -> list[str]:
    """Data lines of one satellite: 5 fields per line."""
    fields = [_field(None if np.isnan(v) else v, lli, ssi) for v in values]
    return [("".join(fields[k : k + 5])).rstrip() for k in range(0, len(fields), 5)]


def test_rinex2_continuation_lines(tmp_path: Path) -> None:
    """13 satellites (two satellite-list lines), 7 observation types (two header lines, two data
    lines per satellite), receiver clock offset, a power-failure epoch (flag 1)."""
    rng = np.random.default_rng(1)
    codes = ["C1", "L1", "D1", "S1", "P2", "L2", "C5"]
    sats = [f"G{k:02d}" for k in range(1, 12)] + ["R07", " 32"]  # blank system letter = GPS
    vals = np.round(rng.uniform(-3e7, 3e7, (2, 13, 7)), 3)
    vals[1, 3, 2] = np.nan
    rows = _v2_header(codes)
    for e, (flag, clock) in enumerate([(0, 0.000123456), (1, None)]):
        rows += _v2_epoch((2020, 5, 17, 1, 2, 3.5 + e), flag, sats, clock)
        for j in range(13):
            rows += _v2_records(vals[e, j], lli="1" if j == 0 else " ", ssi="6")
    path = tmp_path / "cont.20o"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    assert obs.codes == tuple(codes)
    order = [obs.sat_index(s if s != " 32" else "G32") for s in sats]
    # The text written has 3 decimals, so the values read are exactly the rounded ones.
    np.testing.assert_array_equal(obs.values[:, order], vals)
    assert obs.sats == tuple(sorted(s if s != " 32" else "G32" for s in sats))
    np.testing.assert_array_equal(obs.epoch_flag, [0, 1])
    np.testing.assert_array_equal(obs.clock_offset_s, [0.000123456, np.nan])
    assert obs.lli[0, order[0]].tolist() == [1] * 7
    assert obs.lli[0, order[1]].tolist() == [-1] * 7
    assert (obs.ssi[0][order][~np.isnan(vals[0])] == 6).all()
    t0 = calendar_gps_seconds(2020, 5, 17, 1, 2, 3.5)
    np.testing.assert_array_equal(obs.t_gps_s, [t0, t0 + 1])
    assert dict(obs.header.obs_types) == {"G": tuple(codes), "R": tuple(codes)}


def test_rinex2_events_and_new_obs_types(tmp_path: Path) -> None:
    """Flags 2, 3, 5 are kept as events; a flag-4 record with '# / TYPES OF OBSERV' changes the
    codes of the following epochs."""
    rows = _v2_header(["C1", "L1"])
    rows += _v2_epoch((2020, 1, 1, 0, 0, 0.0), 0, ["G01"])
    rows += _v2_records(np.array([20000000.123, 1.5]))
    rows += _v2_epoch((2020, 1, 1, 0, 0, 0.5), 5, [])  # external event at a time, no records
    rows[-1] = rows[-1][:29] + "  0"
    rows.append(" " * 28 + "2  1")  # start moving, one comment
    rows.append(_h("START MOVING", "COMMENT"))
    rows.append(" " * 28 + "3  1")  # new site
    rows.append(_h("ROVER", "MARKER NAME"))
    rows.append(" " * 28 + "4  2")
    rows.append(_h("     3    P2    C1    S1", "# / TYPES OF OBSERV"))
    rows.append(_h("new types", "COMMENT"))
    rows += _v2_epoch((2020, 1, 1, 0, 0, 1.0), 0, ["G01", "G02"])
    rows += _v2_records(np.array([20000001.5, 20000002.25, 45.0]))
    rows += _v2_records(np.array([np.nan, 21000000.0, 40.0]))
    path = tmp_path / "events.20o"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    assert [e.flag for e in obs.events] == [5, 2, 3, 4]
    assert obs.events[0].t_gps_s == calendar_gps_seconds(2020, 1, 1, 0, 0, 0.5)
    assert np.isnan(obs.events[1].t_gps_s)
    assert obs.events[2].records[0].startswith("ROVER")
    assert obs.summary()["events_by_flag"] == {"5": 1, "2": 1, "3": 1, "4": 1}
    assert obs.codes == ("C1", "L1", "P2", "S1")
    assert len(obs.t_gps_s) == 2
    g01, g02 = obs.sat_index("G01"), obs.sat_index("G02")
    np.testing.assert_array_equal(obs.values[0, g01], [20000000.123, 1.5, np.nan, np.nan])
    np.testing.assert_array_equal(obs.values[1, g01], [20000002.25, np.nan, 20000001.5, 45.0])
    np.testing.assert_array_equal(obs.values[1, g02], [21000000.0, np.nan, np.nan, 40.0])


@pytest.mark.parametrize(
    ("system", "time_field", "shift_s"),
    [
        ("G", "GPS", 0.0),
        ("R", "GLO", 18.0),
        ("R", "   ", 18.0),
        ("M", "GLO", 18.0),
        ("M", "   ", 0.0),
    ],
)
def test_rinex2_time_systems(tmp_path: Path, system: str, time_field: str, shift_s: float) -> None:
    """RINEX 2.11 section 8.1.1 / table A1: GLO time tags are UTC; a GLONASS-only file with a
    blank time system is in GLO time, a mixed one in GPS time. GPST - UTC = 18 s in 2020."""
    first = _h(
        f"{2020:6d}{1:6d}{1:6d}{0:6d}{0:6d}{0.0:13.7f}     {time_field}", "TIME OF FIRST OBS"
    )
    rows = _v2_header(["C1"], system=system, extra=[first])
    rows += _v2_epoch((2020, 1, 1, 0, 0, 0.0), 0, ["R01"]) + _v2_records(np.array([2.0e7]))
    obs = read_obs(_write(tmp_path, "t.20o", rows))
    assert obs.t_gps_s[0] == calendar_gps_seconds(2020, 1, 1, 0, 0, 0.0) + shift_s
    assert obs.header.first_obs_gps_s == obs.t_gps_s[0]


def _v3_header(
    types: dict[str, list[str]], time_system: str = "GPS", extra: Sequence[str] = ()
) -> list[str]:
    rows = [_h(f"{'3.05':>9}{'':11}{'OBSERVATION DATA':<20}{'M':<20}", "RINEX VERSION / TYPE")]
    for sys, codes in types.items():
        for k in range(0, len(codes), 13):
            lead = f"{sys}  {len(codes):3d}" if k == 0 else " " * 6
            rows.append(
                _h(lead + "".join(f" {c}" for c in codes[k : k + 13]), "SYS / # / OBS TYPES")
            )
    rows.append(
        _h(f"{2021:6d}{1:6d}{1:6d}{0:6d}{0:6d}{0.0:13.7f}     {time_system}", "TIME OF FIRST OBS")
    )
    rows += list(extra)
    rows.append(_h("", "END OF HEADER"))
    return rows


def _v3_epoch(t: tuple, flag: int, n: int, clock: float | None = None) -> str:
    y, mo, d, h, mi, s = t
    line = f"> {y:4d} {mo:02d} {d:02d} {h:02d} {mi:02d}{s:11.7f}  {flag:1d}{n:3d}"
    if clock is not None:
        line += f"{'':6}{clock:15.12f}"
    return line


def test_rinex3_multiline_types_systems_scale_and_clock(tmp_path: Path) -> None:
    """14 GPS types (a continuation header line), BeiDou, GLONASS, SBAS and NavIC satellites,
    a SYS / SCALE FACTOR, a receiver clock offset."""
    g = [
        "C1C",
        "L1C",
        "D1C",
        "S1C",
        "C2W",
        "L2W",
        "D2W",
        "S2W",
        "C5Q",
        "L5Q",
        "D5Q",
        "S5Q",
        "C1W",
        "S1W",
    ]
    types = {"G": g, "R": ["C1C", "L1C"], "C": ["C2I", "L2I"], "S": ["C1C"], "I": ["C5A"]}
    extra = [_h("G   10   2 L1C L2W", "SYS / SCALE FACTOR")]
    rows = _v3_header(types, extra=extra)
    rows.append(_v3_epoch((2021, 1, 1, 0, 0, 0.0), 0, 5, clock=-0.000012345678))
    gv = np.round(np.linspace(1.0, 2.6e7, 14), 3)
    rows.append("G05" + "".join(_field(v, " ", "7") for v in gv))
    rows.append("R07" + _field(19100000.5) + _field(102000000.25, "1", "5"))
    rows.append("C20" + _field(None) + _field(-5.125, "2"))
    rows.append("S29" + _field(38000000.0))
    rows.append("I05" + _field(36000000.75))
    path = tmp_path / "multi.rnx"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    assert obs.sats == ("C20", "G05", "I05", "R07", "S29")
    assert obs.systems == "GRCSI"
    want = gv.copy()
    want[[1, 5]] /= 10.0  # L1C and L2W are written x10
    k = [obs.codes.index(c) for c in g]
    np.testing.assert_array_equal(obs.values[0, obs.sat_index("G05"), k], want)
    assert obs.code("L1C")[0, obs.sat_index("R07")] == 102000000.25  # no scale for GLONASS
    assert obs.lli[0, obs.sat_index("R07"), obs.codes.index("L1C")] == 1
    assert obs.code("L2I")[0, obs.sat_index("C20")] == -5.125
    assert np.isnan(obs.code("C2I")[0, obs.sat_index("C20")])
    assert obs.code("C5A")[0, obs.sat_index("I05")] == 36000000.75
    assert obs.clock_offset_s[0] == -0.000012345678


@pytest.mark.parametrize("version", ["3.00", "3.02", "3.03", "3.05", "4.00", "4.01"])
def test_rinex3_and_4_versions(tmp_path: Path, version: str) -> None:
    rows = _v3_header({"G": ["C1C"], "E": ["C1X"]})
    rows[0] = f"{version:>9}" + rows[0][9:]
    rows += [_v3_epoch((2021, 1, 1, 0, 0, 0.0), 0, 2), "G01" + _field(2.0e7), "E11" + _field(2.5e7)]
    obs = read_obs(_write(tmp_path, "v.rnx", rows))
    assert obs.header.version == float(version)
    assert obs.code("C1X")[0, obs.sat_index("E11")] == 2.5e7


@pytest.mark.parametrize(
    ("time_system", "shift_s"),
    [("GPS", 0.0), ("GAL", 0.0), ("BDT", 14.0), ("GLO", 18.0), ("UTC", 18.0)],
)
def test_rinex3_time_systems(tmp_path: Path, time_system: str, shift_s: float) -> None:
    # BDT = GPST - 14 s (BDS-SIS-ICD); GLO time tags are UTC (RINEX 3.05 section 6.1) and
    # GPST - UTC = 18 s in 2021 (IERS Bulletin C).
    rows = _v3_header({"G": ["C1C"]}, time_system=time_system)
    rows += [_v3_epoch((2021, 1, 1, 0, 0, 0.0), 0, 1), "G01" + _field(2.0e7)]
    path = tmp_path / "ts.rnx"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    assert obs.header.time_system == time_system
    assert obs.t_gps_s[0] == calendar_gps_seconds(2021, 1, 1, 0, 0, 0.0) + shift_s


def test_rinex3_event_with_new_obs_types_and_flag6(tmp_path: Path) -> None:
    rows = _v3_header({"G": ["C1C", "L1C"], "E": ["C1X"]})
    rows += [
        _v3_epoch((2021, 1, 1, 0, 0, 0.0), 0, 2),
        "G01" + _field(2.0e7) + _field(1.0),
        "E11" + _field(2.5e7),
    ]
    rows += [
        _v3_epoch((2021, 1, 1, 0, 0, 0.0), 4, 2).replace("2021 01 01 00 00  0.0000000", " " * 27),
        _h("G    1 C2W", "SYS / # / OBS TYPES"),
        _h("> not an epoch", "COMMENT"),
    ]
    rows += [_v3_epoch((2021, 1, 1, 0, 0, 1.0), 6, 1), "G01" + _field(3.0)]
    rows += [_v3_epoch((2021, 1, 1, 0, 0, 2.0), 0, 2), "G01" + _field(2.1e7), "E11" + _field(2.6e7)]
    path = tmp_path / "ev.rnx"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    assert obs.codes == ("C1C", "L1C", "C1X", "C2W")
    np.testing.assert_array_equal(obs.epoch_flag, [0, 6, 0])
    assert len(obs.events) == 1
    assert obs.events[0].records[1].startswith("> not an epoch")
    g01 = obs.sat_index("G01")
    np.testing.assert_array_equal(obs.values[:, g01, 3], [np.nan, 3.0, 2.1e7])
    np.testing.assert_array_equal(obs.values[:, g01, 0], [2.0e7, np.nan, np.nan])
    assert obs.code("C1X")[2, obs.sat_index("E11")] == 2.6e7


def test_nonstandard_field_layouts(tmp_path: Path) -> None:
    """Fields not in the F14.3 layout still read as the number written (fallback path)."""
    rows = _v3_header({"G": ["C1C", "L1C", "S1C", "D1C", "C2C"]})
    fields = [
        "  20000000.1234 ",  # F14.3 + LLI 4
        "1234567.89      ",  # left-justified
        "           -.5  ",  # decimal point elsewhere, no leading zero
        "        -0.000  ",
        "     1.5D+03    ",  # Fortran D exponent
    ]
    assert all(len(f) == 16 for f in fields)
    rows += [_v3_epoch((2021, 1, 1, 0, 0, 0.0), 0, 1), "G01" + "".join(fields)]
    path = tmp_path / "odd.rnx"
    path.write_text("\n".join(rows) + "\n")
    obs = read_obs(path)
    got = obs.values[0, 0]
    # "-0.000" is 0.0, which RINEX uses for "missing": NaN.
    np.testing.assert_array_equal(got, [20000000.123, 1234567.89, -0.5, np.nan, 1500.0])
    assert obs.lli[0, 0, 0] == 4


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.integers(-(10**12) + 1, 10**13 - 1).map(lambda n: f"{n / 1000:14.3f}"),
            st.just(" " * 14),
            st.floats(-1e6, 1e7, allow_nan=False).map(lambda x: f"{x:14.5f}"[:14]),
        ),
        min_size=1,
        max_size=30,
    ),
    st.sampled_from([" ", "0", "1", "7"]),
)
def test_decode_equals_python_float(texts: list[str], ind: str) -> None:
    """The vectorised decoder agrees with ``float(text)`` on every field (property)."""
    fields = np.frombuffer("".join(t + ind + ind for t in texts).encode(), dtype=np.uint8)
    value, lli, _ssi, _blank, bad = decode_fields(fields.reshape(-1, 16))
    want = [float(t) if t.strip() else np.nan for t in texts]
    np.testing.assert_array_equal(value, want)
    assert not bad.any()
    assert (lli == (-1 if ind == " " else int(ind))).all()


@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.text(alphabet=" 0123456789-.", min_size=14, max_size=14),
            st.text(alphabet=" 0123456789-.+eEx", min_size=14, max_size=14),
            st.builds(
                lambda k, tail: (" " * k + tail)[-14:].rjust(14),
                st.integers(0, 14),
                st.text(alphabet="0123456789-. ", min_size=0, max_size=14),
            ),
        ),
        min_size=1,
        max_size=30,
    )
)
def test_decode_accepts_exactly_the_numbers(texts: list[str]) -> None:
    """Arbitrary 14-character texts: a number is read as ``float(text)``, blanks as NaN, and
    anything else is flagged bad; the fast path never accepts a text Python rejects."""
    fields = np.frombuffer("".join(t + "  " for t in texts).encode(), dtype=np.uint8)
    value, _, _, blank, bad = decode_fields(fields.reshape(-1, 16))
    for k, text in enumerate(texts):
        if not text.strip():
            assert blank[k]
            assert not bad[k]
            assert np.isnan(value[k])
            continue
        assert not blank[k]
        try:
            want = float(text)
        except ValueError:
            assert bad[k], text
            continue
        assert not bad[k], text
        assert value[k] == want or (np.isnan(want) and np.isnan(value[k])), text


_POOL = [f"{s}{n:02d}" for s in "GREJCSI" for n in (1, 2, 7, 11, 24, 32)]


@st.composite
def _observation_sets(draw: st.DrawFn, v3: bool) -> dict:
    """Random epochs x satellites x codes with missing values and indicators."""
    n_epochs = draw(st.integers(1, 3))
    sats = draw(st.lists(st.sampled_from(_POOL), min_size=1, max_size=16, unique=True))
    if v3:
        types = {
            sys: draw(
                st.lists(
                    st.sampled_from(["C1C", "L1C", "S1C", "C2W", "L5Q", "C7I", "D1C"]),
                    min_size=1,
                    max_size=7,
                    unique=True,
                )
            )
            for sys in sorted({s[0] for s in sats})
        }
    else:
        codes = draw(
            st.lists(
                st.sampled_from(
                    ["C1", "P1", "L1", "L2", "P2", "S1", "S2", "D1", "C5", "L5", "D2", "C2"]
                ),
                min_size=1,
                max_size=12,
                unique=True,
            )
        )
        types = {"G": codes}
    number = st.one_of(
        st.none(), st.integers(-(10**12) + 1, 10**13 - 1).filter(bool).map(lambda n: n / 1000)
    )
    ind = st.sampled_from(" 0123456789")
    epochs = []
    for _ in range(n_epochs):
        present = [s for s in sats if draw(st.booleans())] or sats[:1]
        rows = {}
        for sat in present:
            codes = types[sat[0]] if v3 else types["G"]
            rows[sat] = [(draw(number), draw(ind), draw(ind)) for _ in codes]
        epochs.append(rows)
    return {"types": types, "epochs": epochs}


def _write_obs(path: Path, obs_set: dict, v3: bool) -> None:
    types, rows = obs_set["types"], []
    rows = _v3_header(types) if v3 else _v2_header(types["G"], system="M")
    for e, epoch in enumerate(obs_set["epochs"]):
        t = (2021, 1, 1, 0, 0, float(e))
        if v3:
            rows.append(_v3_epoch(t, 0, len(epoch)))
        else:
            rows += _v2_epoch(t, 0, list(epoch))
        for sat, fields in epoch.items():
            text = [_field(v, lli, ssi) for v, lli, ssi in fields]
            if v3:
                rows.append((sat + "".join(text)).rstrip())
            else:
                rows += ["".join(text[k : k + 5]).rstrip() for k in range(0, len(text), 5)]
    path.write_text("\n".join(rows) + "\n")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)  # the one file in tmp_path is rewritten by every example
@given(st.data())
@pytest.mark.parametrize("v3", [False, True])
def test_round_trip_random_files(tmp_path: Path, v3: bool, data: st.DataObject) -> None:
    """Any file written by the RINEX 2/3 layout rules reads back field by field (multi-line
    records, > 12 satellites, blank lines of missing observations, indicators)."""
    obs_set = data.draw(_observation_sets(v3))
    path = tmp_path / ("r.rnx" if v3 else "r.21o")
    _write_obs(path, obs_set, v3)
    obs = read_obs(path)
    assert len(obs.t_gps_s) == len(obs_set["epochs"])
    seen = set()
    for e, epoch in enumerate(obs_set["epochs"]):
        for sat, fields in epoch.items():
            codes = obs_set["types"][sat[0]] if v3 else obs_set["types"]["G"]
            s = obs.sat_index(sat)
            seen.add(sat)
            for code, (v, lli, ssi) in zip(codes, fields, strict=True):
                c = obs.codes.index(code)
                got = obs.values[e, s, c]
                assert (np.isnan(got) and v is None) or got == v
                assert obs.lli[e, s, c] == (-1 if lli == " " else int(lli))
                assert obs.ssi[e, s, c] == (-1 if ssi == " " else int(ssi))
    assert set(obs.sats) == seen
    n_written = sum(
        v is not None for epoch in obs_set["epochs"] for f in epoch.values() for v, _, _ in f
    )
    assert int(np.isfinite(obs.values).sum()) == n_written


# ----------------------------------------------------------------------------- bad input


def _write(tmp_path: Path, name: str, lines: list[str]) -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def _lines(name: str) -> list[str]:
    return sample_path(name).read_text().splitlines()


def _raises_at(path: Path, line: int, match: str, lenient: bool = False) -> None:
    with pytest.raises(FileFormatError, match=match) as info:
        read_obs(path, lenient=lenient)
    assert info.value.line == line
    assert info.value.path == str(path)
    assert str(path) in str(info.value)
    assert f"line {line}" in str(info.value)


def test_header_only_file(tmp_path: Path) -> None:
    """A header without epochs is a valid, empty file: zero epochs, and the summary says so."""
    obs = read_obs(_write(tmp_path, "h.o", _lines("SEPT078M_120.21O")[:33]))
    assert obs.values.shape == (0, 0, 20)
    assert obs.summary()["warnings"] == ["no observation epochs"]


def test_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.o"
    path.write_bytes(b"")
    _raises_at(path, 1, "empty")
    path.write_bytes(b"\n  \n")
    _raises_at(path, 1, "empty")


def test_unknown_version(tmp_path: Path) -> None:
    rows = _lines("07590920.05o")
    rows[0] = "     9.99" + rows[0][9:]
    _raises_at(_write(tmp_path, "v.o", rows), 1, "version")


def test_not_an_observation_file(tmp_path: Path) -> None:
    _raises_at(sample_path("07590920.05n"), 1, "not a RINEX observation file")


def test_missing_end_of_header(tmp_path: Path) -> None:
    rows = _lines("07590920.05o")
    assert rows[16].strip() == "END OF HEADER"
    del rows[16]
    _raises_at(_write(tmp_path, "h.o", rows), 17, "END OF HEADER", lenient=True)
    rows = _lines("SEPT078M_120.21O")[:20]  # header cut short
    _raises_at(_write(tmp_path, "h3.o", rows), 20, "END OF HEADER")


def test_missing_obs_types(tmp_path: Path) -> None:
    """A header without its observation-types record is refused at END OF HEADER, naming the
    record, even when reading leniently (no data line could be decoded)."""
    rows = _lines("07590920.05o")
    assert rows[11].endswith("# / TYPES OF OBSERV")
    del rows[11]
    assert rows[15].strip() == "END OF HEADER"
    path = _write(tmp_path, "t.o", rows)
    for lenient in (False, True):
        _raises_at(path, 16, "no '# / TYPES OF OBSERV' record in the header", lenient=lenient)
    rows = _lines("SEPT078M_120.21O")
    kept = [r for r in rows if not r.endswith("SYS / # / OBS TYPES")]
    assert len(rows) - len(kept) == 4  # G (2 lines), E, J
    assert kept[28].strip() == "END OF HEADER"
    path = _write(tmp_path, "t3.o", kept)
    for lenient in (False, True):
        _raises_at(path, 29, "no 'SYS / # / OBS TYPES' record in the header", lenient=lenient)


def test_obs_type_count_mismatch(tmp_path: Path) -> None:
    rows = _lines("07590920.05o")
    assert rows[11].startswith("     4    L1")
    rows[11] = "     5" + rows[11][6:]
    _raises_at(_write(tmp_path, "n.o", rows), 12, "5 observation types announced")


def test_truncated_file(tmp_path: Path) -> None:
    # RINEX 2: line 36 is the epoch record of 00:02:00 with 8 satellites; keep 2 data lines.
    rows = _lines("07590920.05o")[:38]
    path = _write(tmp_path, "cut.o", rows)
    _raises_at(path, 36, "announces 8 satellites")
    obs = read_obs(path, lenient=True)
    assert len(obs.t_gps_s) == 3
    assert [s.line for s in obs.skipped] == [36]
    assert np.isfinite(obs.values[2]).any(axis=1).sum() == 2
    # RINEX 3: the epoch record at line 298 announces 23 satellites; keep 2.
    rows = _lines("SEPT078M_120.21O")[:300]
    assert rows[297].startswith("> 2021 03 19 12 00 11")
    path = _write(tmp_path, "cut3.o", rows)
    _raises_at(path, 298, "announces 23 satellites")
    obs = read_obs(path, lenient=True)
    assert [s.line for s in obs.skipped] == [298]
    assert len(obs.t_gps_s) == 12


def test_missing_data_line_mid_file(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    del rows[40]  # one satellite of the first epoch (line 34) is gone
    path = _write(tmp_path, "gap3.o", rows)
    _raises_at(path, 34, "announces 23 satellites but only 22")
    obs = read_obs(path, lenient=True)
    assert len(obs.t_gps_s) == 120
    assert [s.line for s in obs.skipped] == [34]
    rows = _lines("07590920.05o")
    del rows[20]  # RINEX 2: the next epoch record would be read as a data line
    path = _write(tmp_path, "gap2.o", rows)
    _raises_at(path, 18, "line 26, read as its data, is an epoch")
    # Lenient: the whole epoch goes (its satellites cannot be matched to its lines), the rest
    # is read as usual.
    obs = read_obs(path, lenient=True)
    assert [s.line for s in obs.skipped] == list(range(18, 26))
    assert "epoch dropped" in obs.skipped[0].reason
    plain = read_obs(sample_path("07590920.05o"))
    np.testing.assert_array_equal(obs.t_gps_s, plain.t_gps_s[1:])
    np.testing.assert_array_equal(obs.values, plain.values[1:])


def test_surplus_data_line(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    rows.insert(35, "E02" + rows[34][3:])  # a 24th satellite line after an epoch announcing 23
    path = _write(tmp_path, "s3.o", rows)
    _raises_at(path, 34, "announces 23 satellites but 24 data lines follow")
    obs = read_obs(path, lenient=True)
    assert [s.line for s in obs.skipped] == [58]
    # The first 23 lines are read (E02 included); the last one, line 58, is dropped.
    assert obs.code("C1C")[0, obs.sat_index("E02")] == obs.code("C1C")[0, obs.sat_index("E01")]
    assert np.isnan(obs.values[0, obs.sat_index(rows[57][:3])]).all()


def test_garbage_in_data_line(tmp_path: Path) -> None:
    rows = _lines("07590920.05o")
    assert rows[18].startswith("  55923622.160")
    rows[18] = rows[18].replace("24767684.822", "2476x684.822")
    path = _write(tmp_path, "g.o", rows)
    _raises_at(path, 19, "malformed observation field")
    obs = read_obs(path, lenient=True)
    assert [(s.line, "malformed observation field" in s.reason) for s in obs.skipped] == [
        (19, True)
    ]
    plain = read_obs(sample_path("07590920.05o"))
    g03 = obs.sat_index("G03")
    assert np.isnan(obs.values[0, g03]).all()  # the whole damaged line is dropped
    mask = np.ones(obs.values.shape, dtype=bool)
    mask[0, g03] = False
    np.testing.assert_array_equal(obs.values[mask], plain.values[mask])
    # A bad LLI character is garbage too.
    rows = _lines("SEPT078M_120.21O")
    rows[40] = rows[40][:17] + "x" + rows[40][18:]
    _raises_at(_write(tmp_path, "g3.o", rows), 41, "malformed observation field")


def test_unknown_system_letter(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    assert rows[43].startswith("G01")
    rows[43] = "X01" + rows[43][3:]
    path = _write(tmp_path, "x3.o", rows)
    _raises_at(path, 44, "unknown satellite system 'X'")
    obs = read_obs(path, lenient=True)
    assert [s.line for s in obs.skipped] == [44]
    rows = _lines("07590920.05o")
    rows[17] = rows[17].replace("G 3G 7", "G 3X 7")
    path = _write(tmp_path, "x2.o", rows)
    _raises_at(path, 18, "unknown satellite system 'X'")  # in the epoch record, line 18
    obs = read_obs(path, lenient=True)
    assert [s.line for s in obs.skipped] == [20]  # X07's data line is what is skipped
    rows = _lines("SEPT078M_120.21O")
    assert rows[12].endswith("SYS / # / OBS TYPES")
    rows[12] = "X" + rows[12][1:]
    _raises_at(_write(tmp_path, "xh.o", rows), 13, "unknown satellite system")


def test_satellite_list_shorter_than_announced(tmp_path: Path) -> None:
    rows = _lines("07590920.05o")
    rows[17] = rows[17][:-3]  # 8 satellites announced, 7 listed
    _raises_at(_write(tmp_path, "x2b.o", rows), 18, "malformed satellite id")


def test_blank_line_inside_rinex3_data(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    rows[43] = ""
    _raises_at(_write(tmp_path, "b.o", rows), 44, "in satellite id")


def test_system_without_obs_types(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    rows[43] = "R01" + rows[43][3:]
    _raises_at(_write(tmp_path, "r.o", rows), 44, "no observation types")


def test_too_many_fields_and_duplicates(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    rows[34] = rows[34].ljust(3 + 16 * 12) + "  27530613.943 6"  # E01: 13 fields, 12 declared
    _raises_at(_write(tmp_path, "f.o", rows), 35, "more observations")
    rows = _lines("SEPT078M_120.21O")
    rows[35] = rows[34]  # E01 twice in the first epoch
    _raises_at(_write(tmp_path, "d.o", rows), 36, "twice")


def test_malformed_epoch_record(tmp_path: Path) -> None:
    rows = _lines("SEPT078M_120.21O")
    rows[33] = rows[33][:20] + "xx" + rows[33][22:]
    path = _write(tmp_path, "e3.o", rows)
    _raises_at(path, 34, "malformed epoch record")
    obs = read_obs(path, lenient=True)
    assert len(obs.t_gps_s) == 119
    assert obs.skipped[0].line == 34
    assert len(obs.skipped) == 24
    rows = _lines("07590920.05o")
    rows[17] = rows[17][:28] + "9" + rows[17][29:]
    _raises_at(_write(tmp_path, "e2.o", rows), 18, "malformed epoch record")


def test_crlf_line_ends(tmp_path: Path) -> None:
    src = sample_path("07590920.05o").read_bytes()
    path = tmp_path / "crlf.o"
    path.write_bytes(src.replace(b"\n", b"\r\n"))
    _same(read_obs(path), read_obs(sample_path("07590920.05o")))


def _reference_read(path: Path) -> tuple[list[float], dict[tuple[int, str, str], tuple]]:
    """A deliberately plain line-by-line reader written from the RINEX 2.11/3.05 tables, used
    as an independent oracle for LLI/SSI of every code (georinex exposes only some of them).

    Returns epoch calendar seconds and {(epoch, sat, code): (value, lli, ssi)} for every field
    that is not blank.
    """
    lines = path.read_text().splitlines()
    v3 = float(lines[0][:9]) >= 3
    types: dict[str, list[str]] = {}
    k = 0
    system = ""
    while lines[k][60:].strip() != "END OF HEADER":
        label = lines[k][60:].strip()
        if label == "SYS / # / OBS TYPES":
            system = lines[k][0] if lines[k][0] != " " else system
            types.setdefault(system, []).extend(lines[k][7:60].split())
        elif label == "# / TYPES OF OBSERV":
            types.setdefault("G", []).extend(lines[k][6:60].split())
        k += 1
    k += 1
    times: list[float] = []
    out: dict[tuple[int, str, str], tuple] = {}

    def field(text: str, j: int) -> tuple | None:
        f = text[16 * j : 16 * j + 16].ljust(16)
        if not f.strip():
            return None
        lli = int(f[14]) if f[14].strip() else -1
        ssi = int(f[15]) if f[15].strip() else -1
        return (float(f[:14]) if f[:14].strip() else np.nan, lli, ssi)

    while k < len(lines):
        rec = lines[k]
        if v3:
            flag, n = int(rec[31]), int(rec[32:35])
            if flag > 1:
                k += 1 + n
                continue
            y, mo, d, h, mi = (int(x) for x in rec[1:18].split())
            times.append(calendar_gps_seconds(y, mo, d, h, mi, float(rec[18:29])))
            for row in lines[k + 1 : k + 1 + n]:
                sat = row[:3]
                for j, code in enumerate(types[sat[0]]):
                    got = field(row[3:], j)
                    if got:
                        out[(len(times) - 1, sat, code)] = got
            k += 1 + n
        else:
            flag, n = int(rec[28]), int(rec[29:32])
            if flag > 1:
                k += 1 + n
                continue
            y, mo, d, h, mi = (int(x) for x in rec[1:15].split())
            times.append(
                calendar_gps_seconds(
                    2000 + y if y < 80 else 1900 + y, mo, d, h, mi, float(rec[15:26])
                )
            )
            sats = []
            for c in range(0, n, 12):
                sats += [lines[k + c // 12][32 + 3 * m : 35 + 3 * m] for m in range(min(12, n - c))]
            k += (n + 11) // 12
            per = (len(types["G"]) + 4) // 5
            for sat in sats:
                sat = ("G" if sat[0] == " " else sat[0]) + sat[1:].replace(" ", "0")
                for j, code in enumerate(types["G"]):
                    got = field(lines[k + j // 5], j % 5)
                    if got:
                        out[(len(times) - 1, sat, code)] = got
                k += per
    return times, out


@pytest.mark.parametrize("rel", [v[0] for v in SHARED.values()])
def test_against_plain_reference_reader(gnss_data: Path, rel: str) -> None:
    obs = read_obs(gnss_data / rel)
    times, ref = _reference_read(gnss_data / rel)
    np.testing.assert_allclose(obs.t_gps_s, times, rtol=0, atol=1e-6)
    n_fields = 0
    for (e, sat, code), (value, lli, ssi) in ref.items():
        s, c = obs.sat_index(sat), obs.codes.index(code)
        want = np.nan if value == 0.0 else value
        assert obs.values[e, s, c] == want or (np.isnan(want) and np.isnan(obs.values[e, s, c]))
        assert (obs.lli[e, s, c], obs.ssi[e, s, c]) == (lli, ssi), (e, sat, code)
        n_fields += 1
    # Nothing more is set than the reference saw.
    written = (~np.isnan(obs.values)) | (obs.lli >= 0) | (obs.ssi >= 0)
    assert int(written.sum()) <= n_fields
    assert int((obs.lli >= 0).sum()) == sum(v[1] >= 0 for v in ref.values())
    assert int((obs.ssi >= 0).sum()) == sum(v[2] >= 0 for v in ref.values())


# ---------------------------------------------------------------- georinex cross-check

GEORINEX_FILES = [v[0] for v in SHARED.values()]


@pytest.mark.slow
@pytest.mark.parametrize("rel", GEORINEX_FILES)
def test_against_georinex(gnss_data: Path, rel: str) -> None:
    """Every value, LLI and SSI equals georinex 1.16.2's reading of the same file.

    georinex's time tags are not trusted: it truncates RINEX 2 epoch seconds to the
    millisecond below (0759's 00:59:30.0050000 becomes 00:59:30.004), so times are compared
    within [0, 1) ms, and the off-grid tags are checked against the file text in
    ``test_0759_splices_and_off_grid_time_tags``.
    """
    gr = pytest.importorskip("georinex")
    path = gnss_data / rel
    obs = read_obs(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = gr.load(path, useindicators=True)
    assert list(ref.sv.values) == list(obs.sats)
    t_ref = gps_seconds(ref.time.values.astype("datetime64[ns]"))
    assert len(t_ref) == len(obs.t_gps_s)
    lag = obs.t_gps_s - t_ref
    assert lag.min() > -1e-6
    assert lag.max() < 1e-3 + 1e-6
    compared = 0
    indicators = 0
    for k, code in enumerate(obs.codes):
        # RINEX writes a missing observation as blank or 0.0; georinex keeps 0.0, navtrack NaN.
        want = np.where(ref[code].values == 0.0, np.nan, ref[code].values)
        np.testing.assert_array_equal(obs.values[:, :, k], want, err_msg=code)
        compared += int(np.isfinite(want).sum())
        for name, ours in (("lli", obs.lli), ("ssi", obs.ssi)):
            if code + name in ref:
                mine = ours[:, :, k].astype(float)
                mine[mine < 0] = np.nan
                np.testing.assert_array_equal(mine, ref[code + name].values, err_msg=code + name)
                indicators += 1
    assert compared == int(np.isfinite(obs.values).sum())
    assert indicators > 0  # georinex gave indicator columns to compare (ARL1's are all blank)
    assert set(ref.data_vars) <= {c + s for c in obs.codes for s in ("", "lli", "ssi")}


@pytest.mark.parametrize("name", ["07590920.05o", "SEPT078M_120.21O"])
def test_file_cut_mid_line(tmp_path: Path, name: str) -> None:
    """A data line cut inside a field by the end of the file is never read as a value: an error
    naming the line (strict), or the line and its epoch counted as skipped (lenient)."""
    raw = sample_path(name).read_bytes()
    lines = raw.split(b"\n")
    # the first data line of the last 8-satellite (RINEX 2) / complete (RINEX 3) epoch's 2nd sat
    k = len(lines) * 3 // 4
    while not lines[k][:1].isalpha() if name.endswith("O") else not lines[k].startswith(b"   "):
        k += 1
    stem = lines[k][: lines[k].index(b".") - 3]  # the pseudorange's first digits, e.g. '    3714'
    path = tmp_path / name
    path.write_bytes(b"\n".join([*lines[:k], stem]))
    _raises_at(path, k + 1, "data line cut in the middle of a field")
    obs = read_obs(path, lenient=True)
    assert obs.skipped[-1].line == k + 1
    assert "cut short" in obs.skipped[-2].reason
    full = read_obs(sample_path(name))
    n = len(obs.t_gps_s)
    # what was read equals the full file's values; the cut value is nowhere
    np.testing.assert_array_equal(obs.t_gps_s, full.t_gps_s[:n])
    cut_value = float(stem.split()[-1])
    assert not np.isin(obs.values, [cut_value]).any()
    # a last line with no end-of-line that ends on a field boundary is complete
    path.write_bytes(raw.rstrip())
    np.testing.assert_array_equal(read_obs(path).values, full.values)


def test_v3_epoch_record_cut_in_its_clock_field(tmp_path: Path) -> None:
    # issue 9: an epoch record ending inside the receiver clock offset (F15.12, columns 42-56)
    # read the cut digits as the clock; now it is an error naming the line
    rows = sample_path("SEPT078M_120.21O").read_text().splitlines()
    assert rows[33].startswith("> 2021 03 19 12 00  0.0000000  0 23")
    whole = tmp_path / "clock.21o"
    rows[33] = rows[33] + "      -0.123456789012"
    whole.write_text("\n".join(rows) + "\n")
    assert read_obs(whole).clock_offset_s[0] == pytest.approx(-0.123456789012, abs=1e-15)
    cut = tmp_path / "cut.21o"
    rows[33] = rows[33][:-8]
    cut.write_text("\n".join(rows) + "\n")
    _raises_at(cut, 34, r"receiver clock offset '-0\.1234' cut short")
    lenient = read_obs(cut, lenient=True)
    assert 34 in [s.line for s in lenient.skipped]


@pytest.mark.parametrize(
    ("name", "systems", "codes"),
    [
        ("SEPT078M_120.21O", "GE", {"C1C"}),
        ("SEPT078M_120.21O", None, {"C1C", "L1C", "S1C"}),
        ("SEPT078M_120.21O", "J", None),
        ("07590920.05o", None, {"C1", "L2"}),
    ],
)
def test_a_selective_read_equals_the_same_part_of_a_full_read(name, systems, codes) -> None:  # type: ignore[no-untyped-def]
    full = read_obs(sample_path(name))
    part = read_obs(sample_path(name), systems=systems, codes=codes)
    assert set(part.codes) == (set(full.codes) if codes is None else codes & set(full.codes))
    assert all(s[0] in (systems or s[0]) for s in part.sats)
    assert set(part.sats) == {s for s in full.sats if s[0] in (systems or s[0])}
    js = [full.sats.index(s) for s in part.sats]
    ks = [full.codes.index(c) for c in part.codes]
    for attr in ("values", "lli", "ssi"):
        np.testing.assert_array_equal(getattr(part, attr), getattr(full, attr)[:, js][:, :, ks])
    np.testing.assert_array_equal(part.t_gps_s, full.t_gps_s)


def test_a_selective_read_skips_unread_fields_but_not_the_structure(tmp_path: Path) -> None:
    lines = _lines("SEPT078M_120.21O")
    body = next(i for i, ln in enumerate(lines) if "END OF HEADER" in ln)
    k = next(i for i in range(body, len(lines)) if lines[i].startswith("G"))

    def write(path: Path, line: str) -> Path:
        path.write_text("\n".join([*lines[:k], line, *lines[k + 1 :]]) + "\n")
        return path

    bad_field = write(tmp_path / "field.21O", lines[k][:3] + "x" * 16 + lines[k][19:])
    with pytest.raises(FileFormatError, match="malformed observation field 1"):
        read_obs(bad_field)
    assert read_obs(bad_field, codes={"L2W"}).codes == ("L2W",)  # field 1 (C1C) not decoded
    bad_sat = write(tmp_path / "sat.21O", "X" + lines[k][1:])
    with pytest.raises(FileFormatError, match="X"):
        read_obs(bad_sat, codes={"L2W"})  # an unknown system is structure
    # lines of a system not asked for are not decoded, yet their structure is still checked
    n_types = len(read_obs(sample_path("SEPT078M_120.21O")).header.obs_types["G"])
    full_width = lines[k].ljust(3 + 16 * n_types)
    surplus = write(tmp_path / "surplus.21O", full_width + "  20000000.000  ")
    with pytest.raises(FileFormatError, match="more observations than observation types"):
        read_obs(surplus, systems="E")
    padded = write(tmp_path / "padded.21O", full_width + " " * 16)
    assert (
        read_obs(padded, systems="E").sats
        == read_obs(sample_path("SEPT078M_120.21O"), systems="E").sats
    )
    twice = tmp_path / "twice.21O"
    twice.write_text("\n".join([*lines[:k], lines[k], lines[k], *lines[k + 2 :]]) + "\n")
    with pytest.raises(FileFormatError, match="appears twice in one epoch"):
        read_obs(twice, systems="E")


def _read_or_error(path: Path, lenient: bool, codes: set[str] | None) -> Observations | int:
    """The observations read, or the line named by the error."""
    try:
        return read_obs(path, lenient=lenient, codes=codes)
    except FileFormatError as exc:
        line = exc.line
    assert line is not None
    return line


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)  # the one file in tmp_path is rewritten by every example
@given(
    st.lists(
        st.tuples(st.floats(0, 1, exclude_max=True), st.sampled_from(list(b" 0123456789.-x\n>G"))),
        min_size=1,
        max_size=4,
    ),
    st.floats(0, 1),
    st.booleans(),
)
def test_a_read_of_every_code_by_column_equals_the_full_read_on_damaged_files(
    tmp_path: Path, damage: list[tuple[float, int]], keep: float, lenient: bool
) -> None:
    """Asking for every code takes the fields from the text by column (RINEX 3) instead of the
    byte matrix of the full read: both find the same damaged line (their messages may differ
    for a line that is damaged twice over) or read the same values."""
    original = sample_path("SEPT078M_120.21O").read_bytes()
    body = original.index(b"END OF HEADER") + 14
    text = bytearray(original)
    for where, byte in damage:
        text[body + int(where * (len(text) - body))] = byte
    path = tmp_path / "damaged.21O"
    path.write_bytes(bytes(text[: body + int(keep * (len(text) - body))]))
    every = {
        c
        for types in read_obs(sample_path("SEPT078M_120.21O")).header.obs_types.values()
        for c in types
    }
    full = _read_or_error(path, lenient, None)
    by_column = _read_or_error(path, lenient, every)
    if isinstance(full, int) or isinstance(by_column, int):
        assert by_column == full
        return
    assert by_column.codes == tuple(c for c in full.codes if c in every)
    assert by_column.sats == full.sats
    assert [s.line for s in by_column.skipped] == [s.line for s in full.skipped]
    for attr in ("values", "lli", "ssi", "t_gps_s", "epoch_flag", "clock_offset_s"):
        np.testing.assert_array_equal(getattr(by_column, attr), getattr(full, attr))


@pytest.mark.parametrize(
    "record",
    [
        "> 2021 03 19 12 00  0.0000000  0 23       0.000123456789",  # clock offset
        "> 2021 03 19  9  5 59.9999999  0 23",  # blank-padded hour and minute
        "> 2021 03 19 12 00  0.0000000  0 23       0.0001",  # clock cut short
        "> 2021 03 19 12 00  0.0000000  1 23",  # epoch flag 1
        "> 2021 03 19 12 00   .0000000  0 23",  # no digit before the point
        "> 2021 03 19 12 00  0.0000000  0 24",  # one satellite more than its lines
        "> 2021 3 19 12 00  0.0000000  0 23",  # date out of its columns
    ],
)
def test_a_read_by_column_reads_epoch_records_as_the_full_read(tmp_path: Path, record: str) -> None:
    """Epoch records the read by column takes at once (regular ones) or walks one by one:
    times, flags and clock offsets as the full read's, or the same line named."""
    lines = _lines("SEPT078M_120.21O")
    k = next(i for i, ln in enumerate(lines) if ln.startswith(">"))
    path = tmp_path / "record.21O"
    path.write_text("\n".join([*lines[:k], record, *lines[k + 1 :]]) + "\n")
    every = {
        c
        for types in read_obs(sample_path("SEPT078M_120.21O")).header.obs_types.values()
        for c in types
    }
    full = _read_or_error(path, False, None)
    by_column = _read_or_error(path, False, every)
    if isinstance(full, int) or isinstance(by_column, int):
        assert by_column == full
        return
    for attr in ("values", "t_gps_s", "epoch_flag", "clock_offset_s"):
        np.testing.assert_array_equal(getattr(by_column, attr), getattr(full, attr))
