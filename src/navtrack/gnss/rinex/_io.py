"""Opening RINEX and SP3 files: decompression and format sniffing, shared by every reader."""

from __future__ import annotations

import importlib
import zlib
from os import fspath
from pathlib import Path

from navtrack._record import Record
from navtrack._typing import StrPath
from navtrack.errors import FileFormatError, MissingDependencyError

_GZIP_MAGIC = b"\x1f\x8b"
_LZW_MAGIC = b"\x1f\x9d"
_BZ2_MAGIC = b"BZh"
# magic bytes, name, standard-library module (imported when a file needs it)
_DECOMPRESSORS = ((_GZIP_MAGIC, "gzip", "gzip"), (_BZ2_MAGIC, "bzip2", "bz2"))


def read_bytes(path: StrPath) -> bytes:
    """Whole content of a (possibly compressed) text file as bytes.

    gzip and bzip2 are handled by the standard library; Unix ``.Z`` and Hatanaka (Compact RINEX,
    ``.crx``/``.##d``) need the ``hatanaka`` package (``navtrack[crx]``). The compression is
    recognised from the content, not the file name.

    Raises
    ------
    FileFormatError
        For an empty file or a damaged compressed stream.
    """
    raw = Path(path).read_bytes()
    if raw.startswith(_LZW_MAGIC):
        raw = _hatanaka_decompress(path, raw)
    for magic, name, module in _DECOMPRESSORS:
        if raw.startswith(magic):
            try:
                raw = importlib.import_module(module).decompress(raw)
            except (OSError, EOFError, ValueError, zlib.error) as exc:
                # zlib.error (bad deflate data) is not an OSError; a cut stream is an EOFError
                message = f"damaged compressed file ({name}: {exc})"
                raise FileFormatError(path, None, message) from exc
            break
    if raw[60:71] == b"CRINEX VERS":
        raw = _hatanaka_decompress(path, raw)
    if not raw or raw.isspace():  # all whitespace, tested without a copy of the file
        raise FileFormatError(path, 1, "empty file")
    return raw


def ends_inside_field(data: bytes, lead: int, width: int, complete: tuple[int, ...]) -> bool:
    """Whether a fixed-column file was cut in the middle of a field of its last line.

    A file cut at a random byte ends with no end-of-line after its last line; that line is cut
    when, its trailing blanks removed, it does not end where a field of the format can end.
    A last line without an end-of-line that ends on a field boundary reads as complete.

    Parameters
    ----------
    data : bytes
        Whole (decompressed) file content.
    lead : int
        Characters before the first field of the line (satellite id, indentation).
    width : int
        Characters per field.
    complete : tuple of int
        Offsets within a field, modulo ``width``, at which a written field may end.
    """
    if data.endswith((b"\n", b"\r")):
        return False
    last = data[data.rfind(b"\n") + 1 :].rstrip()
    return bool(last) and (len(last) < lead or (len(last) - lead) % width not in complete)


def _hatanaka_decompress(path: StrPath, raw: bytes) -> bytes:
    try:
        import hatanaka
    except ImportError:
        raise MissingDependencyError("hatanaka", "crx", f"reading {fspath(path)}") from None
    try:
        return bytes(hatanaka.decompress(raw))
    except Exception as exc:  # hatanaka raises its own exception types
        raise FileFormatError(path, None, f"cannot decompress ({exc})") from exc


class FileKind(Record, eq=True):
    """What a file is, from its first line (a named tuple: every reader imports it, and a
    dataclass compiles its methods at import, a cost every ``navtrack pos`` start would pay).

    Attributes
    ----------
    format : {"rinex", "sp3"}
    version : float
        RINEX version (2.10, 3.04, ...) or SP3 version letter's number (a=1, c=3, d=4).
    file_type : str
        RINEX file type letter (``O`` observation, ``N`` navigation, ``G`` GLONASS navigation,
        ...) or the SP3 version letter.
    system : str
        RINEX satellite system letter (``M`` mixed; blank means GPS) or ``""`` for SP3.
    """

    format: str
    version: float
    file_type: str
    system: str


def sniff(path: StrPath, data: bytes) -> FileKind:
    """Identify a RINEX or SP3 file from its first line.

    Raises
    ------
    FileFormatError
        When the first line is neither a ``RINEX VERSION / TYPE`` record nor an SP3 header.
    """
    newline = data.find(b"\n")  # the first line without a copy of the rest of the file
    first = data[: newline if newline >= 0 else None].rstrip(b"\r").decode("ascii", "replace")
    if first.startswith("#") and len(first) > 2 and first[1] in "abcd":
        return FileKind("sp3", float("abcd".index(first[1]) + 1), first[1], "")
    if first[60:].startswith("RINEX VERSION / TYPE"):
        try:
            version = float(first[:9])
        except ValueError:
            raise FileFormatError(path, 1, f"unreadable RINEX version {first[:9]!r}") from None
        file_type = first[20:21].upper()
        system = first[40:41].upper() or "G"
        if version < 2 or version >= 5:
            raise FileFormatError(path, 1, f"unsupported RINEX version {version}")
        return FileKind("rinex", version, file_type, system if system.strip() else "G")
    raise FileFormatError(
        path, 1, "not a RINEX file (no 'RINEX VERSION / TYPE' in line 1) nor an SP3 file"
    )
