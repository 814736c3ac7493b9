"""Seeded mutations of a file's bytes: the damage a file meets on disk, in transfer or by hand.

Every operator takes the original bytes, a ``numpy.random.Generator`` and the length of the
file's header (in lines; 0 when the format has none) and returns the damaged bytes and the
1-based line the damage is on (None when it has no single line: empty, binary, header only).
"""

from __future__ import annotations

import gzip
import re
from collections.abc import Callable

import numpy as np

Mutation = tuple[bytes, int | None]
Operator = Callable[[bytes, np.random.Generator, int], Mutation]

_NUMBER = re.compile(rb"-?\d+\.\d+(?:[EeDd][+-]?\d+)?|-?\d+")
_HUGE = (b"NaN", b"nan", b"inf", b"-inf", b"1e400", b"999999999999", b"-1e308", b"")


def _lines(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True)


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _body_line(lines: list[bytes], rng: np.random.Generator, header: int) -> int:
    """A random line index of the data section (the header when there is no data)."""
    lo = min(header, len(lines) - 1)
    return int(rng.integers(lo, len(lines)))


def truncate(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    cut = int(rng.integers(1, max(len(data), 2)))
    return data[:cut], _line_of(data, cut)


def flip_bytes(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    out = bytearray(data)
    first = None
    for _ in range(int(rng.integers(1, 4))):
        k = int(rng.integers(0, len(out)))
        out[k] ^= int(rng.integers(1, 256))
        first = k if first is None else min(first, k)
    return bytes(out), _line_of(data, first or 0)


def delete_line(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    lines = _lines(data)
    k = _body_line(lines, rng, header)
    return b"".join(lines[:k] + lines[k + 1 :]), k + 1


def duplicate_line(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    lines = _lines(data)
    k = _body_line(lines, rng, header)
    return b"".join(lines[: k + 1] + lines[k:]), k + 2


def garbage_line(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    lines = _lines(data)
    k = _body_line(lines, rng, header)
    junk = bytes(rng.integers(32, 127, size=int(rng.integers(1, 90))).astype(np.uint8)) + b"\n"
    return b"".join([*lines[:k], junk, *lines[k:]]), k + 1


def empty(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    return b"", None


def binary(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    head = (b"\x1f\x8b", b"PK\x03\x04", b"\x89PNG", b"")[int(rng.integers(0, 4))]
    return head + bytes(rng.integers(0, 256, size=2048).astype(np.uint8)), None


def fake_gzip(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    """gzip magic bytes on content that is not gzip, or a real gzip stream cut short."""
    if rng.random() < 0.5:
        return b"\x1f\x8b" + data, None
    packed = gzip.compress(data, mtime=0)  # no time stamp: the same mutant every run
    return packed[: int(rng.integers(10, len(packed)))], None


def header_only(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    lines = _lines(data)
    return b"".join(lines[: max(header, 1)]), None


def bad_number(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    """One number of the data section replaced by NaN, inf, 1e400, a huge value or nothing,
    right-aligned in its field where it fits."""
    lines = _lines(data)
    for _ in range(20):
        k = _body_line(lines, rng, header)
        found = list(_NUMBER.finditer(lines[k]))
        if found:
            break
    else:
        return data, None
    m = found[int(rng.integers(0, len(found)))]
    value = _HUGE[int(rng.integers(0, len(_HUGE)))]
    width = m.end() - m.start()
    value = value.rjust(width) if len(value) <= width else value
    lines[k] = lines[k][: m.start()] + value + lines[k][m.end() :]
    return b"".join(lines), k + 1


def swap_lines(data: bytes, rng: np.random.Generator, header: int) -> Mutation:
    """Two data lines swapped: timestamps (and records) out of order."""
    lines = _lines(data)
    i, j = sorted(_body_line(lines, rng, header) for _ in range(2))
    lines[i], lines[j] = lines[j], lines[i]
    return b"".join(lines), i + 1


OPERATORS: dict[str, Operator] = {
    "truncate": truncate,
    "flip_bytes": flip_bytes,
    "delete_line": delete_line,
    "duplicate_line": duplicate_line,
    "garbage_line": garbage_line,
    "empty": empty,
    "binary": binary,
    "fake_gzip": fake_gzip,
    "header_only": header_only,
    "bad_number": bad_number,
    "swap_lines": swap_lines,
}
