"""Continuable parameters as objects: how each is set on the model and what it moves.

A name of the vocabulary (:data:`impactcont.vocabulary.PARAMETERS`: ``omega``, ``b``,
``R``, ``eta``, ``alpha``, ``beta``, ``F0``, ``b_low``, ``R_low``, ``gap``, the element
names ``m<j>``, ``k<j>``, ``c<j>``, ``M[i,j]``, ``K[i,j]``, ``C[i,j]``, ``F[j]``, 1-based as
the paper's masses, and an extra stop's own gap and restitution ``gap[S]``, ``R[S]``,
``S`` the stop's letter) becomes a :class:`ModelParameter` for one oscillator
(:func:`model_parameter`). The object says

- how to read it on the model and set it (:meth:`ModelParameter.value`,
  :meth:`ModelParameter.at`: ``osc.replace(...)``, a new ``Stops`` or a new matrix);
- which flight data it changes (:attr:`ModelParameter.data`): the forcing frequency
  (eq. 1), the position of a stop (eq. 3), the restitution of a stop (eq. 4), the
  damping, the stiffness or the masses (the flow of eq. 9), the forcing amplitude;
- how a stop moves with it: the rate of the upper stop's position or restitution and of
  the lower stop's (:attr:`ModelParameter.upper`, :attr:`ModelParameter.lower`) and of
  each extra stop's (:attr:`ModelParameter.extra`), from which the problems write their
  exact derivatives (:meth:`ModelParameter.stop_rates`);
- the derivative everything else uses: :meth:`ModelParameter.difference`, the one
  finite-difference fallback of the package.

Adding a parameter is one entry: a vocabulary record (name, range, unit) and a line of
:func:`_named` (an element family: one entry of
:data:`~impactcont.vocabulary.ELEMENT_FAMILIES` and its setter in :func:`_element`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any, Generic, TypeVar

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.modal import decay_rate_derivative
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import LOWER, UPPER
from impactcont.vocabulary import (
    CONTINUABLE_PARAMETERS,
    PARAMETERS,
    Parameter,
    check_bounds,
    check_parameter,
    damping_kind,
    element_name,
    stop_parameter_name,
)

__all__ = ["DAMPING", "FD_RELATIVE_STEP", "FORCING", "FREQUENCY", "GAP", "MASS", "RESTITUTION",
           "STIFFNESS", "ModelParameter", "ParameterView", "chain_elements", "check_model_bounds",
           "entry_range", "model_parameter"]

#: The flight data a parameter changes.
FREQUENCY = "forcing frequency"
GAP = "stop position"
RESTITUTION = "stop restitution"
DAMPING = "damping"
STIFFNESS = "stiffness"
MASS = "mass"
FORCING = "forcing amplitude"

#: Relative step of the finite-difference fallback: ``eps^(1/3)``, which balances the
#: central difference's truncation ``h^2 |f'''| / 6`` against rounding ``eps |f| / h``.
FD_RELATIVE_STEP = float(np.finfo(float).eps) ** (1.0 / 3.0)
_AFFINE_STEP = 0.5  # of the scale: a data affine in the parameter has no truncation error


_T = TypeVar("_T")


class ParameterView(Mapping[str, _T], Generic[_T]):
    """What each parameter's vocabulary record gives through ``make``: a read-only mapping.

    A lookup resolves every name :data:`impactcont.vocabulary.PARAMETERS` resolves (the
    named parameters, the elements ``k2``, ``M[1,2]``, ``F[2]``, an extra stop's
    ``gap[A]``, ``R[A]``) and returns ``make(record)``; iterating gives ``names``.

    Parameters
    ----------
    make : callable
        ``make(record) -> value`` of a :class:`~impactcont.vocabulary.Parameter`.
    names : iterable of str, optional
        The names iterating gives; default: the vocabulary's named parameters (the
        elements are patterns, never listed).

    Notes
    -----
    The schema's column metadata (:data:`impactcont.dataset.schema.PARAMETERS`) and the
    scene's admissible values (:data:`impactcont.scene.entries.PARAMETER_RANGES`) are
    such views.
    """

    def __init__(self, make: Callable[[Parameter], _T], names: Iterable[str] | None = None
                 ) -> None:
        self._make = make
        self._names = PARAMETERS if names is None else tuple(names)

    def __getitem__(self, name: str) -> _T:
        return self._make(PARAMETERS[name])

    def __contains__(self, name: object) -> bool:
        return name in PARAMETERS

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)


def check_model_bounds(parameter: str, bounds: Any, argument: str = "bounds"
                       ) -> tuple[float, float]:
    """:func:`~impactcont.vocabulary.check_bounds`, saying why a spring of the chain may
    not reach 0.

    A spring ``k_j = 0`` takes the spring away: K becomes singular (a mode of zero
    frequency, masses free of the ground or of each other), which is another oscillator,
    not a point of a branch. Near it the modes' frequencies go to 0 like ``sqrt(k_j)`` and
    the N-1 closed form stalls (the paper's system with k1 = 0.5 in bounds (1e-6, 0.5):
    steps below ds_min at k1 = 9e-6; from 1e-3 it reaches the bound).

    Raises
    ------
    ParameterError
        As :func:`~impactcont.vocabulary.check_bounds`; bounds of a spring ``k<j>`` that
        reach ``k_j <= 0`` name the spring, the end and why.
    """
    try:
        return check_bounds(parameter, bounds, argument)
    except ParameterError:
        element = element_name(parameter)
        lo = _lower_end(bounds)
        if element is not None and element[0] == "k<j>" and lo is not None and lo <= 0.0:
            raise ParameterError(
                f"{argument} {bounds!r} for {parameter} reach {parameter} = {lo!r}: a spring "
                f"of the chain at 0 is taken away (K singular: a mode of zero frequency, "
                f"another oscillator), which no branch reaches; allowed: bounds with "
                f"{parameter} > 0 (a branch may stall before 0, where K nears a singular "
                f"matrix), or an oscillator built with that spring at 0 (free masses held "
                f"by stops) and another parameter continued") from None
        raise


def _lower_end(bounds: Any) -> float | None:
    """The lower end of `bounds` when it is a pair of finite real numbers, else None."""
    try:
        lo, hi = (float(v) for v in bounds)
    except (TypeError, ValueError):
        return None
    return min(lo, hi) if math.isfinite(lo) and math.isfinite(hi) else None


@dataclasses.dataclass(frozen=True, eq=False)
class ModelParameter:
    """One continuable parameter of one oscillator.

    Attributes
    ----------
    name : str
        The vocabulary name (``"omega"``, ``"b_low"``, ``"k2"``, ``"M[1,2]"``, ``"F[2]"``).
    info : Parameter
        Its vocabulary record: long name, range, unit.
    data : str
        The flight data it changes: :data:`FREQUENCY`, :data:`GAP`, :data:`RESTITUTION`,
        :data:`DAMPING`, :data:`STIFFNESS`, :data:`MASS` or :data:`FORCING`.
    upper, lower : float
        For :data:`GAP`: ``d c / d lam`` of the stop positions (``c = b`` above,
        ``c = -b_low`` below); for :data:`RESTITUTION`: ``d R / d lam`` of the upper and
        the lower stop's restitution. Zero otherwise.
    extra : tuple of (str, float)
        The same rates for extra stops, by name (``gap[A]``: ``(("A", side),)``, the
        stop at ``c = side * gap``; ``R[A]``: ``(("A", 1.0),)``); empty otherwise.
    kernel : int or None
        The closed-form kernel's exact derivative (eq. 13-14) that serves it on the
        proportional path: 0 omega, 1 R, 2 the decay rates; None: none.
    """

    name: str
    info: Parameter
    data: str
    get: Callable[[ImpactOscillator], float] = dataclasses.field(repr=False)
    put: Callable[[ImpactOscillator, float], ImpactOscillator] = dataclasses.field(repr=False)
    scale_of: Callable[[ImpactOscillator], float] = dataclasses.field(repr=False)
    upper: float = 0.0
    lower: float = 0.0
    kernel: int | None = None
    extra: tuple[tuple[str, float], ...] = ()
    entry: tuple[str, int, int] | None = None

    # -- the model ------------------------------------------------------------------------------
    def value(self, osc: ImpactOscillator) -> float:
        """The parameter's value on `osc` (0.0 for an absent damping coefficient)."""
        return float(self.get(osc))

    def at(self, osc: ImpactOscillator, value: float) -> ImpactOscillator:
        """`osc` with the parameter set to `value` (validated by the oscillator).

        Raises
        ------
        ParameterError
            The oscillator refuses the value; the message ends with ``(at name = value)``.
        """
        try:
            return self.put(osc, float(value))
        except ParameterError as exc:
            raise ParameterError(f"{exc} (at {self.name} = {float(value)!r})") from exc

    def admits(self, osc: ImpactOscillator, value: float) -> bool:
        """Whether the oscillator takes `value`: in the vocabulary's range and accepted by
        :class:`~impactcont.model.oscillator.ImpactOscillator` (an element of K keeps K
        positive semi-definite with its free modes held by stops, one of M keeps M
        definite, a gap keeps the stops apart, ...)."""
        if not self.info.contains(value):
            return False
        if self.data in (FREQUENCY, RESTITUTION) or (self.data == DAMPING and self.entry is None):
            return True  # omega > 0, R in [0, 1], a damping coefficient or damper >= 0: all
        try:
            self.put(osc, float(value))
        except ParameterError:
            return False
        return True

    def check_bounds(self, osc: ImpactOscillator, bounds: Any, argument: str = "bounds"
                     ) -> tuple[float, float]:
        """`bounds` of a continuation from `osc`, checked before anything is computed.

        :func:`~impactcont.vocabulary.check_bounds` (two finite numbers ``lo < hi`` in the
        parameter's range), then the oscillator at both ends: the values the oscillator
        takes form an interval, so both ends admitted means every value between is. The
        constraints are convex in the parameter: K (or C) positive semi-definite and M
        positive definite are convex cones, whose segment between two members stays in
        them, with the free modes inside the segment a subspace of those at its ends
        (``ker((1 - s) A + s B) = ker A ∩ ker B``), so held by the stops that hold them
        there; the stops' order is linear in a gap. A forcing entry ``F[j]`` is also
        tried at 0 (F = 0 is no forcing). For an entry of K, M or C the message gives the
        range over which the matrix stays positive semi-definite (definite for M) with its
        other entries fixed.

        Returns
        -------
        (float, float)
            ``(lo, hi)``: the oscillator takes both, so every value between.

        Raises
        ------
        ParameterError
            Naming `argument`, the value, the end the oscillator refuses and why.
        """
        lo, hi = check_model_bounds(self.name, bounds, argument)
        if self.data == FREQUENCY:  # omega > 0 is all the oscillator asks
            return lo, hi
        ends = (lo, hi, 0.0) if self.data == FORCING and lo < 0.0 < hi else (lo, hi)
        for value in ends:
            try:
                moved = self.put(osc, value)
            except ParameterError as exc:
                allowed = self._range_text(osc)
                raise ParameterError(
                    f"{argument} {bounds!r} for {self.name}: at {self.name} = {value!r} the "
                    f"oscillator is refused: {exc}; allowed: bounds inside {allowed}") from None
            if self.data == FORCING and not np.any(moved.F):  # builds, but no periodic motion
                raise ParameterError(
                    f"{argument} {bounds!r} for {self.name}: at {self.name} = {value!r} the "
                    f"forcing vanishes (F = {np.asarray(moved.F).tolist()}), where no periodic "
                    f"motion exists; allowed: bounds that keep {self.name} on one side of 0")
        return lo, hi

    def _range_text(self, osc: ImpactOscillator) -> str:
        if self.entry is None:
            return f"the values the oscillator takes ({self.name} {self.info.allowed})"
        matrix, i, j = self.entry
        definite = matrix == "M"
        low, high = entry_range(getattr(osc, matrix), i, j, definite=definite)
        if not low <= high:
            return f"nothing: {matrix} has no value of {self.name} that makes it positive " \
                   f"{'definite' if definite else 'semi-definite'}"
        left, right = ("(", ")") if definite else ("[", "]")
        return (f"{self.name} in {left}{low:.12g}, {high:.12g}"
                f"{')' if math.isinf(high) else right}, where {matrix} stays positive "
                f"{'definite' if definite else 'semi-definite'} with its other entries")

    def scale(self, osc: ImpactOscillator) -> float:
        """The size on which the parameter acts (its value, or its matrix or vector)."""
        s = max(abs(self.value(osc)), float(self.scale_of(osc)))
        return s if s > 0.0 and math.isfinite(s) else 1.0

    # -- what it moves --------------------------------------------------------------------------
    @property
    def moves_stops(self) -> bool:
        """It moves a stop (:data:`GAP`) or changes a restitution (:data:`RESTITUTION`)."""
        return self.data in (GAP, RESTITUTION)

    @property
    def affine(self) -> bool:
        """The flight data are affine in it (the forcing amplitude: eq. 13 is linear in F)."""
        return self.data == FORCING

    @property
    def exact_on_shooting(self) -> bool:
        """The N-p shooting residual has its exact derivative (frequency, stops, forcing)."""
        return self.data in (FREQUENCY, GAP, RESTITUTION, FORCING)

    @property
    def keeps_symmetry(self) -> bool:
        """A symmetric system (``x -> -x`` with the stops) stays symmetric as it moves.

        Only the stops can break it: both positions must move oppositely (``c = +-gap``)
        and both restitutions together; an extra stop's data have no mirror image.
        """
        if self.extra:
            return False
        if self.data == GAP:
            return self.upper == -self.lower
        if self.data == RESTITUTION:
            return self.upper == self.lower
        return True

    def stop_rates(self, pattern: str) -> np.ndarray:
        """:attr:`upper`, :attr:`lower` or the :attr:`extra` rate for the stop of each
        impact of `pattern` (0 for an extra stop the parameter does not move), (p,)."""
        extra = dict(self.extra)
        return np.array([self.upper if s == UPPER else self.lower if s == LOWER
                         else extra.get(s, 0.0) for s in pattern])

    def clearance_limit(self, osc: ImpactOscillator) -> float:
        """The value at which the clearance ``b + b_low`` between two stops closes (GAP
        parameters of a two-sided system), ``-inf`` when it never does."""
        rate = self.upper - self.lower
        if self.data != GAP or not osc.stops.two_sided or rate == 0.0:
            return -math.inf
        width = osc.b + float(osc.stops.b_low)
        return self.value(osc) - width / rate

    def decay_rates_derivative(self, w: np.ndarray) -> np.ndarray:
        """``d a_i / d lam`` of the modal decay rates (eta, alpha, beta; eq. 6), else 0."""
        if self.kernel == 2:
            return decay_rate_derivative(self.name, w)
        return np.zeros_like(w)

    # -- the one finite-difference fallback ------------------------------------------------------
    def difference(self, f: Callable[[float], Any], lam: float, osc: ImpactOscillator
                   ) -> Any:
        """``df/dlam`` at `lam` by a central difference: the fallback of every problem.

        Parameters
        ----------
        f : callable
            The problem's data (a residual, ``c, s`` of eq. 14) as a function of the
            parameter, returning a float or an array.
        lam : float
            Where.
        osc : ImpactOscillator
            The oscillator at `lam` (its :meth:`scale`).

        Notes
        -----
        The step is ``h = eps^(1/3) max(|lam|, scale)`` (:data:`FD_RELATIVE_STEP`, 6.1e-6):
        the error is ``h^2 |f'''| / 6 + eps |f| / h``, about ``1e-11`` relative to the data
        when they vary on the parameter's scale (measured in ``tests/model/test_parameters.py``).
        Data affine in the parameter (:attr:`affine`: the forcing amplitude) take
        ``h = scale / 2``: no truncation error, rounding only (exact). A side outside the
        parameter's range (:meth:`admits`: a mass at 0, an entry of K that would make it
        indefinite) is not evaluated: the difference is then one-sided (error
        ``h |f''| / 2``).
        """
        lam = float(lam)
        scale = self.scale(osc)
        h = _AFFINE_STEP * scale if self.affine else FD_RELATIVE_STEP * max(abs(lam), scale)
        lo = lam - h if self.admits(osc, lam - h) else lam
        hi = lam + h if self.admits(osc, lam + h) else lam
        return (np.asarray(f(hi)) - np.asarray(f(lo))) / (hi - lo)


# -------------------------------------------------------------------------------------------
# The table: one entry per parameter (the element families are built per index)
# -------------------------------------------------------------------------------------------
def _scalar(name: str) -> tuple[Callable, Callable]:
    return (lambda osc: getattr(osc, name) or 0.0,
            lambda osc, v: osc.replace(**{name: v}))


def _lower_stop(key: str) -> tuple[Callable, Callable]:
    return (lambda osc: getattr(osc.stops, key),
            lambda osc, v: osc.replace(stops=dataclasses.replace(osc.stops, **{key: v})))


def _set_gap(osc: ImpactOscillator, v: float) -> ImpactOscillator:
    if osc.stops.mirror:
        return osc.replace(b=v)
    return osc.replace(b=v, stops=dataclasses.replace(osc.stops, b_low=v))


def _one(_: ImpactOscillator) -> float:
    return 1.0


def _named(name: str, osc: ImpactOscillator) -> ModelParameter:
    """The entry of a named parameter."""
    info = PARAMETERS[name]
    mirror = osc.stops.mirror
    entries: dict[str, dict[str, Any]] = {
        "omega": dict(data=FREQUENCY, kernel=0),
        "b": dict(data=GAP, upper=1.0, lower=-1.0 if mirror else 0.0),
        "R": dict(data=RESTITUTION, upper=1.0, lower=1.0 if mirror else 0.0, kernel=1),
        "eta": dict(data=DAMPING, kernel=2),
        "alpha": dict(data=DAMPING, kernel=2),
        "beta": dict(data=DAMPING, kernel=2),
        "F0": dict(data=FORCING),
        "b_low": dict(data=GAP, lower=-1.0),
        "R_low": dict(data=RESTITUTION, lower=1.0),
        "gap": dict(data=GAP, upper=1.0, lower=-1.0),
    }
    get, put = (_lower_stop(name) if name in ("b_low", "R_low") else _scalar(name))
    if name == "gap":
        get, put = (lambda o: o.b), _set_gap
    scale = (lambda o: o.F0) if name == "F0" else _one
    return ModelParameter(name, info, get=get, put=put, scale_of=scale, **entries[name])


def _stop_datum(name: str, family: str, stop: str, osc: ImpactOscillator,
                argument: str) -> ModelParameter:
    """The entry of an extra stop's own gap (``gap[S]``) or restitution (``R[S]``)."""
    names = [e.name for e in osc.stops.extra]
    if stop not in names:
        own = {"gap[S]": "'b' (U), 'b_low' (L)", "R[S]": "'R' (U), 'R_low' (L)"}[family]
        why = (f"U and L are the oscillator's own stops: continue {own}" if stop in (UPPER, LOWER)
               else f"the oscillator has no extra stop {stop!r}")
        allowed = [f"{family[:-3]}[{e}]" for e in names]
        raise ParameterError(f"{argument}={name!r}: {why}; allowed extra-stop parameters: "
                             f"{allowed or 'none (no Stops(extra=...))'}")
    info = PARAMETERS[name]
    e = osc.stops.extra_stop(stop)
    if family == "gap[S]":
        return ModelParameter(
            name, info, GAP, get=lambda o: float(o.stops.extra_stop(stop).gap),
            put=lambda o, v: o.replace(stops=o.stops.with_extra(stop, gap=v)),
            scale_of=_one, extra=((stop, float(e.side)),))
    return ModelParameter(
        name, info, RESTITUTION, get=lambda o: float(o.stops.extra_stop(stop).restitution),
        put=lambda o, v: o.replace(stops=o.stops.with_extra(stop, restitution=v)),
        scale_of=_one, extra=((stop, 1.0),))


def _pseudo_inverse(B: np.ndarray) -> tuple[np.ndarray, bool]:
    """``B^+`` of a symmetric B, and whether B is positive semi-definite (to rounding)."""
    if B.size == 0:
        return B, True
    w, V = np.linalg.eigh(B)
    tol = 8.0 * B.shape[0] * np.finfo(float).eps * max(1.0, float(np.max(np.abs(w))))
    inv = np.where(w > tol, 1.0 / np.where(w > tol, w, 1.0), 0.0)
    return (V * inv) @ V.T, bool(w[0] >= -tol)


def entry_range(A: np.ndarray, i: int, j: int, *, definite: bool = False) -> tuple[float, float]:
    """The values of the entry ``A[i, j] = A[j, i]`` (0-based) that keep the symmetric `A`
    positive semi-definite, its other entries fixed.

    By the Schur complement on the other rows ``S`` (``B = A[S, S]`` positive
    semi-definite, ``B^+`` its pseudo-inverse): a diagonal entry needs
    ``A[i, i] >= b^T B^+ b`` (``b = A[S, i]``), the interval ``[b^T B^+ b, inf)``; an
    off-diagonal one needs ``(A[i,i] - Q_ii)(A[j,j] - Q_jj) >= (A[i,j] - Q_ij)^2`` with
    ``Q = P^T B^+ P`` (``P = A[S, (i, j)]``), the interval ``Q_ij -+ sqrt(...)``. With
    `definite` (M) the same interval, its ends excluded. The interval is empty
    (``low > high``) when no value of the entry makes `A` so. It serves messages; the
    oscillator's own check decides (:meth:`ModelParameter.check_bounds`).

    Returns
    -------
    (float, float)
        ``(low, high)``; ``high = inf`` for a diagonal entry.
    """
    A = np.asarray(A, dtype=float)
    idx = [k for k in range(A.shape[0]) if k not in (i, j)]
    B = A[np.ix_(idx, idx)]
    Binv, psd = _pseudo_inverse(B)
    empty = (math.inf, -math.inf)
    if not psd:
        return empty
    if i == j:
        b = A[idx, i]
        return float(b @ Binv @ b), math.inf
    P = A[np.ix_(idx, [i, j])]
    Q = P.T @ Binv @ P
    di, dj = A[i, i] - Q[0, 0], A[j, j] - Q[1, 1]
    if di < 0.0 or dj < 0.0:
        return empty
    r = math.sqrt(di * dj)
    return float(Q[0, 1] - r), float(Q[0, 1] + r)


def _pattern(n: int, j: int) -> np.ndarray:
    """The stiffness pattern of element j (1-based) of the chain of eq. (2): between masses
    j and j+1, the last one from mass n to the ground."""
    P = np.zeros((n, n))
    P[j - 1, j - 1] = 1.0
    if j < n:
        P[j, j] = 1.0
        P[j - 1, j] = P[j, j - 1] = -1.0
    return P


def chain_elements(A: np.ndarray) -> np.ndarray | None:
    """The elements ``e_1..e_n`` of a chain matrix (springs or dampers of eq. 2) with
    ``A = sum e_j P_j``, or None when `A` is not such a chain (to rounding)."""
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    e = np.array([-A[j - 1, j] for j in range(1, n)] + [A[n - 1, n - 1] + (A[n - 2, n - 1]
                                                                           if n > 1 else 0.0)])
    rebuilt = sum((ej * _pattern(n, j) for j, ej in enumerate(e, start=1)), np.zeros((n, n)))
    tol = 8.0 * n * np.finfo(float).eps * max(1.0, float(np.max(np.abs(A))))
    return e if np.max(np.abs(rebuilt - A)) <= tol else None


def _element(name: str, family: str, indices: tuple[int, ...], osc: ImpactOscillator,
             argument: str) -> ModelParameter:
    """The entry of an element (mass, spring, damper, matrix entry, forcing of one mass)."""
    n = osc.n
    info = PARAMETERS[name]
    letter = family[0]
    if any(i > n for i in indices):
        allowed = {"m": f"m1..m{n}", "k": f"k1..k{n}", "c": f"c1..c{n}", "F": f"F[1]..F[{n}]"}
        raise ParameterError(f"{argument}={name!r} names an element past the oscillator's n={n} "
                             f"masses (1-based); allowed: "
                             f"{allowed.get(letter, f'{letter}[i,j] with 1 <= i, j <= {n}')}")
    if letter in "cC" and not osc.general_damping:
        raise ParameterError(f"{argument}={name!r} is an element of a damping matrix C; the "
                             f"oscillator's damping is not given as a matrix "
                             f"({'eta' if osc.eta is not None else 'alpha/beta'}): build it with "
                             "C=... (a damper on some parts only), or continue eta, alpha or beta")
    matrix = {"m": "M", "M": "M", "k": "K", "K": "K", "c": "C", "C": "C"}.get(letter)
    if family == "F[j]":
        j = indices[0] - 1
        if 0 <= j < osc.n and complex(osc.F[j]).imag != 0.0:
            raise ParameterError(f"{argument}={name!r}: F[{j + 1}]={complex(osc.F[j])!r} has a "
                                 "phase of its own and a real F_j would drop it; continue "
                                 "'F0' (the amplitude of the whole F, phases kept), or an "
                                 "entry of F without a phase")

        def put_f(o: ImpactOscillator, v: float) -> ImpactOscillator:
            F = o.F.copy()
            F[j] = v
            return o.replace(F=F)

        return ModelParameter(name, info, FORCING, get=lambda o: float(o.F[j].real), put=put_f,
                              scale_of=lambda o: o.F0)
    data = {"M": MASS, "K": STIFFNESS, "C": DAMPING}[matrix]

    def scale_of(o: ImpactOscillator) -> float:
        return float(np.max(np.abs(getattr(o, matrix))))

    if family.endswith("[i,j]"):
        i, j = (k - 1 for k in indices)

        def put_entry(o: ImpactOscillator, v: float) -> ImpactOscillator:
            A = np.array(getattr(o, matrix), dtype=float)
            A[i, j] = A[j, i] = v
            return o.replace(**{matrix: A})

        return ModelParameter(name, info, data, get=lambda o: float(getattr(o, matrix)[i, j]),
                              put=put_entry, scale_of=scale_of, entry=(matrix, i, j))
    j = indices[0]
    if letter == "m":
        if np.count_nonzero(osc.M - np.diag(np.diag(osc.M))):
            raise ParameterError(f"{argument}={name!r} is a mass of the chain of eq. (2), which "
                                 f"needs a diagonal M; got M={osc.M.tolist()}: continue an entry "
                                 f"'M[{j},{j}]' instead")

        def put_mass(o: ImpactOscillator, v: float) -> ImpactOscillator:
            M = np.array(o.M, dtype=float)
            M[j - 1, j - 1] = v
            return o.replace(M=M)

        return ModelParameter(name, info, MASS, get=lambda o: float(o.M[j - 1, j - 1]),
                              put=put_mass, scale_of=scale_of)
    if chain_elements(getattr(osc, matrix)) is None:
        what = "springs" if letter == "k" else "dampers"
        raise ParameterError(f"{argument}={name!r} is one of the {what} of the chain of eq. (2) "
                             f"(between masses j and j+1, the last to the ground); "
                             f"{matrix}={getattr(osc, matrix).tolist()} is not such a chain: "
                             f"continue an entry '{matrix}[i,j]' instead")
    pattern = _pattern(n, j)

    def get_chain(o: ImpactOscillator) -> float:
        e = chain_elements(getattr(o, matrix))
        if e is None:
            raise ParameterError(f"{name}: {matrix}={getattr(o, matrix).tolist()} is no longer "
                                 "a chain of eq. (2)")
        return float(e[j - 1])

    def put_chain(o: ImpactOscillator, v: float) -> ImpactOscillator:
        return o.replace(**{matrix: getattr(o, matrix) + (v - get_chain(o)) * pattern})

    return ModelParameter(name, info, data, get=get_chain, put=put_chain, scale_of=scale_of)


def model_parameter(osc: ImpactOscillator, name: Any, argument: str = "parameter"
                    ) -> ModelParameter:
    """The parameter `name` of `osc` as an object, refused when it does not apply.

    Parameters
    ----------
    osc : ImpactOscillator
    name : str
        A vocabulary name (:data:`~impactcont.vocabulary.PARAMETERS`, element names
        included).
    argument : str
        The argument's name in error messages.

    Raises
    ------
    ParameterError
        An unknown name; a damping parameter of the other damping model (``eta`` with a
        matrix C); ``b_low``, ``R_low`` without a lower stop of their own, ``gap`` without a
        symmetric clearance; an element past the oscillator's masses (``k3`` on two
        masses), a chain element of a matrix that is no chain, a damper without a matrix
        C, ``F[j]`` of a complex F; ``gap[S]``, ``R[S]`` of a stop ``S`` that is not one of
        the oscillator's extra stops. The message names `argument`, the value and what is
        allowed.
    """
    check_parameter(osc, name, argument)  # known, and of the oscillator's damping
    stops = osc.stops
    if name in ("b_low", "R_low", "gap"):
        symmetric = stops.mirror or (stops.two_sided and stops.b_low == osc.b)
        stop_names = (("b_low", "R_low") if stops.two_sided and not stops.mirror else ()) + (
            ("gap",) if symmetric else ())
        if name not in stop_names:
            here = tuple(k for k in CONTINUABLE_PARAMETERS if k not in ("b_low", "R_low", "gap")
                         and PARAMETERS[k].damping in (None, damping_kind(osc))) + stop_names
            why = ("'gap' moves both stops of a symmetric clearance (b_low == b, or "
                   "Stops(mirror=True))" if name == "gap" else
                   "the mirrored lower stop follows b and R" if stops.mirror else
                   f"{name!r} needs a lower stop (stops=Stops(b_low=...))")
            raise ParameterError(f"{argument} must be one of {here} or an element for this "
                                 f"oscillator (b={osc.b!r}, {stops!r}); got {name!r}: {why}")
    element = element_name(name)
    if element is not None:
        return _element(name, *element, osc, argument)
    stop = stop_parameter_name(name)
    if stop is not None:
        return _stop_datum(name, *stop, osc, argument)
    return _named(name, osc)
