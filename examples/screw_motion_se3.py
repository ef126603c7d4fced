"""A user ODE on SE(3): a rigid body moving with a constant body twist (screw motion).

    python examples/screw_motion_se3.py [--quick]

The exact solution is g(t) = g0 exp(t xi); RKMK reproduces it to round-off at any step,
because the vector field is constant in the body frame.
"""

import argparse

import numpy as np

from liegroup_int import SE3, integrate
from liegroup_int.integrators import GroupProblem


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    xi = np.array([0.3, 0.0, 0.1, 0.0, 0.2, 1.5])  # body twist (rho, theta)
    g0 = SE3.exp(np.array([1.0, 0.0, 0.0, 0.1, 0.0, 0.0]))
    pb = GroupProblem(SE3, lambda t, g: SE3.Ad(g) @ xi)  # spatial twist = Ad_g xi
    T = 2.0 if a.quick else 20.0
    sol = integrate(pb, g0, (0.0, T), method="rkmk4", dt=0.1)
    err = np.abs(sol.y_final - g0 @ SE3.exp(T * xi)).max()
    print(f"{sol.stats.steps} steps, error against g0 exp(T xi): {err:.2e}")
    return err


if __name__ == "__main__":
    main()
