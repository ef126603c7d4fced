"""The one place where ``liegroup_int.bench`` reaches past the beam plugin's public package
(the names ``liegroup_int.problems.beam`` exports): the Kelvin-Voigt damping sizing and the
list of spatial formulations. Should the plugin's modules move, this file is the one to
update; the benchmark scripts themselves use only the public plugin contract."""

from ..problems.beam.damping import first_frequency, size_kelvin_voigt
from ..problems.beam.problem import ALL_FORMULATIONS

__all__ = ["ALL_FORMULATIONS", "first_frequency", "size_kelvin_voigt"]
