"""First-call cost of ``integrate`` with a ``numba.njit`` vector field (compilation).

    python benchmarks/free_body_first_call.py [rkmk4 rkmk45 ...]

Each method runs in a fresh process: numba compiles the user's ``f`` (a new function is
never in the disk cache) and loads the engine's loops, which take ``f`` as a first-class
function value, from the disk cache (compiled on the first run after an install). CPU
seconds of the first and the second ``integrate`` call on the README's free rigid body
(:mod:`liegroup_int.bench.free_body`); their difference is the first call's overhead.
"""

from __future__ import annotations

from liegroup_int.bench.free_body import T_END, first_calls_fresh
from liegroup_int.bench.table import markdown, parser


def main(argv=None):
    ap = parser(__doc__, quick_help="rkmk4 only, over 0.1 s")
    ap.add_argument("methods", nargs="*", default=["rkmk4", "rkmk45"])
    args = ap.parse_args(argv)
    methods, t_end = (["rkmk4"], 0.1) if args.quick else (args.methods, T_END)
    res = [first_calls_fresh(m, t_end) for m in methods]
    print(markdown(["method", "span [s]", "first call CPU s", "second call CPU s", "compile s (difference)"],
                   [[r["method"], t_end, r["first"], r["second"], r["first"] - r["second"]] for r in res]))
    return res


if __name__ == "__main__":
    main()
