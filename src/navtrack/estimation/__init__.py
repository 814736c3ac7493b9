"""Estimation numerics shared by the domains: batched least squares (Gauss–Newton, Marquardt)
and robust weights (Danish, Huber, IGG3, Baarda's w-test).

Domain packages (``gnss``, ``integrity``, ``smoothing``, ...) import from here; nothing here
imports a domain package.
"""
