"""The stops of the oscillator: which mass meets them, and an optional second stop below.

The paper (eq. 3-4) has one rigid stop, above mass 1: ``x1 = b`` with restitution
``R``. :class:`Stops` generalises the geometry without changing that meaning:

- ``mass``: the mass ``j`` (1-based, as the paper's "mass 1") that meets the
  stops; the upper stop is ``x_j = b`` with restitution ``R`` (the oscillator's
  own ``b`` and ``R``, eq. 3-4 with ``x1`` replaced by ``x_j``);
- ``b_low``, ``R_low``: an optional lower stop at ``x_j = -b_low``, met moving
  downwards (``x_j' < 0``), with its own restitution ``x_j'^+ = -R_low x_j'^-``
  (the impact matrix of eq. 4 with ``-R_low`` on the velocity of mass j).

- ``relative_to``: a clearance between two masses (an impact pair): both stops act on the
  relative coordinate ``s = x_j - x_k`` (``k = relative_to``), the upper at ``s = b``, the
  lower at ``s = -b_low``, with the two-body impact law (momentum conserved, restitution on
  the relative velocity, :meth:`Stops.impact_matrix`).

- ``extra``: stops on further coordinates (:class:`Stop`, e.g. a stop above mass 2 in a
  chain whose mass 1 meets ``U``: Wagg's two-degree-of-freedom impact oscillator with
  constraints on two masses), each with a one-letter name, its own coordinate (a mass or
  a pair), side, gap and restitution. An impact pattern is then a string of stop names
  (``"UA"``, ``"AUL"``); :meth:`Stops.stop` gives any stop's normal, sign, position,
  restitution and velocity jump, :attr:`Stops.names` every stop's name.

Every path reads the geometry through :meth:`Stops.normal` (the stop coordinate is
``s = normal . x``) and :meth:`Stops.impact_matrix` (the velocity jump ``v+ = D v``).

A two-sided clearance (backlash) of total width ``b + b_low`` is ``b_low`` given;
the symmetric case is ``b_low = b``, and ``mirror=True`` keeps it symmetric when ``b``
or ``R`` change (the lower stop at ``-b`` with restitution ``R``: continuing such a
system in ``b`` widens the backlash on both sides). An impact is labelled ``"U"`` (upper stop)
or ``"L"`` (lower stop); an N-p motion's impact sequence is a string of these
(:data:`UPPER`, :data:`LOWER`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import weakref
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from impactcont.errors import ParameterError
from impactcont.vocabulary import check_positive_integer

__all__ = ["LOWER", "UPPER", "Stop", "StopView", "Stops", "check_pattern",
           "require_forcing", "require_paper_stops", "sticking_pattern"]

#: Relative allowance of the test ``normal . u_free != 0`` (a free mode touched by a stop).
TOUCH_RTOL = 1e-10

#: Label of an impact on the upper stop ``x_j = b``.
UPPER = "U"
#: Label of an impact on the lower stop ``x_j = -b_low``.
LOWER = "L"


def _finite(name: str, value: Any, *, low: float | None = None, high: float | None = None,
            allowed: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number ({allowed}); got {value!r}")
    x = float(value)
    if not math.isfinite(x) or (low is not None and x < low) or (high is not None and x > high):
        raise ParameterError(f"{name} must be {allowed}; got {value!r}")
    return x


def _normal_of(mass: int, relative_to: int | None, n: int) -> np.ndarray:
    out = np.zeros(n)
    out[mass - 1] = 1.0
    if relative_to is not None:
        out[relative_to - 1] = -1.0
    return out


def _jump(M: np.ndarray, mass: int, relative_to: int | None, R: float) -> np.ndarray:
    """``D`` of ``v+ = D v`` at a stop on ``x_j`` (eq. 4) or on ``x_j - x_k`` (two-body law)."""
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    if relative_to is None:
        D = np.eye(n)
        D[mass - 1, mass - 1] = -float(R)
        return D
    nrm = _normal_of(mass, relative_to, n)
    minv_n = np.linalg.solve(M, nrm)
    return np.eye(n) - (1.0 + float(R)) * np.outer(minv_n, nrm) / float(nrm @ minv_n)


class StopView(NamedTuple):
    """One stop in the terms every path uses (:meth:`Stops.stop`).

    Attributes
    ----------
    name : str
        ``"U"``, ``"L"`` or an extra stop's name.
    normal : ndarray, shape (n,)
        The stop coordinate ``s = normal . x``.
    sign : float
        ``+1``: met moving up (``s' > 0``) at ``s = position``; ``-1``: met moving down.
    position : float
        ``c``: the stop sits at ``s = c``.
    restitution : float
    jump : ndarray, shape (n, n)
        The velocity jump ``v+ = D v`` (eq. 4, or the two-body law for a pair).
    pivot : int
        0-based index of the stop's own mass (``normal[pivot] = 1``).
    """

    name: str
    normal: np.ndarray
    sign: float
    position: float
    restitution: float
    jump: np.ndarray
    pivot: int


@dataclasses.dataclass(frozen=True)
class Stop:
    """A further stop, on any mass or between two masses (:attr:`Stops.extra`).

    Parameters
    ----------
    name : str
        One letter naming the stop in impact patterns (not ``"U"``/``"L"``, the
        oscillator's own upper and lower stops), e.g. ``"A"``.
    mass : int
        The mass ``j`` (1-based) whose coordinate ``x_j`` the stop acts on.
    gap : float
        Distance of the stop from the origin of ``s``: it sits at ``s = side * gap``.
    restitution : float
        In [0, 1]: ``s'^+ = -restitution s'^-`` (eq. 4; the two-body law for a pair).
    side : int
        ``+1``: met moving up at ``s = gap`` (an upper stop); ``-1``: met moving down at
        ``s = -gap`` (a lower stop).
    relative_to : int, optional
        A stop between masses ``j`` and ``k`` (``s = x_j - x_k``); None: fixed to the frame.

    Examples
    --------
    >>> Stop("A", mass=2, gap=0.3, restitution=0.7)
    Stop(name='A', mass=2, gap=0.3, restitution=0.7)
    """

    name: str
    mass: int
    gap: float
    restitution: float
    side: int = 1
    relative_to: int | None = None

    def __post_init__(self) -> None:
        name = self.name
        if not isinstance(name, str) or len(name) != 1 or not name.isalpha():
            raise ParameterError(f"Stop name must be one letter (it names the stop in impact "
                                 f"patterns); got {name!r}")
        if name in (UPPER, LOWER):
            raise ParameterError(f"Stop name {name!r} is taken: 'U' and 'L' are the "
                                 "oscillator's own upper and lower stops; give another letter")
        object.__setattr__(self, "mass", check_positive_integer(
            f"Stop {name!r} mass", self.mass, "1-based, the mass the stop acts on"))
        if self.relative_to is not None:
            k = check_positive_integer(
                f"Stop {name!r} relative_to", self.relative_to,
                "the other mass of a stop between two masses, 1-based; or None")
            if k == self.mass:
                raise ParameterError(f"Stop {name!r}: relative_to={k!r} equals mass="
                                     f"{self.mass!r}: a stop between a mass and itself; give "
                                     "another mass (s = x_j - x_k needs k != j) or None")
            object.__setattr__(self, "relative_to", k)
        if isinstance(self.side, bool) or self.side not in (1, -1):
            raise ParameterError(f"Stop {name!r} side must be +1 (met moving up at s = gap) "
                                 f"or -1 (met moving down at s = -gap); got {self.side!r}")
        object.__setattr__(self, "side", int(self.side))
        object.__setattr__(self, "gap", _finite(f"Stop {name!r} gap", self.gap,
                                                allowed="a finite real number"))
        object.__setattr__(self, "restitution", _finite(
            f"Stop {name!r} restitution", self.restitution, low=0.0, high=1.0,
            allowed="in [0, 1]"))

    def __repr__(self) -> str:
        side = "" if self.side == 1 else ", side=-1"
        pair = "" if self.relative_to is None else f", relative_to={self.relative_to!r}"
        return (f"Stop(name={self.name!r}, mass={self.mass!r}, gap={self.gap!r}, "
                f"restitution={self.restitution!r}{side}{pair})")

    @property
    def position(self) -> float:
        """``c = side * gap``: the stop sits at ``s = c``."""
        return self.side * self.gap

    @property
    def coordinate(self) -> str:
        """The stop coordinate as text."""
        return (f"x{self.mass}" if self.relative_to is None
                else f"x{self.mass} - x{self.relative_to}")

    def check(self, n: int) -> None:
        """Refuse masses outside ``1..n``."""
        for what, k in (("mass", self.mass), ("relative_to", self.relative_to)):
            if k is not None and k > n:
                raise ParameterError(f"Stop {self.name!r} {what} must be in 1..{n} (the "
                                     f"oscillator has n={n} masses); got {k!r}")

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python description (JSON-able)."""
        out: dict[str, Any] = {"name": self.name, "mass": self.mass, "gap": self.gap,
                               "restitution": self.restitution, "side": self.side}
        if self.relative_to is not None:
            out["relative_to"] = self.relative_to
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Stop:
        """Inverse of :meth:`to_dict`; unknown or missing keys are refused."""
        keys = {"name", "mass", "gap", "restitution", "side", "relative_to"}
        if not isinstance(data, Mapping):
            raise TypeError(f"an extra stop must be a Stop or a mapping with keys "
                            f"{sorted(keys)}; got {type(data).__name__}")
        unknown = set(data) - keys
        missing = {"name", "mass", "gap", "restitution"} - set(data)
        if unknown or missing:
            raise ParameterError(f"extra stop {dict(data)!r}: unknown key(s) {sorted(unknown)}"
                                 f", missing key(s) {sorted(missing)}; allowed: "
                                 f"{sorted(keys)} (name, mass, gap, restitution required)")
        return cls(**data)


def _as_extra(extra: Any) -> tuple[Stop, ...]:
    if isinstance(extra, (str, bytes, Mapping, Stop)) or not hasattr(extra, "__iter__"):
        raise TypeError(f"stops.extra must be a sequence of Stop (or mappings); got {extra!r}")
    out = tuple(e if isinstance(e, Stop) else Stop.from_dict(e) for e in extra)
    names = [e.name for e in out]
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        raise ParameterError(f"stops.extra: duplicate stop name(s) {dup}; each stop needs "
                             f"its own letter (got names {names})")
    return out


@dataclasses.dataclass(frozen=True)
class Stops:
    """Which mass meets the stops, and the optional lower stop.

    Parameters
    ----------
    mass : int
        The impacting mass ``j``, 1-based (``1 <= mass <= n``; the paper's is 1).
    b_low : float, optional
        The lower stop sits at ``x_j = -b_low`` (any real number with
        ``-b_low < b``, checked by the oscillator). None: no lower stop (the paper).
    R_low : float, optional
        Restitution of the lower stop, ``0 <= R_low <= 1``; only with ``b_low``.
        Defaults to the oscillator's ``R`` when ``b_low`` is given without it
        (resolved by :class:`~impactcont.model.oscillator.ImpactOscillator`).
    mirror : bool
        A lower stop that mirrors the upper one: ``x_j = -b`` with restitution ``R``,
        moving with ``b`` and ``R`` (a symmetric backlash of width ``2 b``: continued in
        ``b`` or ``R``, the system stays symmetric). ``b_low`` and ``R_low`` are not
        given: the oscillator sets them to ``b`` and ``R``.
    relative_to : int, optional
        A clearance between mass ``j`` and mass ``k = relative_to`` (1-based, ``k != j``):
        the stops act on ``s = x_j - x_k`` (upper ``s = b``, lower ``s = -b_low``) with the
        two-body impact law. None: the stops are fixed to the frame (the paper).
    extra : sequence of Stop, optional
        Further stops on any coordinate (:class:`Stop`, named by one letter other than
        U/L), e.g. a stop above mass 2 besides ``U`` above mass 1. Two stops met from the
        same side of one coordinate, or an upper stop not above a lower one on one
        coordinate, are refused (:meth:`check`).

    Examples
    --------
    >>> Stops(mass=2, b_low=0.5, R_low=0.8)
    Stops(mass=2, b_low=0.5, R_low=0.8)
    >>> Stops(mass=2, relative_to=1, mirror=True)  # a symmetric clearance between masses 1, 2
    Stops(mass=2, b_low=None, R_low=None, mirror=True, relative_to=1)
    """

    mass: int = 1
    b_low: float | None = None
    R_low: float | None = None
    mirror: bool = False
    relative_to: int | None = None
    extra: tuple[Stop, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "extra", _as_extra(self.extra))
        mass = check_positive_integer("stops.mass", self.mass,
                                      "the impacting mass, 1-based as the paper's mass 1")
        object.__setattr__(self, "mass", mass)
        k = self.relative_to
        if k is not None:
            if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
                raise ParameterError(f"stops.relative_to must be None (stops fixed to the frame) "
                                     f"or an integer >= 1 (the other mass of a clearance "
                                     f"between two masses, 1-based); got {k!r}")
            if int(k) == mass:
                raise ParameterError(f"stops.relative_to={k!r} equals stops.mass={mass!r}: a "
                                     "stop between a mass and itself; give another mass (the "
                                     "clearance s = x_j - x_k needs k != j) or None")
            object.__setattr__(self, "relative_to", int(k))
        if not isinstance(self.mirror, (bool, np.bool_)):
            raise TypeError(f"stops.mirror must be True or False; got {self.mirror!r}")
        object.__setattr__(self, "mirror", bool(self.mirror))
        if self.mirror:
            if self.b_low is not None or self.R_low is not None:
                raise ParameterError(
                    f"stops.mirror=True: the lower stop mirrors the upper one (x_j = -b, "
                    f"restitution R, moving with them); give no b_low, R_low (got "
                    f"b_low={self.b_low!r}, R_low={self.R_low!r})")
            return
        if self.b_low is None:
            if self.R_low is not None:
                raise ParameterError(f"stops.R_low={self.R_low!r} needs a lower stop: give "
                                     "b_low (the lower stop at x_j = -b_low) or drop R_low")
            return
        object.__setattr__(self, "b_low", _finite("stops.b_low", self.b_low,
                                                   allowed="a finite real number"))
        if self.R_low is not None:
            object.__setattr__(self, "R_low", _finite("stops.R_low", self.R_low, low=0.0,
                                                       high=1.0, allowed="in [0, 1]"))

    def __repr__(self) -> str:
        mirror = ", mirror=True" if self.mirror else ""
        pair = "" if self.relative_to is None else f", relative_to={self.relative_to!r}"
        extra = f", extra={self.extra!r}" if self.extra else ""
        return (f"Stops(mass={self.mass!r}, b_low={self.b_low!r}, R_low={self.R_low!r}"
                f"{mirror}{pair}{extra})")

    # -- views ----------------------------------------------------------------------------------
    @property
    def index(self) -> int:
        """0-based index ``j - 1`` of the impacting mass in ``x``."""
        return self.mass - 1

    @property
    def two_sided(self) -> bool:
        """A lower stop is present."""
        return self.b_low is not None or self.mirror

    @property
    def paper(self) -> bool:
        """The paper's geometry: one stop, on mass 1, fixed to the frame."""
        return (self.mass == 1 and not self.two_sided and self.relative_to is None
                and not self.extra)

    @property
    def names(self) -> str:
        """Every stop's name: ``"U"``, ``"L"`` (with a lower stop), then the extra stops'."""
        return UPPER + (LOWER if self.two_sided else "") + "".join(e.name for e in self.extra)

    def stop(self, name: str, M: np.ndarray, b: float, R: float) -> StopView:
        """The stop `name` in the terms every path uses (:class:`StopView`).

        Parameters
        ----------
        name : str
            ``"U"``, ``"L"`` or an extra stop's name (:attr:`names`).
        M : ndarray, shape (n, n)
            Mass matrix (the velocity jump of a pair depends on it).
        b, R : float
            The oscillator's upper stop and its restitution.

        Raises
        ------
        ParameterError
            `name` not one of :attr:`names`.
        """
        M = np.asarray(M, dtype=float)
        n = M.shape[0]
        if name in (UPPER, LOWER):
            position = self.position(name, b)
            restitution = self.restitution(name, R)
            return StopView(name, self.normal(n), 1.0 if name == UPPER else -1.0, position,
                            restitution, self.impact_matrix(M, restitution), self.index)
        for e in self.extra:
            if e.name == name:
                e.check(n)
                return StopView(name, _normal_of(e.mass, e.relative_to, n), float(e.side),
                                e.position, e.restitution,
                                _jump(M, e.mass, e.relative_to, e.restitution), e.mass - 1)
        raise ParameterError(f"stop must be one of {list(self.names)} (the oscillator's "
                             f"stops); got {name!r}")

    def restitution_slope(self, name: str, M: np.ndarray) -> np.ndarray:
        """``dD/dR`` of the velocity jump of the stop `name` in its own restitution.

        The jump ``D = I - (1 + R) M^-1 n n^T / (n^T M^-1 n)`` (eq. 4 on one mass: ``-R``
        on ``x_j'``) is affine in R, so the slope is ``D(R=1) - D(R=0)`` exactly.

        Parameters
        ----------
        name : str
            ``"U"``, ``"L"`` or an extra stop's name (:attr:`names`).
        M : ndarray, shape (n, n)

        Returns
        -------
        ndarray, shape (n, n)
        """
        if name in (UPPER, LOWER):
            self.position(name, 0.0)  # validates
            return self.impact_matrix(M, 1.0) - self.impact_matrix(M, 0.0)
        e = self.extra_stop(name)
        return _jump(M, e.mass, e.relative_to, 1.0) - _jump(M, e.mass, e.relative_to, 0.0)

    def extra_stop(self, name: str) -> Stop:
        """The extra stop named `name`.

        Raises
        ------
        ParameterError
            No extra stop has that name.
        """
        for e in self.extra:
            if e.name == name:
                return e
        raise ParameterError(f"stop must name an extra stop, one of "
                             f"{[e.name for e in self.extra]}; got {name!r}")

    def with_extra(self, name: str, **changes: Any) -> Stops:
        """The stops with the extra stop `name` changed (``gap=...``, ``restitution=...``)."""
        old = self.extra_stop(name)
        extra = tuple(dataclasses.replace(e, **changes) if e is old else e for e in self.extra)
        if self.mirror:  # b_low, R_low follow b, R: resolved again by the oscillator
            return dataclasses.replace(self, b_low=None, R_low=None, extra=extra)
        return dataclasses.replace(self, extra=extra)

    def coordinates(self, n: int) -> list[tuple[str, np.ndarray]]:
        """Every stop coordinate, once: ``(text, normal)`` of U/L's, then of each extra
        stop on another coordinate (``s = normal . x``; a coordinate and its negative are
        one)."""
        out = [(self.coordinate, self.normal(n))]
        for e in self.extra:
            e.check(n)
            nrm = _normal_of(e.mass, e.relative_to, n)
            if not any(np.array_equal(nrm, v) or np.array_equal(nrm, -v) for _, v in out):
                out.append((e.coordinate, nrm))
        return out

    @property
    def pair(self) -> bool:
        """The stops act between two masses (``relative_to`` given)."""
        return self.relative_to is not None

    @property
    def coordinate(self) -> str:
        """The stop coordinate as text: ``"x_j"`` or ``"x_j - x_k"``."""
        return (f"x{self.mass}" if self.relative_to is None
                else f"x{self.mass} - x{self.relative_to}")

    def normal(self, n: int) -> np.ndarray:
        """The stop coordinate ``s = normal . x``: ``e_j``, or ``e_j - e_k`` for a pair.

        Parameters
        ----------
        n : int
            Degrees of freedom of the oscillator.

        Returns
        -------
        ndarray, shape (n,)
        """
        self._check_masses(n)
        out = np.zeros(n)
        out[self.index] = 1.0
        if self.relative_to is not None:
            out[self.relative_to - 1] = -1.0
        return out

    def impact_matrix(self, M: np.ndarray, R: float) -> np.ndarray:
        """The velocity jump ``v+ = D v`` at a stop of restitution ``R`` (eq. 4 generalised).

        The rigid-impact law of a stop on ``s = normal . x``: the impulse acts along
        ``normal``, momentum is conserved in every direction it does not touch and the
        relative velocity ``s'`` is reversed and scaled by ``R``,

            D = I - (1 + R) M^-1 n n^T / (n^T M^-1 n).

        For a stop fixed to the frame (no ``relative_to``) this is eq. (4) exactly,
        ``diag(1, .., -R, .., 1)`` with ``-R`` on ``x_j'``, for every M: with a diagonal M
        the two laws coincide, and with a non-diagonal M (coupled inertia) eq. (4) is kept
        so that no result of the paper's model changes.

        Parameters
        ----------
        M : ndarray, shape (n, n)
            Mass matrix.
        R : float
            Restitution of the stop hit (``R`` or ``R_low``).

        Returns
        -------
        ndarray, shape (n, n)
        """
        M = np.asarray(M, dtype=float)
        n = M.shape[0]
        nrm = self.normal(n)
        if self.relative_to is None:
            D = np.eye(n)
            D[self.index, self.index] = -float(R)
            return D
        minv_n = np.linalg.solve(M, nrm)
        return np.eye(n) - (1.0 + float(R)) * np.outer(minv_n, nrm) / float(nrm @ minv_n)

    def _check_masses(self, n: int) -> None:
        if self.mass > n:
            raise ParameterError(f"stops.mass must be in 1..{n} (the oscillator has n={n} "
                                 f"masses); got {self.mass!r}")
        if self.relative_to is not None and self.relative_to > n:
            raise ParameterError(f"stops.relative_to must be in 1..{n} (the oscillator has "
                                 f"n={n} masses) and differ from stops.mass={self.mass}; got "
                                 f"{self.relative_to!r}")

    def check(self, n: int, b: float, R: float) -> Stops:
        """Validated against an oscillator of ``n`` masses with upper stop ``b``, ``R``.

        Returns the stops with ``R_low`` resolved (``R`` when not given).

        Raises
        ------
        ParameterError
            ``mass > n`` or ``relative_to > n``, or the lower stop not below the upper one
            (``-b_low >= b``: a clearance that closes).
        """
        self._check_masses(n)
        for e in self.extra:
            e.check(n)
        resolved = self._check_main(n, b, R)
        resolved._check_regions(n, b)
        return resolved

    def _check_regions(self, n: int, b: float) -> None:
        """Refuse an extra stop that shadows or closes another on the same coordinate."""
        entries = [(UPPER, self.normal(n), 1, b, self.coordinate)]
        if self.two_sided:
            entries.append((LOWER, self.normal(n), -1, -self.b_low, self.coordinate))
        entries += [(e.name, _normal_of(e.mass, e.relative_to, n), e.side, e.position,
                     e.coordinate) for e in self.extra]
        for i, (na, nrm_a, side_a, c_a, s_a) in enumerate(entries):
            for nb, nrm_b, side_b, c_b, s_b in entries[i + 1:]:
                if nb in (UPPER, LOWER):
                    continue
                if np.array_equal(nrm_a, nrm_b):
                    flip = 1
                elif np.array_equal(nrm_a, -nrm_b):
                    flip = -1
                else:
                    continue
                side, c = flip * side_b, flip * c_b  # stop b on stop a's coordinate
                if side == side_a:
                    raise ParameterError(
                        f"stops {na!r} and {nb!r} are both met "
                        f"{'moving up' if side_a > 0 else 'moving down'} on the same "
                        f"coordinate {s_a} (stop {nb!r} on {s_b}): one shadows the other; "
                        "allowed: at most one upper and one lower stop per coordinate")
                upper, lower = (c_a, c) if side_a > 0 else (c, c_a)
                if not lower < upper:
                    raise ParameterError(
                        f"stops {na!r} (at {s_a} = {c_a!r}) and {nb!r} (at {s_b} = {c_b!r}) "
                        f"on the same coordinate leave no room between them: the upper stop "
                        f"must lie above the lower one (a clearance that closes)")

    def _check_main(self, n: int, b: float, R: float) -> Stops:
        s = self.coordinate
        if self.mirror:
            if not b > 0:
                raise ParameterError(f"mirrored stops {s} = +-b need b > 0 (the clearance "
                                     f"2 b between them; b <= 0 closes it); got b={b!r}")
            resolved = copy.copy(self)  # b_low, R_low follow b, R (not given by the user)
            object.__setattr__(resolved, "b_low", float(b))
            object.__setattr__(resolved, "R_low", float(R))
            return resolved
        if self.b_low is None:
            return self
        if not -self.b_low < b:
            raise ParameterError(f"the lower stop {s} = -b_low = {-self.b_low!r} must lie below "
                                 f"the upper stop {s} = b = {b!r} (b + b_low > 0; b + b_low "
                                 f"<= 0 is a clearance that closes); got b={b!r}, "
                                 f"stops.b_low={self.b_low!r}")
        if self.R_low is None:
            return dataclasses.replace(self, R_low=R)
        return self

    def position(self, stop: str, b: float) -> float:
        """Position of the stop ``"U"`` (``b``) or ``"L"`` (``-b_low``) of mass j."""
        if stop == UPPER:
            return b
        if stop == LOWER and self.b_low is not None:
            return -self.b_low
        raise ParameterError(f"stop must be {UPPER!r}" + (f" or {LOWER!r}" if self.two_sided
                                                          else " (no lower stop)")
                             + f"; got {stop!r}")

    def restitution(self, stop: str, R: float) -> float:
        """Restitution of the stop ``"U"`` (``R``) or ``"L"`` (``R_low``)."""
        if stop == UPPER:
            return R
        self.position(stop, 0.0)  # validates
        return float(R if self.R_low is None else self.R_low)

    # -- serialisation --------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python description (JSON-able)."""
        out: dict[str, Any] = {"mass": self.mass}
        if self.relative_to is not None:
            out["relative_to"] = self.relative_to
        if self.mirror:
            out["mirror"] = True
        elif self.b_low is not None:
            out["b_low"] = self.b_low
            out["R_low"] = self.R_low
        if self.extra:
            out["extra"] = [e.to_dict() for e in self.extra]
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Stops:
        """Inverse of :meth:`to_dict`; unknown keys are refused."""
        if not isinstance(data, Mapping):
            raise TypeError(f"stops must be a Stops or a mapping with keys mass, b_low, R_low, "
                            f"mirror, relative_to, extra; got {type(data).__name__}")
        unknown = set(data) - {"mass", "b_low", "R_low", "mirror", "relative_to", "extra"}
        if unknown:
            raise ParameterError(f"stops: unknown key(s) {sorted(unknown)}; allowed: mass, "
                                 "b_low, R_low, mirror, relative_to, extra")
        data = dict(data)
        if "extra" in data:
            data["extra"] = _as_extra(data["extra"])
        return cls(**data)


def check_pattern(pattern: Any, p: int, stops: Stops, *, sticking: bool = False) -> str:
    """An impact sequence of an N-p motion: ``p`` stop names (``U``/``L``, extra stops).

    Parameters
    ----------
    pattern : str or None
        Which stop impact ``k`` hits, e.g. ``"UL"``; None: every impact on the
        upper stop (the one-sided motion).
    p : int
        Impacts per motion.
    stops : Stops
    sticking : bool
        Accept sticking phases: a lowercase letter (``"u"``, ``"l"``, ``"a"`` for the extra
        stop ``"A"``) is an impact on that stop followed by a sticking phase on it (entered
        by the impact itself when the stop is plastic, else through complete chatter) until
        the release (:func:`impactcont.orbit.multi_impact.multi_impact_orbit`). A
        letter that is itself a stop's name stays that stop's impact.

    Raises
    ------
    ParameterError
        Wrong length, a letter that names no stop, ``L`` without a lower stop, or a
        sticking phase where `sticking` is False (a path that does not solve them yet).

    Notes
    -----
    Whether a sticking stop's restitution lets its impacts accumulate (``0 <= R < 1``;
    ``R > 0`` enters the sticking phase through complete chatter) is checked where the
    restitutions are known, :func:`sticking_pattern`.
    """
    if pattern is None:
        return UPPER * p
    if not isinstance(pattern, str):
        raise TypeError(f"pattern must be a string of {p} letters U/L; got {pattern!r}")
    names = UPPER + (LOWER if stops.two_sided else "") + "".join(
        e.name for e in getattr(stops, "extra", ()))
    held = "".join(c for c in pattern if c not in names and c.upper() in names)
    if held:
        if not sticking:
            raise ParameterError(
                f"pattern={pattern!r}: the lowercase letter(s) {held!r} ask for sticking phases "
                "(an impact held on its stop until the release), which this path (the "
                "shooting of flights and impacts alone) does not solve: multi_impact_orbit "
                "solves them, and continuation, curve and stability_map take its motion; or "
                "give the impacts' stops in capitals, e.g. "
                + repr("".join(c if c in names else c.upper() for c in pattern)))
        impacts = "".join(c if c in names else c.upper() for c in pattern)
        try:
            check_pattern(impacts, p, stops)
        except ParameterError as exc:  # (it names the impacts in capitals: say what was given)
            raise ParameterError(f"pattern={pattern!r} (lowercase: an impact followed by a "
                                 f"sticking phase on its stop): {exc}") from None
        return pattern
    extra = "".join(e.name for e in getattr(stops, "extra", ()))
    if extra and len(pattern) == p and not set(pattern) - set(UPPER + LOWER + extra):
        if LOWER in pattern and not stops.two_sided:
            raise ParameterError(f"pattern={pattern!r} has impacts on the lower stop, but the "
                                 "oscillator has none: give stops=Stops(b_low=...)")
        return pattern
    if extra:
        raise ParameterError(f"pattern must be {p} stop names (one per impact) from "
                             f"{list(stops.names)}; got {pattern!r}")
    if len(pattern) != p or set(pattern) - {UPPER, LOWER}:
        lower = " and 'L' (lower stop)" if stops.two_sided else ""
        raise ParameterError(f"pattern must be {p} letter{'s' if p != 1 else ''} (one per "
                             f"impact) from 'U' (upper stop){lower}, lowercase where a "
                             f"sticking phase follows the impact; got {pattern!r}")
    if LOWER in pattern and not stops.two_sided:
        raise ParameterError(f"pattern={pattern!r} has impacts on the lower stop, but the "
                             "oscillator has none: give stops=Stops(b_low=...)")
    return pattern


def sticking_pattern(osc: Any, pattern: str) -> tuple[str, np.ndarray]:
    """The impacts of a pattern with sticking phases and where the sticks are.

    A lowercase letter (``"u"``, ``"l"``, ``"a"`` for the extra stop ``"A"``) is an impact
    on that stop followed by a sticking phase on it until the release
    (:func:`check_pattern` with ``sticking=True``): entered by the impact itself on a
    plastic stop (restitution 0), through the complete chatter the impact starts on a stop
    with ``0 < R < 1``.

    Parameters
    ----------
    osc : ImpactOscillator
    pattern : str
        A checked pattern (:func:`check_pattern` with ``sticking=True``).

    Returns
    -------
    impacts : str
        The stop of each impact (capitals for U, L and the extra stops named so).
    sticks : ndarray of bool, shape (p,)
        A sticking phase follows impact k.

    Raises
    ------
    ParameterError
        A sticking phase on a stop whose restitution is not in ``[0, 1)``: restitution 0
        enters it by the plastic impact itself, ``0 < R < 1`` through complete chatter (the
        chatter map of :func:`impactcont.kernel.shooting._chatter_map`); with ``R >= 1`` the
        impacts do not accumulate.
    """
    known = _STICKING.setdefault(osc, {})
    found = known.get(pattern)
    if found is None:
        # what it reads (the stops, the masses, b and R) does not change with omega: a
        # branch in omega finds the start's at each new oscillator
        key = (pattern, osc.stops, np.asarray(osc.b, dtype=float).tobytes(),
               np.asarray(osc.R, dtype=float).tobytes(), np.asarray(osc.M, dtype=float).tobytes())
        found = _STICKING_BY_STOPS.get(key)
        if found is None:
            found = _sticking_pattern(osc, pattern)
            if len(_STICKING_BY_STOPS) >= _STICKING_KEPT:
                _STICKING_BY_STOPS.clear()
            _STICKING_BY_STOPS[key] = found
        known[pattern] = found
    return found


#: :func:`sticking_pattern` of each live oscillator, by pattern.
_STICKING: weakref.WeakKeyDictionary[Any, dict[str, tuple[str, np.ndarray]]] = \
    weakref.WeakKeyDictionary()
#: ... and by what it reads (the pattern, the stops, b, R and M), at most this many.
_STICKING_KEPT = 64
_STICKING_BY_STOPS: dict[tuple[Any, ...], tuple[str, np.ndarray]] = {}


def _sticking_pattern(osc: Any, pattern: str) -> tuple[str, np.ndarray]:
    names = osc.stops.names
    sticks = np.array([c not in names and c.upper() in names for c in pattern], dtype=bool)
    sticks.flags.writeable = False
    impacts = "".join(c.upper() if stick else c for c, stick in zip(pattern, sticks,
                                                                      strict=True))
    for name in sorted({impacts[k] for k in np.flatnonzero(sticks)}):
        r = float(osc.stops.stop(name, osc.M, osc.b, osc.R).restitution)
        if not 0.0 <= r < 1.0:
            raise ParameterError(
                f"pattern={pattern!r}: a sticking phase on stop {name!r}, whose restitution is "
                f"{r!r}; a sticking phase is entered by a plastic impact (restitution 0) or "
                "through complete chatter (0 < restitution < 1: the impacts accumulate in a "
                "finite time); with restitution >= 1 they do not accumulate (give stop "
                f"{name!r} a restitution below 1, or simulate the motion: ic.simulate)")
    return impacts, sticks


def require_forcing(osc: Any, what: str) -> None:
    """Refuse a machine without harmonic forcing (``F = 0``) on a path of periodic motions.

    A periodic motion of this package has the forcing's period ``2 pi N / omega`` and is
    fixed in time by the forcing phase ``delta``. Without a harmonic forcing the machine is
    autonomous (``F_static`` is a constant force, conservative): with any loss (``R < 1`` or
    damping) its impacting motions die out, and without loss every time shift of a motion is
    another one, so no motion is isolated (the shooting Jacobian is singular). Such a
    machine is followed by :func:`impactcont.simulate` from a state.

    Raises
    ------
    ParameterError
        Naming `what`, the forcing received and what is allowed.
    """
    F = getattr(osc, "F", None)
    if F is not None and not np.any(F):
        raise ParameterError(
            f"{what}: F = {np.asarray(F).tolist()} (no harmonic forcing): periodic motions have "
            "the forcing's period 2 pi N / omega and its phase delta, and an unforced machine "
            "has no isolated one (with any loss, R < 1 or damping, its impacts die out; "
            "without loss every time shift of a motion is another). Allowed: F with a "
            "nonzero entry; an unforced machine (e.g. a ball bouncing on a still table under "
            "F_static) is followed by impactcont.simulate from a state")


def require_paper_stops(osc: Any, what: str) -> None:
    """Refuse a system other than the paper's form on the closed-form N-1 path.

    The closed form of eq. (12)-(16) and its kernel are written for one stop on
    mass 1 (the section ``x1 = b``, ``-R`` on ``x1'``), every mode held by a spring
    and no constant force: with a stop on another mass, a lower stop, a clearance
    between masses, a free mass or a constant force ``F_static`` they would give
    motions checked against the wrong stop, or the wrong motion.

    Raises
    ------
    ParameterError
        Naming `what`, what the system has and the shooting path that handles it.
    """
    require_forcing(osc, what)
    others = getattr(osc, "paper_form_violations", None)
    problems = others() if callable(others) else []
    if problems:
        raise ParameterError(
            f"{what}: the closed form of eq. (12)-(16) handles one stop on mass 1 only, "
            f"with K positive definite and no constant force (the paper's form); the "
            f"oscillator has "
            f"{'; '.join(problems)}. Use the N-p shooting path instead: "
            "impactcont.multi_impact_orbit(osc, N, p, guess, pattern=...) and "
            "multi_impact_continuation (p = 1, pattern 'U' for an N-1 motion)")
    stops = getattr(osc, "stops", None)
    if stops is not None and not stops.paper:
        raise ParameterError(
            f"{what}: the closed form of eq. (12)-(16) handles one stop on mass 1 only; got "
            f"stops={stops!r}. Use the N-p shooting path instead: "
            "impactcont.multi_impact_orbit(osc, N, p, guess, pattern=...) and "
            "multi_impact_continuation (p = 1, pattern 'U' for an N-1 motion)")
