"""Fuzz suite settings: the ``deep`` hypothesis profile for long runs outside CI.

``pytest tests/fuzz --hypothesis-profile=deep`` draws 300 mutants per target (about 20 per
operator) instead of CI's 14, with random rather than derandomized seeds; failures found are
replayed from hypothesis' example database.
"""

from __future__ import annotations

from hypothesis import HealthCheck, settings

settings.register_profile(
    "deep",
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
