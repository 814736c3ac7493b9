"""Monte Carlo runs of the reproduction: seeded RANSAC-SVD scenes with 20 % outliers.

Each run draws an attitude, ``n_rays`` target rays over all directions, ray noise and a fifth of
the rays replaced by random directions; RANSAC-SVD must reject every outlier and return the
attitude within the noise, judged against ``Rotation.align_vectors`` on the true inliers (the
oracle: the least-squares attitude an outlier-free solver would return).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack.attitude.wahba import FixStatus, RansacConfig, ransac_attitude
from navtrack.experiments.alhat.params import AlhatParams

__all__ = ["ransac_scene", "summarize_scenes"]


def ransac_scene(params: AlhatParams, rng: np.random.Generator) -> dict[str, Any]:
    """One seeded scene; returns the outcome as a JSON-able dict."""
    n = params.n_rays
    truth = Rotation.random(rng=rng)
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    v = np.asarray(truth.inv().apply(w))
    v = np.asarray(Rotation.from_rotvec(rng.normal(0.0, params.ray_sigma_rad, (n, 3))).apply(v))
    k = round(params.outlier_fraction * n)
    outlier = np.zeros(n, bool)
    outlier[rng.choice(n, k, replace=False)] = True
    v[outlier] = rng.normal(size=(k, 3))
    cfg = RansacConfig(threshold_rad=params.ransac_threshold_rad, trials=params.ransac_trials)
    t0 = time.perf_counter()
    fix = ransac_attitude(v, w, rng, cfg)
    seconds = time.perf_counter() - t0
    oracle, _ = Rotation.align_vectors(w[~outlier], v[~outlier])
    ok = fix.status == FixStatus.OK
    est = Rotation.from_quat(fix.quat) if ok else None
    return {
        "status": str(fix.status),
        "outliers": k,
        "outliers_accepted": int(np.sum(fix.inliers & outlier)),
        "inliers_rejected": int(np.sum(~fix.inliers & ~outlier)),
        "error_rad": float((est * truth.inv()).magnitude()) if est else float("nan"),
        "oracle_error_rad": float((oracle * truth.inv()).magnitude()),
        "from_oracle_rad": float((est * oracle.inv()).magnitude()) if est else float("nan"),
        "seconds": seconds,
    }


def summarize_scenes(params: AlhatParams, runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Outlier recovery and attitude error over the runs."""
    if not runs:
        return {"runs": 0}
    err = np.array([r["error_rad"] for r in runs])
    oracle = np.array([r["oracle_error_rad"] for r in runs])
    gap = np.array([r["from_oracle_rad"] for r in runs])
    return {
        "runs": len(runs),
        "n_rays": params.n_rays,
        "outlier_fraction": params.outlier_fraction,
        "ray_sigma_rad": params.ray_sigma_rad,
        "threshold_rad": params.ransac_threshold_rad,
        "trials": params.ransac_trials,
        "ok": sum(r["status"] == "ok" for r in runs),
        "all_outliers_rejected": sum(r["outliers_accepted"] == 0 for r in runs),
        "outliers_accepted": sum(r["outliers_accepted"] for r in runs),
        "inliers_rejected": sum(r["inliers_rejected"] for r in runs),
        "error_mean_rad": float(np.nanmean(err)),
        "error_max_rad": float(np.nanmax(err)),
        "oracle_error_mean_rad": float(np.mean(oracle)),
        "from_oracle_max_rad": float(np.nanmax(gap)),
        "fix_ms_median": 1e3 * float(np.median([r["seconds"] for r in runs])),
    }
