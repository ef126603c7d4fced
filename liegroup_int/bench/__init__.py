"""Benchmarks shipped with the package: work-precision of beam scenes against PyElastica
(``liegroup-int bench SCENE``), and what the scripts in ``benchmarks/`` share.

Modules: ``plans`` and ``work_precision`` (the work-precision study), ``pyelastica_peer``
(the PyElastica set-ups, imported only when a peer run is requested), ``stability``
(stability maps), ``timing`` (best-of timing), ``table`` (Markdown tables and the
``--quick``/``--out`` command line), ``beam_step`` (the timed cantilever set-up),
``free_body`` (the README's free rigid body in four right-hand-side forms),
``asm_flops`` (flop counts read from compiled kernels' assembly) and ``beam_internals``
(the one access point past the beam plugin's public package)."""

from .plans import PLANS, QUICK, Plan, plan_for
from .work_precision import Result, Run, markdown, plot, ratios, tip_error, work_precision, write

__all__ = ["Plan", "PLANS", "QUICK", "plan_for", "Run", "Result", "work_precision", "markdown", "plot", "write",
           "ratios", "tip_error"]
