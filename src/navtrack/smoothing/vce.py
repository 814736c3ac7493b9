"""Variance-component estimation of the ARI model in the frequency domain (Förstner 1984).

Paper 5 (§2.2) recommends "the formulation in the frequency domain published by Förstner
(1984)" for the variance components ``sigma_n^2`` (observation noise, eq. (2)) and
``sigma_e^2`` (prediction errors, eq. (3)). Both the time-domain and the frequency-domain forms
iterate ``sigma_k^2 <- Omega_k / r_k`` (``Omega_k`` the weighted square sum of the residuals of
group ``k``); they differ in the redundancies ``r_k``:

* time domain (Förstner 1979, the default ``vce="redundancy"``):
  ``r_k = n_k - tr(N^-1 N_k)``, exact traces from the band of ``N^-1``;
* frequency domain (``vce="forstner"``, :func:`spectral_redundancies`): for a long stationary
  series the normal matrix of (2)–(3) is Toeplitz, diagonalised by the Fourier transform, and
  the traces become integrals over frequency of the two groups' spectral shares.

With ``c(z) = phi(z) (1 - z)^d`` the ARI polynomial
(:func:`~navtrack.smoothing.model.ari_polynomial`) and ``q(w) = sigma_n^2 |c(e^{iw})|^2 /
sigma_e^2`` the observation noise over the prediction-error spectrum, the normal matrix per
frequency is ``1/sigma_n^2 + |c|^2/sigma_e^2`` and

    r_n / R = (1/pi) int_0^pi q / (1 + q) dw,     r_e / R = (1/pi) int_0^pi 1 / (1 + q) dw,

which add up to one: the total redundancy ``R`` is split between the groups in proportion to
where each dominates the spectrum (observation noise at high frequencies, the process at low).

Notes
-----
Reading (the paper is silent on it, Förstner's report was not available): the residuals and
their square sums ``Omega_k`` come from the time-domain solution (equal to the frequency-domain
ones by Parseval for a stationary series, and exact with gaps and robust weights); only the
redundancies are the frequency-domain approximation. ``R`` is the total redundancy of the
finite model (observed epochs plus process equations minus unknowns), so that the two
redundancies add up to it exactly as the time-domain ones do; the spectral shares are those of
unit weights (robust weights enter ``Omega_k`` only). The integral is the midpoint rule on
``n_freq`` frequencies (the integrand is smooth: a rational function of ``cos w``).

References
----------
W. Förstner, "Determination of the additive noise variance of observed autoregressive
processes using variance component estimation technique", Schriftenreihe Heft 10, Institut
für Photogrammetrie, Universität Stuttgart, 1984 (cited by paper 5, §2.2).
W. Förstner, "Ein Verfahren zur Schätzung von Varianz- und Kovarianzkomponenten",
Allgemeine Vermessungs-Nachrichten 86, 446–453, 1979 (the time-domain redundancies).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from navtrack._typing import ArrayLike, FloatArray
from navtrack.smoothing.model import ari_polynomial

__all__ = ["VCE_FORMS", "VceForm", "spectral_redundancies", "spectral_shares"]

VceForm = Literal["redundancy", "forstner"]
#: The forms of the variance-component estimation (``AriConfig.vce``).
VCE_FORMS: tuple[str, ...] = ("redundancy", "forstner")


def spectral_shares(
    phi: ArrayLike, d: int, sigma_n2: float, sigma_e2: float, n_freq: int = 512
) -> tuple[float, float]:
    """Shares ``(r_n / R, r_e / R)`` of the observation and process groups in the total
    redundancy ``R`` of an infinitely long stationary ARI(p,d) series (they add up to one).

    Parameters
    ----------
    phi : array_like, shape (p,)
        AR coefficients (paper sign).
    d : int
        Number of differences.
    sigma_n2, sigma_e2 : float
        Variances of the observation noise and of the prediction errors (> 0).
    n_freq : int
        Frequencies of the midpoint rule on ``(0, pi)``.
    """
    if not (sigma_n2 > 0.0 and sigma_e2 > 0.0):
        raise ValueError(f"sigma_n2, sigma_e2: expected > 0, got {sigma_n2}, {sigma_e2}")
    if n_freq < 1:
        raise ValueError(f"n_freq: expected >= 1, got {n_freq}")
    c = ari_polynomial(phi, d)
    omega = (np.arange(n_freq) + 0.5) * (np.pi / n_freq)
    transfer = np.exp(-1j * np.outer(omega, np.arange(c.size))) @ c
    q = (sigma_n2 / sigma_e2) * np.abs(transfer) ** 2
    share_e = float(np.mean(1.0 / (1.0 + q)))
    return 1.0 - share_e, share_e


def spectral_redundancies(
    phi: FloatArray,
    d: int,
    sigma_n2: float,
    sigma_e2: float,
    total: float,
    n_freq: int = 512,
) -> tuple[float, float]:
    """Förstner's frequency-domain redundancies ``(r_n, r_e)``: the total redundancy
    ``total`` split by :func:`spectral_shares` (see the module notes)."""
    share_n, share_e = spectral_shares(phi, d, sigma_n2, sigma_e2, n_freq)
    return total * share_n, total * share_e
