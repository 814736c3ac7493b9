"""u-blox UBX logs: RXM-RAWX observations and RXM-SFRBX ephemerides against RTKLIB's convbin,
the RINEX 3.04 writers read back by navtrack, RTKLIB and georinex, damaged messages.

Data (tests/data/ubx/README.md): two real RXM-RAWX logs (pyubx2's test log of a multi-GNSS
receiver, 14 epochs at 1 Hz; ublox-rs's two RAWX epochs of an F9 receiver with L2 signals) and
ublox-rs's 131 GPS RXM-SFRBX subframes. The ``*_convbin.*`` files are RTKLIB 2.4.3 b34
``convbin`` outputs of the same logs (commands in the README); the live tests run convbin
again when it is installed.
"""

from __future__ import annotations

import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rinex.write import write_nav, write_obs
from navtrack.gnss.ubx import is_ubx, read_ubx

DATA = Path(__file__).parents[1] / "data" / "ubx"
RAWX_1HZ = DATA / "pyubx2_rxmrawx.ubx"
RAWX_F9 = DATA / "ubloxrs_rxm_rawx.ubx"
SFRBX_GPS = DATA / "ubloxrs_rxm_sfrbx_gps.ubx"
WALK = sample_path("gnss_imu_walk_cut.ubx")  # bundled: the example of navtrack convert


def _same_as_printed(ours, theirs, *, superset: bool = False) -> None:
    """Same epochs, satellites, codes, missing pattern, and values to RINEX's 3 decimals.
    ``superset``: ours may hold more satellites and signals (those RTKLIB 2.4.3 does not
    know); theirs are compared."""
    np.testing.assert_array_equal(ours.t_gps_s, theirs.t_gps_s)
    if superset:
        assert set(theirs.sats) <= set(ours.sats)
        for letter, codes in theirs.header.obs_types.items():
            assert set(codes) <= set(ours.header.obs_types[letter]), letter
    else:
        assert ours.sats == theirs.sats
        assert set(ours.codes) == set(theirs.codes)
    cols = [ours.sat_index(s) for s in theirs.sats]
    for code in theirs.codes:
        a, b = ours.code(code)[:, cols], theirs.code(code)
        if superset:  # a code of one system in the union: compare that system's satellites
            has = np.array([code in theirs.header.obs_types[s[0]] for s in theirs.sats])
            a, b = a[:, has], b[:, has]
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg=code)
        ok = ~np.isnan(b)
        # theirs is printed F14.3: ours rounds to it
        assert np.max(np.abs(np.round(a[ok], 3) - b[ok]), initial=0.0) < 6e-4, code


@pytest.mark.parametrize("log", [RAWX_1HZ, RAWX_F9])
def test_rawx_values_as_convbin_prints_them(log: Path) -> None:
    ours = read_ubx(log).obs
    theirs = read_obs(DATA / f"{log.stem}_convbin.obs")
    _same_as_printed(ours, theirs)
    assert dict(ours.header.glonass_fcn) == dict(theirs.header.glonass_fcn)
    assert ours.header.obs_types == theirs.header.obs_types


def test_real_f9_walk_log_as_convbin() -> None:
    """60 epochs at 4 Hz of a triple-frequency receiver walking: every value convbin writes,
    equal to its printed precision; navtrack also keeps the signals RTKLIB 2.4.3 drops (GPS L5,
    BeiDou B1C/B2a/B3I, Galileo E5a/E6) and its phases' loss-of-lock bits agree on the
    continuous epochs."""
    ours = read_ubx(WALK).obs
    theirs = read_obs(DATA / "gnss_imu_walk_cut_convbin.obs")
    _same_as_printed(ours, theirs, superset=True)
    assert set(ours.header.obs_types["G"]) - set(theirs.header.obs_types["G"]) == {
        "C5Q",
        "L5Q",
        "D5Q",
        "S5Q",
    }
    assert "C" in ours.header.obs_types
    assert "C" not in theirs.header.obs_types
    cols = [ours.sat_index(s) for s in theirs.sats]
    for code in ("L1C", "L2L"):
        k, j = ours.codes.index(code), theirs.codes.index(code)
        phase = ~np.isnan(theirs.values[:, :, j])
        a = np.maximum(ours.lli[:, cols, k], 0)
        b = np.maximum(theirs.lli[:, :, j], 0)
        # a signal's first valid phase starts an arc: a possible slip for navtrack; convbin
        # flags only the phases of the file's first epoch (here G18 L2L, valid from epoch 22)
        first = phase & (np.cumsum(phase, axis=0) == 1)
        assert (a[first] & 1).all(), code
        np.testing.assert_array_equal(a[phase & ~first], b[phase & ~first], err_msg=code)
        assert (a[first] != b[first]).sum() == (1 if code == "L2L" else 0)


def test_real_f9_walk_ephemerides_as_convbin() -> None:
    ours = read_ubx(WALK).nav.tables["G"]
    theirs = read_nav(DATA / "gnss_imu_walk_cut_convbin.nav").tables["G"]
    assert list(ours["sat"]) == list(theirs["sat"]) == ["G10", "G23", "G27", "G32"]
    for name in theirs:
        if name not in ("line", "tot_sow", "sat"):
            np.testing.assert_allclose(ours[name], theirs[name], rtol=1e-11, err_msg=name)


def test_pos_on_the_log_equals_pos_on_convbin_rinex(tmp_path: Path) -> None:
    """``navtrack pos LOG`` (observations and ephemerides straight from the UBX log) gives the
    positions of ``navtrack pos`` on convbin's RINEX files of the same log, to the 1 mm of
    RINEX's printed pseudoranges (x PDOP ~5)."""
    import pandas as pd

    from navtrack.cli import main

    opts = ["--iono", "off", "--systems", "G"]  # convbin decodes no Galileo record
    assert main(["pos", str(WALK), *opts, "--out", str(tmp_path / "a.csv")]) == 0
    rinex = [str(DATA / f"gnss_imu_walk_cut_convbin.{x}") for x in ("obs", "nav")]
    assert main(["pos", *rinex, *opts, "--out", str(tmp_path / "b.csv")]) == 0
    a, b = pd.read_csv(tmp_path / "a.csv"), pd.read_csv(tmp_path / "b.csv")
    assert len(a) == len(b) == 60
    xyz = ["x_m", "y_m", "z_m"]
    assert np.abs(a[xyz].to_numpy() - b[xyz].to_numpy()).max() < 0.01


def test_checksum_as_pyubx2() -> None:
    import io

    from pyubx2 import UBXReader, calc_checksum

    from navtrack.gnss.ubx import checksum_ok

    data = WALK.read_bytes()
    n = 0
    for raw, _ in UBXReader(io.BytesIO(data), protfilter=2, parsing=False):
        assert checksum_ok(raw) == (calc_checksum(raw[2:-2]) == raw[-2:])
        broken = raw[:-1] + bytes([raw[-1] ^ 1])
        assert not checksum_ok(broken)
        n += 1
    assert n == 684


def test_rawx_lli_as_convbin_on_continuous_epochs() -> None:
    """1 Hz without gaps: slip and half-cycle flags equal RTKLIB's wherever there is a phase
    (the first epoch's phases, and E08/G07 whose phases become valid later, are slips)."""
    ours = read_ubx(RAWX_1HZ).obs
    theirs = read_obs(DATA / "pyubx2_rxmrawx_convbin.obs")
    for code in ("L1C", "L2I"):
        k, j = ours.codes.index(code), theirs.codes.index(code)
        phase = ~np.isnan(ours.values[:, :, k])
        a = np.maximum(ours.lli[:, :, k], 0)[phase]
        b = np.maximum(theirs.lli[:, :, j], 0)[phase]
        np.testing.assert_array_equal(a, b, err_msg=code)
    # R17 has lock time 0 and no valid phase: no phase, no LLI (convbin writes 3 on the blank)
    assert np.isnan(ours.code("L1C")[0, ours.sat_index("R17")])
    assert (ours.lli[0, :, ours.codes.index("L1C")] & 1)[~np.isnan(ours.code("L1C")[0])].all()


def test_rawx_lli_flags_a_gap_longer_than_the_lock_time() -> None:
    """The two ublox-rs epochs are 49 days apart: every phase of the second is a possible slip
    (lock time shorter than the gap), where convbin, comparing lock times only, flags 2 of 16
    L1C phases."""
    obs = read_ubx(RAWX_F9).obs
    assert obs.t_gps_s[1] - obs.t_gps_s[0] > 4e6
    phases = [c for c in obs.codes if c.startswith("L")]
    for code in phases:
        k = obs.codes.index(code)
        has = ~np.isnan(obs.values[1, :, k])
        assert (obs.lli[1, has, k] & 1).all(), code
    theirs = read_obs(DATA / "ubloxrs_rxm_rawx_convbin.obs")
    k = theirs.codes.index("L1C")
    has = ~np.isnan(theirs.values[1, :, k])
    assert (np.maximum(theirs.lli[1, has, k], 0) & 1).sum() == 2 < has.sum() == 16


def test_rawx_half_cycle_flag_from_tracking_state() -> None:
    """LLI bit 1 where trkStat bit 2 (half cycle valid) is clear, read with pyubx2's parser."""
    from pyubx2 import UBXReader

    obs = read_ubx(RAWX_1HZ).obs
    letters = {0: "G", 2: "E", 6: "R", 3: "C"}  # UBX gnssId
    n_checked = 0
    with RAWX_1HZ.open("rb") as f:
        for e, (_, msg) in enumerate(UBXReader(f, protfilter=2)):
            for i in range(1, msg.numMeas + 1):
                letter = letters[getattr(msg, f"gnssId_{i:02d}")]
                sat = f"{letter}{getattr(msg, f'svId_{i:02d}'):02d}"
                k = obs.codes.index("L2I" if letter == "C" else "L1C")
                j = obs.sat_index(sat)
                if np.isnan(obs.values[e, j, k]):
                    continue
                half_valid = getattr(msg, f"halfCyc_{i:02d}")
                assert bool(obs.lli[e, j, k] & 2) == (not half_valid), (e, sat)
                n_checked += 1
    assert n_checked > 100


def test_sfrbx_gps_ephemeris_as_convbin() -> None:
    """G27 (IODE 57) from subframes 1-3, field by field against convbin's record."""
    nav = read_ubx(SFRBX_GPS).nav
    theirs = read_nav(DATA / "ubloxrs_rxm_sfrbx_gps_convbin.nav").tables["G"]
    ours = nav.tables["G"]
    assert list(ours["sat"]) == list(theirs["sat"]) == ["G27"]
    for name in theirs:
        if name in ("line", "tot_sow", "sat"):
            continue
        np.testing.assert_allclose(ours[name], theirs[name], rtol=1e-11, atol=0, err_msg=name)


def test_sfrbx_transmission_time_is_the_first_subframe_1_start() -> None:
    """tot: start of the first subframe 1 of the issue (its HOW count x 6 - 6 s), read here
    with pyubx2's own parser; convbin writes the count x 6 of the last subframe 1 received
    (303006 s), a later repetition of the same issue."""
    from pyubx2 import UBXReader

    nav = read_ubx(SFRBX_GPS).nav
    with SFRBX_GPS.open("rb") as f:
        counts = [
            (msg.dwrd_02 >> 13) & 0x1FFFF
            for _, msg in UBXReader(f, protfilter=2)
            if msg.svId == 27 and (msg.dwrd_02 >> 8) & 7 == 1
        ]
    assert nav.tables["G"]["tot_sow"][0] == counts[0] * 6 - 6
    assert max(counts) * 6 == 303006


def test_sfrbx_undecoded_counted() -> None:
    log = read_ubx(SFRBX_GPS)
    # 131 subframes: 3 used for G27's ephemeris, the repetitions of subframes 1-3 are not
    # counted as undecoded; nothing else in this cut
    assert log.messages["RXM-SFRBX"] == 131
    assert all(k.startswith("G:") for k in log.undecoded)


def test_writers_read_back(tmp_path: Path) -> None:
    log = read_ubx(RAWX_1HZ)
    write_obs(log.obs, tmp_path / "a.obs", comments=["test"])
    back = read_obs(tmp_path / "a.obs")
    np.testing.assert_array_equal(back.t_gps_s, log.obs.t_gps_s)
    # LLI 0 is written blank (read back -1)
    np.testing.assert_array_equal(np.maximum(back.lli, 0), np.maximum(log.obs.lli, 0))
    ok = ~np.isnan(log.obs.values)
    np.testing.assert_array_equal(ok, ~np.isnan(back.values))
    assert np.max(np.abs(back.values[ok] - log.obs.values[ok])) <= 5e-4 + 1e-9
    nav = read_ubx(SFRBX_GPS).nav
    write_nav(nav, tmp_path / "a.nav")
    nback = read_nav(tmp_path / "a.nav")
    for name, col in nav.tables["G"].items():
        if name in ("line", "sat"):
            continue
        np.testing.assert_allclose(nback.tables["G"][name], col, rtol=1e-12, err_msg=name)


def test_georinex_reads_the_written_files(tmp_path: Path) -> None:
    gr = pytest.importorskip("georinex")
    log = read_ubx(RAWX_1HZ)
    write_obs(log.obs, tmp_path / "a.obs")
    write_nav(read_ubx(SFRBX_GPS).nav, tmp_path / "a.nav")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = gr.load(tmp_path / "a.obs")
        nv = gr.load(tmp_path / "a.nav")
    k = log.obs.sat_index("G11")
    np.testing.assert_allclose(
        ds["C1C"].sel(sv="G11").values, np.round(log.obs.code("C1C")[:, k], 3), atol=1e-9
    )
    assert float(nv["sqrtA"].sel(sv="G27").values[0]) == pytest.approx(
        read_ubx(SFRBX_GPS).nav.tables["G"]["sqrta"][0], rel=1e-12
    )


@pytest.mark.skipif(shutil.which("convbin") is None, reason="RTKLIB convbin not installed")
def test_convbin_live_same_epochs_and_values(tmp_path: Path) -> None:
    out = tmp_path / "c.obs"
    subprocess.run(
        ["convbin", "-r", "ubx", "-od", "-os", "-o", str(out), str(RAWX_1HZ)],
        check=True,
        capture_output=True,
    )
    _same_as_printed(read_ubx(RAWX_1HZ).obs, read_obs(out))


@pytest.mark.skipif(shutil.which("convbin") is None, reason="RTKLIB convbin not installed")
def test_rtklib_reads_the_written_obs(tmp_path: Path) -> None:
    """RTKLIB reads navtrack's RINEX (convbin RINEX -> RINEX) to the same epochs and values."""
    ours = read_ubx(RAWX_1HZ).obs
    write_obs(ours, tmp_path / "n.obs")
    subprocess.run(
        [
            "convbin",
            "-r",
            "rinex",
            "-od",
            "-os",
            "-o",
            str(tmp_path / "r.obs"),
            str(tmp_path / "n.obs"),
        ],
        check=True,
        capture_output=True,
    )
    _same_as_printed(ours, read_obs(tmp_path / "r.obs"))


def test_damaged_message_refused_or_skipped(tmp_path: Path) -> None:
    data = bytearray(RAWX_1HZ.read_bytes())
    data[100] ^= 0xFF  # inside the first RXM-RAWX payload
    bad = tmp_path / "bad.ubx"
    bad.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match="message at byte 0: checksum error"):
        read_ubx(bad)
    log = read_ubx(bad, lenient=True)
    assert len(log.skipped) == 1
    assert len(log.obs.t_gps_s) == 13


def test_is_ubx() -> None:
    assert is_ubx(RAWX_1HZ)
    assert not is_ubx(DATA / "pyubx2_rxmrawx_convbin.obs")


def test_convert_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from navtrack.cli import main

    log = tmp_path / "log.ubx"
    log.write_bytes(RAWX_1HZ.read_bytes() + SFRBX_GPS.read_bytes())
    assert main(["convert", str(log), "--out", str(tmp_path / "x.obs")]) == 0
    out = capsys.readouterr().out
    assert "14 epochs, 23 satellites" in out
    assert "ephemerides G 1" in out
    assert read_obs(tmp_path / "x.obs").values.shape == (14, 23, 8)
    assert list(read_nav(tmp_path / "x.nav").tables["G"]["sat"]) == ["G27"]


def test_rtk_with_a_ubx_rover_zero_baseline(tmp_path: Path) -> None:
    """``navtrack rtk LOG RINEX``: the UBX log against convbin's RINEX of the same log (a zero
    baseline through the two readers): every epoch after the first fixed at the base position
    (the phases agree to RINEX's printed 0.001 cycle)."""
    import pandas as pd

    from navtrack.cli import main

    base = [-1276964.2, -4717226.1, 4087226.7]
    out = tmp_path / "z.csv"
    args = ["rtk", str(WALK), str(DATA / "gnss_imu_walk_cut_convbin.obs"), "--no-progress"]
    assert main([*args, "--base-pos", *map(str, base), "--out", str(out)]) == 0
    sol = pd.read_csv(out)
    # the first epoch's float (code alone) gives its integers below even odds: refused
    assert (sol["status"][1:] == "fix").all()
    assert sol["status"][0] == "fix" or sol["fix_rejected"][0] == "success_rate"
    assert len(sol) == 60
    fixed = (sol["status"] == "fix").to_numpy()
    assert np.abs(sol[["x_m", "y_m", "z_m"]].to_numpy()[fixed] - base).max() < 0.01


def test_beidou_d1_ephemerides_as_convbin(tmp_path: Path) -> None:
    """The B3I D1 subframes of the walk log (153 RXM-SFRBX): the 8 MEO/IGSO ephemerides equal
    convbin's field by field, transmission time and BDT-dated toc included, and survive the
    RINEX writer and reader."""
    log = read_ubx(DATA / "gnss_imu_walk_bds_b3i_sfrbx.ubx")
    ours = log.nav.tables["C"]
    theirs = read_nav(DATA / "gnss_imu_walk_bds_b3i_sfrbx_convbin.nav").tables["C"]
    assert list(ours["sat"]) == list(theirs["sat"])
    assert len(ours["sat"]) == 8
    for name in theirs:
        if name not in ("line", "sat"):
            np.testing.assert_allclose(ours[name], theirs[name], rtol=1e-11, err_msg=name)
    assert log.undecoded == {"C: D1 subframe 4 (almanac)": 25, "C: D1 subframe 5 (almanac)": 38}
    write_nav(log.nav, tmp_path / "c.nav")
    back = read_nav(tmp_path / "c.nav").tables["C"]
    for name in theirs:
        if name not in ("line", "sat"):
            np.testing.assert_allclose(back[name], ours[name], rtol=1e-12, err_msg=name)


def test_galileo_inav_ephemerides_position_the_walk() -> None:
    """No decoder to compare with (RTKLIB 2.4.3 decodes no Galileo record from this log): the
    7 I/NAV ephemerides are judged by positioning. Galileo-only single point positions (6
    satellites, ionosphere left unmodelled as for GPS) of the 60 epochs agree with the
    GPS-only ones of the same receiver to a few metres and lie within 15 m horizontally of
    the RTK trajectory RTKLIB computed for this walk (GNSS_IMU ``gnss_1730_sf.pos``); a wrong
    scale, sign or week in any orbit or clock field moves them by kilometres."""
    from navtrack.geodesy import ecef_to_enu
    from navtrack.gnss.spp import SppConfig
    from navtrack.io.rtklib import read_pos
    from navtrack.positioning import solve_positions

    log = read_ubx(WALK)
    assert list(log.nav.tables["E"]["sat"]) == ["E07", "E08", "E13", "E14", "E26", "E29", "E33"]
    assert (log.nav.tables["E"]["data_source"] == 513).all()
    ref = read_pos(DATA / "gnss_imu_walk_cut_rtk.pos")
    np.testing.assert_allclose(ref["t_gps_s"].to_numpy(), log.obs.t_gps_s, atol=1e-3)
    ref_xyz = ref[["x_m", "y_m", "z_m"]].to_numpy()
    xyz = {}
    for systems in ("G", "E"):
        sol = solve_positions(log.obs, [log.nav], config=SppConfig(systems=systems, iono="off"))
        frame = sol.to_frame()
        assert (frame["status"] == "ok").all(), systems
        xyz[systems] = frame[["x_m", "y_m", "z_m"]].to_numpy()
        enu = ecef_to_enu(xyz[systems], ref_xyz[0]) - ecef_to_enu(ref_xyz, ref_xyz[0])
        assert np.median(np.hypot(enu[:, 0], enu[:, 1])) < 15.0, systems
    assert np.median(np.linalg.norm(xyz["E"] - xyz["G"], axis=1)) < 10.0


@pytest.mark.skipif(shutil.which("rnx2rtkp") is None, reason="RTKLIB rnx2rtkp not installed")
def test_rtklib_positions_galileo_from_the_written_files(tmp_path: Path) -> None:
    """RTKLIB's own orbit and clock code on navtrack's Galileo records: ``rnx2rtkp -sys E`` on
    the RINEX files ``navtrack convert`` writes from the walk cut solves every epoch within
    15 m horizontally of the RTK trajectory."""
    from navtrack.cli import main
    from navtrack.geodesy import ecef_to_enu
    from navtrack.io.rtklib import read_pos

    obs, nav = tmp_path / "w.obs", tmp_path / "w.nav"
    assert main(["convert", str(WALK), "--out", str(obs)]) == 0
    out = tmp_path / "e.pos"
    cmd = ["rnx2rtkp", "-p", "0", "-sys", "E", "-e", "-o", str(out), str(obs), str(nav)]
    subprocess.run(cmd, check=True, capture_output=True)
    sol = read_pos(out)
    ref = read_pos(DATA / "gnss_imu_walk_cut_rtk.pos")
    assert len(sol) == len(ref) == 60
    ref_xyz = ref[["x_m", "y_m", "z_m"]].to_numpy()
    enu = ecef_to_enu(sol[["x_m", "y_m", "z_m"]].to_numpy(), ref_xyz[0]) - ecef_to_enu(
        ref_xyz, ref_xyz[0]
    )
    assert np.hypot(enu[:, 0], enu[:, 1]).max() < 15.0


def test_glonass_strings_as_convbin(tmp_path: Path) -> None:
    """GLONASS strings 1-4 of one frame (ublox-rs log, 18 RXM-SFRBX): the R02, R03, R12
    ephemerides equal convbin's field by field (UTC-dated toc, -TauN, message frame time in s of
    the UTC week, PZ-90 state in m, frequency channel from the SFRBX header), also after the
    RINEX writer and reader."""
    log = read_ubx(DATA / "ubloxrs_rxm_sfrbx_glo_cut.ubx")
    ours = log.nav.tables["R"]
    theirs = read_nav(DATA / "ubloxrs_rxm_sfrbx_glo_cut_convbin.nav").tables["R"]
    assert list(ours["sat"]) == list(theirs["sat"]) == ["R02", "R03", "R12"]
    write_nav(log.nav, tmp_path / "r.nav")
    back = read_nav(tmp_path / "r.nav").tables["R"]
    for name in theirs:
        if name not in ("line", "sat"):
            np.testing.assert_allclose(ours[name], theirs[name], rtol=1e-11, err_msg=name)
            np.testing.assert_allclose(back[name], ours[name], rtol=1e-11, err_msg=name)
    assert log.undecoded == {"R: non-immediate string (almanac, time)": 3}


def test_convert_refuses_what_is_not_a_ubx_log(tmp_path: Path) -> None:
    from navtrack.cli import CommandLineExit, main

    rinex = DATA / "pyubx2_rxmrawx_convbin.obs"
    with pytest.raises(CommandLineExit, match="is not a u-blox UBX log"):
        main(["convert", str(rinex), "--out", str(tmp_path / "x.obs")])
    with pytest.raises(CommandLineExit, match=r"give LOG --out FILE\.obs, or --example"):
        main(["convert", str(RAWX_1HZ)])
    with pytest.raises(CommandLineExit, match="does not exist"):
        main(["convert", str(RAWX_1HZ), "--out", str(tmp_path / "no" / "x.obs")])


def test_rawx_without_gps_time_counted_not_tagged(tmp_path: Path) -> None:
    """A receiver at start-up writes RXM-RAWX with week 0: the epoch cannot be dated, so it is
    counted in ``undated_epochs`` and left out (here the first of the 14, week set to 0 and
    the checksum recomputed with pyubx2)."""
    from pyubx2 import calc_checksum

    data = bytearray(RAWX_1HZ.read_bytes())
    assert data[2:4] == b"\x02\x15"
    length = int.from_bytes(data[4:6], "little")
    data[6 + 8 : 6 + 10] = b"\x00\x00"  # week (U2 at payload offset 8)
    data[6 + length : 8 + length] = calc_checksum(bytes(data[2 : 6 + length]))
    path = tmp_path / "start.ubx"
    path.write_bytes(bytes(data))
    log = read_ubx(path)
    assert log.undated_epochs == 1
    np.testing.assert_array_equal(log.obs.t_gps_s, read_ubx(RAWX_1HZ).obs.t_gps_s[1:])


def test_truncated_nmea_sentence_before_binary_messages(tmp_path: Path) -> None:
    """A logger that writes NMEA and UBX interleaved can cut a sentence short, so that the
    text runs into binary messages (the geofis/ppk ZED-F9P logs do so in their first 300
    bytes). Strict reading refuses it naming the byte; lenient reading skips the text up to
    its next line end (the first RXM-RAWX of this log with it) and reads the rest."""
    bad = tmp_path / "nmea_cut.ubx"
    bad.write_bytes(b"$GNGSV,3,1,12,02,,00" + RAWX_1HZ.read_bytes())
    with pytest.raises(FileFormatError, match="text line ending at byte 328: not NMEA"):
        read_ubx(bad)
    log = read_ubx(bad, lenient=True)
    assert [s.reason for s in log.skipped] == [
        "text line ending at byte 328: not NMEA (a truncated sentence?)"
    ]
    whole = read_ubx(RAWX_1HZ).obs.t_gps_s
    np.testing.assert_array_equal(log.obs.t_gps_s, whole[1:])


def test_a_damaged_length_does_not_swallow_the_next_messages(tmp_path: Path) -> None:
    """A damaged length field makes a message claim the bytes of the messages after it; with
    lenient reading framing resumes after the damaged message's sync characters, so only
    that message is lost (RTKLIB's decoder resynchronises the same way)."""
    data = bytearray(RAWX_1HZ.read_bytes())
    data[5] += 4  # the first RXM-RAWX's length, high byte: 1,024 bytes more than it has
    bad = tmp_path / "long.ubx"
    bad.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match="message at byte 0: checksum error"):
        read_ubx(bad)
    log = read_ubx(bad, lenient=True)
    whole = read_ubx(RAWX_1HZ).obs.t_gps_s
    np.testing.assert_array_equal(log.obs.t_gps_s, whole[1:])
