"""The positioning pipeline: single point positioning with its validation or integrity monitoring.

:func:`solve_positions` chains the stages of :mod:`navtrack.gnss.spp` (signals -> satellite
states -> corrections -> estimate) block by block with the validation stage of the run:
RTKLIB's validity tests (:func:`navtrack.gnss.spp.validate`) or, when RAIM is asked, integrity
monitoring (:func:`navtrack.integrity.raim.monitor`: detection, exclusion, protection levels).
It returns a :class:`PositionSolution`, an :class:`~navtrack.gnss.spp.SppResult` that carries the
integrity of every epoch. ``navtrack pos``, the network run (:mod:`.network`) and the
experiments call it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from navtrack._typing import FloatArray, Int8Array
from navtrack.gnss.spp import (
    CHUNK_EPOCHS,
    Measurements,
    PositionEstimate,
    ProgressFn,
    SppConfig,
    SppResult,
    concatenate_results,
    estimated_blocks,
    spp_result,
    validate,
)
from navtrack.gnss.spp import solution_frame as spp_solution_frame
from navtrack.io.solution import solution_table

if TYPE_CHECKING:
    import pandas as pd

    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3
    from navtrack.integrity.raim import IntegrityResult, RaimConfig

__all__ = ["PositionSolution", "solution_frame", "solve_positions"]


class PositionSolution(SppResult):
    """Single point positions of all epochs (:class:`~navtrack.gnss.spp.SppResult`) with the
    integrity monitoring of every epoch.

    Attributes
    ----------
    integrity : IntegrityResult, optional
        Detection, exclusion and protection levels of every epoch
        (:func:`navtrack.integrity.raim.monitor`); None when the run validated with RTKLIB's
        tests instead.
    """

    integrity: IntegrityResult | None = None

    def frame_columns(self) -> dict[str, np.ndarray]:
        """The solution frame with the integrity columns (:func:`solution_frame`)."""
        return solution_frame(self)

    def to_frame(self) -> pd.DataFrame:
        """The solution as a pandas DataFrame, one row per epoch: ``t_gps_s`` and the columns
        ``pos --out`` writes, as :func:`navtrack.io.solution.read_solution` reads them back."""
        table = solution_table(self.frame_columns())
        table.insert(0, "t_gps_s", self.t_gps_s)
        return table


def solve_positions(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    raim: RaimConfig | None = None,
    x0_m: FloatArray | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
    chunk_epochs: int = CHUNK_EPOCHS,
    progress: ProgressFn | None = None,
) -> PositionSolution:
    """Single point positions of every epoch, validated or monitored for integrity.

    Parameters
    ----------
    obs, nav, sp3, config, x0_m, ephemeris, chunk_epochs, progress
        As :func:`navtrack.gnss.spp.solve_spp`.
    raim : RaimConfig, optional
        Integrity monitoring (:func:`navtrack.integrity.raim.monitor`) in place of
        :func:`navtrack.gnss.spp.validate`: detection, exclusion, protection levels
        (``PositionSolution.integrity``).

    Returns
    -------
    PositionSolution
    """
    cfg = config or SppConfig()
    check = _validation(cfg, raim)
    parts: list[SppResult] = []
    integrity: list[IntegrityResult] = []
    for block in estimated_blocks(
        obs, nav, sp3=sp3, config=cfg, x0_m=x0_m, ephemeris=ephemeris, chunk_epochs=chunk_epochs
    ):
        est, status, integ = check(block.measurements, block.estimate)
        parts.append(spp_result(block.measurements, est, status))
        if integ is not None:
            integrity.append(integ)
        if progress is not None:
            progress(block.done, block.total)
    result = parts[0] if len(parts) == 1 else concatenate_results(parts)
    joined = None
    if integrity:
        joined = integrity[0] if len(integrity) == 1 else type(integrity[0]).concatenate(integrity)
    fields = {name: getattr(result, name) for name in SppResult.record_fields}
    return PositionSolution(**fields, integrity=joined)


Validation = Callable[
    [Measurements, PositionEstimate], tuple[PositionEstimate, Int8Array, "IntegrityResult | None"]
]
"""The validation stage of a block: its estimate (re-estimated after exclusion), the
:class:`~navtrack.gnss.spp.SppStatus` of each epoch and the integrity (None without RAIM)."""


def _validation(config: SppConfig, raim: RaimConfig | None) -> Validation:
    """RTKLIB's validity tests, or integrity monitoring when ``raim`` is given."""
    if raim is None:
        return lambda meas, est: (est, validate(est, config), None)
    # integrity monitoring is imported only when asked for: pos's start-up without RAIM
    from navtrack.integrity.raim import monitor

    return lambda meas, est: monitor(meas, est, config, raim)


def solution_frame(result: SppResult) -> dict[str, np.ndarray]:
    """The solution frame of a result (:func:`navtrack.gnss.spp.solution_frame`) and, for a
    :class:`PositionSolution` with integrity monitoring, its columns ``raim_status`` (name),
    ``excluded``, ``hpl_m``, ``vpl_m``, ``test_stat``, ``threshold`` and ``emt_m``
    (:meth:`navtrack.integrity.raim.IntegrityResult.frame_columns`)."""
    cols = spp_solution_frame(result)
    if isinstance(result, PositionSolution) and result.integrity is not None:
        cols.update(result.integrity.frame_columns(result.sats))
    return cols
