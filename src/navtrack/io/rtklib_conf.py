"""Reader of RTKLIB configuration files (``rnx2rtkp -k FILE.conf``) for ``navtrack pos``.

An RTKLIB option file has one ``name = value`` per line, ``#`` starting a comment. The options
that single point positioning in navtrack has are mapped to navtrack's settings
(:class:`RtklibConf`); every other option must keep the value RTKLIB's ``rnx2rtkp`` resolves
for single point positioning (:data:`IGNORED_DEFAULTS`), or the file is refused with the option's
name and line, so that no setting a user relies on is silently dropped. Written from the option
list RTKLIB's manual and ``rnx2rtkp`` show (``shared/data/gnss/rtklib_spp/conf/*.full.conf``);
no RTKLIB code was used.

References
----------
T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix C (configuration parameters).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from navtrack._typing import StrPath
from navtrack.errors import FileFormatError

__all__ = ["IGNORED_DEFAULTS", "RtklibConf", "read_conf"]

#: The options navtrack's single point positioning has no counterpart for, with the value
#: ``rnx2rtkp`` 2.4.3 b34 resolves for single point positioning (its full option listing): a
#: file may repeat these values, any other value is refused.
IGNORED_DEFAULTS = {
    "pos1-soltype": "forward",
    "pos1-snrmask_r": "off",
    "pos1-snrmask_b": "off",
    "pos1-snrmask_L1": "0,0,0,0,0,0,0,0,0",
    "pos1-snrmask_L2": "0,0,0,0,0,0,0,0,0",
    "pos1-snrmask_L5": "0,0,0,0,0,0,0,0,0",
    "pos1-dynamics": "off",
    "pos1-tidecorr": "off",
    "pos1-posopt1": "off",
    "pos1-posopt2": "off",
    "pos1-posopt3": "off",
    "pos1-posopt4": "off",
    "pos1-posopt5": "off",
    "pos1-posopt6": "off",
    "pos1-exclsats": "",
    "pos2-armode": "continuous",
    "pos2-gloarmode": "on",
    "pos2-bdsarmode": "on",
    "pos2-arthres": "3",
    "pos2-arthres1": "0.9999",
    "pos2-arthres2": "0.25",
    "pos2-arthres3": "0.1",
    "pos2-arthres4": "0.05",
    "pos2-arlockcnt": "0",
    "pos2-arelmask": "0",
    "pos2-arminfix": "10",
    "pos2-armaxiter": "1",
    "pos2-elmaskhold": "0",
    "pos2-aroutcnt": "5",
    "pos2-maxage": "30",
    "pos2-syncsol": "off",
    "pos2-slipthres": "0.05",
    "pos2-rejionno": "30",
    "pos2-niter": "1",
    "pos2-baselen": "0",
    "pos2-basesig": "0",
    "out-outhead": "on",
    "out-outopt": "on",
    "out-timesys": "gpst",
    "out-timeform": "hms",
    "out-timendec": "3",
    "out-degform": "deg",
    "out-fieldsep": "",
    "out-outsingle": "off",
    "out-maxsolstd": "0",
    "out-height": "ellipsoidal",
    "out-geoid": "internal",
    "out-solstatic": "all",
    "out-nmeaintv1": "0",
    "out-nmeaintv2": "0",
    "out-outstat": "off",
    "stats-eratio1": "100",
    "stats-eratio2": "100",
    "stats-errphase": "0.003",
    "stats-errphaseel": "0.003",
    "stats-errphasebl": "0",
    "stats-errdoppler": "1",
    "stats-stdbias": "30",
    "stats-stdiono": "0.03",
    "stats-stdtrop": "0.3",
    "stats-prnaccelh": "0.1",
    "stats-prnaccelv": "0.01",
    "stats-prnbias": "0.0001",
    "stats-prniono": "0.001",
    "stats-prntrop": "0.0001",
    "stats-prnpos": "0",
    "stats-clkstab": "5e-12",
    "ant1-postype": "llh",
    "ant1-pos1": "0",
    "ant1-pos2": "0",
    "ant1-pos3": "0",
    "ant1-anttype": "",
    "ant1-antdele": "0",
    "ant1-antdeln": "0",
    "ant1-antdelu": "0",
    "ant2-postype": "llh",
    "ant2-pos1": "0",
    "ant2-pos2": "0",
    "ant2-pos3": "0",
    "ant2-anttype": "",
    "ant2-antdele": "0",
    "ant2-antdeln": "0",
    "ant2-antdelu": "0",
    "ant2-maxaveep": "0",
    "ant2-initrst": "off",
    "misc-timeinterp": "off",
    "misc-sbasatsel": "0",
    "misc-rnxopt1": "",
    "misc-rnxopt2": "",
    "misc-pppopt": "",
    "file-satantfile": "",
    "file-rcvantfile": "",
    "file-staposfile": "",
    "file-geoidfile": "",
    "file-ionofile": "",
    "file-dcbfile": "",
    "file-eopfile": "",
    "file-blqfile": "",
    "file-tempdir": "",
    "file-geexefile": "",
    "file-solstatfile": "",
    "file-tracefile": "",
}

# pos1-navsys bits (RTKLIB's system mask) -> navtrack system letters; SBAS (2) has none.
_NAVSYS_BITS = {1: "G", 4: "R", 8: "E", 16: "J", 32: "C"}
_IONO = {"off": "off", "brdc": "klobuchar", "dual-freq": "ionofree"}
_TROPO = {"off": "off", "saas": "saastamoinen"}
_EPHEMERIS = {"brdc": False, "precise": True}


@dataclass(frozen=True, slots=True)
class RtklibConf:
    """The settings of an RTKLIB option file that navtrack applies (None: not in the file).

    Attributes
    ----------
    path : str
        The file.
    systems : str, optional
        System letters of ``pos1-navsys``.
    elmask_deg : float, optional
        ``pos1-elmask`` (deg).
    iono : {"off", "klobuchar", "ionofree"}, optional
        ``pos1-ionoopt`` (``off``, ``brdc``, ``dual-freq``; ``dual-freq`` needs
        ``pos1-frequency=l1+2``).
    tropo : {"off", "saastamoinen"}, optional
        ``pos1-tropopt`` (``off``, ``saas``).
    precise_ephemeris : bool, optional
        ``pos1-sateph=precise`` (SP3 orbits, given with ``--sp3``) or ``brdc``.
    max_gdop : float, optional
        ``pos2-rejgdop``.
    lines : dict of str to int
        Line of each option read (for messages).
    """

    path: str
    systems: str | None = None
    elmask_deg: float | None = None
    iono: str | None = None
    tropo: str | None = None
    precise_ephemeris: bool | None = None
    max_gdop: float | None = None
    lines: dict[str, int] = field(default_factory=dict)


def _same(value: str, default: str) -> bool:
    """Option values equal as text or as numbers (``15`` and ``15.0``)."""
    if value == default:
        return True
    try:
        return float(value) == float(default)
    except ValueError:
        return False


def _choice(path: Path, lineno: int, name: str, value: str, table: dict[str, object]) -> object:
    if value not in table:
        raise FileFormatError(
            path,
            lineno,
            f"{name}={value} is not supported by navtrack pos (supported: {', '.join(table)})",
        )
    return table[value]


def _number(path: Path, lineno: int, name: str, value: str) -> float:
    try:
        return float(value)
    except ValueError:
        raise FileFormatError(path, lineno, f"{name}={value}: not a number") from None


def _systems(path: Path, lineno: int, value: str) -> str:
    mask = int(_number(path, lineno, "pos1-navsys", value))
    unknown = mask & ~sum(_NAVSYS_BITS)
    if unknown or mask <= 0:
        raise FileFormatError(
            path,
            lineno,
            f"pos1-navsys={value}: navtrack pos has GPS 1, GLONASS 4, Galileo 8, QZSS 16, "
            "BeiDou 32 (not SBAS 2 or NavIC 64)",
        )
    return "".join(s for bit, s in _NAVSYS_BITS.items() if mask & bit)


#: The options :func:`read_conf` turns into settings (every other option must keep RTKLIB's
#: single point default, :data:`IGNORED_DEFAULTS`).
_HANDLED = {
    "pos1-posmode", "pos1-frequency", "pos1-elmask", "pos1-ionoopt", "pos1-tropopt",
    "pos1-sateph", "pos1-navsys", "pos2-rejgdop", "out-solformat", "out-outvel",
}  # fmt: skip


def _option_lines(p: Path) -> dict[str, tuple[int, str]]:
    """``name -> (line, value)`` of every ``name = value`` line (comments after ``#``)."""
    values: dict[str, tuple[int, str]] = {}
    for lineno, raw in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        name, eq, value = line.partition("=")
        name, value = name.strip(), value.strip()
        if not eq or not name:
            raise FileFormatError(p, lineno, f"expected 'name = value', got {raw.strip()!r}")
        values[name] = (lineno, value)
    return values


def _check_options(p: Path, values: dict[str, tuple[int, str]]) -> None:
    """Refuse an unknown option, an unhandled one away from its default, and the output and
    mode settings navtrack pos does not write."""

    def fail(name: str, why: str) -> FileFormatError:
        return FileFormatError(p, values[name][0], f"{name}={values[name][1]}: {why}")

    for name, (lineno, value) in values.items():
        if name in _HANDLED:
            continue
        if name not in IGNORED_DEFAULTS:
            raise FileFormatError(p, lineno, f"{name}: not an RTKLIB 2.4.3 option")
        if not _same(value, IGNORED_DEFAULTS[name]):
            default = IGNORED_DEFAULTS[name] or "(empty)"
            raise FileFormatError(
                p, lineno, f"{name}={value}: navtrack pos has no such option (only {default})"
            )
    if "pos1-posmode" in values and values["pos1-posmode"][1] != "single":
        raise fail("pos1-posmode", "navtrack pos is single point positioning (single)")
    if "out-solformat" in values and values["out-solformat"][1] != "xyz":
        raise fail("out-solformat", "navtrack pos writes RTKLIB's xyz format (--out x.pos)")
    if "out-outvel" in values and values["out-outvel"][1] != "off":
        raise fail("out-outvel", "the .pos file has no velocity columns (they are in .csv)")


def _settings(p: Path, values: dict[str, tuple[int, str]]) -> dict[str, object]:
    """The :class:`RtklibConf` fields the handled options set (FileFormatError: a frequency
    that does not go with the ionosphere option)."""
    get = values.get
    conf: dict[str, object] = {}
    if (item := get("pos1-elmask")) is not None:
        conf["elmask_deg"] = _number(p, item[0], "pos1-elmask", item[1])
    if (item := get("pos2-rejgdop")) is not None:
        conf["max_gdop"] = _number(p, item[0], "pos2-rejgdop", item[1])
    if (item := get("pos1-navsys")) is not None:
        conf["systems"] = _systems(p, item[0], item[1])
    if (item := get("pos1-ionoopt")) is not None:
        conf["iono"] = _choice(p, item[0], "pos1-ionoopt", item[1], dict(_IONO))
    if (item := get("pos1-tropopt")) is not None:
        conf["tropo"] = _choice(p, item[0], "pos1-tropopt", item[1], dict(_TROPO))
    if (item := get("pos1-sateph")) is not None:
        conf["precise_ephemeris"] = _choice(p, item[0], "pos1-sateph", item[1], dict(_EPHEMERIS))
    freq = values.get("pos1-frequency", (0, "l1"))[1]
    dual = conf.get("iono") == "ionofree"
    if freq not in ("l1", "l1+2") or (freq == "l1+2") != dual:
        raise FileFormatError(
            p,
            values.get("pos1-frequency", values.get("pos1-ionoopt", (None, "")))[0],
            f"pos1-frequency={freq} with pos1-ionoopt="
            f"{values.get('pos1-ionoopt', (0, 'brdc'))[1]}: navtrack pos uses L1 alone, or "
            "L1+L2 for the iono-free combination (pos1-ionoopt=dual-freq)",
        )
    return conf


def read_conf(path: StrPath) -> RtklibConf:
    """Read an RTKLIB option file.

    Parameters
    ----------
    path : str or path-like
        The ``.conf`` file.

    Returns
    -------
    RtklibConf

    Raises
    ------
    FileFormatError
        Naming the file and line: a line that is not ``name = value``, an option RTKLIB does
        not have, an option navtrack pos does not have set to another value than RTKLIB's
        single point default (:data:`IGNORED_DEFAULTS`), or a value navtrack does not support
        (``pos1-posmode`` other than ``single``, ``out-solformat`` other than ``xyz``, ...).
    """
    p = Path(path)
    values = _option_lines(p)
    _check_options(p, values)
    conf = _settings(p, values)
    lines = {name: lineno for name, (lineno, _) in values.items()}
    return RtklibConf(path=str(p), lines=lines, **conf)  # type: ignore[arg-type]
