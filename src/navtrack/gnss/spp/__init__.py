"""Single point positioning (SPP): weighted least squares on code pseudoranges, all epochs at once.

:func:`solve_spp` is a chain of named stages over ``(epochs, satellites)`` arrays with boolean
masks, in the order of RTKLIB's ``pntpos``:

1. :func:`code_pseudoranges` -> :class:`Pseudoranges`: the signals of the configuration;
2. :func:`satellite_states` -> :class:`SatelliteStates`: orbits, clocks, URA, health and group
   delays at transmission (``satposs``);
3. :func:`corrected_measurements` -> :class:`Measurements`: pseudoranges corrected for satellite
   clock and group delay (ionosphere-free if asked), usability masks, clock groups (``prange``);
4. :func:`estimate_position` -> :class:`PositionEstimate`: one batched Gauss–Newton
   (:func:`navtrack.estimation.least_squares.gauss_newton`) whose per-epoch model (the kernel)
   re-evaluates elevation mask, ionosphere, troposphere and weights at every iterate, as RTKLIB's
   ``rescode`` does (``estpos``). It takes a per-(epoch, satellite) exclusion mask and a subset
   of epochs and returns residuals, design matrix, weights, state, covariance, redundancy,
   iterations and status: what fault detection and exclusion need (:func:`merge_estimates`
   puts the re-estimates of some epochs back into the estimate of all);
5. :func:`validate`: chi-square test of the weighted residuals and GDOP limit (``valsol``; the
   stage that integrity monitoring replaces in the positioning pipeline,
   :mod:`navtrack.positioning`);
6. :func:`spp_result` -> :class:`SppResult`.

The stages live in one module each (:mod:`.signals`, :mod:`.satellites`, :mod:`.measurements`,
:mod:`.model`, :mod:`.estimate`, :mod:`.result`; configuration, statuses and RTKLIB's error
constants in :mod:`.config`) and are all importable from here. :func:`estimated_blocks` runs
stages 1-4 block by block for a caller that validates on its own.

Blocks of :data:`CHUNK_EPOCHS` epochs bound the memory of long files. Unknowns per epoch: ECEF
position, the receiver clock of the first clock group and one inter-system bias (ISB) per
further group (QZSS shares GPS's clock by default, as in RTKLIB 2.4.3). Each epoch ends with a
``status``:

=================== =====================================================================
``ok``              solved, passed the validity tests
``no_ephemeris``    satellites observed, but none has a usable ephemeris (nav file of another
                    day or system, all unhealthy)
``too_few_sats``    fewer usable satellites than unknowns (4 + one per extra clock group),
                    including epochs without any pseudorange of the selected systems
``singular_geometry`` normal matrix singular
``no_convergence``  Gauss–Newton did not converge in ``max_iter`` steps
``rejected_validity`` chi-square test of the weighted residuals failed
``high_dop``        GDOP above ``max_gdop``
=================== =====================================================================

References
----------
T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix E.6 (SPP estimator, variance model,
validation); E. D. Kaplan, C. J. Hegarty, *Understanding GPS/GNSS*, 3rd ed., 2017, 11.2 (WLS,
DOPs); J. Sanz Subirana et al., *GNSS Data Processing* vol. I, ESA TM-23, 2013, 6.1 (ISB).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING

from navtrack._record import Record
from navtrack._typing import FloatArray
from navtrack.gnss.spp.config import (
    CHUNK_EPOCHS,
    CODE_PRIORITY,
    DEFAULT_CLOCK_GROUP,
    IONOFREE_BANDS,
    PRIMARY_BAND,
    STATUS_NAMES,
    ProgressFn,
    SppConfig,
    SppStatus,
)
from navtrack.gnss.spp.estimate import (
    PositionEstimate,
    dops,
    estimate_position,
    merge_estimates,
    validate,
)
from navtrack.gnss.spp.measurements import Measurements, corrected_measurements
from navtrack.gnss.spp.model import measurement_variance
from navtrack.gnss.spp.result import SppResult, concatenate_results, solution_frame, spp_result
from navtrack.gnss.spp.satellites import SatelliteStates, navigation_tables, satellite_states
from navtrack.gnss.spp.signals import (
    Pseudoranges,
    code_pseudoranges,
    klobuchar_params,
    observation_codes,
    select_pseudoranges,
    start_position,
    subset_epochs,
)

if TYPE_CHECKING:
    from navtrack.gnss.ephemeris import EphemerisTable
    from navtrack.gnss.observations import Observations
    from navtrack.gnss.rinex.nav import NavData
    from navtrack.gnss.sp3 import Sp3

__all__ = [
    "CHUNK_EPOCHS",
    "CODE_PRIORITY",
    "DEFAULT_CLOCK_GROUP",
    "IONOFREE_BANDS",
    "PRIMARY_BAND",
    "STATUS_NAMES",
    "EstimatedBlock",
    "Measurements",
    "PositionEstimate",
    "ProgressFn",
    "Pseudoranges",
    "SatelliteStates",
    "SppConfig",
    "SppResult",
    "SppStatus",
    "code_pseudoranges",
    "concatenate_results",
    "corrected_measurements",
    "dops",
    "estimate_position",
    "estimated_blocks",
    "klobuchar_params",
    "measurement_variance",
    "merge_estimates",
    "navigation_tables",
    "observation_codes",
    "satellite_states",
    "select_pseudoranges",
    "solution_frame",
    "solve_spp",
    "spp_result",
    "start_position",
    "subset_epochs",
    "validate",
]


class EstimatedBlock(Record):
    """Stages 1-4 of one block of epochs: its measurements, their estimate, and the number of
    epochs done with it (``done`` of ``total``)."""

    measurements: Measurements
    estimate: PositionEstimate
    done: int
    total: int


def estimated_blocks(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    x0_m: FloatArray | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
    chunk_epochs: int = CHUNK_EPOCHS,
) -> Iterator[EstimatedBlock]:
    """Stages :func:`code_pseudoranges` -> :func:`satellite_states` ->
    :func:`corrected_measurements` -> :func:`estimate_position` of each block of
    ``chunk_epochs`` epochs, in order (parameters as :func:`solve_spp`).

    Raises
    ------
    ValueError
        ``chunk_epochs`` below 1.
    """
    if chunk_epochs < 1:
        raise ValueError(f"chunk_epochs: expected a positive number of epochs, got {chunk_epochs}")
    cfg = config or SppConfig()
    tables = navigation_tables(nav, ephemeris)
    n = obs.t_gps_s.size
    for a in range(0, max(n, 1), chunk_epochs):
        block = obs if n <= chunk_epochs else subset_epochs(obs, slice(a, a + chunk_epochs))
        pr = code_pseudoranges(block, cfg)
        sv = satellite_states(pr, nav, sp3=sp3, config=cfg, ephemeris=tables)
        meas = corrected_measurements(pr, sv, cfg)
        est = estimate_position(meas, cfg, x0_m=x0_m)
        yield EstimatedBlock(meas, est, min(a + chunk_epochs, n), n)


def solve_spp(
    obs: Observations,
    nav: NavData | Sequence[NavData] | None = None,
    *,
    sp3: Sp3 | None = None,
    config: SppConfig | None = None,
    x0_m: FloatArray | None = None,
    ephemeris: Mapping[str, EphemerisTable] | None = None,
    chunk_epochs: int = CHUNK_EPOCHS,
    progress: ProgressFn | None = None,
) -> SppResult:
    """Single point positions of every epoch of an observation set.

    Runs the stages :func:`code_pseudoranges` -> :func:`satellite_states` ->
    :func:`corrected_measurements` -> :func:`estimate_position` -> :func:`validate` ->
    :func:`spp_result` on blocks of ``chunk_epochs`` epochs (joined by
    :func:`concatenate_results`). With integrity monitoring in place of :func:`validate`:
    :func:`navtrack.positioning.solve_positions`.

    Parameters
    ----------
    obs : Observations
        RINEX or Android observations.
    nav : NavData or sequence of NavData, optional
        Broadcast navigation data (orbits and clocks unless ``sp3`` is given; group delays and
        Klobuchar parameters in any case).
    sp3 : Sp3, optional
        Precise orbits and clocks; then broadcast records only provide group delays.
    config : SppConfig, optional
    x0_m : ndarray, shape (3,), optional
        Start position (ECEF, m; default: the header's approximate position when plausible,
        else the earth's centre).
    ephemeris : mapping of str to EphemerisTable, optional
        Pre-built tables (otherwise built from ``nav``).
    chunk_epochs : int
        Epochs per block: bounds the memory of the ``(epochs, satellites, unknowns)`` arrays.
        Clock groups are chosen per block (a system seen in one block only has a NaN ISB
        elsewhere).
    progress : callable, optional
        ``progress(epochs_done, epochs_total)``, called after each block.

    Returns
    -------
    SppResult
    """
    cfg = config or SppConfig()
    parts = []
    for block in estimated_blocks(
        obs, nav, sp3=sp3, config=cfg, x0_m=x0_m, ephemeris=ephemeris, chunk_epochs=chunk_epochs
    ):
        est = block.estimate
        parts.append(spp_result(block.measurements, est, validate(est, cfg)))
        if progress is not None:
            progress(block.done, block.total)
    return parts[0] if len(parts) == 1 else concatenate_results(parts)
