"""Timing of integrity monitoring: FCM against scikit-fuzzy's ``cmeans``, and positioning with
and without RAIM, measured in the same run, alternating, medians.

Printed, all from timings of this run:

* FCM per epoch: :func:`navtrack.integrity.fcm.fuzzy_cmeans` and ``skfuzzy.cluster.cmeans`` on
  the same full design matrices (real SEPT epochs with a 20 m fault on two satellites), same
  start memberships, same tolerance; also navtrack's whole per-epoch identification (QR parity
  matrix, full design matrix, FCM, the paper's rule: :func:`navtrack.integrity.raim.
  fcm_exclusion`) — ms per epoch and the ratio;
* a whole file (SEPT, 900 epochs, GPS+Galileo+QZSS, in-process ``solve_positions`` from read
  observations): without RAIM and with ``--raim fcm`` (and ``fde``, ``ss``), s and the ratio to
  no RAIM; ``ss`` runs batched over all epochs of a block;
* the same file with faults on 2 satellites in every epoch (the worst case of ``fcm``: every
  epoch is clustered).

Usage::

    NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python benchmarks/bench_raim.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data")) / "gnss"


def _median_pair(
    a: Callable[[], object], b: Callable[[], object], repeat: int
) -> tuple[float, float]:
    """Medians of alternating timings of ``a`` and ``b`` (order swapped every repeat)."""
    ta, tb = [], []
    a()
    b()
    for i in range(repeat):
        for f, out in ((a, ta), (b, tb)) if i % 2 == 0 else ((b, tb), (a, ta)):
            t = time.perf_counter()
            f()
            out.append(time.perf_counter() - t)
    return statistics.median(ta), statistics.median(tb)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--epochs", type=int, default=100, help="epochs of the FCM comparison")
    args = ap.parse_args()

    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.spp import (
        SppConfig,
        code_pseudoranges,
        corrected_measurements,
        estimate_position,
        satellite_states,
    )
    from navtrack.integrity.exclusion import fcm_exclusion
    from navtrack.integrity.fcm import full_design_matrix, fuzzy_cmeans, parity_matrix
    from navtrack.integrity.raim import RaimConfig, variance_factor
    from navtrack.integrity.residuals import whitened
    from navtrack.positioning import solve_positions

    obs = read_obs(SHARED / "cssrlib_sept" / "SEPT078M.21O")
    nav = read_nav(SHARED / "cssrlib_sept" / "SEPT078M.21P")
    cfg = SppConfig(systems="GEJ")
    pr = code_pseudoranges(obs, cfg)
    meas = corrected_measurements(pr, satellite_states(pr, [nav], config=cfg), cfg)
    clean = estimate_position(meas, cfg)
    s2 = variance_factor(clean)

    rng = np.random.default_rng(0)
    y = np.array(meas.y_m)
    for e in range(y.shape[0]):
        cols = np.flatnonzero(clean.used[e])
        y[e, rng.choice(cols, 2, replace=False)] += 20.0
    faulty = meas.replace(y_m=y)
    est = estimate_position(faulty, cfg)
    g, yw, used = whitened(est)
    g, yw = g / np.sqrt(s2), yw / np.sqrt(s2)

    # ---- FCM per epoch against scikit-fuzzy
    samples, inits = [], []
    for e in range(args.epochs):
        cols = np.flatnonzero(used[e])
        gb = g[e][cols][:, np.abs(g[e][cols]).sum(axis=0) > 0]
        x = full_design_matrix(parity_matrix(gb), -yw[e, cols]).T
        samples.append(x)
        inits.append(fuzzy_cmeans(x, 3, 2.0, max_iter=0).u0)
    try:
        import skfuzzy
    except ImportError:
        skfuzzy = None
        print("scikit-fuzzy not installed: FCM ratio not printed")

    def ours() -> None:
        for x in samples:
            fuzzy_cmeans(x, 3, 2.0, tol=1e-6, max_iter=100)

    n_max = max(x.shape[0] for x in samples)
    q_max = max(x.shape[1] for x in samples)
    stack = np.zeros((len(samples), n_max, q_max))
    valid = np.zeros((len(samples), n_max), dtype=bool)
    for i, x in enumerate(samples):
        stack[i, : x.shape[0], : x.shape[1]] = x
        valid[i, : x.shape[0]] = True

    def ours_batched() -> None:
        fuzzy_cmeans(stack, 3, 2.0, valid=valid, tol=1e-6, max_iter=100)

    def peer() -> None:
        for x, u0 in zip(samples, inits, strict=True):
            skfuzzy.cluster.cmeans(x.T, 3, 2.0, 1e-6, 100, init=u0.copy())

    raim_fcm = RaimConfig("fcm", variance_factor=s2)
    rows = np.arange(args.epochs)

    def identify() -> None:
        fcm_exclusion(g[rows] * np.sqrt(s2), yw[rows] * np.sqrt(s2), used[rows], raim_fcm)

    n_sat = int(np.median(used[rows].sum(axis=1)))
    if skfuzzy is not None:
        t_ours, t_peer = _median_pair(ours, peer, args.repeat)
        n = args.epochs
        print(f"FCM per epoch ({n} SEPT epochs, {n_sat} satellites, 2 faults of 20 m)")
        print(f"  navtrack fuzzy_cmeans  {1e3 * t_ours / n:8.3f} ms")
        print(f"  skfuzzy cmeans         {1e3 * t_peer / n:8.3f} ms")
        print(f"  ratio navtrack/skfuzzy {t_ours / t_peer:8.3f}")
        t_batch, t_peer2 = _median_pair(ours_batched, peer, args.repeat)
        print(f"  navtrack batched over the {n} epochs {1e3 * t_batch / n:8.3f} ms per epoch "
              f"(skfuzzy {1e3 * t_peer2 / n:.3f}, ratio {t_batch / t_peer2:.3f})")  # fmt: skip
    t_id, _ = _median_pair(identify, identify, args.repeat)
    print(f"  navtrack identification (QR + full design matrix + FCM + rule) "
          f"{1e3 * t_id / args.epochs:.3f} ms per epoch")  # fmt: skip

    # ---- whole file with and without RAIM
    def solve(raim: RaimConfig | None, o=obs) -> Callable[[], object]:  # type: ignore[no-untyped-def]
        return lambda: solve_positions(o, [nav], config=cfg, raim=raim)

    print(f"whole file: SEPT {obs.t_gps_s.size} epochs, GEJ, solve_positions in-process")
    for method in ("fcm", "fde", "ss"):
        t0, t1 = _median_pair(solve(None), solve(RaimConfig(method)), args.repeat)
        print(f"  no RAIM {t0:7.3f} s   --raim {method:<4} {t1:7.3f} s   ratio {t1 / t0:6.2f}")

    values = np.array(obs.values)
    c1c = obs.codes.index("C1C")
    for e in range(values.shape[0]):
        have = np.flatnonzero(np.isfinite(values[e, :, c1c]))
        values[e, rng.choice(have, 2, replace=False), c1c] += 20.0
    bad = obs.replace(values=values)
    # the variance factor of the clean file: estimated from a file faulty in every epoch it
    # would absorb the faults
    fcm_clean = RaimConfig("fcm", variance_factor=s2)
    t0, t1 = _median_pair(solve(None, bad), solve(fcm_clean, bad), args.repeat)
    print(f"  faults of 20 m on 2 satellites in every epoch: no RAIM {t0:7.3f} s   "
          f"--raim fcm {t1:7.3f} s   ratio {t1 / t0:6.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
