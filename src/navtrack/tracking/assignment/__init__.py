"""Assignment: 2-D with missed-detection costs, Murty's k best, and S-D assignment.

One module a topic:

=====================  =====================================================================
module                 what it holds
=====================  =====================================================================
``two_d``              2-D track-oriented assignment (:func:`assign2d`), Murty's k best
                       (:func:`murty`), dual potentials of a 2-D assignment
``problem``            the S-D problem with the dummy index (:class:`SdProblem`), its
                       solutions, the exact (``milp``) and greedy solvers
``relaxation``         S-D by Lagrangian relaxation with recovery (:func:`sd_lagrangian`),
                       the dispatcher :func:`sd_assign`
``local_search``       tuple insertions and dimension-wise variation of a feasible solution
``tables``             the index tables a relaxation reads, built once per list order
``kernels``            the compiled (numba) loops and which NumPy path each one twins
``kbest``              the k best S-D solutions by Murty's partitioning (:func:`sd_kbest`)
=====================  =====================================================================

The names below are the public interface; the modules' own public names (the relaxation's
steps, the tables, the kernels) are there for the tests and for a reader who wants the parts.
"""

from navtrack.tracking.assignment.kbest import SdKBest, sd_kbest
from navtrack.tracking.assignment.kernels import compile_kernels
from navtrack.tracking.assignment.problem import (
    SdMethod,
    SdProblem,
    SdSolution,
    SdStatus,
    random_sd_problem,
    sd_exact,
    sd_greedy,
)
from navtrack.tracking.assignment.relaxation import sd_assign, sd_lagrangian
from navtrack.tracking.assignment.two_d import Assignment, KBest, assign2d, augmented_cost, murty

__all__ = [
    "Assignment",
    "KBest",
    "SdKBest",
    "SdMethod",
    "SdProblem",
    "SdSolution",
    "SdStatus",
    "assign2d",
    "augmented_cost",
    "compile_kernels",
    "murty",
    "random_sd_problem",
    "sd_assign",
    "sd_exact",
    "sd_greedy",
    "sd_kbest",
    "sd_lagrangian",
]
