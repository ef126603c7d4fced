"""The compiled engine's loops are cached on disk: a second process loads them instead of
compiling (numba ``cache=True`` through the engine's per-plugin copies), also for a user's
``numba.njit`` field, which the loops take as a first-class function value: a field defined
anew in each process still finds the loops in the cache."""

import json
import os
import subprocess
import sys

SCRIPT = """
import json, numpy as np
from liegroup_int.integrators import integrate_adaptive, integrate_fixed, resolve_method
from liegroup_int.integrators.engine import _ENGINES
from liegroup_int.problems import RigidBody
body = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
y0 = body.state(np.eye(3), np.array([0.3, 0.0, 10.0]))
integrate_fixed(body.problem(), resolve_method("rkmk4"), (0.0, 0.01), y0, 1e-3)
integrate_adaptive(body.problem(), resolve_method("rkmk45"), (0.0, 0.01), y0)
from numba import njit
from liegroup_int import SO3, integrate
@njit
def f(t, R):  # a new function object in every process
    return R @ np.array([0.0, 0.0, 1.0 + t])
for kw in ({"method": "rkmk4", "dt": 1e-3}, {"method": "rkmk45", "rtol": 1e-8, "atol": 1e-8}):
    integrate(f, np.eye(3), (0.0, 0.01), space=SO3, **kw)
out = {}
for k, e in _ENGINES.items():
    for name in ("advance_fixed", "advance_adaptive"):
        st = getattr(e, name).stats
        if st.cache_hits or st.cache_misses:
            out[k.name + "." + name] = [sum(st.cache_hits.values()), sum(st.cache_misses.values())]
print(json.dumps(out))
"""


def _run() -> dict:
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=600, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_the_compiled_loops():
    _run()  # compiles if the cache is cold (or stale), else loads
    second = _run()
    assert set(second) == {"rigid_body.advance_fixed", "rigid_body.advance_adaptive", "user.advance_fixed",
                           "user.advance_adaptive"}
    for name, (hits, misses) in second.items():
        assert (hits, misses) == (1, 0), (name, hits, misses)


KERNEL = """
from numba import njit


@njit(cache=True)
def kernel(x):
    return x + 1.0
"""

ADDRESS = """
import json, sys
sys.path.insert(0, sys.argv[1])
from numba import types
from liegroup_int.integrators.engine import FunctionValue
import kmod
FunctionValue(kmod.kernel, types.FunctionType(types.float64(types.float64))).__wrapper_address__()
st = kmod.kernel.stats
print(json.dumps([sum(st.cache_hits.values()), sum(st.cache_misses.values())]))
"""


def test_a_function_value_loads_what_a_call_from_python_cached(tmp_path):
    """A kernel called from Python once (as ``liegroup-int compile`` warms the beam's stage
    rate) and then, in a new process, taken by its address as a first-class function value
    (as the engine's loops take it): the second process loads it from the disk cache, one
    hit and no miss. Looked up by its full signature (with the return type), numba missed
    that entry and compiled the kernel again (measured: the Galerkin stage rate and action,
    6.8 s, on the first ``integrate`` after ``liegroup-int compile``)."""
    (tmp_path / "kmod.py").write_text(KERNEL)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    call = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import kmod; print(kmod.kernel(1.0))"
    first = subprocess.run([sys.executable, "-c", call], capture_output=True, text=True, timeout=300, env=env,
                           check=True)
    assert first.stdout.strip() == "2.0"
    done = subprocess.run([sys.executable, "-c", ADDRESS, str(tmp_path)], capture_output=True, text=True,
                          timeout=300, env=env, check=True)
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [1, 0]
