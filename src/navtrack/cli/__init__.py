"""The ``navtrack`` command.

argparse rather than a decorator framework: it ships with Python, costs nothing at start-up (the
positioning command is timed as a whole process against RTKLIB), and keeps each command a plain
function over the library. The command list of ``navtrack --help`` is :data:`COMMANDS` (module
and one-line summary of each command): only the module of the command that runs is imported,
and it registers its own sub-parser.

One error path for every command (:func:`main`): a command reports trouble by raising, and
:func:`main` prints one line ``navtrack CMD: error: FILE:LINE: what`` on stderr and returns the
exit code

* :data:`EXIT_OK` (0) -- the command ran and solved what it was asked;
* :data:`EXIT_UNSOLVED` (1) -- it ran, but nothing could be solved (the command returns it);
* :data:`EXIT_BAD_INPUT` (2) -- bad input: a malformed file
  (:class:`~navtrack.errors.FileFormatError` and every other
  :class:`~navtrack.errors.NavtrackError`), a file that cannot be opened
  (``OSError``), a refused option (a command raises ``SystemExit("navtrack CMD: why")``;
  :func:`main` prints the error line and raises :class:`CommandLineExit`, exit 2, as
  argparse's own usage errors do);
* :data:`EXIT_INTERNAL` (3) -- an unexpected exception (a defect in navtrack): a short message
  and a hint to rerun with ``--debug``; 3 keeps it apart from 1, which scripts read as "no
  solution".

No traceback is printed unless ``navtrack --debug CMD ...`` is given. Output piped into a
reader that stops early (``navtrack pos ... | head``) is dropped once the pipe closes, without a
``Broken pipe`` message; the command still runs to its end, so its ``--out`` file and figures
are written and its exit code is its own.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from typing import Any, TextIO

from navtrack import __version__
from navtrack._record import Record
from navtrack.errors import FileFormatError, NavtrackError


class Command(Record):
    """A command of ``navtrack``: the module whose ``register(subparsers)`` adds its sub-parser,
    and the summary ``navtrack --help`` lists."""

    module: str
    summary: str


# In the order ``--help`` lists them.
COMMANDS = {
    "pos": Command(
        "navtrack.cli.pos",
        "single point positioning of a RINEX observation file or an Android raw log",
    ),
    "rinex": Command("navtrack.cli.rinex", "inspect RINEX and SP3 files"),
    "convert": Command(
        "navtrack.cli.convert",
        "convert a u-blox UBX raw log to RINEX 3.04 observation and navigation files",
    ),
    "track": Command(
        "navtrack.cli.track",
        "track real AIS / ADS-B / CSV detections and score against their ids",
    ),
    "smooth": Command(
        "navtrack.cli.smooth",
        "ARI filtering of time series: sigma_n, sigma_e, sigma_x, r(h), gross errors",
    ),
    "reproduce": Command(
        "navtrack.cli.reproduce",
        "reproduce a seed paper's experiment (tables, figures, results.json)",
    ),
    "rtk": Command(
        "navtrack.cli.rtk", "carrier-phase relative positioning (RTK) of a rover against a base"
    ),
    "ppp": Command(
        "navtrack.cli.ppp",
        "static precise point positioning with SP3 orbits and clocks (and clock files)",
    ),
    "agps": Command(
        "navtrack.cli.agps",
        "two-satellite AGPS fix from two epochs (Marquardt / Gauss-Newton / MAP)",
    ),
    "attitude": Command(
        "navtrack.cli.attitude",
        "attitude reconstruction from gyro rates and camera fixes (paper 6)",
    ),
}

EXIT_OK = 0
EXIT_UNSOLVED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3


def _command_of(argv: Sequence[str]) -> str | None:
    """The command word of ``argv`` (the first word that is not an option), if any."""
    return next((w for w in argv if not w.startswith("-")), None)


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The top-level parser. With ``argv`` naming a command, that command's module is imported
    and registers its sub-parser (start-up stays at the cost of what the command uses);
    otherwise (``--help``, no or an unknown command) every command is listed from
    :data:`COMMANDS` without importing any."""
    parser = argparse.ArgumentParser(
        prog="navtrack",
        description="Positioning, navigation integrity and multi-target tracking on real data.",
        epilog="Exit codes: 0 solved, 1 ran but nothing could be solved, 2 bad input or "
        "options, 3 internal error (rerun with --debug for the traceback).",
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"navtrack {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="print the Python traceback of any error"
    )
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=_CommandParser
    )
    command = _command_of(argv) if argv is not None else None
    if command in COMMANDS:
        importlib.import_module(COMMANDS[command].module).register(subparsers)
    else:
        for name, entry in COMMANDS.items():
            subparsers.add_parser(name, help=entry.summary, add_help=False)
    return parser


class _Formatter(argparse.HelpFormatter):
    """argparse's formatter, sized to the terminal without importing :mod:`shutil`.

    argparse builds a formatter for every option it registers and asks
    ``shutil.get_terminal_size`` for the width; importing :mod:`shutil` (with :mod:`lzma`,
    :mod:`bz2`) costs more than registering ``pos``'s options. The width is the same:
    ``COLUMNS``, else the terminal of standard output, else 80 columns.
    """

    def __init__(
        self,
        prog: str,
        indent_increment: int = 2,
        max_help_position: int = 24,
        width: int | None = None,
    ) -> None:
        if width is None:  # as argparse: the terminal's columns less a margin of 2
            width = _columns() - 2
        super().__init__(prog, indent_increment, max_help_position, width)


def _columns() -> int:
    """Columns of the terminal as :func:`shutil.get_terminal_size` reports them."""
    try:
        columns = int(os.environ["COLUMNS"])
    except (KeyError, ValueError):
        columns = 0
    if columns > 0:
        return columns
    try:
        return os.get_terminal_size(sys.__stdout__.fileno()).columns or 80  # type: ignore[union-attr]
    except (AttributeError, ValueError, OSError):
        return 80


class DefaultsHelpFormatter(_Formatter):
    """``--help`` that states every default: ``(default: VALUE)`` after each option's help.

    Options whose help already says its default (a default that depends on the input, "default:
    all present") keep their own words; switches (``store_true``) and options without a default
    (``None``) get nothing.
    """

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default is None
            or default is False
            or default is argparse.SUPPRESS
            or default == []
            or not (action.option_strings or action.nargs in ("?", "*"))
        ):
            return action.help
        return f"{text} (default: %(default)s)"


class _CommandParser(argparse.ArgumentParser):
    """The parser of one command: its ``--help`` states the defaults."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", DefaultsHelpFormatter)
        super().__init__(*args, **kwargs)


def command_name(args: argparse.Namespace) -> str:
    """``navtrack CMD`` as typed: the command and its sub-command, if it has one."""
    words = ["navtrack"]
    if getattr(args, "command", None):
        words.append(args.command)
        sub = getattr(args, f"{args.command}_command", None)
        if sub:
            words.append(sub)
    return " ".join(words)


def error_message(exc: BaseException) -> str:
    """The ``FILE:LINE: what`` part of an error line (``FILE: what`` without a line)."""
    if isinstance(exc, FileFormatError):
        where = exc.path if exc.line is None else f"{exc.path}:{exc.line}"
        return f"{where}: {exc.message}"
    if isinstance(exc, OSError) and exc.filename is not None:
        return f"{exc.filename}: {exc.strerror or exc}"
    return str(exc)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the process exit code (module notes)."""
    words = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(words)
    args = parser.parse_args(words)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_BAD_INPUT
    name = command_name(args)
    stdout = sys.stdout
    sys.stdout = _PipeSafe(stdout)
    try:
        return int(args.func(args) or EXIT_OK)
    except SystemExit as exc:
        if not isinstance(exc.code, str):
            raise
        message = _strip_prefix(exc.code, name)
        _report(name, message, exc, args.debug)
        raise CommandLineExit(message) from None
    except (NavtrackError, OSError) as exc:
        _report(name, error_message(exc), exc, args.debug)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # the defect path: one line, the traceback behind --debug
        _report(
            name,
            f"internal error {type(exc).__name__}: {exc} (this is a navtrack defect; rerun with "
            "navtrack --debug ... for the traceback and report it)",
            exc,
            args.debug,
        )
        return EXIT_INTERNAL
    finally:
        sys.stdout.flush()
        sys.stdout = stdout


class CommandLineExit(SystemExit):
    """Exit 2 for a refused command line, raised by :func:`main` after printing the error line.

    A command refuses its options with ``SystemExit("navtrack CMD: why")``; :func:`main`
    prints ``navtrack CMD: error: why`` and raises this instead, whose exit code is
    :data:`EXIT_BAD_INPUT` (so the interpreter prints nothing more) and whose ``str()`` is
    still the message (so ``pytest.raises(SystemExit, match=...)`` reads it).
    """

    def __init__(self, message: str) -> None:
        super().__init__(EXIT_BAD_INPUT)
        self.message = message

    def __str__(self) -> str:
        return self.message


def _strip_prefix(message: str, name: str) -> str:
    """A command's own ``"navtrack CMD: ..."`` message without that prefix."""
    for prefix in (f"{name}: ", f"{name.rsplit(' ', 1)[0]}: "):
        if message.startswith(prefix):
            return message[len(prefix) :]
    return message


def _report(name: str, message: str, exc: BaseException, debug: bool) -> None:
    if debug:
        import traceback  # only with --debug: its import (linecache, tokenize) slows every start

        traceback.print_exception(exc, file=sys.stderr)
    print(f"{name}: error: {message}", file=sys.stderr)


class _PipeSafe:
    """``sys.stdout`` that drops its output once the reading end of a pipe has closed.

    The first ``BrokenPipeError`` points the file descriptor at ``os.devnull`` (so that the
    interpreter's last flush at exit succeeds too) and every later write is discarded.
    """

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self._closed = False

    def write(self, text: str) -> int:
        if not self._closed:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._drop()
        return len(text)

    def flush(self) -> None:
        if not self._closed:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._drop()

    def _drop(self) -> None:
        self._closed = True
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())
            os.close(devnull)
        except (OSError, ValueError):  # not a real file descriptor (captured output)
            pass

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)
