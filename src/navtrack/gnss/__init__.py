"""GNSS: file readers, satellite orbits and clocks, corrections and positioning.

The names most scripts need, imported on first use (so that ``import navtrack.gnss`` stays
cheap)::

    from navtrack.gnss import read_nav, read_obs
from navtrack.positioning import solve_positions

    result = solve_positions(read_obs("07590920.05o"), read_nav("07590920.05n"))
    table = result.to_frame()  # pandas, one row per epoch: position, status, DOPs, ...
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["SppConfig", "read_gnsslogger", "read_nav", "read_obs", "read_sp3", "solve_spp"]

_HOMES = {
    "SppConfig": "navtrack.gnss.spp",
    "read_gnsslogger": "navtrack.gnss.android",
    "read_nav": "navtrack.gnss.rinex.nav",
    "read_obs": "navtrack.gnss.rinex.obs",
    "read_sp3": "navtrack.gnss.sp3",
    "solve_spp": "navtrack.gnss.spp",
}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'navtrack.gnss' has no attribute {name!r}")
    return getattr(importlib.import_module(home), name)
