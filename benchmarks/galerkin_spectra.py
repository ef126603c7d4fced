"""Linearized spectra of the Galerkin beam: at rest over a (p, n_ctrl) map, and about the
rolled-up half and full circle.

    python benchmarks/galerkin_spectra.py [--quick]

1. **At rest.** ``cantilever``, ``pendulum`` and ``arch`` with ``space.formulation =
   "galerkin"``, p = 2..8 against n_ctrl = 11..121: the largest real part of the dense
   spectrum of the linearized increment map (central differences,
   ``integrators.eigenvalues``), absolute and over ``|lambda|max``. The arch without its
   end couple (a dead couple is not conservative out of the plane: with it on at t = 0 the
   out-of-plane block has a growing pair, printed on its own).
2. **Roll-up.** The ``rollup`` beam under the end couple ``M = k pi EI / L`` (k = 1: half
   circle, k = 2: full circle) in its static state, the exact arc of curvature ``M / EI``
   (positions projected on the basis; the printed residual is the largest acceleration
   that leaves); the spectrum of the undamped problem there, split into the in-plane block
   (x1-x2 translations, rotation about x3) and the out-of-plane block. The dead end couple is not conservative out of
   the plane in 3D, so growth there can be physical; in the plane the problem is
   conservative.
"""

from __future__ import annotations

import math

import numpy as np

from liegroup_int.bench.table import parser
from liegroup_int.groups.so3 import exp_so3
from liegroup_int.integrators import eigenvalues, jacobian
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem


#: The arch's end couple (on at t = 0) is a dead couple: not conservative out of its plane
#: in 3D, so "at rest" means without it (``loaded_arch`` shows what it adds).
UNLOADED = {"arch": {"loads.end.couple": [0.0, 0.0, 0.0]}}


def at_rest(scenes, degrees, sizes) -> None:
    print("| scene | p | n_ctrl | max Re lambda [1/s] | max Re / abs(lambda)max |")
    print("|---|---|---|---|---|")
    for scene in scenes:
        for p in degrees:
            for n in sizes:
                if n < p + 2:
                    continue
                pb = problem(load_scene(scene, {"space.formulation": "galerkin", "space.degree": p,
                                                "space.n_ctrl": n, "material.kelvin_voigt": 0.0,
                                                **UNLOADED.get(scene, {})}))
                ev = eigenvalues(pb, 0.0, pb.initial_state())
                lam = float(np.max(np.abs(ev)))
                print(f"| {scene} | {p} | {n} | {ev.real.max():.2g} | {ev.real.max() / lam:.1e} |", flush=True)


def rolled(k: float, n: int):
    """The roll-up under the end couple M = k pi EI / L in its static state: the exact
    circular arc of curvature M / EI (no axial or shear strain), its positions projected on
    the basis, rotations and curvatures exact at the points. Returns (problem, state, t)
    with t after the couple's ramp."""
    base = problem(load_scene("rollup", {"space.formulation": "galerkin", "space.n_ctrl": n}))
    EI, L = float(base.CM[0, 0]), base.space.length
    kap = k * math.pi / L
    pb = problem(load_scene("rollup", {"space.formulation": "galerkin", "space.n_ctrl": n,
                                       "material.kelvin_voigt": 0.0,
                                       "loads.end.couple": [0.0, 0.0, kap * EI]}))
    y = pb.initial_state()
    s_pts = pb.gs.s
    arc = np.stack([np.sin(kap * s_pts) / kap, (1.0 - np.cos(kap * s_pts)) / kap, 0.0 * s_pts], axis=1)
    y.c = pb.gs.project(arc)
    y.R = exp_so3(np.outer(kap * s_pts, [0.0, 0.0, 1.0])) @ pb.gs.R0
    y.K = pb.gs.K0 + kap * np.einsum("qji,j->qi", pb.gs.R0, [0.0, 0.0, 1.0])
    return pb, y, 20.0


def rollup(ks, sizes) -> None:
    print("| couple | n_ctrl | tip (x, y) | residual max abs(v') | in-plane max Re [1/s] | out-of-plane max Re [1/s] "
          "(at Im) | abs(lambda)max |")
    print("|---|---|---|---|---|---|---|")
    for k in ks:
        for n in sizes:
            pb, y, t = rolled(k, n)
            res = np.max(np.abs(pb.vector_field(t, y)[2]))
            J = jacobian(pb, t, y)
            idx = np.arange(J.shape[0]).reshape(4, pb.n, 3)
            inplane = np.concatenate([idx[0, :, :2].ravel(), idx[1, :, 1], idx[2, :, :2].ravel(), idx[3, :, 1]])
            outplane = np.setdiff1d(idx.ravel(), inplane)
            ei = np.linalg.eigvals(J[np.ix_(inplane, inplane)])
            eo = np.linalg.eigvals(J[np.ix_(outplane, outplane)])
            j = int(np.argmax(eo.real))
            lam = float(max(np.max(np.abs(ei)), np.max(np.abs(eo))))
            print(f"| {k:g} pi EI/L | {n} | ({y.c[-1, 0]:+.4f}, {y.c[-1, 1]:+.4f}) | {res:.1e} | {ei.real.max():.2g} "
                  f"| {eo.real.max():.3g} ({abs(eo[j].imag):.4g}) | {lam:.4g} |", flush=True)


def loaded_arch(p: int = 4, n: int = 21) -> None:
    """The arch at t = 0 with its end couple on: in-plane and out-of-plane blocks."""
    pb = problem(load_scene("arch", {"space.formulation": "galerkin", "space.degree": p, "space.n_ctrl": n,
                                     "material.kelvin_voigt": 0.0}))
    J = jacobian(pb, 0.0, pb.initial_state())
    idx = np.arange(J.shape[0]).reshape(4, pb.n, 3)
    # the arch lies in the x1-x2 plane with d1 = e3: in-plane rotations are about material axis 1
    inp = np.concatenate([idx[0, :, :2].ravel(), idx[1, :, 0], idx[2, :, :2].ravel(), idx[3, :, 0]])
    out = np.setdiff1d(idx.ravel(), inp)
    ei, eo = np.linalg.eigvals(J[np.ix_(inp, inp)]), np.linalg.eigvals(J[np.ix_(out, out)])
    j = int(np.argmax(eo.real))
    print(f"arch p={p} n_ctrl={n} with its end couple at t = 0: in-plane max Re {ei.real.max():.2g} 1/s, "
          f"out-of-plane max Re {eo.real.max():.4g} 1/s at |Im| {abs(eo[j].imag):.6g} 1/s")


def main(argv=None) -> None:
    ap = parser(__doc__, quick_help="cantilever at rest and the half circle, p = 4, n_ctrl = 11 only")
    ap.add_argument("--scenes", nargs="+", default=["cantilever", "pendulum", "arch"])
    args = ap.parse_args(argv)
    if args.quick:
        at_rest(["cantilever"], [4], [11])
        rollup([1.0], [11])
        return
    at_rest(args.scenes, [2, 3, 4, 5, 6, 7, 8], [11, 21, 41, 61, 121])
    loaded_arch()
    rollup([1.0, 2.0], [21, 31, 41])


if __name__ == "__main__":
    main()
