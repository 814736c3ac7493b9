"""Speed of navtrack's attitude propagation and RANSAC-SVD fix against scipy peers.

Timed work, alternating navtrack and peer in the same run (medians of ``--repeat``):

* propagation of a whole BROAD trial (gyro rates -> delta angles -> attitudes at every sample):
  navtrack ``propagate`` (closed form and the paper's third-order series; numba loop when
  installed, else NumPy) against a plain loop of ``scipy.spatial.transform.Rotation`` products
  (``R = R * Rotation.from_rotvec(ω Δt)``) over the same samples — the straightforward
  scipy-based propagation. The attitudes are checked to agree (printed).
* one camera fix of 12 rays with 20 % outliers: navtrack ``ransac_attitude`` (SVD inside
  RANSAC, adaptive trial count) against ``Rotation.align_vectors`` on the same rays (the
  non-robust least squares without RANSAC, so the ratio is the price of robustness).

``ahrs`` is not used as a peer: its 0.4.0 ``'series'`` propagation raises the Θ matrix
element-wise and is wrong beyond first order (tests/attitude/test_attitude_conventions.py).

Usage::

    NAVTRACK_SHARED_DATA=/path/to/shared/data PYTHONPATH=src python benchmarks/bench_attitude.py
        [--trial 07_undisturbed_fast_rotation_B] [--repeat 7] [--loop-samples 5000]

``--loop-samples N`` times the scipy loop on the first N samples only and scales it to the trial
(default 5000; 0: the whole trial, about 20 s on a loaded machine).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack.attitude.quaternion import HAVE_NUMBA, attitude_errors, delta_angles, propagate
from navtrack.attitude.wahba import ransac_attitude
from navtrack.experiments.contract import shared_data_dir
from navtrack.io.broad import read_broad


def _time(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _alternate(fns: dict[str, Callable[[], object]], repeat: int) -> dict[str, float]:
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for k, fn in fns.items():
            times[k].append(_time(fn))
    return {k: statistics.median(v) for k, v in times.items()}


def _scipy_loop(q0: Rotation, t: np.ndarray, gyr: np.ndarray, n: int) -> Rotation:
    r = q0
    out = [r]
    for k in range(n - 1):
        r = r * Rotation.from_rotvec(gyr[k] * (t[k + 1] - t[k]))
        out.append(r)
    return Rotation.concatenate(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trial", default="07_undisturbed_fast_rotation_B")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--loop-samples", type=int, default=5000)
    args = ap.parse_args()
    path = shared_data_dir() / "trajectory" / "broad" / f"{args.trial}.mat"
    if not path.exists():
        raise SystemExit(f"{path} absent (set NAVTRACK_SHARED_DATA)")
    trial = read_broad(path)
    t, gyr = trial.t_s, trial.gyr_rad_s
    n = t.size
    q0 = Rotation.identity()
    n_loop = n if args.loop_samples <= 0 else min(args.loop_samples, n)

    def nav_closed() -> object:
        return propagate(q0, delta_angles(t, gyr))

    def nav_series() -> object:
        return propagate(q0, delta_angles(t, gyr), method="series", order=3)

    def peer() -> object:
        return _scipy_loop(q0, t, gyr, n_loop)

    nav_closed(), nav_series()  # compile (numba cache) outside the timing
    med = _alternate({"closed": nav_closed, "series": nav_series, "scipy": peer}, args.repeat)
    scipy_whole = med["scipy"] * (n - 1) / max(n_loop - 1, 1)
    ref = _scipy_loop(q0, t, gyr, n_loop)
    agree = attitude_errors(propagate(q0, delta_angles(t, gyr)).rotation[:n_loop], ref)[0].max()
    print(f"propagation, BROAD {args.trial}: {n} samples, numba {HAVE_NUMBA}")
    print(f"  navtrack closed form      {1e3 * med['closed']:8.2f} ms")
    print(f"  navtrack series order 3   {1e3 * med['series']:8.2f} ms")
    print(
        f"  scipy Rotation loop       {1e3 * scipy_whole:8.2f} ms"
        + ("" if n_loop == n else f" (timed on {n_loop} samples, scaled)")
    )
    print(f"  ratio scipy / navtrack    {scipy_whole / med['closed']:8.1f} x (closed form)")
    print(f"  max difference            {agree:.2e} rad over {n_loop} samples")

    rng = np.random.default_rng(0)
    truth = Rotation.random(rng=rng)
    w = rng.normal(size=(12, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    v = Rotation.from_rotvec(rng.normal(0, 1e-3, (12, 3))).apply(truth.inv().apply(w))
    v[:3] = rng.normal(size=(3, 3))
    reps = 50 * args.repeat
    fix = _alternate(
        {
            "ransac": lambda: ransac_attitude(v, w, rng),
            "align": lambda: Rotation.align_vectors(w, v),
        },
        reps,
    )
    print("camera fix, 12 rays, 3 outliers:")
    print(f"  navtrack ransac_attitude  {1e3 * fix['ransac']:8.3f} ms")
    print(f"  scipy align_vectors       {1e3 * fix['align']:8.3f} ms (no outlier rejection)")
    print(f"  ratio navtrack / scipy    {fix['ransac'] / fix['align']:8.1f} x")


if __name__ == "__main__":
    main()
