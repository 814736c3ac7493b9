"""Tracking core against Stone Soup and FilterPy.

Run: ``PYTHONPATH=src python benchmarks/bench_tracking.py [--quick]``.

1. Paper-3 two crossing targets (Zhang, Xiong & He 2005): one range-bearing sensor at the
   origin, sigma_r = 300 m, sigma_theta = 0.03 rad, Pd 0.97, 1.8 clutter per scan, 140 steps.
   navtrack ``jpda_step`` vs Stone Soup ``JPDA`` (tutorial tracker: PDAHypothesiser + JPDA +
   gm_reduce_single, EKF with analytic Jacobian). Same scans; prints per-step medians, the ratio
   and the largest differences in marginals and estimates.
2. n closely spaced targets (all gating each other), n = 2, 4, 6, 8, 12: navtrack exact JPDA
   (whole step, and marginals alone) vs Stone Soup ``JPDAwithEHM2.associate``.
3. Kalman update of 1000 tracks: one batched call vs a loop over FilterPy ``KalmanFilter``
   objects; FilterPy updates the covariance in the Joseph form, so the ratio is taken against
   navtrack's Joseph form (the ratio against its default short form is printed apart).

Every ratio comes from timings of both sides in the same run and process.

Options: ``--runs N`` (paper-3 Monte Carlo runs for navtrack, default 50),
``--ss-runs N`` (for Stone Soup, default 50), ``--quick``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "tracking"))

from navtrack.estimation.kalman import kf_update
from navtrack.tracking.jpda import JpdaConfig, jpda_marginals, jpda_step
from navtrack.tracking.models import (
    RangeBearing,
    constant_velocity,
    linear_position,
)
from navtrack.tracking.simulate import (
    paper3_scenario,
    simulate_detections,
    simulate_truth,
)

P0_DIAG = [500.0**2, 50.0**2, 500.0**2, 50.0**2]


def paper3_runs(seed: int, n_runs: int, n_steps: int):
    sc = paper3_scenario()
    mot = constant_velocity(2, 1.0, "continuous")
    rb = RangeBearing(np.diag([sc["sigma_r_m"] ** 2, sc["sigma_theta_rad"] ** 2]))
    lo, hi = np.array([0.0, -np.pi]), np.array([50_000.0, np.pi])
    lam = sc["clutter_rate"] / np.prod(hi - lo)
    runs = []
    for child in np.random.SeedSequence(seed).spawn(n_runs):
        rng = np.random.default_rng(child)
        truth = simulate_truth(mot, sc["x0"], n_steps + 1, 1.0, rng)
        det = simulate_detections(truth[1:], rb, sc["pd"], sc["clutter_rate"], lo, hi, rng)
        runs.append([det.scan(k) for k in range(n_steps)])
    return sc, mot, rb, lam, runs


def bench_paper3(n_runs: int, ss_runs: int, n_steps: int = 140) -> None:
    sc, mot, rb, lam, runs = paper3_runs(2005, max(n_runs, ss_runs), n_steps)
    cfg = JpdaConfig(pd=sc["pd"], clutter_density=lam, gate_probability=0.99)
    P0 = np.tile(np.diag(P0_DIAG), (2, 1, 1))
    F, Q = mot.F(1.0), mot.Q(1.0)
    jpda_step(sc["x0"], P0, runs[0][0], F, Q, rb, cfg)  # warm up imports
    per_run_nt, outs = [], []
    for r in range(n_runs):
        x, P = sc["x0"], P0
        res = []
        t0 = time.perf_counter()
        for k in range(n_steps):
            st = jpda_step(x, P, runs[r][k], F, Q, rb, cfg)
            x, P = st.x, st.P
            res.append(st)
        per_run_nt.append((time.perf_counter() - t0) / n_steps)
        outs.append(res)
    nt = statistics.median(per_run_nt)
    print(
        f"[paper 3] navtrack JPDA: {nt * 1e6:8.1f} us/step (median of {n_runs} runs x "
        f"{n_steps} steps)"
    )
    try:
        from stonesoup_ref import run_stonesoup_jpda
    except ImportError:
        print("[paper 3] Stone Soup not installed: no comparison")
        return
    per_run_ss, db, dx = [], 0.0, 0.0
    for r in range(ss_runs):
        t0 = time.perf_counter()
        B, X, _ = run_stonesoup_jpda(
            runs[r], sc["x0"], P0, 1.0, sc["sigma_r_m"], sc["sigma_theta_rad"], sc["pd"], lam, 0.99
        )
        per_run_ss.append((time.perf_counter() - t0) / n_steps)
        if r < n_runs:
            db = max(
                db, max(np.abs(o.marginals.beta - b).max() for o, b in zip(outs[r], B, strict=True))
            )
            dx = max(dx, max(np.abs(o.x - xx).max() for o, xx in zip(outs[r], X, strict=True)))
    ss = statistics.median(per_run_ss)
    print(
        f"[paper 3] Stone Soup JPDA: {ss * 1e6:8.1f} us/step (median of {ss_runs} runs x "
        f"{n_steps} steps, {ss * n_steps:.2f} s per run)"
    )
    print(
        f"[paper 3] ratio Stone Soup / navtrack per step: {ss / nt:.0f}x   "
        f"max |d beta| = {db:.1e}, max |d x| = {dx:.1e} m over {min(ss_runs, n_runs)} runs"
    )


def close_targets(n: int, rng: np.random.Generator):
    """n targets 30 m apart on a line, sigma 20 m position sensor, 2 clutter points nearby."""
    x = np.zeros((n, 4))
    x[:, 0] = np.arange(n) * 30.0
    x[:, 1] = 10.0
    P = np.tile(np.diag([50.0**2, 5.0**2, 50.0**2, 5.0**2]), (n, 1, 1))
    truth_next = x.copy()
    truth_next[:, 0] += 10.0
    z = truth_next[:, [0, 2]] + rng.normal(0, 20.0, (n, 2))
    clutter = np.column_stack([rng.uniform(-30, 30 * n, 2), rng.uniform(-60, 60, 2)])
    return x, P, np.vstack([z, clutter])


def bench_close(ns: list[int], q: float = 1.0) -> None:
    mot = constant_velocity(2, q, "continuous")
    meas = linear_position(4, (0, 2), 20.0)
    lam = 1e-4
    cfg = JpdaConfig(pd=0.9, clutter_density=lam, gate_probability=0.99)
    F, Q = mot.F(1.0), mot.Q(1.0)
    from navtrack.tracking.gating import chi2_threshold, gate
    from navtrack.tracking.jpda import association_weights

    try:
        import datetime as dt

        from stonesoup.dataassociator.probability import JPDAwithEHM2
        from stonesoup.hypothesiser.probability import PDAHypothesiser
        from stonesoup.models.measurement.linear import LinearGaussian
        from stonesoup.models.transition.linear import (
            CombinedLinearGaussianTransitionModel,
            ConstantVelocity,
        )
        from stonesoup.predictor.kalman import KalmanPredictor
        from stonesoup.types.detection import Detection
        from stonesoup.types.state import GaussianState
        from stonesoup.types.track import Track
        from stonesoup.updater.kalman import KalmanUpdater

        have_ss = True
    except ImportError:
        have_ss = False
    rows = []
    # navtrack first for every n (Stone Soup's runs leave BLAS threads busy for a while)
    for n in ns:
        rng = np.random.default_rng(n)
        x, P, Z = close_targets(n, rng)
        jpda_step(x, P, Z, F, Q, meas, cfg)  # warm-up (first call imports scipy parts)
        tt = []
        for _ in range(20):
            t0 = time.perf_counter()
            st = jpda_step(x, P, Z, F, Q, meas, cfg)
            tt.append(time.perf_counter() - t0)
        S = meas.H @ st.P_pred @ meas.H.T + meas.R
        g = gate(st.x_pred[:, [0, 2]], S, Z, chi2_threshold(0.99, 2))
        W = association_weights(g.log_likelihood(), g.valid, 0.9, 0.99, lam)
        tm = []
        for _ in range(20):
            t0 = time.perf_counter()
            jpda_marginals(W, cfg)
            tm.append(time.perf_counter() - t0)
        rows.append(
            (
                n,
                x,
                P,
                Z,
                st,
                statistics.median(tt),
                statistics.median(tm),
                int(g.valid.sum()),
                min(tt),
            )
        )
    for n, x, P, Z, st, nt, tmarg, n_pairs, tmin in rows:
        line = (
            f"[close n={n:2d}] navtrack exact JPDA step {nt * 1e3:7.2f} ms "
            f"(min {tmin * 1e3:.2f}; marginals "
            f"{tmarg * 1e3:6.2f} ms, exact={bool((st.marginals.method == 1).all())}, "
            f"{n_pairs} gated pairs of {n}x{len(Z)})"
        )
        if have_ss:
            trans = CombinedLinearGaussianTransitionModel(
                [ConstantVelocity(q), ConstantVelocity(q)]
            )
            mm = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * 400.0)
            hyp = PDAHypothesiser(
                predictor=KalmanPredictor(trans),
                updater=KalmanUpdater(mm),
                clutter_spatial_density=lam,
                prob_detect=0.9,
                prob_gate=0.99,
            )
            assoc = JPDAwithEHM2(hypothesiser=hyp)
            t_0 = dt.datetime(2020, 1, 1)
            ts = t_0 + dt.timedelta(seconds=1)
            tracks = [
                Track([GaussianState(x[i].reshape(4, 1), P[i], timestamp=t_0)]) for i in range(n)
            ]
            dets = [Detection(z.reshape(2, 1), timestamp=ts, measurement_model=mm) for z in Z]
            ss_reps = 3 if n <= 8 else 1
            st_ss = []
            for _ in range(ss_reps):
                t0 = time.perf_counter()
                hyps = assoc.associate(set(tracks), set(dets), ts)
                st_ss.append(time.perf_counter() - t0)
            ss = statistics.median(st_ss)
            index = {id(d): j for j, d in enumerate(dets)}
            B = np.zeros((n, len(Z) + 1))
            for i, tr in enumerate(tracks):
                for h in hyps[tr]:
                    B[i, 0 if not h else 1 + index[id(h.measurement)]] += float(h.probability)
            db = np.abs(B - st.marginals.beta).max()
            line += (
                f" | Stone Soup JPDAwithEHM2 {ss * 1e3:8.1f} ms ({ss_reps} rep) "
                f"ratio {ss / nt:5.0f}x, max |d beta| {db:.1e}"
            )
        print(line, flush=True)


def bench_kf(n_tracks: int = 1000, rounds: int = 30) -> None:
    """Kalman update of ``n_tracks`` tracks: navtrack batched vs a loop of FilterPy filters.

    FilterPy's ``KalmanFilter.update`` writes the covariance in the Joseph form
    ``(I-KH) P (I-KH)ᵀ + K R Kᵀ``, so the like-for-like ratio is against ``kf_update(...,
    joseph=True)``; the ratio against navtrack's default (short form ``(I-KH) P``) is printed
    apart and labelled. The three are timed in turn inside each of ``rounds`` rounds (after one
    warm-up round), so that a change of machine load hits all three alike; medians over rounds
    of the wall time, and of the process CPU time for a second pair of ratios.
    """
    rng = np.random.default_rng(0)
    mot = constant_velocity(2, 1.0)
    meas = linear_position(4, (0, 2), 10.0)
    x = rng.normal(size=(n_tracks, 4)) * 100
    A = rng.normal(size=(n_tracks, 4, 4))
    P = A @ np.swapaxes(A, -1, -2) + 4 * np.eye(4)
    z = rng.normal(size=(n_tracks, 2)) * 100
    try:
        from filterpy.kalman import KalmanFilter
    except ImportError:
        KalmanFilter = None
    kfs = []
    for _ in range(n_tracks if KalmanFilter is not None else 0):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.F = mot.F(1.0)
        kf.Q = mot.Q(1.0)
        kf.H = np.array(meas.H)
        kf.R = np.array(meas.R)
        kfs.append(kf)

    def filterpy_loop() -> None:
        for i, kf in enumerate(kfs):
            kf.x = x[i].copy()
            kf.P = P[i].copy()
        for i, kf in enumerate(kfs):
            kf.update(z[i])

    sides = {
        "joseph": lambda: kf_update(x, P, z, meas.H, meas.R, joseph=True),
        "short": lambda: kf_update(x, P, z, meas.H, meas.R),
        "filterpy": filterpy_loop,
    }
    if not kfs:
        del sides["filterpy"]
    times: dict[str, list[float]] = {k: [] for k in sides}
    cpu: dict[str, list[float]] = {k: [] for k in sides}
    for r in range(rounds + 1):
        for k, fn in sides.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            if r:  # round 0 is the warm-up
                times[k].append(time.perf_counter() - t0)
                cpu[k].append(time.process_time() - c0)
    us = {k: statistics.median(v) / n_tracks * 1e6 for k, v in times.items()}
    us_cpu = {k: statistics.median(v) / n_tracks * 1e6 for k, v in cpu.items()}
    print(
        f"[kalman] navtrack batched kf_update, Joseph form: {us['joseph']:.3f} us/track; "
        f"short form (default): {us['short']:.3f} us/track "
        f"(medians of {rounds} rounds over {n_tracks} tracks)"
    )
    if not kfs:
        print("[kalman] FilterPy not installed: no comparison")
        return
    u = kf_update(x, P, z, meas.H, meas.R, joseph=True)
    dx = max(np.abs(kf.x - u.x[i]).max() for i, kf in enumerate(kfs))
    dP = max(np.abs(kf.P - u.P[i]).max() for i, kf in enumerate(kfs))
    print(
        f"[kalman] FilterPy KalmanFilter.update loop (Joseph form): {us['filterpy']:.2f} us/track; "
        f"max |dx| {dx:.1e}, max |dP| {dP:.1e} vs navtrack Joseph form"
    )
    print(
        f"[kalman] ratio FilterPy / navtrack, like for like (both Joseph): "
        f"{us['filterpy'] / us['joseph']:.0f}x; against navtrack's short form (not like for "
        f"like): {us['filterpy'] / us['short']:.0f}x"
    )
    print(
        f"[kalman] same ratios from process CPU time (less disturbed by other load): "
        f"{us_cpu['filterpy'] / us_cpu['joseph']:.0f}x like for like, "
        f"{us_cpu['filterpy'] / us_cpu['short']:.0f}x against the short form"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--ss-runs", type=int, default=50)
    ap.add_argument("--quick", action="store_true", help="fewer runs, n <= 8")
    a = ap.parse_args()
    if a.quick:
        a.runs, a.ss_runs = 5, 1
    bench_close([2, 4, 6, 8] if a.quick else [2, 4, 6, 8, 12])
    bench_paper3(a.runs, a.ss_runs)
    bench_kf()


if __name__ == "__main__":
    main()
