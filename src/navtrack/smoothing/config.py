"""Settings of the ARI estimation (paper 5): order selection, robust weighting, stopping rules."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from navtrack.estimation.robust import ROBUST_DEFAULTS, RobustName
from navtrack.smoothing.vce import VCE_FORMS, VceForm

__all__ = ["AriConfig"]


@dataclass(frozen=True, slots=True)
class AriConfig:
    """Settings of the ARI estimation.

    Parameters
    ----------
    order : (int, int) or None
        ``(p, d)``; ``None`` selects it by ``criterion`` over ``p = 0..max_p``,
        ``d = min_d..max_d`` (``p + d >= 1``).
    max_p, min_d, max_d : int
        Candidate orders for the selection. Defaults cover the paper's (5, 2), (6, 1), (2, 2).
    criterion : {"bic", "aic"}
        Information criterion of the order selection.
    robust : {"danish", "huber", "igg3", "off"}
        Weight function of the robust reweighting (applied to both equation groups unless
        ``robust_process`` is False).
    robust_c : tuple of float or None
        Tuning constants; ``None`` takes
        :data:`navtrack.estimation.robust.ROBUST_DEFAULTS`.
    robust_process : bool
        Reweight the process equations (3) too (the paper's treatment of edges and
        discontinuities). Off by default: an isolated gross error can be explained either by a
        down-weighted observation or by down-weighted process equations around it, and
        reweighting both groups let the estimate drift to ``sigma_n -> 0`` on short series in
        our tests (ARI(5,2), 130 epochs, 1 % gross errors), losing the detections.
    flag_threshold : float
        ``|T|`` above which an observation is flagged as a gross error. Default 3.29 is the
        two-sided 0.1 % normal quantile (Baarda's alpha_0 = 0.001).
    n_starts : int
        Starting points of the estimation (noise fractions spread over (0, 1)).
    tol : float
        Stopping rule of the VCE iteration: relative change of ``sigma_n`` and ``sigma_e``.
    gain_tol : float
        Stopping rule of the quasi-Newton search: predicted log-likelihood gain of the next
        step (default 1e-3: parameter changes far below their standard errors; the last digits
        of the likelihood along the weakly identified sigma_e/phi ridge cost many steps).
    max_iter : int
        Iteration limit of the VCE/AR fixed-point scheme (per start).
    max_robust_iter : int
        Limit of the reweighting loop.
    screen_n : int
        Starts are screened on the first ``screen_n`` epochs when the series is longer.
    stage_growth : int
        A series of ``n >= screen_n * stage_growth`` epochs is fitted on leading blocks of
        ``n / stage_growth^k`` epochs (those longer than ``screen_n``) and finally whole, each
        block started from the previous one's estimate and weights and searched by BFGS
        structured on the spectral information
        (:func:`navtrack.smoothing.exact.estimate_exact_likelihood`); shorter series go
        from the window to the whole series by BFGS. Default 16 (n = 1e6: a block of 62500
        epochs, then the whole series), set on the simulated 1e6-epoch benchmark series.
    boundary_margin : float
        An interior solution (both variances positive) is kept over a boundary one
        (``sigma_n`` or ``sigma_e`` at its lower bound) unless the boundary one has a larger
        log-likelihood by more than this (default 1.92 = half the 95 % point of chi-square(1)).
        The paper's model has observation noise by construction; a boundary optimum the data do
        not significantly prefer is the weak identifiability of short series (``sigma_n -> 0``
        is the failure statsmodels' SARIMAX shows), not evidence of noise-free data.
    initial : {"stationary", "conditional"}
        Start of the AR part. ``"stationary"``: the first ``p`` differences follow the AR's
        stationary distribution — the exact likelihood, the same as statsmodels' SARIMAX with
        ``measurement_error=True`` (``phi`` is then kept stationary). ``"conditional"``: the
        likelihood conditional on them (the plain Gauss–Markov model (2)–(3), any ``phi``).
    estimator : {"exact", "paper"}
        ``"exact"``: maximum of the exact (``initial``) likelihood by quasi-Newton search
        (:func:`navtrack.smoothing.exact.estimate_exact_likelihood`). ``"paper"``: the
        paper's conditional Gauss–Markov model and its alternating iteration of filtering,
        variance-component estimation and AR fit
        (:func:`navtrack.smoothing.alternation.estimate_alternating`; ``initial`` is then
        ``"conditional"`` whatever it says).
    vce : {"redundancy", "forstner"}
        Form of the paper's estimator's variance-component step
        (:mod:`navtrack.smoothing.vce`): redundancies ``r_k = n_k - tr(N^-1 N_k)`` exact from
        the band of ``N^-1`` (default), or Förstner's (1984) frequency-domain form, the paper's
        recommendation (§2.2). Only with ``estimator="paper"``: the exact estimator maximises
        the likelihood, whose variance equations are the exact-trace VCE.
    alternation_tol : float
        Stopping rule of the paper's alternating iteration: largest change of ``phi`` and of
        the relative sigmas per iteration (default 1e-4: the paper prints two to three digits;
        1e-6 cost 5–20x the iterations on the synthetic cases with the same likelihood to
        0.01). ``max_iter`` bounds it (status ``not_converged``).
    select_n : int
        The order is selected on the first ``select_n`` epochs when the series is longer (the
        chosen order is then fitted to the whole series).
    """

    order: tuple[int, int] | None = None
    max_p: int = 6
    min_d: int = 0
    max_d: int = 2
    criterion: Literal["bic", "aic"] = "bic"
    robust: RobustName = "danish"
    robust_c: tuple[float, ...] | None = None
    robust_process: bool = False
    flag_threshold: float = 3.29
    n_starts: int = 3
    tol: float = 1e-6
    gain_tol: float = 1e-3
    max_iter: int = 300
    max_robust_iter: int = 20
    screen_n: int = 4000
    stage_growth: int = 16
    select_n: int = 20000
    boundary_margin: float = 1.92
    initial: Literal["stationary", "conditional"] = "stationary"
    estimator: Literal["exact", "paper"] = "exact"
    alternation_tol: float = 1e-4
    vce: VceForm = "redundancy"

    def __post_init__(self) -> None:
        if self.order is not None:
            p, d = self.order
            if p < 0 or d < 0 or p + d < 1:
                raise ValueError(
                    f"order must be (p, d) with p, d >= 0 and p + d >= 1, got {self.order}"
                )
        if self.max_p < 0 or self.min_d < 0 or self.max_d < self.min_d:
            raise ValueError("need max_p >= 0 and 0 <= min_d <= max_d")
        if self.robust not in ROBUST_DEFAULTS:
            raise ValueError(
                f"robust must be one of {sorted(ROBUST_DEFAULTS)}, got {self.robust!r}"
            )
        if self.criterion not in ("bic", "aic"):
            raise ValueError(f"criterion must be 'bic' or 'aic', got {self.criterion!r}")
        if self.estimator not in ("exact", "paper"):
            raise ValueError(f"estimator must be 'exact' or 'paper', got {self.estimator!r}")
        if self.vce not in VCE_FORMS:
            raise ValueError(f"vce must be one of {VCE_FORMS}, got {self.vce!r}")
        if self.vce == "forstner" and self.estimator != "paper":
            raise ValueError(
                "vce='forstner' needs estimator='paper' (the exact estimator's variance "
                "equations are the likelihood's, with exact redundancies)"
            )
        if self.n_starts < 1 or self.max_iter < 1 or self.tol <= 0:
            raise ValueError("need n_starts >= 1, max_iter >= 1, tol > 0")
        if self.stage_growth < 2:
            raise ValueError(f"stage_growth must be >= 2, got {self.stage_growth}")

    @property
    def tuning(self) -> tuple[float, ...]:
        """The weight function's constants actually used."""
        return ROBUST_DEFAULTS[self.robust] if self.robust_c is None else self.robust_c
