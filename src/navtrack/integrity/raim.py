"""Receiver autonomous integrity monitoring over all epochs of an SPP estimate: the stage that
replaces :func:`navtrack.gnss.spp.validate` in the positioning pipeline
(:mod:`navtrack.positioning`).

:func:`monitor` runs one of the :data:`METHODS`, each an object of the table
:data:`MONITORS` over the kernels of :mod:`.residuals` (chi-square test, normalised residuals,
weighted-RAIM slopes), :mod:`.separation` (fault hypotheses, solution separation),
:mod:`.exclusion` (which satellites to remove) and :mod:`.levels` (protection levels on the
ISM error model):

* ``chi2``: detection only;
* ``loo``: RTKLIB-like leave-one-out single exclusion;
* ``fde``: iterative exclusion of the largest normalised residual;
* ``fcm``: iterative exclusion of the fuzzy clustering's gross errors (paper 2);
* ``ss``: solution separation over one and two faulty satellites;
* ``araim``: the ARAIM MHSS user algorithm (:mod:`.araim`);

then re-estimation without the excluded satellites and protection levels after exclusion.

References
----------
T. Walter, P. Enge, "Weighted RAIM for precision approach", ION GPS 1995, 1995-2004 (slopes,
``p_bias``, HPL/VPL). R. G. Brown, "A baseline GPS RAIM scheme and a note on the equivalence
of three RAIM methods", Navigation 39(3), 1992 (parity space). RTKLIB 2.4.3 ``pntpos.c``
``raim_fde`` (leave-one-out). Gu et al. 2019 (:mod:`.fcm`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import IntEnum
from types import MappingProxyType
from typing import Literal, Protocol

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, Int8Array, IntArray
from navtrack.estimation.chi2 import chi2_quantile
from navtrack.gnss.spp import (
    Measurements,
    PositionEstimate,
    SppConfig,
    SppStatus,
    estimate_position,
    merge_estimates,
    validate,
)
from navtrack.integrity.exclusion import fcm_pick, largest_residual_pick, leave_one_out_pick
from navtrack.integrity.ism import ErrorModel, Ism, default_ism
from navtrack.integrity.levels import bounded_separation_levels, bounded_wraim_levels, model_rows
from navtrack.integrity.residuals import chi2_test, chi2_thresholds, n_params, whitened
from navtrack.integrity.separation import Separation, solution_separation

__all__ = [
    "METHODS",
    "MONITORS",
    "STATUS_NAMES",
    "IntegrityResult",
    "Monitor",
    "RaimConfig",
    "RaimStatus",
    "monitor",
    "variance_factor",
]

RaimMethod = Literal["chi2", "loo", "fde", "ss", "fcm", "araim"]
METHODS: tuple[str, ...] = ("chi2", "loo", "fde", "ss", "fcm", "araim")


class RaimStatus(IntEnum):
    """Per-epoch integrity outcome (printed in lower case)."""

    OK = 0
    """Tested: consistent, nothing excluded."""
    EXCLUDED = 1
    """A fault was detected, satellites were excluded and the rest passed the test."""
    ALERT = 2
    """A fault was detected and not removed (``chi2``, or exclusion failed)."""
    UNAVAILABLE = 3
    """Too few satellites to detect (``n < 3 + clocks + 1``), or to exclude after a
    detection (``n < 3 + clocks + 2``), or no solution."""


STATUS_NAMES = tuple(s.name.lower() for s in RaimStatus)


@dataclass(frozen=True, slots=True)
class RaimConfig:
    """Options of :func:`monitor`.

    Attributes
    ----------
    method : {"chi2", "loo", "fde", "ss", "fcm", "araim"}
        Detection only; RTKLIB-like leave-one-out single exclusion; iterative exclusion of the
        largest normalised residual; solution separation with up to ``max_faults``
        simultaneous faults; fuzzy c-means identification (paper 2); the ARAIM MHSS user
        algorithm (:mod:`.araim`, its own allocations from the ISM: ``pfa``/``pmd`` unused).
    pfa : float
        False-alarm probability of the detection test per epoch (default 1e-3, RTKLIB's
        chi-square significance in ``valsol``).
    pmd : float
        Missed-detection probability of the protection levels (default 1e-3, Walter & Enge's
        WRAIM example).
    max_exclusions : int
        Satellites ``fde`` and ``fcm`` may exclude in total (``loo``: 1; ``ss``: ``max_faults``).
    max_faults : int
        Largest fault hypothesis of ``ss`` (1 or 2).
    fcm_m : float
        FCM weighting exponent (Bezdek's 2; the paper gives none).
    fcm_tol : float
    fcm_max_iter : int
    fcm_stop : {"memberships", "centres"}
        FCM stopping rule: change of the memberships (Bezdek) or of the cluster centres (the
        paper's, section 3.2), both below ``fcm_tol``.
    ism : Ism, optional
        Integrity support message and error model behind every protection level
        (:mod:`.ism`); default :func:`.ism.default_ism` (the ADD baseline).
    variance_factor : float, optional
        Scale ``s^2`` of the measurement variances of the SPP weighting (``sigma^2 s^2``);
        default: estimated from the block of epochs by :func:`variance_factor`. RTKLIB's
        receiver model is conservative: ``s^2`` is 0.04-0.24 on the shared files, and with
        ``s^2 = 1`` the test misses faults of 10-20 m.
    """

    method: str = "fde"
    pfa: float = 1e-3
    pmd: float = 1e-3
    max_exclusions: int = 3
    max_faults: int = 2
    fcm_m: float = 2.0
    fcm_tol: float = 1e-6
    fcm_max_iter: int = 100
    fcm_stop: str = "memberships"
    ism: Ism | None = None
    variance_factor: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method: expected one of {', '.join(METHODS)}, got {self.method!r}")
        for name in ("pfa", "pmd"):
            v = getattr(self, name)
            if not 0.0 < v < 0.5:
                raise ValueError(f"{name}: expected a probability in (0, 0.5), got {v}")
        if self.max_exclusions < 1:
            raise ValueError(f"max_exclusions: expected >= 1, got {self.max_exclusions}")
        if self.max_faults not in (1, 2):
            raise ValueError(f"max_faults: expected 1 or 2, got {self.max_faults}")
        if self.fcm_stop not in ("memberships", "centres"):
            raise ValueError(f"fcm_stop: expected memberships or centres, got {self.fcm_stop!r}")
        if not self.fcm_m > 1.0:
            raise ValueError(f"fcm_m: the weighting exponent must be > 1, got {self.fcm_m}")
        vf = self.variance_factor
        if vf is not None and not (math.isfinite(vf) and vf > 0.0):
            raise ValueError(f"variance_factor: expected a positive number, got {vf}")


@dataclass(frozen=True, slots=True, eq=False)
class IntegrityResult:
    """Integrity of every epoch (after exclusion).

    Attributes
    ----------
    method : str
    status : ndarray of int8, shape (E,)
        :class:`RaimStatus`.
    excluded : ndarray of bool, shape (E, S)
        Satellites excluded.
    detected : ndarray of bool, shape (E,)
        The first test (all satellites) failed.
    test_stat : ndarray, shape (E,)
        Statistic of the final test (after exclusion): ``chi2`` of the whitened residuals, for
        ``ss`` the largest separation in units of its threshold times the threshold 1 (so the
        test fails above ``threshold``); NaN where unavailable.
    threshold : ndarray, shape (E,)
        Its threshold (``chi2_{1-pfa}(dof)``; ``ss``: 1).
    hpl_m, vpl_m : ndarray, shape (E,)
        Horizontal and vertical protection levels of the final solution (m) on the error
        model of the ISM; NaN where unavailable, ``inf`` where a used satellite is outside
        the model (or, ``araim``, the integrity budget is exhausted).
    emt_m : ndarray, shape (E,)
        ``araim``: effective monitor threshold (m); NaN for the other methods.
    """

    method: str
    status: Int8Array
    excluded: BoolArray
    detected: BoolArray
    test_stat: FloatArray
    threshold: FloatArray
    hpl_m: FloatArray
    vpl_m: FloatArray
    emt_m: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def status_counts(self) -> dict[str, int]:
        """Epochs per status name (zeros included)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(RaimStatus))
        return {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}

    @classmethod
    def concatenate(cls, parts: list[IntegrityResult]) -> IntegrityResult:
        """Join the integrity of consecutive epoch blocks (same satellites and method)."""
        if not parts:
            raise ValueError("parts: need at least one result")
        cat = {
            name: np.concatenate([getattr(p, name) for p in parts])
            for name in cls.__dataclass_fields__
            if name != "method"
        }
        return cls(method=parts[0].method, **cat)

    def frame_columns(self, sats: tuple[str, ...]) -> dict[str, np.ndarray]:
        """Solution-frame columns: ``raim_status`` (name), ``excluded`` (space-separated ids of
        the satellites ``sats`` of the satellite axis), ``hpl_m``, ``vpl_m``, ``test_stat``,
        ``threshold``, ``emt_m``."""
        names = np.array(STATUS_NAMES, dtype=object)[self.status.astype(np.int64)]
        ids = np.array(sats, dtype=object)
        excluded = np.array([" ".join(ids[row]) for row in self.excluded], dtype=object)
        return {
            "raim_status": names,
            "excluded": excluded,
            "hpl_m": self.hpl_m,
            "vpl_m": self.vpl_m,
            "test_stat": self.test_stat,
            "threshold": self.threshold,
            "emt_m": self.emt_m,
        }

    @property
    def usable(self) -> BoolArray:
        """Epochs whose status is ``ok`` or ``excluded``: a position with protection levels."""
        return np.asarray((self.status == RaimStatus.OK) | (self.status == RaimStatus.EXCLUDED))

    def availability(self, hal_m: float = 40.0, val_m: float = 35.0) -> dict[str, float]:
        """Fractions of all epochs whose integrity supports an operation: ``vertical``
        (status ``ok`` or ``excluded``, ``HPL <= hal_m`` and ``VPL <= val_m``; LPV-200 with
        the defaults) and ``horizontal`` (``HPL <= hal_m`` only)."""
        n = max(self.status.size, 1)
        usable = self.usable
        with np.errstate(invalid="ignore"):
            h = usable & (self.hpl_m <= hal_m)
            v = h & (self.vpl_m <= val_m)
        return {"vertical": float(v.sum() / n), "horizontal": float(h.sum() / n)}


# --------------------------------------------------------------------------- the stage
def variance_factor(estimate: PositionEstimate) -> float:
    """A-posteriori variance factor of the weighting model over a block of epochs.

    ``s^2 = median_e(chi2_e / chi2_0.5(dof_e))`` over the solved epochs with ``dof >= 1``: the
    median is the estimator's robustness (faulty epochs, fewer than half, do not inflate it);
    dividing by the median of each epoch's chi-square distribution makes it unbiased for a
    correct model (``s^2 = 1``). 1 where no epoch has redundancy.

    Parameters
    ----------
    estimate : PositionEstimate

    Returns
    -------
    float
    """
    ok = (estimate.status == SppStatus.OK) & (estimate.dof >= 1) & np.isfinite(estimate.chi2)
    if not ok.any():
        return 1.0
    med = np.array([chi2_quantile(0.5, int(k)) for k in estimate.dof[ok]])
    s2 = float(np.median(estimate.chi2[ok] / med))
    return s2 if s2 > 0.0 else 1.0


@dataclass(frozen=True, slots=True, eq=False)
class MonitorInput:
    """One block of epochs to monitor.

    Attributes
    ----------
    meas : Measurements
    estimate : PositionEstimate
        Of all measurement epochs (:func:`navtrack.gnss.spp.estimate_position`).
    config : SppConfig
        For the re-estimation without excluded satellites.
    raim : RaimConfig
    ism : Ism
        The integrity support message of the protection levels.
    """

    meas: Measurements
    estimate: PositionEstimate
    config: SppConfig
    raim: RaimConfig
    ism: Ism

    def variance_factor(self) -> float:
        """``raim.variance_factor``, or estimated from the block (:func:`variance_factor`)."""
        vf = self.raim.variance_factor
        return variance_factor(self.estimate) if vf is None else vf

    def reestimate(
        self, est: PositionEstimate, rows: IntArray, excluded: BoolArray
    ) -> PositionEstimate:
        """``est`` with the epochs ``rows`` re-estimated without their ``excluded``
        satellites (from their current state)."""
        if not rows.size:
            return est
        sub = estimate_position(
            self.meas,
            self.config,
            epochs=est.epochs[rows],
            exclude=excluded[rows],
            x0_m=est.x[rows],
        )
        return merge_estimates(est, sub)


@dataclass(frozen=True, slots=True, eq=False)
class _Test:
    """Chi-square test of the whitened problem of every epoch, in units of ``s^2``."""

    stat: FloatArray
    thr: FloatArray
    dof: IntArray
    g: FloatArray
    y: FloatArray
    used: BoolArray


def _test(est: PositionEstimate, pfa: float, s2: float) -> _Test:
    g, y, used = whitened(est)
    scale = 1.0 / math.sqrt(s2)
    g, y = g * scale, y * scale
    stat, thr, dof = chi2_test(y, used, n_params(g), pfa)
    return _Test(stat, thr, dof, g, y, used)


def _bounding(
    block: MonitorInput, est: PositionEstimate, used: BoolArray, s2: float
) -> tuple[FloatArray, ErrorModel]:
    """Whitening of each used pseudorange (1/m) and the ISM error model of ``est``."""
    # araim imports scipy.special (160-220 ms): loaded when RAIM runs, not at pos's start-up
    from navtrack.integrity.araim import araim_model

    model = araim_model(block.meas, est, block.ism)
    return np.sqrt(np.where(used, est.weights, 0.0) / s2), model


def _classify(
    method: str,
    solved: BoolArray,
    avail: BoolArray,
    detected: BoolArray,
    excluded: BoolArray,
    cannot: BoolArray,
    final: tuple[BoolArray, FloatArray, FloatArray, FloatArray, FloatArray],
) -> IntegrityResult:
    """The :class:`IntegrityResult` of a detection, its exclusion (``cannot``: detected with too
    few satellites to exclude) and the final test ``(fail, stat, threshold, hpl, vpl)``."""
    final_fail, stat, thr, hpl, vpl = final
    status = np.full(solved.size, RaimStatus.UNAVAILABLE, dtype=np.int8)
    any_excl = excluded.any(axis=1)
    status[avail & ~detected] = RaimStatus.OK
    status[avail & detected] = RaimStatus.ALERT
    status[avail & detected & any_excl & ~final_fail] = RaimStatus.EXCLUDED
    status[avail & detected & cannot & ~any_excl] = RaimStatus.UNAVAILABLE
    unavailable = status == RaimStatus.UNAVAILABLE
    return IntegrityResult(
        method=method,
        status=status,
        excluded=excluded,
        detected=detected,
        test_stat=np.where(unavailable, np.nan, stat),
        threshold=np.where(unavailable, np.nan, thr),
        hpl_m=np.where(unavailable | ~solved, np.nan, hpl),
        vpl_m=np.where(unavailable | ~solved, np.nan, vpl),
        emt_m=np.full(solved.size, np.nan),
    )


class Monitor(Protocol):
    """An integrity method: the estimate after exclusion and the integrity of every epoch."""

    def __call__(self, block: MonitorInput) -> tuple[PositionEstimate, IntegrityResult]: ...


ExclusionPick = Callable[[FloatArray, FloatArray, BoolArray, "RaimConfig"], BoolArray]
"""``pick(g, y, used, raim)``: the satellites to exclude in one round from failed epochs."""


@dataclass(frozen=True, slots=True)
class ResidualMonitor:
    """Chi-square detection, up to ``rounds(raim)`` rounds of exclusion by ``pick`` (each
    followed by re-estimation and a new test of the epochs that excluded), and weighted-RAIM
    protection levels on the ISM model (``chi2``, ``loo``, ``fde``, ``fcm``)."""

    pick: ExclusionPick | None
    rounds: Callable[[RaimConfig], int]

    def __call__(self, block: MonitorInput) -> tuple[PositionEstimate, IntegrityResult]:
        raim, est = block.raim, block.estimate
        solved = est.status == SppStatus.OK
        s2 = block.variance_factor()
        t = _test(est, raim.pfa, s2)
        avail = solved & (t.dof >= 1)
        detected = avail & (t.stat > t.thr)
        excluded = np.zeros(t.used.shape, dtype=bool)
        cannot = np.zeros(solved.size, dtype=bool)  # detected with too few satellites to exclude
        if self.pick is not None:
            est = self._exclude(block, t, detected, excluded, cannot, s2)
        t = _test(est, raim.pfa, s2)
        scale, model = _bounding(block, est, t.used, s2)
        hpl, vpl = bounded_wraim_levels(
            t.g, t.used, scale, est.enu_rotation, model, raim.pfa, raim.pmd
        )
        final_fail = (t.dof >= 1) & (t.stat > t.thr)
        final = (final_fail, t.stat, t.thr, hpl, vpl)
        return est, _classify(raim.method, solved, avail, detected, excluded, cannot, final)

    def _exclude(
        self,
        block: MonitorInput,
        t: _Test,
        detected: BoolArray,
        excluded: BoolArray,
        cannot: BoolArray,
        s2: float,
    ) -> PositionEstimate:
        """Rounds of exclusion on the failed epochs; fills ``excluded`` and ``cannot``."""
        assert self.pick is not None
        est, raim = block.estimate, block.raim
        fail = detected.copy()
        for _ in range(self.rounds(raim)):
            can = fail & (t.used.sum(axis=1) - n_params(t.g) >= 2)
            cannot |= fail & ~can
            rows = np.flatnonzero(can)
            if not rows.size:
                break
            pick = self.pick(t.g[rows], t.y[rows], t.used[rows], raim)
            none = ~pick.any(axis=1)
            cannot[rows[none]] = True
            rows, pick = rows[~none], pick[~none]
            excluded[rows] |= pick
            est = block.reestimate(est, rows, excluded)
            t = _test(est, raim.pfa, s2)
            fail = np.zeros(fail.size, dtype=bool)
            fail[rows] = (t.dof[rows] >= 1) & (t.stat[rows] > t.thr[rows])
        return est


def _smallest_consistent_hypothesis(
    sep: Separation, rows: IntArray, pfa: float
) -> tuple[BoolArray, IntArray]:
    """Per detected epoch (``rows``): whether a hypothesis passes the chi-square test, and the
    satellites ``(b, 2)`` of the smallest such hypothesis, then of the smallest residual."""
    s = sep.subsets
    ok_k = s.valid[rows] & (s.chi2[rows] <= chi2_thresholds(pfa, s.dof[rows]))
    size = (s.members[rows] >= 0).sum(axis=-1)
    score = np.where(ok_k, size * 1e12 + s.chi2[rows], np.inf)
    best = np.argmin(score, axis=1)
    found = np.isfinite(score[np.arange(rows.size), best])
    return found, s.members[rows, best]


@dataclass(frozen=True, slots=True)
class SeparationMonitor:
    """Solution separation (``ss``): detection by the separation tests, exclusion of the
    smallest consistent hypothesis, and separation protection levels of the remaining
    satellites on the ISM model."""

    def __call__(self, block: MonitorInput) -> tuple[PositionEstimate, IntegrityResult]:
        raim, est = block.raim, block.estimate
        solved = est.status == SppStatus.OK
        s2 = block.variance_factor()
        t = _test(est, raim.pfa, s2)
        sep = solution_separation(t.g, t.y, t.used, est.enu_rotation, raim)
        detected = solved & sep.available & sep.detected
        avail = solved & sep.available
        excluded = np.zeros(t.used.shape, dtype=bool)
        cannot = np.zeros(solved.size, dtype=bool)
        rows = np.flatnonzero(detected)
        if rows.size:
            found, mem = _smallest_consistent_hypothesis(sep, rows, raim.pfa)
            for j in range(2):
                r_ok = found & (mem[:, j] >= 0)
                excluded[rows[r_ok], mem[r_ok, j]] = True
            cannot[rows[~found]] = True
            est = block.reestimate(est, rows[found], excluded)
        t = _test(est, raim.pfa, s2)
        final = self._final(block, est, sep, excluded, t, s2)
        return est, _classify(raim.method, solved, avail, detected, excluded, cannot, final)

    @staticmethod
    def _final(
        block: MonitorInput,
        est: PositionEstimate,
        sep: Separation,
        excluded: BoolArray,
        t: _Test,
        s2: float,
    ) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """The final test and levels: of the first separation, and for the epochs that
        excluded, of the hypotheses of their remaining satellites."""
        raim = block.raim
        scale, model = _bounding(block, est, t.used, s2)
        rot = est.enu_rotation
        final_fail = sep.detected.copy()
        hpl, vpl = bounded_separation_levels(sep, t.g, t.used, scale, rot, model, raim.pmd)
        avail_ss = sep.available.copy()
        stat = np.where(sep.available, sep.ratio.max(axis=1, initial=0.0), np.nan)
        rows = np.flatnonzero(excluded.any(axis=1))
        if rows.size:
            g, y, used = t.g[rows], t.y[rows], t.used[rows]
            sep_r = solution_separation(g, y, used, rot[rows], raim)
            final_fail[rows], avail_ss[rows] = sep_r.detected, sep_r.available
            hpl[rows], vpl[rows] = bounded_separation_levels(
                sep_r, g, used, scale[rows], rot[rows], model_rows(model, rows), raim.pmd
            )
            stat[rows] = np.where(sep_r.available, sep_r.ratio.max(axis=1, initial=0.0), np.nan)
        thr = np.where(avail_ss, 1.0, np.nan)
        return final_fail, stat, thr, hpl, vpl


@dataclass(frozen=True, slots=True)
class AraimMonitor:
    """``araim``: MHSS on the ISM (:func:`.araim.araim`), the reported position the fault-free
    (or post-exclusion) solution with the integrity weights."""

    def __call__(self, block: MonitorInput) -> tuple[PositionEstimate, IntegrityResult]:
        # araim imports scipy.special (160-220 ms): loaded when RAIM runs, not at pos's start-up
        from navtrack.integrity.araim import araim, araim_model

        estimate = block.estimate
        solved = estimate.status == SppStatus.OK
        res = araim(
            estimate, block.meas.sats, araim_model(block.meas, estimate, block.ism), block.ism
        )
        used = estimate.used & ~res.excluded & res.in_model[None, :]
        v = np.nan_to_num(estimate.residuals_m) - (estimate.design @ res.dx[..., None])[..., 0]
        est = estimate.replace(
            x=estimate.x + res.dx,
            residuals_m=np.where(used, v, np.nan),
            used=used,
            design=estimate.design * used[..., None],
            weights=np.where(used, estimate.weights, 0.0),
        )
        avail = solved & res.available
        status = np.full(used.shape[0], RaimStatus.UNAVAILABLE, dtype=np.int8)
        any_excl = res.excluded.any(axis=1)
        status[avail & ~res.detected] = RaimStatus.OK
        status[avail & res.detected] = RaimStatus.ALERT
        status[avail & res.detected & any_excl & res.ok] = RaimStatus.EXCLUDED
        keep = status != RaimStatus.UNAVAILABLE
        integrity = IntegrityResult(
            method="araim",
            status=status,
            excluded=res.excluded,
            detected=res.detected & solved,
            test_stat=np.where(keep, res.ratio, np.nan),
            threshold=np.where(keep, 1.0, np.nan),
            hpl_m=np.where(keep, res.hpl_m, np.nan),
            vpl_m=np.where(keep, res.vpl_m, np.nan),
            emt_m=np.where(keep, res.emt_m, np.nan),
        )
        return est, integrity


MONITORS: Mapping[str, Monitor] = MappingProxyType(
    {
        "chi2": ResidualMonitor(None, lambda raim: 0),
        "loo": ResidualMonitor(leave_one_out_pick, lambda raim: 1),
        "fde": ResidualMonitor(largest_residual_pick, lambda raim: raim.max_exclusions),
        "fcm": ResidualMonitor(fcm_pick, lambda raim: raim.max_exclusions),
        "ss": SeparationMonitor(),
        "araim": AraimMonitor(),
    }
)
"""The integrity method of each name of :data:`METHODS`."""


def monitor(
    meas: Measurements,
    estimate: PositionEstimate,
    config: SppConfig,
    raim: RaimConfig,
) -> tuple[PositionEstimate, Int8Array, IntegrityResult]:
    """Integrity monitoring of an estimate of all epochs: the stage that replaces
    :func:`navtrack.gnss.spp.validate` when RAIM is on.

    Parameters
    ----------
    meas : Measurements
    estimate : PositionEstimate
        Of all measurement epochs (:func:`navtrack.gnss.spp.estimate_position`).
    config : SppConfig
        For the re-estimation and the GDOP limit (its ``chi2_alpha`` is replaced by
        ``raim.pfa``).
    raim : RaimConfig
        With ``variance_factor`` None, the factor is estimated from ``estimate``
        (:func:`variance_factor`).

    Returns
    -------
    estimate : PositionEstimate
        With the epochs that excluded satellites re-estimated without them
        (:func:`navtrack.gnss.spp.merge_estimates`).
    status : ndarray of int8, shape (E,)
        :class:`navtrack.gnss.spp.SppStatus`: ``rejected_validity`` for ``alert`` epochs, the
        GDOP test as :func:`navtrack.gnss.spp.validate`.
    integrity : IntegrityResult
    """
    ism = raim.ism if raim.ism is not None else default_ism()
    est, integrity = MONITORS[raim.method](MonitorInput(meas, estimate, config, raim, ism))
    spp_status = validate(est, config.replace(chi2_alpha=0.0))
    alert = (spp_status == SppStatus.OK) & (integrity.status == RaimStatus.ALERT)
    spp_status[alert] = SppStatus.REJECTED_VALIDITY
    return est, spp_status, integrity
