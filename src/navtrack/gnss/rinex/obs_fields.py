"""The data fields of RINEX observation files, decoded all at once.

A data line is the satellite id (RINEX 3: 3 characters) followed by ``F14.3,I1,I1`` fields (value,
loss-of-lock indicator, signal strength), 16 characters each. The lines of a file are gathered
into one fixed-width byte matrix (:func:`field_matrix`), or the fields wanted are taken from the
file's text at their columns (:func:`line_spans`, :func:`gather_columns`), and the fields are
decoded by vectorised digit arithmetic (:func:`decode_fields`). A value written in the standard
layout (decimal point in column 11 of the field, three decimals) is read as an integer number
of thousandths and divided by 1000: both are exact binary numbers and IEEE division is correctly
rounded, so the result equals Python's ``float(text)``. Fields in any other layout fall back to
``float()``; fields that are not numbers are flagged ``bad``.
"""

from __future__ import annotations

import re

import numpy as np

from navtrack._typing import FloatArray, Int8Array, IntArray

__all__ = [
    "FIELD_WIDTH", "decode_fields", "decode_some", "field_matrix", "gather_columns", "line_spans",
]  # fmt: skip

FIELD_WIDTH = 16
"""Characters of one ``F14.3,I1,I1`` field: value, LLI, signal strength."""

# Decoding works on each 16-byte field viewed as two little-endian uint64 words: ``lo`` holds
# characters 0-7 of the F14.3 value, ``hi`` characters 8-13 and the LLI and SSI characters. Byte
# predicates (is blank, is digit, is minus) are computed as 0/1 bytes and tested as whole words.
_U8 = np.dtype("<u8")
_ONES = 0x0101010101010101
_BLANKS = 0x2020202020202020
_LOW2, _LOW6 = 0xFFFF, 0xFFFFFFFFFFFF
# Blank prefix of length s (0..10) of characters 0-9 as 0/1 bytes, split over lo and hi; and a
# single minus sign right after it.
_PREFIX_LO = np.array([_ONES >> (8 * (8 - min(s, 8))) if s else 0 for s in range(11)], _U8)
_PREFIX_HI = np.array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0x01, 0x0101], _U8)
_MINUS_LO = np.array([1 << (8 * s) if s < 8 else 0 for s in range(11)], _U8)
_MINUS_HI = np.array([0] * 8 + [0x01, 0x0100, 0], _U8)
_SPACE = 32
# compiled (and cached by `re`) on the first field off the F14.3 layout, which few files have
_NUMBER = rb"[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+)?"


def decode_fields(
    fields: np.ndarray,
) -> tuple[FloatArray, Int8Array, Int8Array, np.ndarray, np.ndarray]:
    """Decode ``F14.3,I1,I1`` fields.

    Parameters
    ----------
    fields : ndarray of uint8, shape (n, 16)
        Field bytes (ASCII), blank-padded.

    Returns
    -------
    value : ndarray, shape (n,)
        NaN where the value is blank.
    lli, ssi : ndarray of int8, shape (n,)
        -1 where blank.
    blank : ndarray of bool, shape (n,)
        All 16 characters blank.
    bad : ndarray of bool, shape (n,)
        Not a number (or LLI/SSI not a digit).

    Notes
    -----
    A value in the standard layout (blanks, an optional minus sign, digits, the decimal point
    in character 10, three digits) is read as an integer number of thousandths with the
    8-digits-at-once multiplication of Lemire (2022) plus the remaining digits, then divided by
    1000 (exact operands, correctly rounded division: equal to ``float(text)``). Other layouts go
    through ``float()``.

    References
    ----------
    D. Lemire, "Number parsing at a gigabyte per second", Software: Practice and Experience 51
    (2021); the 8-digit SWAR step as in his blog post "Quickly parsing eight digits" (2018).
    """
    f = np.ascontiguousarray(fields)
    n = len(f)
    words = f.view(_U8)
    lo, hi = words[:, 0], words[:, 1]
    value_blank = (lo == _BLANKS) & ((hi & _LOW6) == (_BLANKS & _LOW6))
    digit = (f - np.uint8(48)) < 10
    sp = (f == _SPACE).view(_U8)
    mi = (f == 45).view(_U8)
    dg = digit.view(_U8)
    sp_lo, sp_hi = sp[:, 0], sp[:, 1] & _LOW2
    mi_lo, mi_hi = mi[:, 0], mi[:, 1] & _LOW2
    allowed = sp | mi | dg
    std = (allowed[:, 0] == _ONES) & ((allowed[:, 1] & _LOW2) == 0x0101)
    std &= f[:, 10] == 46
    std &= ((dg[:, 1] >> 24) & 0xFFFFFF) == 0x010101
    blanks = ((sp_lo * _ONES) >> 56) + (sp_hi & 0xFF) + (sp_hi >> 8)
    std &= (sp_lo == _PREFIX_LO[blanks]) & (sp_hi == _PREFIX_HI[blanks])
    negative = (mi_lo | mi_hi) != 0
    std &= ~negative | ((mi_lo == _MINUS_LO[blanks]) & (mi_hi == _MINUS_HI[blanks]))
    dv = ((f - np.uint8(48)) * digit).view(_U8)  # digit values, 0 for anything else
    v: np.ndarray = dv[:, 0]
    v = (v * 2561) >> 8
    v = ((v & 0x00FF00FF00FF00FF) * 6553601) >> 16
    v = ((v & 0x0000FFFF0000FFFF) * 42949672960001) >> 32  # characters 0-7
    h = dv[:, 1]
    integer = v * 100 + (h & 0xFF) * 10 + ((h >> 8) & 0xFF)
    frac = ((h >> 24) & 0xFF) * 100 + ((h >> 32) & 0xFF) * 10 + ((h >> 40) & 0xFF)
    value = (integer * 1000 + frac).astype(np.float64) / 1000.0
    np.negative(value, out=value, where=negative)
    value[value_blank] = np.nan
    bad = np.zeros(n, dtype=bool)
    for k in np.flatnonzero(~std & ~value_blank).tolist():  # other layouts: float(), if a number
        text = f[k, :14].tobytes().strip()
        if re.fullmatch(_NUMBER, text):
            value[k] = float(text.replace(b"D", b"E").replace(b"d", b"e"))
        else:
            bad[k] = True
            value[k] = np.nan
    lli = _indicator(f[:, 14])
    ssi = _indicator(f[:, 15])
    bad |= (lli == -2) | (ssi == -2)
    lli[lli == -2] = -1
    ssi[ssi == -2] = -1
    blank = value_blank & (f[:, 14] == _SPACE) & (f[:, 15] == _SPACE)
    return value, lli, ssi, blank, bad


def decode_some(
    fields: np.ndarray, which: np.ndarray
) -> tuple[FloatArray, Int8Array, Int8Array, np.ndarray, np.ndarray]:
    """:func:`decode_fields` of the fields ``which`` only, scattered back to all fields: the others
    are NaN with indicators -1, never ``bad``, and ``blank`` where all 16 characters are."""
    n = len(fields)
    words = np.ascontiguousarray(fields).view(_U8)
    blank = (words[:, 0] == _BLANKS) & (words[:, 1] == _BLANKS)
    value = np.full(n, np.nan)
    lli = np.full(n, -1, dtype=np.int8)
    ssi = np.full(n, -1, dtype=np.int8)
    bad = np.zeros(n, dtype=bool)
    value[which], lli[which], ssi[which], _, bad[which] = decode_fields(fields[which])
    return value, lli, ssi, blank, bad


def _indicator(c: np.ndarray) -> Int8Array:
    """Digit -> 0..9, blank -> -1, anything else -> -2 (bad)."""
    out = c.astype(np.int8) - np.int8(48)
    out[c == _SPACE] = -1
    out[(c != _SPACE) & ((c < 48) | (c > 57))] = -2
    return out


def field_matrix(data: list[bytes], lead: int) -> np.ndarray:
    """Data lines as an (n, lead + 16 k) uint8 matrix, blank-padded to whole fields."""
    lengths = np.fromiter(map(len, data), dtype=np.int64, count=len(data))
    return _matrix(np.frombuffer(b"".join(data), dtype=np.uint8), lengths, lead)


def _matrix(chars: np.ndarray, lengths: IntArray, lead: int) -> np.ndarray:
    """The lines whose characters, one after the other, are ``chars`` as a blank-padded matrix."""
    longest = int(lengths.max()) if lengths.size else lead
    width = lead + FIELD_WIDTH * max(1, -(-(longest - lead) // FIELD_WIDTH))
    # the lines' characters fill the rows in order, blanks the rest (no padded copy per line)
    out = np.full((len(lengths), width), _SPACE, dtype=np.uint8)
    out[np.arange(width) < lengths[:, None]] = chars
    return out


def line_spans(data: bytes) -> tuple[IntArray, IntArray]:
    """Start offset and length of every line of ``data``, the lines of ``data.split(b"\\n")``."""
    newline = np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == 10)
    start = np.concatenate((np.zeros(1, dtype=np.int64), newline + 1))
    return start, np.append(newline, len(data)) - start


def gather_columns(
    buf: np.ndarray, start: IntArray, length: IntArray, column: IntArray, width: int
) -> np.ndarray:
    """The ``width`` characters from 0-based ``column`` of each line (``start``, ``length`` in
    the uint8 buffer ``buf``) as an (n, width) uint8 matrix, blank past the line's end."""
    at = np.minimum(start + column, len(buf))  # fields past the text's end: blanked below
    if len(at) and int(at.max()) > len(buf) - width:  # a field at the very end of the text
        buf = np.concatenate((buf, np.full(width, _SPACE, dtype=np.uint8)))
    # every run of `width` characters of the text as a row: a field is one row
    out = np.lib.stride_tricks.sliding_window_view(buf, width)[at]
    short = np.flatnonzero(length < column + width)
    if len(short):
        past = np.arange(width) >= (length[short] - column[short])[:, None]
        out[short[:, None], np.arange(width)] = np.where(past, _SPACE, out[short])
    return out
