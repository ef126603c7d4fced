"""Errors of the problem models, carrying what is wrong as data."""

from __future__ import annotations


class ParameterError(ValueError):
    """A model parameter with an invalid value.

    Attributes
    ----------
    field : str
        The parameter's name in the model (``"E"``, ``"inertia"``, ...); scenes map it to
        their key.
    reason : str
        What is wrong with it (``"expected a positive density, got -1"``).
    """

    def __init__(self, field: str, reason: str):
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason
