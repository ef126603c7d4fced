"""Benchmarks shipped with the package: work-precision of beam scenes against PyElastica
(``liegroup-int bench SCENE``). The PyElastica set-ups (``pyelastica_peer``) are imported
only when a peer run is requested."""

from .plans import PLANS, QUICK, Plan, plan_for
from .work_precision import Result, Run, markdown, plot, ratios, tip_error, work_precision, write

__all__ = ["Plan", "PLANS", "QUICK", "plan_for", "Run", "Result", "work_precision", "markdown", "plot", "write",
           "ratios", "tip_error"]
