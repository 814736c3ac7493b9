"""RINEX 4 navigation files: ephemeris records read through their record headers, ionosphere
records into ``iono``, the other records counted.

Data (tests/data/README.md): two excerpts of real RINEX 4.00 navigation files kept in the test
suites of other readers: a JAVAD receiver file merged by gfzrnx (2022-11-29; BeiDou D1, GPS LNAV,
Galileo F/NAV and I/NAV, GLONASS FDMA) from de-bkg/gognss, and DLR's BRD400DLR multi-GNSS merge
(2024-02-17; STO, EOP, ION and an LNAV ephemeris) from mgfernan/pygnss. Expected values are read
off the printed text (line numbers given); georinex 1.16.2 does not read RINEX 4 navigation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import FileFormatError
from navtrack.gnss.rinex.nav import read_nav
from navtrack.timescale import calendar_gps_seconds

DATA = Path(__file__).parents[1] / "data"
GOGNSS = DATA / "gognss_rinex4_nav_excerpt.rnx"
DLR = DATA / "dlr_brd400_rinex4_nav_excerpt.rnx"


def test_ephemeris_records_of_every_message_type() -> None:
    nav = read_nav(GOGNSS)
    assert nav.version == 4.0
    assert {s: list(t["sat"]) for s, t in nav.tables.items()} == {
        "G": ["G22"], "R": ["R22"], "E": ["E01", "E01"], "C": ["C01"]
    }  # fmt: skip
    # the record's first line in the file (after its "> EPH" line)
    assert nav.tables["C"]["line"].tolist() == [7]
    assert nav.tables["G"]["line"].tolist() == [16]
    assert nav.tables["E"]["line"].tolist() == [25, 34]
    assert nav.tables["R"]["line"].tolist() == [43]
    g = nav.tables["G"]
    assert g["sqrta"][0] == 5.153760629654e03  # line 18
    assert g["toe_sow"][0] == 1.872e05  # line 19
    assert g["toc_gps_s"][0] == calendar_gps_seconds(2022, 11, 29, 4, 0, 0.0)
    # F/NAV then I/NAV of the same issue: data source 258 and 516 (lines 30, 39)
    assert nav.tables["E"]["data_source"].tolist() == [258, 516]
    assert nav.tables["E"]["bgd_e5b"].tolist() == [0.0, 4.656612873077e-10]
    # BeiDou dated in BDT: GPST = BDT + 14 s (line 7)
    assert nav.tables["C"]["toc_gps_s"][0] == calendar_gps_seconds(2022, 11, 29, 12, 0, 14.0)
    assert nav.tables["C"]["tgd1"][0] == pytest.approx(-4.7e-09)  # line 13
    assert nav.tables["R"]["freq_num"].tolist() == [-3]  # line 45
    assert nav.records_not_read == {}
    assert nav.leap_seconds == 18


def test_ion_records_and_records_not_read() -> None:
    nav = read_nav(DLR)
    np.testing.assert_array_equal(
        nav.iono["GPSA"],
        [2.328306436539e-08, 0.0, -1.192092895508e-07, 1.192092895508e-07],  # lines 18-19
    )
    np.testing.assert_array_equal(
        nav.iono["GPSB"],
        [1.35168e05, -8.192e04, 6.5536e04, -4.58752e05],  # lines 19-20
    )
    assert nav.records_not_read == {"STO CNVX": 1, "EOP CNVX": 1}
    assert list(nav.tables["G"]["sat"]) == ["G01"]
    assert nav.tables["G"]["line"].tolist() == [22]
    assert nav.tables["G"]["iodc"].tolist() == [82]  # line 28
    assert nav.summary()["records_not_read"] == {"STO CNVX": 1, "EOP CNVX": 1}


def test_damaged_field_named_by_its_file_line(tmp_path: Path) -> None:
    lines = GOGNSS.read_text().splitlines()
    assert lines[18].startswith("     1.872000000000e+05")  # line 19 of the file
    lines[18] = "     1.87200000x000e+05" + lines[18][23:]
    bad = tmp_path / "bad.rnx"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError) as err:
        read_nav(bad)
    assert err.value.line == 19
    nav = read_nav(bad, lenient=True)
    assert [s.line for s in nav.skipped] == [16]
    assert "G" not in nav.tables
