"""Identifiability of an ARI fit: Cramér–Rao bounds of the sigmas, the paper's conditions.

Paper 5, §2.2: the VCE of the Gauss–Markov model (2)–(3) needs ``sigma_n^2`` and ``sigma_e^2``
"of same order of magnitude" (after Lindenberger 1987). :func:`sigma_bounds` gives the relative
Cramér–Rao standard deviations of ``sigma_n`` and ``sigma_e`` at an estimate (the observed
information of the likelihood, :func:`navtrack.smoothing.estimation.observed_information`);
:func:`identifiability_warnings` names what leaves the conditions: the ratio, an estimate at
its bound, a bound above :data:`WEAK_CRB`.

Notes
-----
Reading of "same order of magnitude": ``sigma_e / sigma_n`` within a factor
:data:`SAME_ORDER` = 10 either way (the paper gives no number; its own Tables 4–5 have ratios
0.21–0.87). The bound is evaluated on the observations the fit kept (flagged gross errors and
down-weighted epochs counted as missing) with unit weights.
"""

from __future__ import annotations

import math

import numpy as np

from navtrack.smoothing.estimation import observed_information
from navtrack.smoothing.result import AriResult, AriStatus

__all__ = ["SAME_ORDER", "WEAK_CRB", "identifiability_warnings", "sigma_bounds"]

#: Largest ``sigma_e / sigma_n`` (or its inverse) counted as "the same order of magnitude".
SAME_ORDER = 10.0
#: Relative Cramér–Rao standard deviation above which a sigma is called weakly identified.
WEAK_CRB = 0.10


def sigma_bounds(res: AriResult, *, conditional: bool = False) -> tuple[float, float]:
    """Relative Cramér–Rao standard deviations ``(sd(sigma_n)/sigma_n, sd(sigma_e)/sigma_e)``
    at the estimate of ``res`` (NaN when it has none or the information is singular).

    ``conditional``: the likelihood without the stationary start (the paper's estimator)."""
    if not res.estimated or not (res.sigma_n > 0 and res.sigma_e > 0):
        return math.nan, math.nan
    y = np.where(res.weight > 0.5, res.y, np.nan)
    p = res.p
    try:
        info = observed_information(
            y,
            res.phi,
            res.d,
            res.sigma_n,
            res.sigma_e,
            initial="conditional" if conditional else "stationary",
        )
        cov = np.linalg.inv(info)
    except (np.linalg.LinAlgError, ValueError):
        return math.nan, math.nan
    # log sigma^2 has sd s: sigma has relative sd s / 2
    return 0.5 * math.sqrt(max(cov[p, p], 0.0)), 0.5 * math.sqrt(max(cov[p + 1, p + 1], 0.0))


def identifiability_warnings(res: AriResult, crb_n: float, crb_e: float) -> list[str]:
    """Sentences naming each identifiability condition ``res`` leaves (empty when none).

    Parameters
    ----------
    res : AriResult
    crb_n, crb_e : float
        :func:`sigma_bounds` of ``res``.
    """
    out: list[str] = []
    if not res.estimated:
        return out
    ratio = res.sigma_e / res.sigma_n if res.sigma_n > 0 else math.inf
    if not 1.0 / SAME_ORDER <= ratio <= SAME_ORDER:
        out.append(
            f"sigma_e/sigma_n is {ratio:.3g}, not of the same order of magnitude (paper §2.2: "
            f"within a factor {SAME_ORDER:g}); the variance components are weakly separable"
        )
    if res.status == AriStatus.BOUNDARY:
        out.append("a variance component sits at its bound: not identifiable from these data")
    for name, crb in (("sigma_n", crb_n), ("sigma_e", crb_e)):
        if math.isfinite(crb) and crb > WEAK_CRB:
            out.append(
                f"{name} weakly identified: Cramér–Rao relative sd {crb:.0%} > {WEAK_CRB:.0%}"
            )
    return out
