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
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtr, ndtri

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.integrity.ism import ErrorModel, Ism, error_model

if TYPE_CHECKING:
    from navtrack.gnss.spp import Measurements, PositionEstimate

__all__ = [
    "AraimEpoch",
    "AraimResult",
    "FaultModes",
    "araim",
    "araim_epoch",
    "fault_modes",
    "protection_level",
]


def _qinv(p: FloatArray | float) -> FloatArray:
    """``Q^-1(p)``, the upper-tail normal quantile."""
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


def _p_at_least(p: FloatArray, mult: FloatArray, r: int, phmi: float) -> float:
    """Prior of ``r`` or more simultaneous events (ADD v4.2, the ``N_fault,max`` rule)."""
    pt = p * mult
    certain = pt >= 1.0
    r -= int(certain.sum())
    p, pt, mult = p[~certain], pt[~certain], mult[~certain]
    if r <= 0:
        return 1.0
    no_fault = float(np.prod(1.0 - p))
    ratio = p / (1.0 - p) * mult
    if r == 1:
        return 1.0 if np.any(pt > phmi) else 1.0 - no_fault
    if r == 2:
        return 1.0 - float(np.prod(1.0 - pt)) - no_fault * float(ratio.sum())
    if r == 3:
        s1 = float(ratio.sum())
        return (
            1.0
            - float(np.prod(1.0 - pt))
            - no_fault * s1
            - 0.5 * no_fault * (s1**2 - float((ratio**2).sum()))
        )
    return float(pt.sum()) ** r / math.factorial(r)


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
    mult = 1.0 + inc
    phmi = ism.phmi_v + ism.phmi_h
    n_ev = p.size
    p_unmon = 1.0 - float(np.prod(1.0 - np.minimum(1.0, p * mult)))
    log_none = float(np.sum(np.log1p(-p)))
    log_odds = np.log(p) - np.log1p(-p)
    modes: list[tuple[tuple[int, ...], float, float, float]] = []
    k = 0
    while k < n and p_unmon > ism.p_thres:
        k += 1
        combos = np.array(list(itertools.combinations(range(n_ev), k)), dtype=np.int64)
        if combos.size == 0:
            break
        prior = np.exp(log_none + log_odds[combos].sum(axis=1))
        m_k = 1.0 + inc[combos].sum(axis=1)
        prior_t = prior * m_k
        order = np.argsort(-prior_t, kind="stable")
        for h in order:
            if not (p_unmon > ism.p_thres or prior_t[h] > phmi):
                break
            if prior_t[h] > 0.0:
                modes.append((tuple(int(e) for e in combos[h]), prior_t[h], prior[h], m_k[h]))
                p_unmon -= prior_t[h]
    removed = np.zeros((len(modes) + 1, n), dtype=bool)
    p_fault = np.ones(len(modes) + 1)
    multiplier = np.ones(len(modes) + 1)
    for i, (events, pt, _, m) in enumerate(modes, start=1):
        for e in events:
            if e < n:
                removed[i, e] = True
            else:
                removed[i] |= const_of_sat == e - n
        p_fault[i], multiplier[i] = pt, m
    # a constellation mode covers the constellation's fault whatever else fails: its prior is
    # the marginal ``p_const`` (ADD v4.2); fault consolidation merges satellite modes inside
    # it while their sum stays below ``fc p_const``
    keep = np.ones(len(p_fault), dtype=bool)
    for c in range(len(cons)):
        in_c = const_of_sat == c
        const_mode = [i for i, (ev, *_) in enumerate(modes, start=1) if ev == (n + c,)]
        if not const_mode:
            continue
        ic = const_mode[0]
        inside = np.flatnonzero(
            keep
            & removed.any(axis=1)
            & ~(removed & ~in_c).any(axis=1)
            & (np.arange(len(p_fault)) != ic)
        )
        inside = inside[np.argsort(p_fault[inside], kind="stable")]
        limit = ism.fc * cons[c].p_const * mult[n + c]
        absorb = inside[np.cumsum(p_fault[inside]) <= limit] if ism.fc > 0.0 else inside[:0]
        new = cons[c].p_const * mult[n + c] + p_fault[absorb].sum()
        p_unmon -= new - p_fault[ic] - p_fault[absorb].sum()
        p_fault[ic] = new
        keep[absorb] = False
    p_fault[0] = 0.0
    return FaultModes(
        removed=removed[keep],
        p_fault=p_fault[keep],
        multiplier=multiplier[keep],
        p_unmonitored=max(p_unmon, 0.0),
    )


def protection_level(
    sigma: FloatArray,
    bias: FloatArray,
    p_fault: FloatArray,
    phmi: FloatArray,
    tol_m: float = 1e-4,
) -> tuple[FloatArray, FloatArray]:
    """Root of ``sum_k p_k Q'((PL - bias_k) / sigma_k) = phmi`` per row, by bisection
    (``Q'`` the normal tail, 1 where the argument is negative; ADD v4.2).

    Parameters
    ----------
    sigma, bias : ndarray, shape (A, H)
        Standard deviations and ``T_k + b_k`` of each mode (A rows, e.g. east/north/up).
    p_fault : ndarray, shape (H,)
        Weights (2 for the fault-free mode).
    phmi : ndarray, shape (A,)
        Allocations; ``<= 0``: infinite level.
    tol_m : float

    Returns
    -------
    pl : ndarray, shape (A,)
        ``inf`` where the allocation is exhausted.
    alloc : ndarray, shape (A, H)
        ``Q'`` of each mode at the level.
    """
    phmi = np.asarray(phmi, dtype=float)
    good = phmi > 0.0
    ph = np.where(good, phmi, 1.0)[:, None]
    k_low = np.maximum(_qinv(np.minimum(1.0, ph / p_fault)), -40.0)
    k_high = np.maximum(0.0, _qinv(ph / (p_fault.size * p_fault)))
    lo = np.max(bias + k_low * sigma, axis=1)
    hi = np.max(bias + k_high * sigma, axis=1)

    def risk(pl: FloatArray) -> FloatArray:
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.nan_to_num(ndtr((bias - pl[:, None]) / sigma), nan=0.0)
        return np.where(q > 0.5, 1.0, q)

    for _ in range(200):
        if np.all(hi - lo <= tol_m):
            break
        mid = 0.5 * (lo + hi)
        above = (risk(mid) * p_fault).sum(axis=1) > ph[:, 0]
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
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


def _gains(g: FloatArray, w: FloatArray, removed: BoolArray) -> tuple[FloatArray, BoolArray]:
    """Least-squares gains ``S_k = (G^T W_k G)^-1 G^T W_k`` of each mode (``(H, P, n)``,
    zero rows for parameters no remaining satellite touches) and the singular modes."""
    wk = np.where(removed, 0.0, w[None, :])  # (H, n)
    gw = g.T[None, :, :] * wk[:, None, :]  # (H, P, n)
    n_k = gw @ g  # (H, P, P)
    absent = np.einsum("hpp->hp", n_k) <= 1e-12
    n_k = n_k + np.eye(g.shape[1]) * absent[:, None, :]
    rank_ok = (wk > 0).sum(axis=1) >= (~absent).sum(axis=1)
    with np.errstate(all="ignore"):
        det = np.linalg.det(n_k)
        diag = np.prod(np.einsum("hpp->hp", n_k), axis=1)
        singular = ~(np.abs(det) > 1e-10 * np.abs(diag)) | ~rank_ok
    n_k = np.where(singular[:, None, None], np.eye(g.shape[1]), n_k)
    s = np.linalg.solve(n_k, gw) * ~absent[:, :, None]
    return np.where(singular[:, None, None], np.nan, s), singular


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
    s, singular = _gains(g_enu, 1.0 / var_int, modes.removed)
    keep = ~singular
    keep[0] = True
    p_unmon = modes.p_unmonitored + float(modes.p_fault[~keep].sum())
    removed, p_fault, mult = modes.removed[keep], modes.p_fault[keep], modes.multiplier[keep]
    s = s[keep]
    sq = s[:, :3, :]  # (H, 3, n)
    sig = np.sqrt((sq**2) @ var_int)  # (H, 3)
    bias = np.abs(sq) @ b_int
    ds = sq - sq[:1]
    sig_ss = np.sqrt((ds**2) @ var_acc)
    b_ss = np.abs(ds) @ b_acc
    n_modes = p_fault.size
    if n_modes > 1:
        k_fa = _qinv(
            np.array(
                [
                    ism.pfa_h / (4.0 * (n_modes - 1) * ism.n_es),
                    ism.pfa_h / (4.0 * (n_modes - 1) * ism.n_es),
                    ism.pfa_v / (2.0 * (n_modes - 1) * ism.n_es),
                ]
            )
        )
        thr = k_fa * sig_ss + b_ss
    else:
        thr = np.zeros_like(sig_ss)
    thr[0] = 0.0
    dx_modes = s @ v  # (H, P)
    sep = dx_modes[:, :3] - dx_modes[:1, :3]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(thr > 0, np.abs(sep) / thr, 0.0).max(axis=1)
    ok = bool(np.all(ratio[1:] <= 1.0))
    phmi = ism.phmi_v + ism.phmi_h
    pf = p_fault.copy()
    pf[0] = 2.0

    def levels(pf: FloatArray, p_unmon: float) -> tuple[FloatArray, FloatArray]:
        scale = 1.0 - p_unmon / phmi
        alloc = np.array([ism.phmi_h / 2.0, ism.phmi_h / 2.0, ism.phmi_v]) / ism.n_es * scale
        return protection_level(sig.T, (bias + thr).T, pf, alloc)

    pl, alloc = levels(pf, p_unmon)
    drop = ism.n_es * alloc.sum(axis=0) >= mult
    drop[0] = False
    if drop.any():
        p_unmon += float(p_fault[drop].sum())
        sig, bias, thr, pf = sig[~drop], bias[~drop], thr[~drop], pf[~drop]
        thr_sub = sig_ss[~drop], b_ss[~drop]
        n2 = pf.size
        if n2 > 1:
            k_fa = _qinv(
                np.array(
                    [
                        ism.pfa_h / (4.0 * (n2 - 1) * ism.n_es),
                        ism.pfa_h / (4.0 * (n2 - 1) * ism.n_es),
                        ism.pfa_v / (2.0 * (n2 - 1) * ism.n_es),
                    ]
                )
            )
            thr = k_fa * thr_sub[0] + thr_sub[1]
            thr[0] = 0.0
        pl, _ = levels(pf, p_unmon)
        p_kept = p_fault[~drop]
    else:
        p_kept = p_fault
    emt_rows = p_kept >= ism.p_emt
    emt_rows[0] = False
    emt = float(thr[emt_rows, 2].max()) if emt_rows.any() else 0.0
    r = np.where(removed, 0.0, v[None, :] - dx_modes @ g_enu.T)
    chi2 = (r**2 / var_acc[None, :]).sum(axis=1)
    return AraimEpoch(
        ok=ok,
        hpl_m=float(np.hypot(pl[0], pl[1])),
        vpl_m=float(pl[2]),
        emt_m=emt,
        sigma_acc_m=float(np.sqrt((sq[0, 2] ** 2) @ var_acc)),
        dx=dx_modes[0],
        chi2=chi2,
        ratio=ratio,
        modes=FaultModes(removed=removed, p_fault=p_fault, multiplier=mult, p_unmonitored=p_unmon),
        dx_modes=dx_modes,
    )


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
    out = {
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
    rot = estimate.enu_rotation
    for b in range(n_b):
        cols = np.flatnonzero(used[b])
        g = estimate.design[b][cols]
        # one receiver clock per clock group (the ADD's parametrisation): a subset without
        # the first group keeps a solvable clock; ``clock_map`` maps back to clock + ISBs
        clock_map, group = np.unique(g[:, 3:], axis=0, return_inverse=True)
        group = group.reshape(-1)  # NumPy 2.0.0 returned it with a trailing axis
        g_enu = np.concatenate([g[:, :3] @ rot[b].T, np.eye(clock_map.shape[0])[group]], axis=1)
        if cols.size < g_enu.shape[1] + 1:
            continue
        v = np.nan_to_num(estimate.residuals_m[b, cols])
        systems = "".join(dict.fromkeys(letters[cols]))
        const = np.array([systems.index(s) for s in letters[cols]], dtype=np.int64)
        args = (
            model.var_int_m2[b, cols],
            model.var_acc_m2[b, cols],
            model.b_int_m[b, cols],
            model.b_acc_m[b, cols],
        )
        ep = araim_epoch(g_enu, v, *args, const, systems, ism)
        final, gone = ep, np.zeros(cols.size, dtype=bool)
        if not ep.ok:
            out["detected"][b] = True
            # the smallest modes first, each size by normalised chi-square
            size = ep.modes.removed.sum(axis=1)
            dof = np.maximum((~ep.modes.removed).sum(axis=1) - g_enu.shape[1], 1)
            key = np.where(size == 0, np.inf, size * 1e6 + ep.chi2 / dof)
            order = np.argsort(key, kind="stable")
            for h in order[: min(max_candidates, ep.chi2.size - 1)]:
                rm = ep.modes.removed[h]
                keep = ~rm
                sub_sys = "".join(dict.fromkeys(letters[cols][keep]))
                g_sub = g_enu[keep]
                live = np.abs(g_sub).sum(axis=0) > 0
                live[:3] = True
                if keep.sum() < live.sum() + 1:
                    continue
                sub = araim_epoch(
                    g_sub[:, live],
                    v[keep],
                    args[0][keep],
                    args[1][keep],
                    args[2][keep],
                    args[3][keep],
                    np.array([sub_sys.index(s) for s in letters[cols][keep]], dtype=np.int64),
                    sub_sys,
                    ism,
                )
                if sub.ok and math.isfinite(sub.vpl_m):
                    dx = np.zeros(g_enu.shape[1])
                    dx[live] = sub.dx
                    final = replace(sub, dx=dx)
                    gone = rm
                    break
        full_dx = np.concatenate(
            [rot[b].T @ final.dx[:3], np.linalg.pinv(clock_map) @ final.dx[3:]]
        )
        out["ok"][b] = final.ok
        out["available"][b] = math.isfinite(final.vpl_m) and math.isfinite(final.hpl_m)
        out["excluded"][b, cols[gone]] = True
        out["hpl_m"][b], out["vpl_m"][b] = final.hpl_m, final.vpl_m
        out["emt_m"][b], out["sigma_acc_m"][b] = final.emt_m, final.sigma_acc_m
        out["ratio"][b] = float(final.ratio.max(initial=0.0))
        out["n_modes"][b] = final.ratio.size
        out["dx"][b] = full_dx
    return AraimResult(**out, in_model=model.covered)


def araim_model(meas: Measurements, estimate: PositionEstimate, ism: Ism) -> ErrorModel:
    """The error model of an estimate's epochs (geodetic position from its state)."""
    from navtrack.geodesy import ecef_to_geodetic

    llh = ecef_to_geodetic(estimate.x[:, :3])
    return error_model(ism, meas.sats, estimate.azel_rad, llh[:, :2], meas.ionofree)
