"""The positioning pipeline above :mod:`navtrack.gnss` and :mod:`navtrack.integrity`.

:func:`solve_positions` chains observations -> satellite states -> corrections -> estimate ->
validate or RAIM -> result (:mod:`.pipeline`); :mod:`.agps` runs the two-satellite AGPS method on
a recorded file (measurements -> assisted pseudoranges -> fixes -> solver). ``navtrack pos``,
``navtrack agps``, the network run and the experiments call them; ``gnss`` knows nothing of
integrity and nothing below imports this package.
"""

from __future__ import annotations

from navtrack.positioning.pipeline import PositionSolution, solution_frame, solve_positions

__all__ = ["PositionSolution", "solution_frame", "solve_positions"]
