"""Integrity monitoring of single point positions.

:mod:`navtrack.integrity.raim`: residual (chi-square) test, parity space, normalised residuals,
weighted-RAIM protection levels, fault exclusion (leave-one-out, iterative, solution
separation) and the :func:`~navtrack.integrity.raim.monitor` stage of
:func:`navtrack.gnss.spp.solve_spp`. :mod:`navtrack.integrity.ism`: the integrity support
message and the airborne error model behind every protection level.
:mod:`navtrack.integrity.araim`: multiple-hypothesis solution separation ARAIM (ADD v4.2).
:mod:`navtrack.integrity.fcm`: the fuzzy-clustering RAIM
of Gu et al. (2019). :mod:`navtrack.integrity.bias`: per-system and per-satellite mean
residuals at a reference position (a check that the measurement model has no bias).
"""
