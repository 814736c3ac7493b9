"""Estimation numerics shared by the domains: batched least squares (Gauss–Newton, Marquardt),
robust weights (Danish, Huber, IGG3, Baarda's w-test), covariance bookkeeping of the
sequential filters (restarting a state), and the Kalman / EKF / UKF kernels (``kalman``) with
the model interfaces they take (``models``: the ``MotionModel`` and ``MeasurementModel``
protocols; concrete models live in the domains, e.g. ``tracking.models``).

Domain packages (``gnss``, ``integrity``, ``smoothing``, ...) import from here; nothing here
imports a domain package.
"""
