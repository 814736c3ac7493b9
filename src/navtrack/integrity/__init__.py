"""Integrity monitoring of single point positions (above :mod:`navtrack.gnss`, which knows
nothing of it).

:mod:`navtrack.integrity.raim`: the :func:`~navtrack.integrity.raim.monitor` stage of the
positioning pipeline (:func:`navtrack.positioning.solve_positions`), a table of integrity methods
over the residual tests (:mod:`.residuals`: chi-square test, normalised residuals, weighted-RAIM
slopes), fault hypotheses and solution separation (:mod:`.separation`), fault exclusion
(:mod:`.exclusion`) and protection levels on the ISM error model (:mod:`.levels`).
:mod:`navtrack.integrity.ism`: the integrity support message and the airborne error model behind
every protection level. :mod:`navtrack.integrity.araim`: multiple-hypothesis solution separation
ARAIM (ADD v4.2). :mod:`navtrack.integrity.fcm`: the fuzzy-clustering RAIM of Gu et al. (2019).
:mod:`navtrack.integrity.bias`: per-system and per-satellite mean residuals at a reference
position (a check that the measurement model has no bias).
"""
