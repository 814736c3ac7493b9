"""matplotlib figures used by the command line and the reports (extra ``plot``).

* :mod:`navtrack.plots.gnss` — positioning solutions: ENU errors, horizontal scatter,
  satellites/DOP, skyplot;
* :mod:`navtrack.plots.tracks` — map-like plot of detections and confirmed tracks;
* :mod:`navtrack.plots.canvas` — figure set-up shared by the modules (Agg canvas, PNG files).

matplotlib is imported only when a figure is drawn.
"""
