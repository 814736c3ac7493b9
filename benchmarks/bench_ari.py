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
        [--big-repeat 1] [--order 5,2] [--skip-sarimax] [--threads 1]

Prints medians of ``--repeat`` runs and the ratio SARIMAX / navtrack from the timings of this run
(``--big-repeat`` runs of the big Danish fit); memory is measured with ``tracemalloc`` (peak
of Python-allocated NumPy memory) at n/10 and n to show it is linear in n.
"""

from __future__ import annotations

import os
import sys

# Single-threaded BLAS/LAPACK on both sides (the SARIMAX figure is single-threaded);
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


def _time_navtrack(y: np.ndarray, order: tuple[int, int], robust: str) -> tuple[float, object]:
    t0 = time.perf_counter()
    res = fit_ari(y, AriConfig(order=order, robust=robust))  # type: ignore[arg-type]
    return time.perf_counter() - t0, res


def _time_sarimax(y: np.ndarray, order: tuple[int, int]) -> tuple[float, object, object]:
    from statsmodels.tsa.statespace.sarimax import SARIMAX

    model = SARIMAX(y - y.mean(), order=(order[0], order[1], 0), measurement_error=True, trend="n")
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = model.fit(disp=False)
        res.smoother_results  # noqa: B018 - smoothing is part of the timed work
    return time.perf_counter() - t0, res, model


def _peak_memory(y: np.ndarray, order: tuple[int, int]) -> float:
    tracemalloc.start()
    fit_ari(y, AriConfig(order=order, robust="off"))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    parser.add_argument("--big", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--big-repeat", type=int, default=1, help="runs of the big Danish fit")
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
        f"BLAS threads {os.environ.get('OMP_NUM_THREADS')}; {extras}; "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    times = []
    res = None
    for _ in range(args.repeat):
        t, res = _time_navtrack(y, order2, "off")
        times.append(t)
    t_nav = statistics.median(times)
    print(
        f"navtrack fit_ari (robust off): median {t_nav:.2f} s of {args.repeat} "
        f"[{', '.join(f'{v:.2f}' for v in times)}]; status {res.status}, "  # type: ignore[union-attr]
        f"sigma_n {res.sigma_n:.5f}, sigma_e {res.sigma_e:.5f}, loglike {res.loglike:.3f}"  # type: ignore[union-attr]
    )
    t_rob, res_rob = _time_navtrack(y, order2, "danish")
    print(
        f"navtrack fit_ari (danish):     {t_rob:.2f} s; flagged {res_rob.n_flagged}"  # type: ignore[attr-defined]
    )
    if not args.skip_sarimax:
        sm_times = []
        for _ in range(max(1, min(args.repeat, 2))):
            t_sm, sm_res, model = _time_sarimax(y, order2)
            sm_times.append(t_sm)
        t_sm = statistics.median(sm_times)
        params = np.concatenate(
            [-res.phi, [res.sigma_n**2, res.sigma_e**2]]  # type: ignore[union-attr]
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ll_ours = float(model.loglike(params))  # type: ignore[attr-defined]
        ll_sm = float(sm_res.llf)  # type: ignore[attr-defined]
        conv = sm_res.mle_retvals.get("converged")  # type: ignore[attr-defined]
        sm_p = np.asarray(sm_res.params)  # type: ignore[attr-defined]
        print(
            f"SARIMAX fit+smooth:            median {t_sm:.2f} s of {len(sm_times)}; converged "
            f"{conv}; sigma_n {np.sqrt(max(sm_p[-2], 0)):.5f}, sigma_e {np.sqrt(sm_p[-1]):.5f}"
        )
        print(
            f"speed-up {t_sm / t_nav:.1f}x;  SARIMAX loglike at navtrack params {ll_ours:.3f}, "
            f"at its own {ll_sm:.3f} (gain {ll_ours - ll_sm:+.3f})"
        )
    small = _peak_memory(y[: args.n // 10], order2)
    large = _peak_memory(y, order2)
    print(
        f"peak traced memory: n={args.n // 10}: {small:.1f} MiB, n={args.n}: {large:.1f} MiB "
        f"(ratio {large / small:.1f} for 10x n)"
    )
    if args.big:
        yb = _series(args.big, order2, seed=2)
        t_big, res_big = _time_navtrack(yb, order2, "off")
        print(
            f"navtrack n={args.big} (robust off): {t_big:.1f} s; status {res_big.status}, "  # type: ignore[attr-defined]
            f"sigma_n {res_big.sigma_n:.5f}, sigma_e {res_big.sigma_e:.5f}"  # type: ignore[attr-defined]
        )
        t_big_r = [_time_navtrack(yb, order2, "danish")[0] for _ in range(args.big_repeat)]
        print(
            f"navtrack n={args.big} (danish):     median {statistics.median(t_big_r):.1f} s of "
            f"{args.big_repeat} [{', '.join(f'{v:.1f}' for v in t_big_r)}]"
        )
        peak = _peak_memory(yb, order2)
        print(f"peak traced memory n={args.big}: {peak:.1f} MiB")


if __name__ == "__main__":
    main()
