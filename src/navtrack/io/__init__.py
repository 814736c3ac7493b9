"""File input/output at the edges: solution tables and tracks, RTKLIB solution files.

* :mod:`navtrack.io.solution` — :func:`~navtrack.io.solution.write_solution` (CSV, Parquet,
  NMEA GGA, KML, GPX) and :func:`~navtrack.io.solution.read_solution` (CSV, Parquet);
* :mod:`navtrack.io.rtklib` — :func:`~navtrack.io.rtklib.read_pos` for RTKLIB ``.pos`` files.

Both need pandas; import the submodules directly.
"""
