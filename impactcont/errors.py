"""Exception and warning types of impactcont.

Every error raised for bad user input names the argument, the value received
and what is allowed. Every warning says why a number may be inexact and how
inexact; the accuracy warnings all derive from :class:`IllConditionedWarning`,
so ``warnings.simplefilter("error", IllConditionedWarning)`` turns them all into
errors.
"""

from __future__ import annotations

__all__ = [
    "IllConditionedWarning",
    "ImpactcontError",
    "LowImpactVelocityWarning",
    "NearFoldWarning",
    "NearResonanceWarning",
    "NoPeriodicMotionError",
    "ParameterError",
    "ResonanceError",
    "UnresolvedMotionWarning",
]


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


class IllConditionedWarning(RuntimeWarning):
    """A linear solve of the closed form is ill-conditioned; the result may be inexact."""


class NearResonanceWarning(IllConditionedWarning):
    """The forcing frequency is so close to the natural frequency of a (nearly) undamped
    mode that the forced response of eq. (7) is known only to the stated relative error.
    """


class NearFoldWarning(IllConditionedWarning):
    """``c^2 + s^2`` is within rounding of ``b^2`` (eq. 15): the two roots merge at a fold
    and the impact phase is determined only to about ``eps / sqrt(1 - b^2/(c^2 + s^2))``.
    """


class LowImpactVelocityWarning(IllConditionedWarning):
    """The impact velocity ``h2`` is tiny against the velocities of the motion: G of
    eq. (25) grows like ``1/h2`` and its relative error like ``eps * |v| / |h2|``.
    """


class UnresolvedMotionWarning(RuntimeWarning):
    """The search grid for the interior maxima of ``x1`` (eq. 16) was capped below the
    resolution of the fastest motion: a short excursion past the stop may be missed.
    """
