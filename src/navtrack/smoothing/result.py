"""Result of an ARI fit and its status codes (paper 5)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import BoolArray, FloatArray, Int8Array

__all__ = ["AriEpochStatus", "AriResult", "AriStatus", "bad_result"]


class AriStatus(IntEnum):
    """Outcome of one series fit (:attr:`AriResult.status`); prints as its lower-case name."""

    OK = 0
    NOT_CONVERGED = 1
    #: a variance component reached its lower bound (not identifiable from the data)
    BOUNDARY = 2
    TOO_SHORT = 3
    CONSTANT = 4
    NON_MONOTONIC_TIME = 5
    IRREGULAR_TIME = 6
    SINGULAR = 7

    def __str__(self) -> str:
        return self.name.lower()

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


class AriEpochStatus(IntEnum):
    """Per-epoch code of :attr:`AriResult.epoch_status` (stored as int8)."""

    OK = 0
    MISSING = 1
    GROSS_ERROR = 2
    NOT_ESTIMATED = 3

    def __str__(self) -> str:
        return self.name.lower()

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


@dataclass(frozen=True, slots=True, eq=False)
class AriResult:
    """Filtered series and stochastic model of one ARI fit.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Filtered series (input units); NaN when ``status`` is a bad-input status.
    sigma_x : ndarray, shape (n,)
        Standard deviation of each filtered value, ``sqrt(diag N^-1)``.
    y : ndarray, shape (n,)
        The input series (NaN = missing).
    weight : ndarray, shape (n,)
        Final robust weight of each observation (0 where missing).
    process_weight : ndarray, shape (n - p - d,)
        Final robust weight of each process equation (3), equation ``s`` ending at epoch
        ``s + p + d``.
    test_statistic : ndarray, shape (n,)
        Studentized deletion residual ``T`` of each observation (NaN where missing).
    gross_error : ndarray of bool, shape (n,)
        ``|T| > flag_threshold``.
    epoch_status : ndarray of int8, shape (n,)
        :class:`AriEpochStatus` code per epoch.
    p, d : int
        ARI order.
    phi : ndarray, shape (p,)
        AR coefficients of the ``d``-th differences, paper sign (``u_t + sum phi_i u_{t-i} = e_t``).
    a : ndarray, shape (p + d,)
        Combined process parameters ``a_1..a_{p+d}`` of eq. (3).
    sigma_n, sigma_e : float
        Observation noise and ARI prediction-error standard deviations (input units).
    sigma_x_rms : float
        RMS of ``sigma_x`` over the observed epochs (the paper's one value per series).
    autocorr : ndarray, shape (4,)
        ``r(1..4)``: correlation of the filtered values ``h`` epochs apart, mean over epochs.
    loglike : float
        Log-likelihood (diffuse, see module notes) at the estimate, with the final weights.
    aic, bic : float
        Information criteria of the conditional likelihood used for the order selection
        (NaN when the order was given).
    redundancy_n, redundancy_e : float
        Redundancy of the observation and process groups at convergence.
    n_iter : int
        Fixed-point iterations of the last estimation (all starts and reweightings).
    status : AriStatus
        Outcome of the fit; ``ok``, ``not_converged`` and ``boundary`` carry estimates
        (:attr:`estimated`), the others are bad-input statuses with NaN estimates.
    message : str
        Human-readable detail of ``status``.
    """

    x: FloatArray
    sigma_x: FloatArray
    y: FloatArray
    weight: FloatArray
    process_weight: FloatArray
    test_statistic: FloatArray
    gross_error: BoolArray
    epoch_status: Int8Array
    p: int
    d: int
    phi: FloatArray
    a: FloatArray
    sigma_n: float
    sigma_e: float
    sigma_x_rms: float
    autocorr: FloatArray
    loglike: float
    aic: float
    bic: float
    redundancy_n: float
    redundancy_e: float
    n_iter: int
    status: AriStatus
    message: str = ""
    candidates: tuple[tuple[int, int, float], ...] = field(default=())

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def n_flagged(self) -> int:
        """Number of observations flagged as gross errors."""
        return int(np.count_nonzero(self.gross_error))

    @property
    def n_missing(self) -> int:
        """Number of missing epochs (NaN input)."""
        return int(np.count_nonzero(self.epoch_status == AriEpochStatus.MISSING))

    @property
    def estimated(self) -> bool:
        """The fit produced estimates (status ``ok``, ``not_converged`` or ``boundary``)."""
        return self.status in (AriStatus.OK, AriStatus.NOT_CONVERGED, AriStatus.BOUNDARY)

    def summary(self) -> dict[str, object]:
        """Key figures as plain Python values (for JSON and the CLI)."""
        return {
            "status": str(self.status),
            "order": [self.p, self.d],
            "sigma_n": self.sigma_n,
            "sigma_e": self.sigma_e,
            "sigma_x": self.sigma_x_rms,
            "r": [float(v) for v in self.autocorr],
            "phi": [float(v) for v in self.phi],
            "n": int(self.x.size),
            "n_missing": self.n_missing,
            "n_flagged": self.n_flagged,
            "loglike": self.loglike,
            "message": self.message,
        }


def bad_result(y: FloatArray, status: AriStatus, message: str, p: int = 0, d: int = 0) -> AriResult:
    """The result of a series that could not be fitted: NaN estimates, ``status``, ``message``.

    Parameters
    ----------
    y : ndarray, shape (n,)
        The input series (NaN = missing).
    status : AriStatus
        A status without estimates.
    message : str
        Why.
    p, d : int
        The order that was tried (0, 0 when none).
    """
    n = y.size
    nan = np.full(n, np.nan)
    m = p + d
    return AriResult(
        x=nan.copy(),
        sigma_x=nan.copy(),
        y=y.copy(),
        weight=np.zeros(n),
        process_weight=np.zeros(max(n - m, 0)),
        test_statistic=nan.copy(),
        gross_error=np.zeros(n, dtype=bool),
        epoch_status=np.where(
            np.isfinite(y), AriEpochStatus.NOT_ESTIMATED, AriEpochStatus.MISSING
        ).astype(np.int8),
        p=p,
        d=d,
        phi=np.full(p, np.nan),
        a=np.full(m, np.nan),
        sigma_n=math.nan,
        sigma_e=math.nan,
        sigma_x_rms=math.nan,
        autocorr=np.full(4, np.nan),
        loglike=math.nan,
        aic=math.nan,
        bic=math.nan,
        redundancy_n=math.nan,
        redundancy_e=math.nan,
        n_iter=0,
        status=status,
        message=message,
    )
