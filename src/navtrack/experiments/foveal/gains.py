"""Numerical check of the foveal gain rules against the one-scan optimum (paper 4, section IV).

Rule (1) and the SO gain were damaged in the extraction; this check settles them: for one
target, the gain minimising the expected posterior position variance
(:func:`~navtrack.tracking.trackers.sensor_control.optimal_gain`) against rule (1) in both readings
of its exponent; for SO, the optimum for two targets at ``±D/2`` fitted by a power law in the
spread ``S``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from navtrack.tracking.trackers.sensor_control import (
    SO_SPREAD_FACTORS,
    expected_posterior_variance,
    foveal_gain,
    gain_exponent,
    optimal_gain,
    so_gain,
)

__all__ = ["gain_check"]

#: Predicted position variances (m²) of the rule (1) check.
CHECK_P_M2 = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0)
#: Separations (m) and variances (m²) of the SO check.
CHECK_SO_D_M = (0.5, 1.0, 2.0, 4.0, 6.0)
CHECK_SO_P_M2 = (0.05, 0.2, 0.5, 1.0)


def gain_check(R: float) -> dict[str, Any]:
    """Rule (1) and the SO gain against the one-scan optimal gain at noise variance ``R``.

    Returns
    -------
    dict
        ``rule1``: per ``P``: optimal gain, rule (1) (``a = log10(R)/8 - 0.4``), the other
        grouping (``a = 1/(8 log10 R) - 0.4``), and their expected posterior variances relative
        to the optimum; ``so``: the optimal gains over ``(D, P)``, the free power-law fit
        ``c = A S^e``, and the rms log-error of the reconstructed ``(0.12 S²)^a(R)``.
    """
    a_alt = 1.0 / (8.0 * math.log10(R)) - 0.4
    rows = []
    for P in CHECK_P_M2:
        c_opt = optimal_gain(P, R)
        c_rule = float(foveal_gain(P, R))
        c_alt = P**a_alt
        v = expected_posterior_variance([c_opt, c_rule, c_alt], P, R)
        rows.append(
            {
                "P_m2": P,
                "c_optimal": c_opt,
                "c_rule1": c_rule,
                "c_rule1_other_reading": c_alt,
                "var_ratio_rule1": float(v[1] / v[0]),
                "var_ratio_other_reading": float(v[2] / v[0]),
                "posterior_over_prior_optimal": float(v[0] / P),
            }
        )
    so = []
    for D in CHECK_SO_D_M:
        for P in CHECK_SO_P_M2:
            c_opt = optimal_gain(P, R, offset=[-D / 2, D / 2])
            so.append(
                {
                    "D_m": D,
                    "P_m2": P,
                    "spread_m": D + SO_SPREAD_FACTORS[0] * 2 * math.sqrt(P),
                    "c_optimal": c_opt,
                    "c_so": float(so_gain(D, P, P, R)),
                }
            )
    S = np.array([r["spread_m"] for r in so])
    c = np.array([r["c_optimal"] for r in so])
    A = np.c_[np.ones(len(S)), np.log(S)]
    coef = np.linalg.lstsq(A, np.log(c), rcond=None)[0]
    c_so = np.array([r["c_so"] for r in so])
    return {
        "R_rad2": R,
        "exponent_rule1": gain_exponent(R),
        "exponent_other_reading": a_alt,
        "kappa_optimal": rows[0]["c_optimal"] * math.sqrt(CHECK_P_M2[0]),
        "rule1": rows,
        "so": {
            "points": so,
            "fit_coefficient": float(math.exp(coef[0])),
            "fit_exponent": float(coef[1]),
            "fit_rms_log": float(np.sqrt(np.mean((A @ coef - np.log(c)) ** 2))),
            "reconstruction_coefficient": float(0.12 ** gain_exponent(R)),
            "reconstruction_exponent": 2 * gain_exponent(R),
            "reconstruction_rms_log": float(np.sqrt(np.mean(np.log(c_so / c) ** 2))),
        },
    }
