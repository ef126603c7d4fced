"""Fuzzing the scene loader: any input gives a valid scene or a one-line SceneError."""

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from liegroup_int.scenes import (
    SceneError,
    build_scene,
    builtin_names,
    builtin_path,
    load_scene,
)
from liegroup_int.scenes.schema import flatten, read_toml

BASES = {name: flatten(read_toml(builtin_path(name))) for name in builtin_names()}
# keep the fuzzed beams small so building a scene stays cheap
for v in BASES.values():
    if "space.n_ctrl" in v:
        v["space.n_ctrl"] = 8
        v["space.degree"] = min(v.get("space.degree", 4), 4)

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-10**6, max_value=10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
)
values = st.one_of(scalars, st.lists(scalars, max_size=4), st.lists(st.lists(scalars, max_size=3), max_size=3))
key_names = st.sampled_from(sorted({k for v in BASES.values() for k in v} | {"integrator.mthod", "space", "x.y.z"}))


@st.composite
def mutated_scene(draw):
    base = dict(BASES[draw(st.sampled_from(sorted(BASES)))])
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        op = draw(st.sampled_from(["set", "delete", "add"]))
        key = draw(key_names)
        if op == "delete":
            base.pop(key, None)
        else:
            val = draw(values)
            if val is None:
                continue  # TOML has no null
            base[key] = val
    return base


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_scene())
def test_loader_gives_scene_or_one_line_error(given_keys):
    try:
        scene = build_scene(given_keys, "fuzz.toml", "fuzz")
    except SceneError as exc:
        msg = str(exc)
        assert msg.startswith("fuzz.toml") and "\n" not in msg
        return
    assert scene.t_end > 0 and math.isfinite(scene.t_end)


@pytest.mark.parametrize("over, key", [({"section.d": 1.157920892373162e+77}, "section.d"),
                                       ({"section.shape": "square", "section.t": 1e200}, "section.t")])
def test_overflowing_section_is_one_line_error(over, key):
    """A size whose section constants overflow a float (a case the fuzz test above finds:
    unguarded, it raises OverflowError) is refused naming the key, once."""
    with pytest.raises(SceneError) as err:
        load_scene("pendulum", over)
    msg = str(err.value)
    assert f"key '{key}': too large" in msg and msg.count("builtin:pendulum") == 1
