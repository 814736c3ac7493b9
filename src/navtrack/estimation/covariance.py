"""Covariance bookkeeping shared by the sequential filters (PPP, RTK)."""

from __future__ import annotations

import numpy as np

from navtrack._typing import ArrayLike, FloatArray

__all__ = ["restart_states"]


def restart_states(P: FloatArray, idx: ArrayLike, variance: ArrayLike) -> None:
    """Restart states ``idx`` of the covariance ``P`` in place.

    Their rows and columns are zeroed (no correlation with the other states is kept) and their
    variances set to ``variance`` (a scalar, or one per state): a state re-initialised from
    scratch, such as a clock that does not carry over between epochs or an ambiguity after a
    cycle slip.
    """
    i = np.atleast_1d(np.asarray(idx))
    P[i, :] = 0.0
    P[:, i] = 0.0
    P[i, i] = variance
