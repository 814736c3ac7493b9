"""One table reader for every command that takes a table file: the format follows the suffix.

:func:`read_table` reads RTKLIB solution files (``.pos``, through
:func:`navtrack.io.rtklib.read_pos`), CSV (``.csv``, ``.txt``; ``#`` starts a comment) and
Parquet (``.parquet``). A CSV or Parquet table that carries navtrack's solution columns
(``time_gps``, ``week``, ``tow_s``) is read as a solution table by
:func:`navtrack.io.solution.read_solution`, so it gains ``t_gps_s`` and its time columns are
checked against each other.

CSV content is sniffed before pandas sees it (:func:`read_csv_text`), and each row of a CSV
table keeps the file line it came from (``DataFrame.attrs["file_line"]``, :func:`file_line`),
so that :func:`numeric_column` can name the line of a value that is not a finite number.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pandas as pd

from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError, MissingDependencyError
from navtrack.io.rtklib import read_pos
from navtrack.io.solution import read_solution

__all__ = [
    "TABLE_SUFFIXES",
    "file_line",
    "last_row_cut",
    "numeric_column",
    "read_csv_text",
    "read_table",
]

#: Suffixes :func:`read_table` understands (compared lower-cased).
TABLE_SUFFIXES = (".pos", ".csv", ".txt", ".parquet")

# Columns whose presence marks a navtrack solution table (io.solution.SOLUTION_COLUMNS' times).
_SOLUTION_TIME_COLUMNS = frozenset({"time_gps", "week", "tow_s"})


def read_table(path: StrPath) -> pd.DataFrame:
    """Read a table file, its format chosen by the suffix.

    Parameters
    ----------
    path : str or path-like
        ``.pos`` (RTKLIB solution), ``.csv``/``.txt`` (comma-separated, ``#`` comments) or
        ``.parquet``.

    Returns
    -------
    pandas.DataFrame
        RTKLIB files as :func:`navtrack.io.rtklib.read_pos` returns them; navtrack solution
        tables as :func:`navtrack.io.solution.read_solution` returns them (with ``t_gps_s``);
        any other table as read. CSV tables carry ``attrs["file_line"]``, the 1-based file
        line of each row (see :func:`file_line`).

    Raises
    ------
    FileFormatError
        Unknown suffix, content that is not a table of that format, or a CSV whose last row
        has no end of line (a file cut mid-line, :func:`last_row_cut`); the message names the
        file, and the line when there is one.
    MissingDependencyError
        A Parquet file without pyarrow installed.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".pos":
        return read_pos(p)
    lines = None
    if suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401  # optional dependency (extra navtrack[parquet])
        except ImportError:
            raise MissingDependencyError("pyarrow", "parquet", f"Parquet input ({p})") from None
        try:
            df = pd.read_parquet(p)
        except (OSError, ValueError) as exc:  # pyarrow's ArrowInvalid is a ValueError
            raise FileFormatError(p, None, f"not a Parquet table: {exc}") from None
    elif suffix in (".csv", ".txt"):
        text = read_csv_text(p)
        try:
            df = pd.read_csv(io.StringIO(text), comment="#")
        except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
            raise FileFormatError(p, None, f"not a CSV table: {exc}") from None
        lines = _data_lines(text)
        if not text.endswith(("\n", "\r")) and last_row_cut(text, "#"):
            raise FileFormatError(
                p,
                int(lines[-1]),
                "last row cut short by the end of the file (no end of line; end the file "
                "with a line break if the row is whole)",
            )
    else:
        raise FileFormatError(
            p, None, f"unknown table suffix {suffix!r} (known: {', '.join(TABLE_SUFFIXES)})"
        )
    if set(df.columns) >= _SOLUTION_TIME_COLUMNS:
        df = read_solution(p)
    if lines is not None and len(lines) == len(df) + 1:
        df.attrs["file_line"] = lines[1:]
    return df


def read_csv_text(path: StrPath) -> str:
    """The file's text, refused with :class:`FileFormatError` when it is not a UTF-8 CSV.

    The content is sniffed before pandas sees it (pandas can spend minutes on a compressed or
    binary file): gzip magic bytes, a NUL byte, or a first character ``{``/``[`` (JSON) are
    refused. A byte sequence that is not UTF-8 is an error naming its line rather than a row
    read with replacement characters: in these files it means damage or another encoding, and
    a replaced character would silently change an id or a value.
    """
    with open(path, "rb") as fh:
        raw = fh.read()
    if raw[:2] == b"\x1f\x8b":
        raise FileFormatError(path, None, "gzip-compressed file, not a CSV (decompress it first)")
    nul = raw.find(b"\x00")
    if nul >= 0:
        line = raw.count(b"\n", 0, nul) + 1
        raise FileFormatError(path, line, "binary content (NUL byte), not a CSV")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = exc.start + (3 if raw.startswith(b"\xef\xbb\xbf") else 0)
        line = raw.count(b"\n", 0, start) + 1
        raise FileFormatError(
            path, line, f"byte 0x{raw[start]:02x} is not UTF-8 text (damaged or other encoding)"
        ) from None
    if text.lstrip()[:1] in ("{", "["):
        raise FileFormatError(path, 1, "JSON content, not a CSV")
    return text


def last_row_cut(text: str, comment: str | None = None) -> bool:
    """True when the last row looks cut by the end of the file: it has no end of line (every
    row before it has one) or fewer fields than the header. A field cut short leaves no other
    trace, so a last row without its end of line is never taken as data.

    ``comment`` starts a comment: lines empty before it are not rows (nor the header).
    """
    lines = text.rstrip().splitlines()
    if comment is not None:
        lines = [ln for ln in lines if ln.split(comment, 1)[0].strip()]
    if len(lines) < 2:
        return False
    if not text.endswith(("\n", "\r")):
        return True
    header = next(csv.reader(lines[:1]))
    last = next(csv.reader(lines[-1:]))
    return len(last) < len(header)


def _data_lines(text: str) -> np.ndarray:
    """1-based numbers of the lines pandas reads as header and rows (``comment="#"``: lines
    blank before any ``#`` are skipped)."""
    kept = [k + 1 for k, line in enumerate(text.splitlines()) if line.split("#", 1)[0].strip()]
    return np.array(kept, dtype=np.int64)


def file_line(df: pd.DataFrame, row: int) -> int | None:
    """The file line of row ``row`` (0-based position) of a table from :func:`read_table`,
    or None when the table does not know its lines (Parquet, RTKLIB ``.pos``)."""
    lines = df.attrs.get("file_line")
    if lines is None or not 0 <= row < len(lines):
        return None
    return int(lines[row])


def numeric_column(path: StrPath, df: pd.DataFrame, column: str) -> FloatArray:
    """One column of a table as floats, every value a finite number or missing (NaN).

    Parameters
    ----------
    path : str or path-like
        The file the table was read from (named in errors).
    df : pandas.DataFrame
        The table, as :func:`read_table` returns it.
    column : str
        Column name.

    Returns
    -------
    ndarray, shape (len(df),)
        The values; NaN where the field is empty.

    Raises
    ------
    FileFormatError
        A field that is not a number (text, a repeated header line) or is infinite (``inf``,
        or a number beyond the float range such as ``1e400``), naming the file line.
    """
    raw = df[column]
    values = pd.to_numeric(raw, errors="coerce").to_numpy(dtype=float)
    text = raw.notna().to_numpy() & np.isnan(values)
    if text.any():
        k = int(np.argmax(text))
        value = str(raw.iloc[k])
        why = " (the header line repeated)" if value == column else ""
        raise FileFormatError(
            path, file_line(df, k), f"column {column!r}: {value!r} is not a number{why}"
        )
    infinite = np.isinf(values)
    if infinite.any():
        k = int(np.argmax(infinite))
        raise FileFormatError(
            path,
            file_line(df, k),
            f"column {column!r}: infinite value (inf, or a number beyond the float range of "
            "about 1.8e308)",
        )
    return values
