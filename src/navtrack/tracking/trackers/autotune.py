"""Tracker model chosen and tuned from the detections themselves, without their ids.

:func:`auto_config` runs the tracker of :mod:`navtrack.tracking.trackers.tracker` once on a sample
of the detections (the first ``SAMPLE_SPAN`` of the time span, at most ``SAMPLE_DETECTIONS``)
with a generic model, an IMM of three CV models (a moored ship to a manoeuvring target: the
last model's q is ``BOOT_Q[2]`` at ``BOOT_SPEED_MPS`` and scales with the square of the
initiation speed limit, at least ``BOOT_Q_MIN_TOP``, since a manoeuvre of a given turn rate has
an acceleration proportional to the speed), sets the model from what that pass shows, then
searches q by a few more runs; it never reads the ids:

1. **Time scales** from the first-pass tracks: the report interval of a target is the median
   interval between consecutive detections of a confirmed track. The coast time is
   ``COAST_INTERVALS`` intervals: for
   one CV model (targets all moving or all still, one report rate with gaps) the interval is
   the ``COAST_QUANTILE`` (90 %) point of all the confirmed tracks' intervals, so that a
   track coasts over the gaps between a target's reports but not through the minutes a
   target goes unreported (it left coverage, or a trace left out points), where its
   predicted positions report nothing; for the IMM (moored and moving targets, whose report
   rates differ: AIS ships moored every 3 min, moving every 2-10 s) the slow reporters set
   it: the 95 % point over the tracks of their report interval, tentative tracks included
   (a sample of minutes confirms no track of a ship that reports every 3 min, yet its
   tentative track of two reports shows that interval), or the 99 % point of all intervals
   if longer. The confirmation window is 1.5 × the coast time; the 95 % point over
   the tracks sets the seed age of two-point initiation (two intervals); the 10 % point of
   all intervals the scan window (at most 10 s;
   :func:`~navtrack.tracking.trackers.tracker.scan_windows` keeps two reports of one target
   apart).
2. **Speed distribution** (reported speeds where the file has them, else the first-pass track
   speeds) sets the initiation speed limit (1.5 × its 99 % point) and the **motion family**:
   a median speed above ``AIRCRAFT_MPS`` gives the aircraft model (CV, starting
   ``q = AIRCRAFT_Q``); otherwise both stationary (< ``STATIONARY_MPS``) and moving reports
   making up at least ``IMM_MIN_SHARE`` give the IMM of a moored and a manoeuvring CV model
   (``SHIP_IMM_Q``), and a fleet that is all moving or all still gets the manoeuvring CV
   model alone.
3. **Measurement noise σ by maximum likelihood on three-point residuals** of the first-pass
   tracks (:func:`fit_noise`): for three consecutive detections of a track at
   ``t0 < t1 < t2`` (``d1 = t1 - t0``, ``d2 = t2 - t1``, ``a = d2 / d1``) the extrapolation
   residual ``e = z2 - z1 - a (z1 - z0)`` cancels any constant velocity; under white
   acceleration of PSD ``q`` and white position noise ``σ`` per axis its per-axis variance is
   ``v = σ² (1 + (1 + a)² + a²) + q d2² (d1 + d2) / 3`` (the velocity at ``t1`` cancels and
   the two integrated Brownian increments are independent, with variances ``q d2³/3`` and
   ``a² q d1³/3``), so one pass gives σ (dominant at short intervals) apart from q (long
   intervals). σ is floored at ``SIGMA_FLOOR_M``: reported positions carry time-stamp latency
   and stale reports that the tracker must absorb and the bulk of the residuals hides.
   During the q search (step 4) ``clutter_density`` is the density at which a report just
   inside the chi-square gate of a track with measurement noise alone scores as well as a new
   track: ``λ = P_D / (1 - P_D P_G) · exp(-γ / 2) / (2π σ²)`` (:func:`gate_edge_density`).
4. **Process noise q by the tracker's own likelihood, among the runs that need the fewest
   tracks** (:func:`fit_q`): the model of steps 1–3 tracks the first ``TRIAL_DETECTIONS``
   detections at the family's q, a decade below and a decade above (one more decade while an
   end wins, at most ``Q_DECADES`` from the family's value; an IMM keeps its quiet model and
   varies the manoeuvring one). Each run scores every detection by the tracker's own
   density: the Gaussian innovation density of the track it updated, or λ for a detection
   that started a track or was left over (:func:`q_trial`). Runs whose births lie within
   ``TIE_SIGMAS`` Poisson standard deviations of the fewest are candidates; the likeliest of
   them is chosen, unless its paired gain per detection over the family's value is within
   ``TIE_SIGMAS`` standard errors (:func:`select_q`). The likelihood alone would prefer a small
   q (a lost report costs only ``log λ``); births alone would not see neighbours' reports
   entering wider gates.
5. **The clutter / new-track density of a JPDA run** follows the same rule with the gate the
   tracker actually has: ``σ²`` is replaced by the steady-state innovation variance ``S̄`` of
   the tuned CV model (an IMM's quiet model) at the median report interval
   (:func:`steady_innovation_variance`), so that a report inside the gate of a track as
   predicted over a report interval is not shared with a new track.
6. **GNN's competing-report density per track** for the CV family
   (``TrackerConfig.gnn_density_at_gate``): each track's λ is the one at which a report on the
   edge of its own predicted gate ties a miss, so that any report inside a gate is worth
   assigning. The IMM (ships) family keeps the σ-based λ: in a harbour the competitors of a
   report are the neighbouring ships.
7. **Track continuation** (``TrackerConfig.continue_tracks``) on for every family: a new track
   that continues one lost in a gap takes its id
   (:func:`~navtrack.tracking.trackers.management.continuation`).

The tuning sees the reports as read, stale repeats included (the tracker skips them,
:func:`navtrack.io.tracks.stale_repeats`). How each constant was chosen, on which data, and
which data judged it: ``docs/tracking.md``, "Method notes" and "Which data chose what".
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.tracking.gating import chi2_threshold
from navtrack.tracking.models import constant_velocity
from navtrack.tracking.trackers.tracker import DetStatus, TrackerConfig, TrackerResult, run_tracker

__all__ = [
    "AutoTune",
    "NoiseFit",
    "QTrial",
    "auto_config",
    "fit_noise",
    "fit_q",
    "q_trial",
    "select_q",
    "track_triplets",
]

SAMPLE_SPAN = 0.3  # first-pass sample: the first 30 % of the time span ...
SAMPLE_DETECTIONS = 1500  # ... or its first detections if fewer
BOOT_Q = (1e-4, 1e-1, 1e2)  # m²/s³, first-pass IMM; the last at BOOT_SPEED_MPS (see below)
BOOT_SIGMA_M = 50.0
BOOT_SPEED_MPS = 350.0
BOOT_Q_MIN_TOP = 1.0  # m²/s³, the manoeuvring first-pass model never below this
COAST_INTERVALS = 2.0
COAST_QUANTILE = 0.9
"""One CV model: the coast time is ``COAST_INTERVALS`` times this quantile of the first-pass
tracks' report intervals (docs/tracking.md, "Which data chose what": chosen on Monterey
2025-06-01, judged on Monterey 2025-06-02, KWVI and OpenSky)."""
STATIONARY_MPS = 0.5
IMM_MIN_SHARE = 0.1
AIRCRAFT_MPS = 25.0
"""Median speed (m/s) above which the motion family is the aircraft model: above the fastest
ships (high-speed craft, ~20 m/s) and below fixed-wing aircraft in flight (docs/tracking.md,
"Which data chose what")."""
AIRCRAFT_Q = 300.0  # m²/s³, TrackerConfig.for_aircraft
SHIP_IMM_Q = (1e-5, 1e-2)  # m²/s³, TrackerConfig.for_ships
SIGMA_FLOOR_M = 25.0
TRIAL_DETECTIONS = 1500  # the q trials track the first this many detections of the file
Q_DECADES = 2  # the q search goes at most this many decades from the family's value
TIE_SIGMAS = 2.0  # births within this many Poisson σ of the fewest count as as few
MIN_TRIPLETS = 20  # fewer three-point residuals than this: no fit, σ at its floor


@dataclass(frozen=True, slots=True)
class NoiseFit:
    """ML noise levels of three-point residuals (:func:`fit_noise`).

    Attributes
    ----------
    sigma_m : measurement noise per axis, m
    q : CV process-noise PSD per axis, m²/s³
    n_triplets, n_dropped : residuals used / dropped beyond the 99.9 % point
    """

    sigma_m: float
    q: float
    n_triplets: int
    n_dropped: int


@dataclass(frozen=True, slots=True)
class AutoTune:
    """Outcome of :func:`auto_config`: the config and the statistics that chose it.

    Attributes
    ----------
    config : TrackerConfig
    motion : ``"cv"`` or ``"imm"``
    noise : NoiseFit of the first pass (σ before the floor)
    report_interval_p50_s, report_interval_p95_s : median and 95 % point over the first-pass
        tracks of their median report interval, s
    speed_p50_mps, speed_p99_mps : speed quantiles, m/s; stationary_share : share below
        ``STATIONARY_MPS``; speed_source : ``"reported"`` or ``"tracks"``
    sample_detections : detections in the sample
    q_trials : the runs of the q search (:func:`fit_q`), in increasing q
    """

    config: TrackerConfig
    motion: Literal["cv", "imm"]
    noise: NoiseFit
    report_interval_p50_s: float
    report_interval_p95_s: float
    speed_p50_mps: float
    speed_p99_mps: float
    stationary_share: float
    speed_source: str
    sample_detections: int
    q_trials: tuple[QTrial, ...] = ()


def _track_sequences(
    t_s: FloatArray, result: TrackerResult, confirmed: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Detections claimed by the confirmed tracks (``confirmed=False``: by any track), ordered
    by track then time; their tracks."""
    mine = (result.det_track >= 0) & (result.det_status != DetStatus.UNUSED)
    if confirmed:
        mine &= np.isin(result.det_track, np.unique(result.track_id[result.track_confirmed]))
    idx = np.flatnonzero(mine)
    order = idx[np.lexsort((t_s[idx], result.det_track[idx]))]
    return order, result.det_track[order]


def track_triplets(t_s: FloatArray, z: FloatArray, result: TrackerResult) -> FloatArray:
    """Three-point residuals of the detections the confirmed tracks of ``result`` claimed.

    Returns
    -------
    (K, 5) rows ``[d1, d2, a, e_east, e_north]`` (s, s, -, m, m), with ``d1, d2 > 0``.
    """
    order, tr = _track_sequences(t_s, result)
    t, p = t_s[order], z[order]
    same = (tr[2:] == tr[:-2]) & (tr[1:-1] == tr[:-2])
    d1 = t[1:-1] - t[:-2]
    d2 = t[2:] - t[1:-1]
    ok = same & (d1 > 0) & (d2 > 0)
    d1, d2 = d1[ok], d2[ok]
    a = d2 / d1
    e = p[2:][ok] - p[1:-1][ok] - a[:, None] * (p[1:-1][ok] - p[:-2][ok])
    return np.column_stack([d1, d2, a, e])


def fit_noise(triplets: ArrayLike) -> NoiseFit:
    """Maximum-likelihood ``σ`` and ``q`` of three-point residuals (module notes, step 3).

    Parameters
    ----------
    triplets : (K, 5) rows of :func:`track_triplets`

    Raises
    ------
    ValueError
        Fewer than ``MIN_TRIPLETS`` residuals.
    """
    from scipy.optimize import minimize

    tri = np.asarray(triplets, dtype=float)
    if tri.ndim != 2 or tri.shape[1] != 5 or tri.shape[0] < MIN_TRIPLETS:
        raise ValueError(
            f"need at least {MIN_TRIPLETS} three-point residuals (K, 5), got shape {tri.shape}"
        )
    d1, d2, a = tri[:, 0], tri[:, 1], tri[:, 2]
    c1 = 1 + (1 + a) ** 2 + a**2
    c2 = d2**2 * (d1 + d2) / 3
    e2 = (tri[:, 3:] ** 2).sum(axis=1)

    def nll(theta: FloatArray, k: np.ndarray) -> float:
        v = np.exp(theta[0]) * c1[k] + np.exp(theta[1]) * c2[k]
        return float(np.sum(np.log(v) + 0.5 * e2[k] / v))  # per residual, two axes

    def fit(k: np.ndarray) -> FloatArray:
        # start from the best point of a log grid below each term's one-term level (the
        # likelihood has a flat valley where one term explains all: a local search from
        # an arbitrary start can end at its edge)
        s0 = np.log(np.median(e2[k] / (2 * c1[k])) + 1e-12)
        q0 = np.log(np.median(e2[k] / (2 * c2[k])) + 1e-12)
        steps = np.log(10.0) * np.linspace(-4.0, 0.5, 19)
        grid = [(s0 + a, q0 + b) for a in steps for b in steps]
        x0 = np.array(min(grid, key=lambda th: nll(np.array(th), k)))
        return np.asarray(minimize(nll, x0, args=(k,), method="Nelder-Mead").x)

    th = fit(np.ones(e2.size, dtype=bool))
    v = np.exp(th[0]) * c1 + np.exp(th[1]) * c2
    keep = e2 / v <= 13.8155  # chi-square(2) 99.9 % point
    th = fit(keep)
    n = int(keep.sum())
    return NoiseFit(float(np.exp(0.5 * th[0])), float(np.exp(th[1])), n, int(e2.size - n))


@dataclass(frozen=True, slots=True, eq=False)
class QTrial:
    """One run of the q search (:func:`q_trial`).

    Attributes
    ----------
    q : manoeuvring process-noise PSD of the run, m²/s³ (an IMM's quiet model is kept)
    births : tracks the run started
    log_likelihood : (N,) the tracker's log-likelihood of each detection (see :func:`q_trial`)
    """

    q: float
    births: int
    log_likelihood: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def mean_log_likelihood(self) -> float:
        """Log-likelihood per detection."""
        return float(self.log_likelihood.mean())


def _with_q(config: TrackerConfig, q: float) -> TrackerConfig:
    """``config`` with manoeuvring process noise ``q`` (an IMM keeps its quiet model)."""
    if config.imm_q is None:
        return replace(config, motion=constant_velocity(2, q, "continuous"))
    return replace(config, imm_q=(config.imm_q[0], q))


def q_trial(
    t_s: FloatArray, z: FloatArray, velocity: FloatArray | None, config: TrackerConfig, q: float
) -> QTrial:
    """Track the sample with ``config`` at process noise ``q``: births and likelihoods.

    The log-likelihood of a detection is the tracker's own: one that updated a track scores
    its Gaussian innovation density (``TrackerResult.det_log_likelihood``, mixed over the
    IMM's models), any other one (a track start, a seed, a gated loser) the clutter /
    new-track density ``config.clutter_density``.
    """
    res = run_tracker(t_s, z, _with_q(config, q), velocity=velocity)
    upd = (res.det_status <= DetStatus.TENTATIVE) & np.isfinite(res.det_log_likelihood)
    ll = np.where(upd, res.det_log_likelihood, np.log(config.clutter_density))
    return QTrial(float(q), int(res.counts.tracks_started), ll)


def select_q(trials: list[QTrial], ref: int) -> int:
    """Index of the chosen trial (module notes, step 4).

    Trials whose births lie within ``TIE_SIGMAS`` Poisson standard deviations of the fewest
    are candidates; of those, the one of largest likelihood, unless its paired gain per
    detection over the candidate ``ref`` (the family's value) is within ``TIE_SIGMAS``
    standard errors, when ``ref`` stays.
    """
    b = min(tr.births for tr in trials)
    tied = [i for i, tr in enumerate(trials) if tr.births <= b + TIE_SIGMAS * np.sqrt(b)]
    best = max(tied, key=lambda i: trials[i].mean_log_likelihood)
    if ref not in tied or best == ref:
        return best
    d = trials[best].log_likelihood - trials[ref].log_likelihood
    return best if d.mean() > TIE_SIGMAS * d.std() / np.sqrt(d.size) else ref


def fit_q(
    t_s: FloatArray,
    z: FloatArray,
    velocity: FloatArray | None,
    config: TrackerConfig,
    q0: float,
) -> tuple[float, tuple[QTrial, ...]]:
    """Process noise of ``config`` searched on decades around ``q0`` (module notes, step 4).

    The trials start at ``q0 / 10, q0, 10 q0``; while the chosen one (:func:`select_q`) is at
    an end of the trials and within ``Q_DECADES`` decades of ``q0``, one more decade is tried
    beyond it.

    Returns
    -------
    q : the chosen manoeuvring q, m²/s³
    trials : every trial, in increasing q
    """
    runs = {k: q_trial(t_s, z, velocity, config, q0 * 10.0**k) for k in (-1, 0, 1)}
    while True:
        ks = sorted(runs)
        best = ks[select_q([runs[k] for k in ks], ks.index(0))]
        if best == ks[0] and best > -Q_DECADES:
            step = best - 1
        elif best == ks[-1] and best < Q_DECADES:
            step = best + 1
        else:
            return runs[best].q, tuple(runs[k] for k in ks)
        runs[step] = q_trial(t_s, z, velocity, config, q0 * 10.0**step)


def gate_edge_density(pd: float, pg: float, s: float) -> float:
    """Density at which a report on the gate of innovation variance ``s`` ties a new track.

    ``λ = P_D / (1 - P_D P_G) · exp(-γ / 2) / (2π s)`` for an innovation covariance ``s I`` in
    the plane, ``γ`` the gate's chi-square threshold at probability ``pg`` (module notes, step 3).
    """
    gamma = chi2_threshold(pg, 2)  # (lru-cached, the scipy import is paid once)
    return float(pd / (1 - pd * pg) * np.exp(-gamma / 2) / (2 * np.pi * s))


def steady_innovation_variance(q: float, sigma_m: float, dt_s: float) -> float:
    """Per-axis innovation variance of a CV filter in steady state at report interval ``dt_s``.

    Nearly-constant-velocity model of continuous white-acceleration PSD ``q`` (m²/s³) on one
    axis (:func:`~navtrack.tracking.models.constant_velocity`), position measured with standard
    deviation ``sigma_m`` every ``dt_s`` seconds: the steady predicted covariance ``P`` solves
    the filter's discrete algebraic Riccati equation (``scipy.linalg.solve_discrete_are``), and
    ``S = P[0, 0] + σ²`` is returned; ``σ²`` for ``dt_s = 0``.
    """
    if not dt_s > 0:
        return sigma_m**2
    from scipy.linalg import solve_discrete_are

    motion = constant_velocity(1, q, "continuous")
    H = np.array([[1.0, 0.0]])
    P = solve_discrete_are(motion.F(dt_s).T, H.T, motion.Q(dt_s), np.array([[sigma_m**2]]))
    return float(P[0, 0] + sigma_m**2)


def _median_per_track(dt: FloatArray, track: IntArray) -> FloatArray:
    """The median of each track's intervals ``dt`` (s)."""
    return np.array([np.median(dt[track == i]) for i in np.unique(track)])


def _track_intervals(
    t_s: FloatArray, result: TrackerResult, confirmed: bool
) -> tuple[FloatArray, IntArray]:
    """Intervals (s) between consecutive detections of the confirmed tracks
    (``confirmed=False``: of every track), and their track ids."""
    order, tr = _track_sequences(t_s, result, confirmed)
    dt = np.diff(t_s[order])
    ok = (tr[1:] == tr[:-1]) & (dt > 0)
    return dt[ok], tr[1:][ok]


def auto_config(
    t_s: ArrayLike,
    z: ArrayLike,
    velocity: ArrayLike | None = None,
    associator: Literal["gnn", "jpda"] = "gnn",
    sample_detections: int = SAMPLE_DETECTIONS,
) -> AutoTune:
    """Choose and tune the tracker model on a sample of the detections (module notes).

    Parameters
    ----------
    t_s : (N,) non-decreasing times, s
    z : (N, 2) east/north positions, m
    velocity : (N, 2) or None
        Reported velocities (m/s, NaN unknown), used for one-point initiation as in
        :func:`~navtrack.tracking.trackers.tracker.run_tracker` and for the speed distribution.
    associator : the associator of the returned config (the first pass and the q trials
        use GNN)
    sample_detections : int
        At most this many detections (the first in time) in the first pass.

    Returns
    -------
    AutoTune

    Raises
    ------
    ValueError
        No detections.

    Notes
    -----
    When the sample holds fewer than ``MIN_TRIPLETS`` three-point residuals the whole file is
    the sample (up to ``sample_detections``); with still too few, σ takes its floor and
    ``noise.sigma_m`` is NaN.
    """
    t = np.asarray(t_s, dtype=float)
    Z = np.asarray(z, dtype=float)
    if t.size == 0:
        raise ValueError("no detections to tune on")
    V = None if velocity is None else np.asarray(velocity, dtype=float)
    first = _first_pass(t, Z, V, sample_detections)
    fit = (
        fit_noise(first.triplets)
        if first.triplets.shape[0] >= MIN_TRIPLETS
        else NoiseFit(float("nan"), float("nan"), int(first.triplets.shape[0]), 0)
    )  # too few tracks to fit: the floor sets σ (NaN shows it in the summary)
    st = _first_pass_statistics(first)
    dt50, dt95, dt10 = st.dt50, st.dt95, st.dt10
    v50, v99, still = st.v50, st.v99, st.still
    q, imm_q, family = _motion_family(v50, still)
    sigma = SIGMA_FLOOR_M if not fit.sigma_m > SIGMA_FLOOR_M else fit.sigma_m
    pd, pg = 0.9, 0.9999
    coast = COAST_INTERVALS * (st.gap90 if imm_q is None else max(st.slow95, st.gap99))
    cfg = TrackerConfig(
        motion=constant_velocity(2, q, "continuous"),
        sigma_m=sigma,
        associator=associator,
        pd=pd,
        clutter_density=gate_edge_density(pd, pg, sigma**2),
        gate_probability=pg,
        init_max_speed_mps=max(1.5 * v99, 1.0),
        init_max_dt_s=2.0 * dt95,
        confirm_hits=3,
        confirm_window_s=1.5 * coast,
        max_coast_s=coast,
        max_position_std_m=5000.0,
        init_from="unassociated",
        imm_q=imm_q,
        scan_window_s=min(dt10, 10.0),
    )
    kq = min(t.size, TRIAL_DETECTIONS)
    vq = None if V is None else V[:kq]
    gnn = replace(cfg, associator="gnn")  # the trials, like the first pass, use GNN
    q_fit, trials = fit_q(t[:kq], Z[:kq], vq, gnn, q if imm_q is None else imm_q[1])
    cfg = replace(_with_q(cfg, q_fit), gnn_density_at_gate=imm_q is None, continue_tracks=True)
    if associator == "jpda":  # module notes, step 5
        s_bar = steady_innovation_variance(q_fit if imm_q is None else imm_q[0], sigma, dt50)
        cfg = replace(cfg, clutter_density=gate_edge_density(pd, pg, s_bar))
    return AutoTune(cfg, family, fit, dt50, dt95, v50, v99, still, st.source, first.k, trials)


@dataclass(frozen=True, slots=True)
class _Statistics:
    """Report intervals (s) and speeds (m/s) of the first pass (module notes, steps 1-2)."""

    dt50: float
    dt95: float
    slow95: float
    dt10: float
    gap90: float
    gap99: float
    v50: float
    v99: float
    still: float
    source: str


def _first_pass_statistics(first: _FirstPass) -> _Statistics:
    """Median and 95 % point of the tracks' median report intervals, 10 %, 90 % and 99 % points
    of all their intervals; median and 99 % point of the speeds (reported, else the confirmed
    tracks'), and the share below ``STATIONARY_MPS``."""
    dt_all, tk = _track_intervals(first.t_s, first.result, confirmed=True)
    dt_track = _median_per_track(dt_all, tk)
    dt50, dt95 = (
        (float(np.quantile(dt_track, 0.5)), float(np.quantile(dt_track, 0.95)))
        if dt_track.size
        else (60.0, 60.0)
    )
    # the slow reporters' interval from every track of two reports or more: a short sample
    # confirms no track of a ship that reports every 3 min, yet its tentative track shows it
    slow = _median_per_track(*_track_intervals(first.t_s, first.result, confirmed=False))
    slow95 = max(float(np.quantile(slow, 0.95)), dt95) if slow.size else dt95
    dt10 = float(np.quantile(dt_all, 0.1)) if dt_all.size else 0.0
    # the coast spans the gaps between a target's reports (step 1)
    gap90, gap99 = (
        (float(np.quantile(dt_all, COAST_QUANTILE)), float(np.quantile(dt_all, 0.99)))
        if dt_all.size
        else (dt95, dt95)
    )
    speed, source = first.speed, "reported"
    if speed is None:
        conf = first.result.track_confirmed
        speed, source = (
            np.hypot(first.result.track_x[conf, 1], first.result.track_x[conf, 3]),
            "tracks",
        )
    v50, v99 = (
        (float(np.quantile(speed, 0.5)), float(np.quantile(speed, 0.99)))
        if speed.size
        else (10.0, BOOT_SPEED_MPS)
    )
    still = float(np.mean(speed < STATIONARY_MPS)) if speed.size else 0.0
    return _Statistics(dt50, dt95, slow95, dt10, gap90, gap99, v50, v99, still, source)


@dataclass(frozen=True, slots=True, eq=False)
class _FirstPass:
    """The generic first pass of :func:`auto_config` on the first ``k`` detections."""

    k: int
    t_s: FloatArray
    result: TrackerResult
    triplets: FloatArray
    speed: FloatArray | None  # finite reported speeds of the sample (None: too few)


def _first_pass(
    t: FloatArray, Z: FloatArray, V: FloatArray | None, sample_detections: int
) -> _FirstPass:
    """Run the first-pass IMM (module notes) on the sample; a short file: the whole of it."""
    span_end = t[0] + SAMPLE_SPAN * (t[-1] - t[0])
    k = min(int(np.searchsorted(t, span_end, "right")), sample_detections)
    vs = None if V is None else V[:k]
    speed = None if vs is None else np.hypot(vs[:, 0], vs[:, 1])
    speed = None if speed is None or np.isfinite(speed).sum() < 20 else speed[np.isfinite(speed)]
    v_boot = BOOT_SPEED_MPS if speed is None else float(1.5 * np.quantile(speed, 0.99))
    q_top = float(np.clip(BOOT_Q[2] * (v_boot / BOOT_SPEED_MPS) ** 2, BOOT_Q_MIN_TOP, BOOT_Q[2]))
    boot = TrackerConfig(
        motion=constant_velocity(2, BOOT_Q[0], "continuous"),
        sigma_m=BOOT_SIGMA_M,
        imm_q=(BOOT_Q[0], BOOT_Q[1], q_top),
        clutter_density=1e-9,
        init_max_speed_mps=max(v_boot, 1.0),
        init_max_dt_s=400.0,
        confirm_window_s=900.0,
        max_coast_s=600.0,
        max_position_std_m=1e6,  # tracks end by coasting only (the q = 100 model of a moored
        init_from="unassociated",  # ship's track grows km wide between its reports)
        scan_window_s=1.0,
    )
    first = run_tracker(t[:k], Z[:k], boot, velocity=vs)
    tri = track_triplets(t[:k], Z[:k], first)
    if tri.shape[0] < MIN_TRIPLETS and k < min(t.size, sample_detections):
        k = min(t.size, sample_detections)  # a short file: the whole of it (capped)
        vs = None if V is None else V[:k]
        first = run_tracker(t[:k], Z[:k], boot, velocity=vs)
        tri = track_triplets(t[:k], Z[:k], first)
    return _FirstPass(k, t[:k], first, tri, speed)


def _motion_family(
    v50: float, still: float
) -> tuple[float, tuple[float, float] | None, Literal["cv", "imm"]]:
    """Starting q, IMM levels (None: one CV model) and family from the median speed and the
    stationary share (module notes, step 2)."""
    if v50 > AIRCRAFT_MPS:
        return AIRCRAFT_Q, None, "cv"
    if min(still, 1 - still) >= IMM_MIN_SHARE:
        return SHIP_IMM_Q[0], SHIP_IMM_Q, "imm"
    return SHIP_IMM_Q[1], None, "cv"
