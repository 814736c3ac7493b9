"""Estimation numerics shared by the domains: batched least squares (Gauss–Newton, Marquardt),
robust weights (Danish, Huber, IGG3, Baarda's w-test) and covariance bookkeeping of the
sequential filters (restarting a state).

Domain packages (``gnss``, ``integrity``, ``smoothing``, ...) import from here; nothing here
imports a domain package.
"""
