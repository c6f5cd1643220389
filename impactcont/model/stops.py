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
from collections.abc import Mapping
from typing import Any

import numpy as np

from impactcont.errors import ParameterError

__all__ = ["LOWER", "UPPER", "Stops", "check_pattern", "require_paper_stops"]

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

    def __post_init__(self) -> None:
        mass = self.mass
        if isinstance(mass, bool) or not isinstance(mass, (int, np.integer)) or mass < 1:
            raise ParameterError(f"stops.mass must be an integer >= 1 (the impacting mass, "
                                 f"1-based as the paper's mass 1); got {mass!r}")
        object.__setattr__(self, "mass", int(mass))
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
        return (f"Stops(mass={self.mass!r}, b_low={self.b_low!r}, R_low={self.R_low!r}"
                f"{mirror}{pair})")

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
        return self.mass == 1 and not self.two_sided and self.relative_to is None

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
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Stops:
        """Inverse of :meth:`to_dict`; unknown keys are refused."""
        if not isinstance(data, Mapping):
            raise TypeError(f"stops must be a Stops or a mapping with keys mass, b_low, R_low, "
                            f"mirror, relative_to; got {type(data).__name__}")
        unknown = set(data) - {"mass", "b_low", "R_low", "mirror", "relative_to"}
        if unknown:
            raise ParameterError(f"stops: unknown key(s) {sorted(unknown)}; allowed: mass, "
                                 "b_low, R_low, mirror, relative_to")
        return cls(**data)


def check_pattern(pattern: Any, p: int, stops: Stops) -> str:
    """An impact sequence of an N-p motion: ``p`` letters ``U``/``L``.

    Parameters
    ----------
    pattern : str or None
        Which stop impact ``k`` hits, e.g. ``"UL"``; None: every impact on the
        upper stop (the one-sided motion).
    p : int
        Impacts per motion.
    stops : Stops

    Raises
    ------
    ParameterError
        Wrong length, a letter other than U/L, or ``L`` without a lower stop.
    """
    if pattern is None:
        return UPPER * p
    if not isinstance(pattern, str):
        raise TypeError(f"pattern must be a string of {p} letters U/L; got {pattern!r}")
    if len(pattern) != p or set(pattern) - {UPPER, LOWER}:
        raise ParameterError(f"pattern must be {p} letters (one per impact) from 'U' (upper "
                             f"stop) and 'L' (lower stop); got {pattern!r}")
    if LOWER in pattern and not stops.two_sided:
        raise ParameterError(f"pattern={pattern!r} has impacts on the lower stop, but the "
                             "oscillator has none: give stops=Stops(b_low=...)")
    return pattern


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
