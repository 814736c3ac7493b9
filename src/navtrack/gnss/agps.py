"""Two-satellite AGPS positioning with two receiver clock biases (method 1, Li 2010).

A phone that sees only two satellites, twice, a few minutes apart, is positioned with assistance
data from a server (ephemerides, ionosphere, the serving cell's position). Per fix, the unknowns
are ``X = (x, y, z, c dt1, c dt2)`` — ECEF position (m) and one receiver clock bias per epoch (m)
— and the five equations are (Li 2010, section III)::

    f_i = |X_S,i - R| + c dt_k(i) - P_i            i = 1..4 (2 satellites x 2 epochs)
    f_5 = (x^2 + y^2) / (a + h)^2 + z^2 / (b + h)^2 - 1

with ``P_i`` the pseudorange corrected for satellite clock, group delay, ionosphere and
troposphere, ``|.|`` the geometric range with the Sagnac term
(:func:`navtrack.gnss.corrections.geometric_range`), ``a, b`` the WGS-84 semi-axes and ``h`` the
assumed height. Each fix starts at the base-station (cell) position with zero clock biases.

Solvers (:func:`solve_agps`), all on the shared batched kernels of
:mod:`navtrack.estimation.least_squares`:

``gn``
    Gauss–Newton, the paper's eq. (7): :func:`~navtrack.estimation.least_squares.gauss_newton`
    with the paper's stopping rule ``||A^T f|| <= epsilon`` (``gtol``).
``lm``
    Marquardt, the paper's steps 1–6 with ``mu_1 = 0.1``, ``beta = 10``, ``epsilon = 0.1``:
    :func:`~navtrack.estimation.least_squares.marquardt`.
``map``
    Beyond the paper: maximum a posteriori with the cell position as a Gaussian prior of stated
    standard deviation (``AgpsConfig.prior_sigma_m``), pseudoranges and the height equation
    weighted by their standard deviations — Gauss–Newton on the five equations plus three
    pseudo-observations ``R - R_cell = 0``. The damping ``mu I`` of Marquardt acts like such a
    prior on the step; this is the principled form, with a variance one can state.

Per-fix outcome: :class:`AgpsStatus`; positions are NaN wherever no estimate exists, so that a
NaN is never reported as a fix.

References
----------
J.-z. Li, "Two satellites positioning algorithm based on AGPS system with two clock bias",
ICCET 2010, V2-416..419 (equations f1..f5, Marquardt steps 1–6, Tables I–III);
B. Chen, *Optimization theory and algorithms*, 2nd ed., Tsinghua Univ. Press 2005 (the paper's
ref. [8]: the Levenberg–Marquardt steps the paper follows);
NIMA TR8350.2 (WGS-84 semi-axes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray
from navtrack.estimation.least_squares import (
    LsqResult,
    LsqStatus,
    gauss_newton,
    marquardt,
    singular_normal_matrices,
)
from navtrack.geodesy import NEAR_SURFACE_NORM_M, WGS84_A_M, WGS84_F, ecef_to_geodetic
from navtrack.gnss.corrections import geometric_range

__all__ = [
    "HEIGHT_RANGE_M",
    "SOLVERS",
    "STATUS_NAMES",
    "XTOL_M",
    "AgpsConfig",
    "AgpsProblem",
    "AgpsResult",
    "AgpsStatus",
    "F5Units",
    "Solver",
    "ellipsoid_residual",
    "fix_dop",
    "solve_agps",
]

WGS84_B_M = WGS84_A_M * (1.0 - WGS84_F)

HEIGHT_RANGE_M = (-1000.0, 20000.0)
"""Accepted assumed heights (m above the ellipsoid): the lowest land (Dead Sea, about -430 m
ellipsoidal) to above airliner cruise; anything else is a wrong unit or a mistake."""

Solver = Literal["gn", "lm", "map"]
SOLVERS: tuple[Solver, ...] = ("gn", "lm", "map")


class AgpsStatus(IntEnum):
    """Per-fix outcome of :func:`solve_agps` (printed by lower-case name)."""

    OK = 0
    MISSING_MEASUREMENT = 1
    SINGULAR = 2
    NO_CONVERGENCE = 3
    DIVERGED = 4
    WEAK_GEOMETRY = 5
    IMPLAUSIBLE = 6


STATUS_NAMES = tuple(s.name.lower() for s in AgpsStatus)


F5Units = Literal["m", "dimensionless"]


@dataclass(frozen=True, slots=True)
class AgpsConfig:
    """Options of :func:`solve_agps`.

    Attributes
    ----------
    mu1 : float
        Initial Marquardt damping ``mu_1`` (paper: 0.1).
    beta : float
        Growth factor ``beta`` (paper: 10).
    eps : float
        Gradient tolerance ``epsilon`` on ``||A^T f||`` (paper: 0.1, units of ``A^T f``: m for
        the pseudorange rows), the stopping rule of both ``gn`` and ``lm``.
    max_iter : int
        Maximum linear solves per fix (the paper gives none).
    f5_units : {"m", "dimensionless"}
        Scale of the height equation in the objective ``F = sum f_i^2``. ``m`` (default):
        ``f_5`` times ``(a + h) / 2``, a height residual in metres weighing like a pseudorange.
        ``dimensionless``: ``f_5`` exactly as printed, which weighs about ``(2 / a)^2 ~ 1e-13``
        per m^2 against a pseudorange, so that Marquardt's damping, not the assumed height, fixes
        the weak direction and its fix does not depend on the height at all. The paper's
        Table II varies with the height, which only the ``m`` reading reproduces
        (``docs/agps.md``). Gauss–Newton's iterates on the square system do not depend on it;
        its gradient test and its conditioning use metres.
    prior_sigma_m : float
        ``map``: standard deviation (m, per ECEF axis) of the cell position as a prior of the
        phone's position: about the cell radius.
    sigma_pr_m : float
        Standard deviation (m) of a corrected pseudorange: the ``map`` weights and the predicted
        position error ``dop * sigma_pr_m`` that :attr:`max_sigma_m` bounds
        (:func:`pseudorange_sigma_m` estimates it from a receiver's file).
    sigma_height_m : float
        ``map``: standard deviation (m) of the assumed height.
    clock_start : {"zero", "cell"}
        Start of the clock biases: ``zero`` (the paper's step 1) or ``cell``, beyond the paper,
        the mean over the epoch's two satellites of ``P - |X_S - R_cell|`` (what a receiver
        knows before any iteration; it matters to Marquardt, whose damping also slows the
        clock steps, when the receiver clock is kilometres off).
    max_dop : float
        Geometry screen: a fix whose dilution of precision (:func:`fix_dop`, metres of position
        per metre of pseudorange noise, at the start) exceeds it is ``weak_geometry``. Infinite
        (the default) screens nothing.
    max_sigma_m : float
        Accuracy screen: a fix whose predicted 3-D error ``dop * sigma_pr_m`` (m, one sigma)
        exceeds it is ``weak_geometry``. Infinite (the default) screens nothing.
    max_height_residual_m : float
        A fix further than this from the assumed height (m) is ``implausible``: the height
        equation is one of the five, so a solution off it has not solved the system. Infinite
        turns the check off (the paper's statistics count every fix).
    max_residual_m : float
        A fix whose pseudorange residuals (root mean square, m) exceed this is ``implausible``:
        four pseudoranges and five unknowns close exactly at a solution, so residuals of many
        metres mean the iteration stopped short of it. Infinite turns the check off.
    """

    mu1: float = 0.1
    beta: float = 10.0
    eps: float = 0.1
    max_iter: int = 50
    f5_units: F5Units = "m"
    prior_sigma_m: float = 3000.0
    sigma_pr_m: float = 5.0
    sigma_height_m: float = 20.0
    clock_start: Literal["zero", "cell"] = "zero"
    max_dop: float = math.inf
    max_sigma_m: float = math.inf
    max_height_residual_m: float = 50.0
    max_residual_m: float = 50.0

    def __post_init__(self) -> None:
        for name in (
            "mu1",
            "eps",
            "prior_sigma_m",
            "sigma_pr_m",
            "sigma_height_m",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name}: expected a finite positive number, got {value}")
        for name in ("max_dop", "max_sigma_m", "max_height_residual_m", "max_residual_m"):
            value = getattr(self, name)
            if not value > 0.0:
                raise ValueError(f"{name}: expected a positive number or inf, got {value}")
        if not self.beta > 1.0:
            raise ValueError(f"beta: growth factor must be > 1, got {self.beta}")
        if self.clock_start not in ("zero", "cell"):
            raise ValueError(f"clock_start: expected 'zero' or 'cell', got {self.clock_start!r}")
        if self.f5_units not in ("m", "dimensionless"):
            raise ValueError(f"f5_units: expected 'm' or 'dimensionless', got {self.f5_units!r}")
        if self.max_iter < 1:
            raise ValueError(f"max_iter: expected >= 1, got {self.max_iter}")

    @classmethod
    def for_receiver(
        cls, sigma_pr_m: float, max_sigma_m: float = 300.0, **options: Any
    ) -> AgpsConfig:
        """The screens of ``navtrack agps`` for a receiver of pseudorange noise ``sigma_pr_m``
        (:func:`pseudorange_sigma_m`): ``ok`` only for a predicted 3-D error
        ``dop * sigma_pr_m`` of at most ``max_sigma_m`` (300 m: a kilometre is over three
        sigma) and residuals closing to ``3 sigma_pr_m``."""
        return cls(
            sigma_pr_m=sigma_pr_m,
            max_sigma_m=max_sigma_m,
            max_residual_m=3.0 * sigma_pr_m,
            **options,
        )


@dataclass(frozen=True, slots=True, eq=False)
class AgpsProblem:
    """A batch of two-satellite, two-epoch fixes.

    Row order of the measurement axis: (epoch 1, satellite 1), (epoch 1, satellite 2),
    (epoch 2, satellite 1), (epoch 2, satellite 2).

    Attributes
    ----------
    t_gps_s : ndarray, shape (B, 2)
        Reception times of the two epochs (GPS s).
    sat_pos_m : ndarray, shape (B, 4, 3)
        Satellite ECEF positions at transmission (m), earth-fixed frame of transmission.
    y_m : ndarray, shape (B, 4)
        Pseudoranges corrected for satellite clock, group delay, ionosphere and troposphere (m).
    height_m : ndarray, shape (B,)
        Assumed ellipsoidal height ``h`` (m).
    start_xyz_m : ndarray, shape (B, 3)
        Start position: the base-station (cell) position (ECEF, m); also the ``map`` prior.
    usable : ndarray of bool, shape (B, 4)
        Measurement present with a satellite state; a fix with a missing one is not solved
        (status ``missing_measurement``).

    Raises
    ------
    ValueError
        Shapes disagree, a fix uses the same epoch twice, a height outside
        :data:`HEIGHT_RANGE_M`, a non-finite start.
    """

    t_gps_s: FloatArray
    sat_pos_m: FloatArray
    y_m: FloatArray
    height_m: FloatArray
    start_xyz_m: FloatArray
    usable: BoolArray

    def __post_init__(self) -> None:
        for name in ("t_gps_s", "sat_pos_m", "y_m", "height_m", "start_xyz_m"):
            object.__setattr__(self, name, np.array(getattr(self, name), dtype=float))
        b = self.y_m.shape[0] if self.y_m.ndim == 2 else -1
        shapes = {
            "t_gps_s": (b, 2),
            "sat_pos_m": (b, 4, 3),
            "y_m": (b, 4),
            "height_m": (b,),
            "start_xyz_m": (b, 3),
            "usable": (b, 4),
        }
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name))
            if value.shape != shape:
                raise ValueError(f"{name}: expected shape {shape} (B = fixes), got {value.shape}")
        t = np.asarray(self.t_gps_s, dtype=float)
        same = np.flatnonzero(~(np.abs(t[:, 1] - t[:, 0]) > 0.0))
        if same.size:
            raise ValueError(
                f"t_gps_s: fix {same[0]} uses the same epoch twice ({t[same[0], 0]} s); the two "
                "measurements must be at different times"
            )
        h = np.asarray(self.height_m, dtype=float)
        lo, hi = HEIGHT_RANGE_M
        bad = np.flatnonzero(~((h >= lo) & (h <= hi)))
        if bad.size:
            raise ValueError(
                f"height_m: assumed height {h[bad[0]]} m of fix {bad[0]} is outside the earth's "
                f"range {lo:g}..{hi:g} m (ellipsoidal height in metres)"
            )
        if not np.isfinite(np.asarray(self.start_xyz_m, dtype=float)).all():
            raise ValueError("start_xyz_m: expected finite ECEF start positions (m)")
        usable = np.asarray(self.usable, dtype=bool) & np.isfinite(self.y_m)
        usable &= np.isfinite(self.sat_pos_m).all(axis=-1)
        object.__setattr__(self, "usable", usable)
        freeze_arrays(self)

    @property
    def size(self) -> int:
        """Number of fixes ``B``."""
        return int(self.y_m.shape[0])


@dataclass(frozen=True, slots=True, eq=False)
class AgpsResult:
    """Fixes of :func:`solve_agps`.

    Attributes
    ----------
    solver : str
        ``gn``, ``lm`` or ``map``.
    pos_m : ndarray, shape (B, 3)
        ECEF position (m): the solution for ``ok``, ``weak_geometry`` and ``implausible`` (to
        show what was rejected), the last iterate for ``no_convergence``, NaN for the other
        statuses.
    clock_m : ndarray, shape (B, 2)
        ``c dt1, c dt2`` (m), NaN where ``pos_m`` is.
    iterations : ndarray of int, shape (B,)
        Linear solves: the ``k`` of the paper's steps when they stop (Gauss–Newton steps;
        Marquardt trial steps, accepted or not), the last one taken from an iterate whose
        gradient already met ``epsilon``.
    accepted : ndarray of int, shape (B,)
        Steps that moved the estimate (Gauss–Newton: all; Marquardt: the accepted trials).
    status : ndarray of int8, shape (B,)
        :class:`AgpsStatus`.
    cost : ndarray, shape (B,)
        Objective at the estimate (the solver's weighting).
    height_residual_m : ndarray, shape (B,)
        Ellipsoidal height of the estimate minus the assumed height (m).
    residual_m : ndarray, shape (B,)
        Root mean square of the four pseudorange residuals at the estimate (m).
    dop : ndarray, shape (B,)
        Dilution of precision of the fix at the start (:func:`fix_dop`).
    sigma_m : ndarray, shape (B,)
        Predicted 3-D error (m, one sigma): ``dop * sigma_pr_m``.
    reason : ndarray of str, shape (B,)
        Why a fix is ``weak_geometry`` or ``implausible`` (empty for the other statuses).
    """

    solver: str
    pos_m: FloatArray
    clock_m: FloatArray
    iterations: IntArray
    accepted: IntArray
    status: np.ndarray
    cost: FloatArray
    height_residual_m: FloatArray
    residual_m: FloatArray
    dop: FloatArray
    sigma_m: FloatArray
    reason: np.ndarray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def ok(self) -> BoolArray:
        return np.asarray(self.status == AgpsStatus.OK)

    def status_counts(self) -> dict[str, int]:
        """Number of fixes per status name (all statuses, zeros included)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(AgpsStatus))
        return {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}


def ellipsoid_residual(xyz_m: ArrayLike, height_m: ArrayLike) -> FloatArray:
    """The paper's height equation ``f_5 = (x^2 + y^2)/(a + h)^2 + z^2/(b + h)^2 - 1``.

    Parameters
    ----------
    xyz_m : array-like, shape (..., 3)
        ECEF position (m).
    height_m : array-like, shape (...)
        Assumed height ``h`` (m).

    Returns
    -------
    ndarray, shape (...)
        Dimensionless; about ``2 dh / a`` for a point ``dh`` above the surface.

    Notes
    -----
    The surface ``f_5 = 0`` has semi-axes ``a + h`` and ``b + h``; it is not the surface of
    geodetic height ``h`` but departs from it by less than ``h e^2`` (0.4 m at 56 m).
    """
    xyz = np.asarray(xyz_m, dtype=float)
    h = np.asarray(height_m, dtype=float)
    ah, bh = WGS84_A_M + h, WGS84_B_M + h
    return np.asarray((xyz[..., 0] ** 2 + xyz[..., 1] ** 2) / ah**2 + xyz[..., 2] ** 2 / bh**2 - 1)


@dataclass(frozen=True, slots=True, eq=False)
class _AgpsModel:
    """The five (``map``: eight) equations of a batch of fixes as a
    :data:`navtrack.estimation.least_squares.ModelFn`: ``v = y - h(X)``, ``J = dh/dX``.

    Rows 0..3 pseudoranges (weight ``w_pr``), row 4 the height equation times ``scale``
    (weight ``w_h``), rows 5..7 (``prior``) the pseudo-observations ``R = R_cell``.
    """

    problem: AgpsProblem
    scale: FloatArray  # (B,) factor on f5
    w_pr: float
    w_h: float
    w_prior: float | None

    def __call__(
        self, x: FloatArray, idx: IntArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        p = self.problem
        rcv = x[:, :3]
        rho, los = geometric_range(p.sat_pos_m[idx], rcv[:, None, :])
        n_rows = 5 if self.w_prior is None else 8
        b = idx.size
        v = np.zeros((b, n_rows))
        J = np.zeros((b, n_rows, 5))
        w = np.zeros((b, n_rows))
        valid = np.ones((b, n_rows), dtype=bool)
        usable = p.usable[idx]
        clock = np.stack([x[:, 3], x[:, 3], x[:, 4], x[:, 4]], axis=1)
        v[:, :4] = np.where(usable, p.y_m[idx] - rho - clock, 0.0)
        J[:, :4, :3] = np.where(usable[..., None], -los, 0.0)
        J[:, 0:2, 3] = 1.0
        J[:, 2:4, 4] = 1.0
        w[:, :4] = self.w_pr
        valid[:, :4] = usable
        h = p.height_m[idx]
        s = self.scale[idx]
        ah2, bh2 = (WGS84_A_M + h) ** 2, (WGS84_B_M + h) ** 2
        v[:, 4] = -s * ellipsoid_residual(rcv, h)
        J[:, 4, 0] = s * 2.0 * rcv[:, 0] / ah2
        J[:, 4, 1] = s * 2.0 * rcv[:, 1] / ah2
        J[:, 4, 2] = s * 2.0 * rcv[:, 2] / bh2
        w[:, 4] = self.w_h
        if self.w_prior is not None:
            v[:, 5:8] = p.start_xyz_m[idx] - rcv
            J[:, 5:8, :3] = np.eye(3)
            w[:, 5:8] = self.w_prior
        return v, J, w, valid


XTOL_M = 1e-4
"""Safeguard of ``gn`` and ``map`` beyond the paper: a step shorter than this (m, RTKLIB's
``estpos`` threshold) also ends the iteration, where rounding keeps ``||A^T f||`` above a tiny
``epsilon``."""


def _start_jacobian(problem: AgpsProblem, x0: FloatArray) -> tuple[FloatArray, BoolArray]:
    """The five equations' Jacobian at the start (height equation in metres, (B, 5, 5)) and the
    fixes with all of them valid."""
    metric = (WGS84_A_M + problem.height_m) / 2.0
    model = _AgpsModel(problem, metric, 1.0, 1.0, None)
    _, J, _, valid = model(x0, np.arange(problem.size))
    return np.where(valid[..., None], J, 0.0), np.asarray(valid.all(axis=1))


def _singular_start(J: FloatArray, complete: BoolArray) -> BoolArray:
    """Fixes whose five equations are singular at the start — the same satellite twice, a start
    at the earth's centre, two epochs of the same geometry — by the singularity test of the
    Gauss–Newton kernel (``rcond = 1e-12`` on the scaled normal matrix)."""
    return np.asarray(singular_normal_matrices(np.einsum("bmp,bmq->bpq", J, J), 1e-12) & complete)


def fix_dop(problem: AgpsProblem) -> FloatArray:
    """Dilution of precision of each fix at its start (the cell, the clocks at zero).

    The four pseudoranges and the height equation make a square system ``A dX = df``; the
    position error caused by independent pseudorange errors of unit variance has the covariance
    ``B B^T`` with ``B`` the position rows and pseudorange columns of ``A^-1``. The DOP is
    ``sqrt(trace(B B^T))``: metres of 3-D position error (root mean square) per metre of
    pseudorange noise. Two satellites seen twice a few minutes apart give hundreds.

    Parameters
    ----------
    problem : AgpsProblem

    Returns
    -------
    ndarray, shape (B,)
        Infinite where the system is singular or a measurement is missing.
    """
    x0 = np.zeros((problem.size, 5))
    x0[:, :3] = problem.start_xyz_m
    J, complete = _start_jacobian(problem, x0)
    return _dop(J, complete & ~_singular_start(J, complete))


def _dop(J: FloatArray, good: BoolArray) -> FloatArray:
    """:func:`fix_dop` of the start Jacobians ``J`` (B, 5, 5), infinite where not ``good``."""
    dop = np.full(J.shape[0], np.inf)
    if good.any():
        # h(X) has Jacobian J; the residual rows f = h - y have the same, and the height row
        # carries no noise: only the pseudorange columns of the inverse enter.
        B = np.linalg.inv(J[good])[:, :3, :4]
        dop[good] = np.sqrt(np.einsum("bij,bij->b", B, B))
    return dop


def solve_agps(
    problem: AgpsProblem, solver: Solver = "lm", config: AgpsConfig | None = None
) -> AgpsResult:
    """Solve a batch of two-satellite fixes in one vectorised call.

    Parameters
    ----------
    problem : AgpsProblem
    solver : {"gn", "lm", "map"}
        Gauss–Newton, Marquardt (paper), or maximum a posteriori with the cell prior.
    config : AgpsConfig, optional

    Returns
    -------
    AgpsResult

    Notes
    -----
    Readings of the paper (its text lost the symbols of steps 2, 5 and 6; filled from its
    ref. [8], Chen 2005): step 2 sets ``mu_k <- mu_k / beta`` before each linear solve of a new
    iterate, step 5 ``mu_k <- beta mu_k`` after a rejected trial; step 5 stops at ``X_k``,
    step 6 at ``X_{k+1}``, both when ``||A_k^T f_k|| <= epsilon``. The first trial step
    therefore uses ``mu_1 / beta``; :func:`~navtrack.estimation.least_squares.marquardt`
    (which divides after an accepted step) runs with ``mu0 = mu_1 / beta``. Gauss–Newton is
    eq. (7) with the same stopping rule. Iterations count linear solves (the paper's measure of
    computation).
    A fix ends ``diverged`` when its estimate is not finite or not within
    :data:`navtrack.geodesy.NEAR_SURFACE_NORM_M` of the earth's centre, ``weak_geometry`` when
    its DOP exceeds ``max_dop`` or its predicted error ``max_sigma_m``, ``implausible`` when it
    lies off the assumed height or its pseudoranges do not close (``max_height_residual_m``,
    ``max_residual_m``), with the reason in :attr:`AgpsResult.reason`.
    """
    cfg = config or AgpsConfig()
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {', '.join(SOLVERS)}, got {solver!r}")
    p = problem
    x0 = _start_state(p, cfg)
    lsq = _iterate(p, solver, cfg, x0)
    J0, complete = _start_jacobian(p, x0)
    singular = _singular_start(J0, complete)
    status = _solver_status(p, solver, lsq, singular)
    keep = (status == AgpsStatus.OK) | (status == AgpsStatus.NO_CONVERGENCE)
    x = lsq.x
    pos = np.where(keep[:, None], x[:, :3], np.nan)  # weak or implausible fixes keep theirs
    height = np.full(p.size, np.nan)
    if keep.any():
        height[keep] = ecef_to_geodetic(pos[keep])[:, 2] - p.height_m[keep]
    with np.errstate(invalid="ignore"):
        residual = np.sqrt(np.nanmean(lsq.residuals[:, :4] ** 2, axis=1))
    residual = np.where(keep, residual, np.nan)
    dop = _dop(J0, complete & ~singular)
    sigma = dop * cfg.sigma_pr_m
    reason = _screen(status, dop, sigma, height, residual, cfg)
    return AgpsResult(
        solver=solver,
        pos_m=pos,
        clock_m=np.where(keep[:, None], x[:, 3:5], np.nan),
        iterations=lsq.iterations,
        accepted=lsq.accepted,
        status=status,
        cost=np.where(keep, lsq.cost, np.nan),
        height_residual_m=height,
        residual_m=residual,
        dop=dop,
        sigma_m=sigma,
        reason=reason,
    )


def _start_state(p: AgpsProblem, cfg: AgpsConfig) -> FloatArray:
    """Start of every fix: the cell position, clock biases zero or (``clock_start="cell"``) the
    mean pseudorange offset at the cell of each epoch."""
    x0 = np.zeros((p.size, 5))
    x0[:, :3] = p.start_xyz_m
    if cfg.clock_start == "cell":
        rho, _ = geometric_range(p.sat_pos_m, p.start_xyz_m[:, None, :])
        offset = np.where(p.usable, p.y_m - rho, 0.0)
        x0[:, 3] = 0.5 * (offset[:, 0] + offset[:, 1])
        x0[:, 4] = 0.5 * (offset[:, 2] + offset[:, 3])
    return x0


def _iterate(p: AgpsProblem, solver: Solver, cfg: AgpsConfig, x0: FloatArray) -> LsqResult:
    """The iterations of ``solver`` from ``x0`` (the batched kernels)."""
    metric = (WGS84_A_M + p.height_m) / 2.0  # f5 in metres of height
    if solver == "gn":
        model = _AgpsModel(p, metric, 1.0, 1.0, None)
        return gauss_newton(model, x0, max_iter=cfg.max_iter, xtol=XTOL_M, gtol=cfg.eps)
    if solver == "lm":
        scale = metric if cfg.f5_units == "m" else np.ones(p.size)
        model = _AgpsModel(p, scale, 1.0, 1.0, None)
        # The damped matrix is regular; the undamped one of the paper's dimensionless f5 has
        # eigenvalues near 1e-13 of its largest: only rank deficiency to rounding is singular.
        return marquardt(
            model,
            x0,
            mu0=cfg.mu1 / cfg.beta,
            beta=cfg.beta,
            eps=cfg.eps,
            max_iter=cfg.max_iter,
            rcond=1e-15,
        )
    model = _AgpsModel(
        p,
        metric,
        cfg.sigma_pr_m**-2,
        cfg.sigma_height_m**-2,
        cfg.prior_sigma_m**-2,
    )
    grad_tol = cfg.eps * cfg.sigma_pr_m**-2  # epsilon in metres of pseudorange
    return gauss_newton(model, x0, max_iter=cfg.max_iter, xtol=XTOL_M, gtol=grad_tol)


def _solver_status(
    p: AgpsProblem, solver: Solver, lsq: LsqResult, singular: BoolArray
) -> np.ndarray:
    """:class:`AgpsStatus` from the iterations: no convergence, singular, diverged (not finite
    or off the earth's surface), missing measurement; ``ok`` otherwise."""
    status = np.full(p.size, AgpsStatus.OK, dtype=np.int8)
    status[lsq.status == LsqStatus.NO_CONVERGENCE] = AgpsStatus.NO_CONVERGENCE
    if solver != "lm":  # Marquardt's damped steps exist; its final covariance is not used
        status[lsq.status == LsqStatus.SINGULAR] = AgpsStatus.SINGULAR
    status[singular] = AgpsStatus.SINGULAR
    x = lsq.x
    finite = np.asarray(np.isfinite(x).all(axis=1))
    norm = np.linalg.norm(np.where(finite[:, None], x[:, :3], 0.0), axis=1)
    lo, hi = NEAR_SURFACE_NORM_M
    off = ~finite | (norm < lo) | (norm > hi)
    status[off & (status != AgpsStatus.SINGULAR)] = AgpsStatus.DIVERGED
    status[~p.usable.all(axis=1)] = AgpsStatus.MISSING_MEASUREMENT
    return status


def _screen(
    status: np.ndarray,
    dop: FloatArray,
    sigma: FloatArray,
    height: FloatArray,
    residual: FloatArray,
    cfg: AgpsConfig,
) -> np.ndarray:
    """Turn ``ok`` fixes of weak geometry (DOP or predicted error) or implausible (off the
    assumed height, residuals that do not close) into those statuses, in place; the reason of
    each."""
    reason = np.full(status.size, "", dtype=object)
    weak = (status == AgpsStatus.OK) & ((dop > cfg.max_dop) | (sigma > cfg.max_sigma_m))
    off_height = ~(np.abs(height) <= cfg.max_height_residual_m)
    open_residuals = ~(residual <= cfg.max_residual_m)
    implausible = (status == AgpsStatus.OK) & ~weak & (off_height | open_residuals)
    for i in np.flatnonzero(weak):
        reason[i] = (
            f"dop {dop[i]:.0f} above {cfg.max_dop:g}"
            if dop[i] > cfg.max_dop
            else f"predicted error {sigma[i]:.0f} m (dop {dop[i]:.0f} x {cfg.sigma_pr_m:.2g} m) "
            f"above {cfg.max_sigma_m:g} m"
        )
    for i in np.flatnonzero(implausible):
        why = [f"{height[i]:+.0f} m from the assumed height"] if off_height[i] else []
        if open_residuals[i]:
            why.append(f"pseudorange residuals {residual[i]:.0f} m rms")
        reason[i] = "; ".join(why)
    status[weak] = AgpsStatus.WEAK_GEOMETRY
    status[implausible] = AgpsStatus.IMPLAUSIBLE
    return reason
