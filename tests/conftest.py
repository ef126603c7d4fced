"""Shared hypothesis settings for the whole test suite.

Profiles
--------
``liegroup`` (default, and what CI runs)
    Deterministic: ``derandomize=True`` draws the same examples on every run and machine, and
    no example database is read or written, so a run cannot fail on an example another run
    found. ``deadline=None`` (numpy/sympy first calls are slow and timing is not what we test)
    and a modest ``max_examples`` keep ``pytest tests/groups`` well under 30 s on two cores.
``explore``
    Random seeds and more examples, to look for new failures locally:
    ``HYPOTHESIS_PROFILE=explore pytest tests/groups`` (a failure prints the seed to replay
    it with ``--hypothesis-seed``).
``thorough``
    Random seeds and many more examples, for occasional deeper runs.

Tests that pin their own ``@settings(max_examples=...)`` keep their value.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

_COMMON = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])

settings.register_profile("liegroup", max_examples=20, derandomize=True, database=None, **_COMMON)
settings.register_profile("explore", max_examples=60, **_COMMON)
settings.register_profile("thorough", max_examples=500, **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "liegroup"))
