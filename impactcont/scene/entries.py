"""The entries of the built-in scene sections: one dataclass per table, validated.

A scene section (``[[branches]]``, ...) is an array of tables; each table is
validated into a frozen dataclass, a subclass of :class:`EntrySpec`, whose
keys are declared once as fields made by :func:`~impactcont.scene.keys.declare`.
This module holds the base class, the ``[oscillator]`` table, the keys every
continuation entry shares (:func:`continuation_entry`) and the entries of
``[[orbits]]``, ``[[branches]]``, ``[[robust]]`` and ``[[simulations]]``.
A problem of another package subclasses :class:`EntrySpec` the same way
(``docs/plugins.md``). The scene as a whole is in :mod:`impactcont.scene.schema`.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from impactcont.analysis.branch import check_continuation_arguments, continuation
from impactcont.detection import LABELS
from impactcont.errors import ImpactcontError, ParameterError
from impactcont.model.oscillator import ImpactOscillator, chain_stiffness
from impactcont.model.parameters import ParameterView
from impactcont.model.stops import (
    LOWER,
    UPPER,
    Stop,
    Stops,
    require_forcing,
    require_paper_stops,
)
from impactcont.orbit.robust import check_robust_arguments, robust_stability
from impactcont.scene.keys import (
    ENTRY_NAME,
    Boolean,
    Integer,
    Interval,
    ParameterName,
    Real,
    RealArray,
    String,
    StringList,
    ValueType,
    Where,
    declare,
    read_table,
    scene_keys,
    show,
)
from impactcont.simulate import simulate
from impactcont.vocabulary import PARAMETERS, Parameter

__all__ = [
    "CONTINUATION_KEYS",
    "PARAMETER_NAME",
    "PARAMETER_RANGES",
    "BranchSpec",
    "EntrySpec",
    "OrbitSpec",
    "OscillatorSpec",
    "RobustSpec",
    "SimulationSpec",
    "check_closed_form",
    "check_continuation",
    "continuation_entry",
    "defaults_of",
    "detect_key",
    "library_check",
    "refuse_changes",
    "spec_dict",
]


def _value_to_toml(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_value_to_toml(v) for v in value]
    if isinstance(value, dict):
        return {k: _value_to_toml(v) for k, v in value.items()}
    if isinstance(value, Stop):  # an extra stop: its table of extra_stops
        return value.to_dict()
    return value


def spec_dict(spec: Any) -> dict[str, Any]:
    """The scene keys of a spec with their values, ``None`` left out (TOML has no null)."""
    return {name: _value_to_toml(getattr(spec, name)) for name in scene_keys(type(spec))
            if getattr(spec, name) is not None}


# ---------------------------------------------------------------------------------------------
# The oscillator
# ---------------------------------------------------------------------------------------------
_OMEGA = Real(0.0, low_open=True)
_NONNEGATIVE = Real(0.0)
_RESTITUTION = Real(0.0, 1.0)
# The scalar parameters of an [oscillator] table (iterating PARAMETER_RANGES gives them).
_SCALARS = ("omega", "b", "R", "eta", "alpha", "beta", "F0")


def _admissible(info: Parameter) -> Real:
    """The vocabulary's range of a parameter as a scene value type."""
    return Real(None if info.low == -math.inf else info.low,
                None if info.high == math.inf else info.high, low_open=info.low_open)


#: Admissible values of each parameter, from its vocabulary record: a lookup resolves every
#: name :data:`impactcont.vocabulary.PARAMETERS` resolves (the stops' own ``b_low``,
#: ``R_low``, ``gap`` and the elements ``k2``, ``M[1,2]``, ``F[2]``, ...); iterating gives
#: the scalar parameters of an ``[oscillator]`` table (``omega``, ``b``, ``R``, ``eta``,
#: ``alpha``, ``beta``, ``F0``).
PARAMETER_RANGES: Mapping[str, Real] = ParameterView(_admissible, _SCALARS)
#: The value type of a continued parameter's name (``parameter = "k2"``).
PARAMETER_NAME = ParameterName()


#: The scene key of a :class:`~impactcont.model.stops.Stops` error, by how its message starts.
_STOPS_ERROR_KEYS = (("stops.mass", "stop_mass"), ("stops.relative_to", "stop_relative_to"),
                     ("stops.b_low", "b_low"),
                     ("stops.R_low", "R_low"), ("the lower stop", "b_low"),
                     ("stops.mirror", "mirror_stop"), ("mirrored stops", "b"),
                     ("stops '", "extra_stops"), ("Stop '", "extra_stops"),
                     ("stops.extra", "extra_stops"))


def _library_error_key(message: str, keys: Iterable[str]) -> str | None:
    """The argument a library error message starts with, if it is one of ``keys``.

    The stops' errors name the library's ``stops.<field>``; their scene keys are
    ``stop_mass``, ``b_low`` and ``R_low``.
    """
    text = message.strip()
    first = re.split(r"[\s,;:=\[]", text, maxsplit=1)[0]
    if first in keys:
        return first
    for start, key in _STOPS_ERROR_KEYS:
        if text.startswith(start) and key in keys:
            return key
    return None


def library_check(where: Where, check: Callable[..., Any], *args: Any,
                  keys: Iterable[str] = (), allowed: str | None = None, **kwargs: Any) -> Any:
    """Run an argument check of the library on an entry's arguments; refuse the scene if it fails.

    An entry is validated with the checks its driver's API function makes before it
    computes, on the arguments the driver passes, so that a scene that validates
    (``impactcont run --check``) does not then fail on its input.

    Parameters
    ----------
    where : Where
        The entry (or key) the arguments come from.
    check : callable
        The library's check, called as ``check(*args, **kwargs)``.
    keys : iterable of str
        Scene keys of the entry: an error message that starts with one of them is
        reported at that key.
    allowed : str, optional
        What is allowed, for the message.

    Returns
    -------
    object
        What ``check`` returns.

    Raises
    ------
    SceneError
        With the library's message, at the key it names (else at ``where``).
    """
    try:
        return check(*args, **kwargs)
    except (ImpactcontError, ValueError, TypeError) as exc:
        key = _library_error_key(str(exc), keys)
        raise (where.key(key) if key else where).error(str(exc), allowed) from None


#: What the closed-form sections take: the paper's single stop on mass 1.
_CLOSED_FORM_ALLOWED = ("an [oscillator] without stop_mass, stop_relative_to, b_low, R_low, "
                        "mirror_stop, F_static and free masses (the "
                        "paper's single "
                        "stop on mass 1); [[simulations]] with start = \"state\" and "
                        "[[multi_impact]] take other stops")


def check_closed_form(osc: ImpactOscillator, where: Where, what: str) -> None:
    """Refuse an oscillator the closed form of eq. (12)-(16) cannot take (its stops).

    The check :func:`~impactcont.periodic_orbits`, :func:`~impactcont.continuation`,
    the robust stability, curves and maps make (``what`` names the computation).
    """
    library_check(where, require_forcing, osc, what)  # its own "allowed", not the stops'
    library_check(where, require_paper_stops, osc, what, allowed=_CLOSED_FORM_ALLOWED)


#: The damping keys of [oscillator] that exclude each other: (keys, other keys, problem,
#: allowed).
_EXCLUSIVE_DAMPING = (
    (("eta",), ("alpha", "beta"), "give either eta or alpha/beta, not both",
     "eta (C = 2 eta K) or alpha, beta (C = alpha M + beta K)"),
    (("eta", "alpha", "beta"), ("C",), "give either a damping matrix C or eta or alpha/beta",
     "C (any damping matrix) without eta, alpha, beta"),
)


def damping_keys(osc: ImpactOscillator) -> set[str]:
    """The damping keys of the ``[oscillator]`` table ``osc`` was built from."""
    if osc.general_damping:
        return {"C"}
    if osc.eta is not None:
        return {"eta"}
    return {"alpha", "beta"} if osc.alpha is not None or osc.beta is not None else set()


def check_damping_keys(keys: Iterable[str], where: Where, inherited: Iterable[str] = ()
                       ) -> None:
    """Refuse damping keys that exclude each other (eta, alpha/beta, C).

    ``keys`` are those of one table (reported at ``where``), ``inherited`` those of
    the ``[oscillator]`` an entry changes: an entry's keys are refused exactly when
    ``[oscillator]`` would refuse them written into it, so that no key is dropped.
    """
    own, inherited = set(keys), set(inherited) - set(keys)
    given = own | inherited
    for first, second, problem, allowed in _EXCLUSIVE_DAMPING:
        if not (given & set(first) and given & set(second)):
            continue
        key = next((k for k in (*second, *first) if k in own), None)
        if key is None:
            continue
        clash = sorted(inherited & {*first, *second})
        if clash:
            problem += (f": [oscillator] has {' and '.join(clash)}, so an entry cannot set "
                        f"{key}")
            allowed = (f"the damping keys of [oscillator] ({', '.join(sorted(inherited))}), "
                       "or change the damping in [oscillator]")
        raise where.key(key).error(problem, allowed)


@dataclasses.dataclass(frozen=True, kw_only=True)
class ExtraStopSpec:
    """One table of ``extra_stops``: a stop on a further coordinate
    (:class:`~impactcont.model.stops.Stop`)."""

    name: str = declare(String(), "one letter naming the stop in impact patterns (not U, L)",
                        required=True)
    mass: int = declare(Integer(1), "the mass the stop acts on (1-based)", required=True)
    gap: float = declare(Real(), "the stop sits at s = side * gap", required=True)
    restitution: float = declare(_RESTITUTION, "restitution of this stop", required=True)
    side: int = declare(Integer(choices=(1, -1)), "+1: met moving up at s = gap; -1: met "
                        "moving down at s = -gap", 1)
    relative_to: int | None = declare(Integer(1), "a stop between two masses: s = x_mass - "
                                      "x_relative_to")


class _ExtraStops(ValueType):
    """``extra_stops``: an array of tables, each a :class:`ExtraStopSpec`."""

    allowed = ("an array of tables with keys name, mass, gap, restitution (required), side, "
               "relative_to")

    def check(self, value: Any, where: Where) -> tuple[Stop, ...]:
        if not isinstance(value, list):
            raise self.fail(value, where, "wrong type")
        out = []
        for i, raw in enumerate(value):
            here = where.item(i)
            values = read_table(ExtraStopSpec, raw, here)
            try:
                out.append(Stop(**values))
            except (ImpactcontError, ValueError, TypeError) as exc:
                key = next((k for k in ("restitution", "relative_to", "name", "side", "gap",
                                        "mass") if f" {k}" in str(exc)), None)
                raise (here.key(key) if key else here).error(str(exc)) from None
        return tuple(out)


@dataclasses.dataclass(frozen=True, kw_only=True)
class OscillatorSpec:
    """``[oscillator]``: the machine of eq. (1)-(4).

    Give the stiffness as ``K`` (a full symmetric matrix) or ``springs`` (the
    chain of eq. 2), the mass as ``M`` or ``masses`` (default: unit masses),
    and the damping as ``eta`` (``C = 2 eta K``) or ``alpha``/``beta``
    (``C = alpha M + beta K``) or a damping matrix ``C``; none means undamped.
    ``F_imag`` (the imaginary part of F) gives the masses their own forcing phases.
    ``stop_mass``, ``b_low`` and ``R_low`` place the stops on another mass and add a
    lower stop (:class:`~impactcont.model.stops.Stops`); ``mirror_stop`` adds the lower
    stop as the mirror of the upper one; ``stop_relative_to`` puts both stops between two
    masses (on ``x_j - x_k``: an impact pair, an impact damper's cavity); ``extra_stops``
    (an array of tables: name, mass, gap, restitution, side, relative_to) adds stops on
    further coordinates (docs/machines.md, "Stops on several masses"). ``F_static`` is a
    constant force (gravity, a preload, a mean torque). K (or a spring of the chain) may
    leave a mass free when a stop holds it (docs/machines.md).
    """

    M: tuple | None = declare(RealArray(2), "mass matrix (symmetric positive definite)")
    K: tuple | None = declare(RealArray(2), "stiffness matrix (symmetric positive "
                              "semi-definite; a free mode must be held by a stop)")
    masses: tuple | None = declare(RealArray(1, positive=True), "chain masses m_1..m_n (eq. 2)")
    springs: tuple | None = declare(RealArray(1, nonnegative=True),
                                    "chain springs k_1..k_n (eq. 2; 0 leaves a mass free)")
    F: tuple = declare(RealArray(1), "forcing amplitude vector, length n", required=True)
    R: float = declare(_RESTITUTION, "coefficient of restitution (eq. 4)", required=True)
    b: float = declare(Real(), "gap: mass 1 meets the stop at x1 = b (eq. 3)", required=True)
    omega: float = declare(_OMEGA, "forcing frequency", required=True)
    eta: float | None = declare(_NONNEGATIVE, "damping C = 2 eta K (the paper's)")
    alpha: float | None = declare(_NONNEGATIVE, "Rayleigh damping C = alpha M + beta K")
    beta: float | None = declare(_NONNEGATIVE, "Rayleigh damping C = alpha M + beta K")
    C: tuple | None = declare(RealArray(2), "damping matrix (symmetric positive semi-definite)")
    F_imag: tuple | None = declare(RealArray(1), "imaginary part of F: per-mass forcing phases")
    stop_mass: int | None = declare(Integer(1), "the mass meeting the stops (1-based; "
                                    "default 1)")
    b_low: float | None = declare(Real(), "a lower stop at x_j = -b_low (j = stop_mass)")
    R_low: float | None = declare(_RESTITUTION, "restitution of the lower stop (default R)")
    mirror_stop: bool = declare(Boolean(), "a lower stop at x_j = -b with restitution R that "
                                "moves with b and R (a symmetric backlash)", False)
    stop_relative_to: int | None = declare(Integer(1), "a clearance between two masses: the "
                                           "stops act on x_j - x_k (k = stop_relative_to, "
                                           "j = stop_mass), two-body impact law")
    F_static: tuple | None = declare(RealArray(1), "constant force vector, length n (gravity, "
                                     "a preload, a mean torque)")
    extra_stops: tuple | None = declare(_ExtraStops(), "stops on further coordinates, each a "
                                        "table: name, mass, gap, restitution, side (+1/-1), "
                                        "relative_to")

    @classmethod
    def parse(cls, raw: Any, where: Where) -> OscillatorSpec:
        values = read_table(cls, raw, where)
        for a, b in (("M", "masses"), ("K", "springs")):
            if a in values and b in values:
                raise where.key(b).error(f"give either {a} or {b}, not both",
                                         f"{a} (a matrix) or {b} (the chain of eq. 2)")
        if "K" not in values and "springs" not in values:
            raise where.key("K").error("the stiffness is missing",
                                       "K (a matrix) or springs (the chain of eq. 2)")
        check_damping_keys(values, where)
        spec = cls(**values)
        try:
            spec.build()
        except (ImpactcontError, ValueError, TypeError) as exc:
            key = _library_error_key(str(exc), scene_keys(cls))
            raise (where.key(key) if key else where).error(str(exc)) from None
        return spec

    def build(self) -> ImpactOscillator:
        """The :class:`~impactcont.ImpactOscillator` this table describes."""
        damping = {k: getattr(self, k) for k in ("eta", "alpha", "beta")
                   if getattr(self, k) is not None}
        if self.C is not None:
            damping["C"] = np.array(self.C, dtype=float)
        F = np.array(self.F, dtype=float)
        if self.F_imag is not None:
            if len(self.F_imag) != F.size:
                raise ParameterError(f"F_imag must have the length of F ({F.size}); got "
                                     f"{list(self.F_imag)!r}")
            F = F + 1j * np.array(self.F_imag, dtype=float)
        params = {"F": F, "R": self.R, "b": self.b, "omega": self.omega, **damping}
        if (self.stop_mass is not None or self.b_low is not None or self.R_low is not None
                or self.mirror_stop or self.stop_relative_to is not None or self.extra_stops):
            params["stops"] = Stops(mass=1 if self.stop_mass is None else self.stop_mass,
                                    b_low=self.b_low, R_low=self.R_low, mirror=self.mirror_stop,
                                    relative_to=self.stop_relative_to,
                                    extra=self.extra_stops or ())
        if self.F_static is not None:
            params["F_static"] = np.array(self.F_static, dtype=float)
        K = (chain_stiffness(list(self.springs)) if self.springs is not None
             else np.array(self.K, dtype=float))
        if self.M is not None:
            M = np.array(self.M, dtype=float)
        elif self.masses is not None:
            M = np.diag(np.array(self.masses, dtype=float))
        else:
            M = np.eye(K.shape[0])
        return ImpactOscillator(M=M, K=K, **params)


# ---------------------------------------------------------------------------------------------
# Entries of the sections
# ---------------------------------------------------------------------------------------------
def defaults_of(func: Callable[..., Any]) -> dict[str, Any]:
    """Keyword defaults of a library function, so a scene never restates them."""
    return {name: p.default for name, p in inspect.signature(func).parameters.items()
            if p.default is not inspect.Parameter.empty}


@dataclasses.dataclass(frozen=True, kw_only=True)
class EntrySpec:
    """Base of one table of a section (``[[branches]]``, ...).

    Every entry has a ``name`` (unique in the scene; default
    ``<section><number>``) and may change the oscillator's parameters for
    itself: ``F``, ``F_imag``, ``R``, ``b``, ``omega``, ``eta``, ``alpha``, ``beta``.
    As in ``[oscillator]``, ``F`` is the real part of the forcing vector and ``F_imag``
    its imaginary part (per-mass phases); each one an entry leaves out is the
    oscillator's, so ``F`` alone changes the amplitudes and keeps the phases.
    Subclasses add their keys and override :meth:`check` for the rules that
    involve several keys or the oscillator.
    """

    section: ClassVar[str] = ""

    name: str = declare(ENTRY_NAME,
                     "entry name, unique in the scene (default <section><number>)", "")
    F: tuple | None = declare(RealArray(1), "forcing vector (real part) for this entry")
    R: float | None = declare(_RESTITUTION, "restitution for this entry")
    b: float | None = declare(Real(), "gap for this entry")
    omega: float | None = declare(_OMEGA, "forcing frequency for this entry")
    eta: float | None = declare(_NONNEGATIVE, "damping eta for this entry")
    alpha: float | None = declare(_NONNEGATIVE, "Rayleigh alpha for this entry")
    beta: float | None = declare(_NONNEGATIVE, "Rayleigh beta for this entry")
    F_imag: tuple | None = declare(RealArray(1), "imaginary part of F for this entry "
                                   "(default: the oscillator's)")

    #: The oscillator of this entry (the scene's with this entry's changes); set by parsing.
    oscillator: ImpactOscillator | None = dataclasses.field(default=None, repr=False,
                                                            compare=False)

    @property
    def changes(self) -> dict[str, Any]:
        """The oscillator parameters this entry changes."""
        out = {k: getattr(self, k) for k in ("F", "F_imag", "R", "b", "omega", "eta", "alpha",
                                             "beta") if getattr(self, k) is not None}
        for key in ("F", "F_imag"):
            if key in out:
                out[key] = list(out[key])
        return out

    def _parameters(self, base: ImpactOscillator) -> dict[str, Any]:
        """:attr:`changes` as arguments of ``base.replace``: ``F`` and ``F_imag`` combined
        into one forcing vector, the part the entry leaves out taken from ``base``."""
        out = self.changes
        if "F" in out or "F_imag" in out:
            real = np.array(out.get("F", base.F.real), dtype=float)
            if "F_imag" in out:
                imag = np.array(out.pop("F_imag"), dtype=float)
            else:
                imag = base.F.imag if base.F.dtype.kind == "c" else np.zeros(real.shape)
            if imag.shape != real.shape:
                raise ParameterError(f"F_imag must have the length of F ({real.size}); got "
                                     f"{imag.tolist()!r}")
            out["F"] = real + 1j * imag  # a zero imaginary part gives a real F
        return out

    @classmethod
    def parse(cls, raw: Any, where: Where, base: ImpactOscillator, index: int, *,
              section: str | None = None) -> EntrySpec:
        """Validate one table (``index`` in its section ``section``, default ``cls.section``)."""
        values = read_table(cls, raw, where)
        values.setdefault("name", f"{section or cls.section}{index + 1}")
        spec = cls(**values)
        check_damping_keys(spec.changes, where, inherited=damping_keys(base))
        try:
            osc = base.replace(**spec._parameters(base))
        except (ImpactcontError, ValueError, TypeError) as exc:
            key = _library_error_key(str(exc), spec.changes)
            raise (where.key(key) if key else where).error(str(exc)) from None
        spec = dataclasses.replace(spec, oscillator=osc)
        spec.check(where, osc)
        return spec

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        """Rules involving several keys or the oscillator; raise ``where.error(...)``."""

    def check_scene(self, where: Where, sections: Mapping[str, tuple[EntrySpec, ...]]
                    ) -> None:
        """Rules involving other entries of the scene (references by name)."""

    def to_dict(self) -> dict[str, Any]:
        """The entry as a TOML table (defaults filled in)."""
        return spec_dict(self)


def detect_key() -> Any:
    """The ``detect`` key of a continuing entry: the special points to detect (default all)."""
    return declare(StringList(tuple(LABELS)), "special points to detect ([] for none)",
                   tuple(LABELS))


def refuse_changes(entry: EntrySpec, where: Where, why: str) -> None:
    """Raise when an entry that takes another entry's oscillator changes the oscillator."""
    if entry.changes:
        raise where.key(next(iter(entry.changes))).error(why,
                                                         "leave out the oscillator parameters")


def _check_damping_parameter(name: str, osc: ImpactOscillator, where: Where) -> None:
    if name in ("eta", "alpha", "beta") and osc.general_damping:
        raise where.error(f"{name!r} is meaningless with a damping matrix C",
                          "omega, b, R, F0 (C fixes the damping)")
    if name == "eta" and osc.eta is None:
        raise where.error("'eta' needs the paper's damping C = 2 eta K; the oscillator uses "
                          "alpha/beta", "alpha, beta (the damping the oscillator uses)")
    if name in ("alpha", "beta") and osc.eta is not None:
        raise where.error(f"{name!r} needs Rayleigh damping; the oscillator uses eta",
                          "eta (the damping the oscillator uses)")




@dataclasses.dataclass(frozen=True, kw_only=True)
class OrbitSpec(EntrySpec):
    """``[[orbits]]``: every root of eq. (15) at one parameter point, with G and its checks."""

    section: ClassVar[str] = "orbits"

    N: int = declare(Integer(1, 1000), "one impact every N forcing periods", 1)
    which: str = declare(String(("all", "physical", "stable")),
                      "which roots to keep: all (with their physical flag), only physical "
                      "ones, or only physical and stable ones", "all")

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        check_closed_form(osc, where, "the N-1 closed form")


#: The keys every continuing entry has (:func:`continuation_entry`).
CONTINUATION_KEYS = ("ds", "ds_min", "ds_max", "newton_tol", "max_points", "both_directions")

_POSITIVE = Real(0.0, low_open=True)
#: Value type, meaning and Python type of each continuation key.
_CONTINUATION_FIELDS: dict[str, tuple[ValueType, str, type]] = {
    "ds": (_POSITIVE, "initial arclength step", float),
    "ds_min": (_POSITIVE, "smallest step", float),
    "ds_max": (_POSITIVE, "largest step", float),
    "newton_tol": (_POSITIVE, "Newton tolerance", float),
    "max_points": (Integer(2, 10_000_000), "largest number of points per direction", int),
    "both_directions": (Boolean(), "continue both ways from the start", bool),
}


def _check_steps(self: Any, where: Where, osc: ImpactOscillator) -> None:
    steps = [getattr(self, k, None) for k in ("ds_min", "ds", "ds_max")]
    known = [v for v in steps if v is not None]
    if known != sorted(known):
        shown = ", ".join(f"{k} = {v!r}" for k, v in zip(("ds_min", "ds", "ds_max"), steps,
                                                          strict=True) if v is not None)
        raise where.key("ds").error(shown, "ds_min <= ds <= ds_max")


def _continuation_options(self: Any) -> dict[str, Any]:
    """The continuation keys given (or defaulted) as keyword arguments of the driver."""
    return {k: getattr(self, k) for k in CONTINUATION_KEYS
            if hasattr(self, k) and getattr(self, k) is not None}


def check_continuation(osc: ImpactOscillator, where: Where, N: int, parameter: str,
                       bounds: tuple[float, float], *, start: float | None = None,
                       root: int | None = None, detect: Sequence[str] = tuple(LABELS),
                       **options: Any) -> None:
    """The checks :func:`impactcont.continuation` makes before it computes, on its arguments.

    ``where`` is the entry; the arguments are those the entry passes to the driver
    (:meth:`BranchSpec.continuation_kwargs`). A failing check is reported at the key
    its message names (``parameter``, ``bounds``, ``ds``, ...), else at the entry.
    """
    check_closed_form(osc, where, "the N-1 branch")
    library_check(where, check_continuation_arguments, osc, N, parameter, bounds,
                  detect=detect, **options,
                  keys=("N", "parameter", "bounds", "start", "root", "detect",
                        *CONTINUATION_KEYS))


def continuation_entry(func: Callable[..., Any], name: str,
                       keys: Sequence[str] = CONTINUATION_KEYS) -> type[EntrySpec]:
    """A base entry with continuation keys that take the defaults of ``func``.

    Every continuing section (``[[branches]]``, ``[[curves]]``,
    ``[[switches]]``, a plugin's) subclasses it, so the keys ``ds``,
    ``ds_min``, ``ds_max``, ``newton_tol``, ``max_points`` and
    ``both_directions`` are spelled, checked (``ds_min <= ds <= ds_max``) and
    passed the same way everywhere, with the defaults of the driver ``func``
    (a scene never restates them; a key ``func`` defaults to None, or does not
    have, is left to the driver when the scene omits it).
    ``entry.continuation_options()`` gives them as keyword arguments.

    Parameters
    ----------
    func : callable
        The driver whose keyword defaults the keys take.
    name : str
        The class name (for error messages and the documentation).
    keys : sequence of str
        The continuation keys the section has (a subset of ``CONTINUATION_KEYS``).
    """
    defaults = defaults_of(func)
    fields = [(k, _CONTINUATION_FIELDS[k][2] | None,
               declare(_CONTINUATION_FIELDS[k][0], _CONTINUATION_FIELDS[k][1], defaults.get(k)))
              for k in keys]
    return dataclasses.make_dataclass(
        name, fields, bases=(EntrySpec,), frozen=True, kw_only=True,
        namespace={"check": _check_steps, "continuation_options": _continuation_options,
                   "__module__": __name__,
                   "__doc__": f"Continuation keys {', '.join(keys)} (defaults of "
                              f"{func.__module__}.{func.__qualname__})."})


@dataclasses.dataclass(frozen=True, kw_only=True)
class BranchSpec(continuation_entry(continuation, "BranchEntry")):
    """``[[branches]]``: a one-parameter branch of N-1 motions with its special points."""

    section: ClassVar[str] = "branches"

    N: int = declare(Integer(1, 1000), "one impact every N forcing periods", 1)
    parameter: str = declare(PARAMETER_NAME, "the continued parameter (an element: \"k2\", "
                             "\"M[1,2]\", \"F[2]\", ...)", "omega")
    bounds: tuple[float, float] = declare(Interval(), "range of the parameter", required=True)
    start: float | None = declare(Real(), "parameter value to start from (inside bounds)")
    root: int | None = declare(Integer(choices=(1, -1)), "root of eq. (15) to start on")
    detect: tuple[str, ...] = detect_key()

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        super().check(where, osc)
        lo, hi = self.bounds
        admissible = PARAMETER_RANGES[self.parameter]
        if not (admissible.inside(lo) and admissible.inside(hi)):
            raise where.key("bounds").error(
                f"{show(list(self.bounds))} leaves the admissible values of "
                f"{self.parameter}", f"bounds inside the range of {self.parameter}: "
                f"{admissible.allowed}")
        if self.start is not None and not lo <= self.start <= hi:
            raise where.key("start").error(f"{self.start!r} is outside bounds "
                                           f"{show(list(self.bounds))}",
                                           f"a real number in [{lo:g}, {hi:g}]")
        _check_damping_parameter(self.parameter, osc, where.key("parameter"))
        check_continuation(osc, where, **self.continuation_kwargs())

    def continuation_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`impactcont.continuation` for this branch."""
        return {"N": self.N, "parameter": self.parameter, "bounds": self.bounds,
                "start": self.start, "root": self.root, "detect": self.detect,
                **self.continuation_options()}


class _Box(ValueType):
    """A table ``{name = [lo, hi], ...}`` of uncertain parameters (what robust stability
    can vary of the oscillator is checked with it: :func:`~impactcont.orbit.robust.
    check_robust_arguments`)."""

    allowed = ("a table {name = [lo, hi]} with names b, omega, R, eta, alpha, beta, F0 or "
               "an element (\"k2\", \"M[1,2]\", \"F[2]\", 1-based), and lo < hi")

    def check(self, value: Any, where: Where) -> dict[str, tuple[float, float]]:
        if not isinstance(value, dict) or not value:
            raise self.fail(value, where, "wrong type or empty")
        out = {}
        for name, interval in value.items():  # the names: check_robust_arguments
            bound = PARAMETER_RANGES.get(name, Real()) if name in PARAMETERS else Real()
            out[name] = Interval(bound).check(interval, where.key(name))
        return out


class _Point(ValueType):
    allowed = "a table {name = value} of real numbers"

    def check(self, value: Any, where: Where) -> dict[str, float]:
        if not isinstance(value, dict):
            raise self.fail(value, where, "wrong type")
        return {k: Real().check(v, where.key(k)) for k, v in value.items()}


_ROBUST = defaults_of(robust_stability)


@dataclasses.dataclass(frozen=True, kw_only=True)
class RobustSpec(EntrySpec):
    """``[[robust]]``: robust stability of an N-1 motion over a parameter box (eq. 26-29)."""

    section: ClassVar[str] = "robust"

    N: int = declare(Integer(1, 1000), "one impact every N forcing periods", 1)
    vary: Mapping[str, tuple[float, float]] = declare(
        _Box(), "the box Q of uncertain parameters", required=True)
    nominal: Mapping[str, float] | None = declare(
        _Point(), "q0 inside the box (default its centre)")
    root: int | None = declare(Integer(choices=(1, -1)), "root of eq. (15) to follow")
    samples: int = declare(Integer(2, 100_001), "grid points per parameter", _ROBUST["samples"])

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        for name in self.vary:
            if name in ("eta", "alpha", "beta"):
                _check_damping_parameter(name, osc, where.key("vary").key(name))
        for name, value in (self.nominal or {}).items():
            if name not in self.vary:
                raise where.key("nominal").key(name).error(
                    "not a parameter of vary", ", ".join(self.vary))
            lo, hi = self.vary[name]
            if not lo <= value <= hi:
                raise where.key("nominal").key(name).error(
                    f"{value!r} is outside the box", f"a real number in [{lo:g}, {hi:g}]")
        if self.samples ** len(self.vary) > 1_000_000:
            raise where.key("samples").error(
                f"{self.samples} per parameter for {len(self.vary)} parameters is "
                f"{self.samples ** len(self.vary)} grid points", "at most 1000000 grid points")
        for name in self.vary:
            if name in self.changes:
                raise where.key(name).error(
                    f"{name} is varied over the box, where its nominal value is nominal.{name} "
                    f"(default the box centre): {name} = {self.changes[name]!r} would not be "
                    "used", f"nominal = {{ {name} = {self.changes[name]!r} }} instead")
        _check_robust(osc, where, self)


def _check_robust(osc: ImpactOscillator, where: Where, spec: RobustSpec) -> None:
    """The checks :func:`impactcont.robust_stability` makes before it computes
    (:func:`~impactcont.orbit.robust.check_robust_arguments`: the box, the nominal point,
    every end of the box admissible), then the stops."""
    library_check(where.key("vary"), check_robust_arguments, osc, spec.N, spec.vary,
                  nominal=spec.nominal, root=spec.root, samples=spec.samples)
    check_closed_form(osc, where, "the N-1 closed form")


_SIM = defaults_of(simulate)


def _check_start_state(where: Where, osc: ImpactOscillator, state: tuple) -> None:
    """Refuse a start state beyond any stop, each on its own stop coordinate.

    Every stop (``U``, ``L``, each extra stop) is read through
    :meth:`~impactcont.model.stops.Stops.stop`: the state's ``s = normal . x`` must lie on
    the open side of the stop, ``sign (s - position) <= 0`` (eq. 3 on ``x_j``, on
    ``x_j - x_k`` for a clearance between masses).
    """
    x = np.asarray(state[:osc.n], dtype=float)
    for name in osc.stops.names:
        view = osc.stops.stop(name, osc.M, osc.b, osc.R)
        s = float(view.normal @ x)
        if view.sign * (s - view.position) > 0:
            coordinate = (osc.stops.coordinate if name in (UPPER, LOWER)
                          else osc.stops.extra_stop(name).coordinate)
            relation = "<=" if view.sign > 0 else ">="
            raise where.error(f"{coordinate} = {s!r} is beyond stop {name!r} at "
                              f"{view.position!r}", f"{coordinate} {relation} {view.position!r}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class SimulationSpec(EntrySpec):
    """``[[simulations]]``: the event-driven simulator from a periodic motion or a state."""

    section: ClassVar[str] = "simulations"

    periods: float = declare(Real(0.0, 1e7, low_open=True), "duration in forcing periods",
                          required=True)
    start: str = declare(String(("orbit", "state")),
                      "start on the N-1 motion (orbit) or at a given state and phase", "orbit")
    N: int = declare(Integer(1, 1000), "with start = orbit: the N of the motion", 1)
    root: int | None = declare(Integer(choices=(1, -1)), "with start = orbit: which root")
    state: tuple | None = declare(RealArray(1), "with start = state: [x1..xn, v1..vn] at t = 0")
    delta: float | None = declare(Real(), "with start = state: forcing phase at t = 0")
    perturbation: float = declare(Real(0.0), "added to every velocity of the start state", 0.0)
    trajectory: bool = declare(Boolean(), "store the sampled time history (dense)", False)
    samples_per_period: int = declare(Integer(2, 100_000), "trajectory samples per period",
                                   _SIM["samples_per_period"])
    max_impacts: int = declare(Integer(1), "stop after this many impacts", _SIM["max_impacts"])

    def check(self, where: Where, osc: ImpactOscillator) -> None:
        if self.start == "state":
            for key in ("state", "delta"):
                if getattr(self, key) is None:
                    raise where.key(key).error("required with start = \"state\"",
                                               "a start state [x1..xn, v1..vn] and its phase"
                                               " delta")
            if len(self.state) != 2 * osc.n:
                raise where.key("state").error(f"has length {len(self.state)}",
                                               f"an array of 2n = {2 * osc.n} real numbers")
            _check_start_state(where.key("state"), osc, self.state)
        else:
            if not osc.stops.paper:
                raise where.key("start").error(
                    "\"orbit\" starts on the closed-form N-1 motion, which handles one stop "
                    f"on mass 1 only (the oscillator has stops={osc.stops!r})",
                    'start = "state" with state and delta')
            for key in ("state", "delta"):
                if getattr(self, key) is not None:
                    raise where.key(key).error("only used with start = \"state\"",
                                               "leave it out, or set start = \"state\"")


