"""Smoothing of navigation time series: ARI(p,d) filtering with variance components (paper 5)."""
