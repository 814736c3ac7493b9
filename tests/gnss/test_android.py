"""Android GnssLogger reader: row accounting, pseudoranges from the printed fields, filters.

Reference pseudoranges are computed here directly from the printed integers of single rows with
the European GNSS Agency white paper formulas ("Using GNSS raw measurements on Android
devices", 2017, section 5.2: tRx = TimeNanos + TimeOffsetNanos - (FullBiasNanos + BiasNanos),
rho = (tRx - ReceivedSvTimeNanos) * c, with the receive time reduced to the constellation's
time of week / day / 100 ms); the row counts per constellation are those of the shared data
README (``../shared/data/gnss/README.md`` section 5).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.android import SKIP_REASONS, read_gnsslogger, skipped_counts
from navtrack.gnss.observations import Observations
from navtrack.timescale import calendar_gps_seconds

LOG = "google_gnsslogger/pseudoranges_log_2016_08_22_14_45_50.txt"
BUNDLED = "pseudoranges_log_2016_08_22_14_45_50.txt"
PIXEL10 = Path(__file__).resolve().parents[1] / "data" / "pixel10_gnsslogger_v3_cut.txt"
C = 299792458.0
WEEK_NS = 604800 * 10**9
_SYSTEM = {"1": "G", "3": "R", "5": "C", "6": "E", "4": "J"}


def _raw_rows(path: Path) -> dict[int, list[str]]:
    """Raw rows by 1-based line number, split at commas (first field 'Raw' dropped)."""
    return {
        i + 1: line.split(",")[1:]
        for i, line in enumerate(path.read_text().splitlines())
        if line.startswith("Raw,")
    }


@pytest.fixture(scope="module")
def old_log(gnss_data: Path) -> tuple[Path, Observations]:
    path = gnss_data / LOG
    return path, read_gnsslogger(path)


def test_every_raw_row_accounted_for(old_log: tuple[Path, Observations]) -> None:
    path, obs = old_log
    rows = _raw_rows(path)
    # README: Raw rows GPS 2484, GLONASS 1833, Galileo 517, BeiDou 207 (old column set: the
    # constellation is the last field)
    per_const: dict[str, int] = {}
    for f in rows.values():
        per_const[_SYSTEM[f[-1]]] = per_const.get(_SYSTEM[f[-1]], 0) + 1
    assert per_const == {"G": 2484, "R": 1833, "E": 517, "C": 207}
    used = {s: 0 for s in per_const}
    pr_codes = [k for k, c in enumerate(obs.codes) if c.startswith("C")]
    for s, sat in enumerate(obs.sats):
        used[sat[0]] += int(np.isfinite(obs.values[:, s, pr_codes]).sum())
    skipped = {s: 0 for s in per_const}
    for sk in obs.skipped:
        assert sk.reason in SKIP_REASONS
        skipped[_SYSTEM[rows[sk.line][-1]]] += 1
    assert {s: used[s] + skipped[s] for s in per_const} == per_const
    # every GLONASS row of this 2016 log gives a frequency channel (Svid 93-106), not a slot
    assert skipped_counts(obs)["GLONASS slot unknown (frequency channel only)"] == 1833


def test_epochs_and_time_tags(old_log: tuple[Path, Observations]) -> None:
    path, obs = old_log
    rows = _raw_rows(path)
    # README: 207 epochs at 1 Hz, 2016-08-22 21:46:13 - 21:49:39 GPST
    assert obs.t_gps_s.shape == (207,)
    assert len({f[1] for f in rows.values()}) == 207  # distinct TimeNanos
    assert abs(obs.t_gps_s[0] - calendar_gps_seconds(2016, 8, 22, 21, 46, 13)) < 1e-3
    assert abs(obs.t_gps_s[-1] - calendar_gps_seconds(2016, 8, 22, 21, 49, 39)) < 1e-3
    np.testing.assert_allclose(np.diff(obs.t_gps_s), 1.0, atol=1e-3)
    assert obs.header.receiver.startswith("Android GnssLogger (Version: 1.4.0.0")


def _expected_pr(fields: list[str], col: dict[str, int], period_ns: int, shift_ns: int) -> float:
    """White-paper pseudorange from one row's printed fields, in exact integers."""
    t_rx = int(fields[col["TimeNanos"]]) - int(fields[col["FullBiasNanos"]]) + shift_ns
    frac = float(fields[col["TimeOffsetNanos"]]) - float(fields[col["BiasNanos"]])
    tau = (t_rx % period_ns) - int(fields[col["ReceivedSvTimeNanos"]])
    tau %= period_ns
    return (tau + frac) * 1e-9 * C


def _columns(path: Path) -> dict[str, int]:
    header = next(ln for ln in path.read_text().splitlines() if ln.startswith("# Raw,"))
    names = [c.strip() for c in header[2:].split(",")][1:]
    return {n: k for k, n in enumerate(names)}


def test_pseudoranges_from_printed_rows(old_log: tuple[Path, Observations]) -> None:
    path, obs = old_log
    rows = _raw_rows(path)
    col = _columns(path)
    checked = {"G": 0, "E": 0, "C": 0}
    skipped_lines = {s.line for s in obs.skipped}
    for lineno, f in rows.items():
        if lineno in skipped_lines:
            continue
        sys_letter = _SYSTEM[f[col["ConstellationType"]]]
        state = int(f[col["State"]])
        if sys_letter == "G":
            expected, code = _expected_pr(f, col, WEEK_NS, 0), "C1C"
        elif sys_letter == "C":  # BDT = GPST - 14 s
            expected, code = _expected_pr(f, col, WEEK_NS, -14 * 10**9), "C2I"
        elif state & 8:  # Galileo with TOW decoded
            expected, code = _expected_pr(f, col, WEEK_NS, 0), "C1C"
        else:  # Galileo E1C secondary code lock: time known modulo 100 ms
            expected, code = _expected_pr(f, col, 100 * 10**6, 0), "C1C"
        sat = f"{sys_letter}{int(f[col['Svid']]):02d}"
        t = (int(f[col["TimeNanos"]]) - int(f[col["FullBiasNanos"]])) * 1e-9
        e = int(np.argmin(np.abs(obs.t_gps_s - t)))
        got = obs.code(code)[e, obs.sat_index(sat)]
        assert got == pytest.approx(expected, abs=1e-6), (lineno, sat)
        checked[sys_letter] += 1
        # C/N0 as logged; Doppler = -PRR * f / c with L1 1575.42 MHz / B1I 1561.098 MHz
        s_code = "S" + code[1:]
        assert obs.code(s_code)[e, obs.sat_index(sat)] == float(f[col["Cn0DbHz"]])
        f_hz = 1561.098e6 if sys_letter == "C" else 1575.42e6
        d = -float(f[col["PseudorangeRateMetersPerSecond"]]) * f_hz / C
        assert obs.code("D" + code[1:])[e, obs.sat_index(sat)] == pytest.approx(d, rel=1e-12)
    assert min(checked.values()) > 100
    # plausibility: GPS MEO ranges 20 000-26 000 km (+ small receiver clock error); BeiDou C07
    # is an IGSO satellite (~36 000-41 000 km); Galileo MEO 23 000-29 000 km
    pr = obs.code("C1C")
    g = [obs.sat_index(s) for s in obs.sats if s[0] == "G"]
    assert np.nanmin(pr[:, g]) > 19.5e6
    assert np.nanmax(pr[:, g]) < 26.5e6
    c07 = obs.code("C2I")[:, obs.sat_index("C07")]
    assert 35.0e6 < np.nanmin(c07) < np.nanmax(c07) < 42.0e6


def test_galileo_100ms_and_tow_pseudoranges_agree(old_log: tuple[Path, Observations]) -> None:
    # E30 switches between TOW-decoded and secondary-code-lock rows; a wrong 100 ms resolution
    # would show as a 30 000 km jump, a wrong sign/offset as a step between neighbours
    _, obs = old_log
    pr = obs.code("C1C")[:, obs.sat_index("E30")]
    ok = np.isfinite(pr)
    assert ok.sum() > 150
    steps = np.abs(np.diff(pr[ok]))
    assert steps.max() < 1000.0  # range rate < 1 km/s at 1 Hz


def test_uncertainty_threshold_configurable(gnss_data: Path) -> None:
    path = gnss_data / LOG
    rows = _raw_rows(path)
    col = _columns(path)
    strict = read_gnsslogger(path, max_sv_time_uncertainty_ns=20.0)
    n_unc = skipped_counts(strict)["satellite time uncertainty too large"]
    # rows that pass every other test but have uncertainty >= 20 ns
    others = read_gnsslogger(path, max_sv_time_uncertainty_ns=1e12)
    ok_lines = set(rows) - {s.line for s in others.skipped}
    expected = sum(
        1 for ln in ok_lines if float(rows[ln][col["ReceivedSvTimeUncertaintyNanos"]]) >= 20
    )
    assert n_unc == expected > 0


def test_bundled_copy_reads() -> None:
    obs = read_gnsslogger(sample_path(BUNDLED))
    assert obs.t_gps_s.shape == (207,)
    assert len(obs.skipped) + int(np.isfinite(obs.values[:, :, 0::4]).sum()) == 5041


def test_new_column_set_dual_frequency() -> None:
    # Pixel 10, GnssLogger v3.1.1.3 (Google's gps-measurement-tools sample): CarrierFrequencyHz,
    # CodeType and the satellite-state columns logged; GPS L1/L5, GLONASS FDMA, Galileo E1/E5a
    obs = read_gnsslogger(PIXEL10)
    rows = _raw_rows(PIXEL10)
    col = _columns(PIXEL10)
    assert obs.t_gps_s.shape == (1,)
    assert set(obs.codes) == {f"{t}{s}" for s in ("1C", "5Q") for t in "CLDS"}
    # seven rows keep the millisecond ambiguity bit of State (0x10) set: G10 (State 23), R15 (115),
    # the Galileo E1 rows (3088) and E5a rows (65557), E27/E05 E5a with 5.3 ms uncertainty too
    assert skipped_counts(obs) == {"millisecond ambiguity": 7}
    assert len(obs.skipped) + int(np.isfinite(obs.values[:, :, 0::4]).sum()) == len(rows)
    for lineno, f in rows.items():
        if lineno in {s.line for s in obs.skipped}:
            continue
        const = f[col["ConstellationType"]]
        sys_letter = _SYSTEM[const]
        f_hz = float(f[col["CarrierFrequencyHz"]])
        band = "5" if abs(f_hz - 1176.45e6) < 1e6 else "1"
        code = band + f[col["CodeType"]]
        if sys_letter == "R":
            # GLONASS time of day in UTC(SU) + 3 h; 18 leap seconds in 2026 (IERS)
            expected = _expected_pr(f, col, 86400 * 10**9, (3 * 3600 - 18) * 10**9)
        else:
            expected = _expected_pr(f, col, WEEK_NS, 0)
        sat = f"{sys_letter}{int(f[col['Svid']]):02d}"
        s = obs.sat_index(sat)
        assert obs.code("C" + code)[0, s] == pytest.approx(expected, abs=1e-6)
        d = -float(f[col["PseudorangeRateMetersPerSecond"]]) * f_hz / C
        assert obs.code("D" + code)[0, s] == pytest.approx(d, rel=1e-12)
    pr = obs.values[0, :, 0::4]
    assert np.nanmin(pr) > 19.0e6
    assert np.nanmax(pr) < 30.0e6


def test_bad_input(tmp_path: Path) -> None:
    no_header = tmp_path / "nohdr.txt"
    no_header.write_text("Fix,gps,37.4,-122.0,0,0,4,1471902355999\n")
    with pytest.raises(FileFormatError, match=r"nohdr\.txt: not a GnssLogger log"):
        read_gnsslogger(no_header)
    lines = PIXEL10.read_text().splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith("Raw,"))
    bad = lines.copy()
    bad[k] = "Raw,1699400594000,garbage,,,\n"
    path = tmp_path / "bad.txt"
    path.write_text("".join(bad))
    with pytest.raises(FileFormatError, match=rf"bad\.txt, line {k + 1}: unreadable Raw row"):
        read_gnsslogger(path)
    lenient = read_gnsslogger(path, lenient=True)
    assert skipped_counts(lenient)["unreadable row"] == 1
    hdr = [ln.replace("ReceivedSvTimeNanos,", "") if ln.startswith("# Raw") else ln for ln in lines]
    path2 = tmp_path / "cols.txt"
    path2.write_text("".join(hdr))
    with pytest.raises(FileFormatError, match="lacks column"):
        read_gnsslogger(path2)
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    with pytest.raises(FileFormatError, match="empty file"):
        read_gnsslogger(empty)


def test_garbage_and_malformed_unused_fields_are_counted(tmp_path: Path) -> None:
    # issue 9, failure 11: a garbage line and a malformed value in a column navtrack does not
    # use (MultipathIndicator) were accepted without a word
    lines = PIXEL10.read_text().splitlines(keepends=True)
    col = {
        n: k for k, n in enumerate(next(ln for ln in lines if ln.startswith("# Raw")).split(","))
    }
    raw = [i for i, ln in enumerate(lines) if ln.startswith("Raw,")]
    bad = lines.copy()
    fields = bad[raw[3]].split(",")
    fields[col["MultipathIndicator"]] = "x1"
    bad[raw[3]] = ",".join(fields)
    path = tmp_path / "damaged.txt"
    path.write_text("".join(bad))
    with pytest.raises(
        FileFormatError, match=rf"line {raw[3] + 1}: unreadable Raw row \(MultipathIndicator 'x1'"
    ):
        read_gnsslogger(path)
    bad.insert(raw[5], "%%garbage: 12 34\n")
    path.write_text("".join(bad))
    good = read_gnsslogger(PIXEL10)
    lenient = read_gnsslogger(path, lenient=True)
    counts = skipped_counts(lenient)
    assert counts["unreadable row"] == 1
    assert counts["not a log record"] == 1
    assert {s.line for s in lenient.skipped} - {s.line for s in good.skipped} >= {
        raw[3] + 1,
        raw[5] + 1,
    }
    # the other rows give what they gave before
    assert np.isfinite(lenient.values).sum() < np.isfinite(good.values).sum()
    strict_garbage = lines.copy()
    strict_garbage.insert(raw[5], "%%garbage: 12 34\n")
    path.write_text("".join(strict_garbage))
    with pytest.raises(FileFormatError, match=rf"line {raw[5] + 1}: not a GnssLogger record"):
        read_gnsslogger(path)


def test_last_row_cut_by_the_end_of_the_file(tmp_path: Path) -> None:
    # issue 9, failure 10: a last Raw row cut mid-line was read with its cut value as data
    text = PIXEL10.read_text()
    last_raw = text.rstrip("\n").rsplit("\n", 1)[1]
    assert last_raw.startswith("Raw,")
    n_lines = len(text.rstrip("\n").split("\n"))
    path = tmp_path / "cut.txt"
    path.write_text(text.rstrip("\n")[: -len(last_raw) // 2])
    with pytest.raises(FileFormatError, match=rf"line {n_lines}: Raw row cut short"):
        read_gnsslogger(path)
    lenient = read_gnsslogger(path, lenient=True)
    assert n_lines in [s.line for s in lenient.skipped if s.reason == "unreadable row"]


def test_infinite_integer_field_is_unreadable(tmp_path: Path) -> None:
    # found by the fuzz suite (bad_number, seed 606): "inf" in an integer column raised
    # OverflowError from int(float("inf"))
    lines = PIXEL10.read_text().splitlines(keepends=True)
    header = next(ln for ln in lines if ln.startswith("# Raw"))
    col = {n: k for k, n in enumerate(header.split(","))}
    k = next(i for i, ln in enumerate(lines) if ln.startswith("Raw,"))
    fields = lines[k].split(",")
    fields[col["State"]] = "inf"
    lines[k] = ",".join(fields)
    path = tmp_path / "inf.txt"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=rf"line {k + 1}: unreadable Raw row"):
        read_gnsslogger(path)
    assert skipped_counts(read_gnsslogger(path, lenient=True))["unreadable row"] == 1
