"""ARI(p, d) modelling of orientation parameters (Lindenberger, paper 5): the public entry.

Each series ``y_t`` (a position coordinate, an attitude angle, ...) is modelled as an ARI(p, d)
process ``x_t`` observed with white noise. The Gauss–Markov model of the paper is

* eq. (2), observations:    ``E(y_t) = x_t``,                      ``V(y_t) = sigma_n^2``
* eq. (3), process:         ``E(e_t) = 0 = x_t + sum_i a_i x_{t-i}``, ``V(e_t) = sigma_e^2``

with ``1 + sum_i a_i B^i = phi(B) (1 - B)^d`` (``B`` the backshift, ``phi(B) = 1 + phi_1 B + ...
+ phi_p B^p``; the paper's sign convention, eq. (1): ``x_t = -sum a_i x_{t-i} + e_t``). Both
groups together are a least-squares problem in the ``n`` unknowns ``x``; its normal matrix
``N = S^T W S / sigma_n^2 + C^T V C / sigma_e^2`` is banded (half-bandwidth ``m = p + d``), so
the filtered series, ``log det N`` and — by selected inversion — the band of ``N^-1`` cost O(n).

Everything the paper lists is estimated without a-priori stochastic information:

* ``sigma_n^2, sigma_e^2`` by redundancy-based variance component estimation (Förstner 1979;
  Koch 1986: ``sigma_k^2 = v_k^T P_k v_k / r_k`` with the redundancy
  ``r_k = n_k - tr(N^-1 N_k)``), iterated until the relative change of both sigmas is below
  ``tol``. The paper recommends Förstner's (1984) *frequency-domain* formulation, which replaces
  the redundancies by integrals of the stationary filter's transfer function. We use the exact
  time-domain redundancies instead, from the band of ``N^-1``: with gaps (missing epochs),
  robust weights and short strips (the paper's GPS strips have ~130 epochs) the series is not
  stationary and the frequency-domain values are only asymptotic, while selected inversion makes
  the exact ones O(n). The VCE fixed point is the stationary point of the likelihood below in
  the two variances (``d(-2 log L)/d log sigma_k^2 = r_k - Omega_k / sigma_k^2``).
* ``phi`` (the AR part; the ``d`` differences are fixed) jointly with the variances. The paper
  alternates (Lindenberger 1987) between filtering and a least-squares fit of eq. (3); its
  proper form is the EM step (moments ``E[x x^T] = x_hat x_hat^T + N^-1``, band only), whose
  equation is the ``phi`` part of the likelihood gradient. That alternation converged linearly
  and needed hundreds of iterations in our tests (even with SQUAREM acceleration), so the same
  gradient — VCE equations for the variances, expected-moment equations for ``phi``, plus the
  stationary-start term — drives a quasi-Newton (BFGS) search with Armijo backtracking,
  started from a finite-difference Hessian; a final VCE iteration certifies the variance
  components. Stopping rule: predicted log-likelihood gain of the next quasi-Newton step below
  ``gain_tol`` (1e-3), then VCE relative change below ``tol`` (1e-6); ``max_iter`` otherwise
  (status ``not_converged``). Series longer than ``screen_n`` are fitted on growing leading
  blocks (``stage_growth``), each searched by BFGS structured on Whittle's spectral
  information (:func:`~navtrack.smoothing.estimation.spectral_information`, recomputed at every
  iterate): the curved ``sigma_e``/``phi`` ridge of long ARI(p, 2) series made plain BFGS crawl.
* The likelihood in ``(phi, sigma_n, sigma_e)`` is multimodal on short series (``sigma_n -> 0``
  is a local optimum — the SARIMAX failure the issue describes); several starts spread over the
  noise fraction are run (on long series on a leading window, then refined on the whole
  series), and an interior optimum is kept over a boundary one unless the latter is
  significantly better (``boundary_margin``).
* The normal equations are solved for the correction ``x - y`` to the observations (``y``
  interpolated over gaps), not for ``x``: an integrated series drifts to values far larger than
  its noise, and the solve's rounding, proportional to ``|x|``, made the likelihood of a 1e6
  epoch series noisy by up to one unit.
* robust reweighting (IRLS inside the VCE iteration) with a weight function of the studentized
  *deletion* residual ``T`` (Baarda's w-test statistic for unit weight; for a down-weighted
  observation it is the prediction residual from all other data, so the test does not
  oscillate as weights change). Danish method (default), Huber, IGG-III; observations with
  ``|T| > flag_threshold`` are flagged as gross errors; the process equations (3) can be
  reweighted too (``robust_process``) for edges and discontinuities.
* order ``(p, d)`` by BIC (or AIC) of the likelihood conditional on the first ``max(p + d)``
  epochs, so that candidates with different ``d`` are compared on the same data.
* ``sigma_x`` per epoch and the correlations ``r(h)`` of the filtered data from ``N^-1``.

Selected inversion: Takahashi's recursion on the banded Cholesky factor (compiled with numba
when installed, extra ``speed``; O(n m^2)), else an odd–even block recursion in NumPy
(:mod:`navtrack.smoothing.banded`). Both are tested against dense inverses.

Modules (this one re-exports the public names):

* :mod:`navtrack.smoothing.model` — ARI polynomial, process equations, banded normal
  equations, stationary start, :func:`gauss_markov_filter`, :func:`simulate_ari`, and
  :class:`~navtrack.smoothing.model.AriProblem` (one series ready for estimation);
* :mod:`navtrack.smoothing.estimation` — likelihood gradient, variance components,
  quasi-Newton search, robust reweighting, the estimator
  (:func:`~navtrack.smoothing.exact.estimate_exact_likelihood`) and
  :func:`observed_information`;
* :mod:`navtrack.smoothing.alternation` — the paper's estimator (``AriConfig(estimator=
  "paper")``): conditional model, alternating filtering / VCE / expected-moment AR step;
* :mod:`navtrack.smoothing.identifiability` — Cramér–Rao bounds of the sigmas at an estimate
  and the paper's "same order of magnitude" condition;
* :mod:`navtrack.estimation.robust` — weight functions and Baarda's w-test, generic over
  residuals (shared with integrity monitoring);
* :mod:`navtrack.smoothing.fitting` — input checks, fixed-order fit, order selection,
  :func:`fit_ari`, :func:`regularize_time`;
* :mod:`navtrack.smoothing.config`, :mod:`navtrack.smoothing.result` — :class:`AriConfig`,
  :class:`AriResult`, :class:`AriStatus`, :class:`AriEpochStatus`;
* :mod:`navtrack.smoothing.banded` — banded Cholesky, selected inversion, band sums.

Likelihood (``initial="stationary"``, the default; ``n_o`` observed epochs): the first ``d``
states are diffuse, the first ``p`` differences ``u = (1 - B)^d x`` follow the AR's stationary
distribution ``N(0, sigma_e^2 Gamma_p)``, then eq. (3)::

    -2 log L = (n_o - d) log 2 pi + sum log(sigma_n^2 / w_t) + sum log(sigma_e^2 / v_s)
               + p log sigma_e^2 + log det Gamma_p + log det N + Omega,
    Omega = sum w v^2 / sigma_n^2 + (sum v e^2 + u_0^T Gamma_p^-1 u_0) / sigma_e^2

(the change of variables ``x -> (x_1..x_d, u_0, e)`` has unit Jacobian because ``a_0 = 1``).
This is exactly the likelihood of statsmodels' ``SARIMAX(order=(p, d, 0),
measurement_error=True)`` (tested to 1e-5). ``initial="conditional"`` drops the stationary
start (the plain Gauss–Markov model (2)–(3), conditional on the first ``p`` differences).

References
----------
J. Lindenberger, "Modelling orientation parameters of sensor platforms", ISPRS Comm. I (paper 5
in ``shared/papers``), eqs. (1)–(3), section 2.
W. Förstner, "Ein Verfahren zur Schätzung von Varianz- und Kovarianzkomponenten",
Allgemeine Vermessungs-Nachrichten 86, 446–453, 1979.
W. Förstner, "Determination of the additive noise variance of observed autoregressive processes
using variance component estimation technique", Schriftenreihe 10, Inst. f. Photogrammetrie,
Univ. Stuttgart, 1984.
K.-R. Koch, "Maximum likelihood estimate of variance components", Bull. Géod. 60, 329–338, 1986.
T. Krarup, J. Juhl, K. Kubik, "Götterdämmerung over least squares adjustment", Int. Arch.
Photogramm. 23(B3), 369–378, 1980 (Danish method).
P. J. Huber, "Robust estimation of a location parameter", Ann. Math. Stat. 35, 73–101, 1964.
Y. Yang, "Robust estimation for dependent observations", Manuscripta Geodaetica 19, 10–17, 1994
(IGG-III).
R. Varadhan, C. Roland, "Simple and globally convergent methods for accelerating the
convergence of any EM algorithm", Scand. J. Stat. 35, 335–353, 2008.
"""

from navtrack.estimation.robust import ROBUST_DEFAULTS, robust_weight
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.estimation import observed_information
from navtrack.smoothing.fitting import fit_ari, fit_ari_order, regularize_time
from navtrack.smoothing.model import ari_polynomial, gauss_markov_filter, simulate_ari
from navtrack.smoothing.result import AriEpochStatus, AriResult, AriStatus

__all__ = [
    "ROBUST_DEFAULTS",
    "AriConfig",
    "AriEpochStatus",
    "AriResult",
    "AriStatus",
    "ari_polynomial",
    "fit_ari",
    "fit_ari_order",
    "gauss_markov_filter",
    "observed_information",
    "regularize_time",
    "robust_weight",
    "simulate_ari",
]
