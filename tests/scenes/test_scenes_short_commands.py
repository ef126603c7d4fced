"""Short commands load no numba: short rigid-body runs stay in NumPy (numba's start-up,
about 0.8 s per process, would cost more than the run; the NumPy path gives the compiled
path's answer), and `validate` builds a beam problem without its compiled kernels."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from liegroup_int.integrators import integrate_fixed, resolve_method
from liegroup_int.scenes import KINDS, load_scene
from liegroup_int.scenes.rigid_body import NUMPY_BELOW_STAGES, compiles


@pytest.mark.parametrize("t_end, expected", [(0.01, False), (NUMPY_BELOW_STAGES / 4 * 1e-3 * 0.99, False),
                                             (NUMPY_BELOW_STAGES / 4 * 1e-3 * 1.01, True)])
def test_threshold_in_stage_evaluations(t_end, expected):
    """heavy_top: rkmk4 (4 stages) at dt = 1e-3."""
    assert compiles(load_scene("heavy_top", {"t_end": t_end})) is expected


def test_adaptive_runs_compile():
    scene = load_scene("heavy_top", {"t_end": 0.01, "integrator.method": "rkmk45", "integrator.dt": "none",
                                     "integrator.rtol": 1e-6})
    assert compiles(scene)


def test_numpy_path_matches_compiled_path():
    scene = load_scene("heavy_top", {"t_end": 0.05})
    sim = KINDS["rigid_body"].build(scene)
    assert sim.info["kernels"] == "numpy (short run)" and sim.problem.compiled_kernels() is None
    compiled = sim.problem.body.problem(compiled=True)
    assert compiled.compiled_kernels() is not None
    tab = resolve_method("rkmk4")
    _, y_np, _ = integrate_fixed(sim.problem, tab, (0.0, 0.05), sim.y0, 1e-3)
    _, y_nb, _ = integrate_fixed(compiled, tab, (0.0, 0.05), sim.y0, 1e-3)
    # same arithmetic up to the order of floating-point operations in exp/dexpinv
    assert np.max(np.abs(np.asarray(y_np) - np.asarray(y_nb))) < 1e-13


def test_short_run_imports_no_numba(tmp_path):
    """The CLI run in a fresh interpreter: no numba module is loaded, the summary says so."""
    code = ("import sys; from liegroup_int.cli import main; "
            f"rc = main(['run', 'heavy_top', '--set', 't_end=0.01', '--out', r'{tmp_path / 'r'}', '--no-plots', "
            "'--quiet']); print(rc, 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.splitlines()[-1].split() == ["0", "False"], out.stderr[-500:]
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["kernels"] == "numpy (short run)"


def test_validate_beam_scene_imports_no_numba():
    """`validate` checks a beam scene by building its problem; the compiled kernels are
    built at first use, so validation loads no numba."""
    code = ("import sys; from liegroup_int.cli import main; "
            "rc = main(['validate', 'cantilever']); print(rc, 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.splitlines()[-1].split() == ["0", "False"], out.stderr[-500:]
