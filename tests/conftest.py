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

# One BLAS thread per test process: the suite runs one process per core (pytest -n 2) and
# tests start subprocesses, so BLAS threads only contend; a dense eigenvalue problem of 384
# unknowns measured 1.9 s with OpenBLAS's default threads on a busy 2-core machine, 0.18 s with
# one. Set before numpy is first imported (pytest and hypothesis do not import it).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from hypothesis import HealthCheck, settings

_COMMON = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])

settings.register_profile("liegroup", max_examples=20, derandomize=True, database=None, **_COMMON)
settings.register_profile("explore", max_examples=60, **_COMMON)
settings.register_profile("thorough", max_examples=500, **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "liegroup"))
