"""GNSS: file readers, satellite orbits and clocks, corrections and positioning."""
