"""One table reader for every command that takes a table file: the format follows the suffix.

:func:`read_table` reads RTKLIB solution files (``.pos``, through
:func:`navtrack.io.rtklib.read_pos`), CSV (``.csv``, ``.txt``; ``#`` starts a comment) and
Parquet (``.parquet``). A CSV or Parquet table that carries navtrack's solution columns
(``time_gps``, ``week``, ``tow_s``) is read as a solution table by
:func:`navtrack.io.solution.read_solution`, so it gains ``t_gps_s`` and its time columns are
checked against each other.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from navtrack._typing import StrPath
from navtrack.errors import FileFormatError, MissingDependencyError

__all__ = ["TABLE_SUFFIXES", "read_table"]

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
        any other table as read.

    Raises
    ------
    FileFormatError
        Unknown suffix, or content that is not a table of that format (the message names the
        file).
    MissingDependencyError
        A Parquet file without pyarrow installed.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".pos":
        from navtrack.io.rtklib import read_pos

        return read_pos(p)
    if suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise MissingDependencyError("pyarrow", "parquet", f"Parquet input ({p})") from None
        df = pd.read_parquet(p)
    elif suffix in (".csv", ".txt"):
        try:
            df = pd.read_csv(p, comment="#")
        except (pd.errors.ParserError, UnicodeDecodeError, pd.errors.EmptyDataError) as exc:
            raise FileFormatError(p, None, f"not a CSV table: {exc}") from None
    else:
        raise FileFormatError(
            p, None, f"unknown table suffix {suffix!r} (known: {', '.join(TABLE_SUFFIXES)})"
        )
    if set(df.columns) >= _SOLUTION_TIME_COLUMNS:
        from navtrack.io.solution import read_solution

        return read_solution(p)
    return df
