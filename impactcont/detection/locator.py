"""The one locator of special and codim-2 points: a test function's zero on a step.

:func:`locate_zero` lives in the core (:mod:`impactcont.core.locate`) and is
re-exported here with the decision :func:`is_critical`.

Every detector (N-1 branches, N-p branches, codim-1 curves) parametrises the
branch between two accepted points by one coordinate (a chord coordinate, the
parameter or the phase), evaluates a test function there (each trial point is
corrected onto the branch by :func:`impactcont.core.solve_on_hyperplane` or the
curve's augmented Newton) and hands it to :func:`locate_zero`. Whether the zero
is a bifurcation is decided from the multipliers there (:func:`is_critical`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np

from impactcont.core.locate import Event, MotionTest, locate_zero
from impactcont.problems.events import MULTIPLIER_CRITERIA
from impactcont.vocabulary import STATUSES, Label

log = logging.getLogger(__name__)

_Point = TypeVar("_Point")

__all__ = ["COMPANIONS", "STATUSES", "TWIN_OF", "TWIN_TOL", "drop_grazing_at_zero_velocity",
           "drop_twins", "is_critical", "kind_event", "last_motions", "locate_zero", "twins",
           "watched_labels"]


def is_critical(label: str, multipliers: np.ndarray, unit_tol: float) -> bool:
    """Whether the multipliers at a zero of the PD or NS test make it a bifurcation.

    PD: a multiplier within `unit_tol` of -1 (``det(G + I)`` also changes sign
    through the pole of G). NS: a complex pair within `unit_tol` of the unit circle (a
    real reciprocal pair is a neutral saddle; ``sqrt(unit_tol)``, 3e-4, let a pair at
    ``|mu| - 1 = 1e-5`` next to a zero-velocity impact pass). Other labels: always.
    The criteria are the kinds' (:data:`~impactcont.problems.events.MULTIPLIER_CRITERIA`).
    """
    criterion = MULTIPLIER_CRITERIA.get(label)
    return True if criterion is None else criterion(multipliers, unit_tol)


#: The points a kind's zero is when both are located on one step (:func:`drop_twins`): the
#: kinds each kind is absorbed by (:attr:`~impactcont.vocabulary.Label.absorbs`). A GR at a
#: ZV is the grazing of the zero-velocity impact; an RG or an SO at an SE is the end of a
#: sticking phase (the landing is the release there, so the pressing force at the landing
#: and the smallest one inside the stick vanish with the stick time); an RG at an SO is the
#: onset of complete chatter on a stick entered through chatter (the accumulation point
#: reaches the release: the held phase shrinks to nothing); a ZV, GR, RG or SO at an FT is
#: the end of a flight (the impact ending it arrives at rest, the flight's clearance and
#: the landing's pressing force vanish with it).
TWIN_OF: dict[str, tuple[Label, ...]] = {
    label: twins_of for label in Label
    if (twins_of := tuple(kind for kind in Label if label.value in kind.absorbs))}

#: The kinds a detector also watches when one is asked for: ZV with GR, SE (and SO) with
#: RG, SE with SO, FT with each of those, whose located points tell which point is the
#: other's twin (dropped, :func:`drop_twins`, also when the twin's kind is not asked for).
COMPANIONS: dict[str, tuple[Label, ...]] = dict(TWIN_OF)


def watched_labels(labels: Sequence[str]) -> list[str]:
    """The labels a detector locates for `labels`: each with its :data:`COMPANIONS`."""
    out = list(labels)
    for label in labels:
        out.extend(extra for extra in COMPANIONS.get(label, ()) if extra not in out)
    return out


def kind_event(label: str, test: MotionTest, at: Callable[[Any, float], Any],
               sample_orbit: Callable[[int], Any]) -> Event:
    """The event of a kind declared with its `test` (a function of the motion).

    Parameters
    ----------
    label : str
        The kind.
    test : MotionTest
        Its test, rounding and poles as functions of the motion.
    at : callable
        ``at(u, lam)``: the motion at a point of the branch (one with the
        interior-contact search when ``test.checks``).
    sample_orbit : callable
        ``sample_orbit(k)``: the motion at accepted point ``k``.
    """
    fields: dict[str, Any] = {}
    if test.poles is not None:
        poles = test.poles
        fields = dict(poles=lambda u, lam: poles(at(u, lam)),
                      poles_at=lambda k: poles(sample_orbit(k)))
    if test.noise is not None:
        fields["noise_at"] = lambda u, lam, n=test.noise: n(at(u, lam))
    return Event(label, lambda u, lam: test.test(at(u, lam)),
                 lambda k: test.test(sample_orbit(k)),
                 None if test.noise is None else lambda k: test.noise(sample_orbit(k)),
                 **fields)


#: a GR this close (relative) to a ZV on the same step is its grazing (an RG or SO to an
#: SE, its end of a sticking phase): the square root of the GR test's rounding (a double
#: zero) is 1e-8..1e-7
TWIN_TOL = 1e-6


def twins(distance: float, precisions: float, scale: Any) -> bool:
    """Whether a point `distance` from its located twin (same step; a GR from a ZV) is
    that point: within the two points' `precisions` or :data:`TWIN_TOL` times the size of
    where they are."""
    return distance <= max(precisions, TWIN_TOL * max(1.0, float(np.max(np.abs(scale)))))


def drop_twins(points: Sequence[_Point], parameter: str = "lam") -> list[_Point]:
    """The special points without each one that is the twin of another (:data:`TWIN_OF`).

    GR at ZV: an impact whose velocity ``h2`` passes through zero is itself a grazing
    contact: on the side ``h2 < 0`` the free flight reaches its maximum
    ``x = b + h2^2 / (2 |a|)`` just before the impact (``a`` the acceleration there), so
    the GR test function (the smallest clearance inside the flights) is
    ``-h2^2 / (2 |a|)`` near the ZV point and touches zero quadratically there. When the
    clearance on the other side is finite and positive (another flight's maximum, N-p
    motions) the GR test changes sign at the ZV point and is located there, but only to
    about the square root of its rounding noise (1e-9..1e-7 instead of 1e-14): one
    codim-1 point, the grazing impact, found twice. It is reported once, as the ZV (its
    test ``h2`` is simple).

    RG and SO at SE: where a stick time passes through 0 (SE) the plastic impact lands
    at the release, so the pressing force at the landing (SO's test) and the smallest
    inside the stick (RG's, which counts the landing's for a stick of no duration)
    vanish at the same point: one point, the end of the sticking phase, reported once,
    as the SE. RG at SO: on a stick entered through complete chatter the held phase
    shrinks to nothing where the pressing force at the accumulation point passes through
    0 (the onset of complete chatter; the stick time, counted from the landing, does not
    vanish there): one point, reported once, as the SO.

    ZV, GR, RG and SO at FT: where a flight time passes through 0 the impact ending the
    flight arrives at rest, and the flight's clearance and the pressing force of the stick
    it lands on vanish with it: one point, the end of the flight, reported once, as the FT.

    A point is dropped when its twin was located on the same step within the two points'
    precisions (at least :data:`TWIN_TOL` relative: on the side where no flight has an
    interior maximum the GR test is +inf, and the precision search sees only one side of
    the double zero), or, when its twin is a singular point of the branch's system
    (:attr:`~impactcont.vocabulary.Label.singular`: FT), when it is only bracketed on that
    step (the locator cannot follow the branch inside it, so no other zero of its kind can
    be told from the twin's there); every other point is kept, in order.
    """
    kinds = {kind for twins_of in TWIN_OF.values() for kind in twins_of}
    located = [z for z in points if z.label in kinds and z.status == "located"]
    kept = []
    for point in points:
        twin = None
        if point.label in TWIN_OF:
            twin = next((z for z in located if z.label in TWIN_OF[point.label]
                         and z.bracket == point.bracket and (twins(
                             abs(z.value - point.value), z.precision + point.precision,
                             z.value) or (Label(z.label).singular
                                          and point.status != "located"))), None)
        if twin is None:
            kept.append(point)
        else:
            log.info("%s at %s=%.12g (precision %.1e, %s) is the %s at %.12g: reported once, "
                     "as %s", point.label, parameter, point.value, point.precision,
                     point.status, twin.label, twin.value, twin.label)
    return kept


#: The name of :func:`drop_twins` when GR at ZV was its only pair.
drop_grazing_at_zero_velocity = drop_twins


def last_motions(orbit: Callable[[Any, float], Any], size: int = 8
                 ) -> Callable[[Any, float], Any]:
    """`orbit` remembering its last few motions: the test, its poles and its noise at a
    trial point of a locator share one (each a shot or a closed form)."""
    cache: dict[tuple[bytes, float], Any] = {}

    def at(u: Any, lam: float) -> Any:
        key = (np.asarray(u, dtype=float).tobytes(), float(lam))
        if key not in cache:
            if len(cache) >= size:
                cache.pop(next(iter(cache)))
            cache[key] = orbit(u, lam)
        return cache[key]
    return at
