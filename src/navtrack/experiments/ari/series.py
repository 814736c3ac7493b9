"""One real data set as the ARI reproduction fits it: columns on a uniform time grid."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from navtrack._frozen import freeze_arrays
from navtrack._typing import FloatArray

__all__ = ["RealSeries"]


@dataclass(frozen=True, slots=True)
class RealSeries:
    """Columns of one real data set on a uniform time grid (NaN = missing epoch).

    Attributes
    ----------
    source : str
    t_s : ndarray, shape (n,)
    columns : dict of str to ndarray (n,)
    unit : str
    dt_s : float
    n_inserted : int
        Epochs inserted into gaps by :func:`navtrack.smoothing.ari.regularize_time`.
    meta : dict
        Provenance of the series (for GNSS solutions: solver, run, epochs, solved, statuses).
    """

    source: str
    t_s: FloatArray
    columns: dict[str, FloatArray]
    unit: str
    dt_s: float
    n_inserted: int = 0
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        freeze_arrays(self)
        for values in self.columns.values():
            values.flags.writeable = False
