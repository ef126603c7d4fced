"""Shared hypothesis settings for the whole test suite.

Profiles
--------
``liegroup`` (default)
    ``deadline=None`` (numpy/sympy first calls are slow and timing is not what we test),
    a modest ``max_examples`` so that ``pytest tests/groups`` stays well under 30 s on
    two cores.
``thorough``
    Many more examples, for occasional deeper runs:
    ``HYPOTHESIS_PROFILE=thorough pytest tests/groups``.

Tests that pin their own ``@settings(max_examples=...)`` keep their value.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "liegroup",
    deadline=None,
    max_examples=20,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile(
    "thorough",
    deadline=None,
    max_examples=500,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "liegroup"))
