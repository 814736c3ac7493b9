"""restart_states: the block of a restarted state is its prior variance, nothing else moves."""

from __future__ import annotations

import numpy as np

from navtrack.estimation.covariance import restart_states


def test_restart_zeroes_rows_and_columns_and_sets_variances() -> None:
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 6))
    P = a @ a.T
    before = P.copy()
    restart_states(P, np.array([1, 4]), np.array([9.0, 16.0]))
    keep = np.array([0, 2, 3, 5])
    np.testing.assert_array_equal(P[np.ix_(keep, keep)], before[np.ix_(keep, keep)])
    np.testing.assert_array_equal(P[[1, 4], :][:, keep], 0.0)
    np.testing.assert_array_equal(P[:, [1, 4]][keep, :], 0.0)
    np.testing.assert_array_equal(P[np.ix_([1, 4], [1, 4])], np.diag([9.0, 16.0]))
    restart_states(P, 2, 25.0)  # one state, scalar variance
    assert P[2, 2] == 25.0
    assert not P[2, np.arange(6) != 2].any()
