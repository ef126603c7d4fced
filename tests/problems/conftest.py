"""Fixtures shared by the problem tests."""

import pytest

from liegroup_int.integrators.engine import CompiledStepper


@pytest.fixture
def advance_calls(monkeypatch):
    """The ``n_steps`` of every call of the compiled engine's fixed-step loop, in order."""
    calls = []
    original = CompiledStepper.advance

    def counted(self, *args):
        calls.append(args[4])  # n_steps
        return original(self, *args)

    monkeypatch.setattr(CompiledStepper, "advance", counted)
    return calls
