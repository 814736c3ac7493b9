"""Speed of navtrack's batched two-satellite AGPS solvers against scipy ``least_squares``.

Fixes: those of the reproduction's simulation (paper 1's site, the bundled broadcast ephemerides,
the documented error model; :func:`navtrack.experiments.agps.simulation.fix_set_problem`), all
intervals and heights, ``--fixes`` of them (default 10,000). Timed work:

* navtrack: :func:`navtrack.gnss.agps.solve_agps` on all fixes in one call, Gauss–Newton and
  Marquardt (the paper's steps, ``mu_1 = 0.1, beta = 10, epsilon = 0.1``), both included in one
  timing — the issue's bar is both solvers on 10,000 fixes in under 1 s;
* peer: ``scipy.optimize.least_squares(method="lm")`` (MINPACK's Levenberg–Marquardt) on the
  same five equations, one call per fix in a Python loop, on ``--peer-fixes`` of them (default
  1,000), scaled to the same number of fixes for the ratio.

navtrack and the peer alternate ``--repeat`` times; medians of CPU time (``process_time``,
single-threaded BLAS: robust to a machine shared with other jobs) are printed with navtrack's
wall time, and the ratio of the CPU medians of this run. Usage::

    PYTHONPATH=src python benchmarks/bench_agps.py [--fixes 10000] [--peer-fixes 1000]
        [--repeat 5]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from navtrack.experiments.agps.simulation import (  # noqa: E402
    AgpsExperimentParams,
    fix_set_problem,
)
from navtrack.geodesy import WGS84_A_M  # noqa: E402
from navtrack.gnss.agps import (  # noqa: E402
    WGS84_B_M,
    AgpsProblem,
    ellipsoid_residual,
    solve_agps,
)
from navtrack.gnss.corrections import geometric_range  # noqa: E402


def _fixes(n: int, seed: int = 1) -> tuple[AgpsProblem, np.ndarray]:
    params = AgpsExperimentParams(real_data=False)
    rng = np.random.default_rng(seed)
    parts, truths = [], []
    count = 0
    while count < n:
        prob, truth, _ = fix_set_problem(params, rng)
        parts.append(prob)
        truths.append(np.repeat(truth[None], prob.size, 0))
        count += prob.size

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])[:n]

    problem = AgpsProblem(
        cat("t_gps_s"),
        cat("sat_pos_m"),
        cat("y_m"),
        cat("height_m"),
        cat("start_xyz_m"),
        cat("usable"),
    )
    return problem, np.concatenate(truths)[:n]


def _time_navtrack(problem: AgpsProblem) -> tuple[float, float]:
    """Wall and CPU seconds of both solvers on all fixes."""
    t0, c0 = time.perf_counter(), time.process_time()
    solve_agps(problem, "gn")
    solve_agps(problem, "lm")
    return time.perf_counter() - t0, time.process_time() - c0


def _peer_solve(problem: AgpsProblem, n: int) -> tuple[float, np.ndarray]:
    from scipy.optimize import least_squares

    out = np.empty((n, 3))
    t0 = time.process_time()
    for i in range(n):
        sat, y, h = problem.sat_pos_m[i], problem.y_m[i], problem.height_m[i]
        ah2, bh2 = (WGS84_A_M + h) ** 2, (WGS84_B_M + h) ** 2
        scale = (WGS84_A_M + h) / 2.0

        def fun(x: np.ndarray, sat=sat, y=y, h=h, scale=scale) -> np.ndarray:
            rho, _ = geometric_range(sat, x[:3])
            clk = np.array([x[3], x[3], x[4], x[4]])
            return np.append(rho + clk - y, scale * ellipsoid_residual(x[:3], h))

        def jac(x: np.ndarray, sat=sat, ah2=ah2, bh2=bh2, scale=scale) -> np.ndarray:
            _, los = geometric_range(sat, x[:3])
            a = np.zeros((5, 5))
            a[:4, :3] = -los
            a[0:2, 3] = 1.0
            a[2:4, 4] = 1.0
            a[4, :3] = scale * 2.0 * x[:3] / np.array([ah2, ah2, bh2])
            return a

        x0 = np.concatenate([problem.start_xyz_m[i], [0.0, 0.0]])
        out[i] = least_squares(fun, x0, jac=jac, method="lm").x[:3]
    return time.process_time() - t0, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fixes", type=int, default=10000)
    ap.add_argument("--peer-fixes", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    problem, truth = _fixes(args.fixes)
    have_scipy = importlib.util.find_spec("scipy") is not None
    n_peer = min(args.peer_fixes, problem.size)
    ours, theirs = [], []
    for _ in range(args.repeat):
        ours.append(_time_navtrack(problem))
        if have_scipy:
            theirs.append(_peer_solve(problem, n_peer)[0])
    gn = solve_agps(problem, "gn")
    lm = solve_agps(problem, "lm")
    t_ours = statistics.median(c for _, c in ours)
    wall = statistics.median(w for w, _ in ours)
    print(f"fixes {problem.size}, repeats {args.repeat} (navtrack and peer alternating)")
    print(
        f"navtrack gn + lm, one call each   median CPU {t_ours:.3f} s, wall {wall:.3f} s "
        "(bar: < 1 s; wall time includes the waits of a loaded machine)"
    )
    for name, res in (("gn", gn), ("lm", lm)):
        err = np.linalg.norm(res.pos_m - truth, axis=1)
        print(
            f"  {name}: ok {int(res.ok.sum())}, mean iterations {res.iterations.mean():.2f}, "
            f"median error {np.nanmedian(err):.1f} m"
        )
    if not have_scipy:
        print("scipy not installed: no peer, no ratio")
        return
    t_peer = statistics.median(theirs) * problem.size / n_peer
    _, x_peer = _peer_solve(problem, min(n_peer, 200))
    same = np.linalg.norm(x_peer - gn.pos_m[: x_peer.shape[0]], axis=1)
    print(
        f"scipy least_squares(method='lm') looped, {n_peer} fixes scaled to {problem.size}: "
        f"median CPU {t_peer:.3f} s"
    )
    print(
        f"  its fixes vs navtrack gn (square system, same root): median distance "
        f"{np.nanmedian(same):.2e} m"
    )
    print(f"ratio peer / navtrack (CPU; gn + lm vs one lm): {t_peer / t_ours:.1f}x")


if __name__ == "__main__":
    main()
