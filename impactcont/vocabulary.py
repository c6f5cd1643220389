"""The words of impactcont, defined once: special-point labels and the parameter table.

Every module that names a special point or checks a parameter uses this module:
the labels of the special points (:class:`Label`), the codimension-two labels, the
continuable parameters with their allowed ranges, units and the damping each
needs (:data:`PARAMETERS`), and the rule that ``eta`` (``C = 2 eta K``, the
paper's damping) and the Rayleigh coefficients ``alpha, beta``
(``C = alpha M + beta K``) exclude each other (:func:`check_damping`); and the one
refusal of a number of periods, impacts or a mass's number that is not an integer
``>= 1`` (:func:`check_positive_integer`).
"""

from __future__ import annotations

import dataclasses
import enum
import math
import re
from collections.abc import Iterator, Mapping
from numbers import Integral, Real
from typing import Any

from impactcont.errors import ParameterError

__all__ = [
    "CODIM2_LABELS",
    "CONTINUABLE_PARAMETERS",
    "CURVE_KINDS",
    "ELEMENT_FAMILIES",
    "LABELS",
    "LABEL_COLOURS",
    "LABEL_MARKERS",
    "LABEL_NAMES",
    "PARAMETERS",
    "STATUSES",
    "STOP_FAMILIES",
    "Label",
    "Parameter",
    "ParameterTable",
    "check_bounds",
    "check_damping",
    "check_labels",
    "check_parameter",
    "check_positive_integer",
    "damping_kind",
    "element_name",
    "stop_parameter_name",
]


class Label(str, enum.Enum):
    """A kind of special point of a branch (a codim-1 point of the two-parameter plane).

    Each kind is an object carrying what every module says of it: its ``marker`` in
    figures (a matplotlib marker code), its ``colour`` (its curves in two-parameter
    figures), its ``words`` (legends), its ``codimension`` (1: one condition on a branch)
    and whether it has ``curves`` of every motion (two-parameter continuation,
    :data:`CURVE_KINDS`; BP, SE, RG, SO and FT have curves of their motions only:
    :data:`impactcont.problems.codim1.SHOOTING_KINDS`); the kinds it ``absorbs`` (a point of
    such a kind located on the same step at one of this kind is this one, reported once:
    :data:`impactcont.detection.locator.TWIN_OF`), whether its test ``bounds`` the physical
    motions (past its zero a motion is not physical: a curve of a motion with sticking
    phases ends where such a test changes sign) and whether its points are ``singular``
    points of a branch's system (the shooting system is degenerate there, so a step across
    one is not followed by Newton: its zero is interpolated from the branch on both sides,
    and the other kinds' sign changes on that step or beyond it among motions past it are
    not told apart from it: :mod:`impactcont.detection.special_points`).
    How a problem detects it
    (its test function, rounding noise and criticality) is declared by the problem
    (:mod:`impactcont.problems.events`; the points that bound a sticking phase, ``SE``,
    ``RG`` and ``SO``, by a branch problem of motions with sticking phases,
    :data:`impactcont.problems.multi_impact_branch.STICKING_TESTS`).
    A problem that does not declare a kind never reports it: ``detect=`` may name every
    kind on every branch.

    Notes
    -----
    The members are strings (``Label.PD == "PD"``), so comparisons with the labels
    stored in datasets keep working.
    """

    marker: str
    words: str
    colour: str
    codimension: int
    curves: bool
    absorbs: tuple[str, ...]
    bounds: bool
    singular: bool

    def __new__(cls, value: str, marker: str, words: str, colour: str, curves: bool = True,
                absorbs: str = "", bounds: bool = False, singular: bool = False) -> Label:
        kind = str.__new__(cls, value)
        kind._value_ = value
        kind.marker, kind.words, kind.colour, kind.codimension = marker, words, colour, 1
        kind.curves, kind.absorbs = curves, tuple(absorbs.split())
        kind.bounds, kind.singular = bounds, singular
        return kind

    SN = ("SN", "o", "saddle-node", "black")
    """Saddle-node (fold): a multiplier crosses +1 (eq. 25)."""
    PD = ("PD", "s", "period doubling", "tab:red")
    """Period-doubling (flip): a multiplier crosses -1."""
    NS = ("NS", "D", "Neimark-Sacker", "tab:purple")
    """Neimark-Sacker: a pair of complex multipliers crosses the unit circle."""
    GR = ("GR", "^", "grazing", "tab:green", True, "", True)
    """Grazing: mass 1 touches the stop between impacts (eq. 16 with equality)."""
    ZV = ("ZV", "v", "zero-velocity impact", "tab:blue", True, "GR", True)
    """Zero-velocity impact: the impact velocity h2 of eq. (22) vanishes. A grazing located
    with it is the grazing of that impact (the GR test touches 0 quadratically there)."""
    BP = ("BP", "P", "symmetry-breaking pitchfork", "tab:orange", False)
    """Symmetry-breaking pitchfork of a symmetric motion of a symmetric two-sided system:
    a multiplier of its half-map crosses -1 (G gets +1 without a fold) and a pair of
    asymmetric motions, mirror images, branches off (:mod:`impactcont.orbit.symmetry`)."""
    SE = ("SE", "X", "end of a sticking phase", "tab:brown", False, "RG SO", True)
    """End of a sticking phase (the end of a ride): a stick time of a motion with sticking
    phases passes through 0, the plastic impact landing where the stop stops pressing its
    coordinate, so that the landing is itself a release; beyond it the motion would stick
    for a negative time (not physical). Only branches of motions with sticking phases have
    it (:func:`impactcont.problems.multi_impact_branch.stick_end_test`). A release grazing
    or a sticking onset located with it is that end (the landing is the release there)."""
    RG = ("RG", "p", "release grazing", "tab:pink", False, "", True)
    """Release grazing: the pressing force of a stop on the coordinate it holds touches 0
    inside a sticking phase (a release that almost happens early; beyond it the mass
    leaves there: another motion). Branches of motions with sticking phases only
    (:func:`impactcont.problems.multi_impact_branch.release_grazing_test`)."""
    SO = ("SO", "h", "sticking onset", "tab:olive", False, "RG", True)
    """Sticking onset: the pressing force right after a plastic impact that starts a
    sticking phase passes through 0 (the acceleration tangent to the stop at the
    landing: on one side the stop holds the coordinate, on the other the mass leaves at
    once). Branches of motions with sticking phases only
    (:func:`impactcont.problems.multi_impact_branch.sticking_onset_test`). A release
    grazing located with it on a stick entered through chatter is that onset."""
    FT = ("FT", "<", "end of a flight", "tab:cyan", False, "ZV GR RG SO", True, True)
    """End of a flight: a flight time of a motion passes through 0, two consecutive
    contacts merging (an impact and the next, or a release and the landing after it:
    the ball on a table as the forcing just lifts it). The impact ending the vanishing
    flight arrives at zero velocity and the flight's clearance and the stick's pressing
    force vanish with it, so a ZV, GR, RG or SO located there is this point; beyond it
    the motion would fly for a negative time (not physical). The shooting system is
    singular there (the impact condition of a flight of length tau is of order tau^3),
    so its zero is interpolated from the branch on both sides
    (:data:`impactcont.problems.events.FLIGHT_END`). A one-impact motion's one flight
    lasts its period: only motions with several contacts per period have it."""

    def __str__(self) -> str:
        return str(self.value)

    def __repr__(self) -> str:  # as the label's string: messages list kinds as the user types them
        return repr(self.value)

    __format__ = str.__format__


#: The special-point labels as plain strings, in their canonical order.
LABELS: tuple[str, ...] = tuple(label.value for label in Label)

#: The marker of each label in figures (matplotlib marker codes): :attr:`Label.marker`.
LABEL_MARKERS: dict[str, str] = {label.value: label.marker for label in Label}

#: What each label stands for, in words (legends): :attr:`Label.words`.
LABEL_NAMES: dict[str, str] = {label.value: label.words for label in Label}

#: The colour of each kind's curves in two-parameter figures: :attr:`Label.colour`.
LABEL_COLOURS: dict[str, str] = {label.value: label.colour for label in Label}

#: The kinds of codimension-one curves of every motion (two-parameter continuation of a
#: special point): the labels with :attr:`Label.curves`, every one but ``BP``, which exists
#: only on symmetric N-p motions, ``SE``, ``RG``, ``SO``, which bound the motions with
#: sticking phases, and ``FT``, which bounds motions with several contacts per period.
#: Those five have curves too, of their motions only, followed by
#: shooting (:data:`impactcont.problems.codim1.SHOOTING_KINDS`, whose table declares each
#: curve kind's test function and the codim-2 tests it watches); ``curves=False`` keeps
#: them out of the kinds a curve of any motion (an N-1 curve in closed form, a scene's
#: ``[[curves]]``, a curve dataset's ``kind``) may have. The members are the kinds
#: themselves.
CURVE_KINDS: tuple[Label, ...] = tuple(label for label in Label if label.curves)

#: Codimension-two points, one name per point: ``A+B`` is where a curve of kind A meets
#: the curve of kind B (its test function vanishes on the curve A); ``R1`` and ``R2``
#: are the 1:1 and 1:2 strong resonances (a double multiplier +1, a double -1), whichever
#: curve meets them: the end of a Neimark-Sacker curve (theta -> 0, pi), or a second
#: multiplier +1 on an SN curve (``R1``), a second -1 on a PD curve (``R2``). Files
#: written before carry ``SN+SN`` and ``PD+PD`` for these; they read as ``R1``, ``R2``
#: (:data:`impactcont.dataset.curves.CODIM2_FORMER_LABELS`). The standard name of each
#: label (MatCont's LPPD, LPNS, ...) is in ``docs/two_parameter.md``.
CODIM2_LABELS: tuple[str, ...] = (
    "SN+ZV", "SN+GR", "SN+PD", "SN+NS",
    "PD+ZV", "PD+GR", "PD+SN", "PD+NS",
    "NS+ZV", "NS+GR", "NS+SN", "NS+PD", "R1", "R2",
    "GR+ZV", "GR+GR", "GR+SN", "GR+PD", "GR+NS",
    "ZV+SN",
    # curves of motions with sticking phases (SE: a stick time 0; RG: a pressing force
    # touching 0 inside a stick; SO: the pressing force 0 at a landing), and the curves of
    # every motion followed on such motions meeting them
    "SE+ZV", "SE+GR", "SE+SN", "SE+PD", "SE+NS",
    "RG+SE", "RG+SO", "RG+ZV", "RG+GR", "RG+SN", "RG+PD", "RG+NS",
    "SO+SE", "SO+ZV", "SO+GR", "SO+SN", "SO+PD", "SO+NS",
    "SN+SE", "SN+RG", "SN+SO", "PD+SE", "PD+RG", "PD+SO",
    "NS+SE", "NS+RG", "NS+SO", "GR+SE", "GR+RG", "GR+SO",
)

#: How well a special point is known: ``located`` (refined to its precision) or
#: ``bracketed`` (only known to lie between two accepted points).
STATUSES: tuple[str, ...] = ("located", "bracketed")


def check_positive_integer(argument: str, value: Any, meaning: str = "") -> int:
    """`value` as an int ``>= 1``: a number of forcing periods ``N``, of impacts ``p``, a
    mass's number, ...

    Parameters
    ----------
    argument : str
        The argument's name in error messages.
    value : object
        What the caller gave: an integer (Python's or NumPy's; a bool is none).
    meaning : str, optional
        What the integer counts, said in the message (``"impact every N forcing periods"``).

    Raises
    ------
    ParameterError
        ``"<argument> must be an integer >= 1 (<meaning>); got <value>"``.
    """
    if isinstance(value, bool) or not isinstance(value, Integral) or value < 1:
        raise ParameterError(f"{argument} must be an integer >= 1"
                             f"{f' ({meaning})' if meaning else ''}; got {value!r}")
    return int(value)


def check_labels(detect: Any, argument: str = "detect") -> list[str]:
    """The labels of `detect` as a list of str, refused unless all are known.

    Raises
    ------
    ParameterError
        Naming `argument`, the unknown labels and the allowed ones.
    """
    if isinstance(detect, str):
        raise ParameterError(f"{argument} must be a sequence of labels; got the string "
                             f"{detect!r}")
    labels = [str(label) for label in detect]
    unknown = sorted(set(labels) - set(LABELS))
    if unknown:
        raise ParameterError(f"{argument}: labels must be a subset of {LABELS}; got unknown "
                             f"{unknown}")
    return labels


@dataclasses.dataclass(frozen=True, slots=True)
class Parameter:
    """One scalar parameter of the oscillator that can be continued.

    Attributes
    ----------
    name : str
        As in the paper and as the attribute of :class:`ImpactOscillator`.
    long_name, description : str
        Readable name and one sentence with the equation it enters.
    unit : str
        ``"1"``: the model is nondimensional.
    low, high : float
        Allowed range; ``low_open`` excludes ``low`` itself.
    allowed : str
        The range in words, for error messages.
    damping : {"eta", "rayleigh", None}
        The damping model the parameter belongs to (``None``: any).
    """

    name: str
    long_name: str
    description: str
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    allowed: str = "a finite real number"
    unit: str = "1"
    damping: str | None = None

    def contains(self, value: float) -> bool:
        """Whether `value` lies in the allowed range (finite)."""
        if not math.isfinite(value):
            return False
        above = value > self.low if self.low_open else value >= self.low
        return above and value <= self.high

    @property
    def domain(self) -> tuple[float, float]:
        """The closed interval of representable allowed values."""
        low = math.nextafter(self.low, math.inf) if self.low_open else self.low
        return low, self.high


_NONNEGATIVE = dict(low=0.0, allowed="finite and >= 0")
_POSITIVE = dict(low=0.0, low_open=True, allowed="finite and > 0")


class ParameterTable(Mapping[str, Parameter]):
    """The continuable parameters: a table of names, and the element families.

    Iterating gives the named parameters (omega, b, R, ...); a lookup also resolves the
    names of elements (:data:`ELEMENT_FAMILIES`, 1-based as the paper's masses):
    ``m2`` (a mass), ``k1`` (a spring of the chain of eq. 2), ``c1`` (a damper),
    ``M[1,2]``, ``K[1,2]``, ``C[1,2]`` (an entry and its symmetric partner), ``F[2]``
    (the forcing amplitude of one mass), and the names of an extra stop's own data
    (:data:`STOP_FAMILIES`: ``gap[A]``, ``R[A]`` of the stop named ``A``). Whether an
    element or a stop exists on a given oscillator is checked by
    :func:`impactcont.model.parameters.model_parameter`.
    """

    def __init__(self, named: dict[str, Parameter]) -> None:
        self._named = named

    def __getitem__(self, name: str) -> Parameter:
        hit = self._named.get(name) if isinstance(name, str) else None
        if hit is not None:
            return hit
        element = element_name(name)
        if element is not None:
            family, indices = element
            return _element_parameter(name, family, indices)
        stop = stop_parameter_name(name)
        if stop is None:
            raise KeyError(name)
        return _stop_parameter(name, *stop)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self._named or element_name(name) is not None
                                          or stop_parameter_name(name) is not None)

    def __iter__(self) -> Iterator[str]:
        return iter(self._named)

    def __len__(self) -> int:
        return len(self._named)


#: The element families: name pattern -> (long name, description, range keywords).
ELEMENT_FAMILIES: dict[str, tuple[str, str, dict[str, Any]]] = {
    "m<j>": ("mass", "Mass m_j of the chain of eq. (2): the entry M[j,j] of a diagonal M.",
             _POSITIVE),
    "k<j>": ("spring", "Spring k_j of the chain of eq. (2): between masses j and j+1, k_n "
             "from mass n to the ground.", _POSITIVE),
    "c<j>": ("damper", "Damper c_j of a chain damping matrix C (laid out as the springs of "
             "eq. 2).", _NONNEGATIVE),
    "M[i,j]": ("mass matrix entry", "Entry M[i,j] = M[j,i] of the mass matrix (eq. 1).", {}),
    "K[i,j]": ("stiffness matrix entry", "Entry K[i,j] = K[j,i] of the stiffness matrix "
               "(eq. 1).", {}),
    "C[i,j]": ("damping matrix entry", "Entry C[i,j] = C[j,i] of a damping matrix C "
               "(eq. 1).", {}),
    "F[j]": ("forcing amplitude of one mass", "Entry F_j of the forcing vector F of eq. (1).",
             {}),
}

_ELEMENT = re.compile(r"^(?:([mkc])([1-9][0-9]*)|([MKC])\[([1-9][0-9]*),([1-9][0-9]*)\]"
                      r"|F\[([1-9][0-9]*)\])$")


def element_name(name: Any) -> tuple[str, tuple[int, ...]] | None:
    """``(family, 1-based indices)`` of an element name (``"k2"`` -> ``("k<j>", (2,))``,
    ``"M[1,2]"`` -> ``("M[i,j]", (1, 2))``), None for any other name."""
    match = _ELEMENT.match(name) if isinstance(name, str) else None
    if match is None:
        return None
    letter, j, matrix, i1, i2, f = match.groups()
    if letter:
        return f"{letter}<j>", (int(j),)
    if matrix:
        return f"{matrix}[i,j]", (int(i1), int(i2))
    return "F[j]", (int(f),)


def _element_parameter(name: str, family: str, indices: tuple[int, ...]) -> Parameter:
    long_name, description, limits = ELEMENT_FAMILIES[family]
    where = ",".join(str(i) for i in indices)
    return Parameter(name, f"{long_name} {name}", f"{description} (here {where}.)", **limits)


#: The data of one extra stop (:class:`impactcont.model.stops.Stop`, named by one letter
#: ``S`` other than U/L): name pattern -> (long name, description, range keywords).
STOP_FAMILIES: dict[str, tuple[str, str, dict[str, Any]]] = {
    "gap[S]": ("gap of an extra stop", "Gap of the extra stop S: it sits at s = side * gap on "
               "its own coordinate (eq. 3 on that coordinate).", {}),
    "R[S]": ("restitution of an extra stop", "Coefficient of restitution of the extra stop S "
             "(eq. 4 on its coordinate; the two-body law for a pair).",
             dict(low=0.0, high=1.0, allowed="in [0, 1]")),
}

_STOP = re.compile(r"^(gap|R)\[([A-Za-z])\]$")


def stop_parameter_name(name: Any) -> tuple[str, str] | None:
    """``(family, stop name)`` of an extra stop's parameter name (``"gap[A]"`` ->
    ``("gap[S]", "A")``, ``"R[B]"`` -> ``("R[S]", "B")``), None for any other name.

    Whether the oscillator has that stop (and that it is not ``U`` or ``L``, whose data
    are ``b``, ``R``, ``b_low``, ``R_low``) is checked by
    :func:`impactcont.model.parameters.model_parameter`."""
    match = _STOP.match(name) if isinstance(name, str) else None
    if match is None:
        return None
    kind, letter = match.groups()
    return f"{kind}[S]", letter


def _stop_parameter(name: str, family: str, stop: str) -> Parameter:
    long_name, description, limits = STOP_FAMILIES[family]
    return Parameter(name, f"{long_name} {stop}", description.replace(" S", f" {stop}", 1),
                     **limits)


#: The continuable parameters, in the order of the API documentation; a lookup also
#: resolves the element names (:class:`ParameterTable`).
PARAMETERS: ParameterTable = ParameterTable({p.name: p for p in (
    Parameter("omega", "forcing frequency", "Nondimensional forcing frequency omega of eq. (1).",
              low=0.0, low_open=True, allowed="finite and > 0"),
    Parameter("b", "gap", "Position b of the stop met by mass 1 (eq. 3)."),
    Parameter("R", "coefficient of restitution",
              "Coefficient of restitution R of the impact law (eq. 4).",
              low=0.0, high=1.0, allowed="in [0, 1]"),
    Parameter("eta", "damping coefficient", "Damping eta of C = 2 eta K.", damping="eta",
              **_NONNEGATIVE),
    Parameter("alpha", "Rayleigh mass damping", "alpha of C = alpha M + beta K.",
              damping="rayleigh", **_NONNEGATIVE),
    Parameter("beta", "Rayleigh stiffness damping", "beta of C = alpha M + beta K.",
              damping="rayleigh", **_NONNEGATIVE),
    Parameter("F0", "forcing amplitude",
              "Amplitude of the periodic forcing F of eq. (1), the largest |F_i|; "
              "changing it scales F and keeps its shape.",
              low=0.0, low_open=True, allowed="finite and > 0"),
    Parameter("b_low", "gap of the lower stop",
              "Position -b_low of the lower stop x_j = -b_low (stops.b_low; docs/two_sided.md)."),
    Parameter("R_low", "restitution of the lower stop",
              "Coefficient of restitution of the lower stop (stops.R_low), eq. (4) there.",
              low=0.0, high=1.0, allowed="in [0, 1]"),
    Parameter("gap", "symmetric clearance",
              "b and b_low together: the stops x_j = +-gap of a symmetric clearance.",
              low=0.0, low_open=True, allowed="finite and > 0"),
)})

#: Names of the continuable parameters (the element names are patterns:
#: :data:`ELEMENT_FAMILIES`).
CONTINUABLE_PARAMETERS: tuple[str, ...] = tuple(PARAMETERS)


def damping_kind(osc: Any) -> str:
    """``"eta"`` when `osc` uses the paper's damping ``C = 2 eta K``, ``"matrix"`` for a
    general damping matrix C, else ``"rayleigh"``."""
    if getattr(osc, "general_damping", False):
        return "matrix"
    return "eta" if osc.eta is not None else "rayleigh"


def check_damping(osc: Any, name: str, argument: str = "parameter") -> None:
    """Refuse a parameter of the other damping model than the oscillator's.

    ``eta`` exists only with ``C = 2 eta K``, ``alpha`` and ``beta`` only with
    Rayleigh damping ``C = alpha M + beta K``.

    Raises
    ------
    ParameterError
        Naming `argument`, the parameter and the oscillator's damping.
    """
    needs = PARAMETERS[name].damping if name in PARAMETERS else None
    kind = damping_kind(osc)
    if needs is None or needs == kind:
        return
    if kind == "matrix":
        raise ParameterError(f"{argument}={name!r} is meaningless with a general damping matrix "
                             f"C={osc.C.tolist()}: eta, alpha and beta exist only for C = 2 eta K "
                             "or C = alpha M + beta K; continue in omega, b, R, F0 or an element "
                             "of C ('c<j>', 'C[i,j]')")
    if needs == "rayleigh":
        raise ParameterError(f"{argument}={name!r} needs Rayleigh damping (C = alpha M + beta K); "
                             f"the oscillator uses the paper's damping C = 2 eta K "
                             f"(eta={osc.eta!r}); use 'eta' instead")
    raise ParameterError(f"{argument}={name!r} needs the paper's damping C = 2 eta K; the "
                         f"oscillator uses Rayleigh damping (alpha={osc.alpha!r}, "
                         f"beta={osc.beta!r}); use 'alpha' or 'beta' instead")


def check_parameter(osc: Any, name: Any, argument: str = "parameter") -> str:
    """`name` as a continuable parameter of `osc`: known, and of the oscillator's damping.

    Raises
    ------
    ParameterError
        Naming `argument`, the value and the allowed names.
    """
    if not isinstance(name, str) or name not in PARAMETERS:
        raise ParameterError(f"{argument} must be one of {CONTINUABLE_PARAMETERS} or an element "
                             f"{tuple(ELEMENT_FAMILIES)} (1-based, e.g. 'k2', 'M[1,2]', "
                             f"'F[2]') or an extra stop's {tuple(STOP_FAMILIES)} (e.g. "
                             f"'gap[A]'); got {name!r}")
    check_damping(osc, name, argument)
    return name


def check_bounds(parameter: str, bounds: Any, argument: str = "bounds") -> tuple[float, float]:
    """`bounds` of a continuation in `parameter`: two finite numbers ``lo < hi`` in its range.

    The one check of every driver's bounds (:func:`impactcont.continuation`,
    :func:`impactcont.multi_impact_continuation`, the curves); the range that depends on
    the rest of the oscillator (an element of K, M or C) is checked on top by
    :meth:`impactcont.model.parameters.ModelParameter.check_bounds`.

    Parameters
    ----------
    parameter : str
        A name of :data:`PARAMETERS` (element names included).
    bounds : object
        What the caller gave.
    argument : str
        The argument's name in error messages.

    Returns
    -------
    (float, float)
        ``(lo, hi)``, both in the parameter's range.

    Raises
    ------
    ParameterError
        Not two real numbers; not finite or ``lo >= hi``; outside the parameter's range
        (:attr:`Parameter.allowed`). The message names `argument` and the value.
    """
    pair = None
    if not isinstance(bounds, (str, bytes, Mapping)):
        try:
            pair = tuple(bounds)
        except TypeError:
            pair = None
    if pair is None or len(pair) != 2 or not all(
            isinstance(v, Real) and not isinstance(v, bool) for v in pair):
        raise ParameterError(f"{argument} must be two numbers (lo, hi); got {bounds!r}")
    lo, hi = (float(v) for v in pair)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ParameterError(f"{argument} must be two finite numbers with lo < hi; got "
                             f"{bounds!r}")
    table = PARAMETERS[parameter]
    if not (table.contains(lo) and table.contains(hi)):
        raise ParameterError(f"{argument} for {parameter} must lie where {parameter} is "
                             f"{table.allowed}; got {bounds!r}")
    return lo, hi
