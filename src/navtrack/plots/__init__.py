"""matplotlib figures used by the command line and the reports (extra ``plot``).

* :mod:`navtrack.plots.gnss` — positioning solutions: ENU errors, horizontal scatter,
  satellites/DOP, skyplot.

matplotlib is imported only when a figure is drawn.
"""
