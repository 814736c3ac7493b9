"""Multi-target tracking core: models, Kalman kernels, gating, assignment, JPDA, tracker, metrics.

Submodules are imported on demand (``from navtrack.tracking.jpda import jpda_marginals``); this
package file stays light so the CLI starts fast.
"""
