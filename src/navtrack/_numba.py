"""numba, the optional accelerator (extra ``speed``): one switch for every compiled kernel.

Everything works without it: each compiled kernel has a NumPy or Python path with the same
results (the tests compare them). A non-empty environment variable ``NAVTRACK_NO_NUMBA``
disables it, e.g. to time or test those paths.
"""

from __future__ import annotations

import importlib.util
import os
from functools import lru_cache
from typing import Any

__all__ = ["HAVE_NUMBA", "jit", "numba_module"]

#: True when numba is installed and not disabled (checked without importing it).
HAVE_NUMBA = importlib.util.find_spec("numba") is not None and not os.environ.get(
    "NAVTRACK_NO_NUMBA"
)


@lru_cache(maxsize=1)
def numba_module() -> Any:
    """The numba module (imported on the first call, about a second), or None when it is not
    installed or disabled by ``NAVTRACK_NO_NUMBA``."""
    if not HAVE_NUMBA:
        return None
    import numba

    return numba


def jit(fn: Any) -> Any:
    """``fn`` compiled by numba (nopython, without the GIL, cached on disk; compiled on its
    first call for the argument types it gets), or None without numba."""
    numba = numba_module()
    return None if numba is None else numba.njit(cache=True, nogil=True)(fn)
