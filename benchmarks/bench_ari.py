"""Speed and likelihood of navtrack's ARI estimation against statsmodels SARIMAX.

Same model on both sides: ``SARIMAX(order=(p, d, 0), measurement_error=True)`` is the ARI(p, d)
process observed with white noise, and navtrack's ``AriConfig(initial="stationary")`` maximises
the same exact likelihood (checked to agree to 1e-6 at equal parameters in
``tests/smoothing/test_ari.py``). Timed work: navtrack ``fit_ari`` with a fixed order (estimation,
filtered series, sigma_x per epoch; robust weighting off so that both sides estimate the same
thing; a second timing with the default Danish reweighting is printed too); SARIMAX ``fit`` (its
default L-BFGS, default start) plus the smoothed states. Likelihoods: SARIMAX's ``loglike`` at
both parameter sets.

Usage::

    PYTHONPATH=src python benchmarks/bench_ari.py [--n 100000] [--repeat 3] [--big 1000000]
        [--big-repeat 3] [--big-sarimax] [--order 5,2] [--skip-sarimax] [--threads 1]

At ``--n`` navtrack (robust off, Danish) and SARIMAX alternate on the same series; medians of
``--repeat`` runs (SARIMAX: at most 2) and the ratios SARIMAX / navtrack of this run. At ``--big``
the medians of ``--big-repeat`` robust-off and Danish fits (alternating), with their ratios to
SARIMAX at ``--big``: measured in this run with ``--big-sarimax`` (about 10x its ``--n`` time,
over 10 min), else its ``--n`` figure of this run scaled linearly and labelled an estimate. The
load average is printed with the timings. Memory is measured with ``tracemalloc`` (peak of
Python-allocated NumPy memory) at n/10 and n to show it is linear in n.
"""

from __future__ import annotations

import os
import sys

# Single-threaded BLAS/LAPACK on both sides (the issue's SARIMAX figure is single-threaded);
# ``--threads N`` overrides. Must be set before NumPy is imported.
_threads = "1"
if "--threads" in sys.argv:
    _threads = sys.argv[sys.argv.index("--threads") + 1]
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, _threads)

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

from navtrack.smoothing.ari import AriConfig, fit_ari, simulate_ari  # noqa: E402

# The GPS case of the reproduction: smooth ARI(5,2), sigma_n = 0.02 m, sigma_e = 0.01 m.
PHI = {
    (5, 2): (-2.0, 1.26, -0.126, -0.1323, 0.0243),
    (2, 2): (-1.2, 0.5),
    (1, 2): (-0.9,),
}


def _series(n: int, order: tuple[int, int], seed: int = 1) -> np.ndarray:
    phi = PHI[order]
    y, _ = simulate_ari(np.random.default_rng(seed), n, phi, order[1], 0.02, 0.01)
    return y


def _time_navtrack(
    y: np.ndarray, order: tuple[int, int], robust: str
) -> tuple[float, float, object]:
    """Wall and CPU seconds of one fit, and the fit (CPU time is what a loaded machine
    changes least: both sides are single-threaded)."""
    c0 = time.process_time()
    t0 = time.perf_counter()
    res = fit_ari(y, AriConfig(order=order, robust=robust))  # type: ignore[arg-type]
    return time.perf_counter() - t0, time.process_time() - c0, res


def _time_sarimax(y: np.ndarray, order: tuple[int, int]) -> tuple[float, float, object, object]:
    from statsmodels.tsa.statespace.sarimax import SARIMAX

    model = SARIMAX(y - y.mean(), order=(order[0], order[1], 0), measurement_error=True, trend="n")
    c0 = time.process_time()
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = model.fit(disp=False)
        res.smoother_results  # noqa: B018 - smoothing is part of the timed work
    return time.perf_counter() - t0, time.process_time() - c0, res, model


def _peak_memory(y: np.ndarray, order: tuple[int, int]) -> float:
    tracemalloc.start()
    fit_ari(y, AriConfig(order=order, robust="off"))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def _load() -> str:
    return f"{os.getloadavg()[0]:.1f}"


def _medians(runs: list[tuple[float, float]]) -> tuple[float, float]:
    return statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)


def _describe(runs: list[tuple[float, float]]) -> str:
    wall, cpu = _medians(runs)
    each = ", ".join(f"{r[0]:.2f}" for r in runs)
    return f"median {wall:.2f} s (CPU {cpu:.2f} s) of {len(runs)} [{each}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    parser.add_argument("--big", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--big-repeat", type=int, default=3, help="runs of each big fit")
    parser.add_argument("--big-sarimax", action="store_true", help="SARIMAX at --big too (slow)")
    parser.add_argument("--order", default="5,2")
    parser.add_argument("--skip-sarimax", action="store_true")
    parser.add_argument("--threads", default="1", help="BLAS threads (default 1)")
    args = parser.parse_args()
    order = tuple(int(v) for v in args.order.split(","))
    assert len(order) == 2
    order2: tuple[int, int] = (order[0], order[1])
    y = _series(args.n, order2)
    extras = ", ".join(
        f"{m} {'yes' if importlib.util.find_spec(m) else 'no'}" for m in ("numba", "threadpoolctl")
    )
    print(
        f"series: ARI{order2}, n = {args.n}, sigma_n = 0.02, sigma_e = 0.01; "
        f"BLAS threads {os.environ.get('OMP_NUM_THREADS')}; {extras}; load average {_load()}"
    )
    _time_navtrack(y[:5000], order2, "danish")  # compile (numba cache) outside the timings
    # navtrack (robust off, Danish) and SARIMAX alternate on the same series: under a varying
    # load the ratios of this run stay meaningful
    runs: dict[str, list[tuple[float, float]]] = {"off": [], "danish": [], "sarimax": []}
    res = res_rob = sm_res = model = None
    sarimax = not args.skip_sarimax
    for k in range(args.repeat):
        wall, cpu, res = _time_navtrack(y, order2, "off")
        runs["off"].append((wall, cpu))
        wall, cpu, res_rob = _time_navtrack(y, order2, "danish")
        runs["danish"].append((wall, cpu))
        if sarimax and k < max(1, min(args.repeat, 2)):
            wall, cpu, sm_res, model = _time_sarimax(y, order2)
            runs["sarimax"].append((wall, cpu))
    assert res is not None
    assert res_rob is not None
    med = {key: _medians(val) for key, val in runs.items() if val}
    print(
        f"navtrack fit_ari n={args.n} (robust off): {_describe(runs['off'])}; status "
        f"{res.status}, sigma_n {res.sigma_n:.5f}, sigma_e {res.sigma_e:.5f}, "  # type: ignore[attr-defined]
        f"loglike {res.loglike:.3f}"  # type: ignore[attr-defined]
    )
    print(
        f"navtrack fit_ari n={args.n} (danish):     {_describe(runs['danish'])}; "
        f"flagged {res_rob.n_flagged}; load {_load()}"  # type: ignore[attr-defined]
    )
    if sarimax:
        params = np.concatenate(
            [-res.phi, [res.sigma_n**2, res.sigma_e**2]]  # type: ignore[attr-defined]
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ll_ours = float(model.loglike(params))  # type: ignore[attr-defined]
        ll_sm = float(sm_res.llf)  # type: ignore[attr-defined]
        conv = sm_res.mle_retvals.get("converged")  # type: ignore[attr-defined]
        sm_p = np.asarray(sm_res.params)  # type: ignore[attr-defined]
        print(
            f"SARIMAX fit+smooth n={args.n}:           {_describe(runs['sarimax'])}; converged "
            f"{conv}; sigma_n {np.sqrt(max(sm_p[-2], 0)):.5f}, sigma_e {np.sqrt(sm_p[-1]):.5f}"
        )
        sm_w, sm_c = med["sarimax"]
        print(
            f"SARIMAX / navtrack at n={args.n} (wall, CPU): robust off "
            f"{sm_w / med['off'][0]:.1f}x, {sm_c / med['off'][1]:.1f}x; danish "
            f"{sm_w / med['danish'][0]:.1f}x, {sm_c / med['danish'][1]:.1f}x; SARIMAX loglike at "
            f"navtrack params {ll_ours:.3f}, at its own {ll_sm:.3f} (gain {ll_ours - ll_sm:+.3f})"
        )
    small = _peak_memory(y[: args.n // 10], order2)
    large = _peak_memory(y, order2)
    print(
        f"peak traced memory: n={args.n // 10}: {small:.1f} MiB, n={args.n}: {large:.1f} MiB "
        f"(ratio {large / small:.1f} for 10x n)"
    )
    if args.big:
        yb = _series(args.big, order2, seed=2)
        # robust off and Danish alternate: under a varying load both medians see the same load
        big: dict[str, list[tuple[float, float]]] = {"off": [], "danish": []}
        last: dict[str, object] = {}
        for _ in range(args.big_repeat):
            for robust in ("off", "danish"):
                wall, cpu, last[robust] = _time_navtrack(yb, order2, robust)
                big[robust].append((wall, cpu))
        big_med = {key: _medians(val) for key, val in big.items()}
        for robust in ("off", "danish"):
            res_big = last[robust]
            print(
                f"navtrack n={args.big} ({robust}): {_describe(big[robust])}; status "
                f"{res_big.status}, sigma_n {res_big.sigma_n:.5f}, "  # type: ignore[attr-defined]
                f"sigma_e {res_big.sigma_e:.5f}, flagged {res_big.n_flagged}, "  # type: ignore[attr-defined]
                f"evaluations {res_big.n_iter}; load {_load()}"  # type: ignore[attr-defined]
            )
        if sarimax:
            if args.big_sarimax:
                sm_w, sm_c, _, _ = _time_sarimax(yb, order2)
                what = f"SARIMAX fit+smooth n={args.big}: {sm_w:.1f} s (CPU {sm_c:.1f} s), measured"
            else:
                # SARIMAX's Kalman filter is linear in n: its n-epoch figure of this run scaled
                scale = args.big / args.n
                sm_w, sm_c = med["sarimax"][0] * scale, med["sarimax"][1] * scale
                what = (
                    f"SARIMAX at n={args.big} NOT RUN (needs --big-sarimax, over 10 min): "
                    f"ESTIMATE from its n={args.n} median of this run scaled linearly, "
                    f"{sm_w:.0f} s (CPU {sm_c:.0f} s)"
                )
            print(
                f"{what}; SARIMAX / navtrack at n={args.big} (wall, CPU): robust off "
                f"{sm_w / big_med['off'][0]:.1f}x, {sm_c / big_med['off'][1]:.1f}x; danish "
                f"{sm_w / big_med['danish'][0]:.1f}x, {sm_c / big_med['danish'][1]:.1f}x"
                + ("" if args.big_sarimax else " (ratios to an estimate, not a measurement)")
                + f"; load {_load()}"
            )
        peak = _peak_memory(yb, order2)
        print(f"peak traced memory n={args.big}: {peak:.1f} MiB; load average {_load()}")


if __name__ == "__main__":
    main()
