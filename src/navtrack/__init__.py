"""navtrack: positioning, navigation integrity and multi-target tracking.

Submodules are imported on demand (``navtrack.gnss.rinex``, ``navtrack.tracking``, ...)
so that ``import navtrack`` and the ``navtrack`` command start quickly.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
