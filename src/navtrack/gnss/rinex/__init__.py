"""RINEX 2.x/3.x observation and navigation readers.

``read_obs`` turns an observation file into :class:`navtrack.gnss.observations.Observations`;
``read_nav`` turns a navigation file into :class:`navtrack.gnss.rinex.nav.NavData`. Both accept
plain, gzip, bzip2, ``.Z`` and Hatanaka-compressed files, and raise
:class:`navtrack.errors.FileFormatError` naming file and line for malformed input.
"""

from navtrack.gnss.rinex._io import FileKind, read_bytes, sniff
from navtrack.gnss.rinex.obs import read_obs

__all__ = ["FileKind", "read_bytes", "read_obs", "sniff"]
