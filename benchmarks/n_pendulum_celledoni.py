"""The N-fold 3D pendulum with variable steps, the experiment of Celledoni, Cokaj, Leone,
Murari & Owren, "Lie group integrators for mechanical systems" (Int. J. Comput. Math. 99,
2022), against their published set-up and numbers.

    python benchmarks/n_pendulum_celledoni.py [--n 2 4 6 10]

Their set-up (the authors' MATLAB code, github.com/davidemurari/NFold3dPendulumLieGroups,
``AA_Variable.m``, commit b961363b, and its 2022 clean-up in THREAD-3-2): N links of length
``5 / N`` and unit masses, g = 9.81 along -e3, released at rest with every link horizontal
(``q_i = (1, 0, 0)``, ``w_i = 0``), T = 3; SE(3)^N acting on (TS^2)^N; an RKMK(5,4) pair
(Dormand-Prince weights in the algebra) with error ``|sigma - sigma_hat|_2`` against
``tol = 1e-6`` and ``h <- 0.85 (tol / err)^(1/4) h``, from ``h0 = T / 100``; accuracy
``|z_ref - z(T)|_2`` against ode45 at AbsTol 1e-12, RelTol 1e-6.

Ours: :class:`liegroup_int.problems.NPendulum` with those masses, lengths and start, ``integrate(...,
method="rkmk45", rtol=1e-10, atol=1e-6)`` (our RKMK45 pair and PI controller, error
against ``atol``), accuracy ``|z_ref - z(T)|_2`` against our own RKMK45 at
``rtol = atol = 1e-12``. Also the energy drift.

Their figures (read from the vector data of the regenerated figure
``New plots/PendVarStepECMI1.pdf`` in github.com/ergyscokaj/NFold3dPendulumLieGroups,
commit 2232ff9c; about two significant digits; not the printed paper, which was not
available here): accepted steps and accuracy at T = 3 of their RKMK(5,4).
"""

from __future__ import annotations

import numpy as np

from liegroup_int import integrate
from liegroup_int.bench.table import markdown, parser
from liegroup_int.bench.timing import cpu
from liegroup_int.problems import NPendulum

#: N -> (accepted steps, accuracy at T = 3) of their RKMK(5,4), tol = 1e-6
PUBLISHED = {2: (52, 8.0e-6), 4: (114, 8.2e-6), 6: (181, 2.3e-5), 8: (248, 3.1e-5), 10: (316, 4.8e-5),
             12: (385, 3.6e-5), 14: (446, 3.8e-5), 16: (508, 3.9e-5), 18: (594, 5.9e-5), 20: (675, 5.7e-5)}


def case(n: int):
    pend = NPendulum(n, masses=np.ones(n), lengths=np.full(n, 5.0 / n))
    y0 = np.tile(np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), n)
    return pend.space, pend.generator, y0, pend.energy


def row(n: int, tol: float, t_end: float) -> list:
    space, gen, y0, energy = case(n)
    ref = integrate(gen, y0, (0.0, t_end), space=space, method="rkmk45", rtol=1e-12, atol=1e-12).y_final
    sol, c = cpu(lambda: integrate(gen, y0, (0.0, t_end), space=space, method="rkmk45", rtol=1e-10, atol=tol))
    err = float(np.linalg.norm(sol.y_final - ref))
    drift = abs(energy(sol.y_final) - energy(y0))
    steps, acc = PUBLISHED.get(n, (None, None)) if t_end == 3.0 else (None, None)
    return [n, f"{sol.stats.steps} ({sol.stats.rejected})", f"{err:.1e}", f"{drift:.1e}", f"{c:.2f}",
            "-" if steps is None else steps, "-" if acc is None else f"{acc:.1e}"]


def main(argv=None) -> None:
    ap = parser(__doc__, quick_help="N = 2 over 0.3 s (their figures are for T = 3: not compared)")
    # N = 20 works too, but its 1e-12 reference takes over 25 min in the generic loop (the
    # example's field is plain Python, one 3N x 3N solve per stage)
    ap.add_argument("--n", type=int, nargs="+", default=[2, 4, 6, 10])
    ap.add_argument("--tol", type=float, default=1e-6)
    args = ap.parse_args(argv)
    ns, t_end = ([2], 0.3) if args.quick else (args.n, 3.0)
    print(markdown(["N", "ours: steps (rejected)", f"ours: accuracy at T = {t_end:g}", "ours: energy drift [J]",
                    "ours: CPU [s]", "theirs: steps", "theirs: accuracy"], [row(n, args.tol, t_end) for n in ns]))


if __name__ == "__main__":
    main()
