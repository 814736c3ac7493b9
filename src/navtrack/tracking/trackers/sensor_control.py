"""Foveal sensor configuration: the single-target gain rule (1) and the SO, TO, WO rules (paper 4).

The foveal sensor measures ``z = arctan(c (X - d)) + v``; each scan the tracker chooses the
centre ``d`` and the gain ``c`` from the predicted estimates (Table 1 step 5):

* :func:`foveal_gain` — rule (1): ``d`` at the predicted position, ``c = P^a(R)``;
* :func:`so_gain` — SO: ``d`` midway between the two most widely separated targets, the gain
  from their spread;
* TO: centred on each target in turn; WO: on the target with the largest predicted position
  variance; both with rule (1) for that target (:func:`configure`).

:func:`expected_posterior_variance` and :func:`optimal_gain` compute, by quadrature, the gain
that minimises the expected posterior position variance of one scan — the numerical check the
rules are compared against (``docs/foveal.md``).

References
----------
.. [1] F. Xi, D. Morrell, "Tracking multiple closely spaced targets using an adaptive foveal
   sensor", ICASSP 2005, V-941..944, section IV, rule (1) and the SO gain.
.. [2] Y. Xue, D. Morrell, "Adaptive foveal sensor for target tracking", 36th Asilomar Conf.,
   2002 (the single-target rule (1) improves).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from navtrack._typing import ArrayLike, FloatArray, IntArray

__all__ = [
    "R_BRANCH",
    "SO_SPREAD_FACTORS",
    "ControlRule",
    "configure",
    "expected_posterior_variance",
    "foveal_gain",
    "gain_exponent",
    "optimal_gain",
    "so_gain",
]

ControlRule = Literal["so", "to", "wo"]
_RULES = ("so", "to", "wo")

#: Noise variance (rad²) where rule (1) switches branch; the two branches meet there
#: (``log10(0.0146)/8 - 0.4 = -0.629``).
R_BRANCH = 0.0146

#: Factor on ``sqrt(P_i) + sqrt(P_j)`` in the SO spread, for ``R >= R_BRANCH`` and below.
SO_SPREAD_FACTORS = (0.9, 1.65)

#: Coefficient of the squared SO spread (paper: 0.12).
SO_COEFFICIENT = 0.12


def _check_R(R: float) -> float:
    if not (np.isfinite(R) and R > 0):
        raise ValueError(f"R (foveal measurement-noise variance, rad²) must be > 0, got {R}")
    return float(R)


def gain_exponent(R: float) -> float:
    """Exponent ``a(R)`` of rule (1): ``log10(R)/8 - 0.4`` for ``R >= 0.0146``, else ``-0.630``.

    Notes
    -----
    The extraction reads ``c = P^((1/8 log10 R) - 0.4)`` for ``R >= 0.0146`` and ``P^(-0.630)``
    below. The two branches meet at ``R = 0.0146``, which supports ``(1/8)·log10(R)`` against the
    other grouping ``1/(8 log10 R)``; the quadrature check (``docs/foveal.md``,
    :func:`optimal_gain`) agrees: at ``R = 0.05`` the one-step optimum is ``c ∝ P^-1/2`` and rule
    (1) with ``a = -0.563`` lies within a few per cent of its expected posterior variance over the
    predicted variances the tracker meets.
    """
    R = _check_R(R)
    return math.log10(R) / 8.0 - 0.4 if R >= R_BRANCH else -0.630


def foveal_gain(P: ArrayLike, R: float) -> FloatArray:
    """Rule (1): gain ``c = P^a(R)`` (1/m) for predicted position variance ``P (...)`` (m²)."""
    P = np.asarray(P, dtype=float)
    if np.any(~(P > 0)):
        raise ValueError("predicted position variance P must be > 0")
    return np.asarray(P ** gain_exponent(R))


def so_gain(
    D: ArrayLike, P_i: ArrayLike, P_j: ArrayLike, R: float, exponent: float | None = None
) -> FloatArray:
    """SO gain from the spread of the two most widely separated targets ``i`` and ``j``.

    ``c = (0.12 S²)^a(R)`` with the spread ``S = D_ij + f (sqrt(P_i) + sqrt(P_j))``, ``f = 0.9``
    (``R >= 0.0146``) or ``1.65``: rule (1) with the predicted variance replaced by ``0.12 S²``.

    Parameters
    ----------
    D : (...) float
        Distance between the predicted positions of ``i`` and ``j``, m.
    P_i, P_j : (...) float
        Their predicted position variances, m².
    R : float
        Measurement-noise variance, rad².
    exponent : float or None
        The exponent; None takes ``a(R)`` of :func:`gain_exponent`.

    Notes
    -----
    The exponent is garbled in the extraction: "c = 0.12 (D_ij + 0.9(sqrt P_i + sqrt P_j))
    ... log10 R - 0.4". Reconstructed numerically, as rule (1) is checked: for two targets at
    ``±D/2`` from the centre with variance ``P`` each, the gain minimising their summed expected
    posterior variance (:func:`optimal_gain` with two offsets; D in 0.5..6 m, P in 0.05..1 m²,
    R = 0.05) fits ``c = 3.60 S^-1.145`` (rms 0.14 in ``ln c``). ``(0.12 S²)^a(R)`` is
    ``3.30 S^-1.125`` at R = 0.05 — the same law (rms 0.15 in ``ln c``) — whereas the literal
    ``0.12 S^e`` is 30 times too small for any exponent near ``2 a``. So the 0.12 multiplies the
    squared spread inside the power, and the exponent is rule (1)'s ``a(R)``.
    """
    R = _check_R(R)
    f = SO_SPREAD_FACTORS[0] if R >= R_BRANCH else SO_SPREAD_FACTORS[1]
    S = np.asarray(D, dtype=float) + f * (
        np.sqrt(np.asarray(P_i, dtype=float)) + np.sqrt(np.asarray(P_j, dtype=float))
    )
    a = gain_exponent(R) if exponent is None else float(exponent)
    return np.asarray((SO_COEFFICIENT * S * S) ** a)


def configure(
    rule: ControlRule,
    x_pred: ArrayLike,
    P_pred: ArrayLike,
    R: float,
    k: int,
    position_index: int = 0,
    so_exponent: float | None = None,
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Foveal centre and gain for the next scan (Table 1 step 5).

    Parameters
    ----------
    rule : {"so", "to", "wo"}
    x_pred : (B, T, n) float
        Predicted target states (:func:`navtrack.tracking.trackers.particle.predicted_estimates`).
    P_pred : (B, T, n, n) float
        Their covariances.
    R : float
        Measurement-noise variance, rad².
    k : int
        Scan number (1 for the first scan; TO centres on target ``(k - 1) mod T``).
    position_index : int
    so_exponent : float or None
        See :func:`so_gain`.

    Returns
    -------
    c : (B,) gain, 1/m
    d : (B,) centre, m
    target : (B,) int
        Target the fovea is centred on (``-1`` for SO).
    """
    if rule not in _RULES:
        raise ValueError(f"rule must be one of {_RULES}, got {rule!r}")
    X = np.asarray(x_pred, dtype=float)[..., position_index]  # (B, T)
    var = np.asarray(P_pred, dtype=float)[..., position_index, position_index]
    B, T = X.shape
    rows = np.arange(B)
    if rule == "so":
        i, j = np.argmin(X, axis=1), np.argmax(X, axis=1)
        c = so_gain(X[rows, j] - X[rows, i], var[rows, i], var[rows, j], R, so_exponent)
        return c, 0.5 * (X[rows, i] + X[rows, j]), np.full(B, -1, dtype=np.int64)
    if rule == "to":
        t = np.full(B, (k - 1) % T, dtype=np.int64)
    else:
        t = np.argmax(var, axis=1).astype(np.int64)
    return foveal_gain(var[rows, t], R), X[rows, t], t


def expected_posterior_variance(
    c: ArrayLike,
    P: float,
    R: float,
    offset: ArrayLike = 0.0,
    n_grid: int = 161,
) -> FloatArray:
    """Expected posterior variance of a target's position after one foveal scan, by quadrature.

    The target's position relative to the foveal centre is ``u ~ N(offset, P)``, the
    measurement ``z = arctan(c u) + v``, ``v ~ N(0, R)`` (detected, no clutter). Returns
    ``E_z[Var(u | z)]`` (m²) for each gain.

    Parameters
    ----------
    c : (G,) float
        Gains, 1/m.
    P : float
        Prior position variance, m².
    R : float
        Noise variance, rad².
    offset : float or (K,) float
        Prior mean relative to the centre, m; several offsets are summed over (SO: the targets
        at the two ends).
    n_grid : int
        Points of the position and measurement grids (``±7`` prior standard deviations and
        ``(-pi/2 - 6 sqrt(R), pi/2 + 6 sqrt(R))``).

    Returns
    -------
    (G,) float
    """
    R = _check_R(R)
    c = np.atleast_1d(np.asarray(c, dtype=float))
    offsets = np.atleast_1d(np.asarray(offset, dtype=float))
    s = np.linspace(-7.0, 7.0, n_grid)
    prior = np.exp(-0.5 * s * s)
    prior /= prior.sum()
    u = s * math.sqrt(P)  # position relative to the prior mean
    zg = np.linspace(-0.5 * np.pi - 6 * math.sqrt(R), 0.5 * np.pi + 6 * math.sqrt(R), n_grid)
    dz = zg[1] - zg[0]
    total = np.zeros(c.shape)
    for m in offsets:
        h = np.arctan(c[:, None] * (m + u[None, :]))  # (G, nu)
        lik = np.exp(-0.5 * (zg[None, :, None] - h[:, None, :]) ** 2 / R) / math.sqrt(
            2 * np.pi * R
        )  # (G, nz, nu)
        joint = lik * prior  # p(z, u) dz-density
        pz = joint.sum(axis=-1)
        mean = (joint * u).sum(axis=-1) / np.maximum(pz, 1e-300)
        second = (joint * u * u).sum(axis=-1) / np.maximum(pz, 1e-300)
        total += np.sum(pz * (second - mean * mean), axis=-1) * dz
    return total


def optimal_gain(P: float, R: float, offset: ArrayLike = 0.0) -> float:
    """Gain minimising :func:`expected_posterior_variance` (golden-section on ``log c``).

    Returns
    -------
    float
        The one-step optimal gain, 1/m.
    """
    from scipy.optimize import minimize_scalar

    scale = 1.0 / math.sqrt(P)
    grid = scale * np.logspace(-2, 2, 25)
    v = expected_posterior_variance(grid, P, R, offset)
    i = int(np.argmin(v))
    lo, hi = math.log(grid[max(i - 1, 0)]), math.log(grid[min(i + 1, len(grid) - 1)])
    res = minimize_scalar(
        lambda lc: float(expected_posterior_variance(math.exp(lc), P, R, offset)[0]),
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-4},
    )
    return float(math.exp(res.x))
