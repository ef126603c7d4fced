"""The flexible pendulum from the command line's scene, written for ParaView.

    python examples/pendulum_to_paraview.py [--quick] [--out DIR]

Writes DIR/pendulum/{history.csv, results.h5, beam.pvd, paraview/*.vtu, shapes.png};
open beam.pvd in ParaView (File > Open), press Apply, add a Glyph filter on d1/d2 to see
the section frames.
"""

import argparse
from pathlib import Path

from liegroup_int.runner import run_scene
from liegroup_int.scenes import load_scene


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("examples_out"))
    a = ap.parse_args(argv)
    overrides = {"t_end": 0.05, "output.every": 0.01} if a.quick else {"output.every": 0.02}
    res = run_scene(load_scene("pendulum", overrides), a.out / "pendulum")
    print(f"tip at t = {res.summary['final']['t']:g} s: {res.summary['final']['tip']}")
    print(f"wrote {a.out / 'pendulum'}; open {a.out / 'pendulum' / 'beam.pvd'} in ParaView")
    return res


if __name__ == "__main__":
    main()
