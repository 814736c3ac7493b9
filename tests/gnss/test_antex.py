"""ANTEX antenna phase centres: reader, range corrections, and their use in PPP."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import FileFormatError
from navtrack.gnss.antex import read_antex, receiver_range_m, satellite_offset_m
from navtrack.timescale import calendar_gps_seconds

ATX = Path(__file__).parent / "data" / "igs05_cut.atx"


def _block_line(first: str, label: str) -> str:
    """The first line labelled ``label`` after the line starting with ``first`` (file text)."""
    lines = ATX.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith(first))
    return next(ln for ln in lines[k:] if ln[60:].strip() == label)


def test_reads_receiver_offsets_and_variations() -> None:
    atx = read_antex(ATX)
    pats, note = atx.receiver("JAVRINGANT_DM   NONE")
    assert note == ""
    north, east, up = (
        float(v) for v in _block_line("JAVRINGANT_DM", "NORTH / EAST / UP").split()[:3]
    )
    np.testing.assert_allclose(pats["G01"].offset_m, np.array([north, east, up]) * 1e-3)
    assert pats["G01"].zenith_deg[0] == 0.0
    assert pats["G01"].zenith_deg[-1] == 90.0
    assert pats["G01"].variation_m.size == 19
    # the SEPT header writes the radome JVDM, not in the file: NONE with a note; serial first
    pats_jvdm, note = atx.receiver("12345 JAVRINGANT_DM   JVDM")
    assert pats_jvdm is pats
    assert "radome JVDM" in note
    with pytest.raises(KeyError, match=r"TRM59800\.00"):
        atx.receiver("TRM59800.00     NONE")


def test_satellite_antenna_by_validity() -> None:
    atx = read_antex(ATX)
    entries = atx.satellites["G01"]
    assert len(entries) >= 2
    t_2010 = calendar_gps_seconds(2010, 1, 1, 0, 0, 0.0)
    pats = atx.satellite("G01", t_2010)
    assert pats is not None
    # the block valid in 2010 is G01's IIR-M (SVN 49, from 2009-03-24), z offset 700 mm
    assert pats["G01"].offset_m[2] == pytest.approx(0.7)
    assert atx.satellite("G01", calendar_gps_seconds(1980, 2, 1, 0, 0, 0.0)) is None


def test_receiver_range_correction() -> None:
    pats, _ = read_antex(ATX).receiver("JAVRINGANT_DM NONE")
    p = pats["G01"]
    north, _east, up = p.offset_m
    zenith = receiver_range_m(p, np.array([0.0, 0.0, 1.0]))
    assert zenith == pytest.approx(-up + p.variation_m[0])
    horizon_north = receiver_range_m(p, np.array([0.0, 1.0, 0.0]))
    assert horizon_north == pytest.approx(-north + p.variation_m[-1])


def test_satellite_offset_in_the_nominal_attitude() -> None:
    """z points to the geocentre, y is perpendicular to the Sun: a pure z offset moves the
    phase centre towards the Earth, an x offset towards the Sun's side."""
    sat = np.array([[2.6e7, 0.0, 0.0]])
    sun = np.array([[0.0, 1.5e11, 0.0]])
    np.testing.assert_allclose(satellite_offset_m(np.array([0, 0, 1.0]), sat, sun), [[-1, 0, 0]])
    x_off = satellite_offset_m(np.array([1.0, 0, 0]), sat, sun)
    np.testing.assert_allclose(x_off, [[0, 1, 0]], atol=1e-6)


def test_not_an_antex_file(tmp_path: Path) -> None:
    bad = tmp_path / "x.atx"
    bad.write_text("hello\n")
    with pytest.raises(FileFormatError, match="line 1: not an ANTEX file"):
        read_antex(bad)
