"""Synthetic truths built from paper 5's published statistics.

The paper prints, per application, the order, ``sigma_n``, ``sigma_e`` (INS only), ``sigma_x``
and the autocorrelations ``r(h)`` of the filtered series (Tables 1, 3–5), but no AR
coefficients. Those statistics are functions of the model: for a series of ``n`` epochs,
``sigma_x^2`` and ``r(h)`` are the mean diagonal and normalised off-diagonals of ``N^-1`` of
eqs. (2)–(3) (:func:`filtered_statistics`). :func:`fit_published` chooses the AR coefficients
(and ``sigma_e`` where the paper does not print it) whose theoretical ``sigma_x / sigma_n`` and
``r(1..k)`` are closest to the printed ones.

Notes
-----
Fitting: nonlinear least squares (``scipy.optimize.least_squares``, trust-region reflective)
over the partial autocorrelations ``pi_1..pi_p`` of the AR part, bounded to ``[-0.95, 0.95]``
(so every candidate is stationary; Durbin–Levinson maps them to ``phi``), and ``log sigma_e``
when it is free. Residuals: ``sigma_x / sigma_n`` and each ``r(h)`` minus the printed value,
each divided by 0.01 (the printed resolution), plus a ridge ``0.1 * pi_j`` so that
under-determined cases (GPS: six unknowns, four printed values) get the smoothest of the
equally good solutions. The result depends on ``n`` (the strip length) only weakly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from navtrack._typing import ArrayLike, FloatArray
from navtrack.experiments.ari.printed import PAPER_TABLES
from navtrack.smoothing.ari import gauss_markov_filter

__all__ = [
    "MATCH_TOLERANCE",
    "filtered_statistics",
    "fit_published",
    "pacf_to_phi",
    "printed_columns",
    "printed_truths",
]


def pacf_to_phi(pacf: ArrayLike) -> FloatArray:
    """AR coefficients ``(p,)`` in the paper's sign (``u_t + sum phi_i u_{t-i} = e_t``) of
    the partial autocorrelations ``pacf`` (Durbin–Levinson recursion; ``|pi| < 1`` gives a
    stationary AR)."""
    a = np.zeros(0)
    for k, pi in enumerate(np.asarray(pacf, dtype=float)):
        a = np.concatenate([a - pi * a[::-1], [pi]]) if k else np.array([pi])
    return -a


def filtered_statistics(
    phi: ArrayLike, d: int, sigma_n: float, sigma_e: float, n: int, lags: int = 4
) -> tuple[float, FloatArray]:
    """Theoretical ``sigma_x / sigma_n`` and ``r(1..lags)`` ``(lags,)`` of the filtered series
    of ``n`` epochs (stationary start, unit weights), as the paper computes them from ``N^-1``."""
    _, zb, _ = gauss_markov_filter(
        np.zeros(n), phi, d, sigma_n, sigma_e, width=lags, initial="stationary"
    )
    var = zb[0]
    r = np.array(
        [np.mean(zb[h, : n - h] / np.sqrt(var[: n - h] * var[h:])) for h in range(1, lags + 1)]
    )
    return math.sqrt(float(np.mean(var))) / sigma_n, r


def fit_published(
    p: int,
    d: int,
    sigma_n: float,
    sigma_e: float | None,
    n: int,
    ratio: float,
    r: Sequence[float],
    start: ArrayLike | None = None,
) -> tuple[FloatArray, float, float]:
    """AR coefficients (and ``sigma_e`` if ``None``) matching the printed statistics.

    Parameters
    ----------
    p, d : int
        The paper's order.
    sigma_n : float
        Printed observation noise.
    sigma_e : float or None
        Printed prediction error; ``None``: fitted too (GPS, Table 1 has none).
    n : int
        Epochs per series (strip length).
    ratio : float
        Printed ``sigma_x / sigma_n``.
    r : sequence of float
        Printed ``r(1..k)``.
    start : array_like, shape (p,), optional
        Starting partial autocorrelations (default zero).

    Returns
    -------
    phi : ndarray, shape (p,)
    sigma_e : float
    cost : float
        RMS of the residuals in units of 0.01 (without the ridge).
    """
    target_r = np.asarray(r, dtype=float)
    free_e = sigma_e is None

    def unpack(theta: FloatArray) -> tuple[FloatArray, float]:
        se = math.exp(theta[p]) if free_e else float(sigma_e)  # type: ignore[arg-type]
        return pacf_to_phi(theta[:p]), se

    def resid(theta: FloatArray, ridge: float = 0.1) -> FloatArray:
        phi, se = unpack(theta)
        rat, rr = filtered_statistics(phi, d, sigma_n, se, n, target_r.size)
        fit = np.concatenate([[rat - ratio], rr - target_r]) / 0.01
        return np.concatenate([fit, ridge * theta[:p]])

    pacf0 = np.zeros(p) if start is None else np.asarray(start, dtype=float)
    theta0 = np.concatenate([pacf0, [math.log(0.5 * sigma_n)] if free_e else []])
    lo = np.concatenate([np.full(p, -0.95), [math.log(1e-3 * sigma_n)] if free_e else []])
    hi = np.concatenate([np.full(p, 0.95), [math.log(1e2 * sigma_n)] if free_e else []])
    sol = least_squares(resid, theta0, bounds=(lo, hi), x_scale=1.0)
    phi, se = unpack(sol.x)
    cost = float(np.sqrt(np.mean(resid(sol.x, 0.0)[: 1 + target_r.size] ** 2)))
    return phi, se, cost


#: Orders, series lengths and printed resolution of the sigmas of the applications (paper
#: §3): GPS strips of ~130 registrations (mm), Shuttle strips of 120–800 points (400 taken),
#: 5 min of the aircraft at 10 Hz (both 1e-4 deg).
_APPLICATIONS = {
    "GPS": (5, 2, 130, 1e-3),
    "Shuttle INS": (6, 1, 400, 1e-4),
    "Aircraft INS": (2, 2, 3000, 1e-4),
}

#: A truth *matches* when its theoretical ``r(h)`` are within this of the printed values and
#: its ``sigma_x / sigma_n`` within this of the interval the printed (rounded) sigma_x and
#: sigma_n allow; the margin leaves room for the strip length the paper gives only roughly.
MATCH_TOLERANCE = 0.05


def printed_columns() -> list[dict[str, Any]]:
    """Every column the paper prints with its order, sigmas, ``sigma_x`` and ``r(h)``: GPS X,
    Y, Z for strips 3,4,5 and 1,6,7 (Tables 1, 3), Shuttle and aircraft yaw, pitch, roll
    (Tables 4, 5)."""
    out = []
    for label, tab in PAPER_TABLES.items():
        app = next(a for a in _APPLICATIONS if label.startswith(a))
        p, d, n, step = _APPLICATIONS[app]
        groups = [("", tab["sigma_n"], tab["sigma_x"])]
        if "sigma_n_167" in tab:
            groups = [(" strips 3,4,5", tab["sigma_n"], tab["sigma_x"])]
            groups.append((" strips 1,6,7", tab["sigma_n_167"], tab["sigma_x_167"]))
        for suffix, sig_n, sig_x in groups:
            for k, col in enumerate(tab["columns"]):
                out.append(
                    {
                        "table": app + suffix,
                        "column": col,
                        "order": [p, d],
                        "n": n,
                        "sigma_n": sig_n[k],
                        "sigma_e": tab["sigma_e"][k] if "sigma_e" in tab else None,
                        "ratio": sig_x[k] / sig_n[k],
                        # the ratios the rounded printed values allow
                        "ratio_range": [
                            (sig_x[k] - step / 2) / (sig_n[k] + step / 2),
                            (sig_x[k] + step / 2) / (sig_n[k] - step / 2),
                        ],
                        "r": list(tab["r"][k]),
                    }
                )
    return out


def printed_truths(
    columns: Sequence[dict[str, Any]] | None = None, n_starts: int = 6, seed: int = 5
) -> list[dict[str, Any]]:
    """A fitted truth for every printed column (:func:`printed_columns`), or the evidence that
    no stationary ARI(p,d) of the printed order matches it.

    Each column is fitted by :func:`fit_published` from the zero start and, when that does not
    match within :data:`MATCH_TOLERANCE`, from ``n_starts`` further random starts (partial
    autocorrelations uniform in ±0.9); the best is kept. The row carries the truth, its
    theoretical statistics, the largest deviation from the printed values (``sigma_x/sigma_n``
    measured from the interval its rounded printed values allow), the statistic it is largest
    for (``worst``) and ``matched``. ``columns``: a subset of :func:`printed_columns` (default
    all).
    """
    rng = np.random.default_rng(seed)
    rows = []
    for col in printed_columns() if columns is None else columns:
        p, d = col["order"]
        best = None
        for k in range(1 + n_starts):
            start = None if k == 0 else rng.uniform(-0.9, 0.9, p)
            phi, se, cost = fit_published(
                p, d, col["sigma_n"], col["sigma_e"], col["n"], col["ratio"], col["r"], start
            )
            ratio, r = filtered_statistics(phi, d, col["sigma_n"], se, col["n"], len(col["r"]))
            lo, hi = col["ratio_range"]
            devs = [max(lo - ratio, ratio - hi, 0.0), *np.abs(r - col["r"]).tolist()]
            worst = int(np.argmax(devs))
            dev = devs[worst]
            if best is None or dev < best["max_deviation"]:
                best = {
                    "phi": [float(v) for v in phi],
                    "sigma_e_truth": se,
                    "ratio_truth": ratio,
                    "r_truth": [float(v) for v in r],
                    "cost_hundredths": cost,
                    "max_deviation": dev,
                    "worst": "sigma_x/sigma_n" if worst == 0 else f"r({worst})",
                }
            if dev <= MATCH_TOLERANCE:
                break
        assert best is not None
        rows.append(col | best | {"matched": best["max_deviation"] <= MATCH_TOLERANCE})
    return rows
