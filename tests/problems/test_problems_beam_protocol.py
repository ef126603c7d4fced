"""Every beam formulation offers what scenes and writers read from a beam
(:class:`~liegroup_int.problems.beam.base.BeamModel`), with the Protocol's signatures."""

import inspect

import pytest

from liegroup_int.problems.beam.base import BeamModel
from liegroup_int.problems.beam.problem import ALL_FORMULATIONS
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

MEMBERS = [name for name in dir(BeamModel) if not name.startswith("_") and callable(getattr(BeamModel, name))]


def _params(fn):
    """Names, kinds and defaults of the parameters (``self`` dropped)."""
    sig = inspect.signature(fn)
    return [(p.name, p.kind, p.default) for p in sig.parameters.values() if p.name != "self"]


@pytest.mark.parametrize("formulation", ALL_FORMULATIONS)
def test_every_formulation_is_a_beam_model(formulation):
    pb = problem(load_scene("cantilever", {"space.formulation": formulation}))
    assert isinstance(pb, BeamModel)
    for name in ("formulation", "tau", "damping_report", "space", "n"):
        assert hasattr(pb, name), name
    assert pb.formulation == formulation
    for name in MEMBERS:
        assert _params(getattr(type(pb), name)) == _params(getattr(BeamModel, name)), name
    assert {"reactions", "tip", "energy_parts", "section_fields", "supports"} <= set(MEMBERS)
