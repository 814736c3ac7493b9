"""Advanced RAIM: the multiple-hypothesis solution separation (MHSS) user algorithm of the
EU-US ARAIM Airborne Algorithm Description Document (ADD v4.2; Blanch et al. 2015).

Per epoch, on the satellites the integrity support message covers (:mod:`.ism`):

1. **Fault modes** (:func:`fault_modes`): events are single satellites (prior ``p_sat``) and
   whole constellations (``p_const``), each times the exposure multiplier
   ``1 + T_exp / MFD``. Modes of 1, 2, ... simultaneous events are added in decreasing prior
   until the prior left unmonitored is below ``p_thres`` (and every mode above ``PHMI``
   is in); satellite modes inside a constellation mode are merged into it while their sum
   stays below ``fc p_const``.
2. **Fault-tolerant positions**: the weighted least squares without the satellites of each mode
   (weights ``1 / sigma_int^2``), its gains ``S_k``; ``sigma_k,q^2 = sum_i S_k,qi^2
   sigma_int,i^2``, ``b_k,q = sum_i |S_k,qi| b_nom,i``; the separation
   ``sigma_ss,k,q^2 = sum_i (S_k - S_0)_qi^2 sigma_acc,i^2`` and ``b_ss,k,q`` with ``b_cont``.
   Modes that leave the geometry singular are unmonitorable (their prior goes to the
   unmonitored risk).
3. **Solution-separation tests**: ``|x_k,q - x_0,q| <= T_k,q = K_fa,q sigma_ss,k,q + b_ss,k,q``
   with ``K_fa,q = Q^-1(pfa_h / (4 (N - 1) N_es))`` east and north, ``Q^-1(pfa_v / (2 (N - 1)
   N_es))`` up (``N`` modes including the fault-free one).
4. **Protection levels**: the root of ``2 Q((PL - b_0) / sigma_0) + sum_k p_k
   Q((PL - T_k - b_k) / sigma_k) = PHMI_q (1 - P_unmon / PHMI) / N_es`` (``PHMI_h / 2`` per
   horizontal axis, ``HPL = sqrt(PL_e^2 + PL_n^2)``; the Q terms are 1 where the argument is
   negative), by bisection; modes that take more than their share (``N_es Q >= 1 + T_exp /
   MFD``) are moved to the unmonitored risk and the levels recomputed once (ADD v4.2 eqs.
   42-43).
5. **EMT**: the largest vertical threshold of the modes with prior ``>= p_emt``; the vertical
   accuracy ``sigma_acc``.
6. **Exclusion**: where a test fails, the modes are tried from the fewest satellites up, each
   size in the order of the normalised chi-square of the subset (with ``sigma_acc``); the first
   whose remaining satellites pass all the tests of their own fault modes is excluded, and the
   protection levels are those of the remaining satellites (post-exclusion PL).

The position reported is the fault-free (or post-exclusion) solution of step 2, one
linearised step from the SPP estimate with the integrity weights.

Steps 2-5 run on a batch of epochs at once: epochs with the same satellites per constellation
share their fault modes, so their gains, tests and protection levels are stacked arrays (the
bisection of step 4 runs on all of them together); only the exclusion of step 6 goes epoch by
epoch, on the epochs whose tests fail.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import ecef_to_geodetic
from navtrack.integrity.ism import ErrorModel, Ism, error_model

if TYPE_CHECKING:
    from navtrack.gnss.spp import Measurements, PositionEstimate

__all__ = [
    "AraimEpoch",
    "AraimResult",
    "FaultModes",
    "araim",
    "araim_epoch",
    "araim_model",
    "fault_modes",
    "protection_level",
]

_BATCH_ELEMENTS = 2_000_000
"""Upper bound on the elements of one stacked gain array ``(B, H, P, n)``: epochs are
processed in chunks of this size to bound memory."""


def _qinv(p: FloatArray | float) -> FloatArray:
    """``Q^-1(p)``, the upper-tail normal quantile."""
    # scipy.special costs 160-220 ms to import and ``pos`` loads this module for every RAIM
    # method (:func:`araim_model`): imported where a level is computed
    from scipy.special import ndtri

    return np.asarray(-ndtri(np.asarray(p, dtype=float)))


@dataclass(frozen=True, slots=True, eq=False)
class FaultModes:
    """Fault modes of one epoch.

    Attributes
    ----------
    removed : ndarray of bool, shape (H, n)
        Satellites each mode leaves out; row 0 is the fault-free mode (none).
    p_fault : ndarray, shape (H,)
        Prior of each mode with the exposure multiplier (row 0: unused).
    multiplier : ndarray, shape (H,)
        Exposure multiplier ``1 + sum T_exp / MFD`` of the mode's events.
    p_unmonitored : float
        Prior of the fault combinations not monitored.
    """

    removed: BoolArray
    p_fault: FloatArray
    multiplier: FloatArray
    p_unmonitored: float


def _monitored_events(
    p: FloatArray, inc: FloatArray, n_sat: int, ism: Ism
) -> tuple[list[tuple[int, ...]], list[float], list[float], float]:
    """Event combinations to monitor in decreasing prior (step 1): their events, priors with
    the exposure multiplier, multipliers, and the prior left unmonitored."""
    phmi = ism.phmi_v + ism.phmi_h
    p_unmon = 1.0 - float(np.prod(1.0 - np.minimum(1.0, p * (1.0 + inc))))
    log_none = float(np.sum(np.log1p(-p)))
    log_odds = np.log(p) - np.log1p(-p)
    events: list[tuple[int, ...]] = []
    priors: list[float] = []
    mults: list[float] = []
    k = 0
    while k < n_sat and p_unmon > ism.p_thres:
        k += 1
        combos = np.array(list(itertools.combinations(range(p.size), k)), dtype=np.int64)
        if combos.size == 0:
            break
        m_k = 1.0 + inc[combos].sum(axis=1)
        prior_t = np.exp(log_none + log_odds[combos].sum(axis=1)) * m_k
        for h in np.argsort(-prior_t, kind="stable"):
            if not (p_unmon > ism.p_thres or prior_t[h] > phmi):
                break
            if prior_t[h] > 0.0:
                events.append(tuple(int(e) for e in combos[h]))
                priors.append(float(prior_t[h]))
                mults.append(float(m_k[h]))
                p_unmon -= prior_t[h]
    return events, priors, mults, p_unmon


def _merge_into_constellations(
    removed: BoolArray,
    p_fault: FloatArray,
    const_of_sat: IntArray,
    const_rows: dict[int, int],
    p_const: FloatArray,
    fc: float,
) -> tuple[BoolArray, float]:
    """Fault consolidation (ADD v4.2): a constellation mode covers the constellation's fault
    whatever else fails, so its prior is the marginal ``p_const``; satellite modes inside it
    are merged into it while their sum stays below ``fc p_const``. Updates ``p_fault`` in
    place; returns the rows kept and the change of the unmonitored prior."""
    keep = np.ones(len(p_fault), dtype=bool)
    d_unmon = 0.0
    rows = np.arange(len(p_fault))
    for c, ic in const_rows.items():
        in_c = const_of_sat == c
        inside = np.flatnonzero(
            keep & removed.any(axis=1) & ~(removed & ~in_c).any(axis=1) & (rows != ic)
        )
        inside = inside[np.argsort(p_fault[inside], kind="stable")]
        limit = fc * p_const[c]
        absorb = inside[np.cumsum(p_fault[inside]) <= limit] if fc > 0.0 else inside[:0]
        new = p_const[c] + p_fault[absorb].sum()
        d_unmon -= new - p_fault[ic] - p_fault[absorb].sum()
        p_fault[ic] = new
        keep[absorb] = False
    return keep, d_unmon


def fault_modes(const_of_sat: IntArray, ism: Ism, systems: str) -> FaultModes:
    """Fault modes to monitor and their priors (step 1 of the module docstring).

    Parameters
    ----------
    const_of_sat : ndarray of int, shape (n,)
        Index into ``systems`` of each satellite.
    ism : Ism
    systems : str
        The constellations of the epoch (letters of ``ism.constellations``).

    Returns
    -------
    FaultModes
    """
    n = const_of_sat.size
    cons = [ism.constellations[s] for s in systems]
    p = np.array([cons[c].p_sat for c in const_of_sat] + [c.p_const for c in cons])
    mfd = np.array([cons[c].mfd_sat_s for c in const_of_sat] + [c.mfd_const_s for c in cons])
    inc = ism.t_exp_s / mfd  # exposure increment of each event
    events, priors, mults, p_unmon = _monitored_events(p, inc, n, ism)
    removed = np.zeros((len(events) + 1, n), dtype=bool)
    for i, ev in enumerate(events, start=1):
        for e in ev:
            if e < n:
                removed[i, e] = True
            else:
                removed[i] |= const_of_sat == e - n
    p_fault = np.array([1.0, *priors])
    multiplier = np.array([1.0, *mults])
    const_rows = {e[0] - n: i for i, e in enumerate(events, start=1) if len(e) == 1 and e[0] >= n}
    p_const = p[n:] * (1.0 + inc[n:])
    keep, d_unmon = _merge_into_constellations(
        removed, p_fault, const_of_sat, const_rows, p_const, ism.fc
    )
    p_fault[0] = 0.0
    return FaultModes(
        removed=removed[keep],
        p_fault=p_fault[keep],
        multiplier=multiplier[keep],
        p_unmonitored=max(p_unmon + d_unmon, 0.0),
    )


def protection_level(
    sigma: FloatArray,
    bias: FloatArray,
    p_fault: FloatArray,
    phmi: FloatArray,
    tol_m: float = 1e-4,
) -> tuple[FloatArray, FloatArray]:
    """Root of ``sum_k p_k Q'((PL - bias_k) / sigma_k) = phmi`` per row, by bisection
    (``Q'`` the normal tail, 1 where the argument is negative; ADD v4.2), for a stack of
    epochs at once.

    Parameters
    ----------
    sigma, bias : ndarray, shape (..., A, H)
        Standard deviations and ``T_k + b_k`` of each mode (A rows, e.g. east/north/up).
    p_fault : ndarray, shape (..., H)
        Weights (2 for the fault-free mode; 0 for a mode not monitored).
    phmi : ndarray, shape (..., A)
        Allocations; ``<= 0``: infinite level.
    tol_m : float
        The bisection of an epoch stops when all its A rows are this narrow.

    Returns
    -------
    pl : ndarray, shape (..., A)
        ``inf`` where the allocation is exhausted.
    alloc : ndarray, shape (..., A, H)
        ``Q'`` of each mode at the level.
    """
    from scipy.special import ndtr  # lazy: see _qinv

    phmi = np.asarray(phmi, dtype=float)
    pf = np.asarray(p_fault, dtype=float)[..., None, :]
    good = phmi > 0.0
    ph = np.where(good, phmi, 1.0)[..., None]
    live = pf > 0.0
    n_live = live.sum(axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_low = np.maximum(_qinv(np.minimum(1.0, ph / pf)), -40.0)
        k_high = np.maximum(0.0, _qinv(ph / (n_live * pf)))
        lo = np.max(np.where(live, bias + k_low * sigma, -np.inf), axis=-1)
        hi = np.max(np.where(live, bias + k_high * sigma, -np.inf), axis=-1)

    def risk(pl: FloatArray) -> FloatArray:
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.fmax(ndtr((bias - pl[..., None]) / sigma), 0.0)  # NaN (0 / 0) to 0
        return np.where(q > 0.5, 1.0, q)

    for _ in range(200):
        open_ = np.any(hi - lo > tol_m, axis=-1, keepdims=True)
        if not open_.any():
            break
        mid = 0.5 * (lo + hi)
        above = (risk(mid) * pf).sum(axis=-1) > ph[..., 0]
        lo = np.where(open_ & above, mid, lo)
        hi = np.where(open_ & ~above, mid, hi)
    return np.where(good, hi, np.inf), risk(hi)


@dataclass(frozen=True, slots=True, eq=False)
class AraimEpoch:
    """ARAIM outcome of one epoch (satellites of the call).

    Attributes
    ----------
    ok : bool
        All solution-separation tests pass.
    hpl_m, vpl_m, emt_m, sigma_acc_m : float
        ``inf`` (PLs) where the integrity budget is exhausted; NaN without modes.
    dx : ndarray, shape (P,)
        Fault-free solution minus the linearisation point (state of the design matrix).
    chi2 : ndarray, shape (H,)
        Chi-square (accuracy weights) of each mode's solution.
    ratio : ndarray, shape (H,)
        Largest ``|separation| / threshold`` of each mode.
    modes : FaultModes
    dx_modes : ndarray, shape (H, P)
    """

    ok: bool
    hpl_m: float
    vpl_m: float
    emt_m: float
    sigma_acc_m: float
    dx: FloatArray
    chi2: FloatArray
    ratio: FloatArray
    modes: FaultModes
    dx_modes: FloatArray


@dataclass(frozen=True, slots=True, eq=False)
class _Batch:
    """Steps 2-5 on B epochs sharing their fault modes (H of them)."""

    ok: BoolArray  # (B,)
    pl: FloatArray  # (B, 3) east, north, up
    emt_m: FloatArray  # (B,)
    sigma_acc_m: FloatArray  # (B,)
    active: BoolArray  # (B, H) monitored (geometry not singular), before the drop of step 4
    chi2: FloatArray  # (B, H)
    ratio: FloatArray  # (B, H)
    dx_modes: FloatArray  # (B, H, P)
    p_unmonitored: FloatArray  # (B,)


def _gains(g: FloatArray, w: FloatArray, removed: BoolArray) -> tuple[FloatArray, BoolArray]:
    """Least-squares gains ``S_k = (G^T W_k G)^-1 G^T W_k`` of each mode of each epoch
    (``(B, H, P, n)``, zero rows for parameters no remaining satellite touches) and the
    singular modes ``(B, H)``."""
    n_p = g.shape[-1]
    wk = np.where(removed[None], 0.0, w[:, None, :])  # (B, H, n)
    gw = np.swapaxes(g, -1, -2)[:, None, :, :] * wk[:, :, None, :]  # (B, H, P, n)
    n_k = gw @ g[:, None, :, :]  # (B, H, P, P)
    absent = np.diagonal(n_k, axis1=-2, axis2=-1) <= 1e-12
    n_k = n_k + np.eye(n_p) * absent[..., None, :]
    rank_ok = (wk > 0).sum(axis=-1) >= (~absent).sum(axis=-1)
    with np.errstate(all="ignore"):
        det = np.linalg.det(n_k)
        diag = np.prod(np.diagonal(n_k, axis1=-2, axis2=-1), axis=-1)
        singular = ~(np.abs(det) > 1e-10 * np.abs(diag)) | ~rank_ok
    n_k = np.where(singular[..., None, None], np.eye(n_p), n_k)
    s = np.linalg.solve(n_k, gw) * ~absent[..., None]
    return np.where(singular[..., None, None], 0.0, s), singular


def _thresholds(sig_ss: FloatArray, b_ss: FloatArray, active: BoolArray, ism: Ism) -> FloatArray:
    """``T_k,q`` of step 3 ``(B, H, 3)`` for the monitored modes (0 elsewhere)."""
    n_modes = active.sum(axis=1)
    denom = np.maximum(n_modes - 1, 1) * ism.n_es
    k_fa = _qinv(
        np.stack(
            [ism.pfa_h / (4.0 * denom), ism.pfa_h / (4.0 * denom), ism.pfa_v / (2.0 * denom)],
            axis=-1,
        )
    )
    thr = k_fa[:, None, :] * sig_ss + b_ss
    thr[:, 0] = 0.0
    thr[n_modes <= 1] = 0.0
    return np.where(active[..., None], thr, 0.0)


def _levels(
    sig: FloatArray, bias: FloatArray, pf: FloatArray, p_unmon: FloatArray, ism: Ism
) -> tuple[FloatArray, FloatArray]:
    """Step 4's levels ``(B, 3)`` and the ``Q'`` of each mode ``(B, 3, H)``."""
    scale = 1.0 - p_unmon / (ism.phmi_v + ism.phmi_h)
    share = np.array([ism.phmi_h / 2.0, ism.phmi_h / 2.0, ism.phmi_v]) / ism.n_es
    return protection_level(
        np.swapaxes(sig, 1, 2), np.swapaxes(bias, 1, 2), pf, share[None, :] * scale[:, None]
    )


def _mhss(
    g: FloatArray, v: FloatArray, err: tuple[FloatArray, ...], modes: FaultModes, ism: Ism
) -> _Batch:
    """Steps 2-5 for epochs ``g (B, n, P)``, ``v (B, n)`` with the error model ``err``
    (``var_int``, ``var_acc``, ``b_int``, ``b_acc``, each ``(B, n)``) and common fault modes."""
    var_int, var_acc, b_int, b_acc = err
    s, singular = _gains(g, 1.0 / var_int, modes.removed)
    active = ~singular
    active[:, 0] = True
    p_unmon = modes.p_unmonitored + np.where(active, 0.0, modes.p_fault).sum(axis=1)
    sq = s[:, :, :3, :]  # (B, H, 3, n)
    sig = np.sqrt((sq**2) @ var_int[:, None, :, None])[..., 0]  # (B, H, 3)
    bias = (np.abs(sq) @ b_int[:, None, :, None])[..., 0]
    ds = sq - sq[:, :1]
    sig_ss = np.sqrt((ds**2) @ var_acc[:, None, :, None])[..., 0]
    b_ss = (np.abs(ds) @ b_acc[:, None, :, None])[..., 0]
    thr = _thresholds(sig_ss, b_ss, active, ism)
    dx_modes = (s @ v[:, None, :, None])[..., 0]  # (B, H, P)
    sep = dx_modes[..., :3] - dx_modes[:, :1, :3]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(thr > 0, np.abs(sep) / thr, 0.0).max(axis=-1)
    ok = np.all(ratio[:, 1:] <= 1.0, axis=1)
    pf = np.where(active, modes.p_fault, 0.0)
    pf[:, 0] = 2.0
    sig_safe = np.where(active[..., None], sig, 1.0)
    pl, alloc = _levels(sig_safe, bias + thr, pf, p_unmon, ism)
    drop = (ism.n_es * alloc.sum(axis=1) >= modes.multiplier) & active
    drop[:, 0] = False
    kept = active & ~drop  # after the modes that take more than their share are dropped
    redo = np.flatnonzero(drop.any(axis=1))
    if redo.size:
        p_unmon[redo] += np.where(drop[redo], modes.p_fault, 0.0).sum(axis=1)
        pf[redo] = np.where(kept[redo], pf[redo], 0.0)
        thr[redo] = _thresholds(sig_ss[redo], b_ss[redo], kept[redo], ism)
        pl[redo], _ = _levels(sig_safe[redo], bias[redo] + thr[redo], pf[redo], p_unmon[redo], ism)
    emt_rows = kept & (modes.p_fault >= ism.p_emt)
    emt_rows[:, 0] = False
    emt = np.where(emt_rows, thr[..., 2], -np.inf).max(axis=1, initial=-np.inf)
    r = np.where(modes.removed, 0.0, v[:, None, :] - dx_modes @ np.swapaxes(g, -1, -2))
    return _Batch(
        ok=ok,
        pl=pl,
        emt_m=np.where(emt_rows.any(axis=1), emt, 0.0),
        sigma_acc_m=np.sqrt(np.einsum("bn,bn->b", sq[:, 0, 2] ** 2, var_acc)),
        active=active,
        chi2=(r**2 / var_acc[:, None, :]).sum(axis=-1),
        ratio=ratio,
        dx_modes=dx_modes,
        p_unmonitored=p_unmon,
    )


def _epoch_of(batch: _Batch, i: int, modes: FaultModes) -> AraimEpoch:
    """Epoch ``i`` of a batch, its modes those monitored."""
    act = batch.active[i]
    pl = batch.pl[i]
    return AraimEpoch(
        ok=bool(batch.ok[i]),
        hpl_m=float(np.hypot(pl[0], pl[1])),
        vpl_m=float(pl[2]),
        emt_m=float(batch.emt_m[i]),
        sigma_acc_m=float(batch.sigma_acc_m[i]),
        dx=batch.dx_modes[i, 0],
        chi2=batch.chi2[i, act],
        ratio=batch.ratio[i, act],
        modes=FaultModes(
            removed=modes.removed[act],
            p_fault=modes.p_fault[act],
            multiplier=modes.multiplier[act],
            p_unmonitored=float(batch.p_unmonitored[i]),
        ),
        dx_modes=batch.dx_modes[i, act],
    )


def araim_epoch(
    g_enu: FloatArray,
    v: FloatArray,
    var_int: FloatArray,
    var_acc: FloatArray,
    b_int: FloatArray,
    b_acc: FloatArray,
    const_of_sat: IntArray,
    systems: str,
    ism: Ism,
) -> AraimEpoch:
    """The MHSS algorithm of one epoch (steps 1-5 of the module docstring).

    Parameters
    ----------
    g_enu : ndarray, shape (n, P)
        Design matrix, position columns in east/north/up, then clocks.
    v : ndarray, shape (n,)
        Residuals at the linearisation point (m).
    var_int, var_acc, b_int, b_acc : ndarray, shape (n,)
        Error model (:func:`.ism.error_model`).
    const_of_sat : ndarray of int, shape (n,)
    systems : str
    ism : Ism

    Returns
    -------
    AraimEpoch
    """
    modes = fault_modes(const_of_sat, ism, systems)
    err = tuple(np.asarray(a, dtype=float)[None] for a in (var_int, var_acc, b_int, b_acc))
    return _epoch_of(_mhss(g_enu[None], v[None], err, modes, ism), 0, modes)


@dataclass(frozen=True, slots=True, eq=False)
class AraimResult:
    """ARAIM of an epoch batch.

    Attributes
    ----------
    ok : ndarray of bool, shape (B,)
        The tests of the final satellite set pass.
    detected : ndarray of bool, shape (B,)
        The all-in-view tests failed.
    available : ndarray of bool, shape (B,)
        Enough satellites in the model and finite protection levels.
    excluded : ndarray of bool, shape (B, S)
    hpl_m, vpl_m, emt_m, sigma_acc_m : ndarray, shape (B,)
    ratio : ndarray, shape (B,)
        Largest separation over its threshold of the final set (> 1: a test fails).
    n_modes : ndarray of int, shape (B,)
    dx : ndarray, shape (B, P)
        State correction from the SPP estimate to the reported solution.
    in_model : ndarray of bool, shape (S,)
        The satellite's system is in the ISM (the others are not used).
    """

    ok: BoolArray
    detected: BoolArray
    available: BoolArray
    excluded: BoolArray
    hpl_m: FloatArray
    vpl_m: FloatArray
    emt_m: FloatArray
    sigma_acc_m: FloatArray
    ratio: FloatArray
    n_modes: IntArray
    dx: FloatArray
    in_model: BoolArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class _Job:
    """One epoch (or one exclusion candidate of an epoch) for the batched steps 2-5: design
    matrix in east/north/up with one clock per clock group (the ADD's parametrisation: a
    subset without the first group keeps a solvable clock), residuals, error model
    (``var_int``, ``var_acc``, ``b_int``, ``b_acc``) and constellations."""

    g: FloatArray
    v: FloatArray
    err: tuple[FloatArray, ...]
    letters: np.ndarray
    const: IntArray
    systems: str


def _job(g: FloatArray, v: FloatArray, err: tuple[FloatArray, ...], letters: np.ndarray) -> _Job:
    index = {c: i for i, c in enumerate(dict.fromkeys(letters.tolist()))}
    const = np.array([index[c] for c in letters.tolist()], dtype=np.int64)
    return _Job(g, v, err, letters, const, "".join(index))


def _solve_jobs(
    jobs: dict[int, _Job], ism: Ism, cache: dict[tuple[str, bytes], FaultModes]
) -> dict[int, AraimEpoch]:
    """Steps 1-5 of every job, batched over the jobs with the same satellites per
    constellation (one set of fault modes each, computed once per call of :func:`araim`)."""
    groups: dict[tuple[str, bytes, tuple[int, ...]], list[int]] = {}
    for j, job in jobs.items():
        groups.setdefault((job.systems, job.const.tobytes(), job.g.shape), []).append(j)
    out: dict[int, AraimEpoch] = {}
    for (systems, const, _), ids in groups.items():
        if (systems, const) not in cache:
            cache[systems, const] = fault_modes(jobs[ids[0]].const, ism, systems)
        modes = cache[systems, const]
        for chunk in _chunks(ids, modes, jobs[ids[0]].g.shape[1]):
            batch = _mhss(
                np.stack([jobs[j].g for j in chunk]),
                np.stack([jobs[j].v for j in chunk]),
                tuple(np.stack([jobs[j].err[k] for j in chunk]) for k in range(4)),
                modes,
                ism,
            )
            out.update((j, _epoch_of(batch, i, modes)) for i, j in enumerate(chunk))
    return out


def _candidates(
    ep: AraimEpoch, job: _Job, max_candidates: int
) -> list[tuple[BoolArray, BoolArray]]:
    """Exclusion candidates of step 6 in the order tried (the smallest modes first, each size
    by normalised chi-square): the satellites kept and the state columns they still solve."""
    n_p = job.g.shape[1]
    size = ep.modes.removed.sum(axis=1)
    dof = np.maximum((~ep.modes.removed).sum(axis=1) - n_p, 1)
    key = np.where(size == 0, np.inf, size * 1e6 + ep.chi2 / dof)
    out = []
    for h in np.argsort(key, kind="stable")[: min(max_candidates, ep.chi2.size - 1)]:
        keep = ~ep.modes.removed[h]
        live = np.abs(job.g[keep]).sum(axis=0) > 0
        live[:3] = True
        if keep.sum() >= live.sum() + 1:
            out.append((keep, live))
    return out


def _exclusions(
    failed: dict[int, AraimEpoch],
    jobs: dict[int, _Job],
    ism: Ism,
    max_candidates: int,
    cache: dict[tuple[str, bytes], FaultModes],
) -> dict[int, tuple[AraimEpoch, BoolArray, BoolArray]]:
    """Step 6 on the epochs whose tests fail, one candidate per epoch per round (each round
    batched over the epochs): the first candidate whose remaining satellites pass their own
    tests with a finite VPL is excluded. Returns the final outcome, the satellites excluded
    and the state columns of the final solution of the epochs that found one."""
    cands = {b: _candidates(ep, jobs[b], max_candidates) for b, ep in failed.items()}
    done: dict[int, tuple[AraimEpoch, BoolArray, BoolArray]] = {}
    for r in range(max_candidates):
        pending = [b for b, c in cands.items() if b not in done and r < len(c)]
        if not pending:
            break
        sub_jobs = {}
        for b in pending:
            keep, live = cands[b][r]
            job = jobs[b]
            sub_jobs[b] = _job(
                job.g[keep][:, live],
                job.v[keep],
                tuple(e[keep] for e in job.err),
                job.letters[keep],
            )
        for b, sub in _solve_jobs(sub_jobs, ism, cache).items():
            if sub.ok and np.isfinite(sub.vpl_m):
                keep, live = cands[b][r]
                done[b] = (sub, ~keep, live)
    return done


def _chunks(ids: list[int], modes: FaultModes, n_p: int) -> Iterator[list[int]]:
    h, n = modes.removed.shape
    size = max(1, _BATCH_ELEMENTS // (h * n_p * max(n, 1)))
    for i in range(0, len(ids), size):
        yield ids[i : i + size]


def _epoch_jobs(
    estimate: PositionEstimate, used: BoolArray, letters: np.ndarray, model: ErrorModel
) -> tuple[dict[int, _Job], dict[int, FloatArray]]:
    """The job of every epoch with more satellites than unknowns, and the map of its clock
    columns back to the estimate's clock + ISBs."""
    g_pos = estimate.design[..., :3] @ np.swapaxes(estimate.enu_rotation, -1, -2)
    n_b, n_s, n_p = estimate.design.shape
    # clock columns: the distinct patterns of the batch (in np.unique's order), and per epoch
    # the rank of each pattern among those of its used satellites (the epoch's clock group)
    patterns, pid = np.unique(
        estimate.design[..., 3:].reshape(n_b * n_s, n_p - 3), axis=0, return_inverse=True
    )
    pid = pid.reshape(n_b, n_s)
    present = np.zeros((n_b, patterns.shape[0]), dtype=bool)
    rows, sats = np.nonzero(used)
    present[rows, pid[rows, sats]] = True
    rank = np.cumsum(present, axis=1) - 1
    fields = (model.var_int_m2, model.var_acc_m2, model.b_int_m, model.b_acc_m)
    jobs: dict[int, _Job] = {}
    clock_maps: dict[int, FloatArray] = {}
    for b in np.flatnonzero(used.sum(axis=1) >= 4 + present.sum(axis=1)):
        cols = np.flatnonzero(used[b])
        group = rank[b, pid[b, cols]]
        g_enu = np.concatenate([g_pos[b, cols], np.eye(int(present[b].sum()))[group]], axis=1)
        v = np.nan_to_num(estimate.residuals_m[b, cols])
        jobs[int(b)] = _job(g_enu, v, tuple(f[b, cols] for f in fields), letters[cols])
        clock_maps[int(b)] = patterns[present[b]]
    return jobs, clock_maps


def araim(
    estimate: PositionEstimate,
    sats: tuple[str, ...],
    model: ErrorModel,
    ism: Ism,
    max_candidates: int = 8,
) -> AraimResult:
    """MHSS ARAIM of every epoch of an estimate, with exclusion (steps 1-6).

    Parameters
    ----------
    estimate : PositionEstimate
        Linearisation point: design matrix, residuals and used satellites.
    sats : tuple of str, length S
    model : ErrorModel
        Of the same epochs (:func:`.ism.error_model`).
    ism : Ism
    max_candidates : int
        Exclusion candidates tried per failed epoch.

    Returns
    -------
    AraimResult
    """
    n_b, n_s, n_p = estimate.design.shape
    letters = np.array([s[0] for s in sats])
    used = estimate.used & model.covered[None, :] & np.isfinite(model.var_int_m2)
    out = _empty_outputs(n_b, n_s, n_p)
    jobs, clock_maps = _epoch_jobs(estimate, used, letters, model)
    cache: dict[tuple[str, bytes], FaultModes] = {}
    eps = _solve_jobs(jobs, ism, cache)
    failed = {b: ep for b, ep in eps.items() if not ep.ok}
    out["detected"][list(failed)] = True
    excluded = _exclusions(failed, jobs, ism, max_candidates, cache)
    for b, ep in eps.items():
        cols = np.flatnonzero(used[b])
        dx = ep.dx
        gone = np.zeros(cols.size, dtype=bool)
        if b in excluded:
            ep, gone, live = excluded[b]
            dx = np.zeros(live.size)
            dx[live] = ep.dx
        _store(out, b, ep, cols[gone], dx, estimate.enu_rotation[b], clock_maps[b])
    return AraimResult(**out, in_model=model.covered)


@lru_cache(maxsize=64)
def _pinv(clock_map: bytes, shape: tuple[int, int]) -> FloatArray:
    """Pseudo-inverse of a clock map (few distinct ones per file)."""
    return np.asarray(np.linalg.pinv(np.frombuffer(clock_map).reshape(shape)), dtype=float)


def _empty_outputs(n_b: int, n_s: int, n_p: int) -> dict[str, np.ndarray]:
    return {
        "ok": np.zeros(n_b, dtype=bool),
        "detected": np.zeros(n_b, dtype=bool),
        "available": np.zeros(n_b, dtype=bool),
        "excluded": np.zeros((n_b, n_s), dtype=bool),
        "hpl_m": np.full(n_b, np.nan),
        "vpl_m": np.full(n_b, np.nan),
        "emt_m": np.full(n_b, np.nan),
        "sigma_acc_m": np.full(n_b, np.nan),
        "ratio": np.full(n_b, np.nan),
        "n_modes": np.zeros(n_b, dtype=np.int64),
        "dx": np.zeros((n_b, n_p)),
    }


def _store(
    out: dict[str, np.ndarray],
    b: int,
    ep: AraimEpoch,
    gone: IntArray,
    dx: FloatArray,
    rot: FloatArray,
    clock_map: FloatArray,
) -> None:
    """Epoch ``b``'s final outcome into the result arrays (state back to ECEF, clock + ISBs)."""
    out["ok"][b] = ep.ok
    out["available"][b] = np.isfinite(ep.vpl_m) and np.isfinite(ep.hpl_m)
    out["excluded"][b, gone] = True
    out["hpl_m"][b], out["vpl_m"][b] = ep.hpl_m, ep.vpl_m
    out["emt_m"][b], out["sigma_acc_m"][b] = ep.emt_m, ep.sigma_acc_m
    out["ratio"][b] = float(ep.ratio.max(initial=0.0))
    out["n_modes"][b] = ep.ratio.size
    out["dx"][b] = np.concatenate(
        [rot.T @ dx[:3], _pinv(clock_map.tobytes(), clock_map.shape) @ dx[3:]]
    )


def araim_model(meas: Measurements, estimate: PositionEstimate, ism: Ism) -> ErrorModel:
    """The error model of an estimate's epochs (geodetic position from its state)."""
    llh = ecef_to_geodetic(estimate.x[:, :3])
    return error_model(ism, meas.sats, estimate.azel_rad, llh[:, :2], meas.ionofree)
