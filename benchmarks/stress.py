"""Stability stress tests: long horizons, fast spin, large rotations, many small steps.

    python benchmarks/stress.py [--quick] [--only NAME ...]

Prints one row per scenario (steps, CPU time, energy drift, orthogonality error, the
scenario's own figure) and saves ``docs/img/stress_*.png`` (energy drift and
orthogonality error against time). ``--quick``: the scenarios ``QUICK_ONLY`` over their
shortest spans (``SMOKE``), figures in a temporary directory or ``--out``. The fast versions in CI are
``tests/problems/test_problems_beam_stress.py``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from liegroup_int.bench.table import figure_dir, markdown, parser
from liegroup_int.bench.timing import cpu
from liegroup_int.io import read_history
from liegroup_int.runner import RunError, run_scene
from liegroup_int.scenes import load_scene

IMG = Path(__file__).resolve().parents[1] / "docs" / "img"
#: the smoke run: two scenarios over a few output intervals, undamped and without the
#: start-up spectrum guard (a dense spectrum takes seconds for the helix)
QUICK_ONLY = ("pendulum_10s", "helix_5s")
_SMOKE = {"material.kelvin_voigt": 0.0, "guard.spectrum": False}
SMOKE = {"pendulum_10s": {"t_end": 0.01, "output.every": 0.002, **_SMOKE},
         "helix_5s": {"t_end": 0.002, "output.every": 0.0005, **_SMOKE}}

SCENARIOS = {
    # name: (scene, overrides, quick overrides, note)
    "pendulum_10s": ("pendulum", {"t_end": 10.0, "output.every": 0.02,
                                  "output.quantities": ["tip", "energy", "kinetic", "orth_error"]},
                     {"t_end": 2.0}, "long horizon"),
    # the same with a finer mesh, and with n_ctrl = 61 plus Kelvin-Voigt damping tau = 0.3 / |lambda|max
    "pendulum_10s_n81": ("pendulum", {"t_end": 10.0, "output.every": 0.02, "space.n_ctrl": 81, "integrator.dt": "auto",
                                      "output.quantities": ["tip", "energy", "kinetic", "orth_error"]},
                         {"t_end": 2.0}, "n_ctrl=81, dt = auto"),
    "pendulum_10s_n61_kv": ("pendulum", {"t_end": 10.0, "output.every": 0.02, "space.n_ctrl": 61,
                                         "integrator.dt": "auto", "material.kelvin_voigt": 5e-6,
                                         "output.quantities": ["tip", "energy", "kinetic", "orth_error"]},
                            {"t_end": 2.0}, "n_ctrl=61, dt = auto, kelvin_voigt = 5e-6 s"),
    "helix_5s": ("spinning_helix", {"t_end": 5.0, "output.every": 0.01,
                                    "output.quantities": ["tip", "energy", "kinetic", "angular_momentum", "orth_error"]},
                 {"t_end": 1.0}, "long horizon; h_z conserved"),
    "helix_fast_spin": ("spinning_helix", {"t_end": 0.5, "initial.omega": [0.0, 0.0, 62.83185307179586],
                                           "integrator.dt": "auto", "output.every": 0.005,
                                           "output.quantities": ["tip", "energy", "kinetic", "angular_momentum",
                                                                 "orth_error"]},
                        {"t_end": 0.1}, "10x angular velocity"),
    "helix_fast_spin_kv": ("spinning_helix", {"t_end": 0.5, "initial.omega": [0.0, 0.0, 62.83185307179586],
                                              "integrator.dt": "auto", "output.every": 0.005,
                                              "material.kelvin_voigt": 3e-6,
                                              "output.quantities": ["tip", "energy", "kinetic", "angular_momentum",
                                                                    "orth_error"]},
                           {"t_end": 0.1}, "10x angular velocity, kelvin_voigt = 3e-6 s"),
    "rollup_3_4": ("rollup", {}, {"t_end": 3.5, "loads.end.ramp": 3.0,
                                  "loads.end.couple": [0.0, 0.0, np.pi * 3.0679615757712823]},
                   "3/4 circle (quick: half circle)"),
    "rollup_full": ("rollup", {"loads.end.couple": [0.0, 0.0, 2 * np.pi * 3.0679615757712823],
                               "space.n_ctrl": 41, "space.degree": 3}, {"t_end": 3.0},
                    "full circle, n_ctrl=41, p=3"),
    "rollup_full_kv": ("rollup", {"loads.end.couple": [0.0, 0.0, 2 * np.pi * 3.0679615757712823],
                                  "space.n_ctrl": 41, "space.degree": 3, "material.kelvin_voigt": 7e-6},
                       {"t_end": 3.0}, "full circle, n_ctrl=41, p=3, kelvin_voigt = 7e-6 s"),
    "pendulum_1e6_steps": ("pendulum", {"integrator.dt": 1e-6, "t_end": 1.0, "output.every": 0.01,
                                        "output.quantities": ["tip", "energy", "kinetic", "orth_error"]},
                           {"t_end": 0.1}, "round-off growth over 1e6 steps"),
}


def run(name, quick, img: Path):
    scene_name, ov, qov, note = SCENARIOS[name]
    ov = {**ov, **(qov if quick else {}), **(SMOKE.get(name, {}) if quick else {}), "output.hdf5": False,
          "output.plots": False}
    if "orth_error" not in ov.get("output.quantities", ["orth_error"]):
        ov["output.quantities"] = list(ov["output.quantities"]) + ["orth_error"]
    scene = load_scene(scene_name, ov)
    out = Path(tempfile.mkdtemp(prefix=f"stress_{name}_"))
    status, err = "ok", ""
    try:
        res, cpu_s = cpu(lambda: run_scene(scene, out))
        steps = res.summary["steps"]
    except RunError as exc:
        status, err, steps, cpu_s = "blow-up", str(exc).split(" (outputs")[0], None, float("nan")
    h = read_history(out / "history.csv")
    row = {"name": name, "note": note, "status": status, "steps": steps, "cpu_s": cpu_s, "t_reached": float(h["t"][-1]),
           "error": err}
    if "energy" in h and len(h["t"]) > 1:
        scale = max(np.max(np.abs(h.get("kinetic", h["energy"]))), 1e-300)
        row["energy_drift_rel"] = float(np.max(np.abs(h["energy"] - h["energy"][0])) / scale)
    if "orth_error" in h:
        row["orth_max"] = float(np.max(h["orth_error"]))
    if "h_z" in h:
        row["hz_drift_rel"] = float(np.max(np.abs(h["h_z"] - h["h_z"][0])) / abs(h["h_z"][0]))
    plot(name, h, img)
    return row


def plot(name, h, img: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 3.4))
    if "energy" in h:
        ax[0].plot(h["t"], h["energy"] - h["energy"][0])
        ax[0].set_ylabel("E(t) - E(0) [J]")
    if "orth_error" in h:
        ax[1].semilogy(h["t"], np.maximum(h["orth_error"], 1e-17))
        ax[1].set_ylabel("max |R^T R - I|")
    for a in ax:
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3)
    fig.suptitle(name)
    fig.tight_layout()
    fig.savefig(img / f"stress_{name}.png", dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = parser(__doc__, quick_help="two scenarios over a few output intervals")
    ap.add_argument("--only", nargs="*", default=None)
    a = ap.parse_args(argv)
    img = figure_dir(a, IMG)
    rows = [run(n, a.quick, img) for n in (a.only or (QUICK_ONLY if a.quick else SCENARIOS))]
    print(markdown(["scenario", "status", "steps", "CPU s", "t reached", "dE/Ekin", "orth max", "dh_z/h_z", "note"],
                   [[r["name"], r["status"], r["steps"], f"{r['cpu_s']:.1f}", f"{r['t_reached']:.4g}",
                     r.get("energy_drift_rel"), r.get("orth_max"), r.get("hz_drift_rel"), r["note"]] for r in rows]))
    for r in rows:
        if r["error"]:
            print(f"{r['name']}: {r['error']}")
    print(f"figures: {img}")
    return rows


if __name__ == "__main__":
    main()
