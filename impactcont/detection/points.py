"""The one record of a special point: where a test function of a kind vanishes.

Every detector returns these: the special points of N-1 and N-p branches
(:func:`~impactcont.detection.special_points.detect_special_points`,
:func:`~impactcont.detection.special_points.detect_special_points`) and the zeros of
the user's event functions (:func:`~impactcont.detection.special_points.locate_user_events`).
The former names :class:`SpecialPoint`, ``MultiImpactSpecialPoint`` and ``UserEvent`` are
all this class.

Notes
-----
A codimension-two point of a curve (two parameters; label ``"A+B"``, ``R1``, ``R2``) fits
the same record (:meth:`SpecialPoint.on_curve`): ``codimension=2``, ``u`` the curve
problem's unknowns (one of them the first parameter), ``value`` the second parameter and
``x = [u, value]``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from impactcont.vocabulary import STATUSES, Label

__all__ = ["SpecialPoint"]


@dataclasses.dataclass(frozen=True, eq=False, kw_only=True)
class SpecialPoint:
    """A special point located (or bracketed) between two accepted points.

    Attributes
    ----------
    label : str
        Its kind: a :class:`~impactcont.vocabulary.Label` (``SN``, ``PD``, ...), a
        codim-2 name (``"PD+NS"``, ``"R1"``, ...) or the name of a user event.
    value : float
        The continued parameter there (``lam``).
    u : ndarray
        The problem's unknowns there: ``[delta]`` on an N-1 branch, the shooting
        unknowns on an N-p one (given ``delta`` alone, ``[delta]``).
    point : int
        Index of the nearest accepted point.
    precision : float
        Bound on the error of the location (of `value`; of both parameters, max-norm,
        on a curve).
    status : str
        ``"located"`` (refined to `precision`) or ``"bracketed"`` (only known to lie
        in the step: the location failed, or the test jumps there).
    orbit : object
        The motion there (:class:`~impactcont.orbit.periodic.PeriodicOrbit`,
        :class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`).
    bracket : (float, float) or None
        The continued parameter at the two accepted points around it, when known.
    delta : float or None
        Forcing phase at the (first) impact: given by an N-1 detector (`u` is then
        ``[delta]``), else the motion's ``delta`` (None for a motion without one).
    codimension : int
        1 on a branch (default: the kind's own for a Label), 2 for a point of a curve.
    """

    label: str
    value: float
    point: int
    precision: float
    status: str
    orbit: Any
    u: np.ndarray | None = None
    bracket: tuple[float, float] | None = None
    delta: float | None = None
    codimension: int | None = None

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}; got {self.status!r}")
        if self.u is None and self.delta is None:
            raise ValueError("a special point needs its unknowns u or its phase delta")
        if self.u is None:
            object.__setattr__(self, "u", np.array([float(self.delta)]))
        if self.delta is None and getattr(self.orbit, "delta", None) is not None:
            object.__setattr__(self, "delta", float(self.orbit.delta))
        if self.codimension is None:
            kind = self.kind
            object.__setattr__(self, "codimension",
                               kind.codimension if isinstance(kind, Label) else 1)

    @classmethod
    def on_curve(cls, label: str, x: np.ndarray, orbit: Any, point: int, precision: float,
                 status: str) -> SpecialPoint:
        """A codimension-two point of a curve from ``x = [u, lam]`` of the curve problem.

        Parameters
        ----------
        label : str
            ``"A+B"`` (a curve of kind A meets kind B), ``"R1"`` or ``"R2"``.
        x : ndarray
            ``[u, lam]`` of the curve problem there (``x`` of the record is the same).
        orbit : object
            The motion there.
        point : int
            Index of the nearest accepted curve point.
        precision : float
            Bound on the error in the plane of the two parameters (max-norm).
        status : str
            ``"located"`` or ``"bracketed"``.
        """
        x = np.asarray(x, dtype=float)
        return cls(label=label, value=float(x[-1]), u=x[:-1], point=point,
                   precision=precision, status=status, orbit=orbit, codimension=2)

    @property
    def kind(self) -> Label | str:
        """The :class:`~impactcont.vocabulary.Label` of a built-in kind (its marker,
        words and codimension), else the label itself (a user event, a codim-2 name)."""
        try:
            return Label(self.label)
        except ValueError:
            return self.label

    @property
    def name(self) -> str:
        """The label as a plain string (a user event's name)."""
        return str(self.label)

    @property
    def lam(self) -> float:
        """The continued parameter there (`value`)."""
        return self.value

    @property
    def x(self) -> np.ndarray:
        """``[u, value]``: the point of the problem's extended space."""
        return np.append(np.asarray(self.u, dtype=float), self.value)
