"""Render a run's ParaView series (beam.pvd) read back with meshio, section frames as arrows.

    python examples/render_pvd.py RUN_DIR OUT.png

A stand-in for a ParaView screenshot on machines without ParaView: it reads exactly the
files ParaView opens.
"""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib
import meshio

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv=None):
    run, out = (Path(x) for x in (argv if argv is not None else sys.argv[1:]))
    entries = [(float(d.get("timestep")), d.get("file")) for d in ET.parse(run / "beam.pvd").getroot().iter("DataSet")]
    shown = entries[:: max(1, len(entries) // 6)]
    fig = plt.figure(figsize=(7, 5))
    ax = fig.add_subplot(projection="3d")
    for k, (t, f) in enumerate(shown):
        m = meshio.read(run / f)
        p, d2 = m.points, m.point_data["d2"]
        col = plt.get_cmap("viridis")(k / max(1, len(shown) - 1))
        ax.plot(p[:, 0], p[:, 1], p[:, 2], color=col, label=f"t = {t:.3g} s")
        ax.quiver(p[::3, 0], p[::3, 1], p[::3, 2], d2[::3, 0], d2[::3, 1], d2[::3, 2], length=0.05, color=col,
                  linewidth=0.6)
    ax.set_xlabel("x1"), ax.set_ylabel("x2"), ax.set_zlabel("x3")
    ax.legend(fontsize=7)
    ax.set_title(f"{run.name}: beam.pvd read back with meshio, section axis d2")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    return len(shown)


if __name__ == "__main__":
    main()
