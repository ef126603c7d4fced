"""Time convergence of RKMK4 on the heavy top as a study (serial or on Dask).

    python examples/time_convergence.py [--quick] [--dask] [--out DIR]
"""

import argparse
from pathlib import Path

from liegroup_int import studies


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--dask", action="store_true", help="run on a local Dask cluster")
    ap.add_argument("--out", type=Path, default=Path("examples_out"))
    a = ap.parse_args(argv)
    dts = [0.02, 0.01, 0.005, 0.0025] if a.quick else [0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125]
    rows = studies.run_study("heavy_top", {"t_end": 1.0 if a.quick else 5.0}, studies.expand_grid({"integrator.dt": dts}),
                             a.out / "time_convergence", serial=not a.dask)
    table = studies.convergence_table(rows, "integrator.dt")
    studies.write_study(a.out / "time_convergence", rows, table)
    rate = studies.table_rate(table)
    print(f"fitted order of RKMK4: {rate:.3f}")
    print(f"wrote {a.out / 'time_convergence'} (study.csv, convergence.csv, plots)")
    return rate


if __name__ == "__main__":
    main()
