"""A run prepares its plots while it integrates: the compiled loops release the GIL, and a
thread imports and warms the plotting library meanwhile (``runner._preload_plots``)."""

import sys
import threading
import time

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.integrators import integrate_fixed, resolve_method
from liegroup_int.problems import RigidBody


def test_the_compiled_loop_lets_other_threads_run():
    """While one call of the compiled engine takes 2.5 million steps of the heavy top (0.93 s
    here), a Python thread that wakes every millisecond runs: its wake-ups fall in the middle
    of the call (0.1 s clear of either end, where Python code of the driver runs). With the
    GIL held for the call it could not wake there at all (measured: none, against hundreds)."""
    top = RigidBody(inertia=(1.0, 1.0, 0.5), mass=1.0, com=(0.0, 0.0, 0.5))
    y0 = top.state(np.eye(3), np.array([0.3, 0.0, 10.0]))
    pb, tab, dt = top.problem(), resolve_method("rkmk4"), 1e-5
    integrate_fixed(pb, tab, (0.0, 10 * dt), y0, dt)  # compile or load the loop
    wakes, stop = [], threading.Event()

    def tick():
        while not stop.is_set():
            wakes.append(time.perf_counter())
            time.sleep(1e-3)

    th = threading.Thread(target=tick, daemon=True)
    th.start()
    t_in = time.perf_counter()
    integrate_fixed(pb, tab, (0.0, 2.5e6 * dt), y0, dt)
    t_out = time.perf_counter()
    stop.set()
    th.join()
    assert t_out - t_in > 0.3, "the call was too short to tell"
    inside = [t for t in wakes if t_in + 0.1 < t < t_out - 0.1]
    assert len(inside) >= 10, (len(inside), t_out - t_in)


def test_plots_are_drawn_when_their_preloading_fails(tmp_path, monkeypatch):
    """A failure in the preloading thread is left to the plots, which import the same
    modules in the run's own thread; the thread switch interval is restored."""
    import liegroup_int.io.plots as plots

    def broken():
        raise ImportError("no plotting here")

    interval = sys.getswitchinterval()
    monkeypatch.setattr(plots, "preload", broken)
    out = tmp_path / "run"
    assert main(["run", "heavy_top", "--quiet", "--out", str(out), "--set", "t_end=0.05"]) == 0
    assert (out / "history.png").stat().st_size > 1000
    assert sys.getswitchinterval() == interval


def test_preload_draws_a_figure_into_memory():
    """What the thread runs: the plotting modules imported and a small figure drawn."""
    import liegroup_int.io.plots as plots

    plots.preload()
    assert "matplotlib.backends.backend_agg" in sys.modules and "matplotlib.ticker" in sys.modules


def test_the_switch_interval_comes_back_after_overlapping_preloads():
    """Runs in two threads of one process: the interval stays short while either preloads
    and comes back to its value when both are done."""
    from liegroup_int.runner import _ShortSwitch

    before = sys.getswitchinterval()
    _ShortSwitch.enter()
    _ShortSwitch.enter()
    short = sys.getswitchinterval()
    _ShortSwitch.leave()
    assert sys.getswitchinterval() == short == pytest.approx(min(before, 1e-4), rel=1e-6)  # kept in microseconds
    _ShortSwitch.leave()
    assert sys.getswitchinterval() == pytest.approx(before, rel=1e-6)
