"""Stone Soup reference runs used by the cross-check tests (and mirrored in the benchmarks).

Builds the JPDA tracker of Stone Soup's own JPDA tutorial (PDAHypothesiser + JPDA +
gm_reduce_single over the per-hypothesis EKF posteriors) for the paper-3 scenario: one
range-bearing sensor at the origin, nearly-constant-velocity targets.
Stone Soup measures ``[bearing, range]``; navtrack ``[range, bearing]``. The sensor is at the
origin (``translation_offset`` zero), which the analytic Jacobian below assumes.
"""

from __future__ import annotations

import datetime as _dt

import numpy as np


def run_stonesoup_jpda(
    scans: list[np.ndarray],
    x0: np.ndarray,
    P0: np.ndarray,
    q: float,
    sigma_r: float,
    sigma_theta: float,
    pd: float,
    clutter_density: float,
    gate_probability: float,
    dt: float = 1.0,
    associator: str = "jpda",
) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """Run Stone Soup JPDA over ``scans`` (each ``(M, 2)`` as ``[range, bearing]``).

    Returns per step: marginals ``(T, M+1)`` (column 0 = missed), states ``(T, 4)`` and
    covariances ``(T, 4, 4)``.
    """
    from stonesoup.dataassociator.probability import JPDA, JPDAwithEHM2
    from stonesoup.functions import gm_reduce_single
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.models.measurement.nonlinear import CartesianToBearingRange
    from stonesoup.models.transition.linear import (
        CombinedLinearGaussianTransitionModel,
        ConstantVelocity,
    )
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor
    from stonesoup.types.array import StateVectors
    from stonesoup.types.detection import Detection
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track
    from stonesoup.types.update import GaussianStateUpdate
    from stonesoup.updater.kalman import ExtendedKalmanUpdater

    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])

    class AnalyticBearingRange(CartesianToBearingRange):
        """Stone Soup's model with the analytic Jacobian (its default is a finite difference,
        off by ~1e-3 relative, which would hide everything else in the comparison)."""

        def jacobian(self, state, **kwargs):  # type: ignore[no-untyped-def]
            x = np.asarray(state.state_vector, dtype=float).ravel()
            dx, dy = x[0], x[2]
            r2 = dx * dx + dy * dy
            r = np.sqrt(r2)
            return np.array([[-dy / r2, 0, dx / r2, 0], [dx / r, 0, dy / r, 0]])

    meas = AnalyticBearingRange(
        ndim_state=4, mapping=(0, 2), noise_covar=np.diag([sigma_theta**2, sigma_r**2])
    )
    predictor = ExtendedKalmanPredictor(transition)
    updater = ExtendedKalmanUpdater(meas)
    hyp = PDAHypothesiser(
        predictor=predictor,
        updater=updater,
        clutter_spatial_density=clutter_density,
        prob_detect=pd,
        prob_gate=gate_probability,
    )
    assoc = JPDA(hypothesiser=hyp) if associator == "jpda" else JPDAwithEHM2(hypothesiser=hyp)
    t0 = _dt.datetime(2005, 8, 18)
    tracks = [
        Track([GaussianState(x0[i].reshape(4, 1), P0[i], timestamp=t0)]) for i in range(len(x0))
    ]
    out_b, out_x, out_P = [], [], []
    for k, Z in enumerate(scans):
        ts = t0 + _dt.timedelta(seconds=dt * (k + 1))
        dets = [
            Detection(np.array([[z[1]], [z[0]]]), timestamp=ts, measurement_model=meas) for z in Z
        ]
        index = {id(d): j for j, d in enumerate(dets)}
        hyps = assoc.associate(set(tracks), set(dets), ts)
        B = np.zeros((len(tracks), len(dets) + 1))
        for i, track in enumerate(tracks):
            states, weights = [], []
            for h in hyps[track]:
                if not h:
                    B[i, 0] += float(h.probability)
                    states.append(h.prediction)
                else:
                    B[i, 1 + index[id(h.measurement)]] += float(h.probability)
                    states.append(updater.update(h))
                weights.append(float(h.probability))
            means = StateVectors([s.state_vector for s in states])
            covars = np.stack([s.covar for s in states], axis=2)
            m, c = gm_reduce_single(means, covars, np.asarray(weights))
            track.append(GaussianStateUpdate(m, c, hyps[track], ts))
        out_b.append(B)
        out_x.append(np.array([np.asarray(t.state_vector, dtype=float).ravel() for t in tracks]))
        out_P.append(np.array([np.asarray(t.covar, dtype=float) for t in tracks]))
    return out_b, out_x, out_P
