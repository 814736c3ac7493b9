"""Opening RINEX/SP3 files: decompression (gzip, bzip2, .Z, Hatanaka) and format sniffing."""

from __future__ import annotations

import bz2
import gzip
from pathlib import Path

import pytest

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.rinex import read_bytes, sniff

OBS2 = "07590920.05o"
OBS3 = "SEPT078M_120.21O"


def test_plain_gzip_bzip2(tmp_path: Path) -> None:
    raw = sample_path(OBS2).read_bytes()
    assert read_bytes(sample_path(OBS2)) == raw
    for name, data in (("a.gz", gzip.compress(raw)), ("a.bz2", bz2.compress(raw))):
        (tmp_path / name).write_bytes(data)
        assert read_bytes(tmp_path / name) == raw
    # The content decides, not the name.
    (tmp_path / "gz_named.o").write_bytes(gzip.compress(raw))
    assert read_bytes(tmp_path / "gz_named.o") == raw


@pytest.mark.parametrize("compression", ["none", "gz", "Z"])
def test_hatanaka(tmp_path: Path, compression: str) -> None:
    hatanaka = pytest.importorskip("hatanaka")
    raw = sample_path(OBS3).read_bytes()
    crx = hatanaka.compress(raw, compression=compression)
    if compression == "none":
        assert crx[60:80].startswith(b"CRINEX VERS")
    path = tmp_path / "a.crx"
    path.write_bytes(crx)
    back = read_bytes(path)
    # crx2rnx restores the RINEX text; trailing blanks of data lines are not kept.
    assert [r.rstrip() for r in back.splitlines()] == [r.rstrip() for r in raw.splitlines()]


def test_empty_and_damaged(tmp_path: Path) -> None:
    (tmp_path / "e").write_bytes(b"")
    with pytest.raises(FileFormatError, match="empty") as info:
        read_bytes(tmp_path / "e")
    assert info.value.line == 1
    (tmp_path / "d.gz").write_bytes(gzip.compress(b"x" * 1000)[:20])
    with pytest.raises(FileFormatError, match="damaged compressed") as info:
        read_bytes(tmp_path / "d.gz")
    assert info.value.path == str(tmp_path / "d.gz")


@pytest.mark.parametrize(
    ("content", "compression"),
    [
        (b"\x1f\x8b" + b"not gzip at all" * 10, "gzip"),  # gzip magic, then garbage
        # a valid gzip header, then bytes that are no deflate stream: zlib.error
        (b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03" + b"\xff" * 50, "gzip"),
        (gzip.compress(sample_path(OBS2).read_bytes())[:2000], "gzip"),  # cut stream
        (bz2.compress(sample_path(OBS2).read_bytes())[:2000], "bzip2"),
        (b"BZh9" + b"\x00" * 100, "bzip2"),
    ],
)
def test_damaged_compression_named_by_every_reader(
    tmp_path: Path, content: bytes, compression: str
) -> None:
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.sp3 import read_sp3

    path = tmp_path / "damaged"
    path.write_bytes(content)
    for reader in (read_bytes, read_obs, read_nav, read_sp3):
        with pytest.raises(
            FileFormatError, match=f"damaged compressed file \\({compression}: "
        ) as info:
            reader(path)
        assert info.value.path == str(path)


def test_sniff_rinex_and_sp3() -> None:
    kind = sniff(OBS2, sample_path(OBS2).read_bytes())
    assert (kind.format, kind.version, kind.file_type, kind.system) == ("rinex", 2.10, "O", "G")
    kind = sniff(OBS3, sample_path(OBS3).read_bytes())
    assert (kind.format, kind.version, kind.file_type, kind.system) == ("rinex", 3.04, "O", "M")
    kind = sniff("n", sample_path("07590920.05n").read_bytes())
    assert (kind.format, kind.file_type) == ("rinex", "N")
    kind = sniff("p", b"#dP2021  3 19  0  0  0.00000000     289 ORBIT IGb14 FIT  COD\n")
    assert (kind.format, kind.file_type, kind.version) == ("sp3", "d", 4.0)


@pytest.mark.parametrize(
    ("first", "match"),
    [
        (
            "     9.99           OBSERVATION DATA    G                   RINEX VERSION / TYPE",
            "unsupported RINEX version",
        ),
        (
            "     x.yz           OBSERVATION DATA    G                   RINEX VERSION / TYPE",
            "unreadable RINEX version",
        ),
        ("hello world", "not a RINEX file"),
    ],
)
def test_sniff_rejects(first: str, match: str) -> None:
    with pytest.raises(FileFormatError, match=match) as info:
        sniff("f.o", first.encode() + b"\n")
    assert info.value.line == 1
    assert info.value.path == "f.o"
