"""Compiled (numba) kernels of the beam plugin, one module per concern: :mod:`.vec3`
(3-vector helpers), :mod:`.band` (banded solves, basis windows), :mod:`.profiles` (load
time profiles), :mod:`.physics` (pointwise strains, resultants, load power),
:mod:`.collocation` and :mod:`.galerkin` (each formulation's rates and actions),
:mod:`.adapters` (named data and the compiled engine's views)."""
