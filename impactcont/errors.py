"""Exception types of impactcont.

Every error raised for bad user input names the argument, the value received
and what is allowed.
"""

from __future__ import annotations

__all__ = ["ImpactcontError", "NoPeriodicMotionError", "ParameterError", "ResonanceError"]


class ImpactcontError(Exception):
    """Base class of the errors raised by impactcont."""


class ParameterError(ImpactcontError, ValueError):
    """An argument has a value outside the allowed set."""


class ResonanceError(ParameterError):
    """The forcing frequency equals the natural frequency of an undamped mode.

    The steady forced response of eq. (6) does not exist (Δ_i = 0).
    """


class NoPeriodicMotionError(ImpactcontError, ValueError):
    """A requested periodic motion does not exist at the given parameters."""
