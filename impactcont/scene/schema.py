"""The scene format: a TOML file describing one study, validated into dataclasses.

A scene names the oscillator (``[oscillator]``), what to compute (one
array of tables per section: ``[[orbits]]``, ``[[branches]]``,
``[[robust]]``, ``[[simulations]]``; more sections plug in through
:mod:`impactcont.scene.sections`), the figures (``[[plots]]``) and where to
write (``[output]``). The format is documented in ``docs/scenes.md``.

Validation turns the TOML tables into frozen dataclasses and stops at the
first problem with a :class:`SceneError` that names the file, the line when it
can be found, the key path (``branches[1].bounds``), the value received and
what is allowed; an unknown key gets a "did you mean" suggestion. Every key of
every table is declared once, as a dataclass field with a :class:`Key`
description in its metadata; the resolved scene (defaults filled in,
``--set`` overrides applied) is :meth:`Scene.to_dict`.
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import json
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from impactcont.errors import ImpactcontError
from impactcont.model.oscillator import ImpactOscillator, chain_stiffness
from impactcont.scene.keys import (
    NAME_ALLOWED,
    NAME_PATTERN,
    Boolean,
    Integer,
    Interval,
    Key,
    Names,
    Real,
    RealArray,
    SceneError,
    String,
    StringList,
    ValueType,
    Where,
    declare,
    read_table,
    scene_keys,
    show,
    type_name,
    unknown_key,
)
from impactcont.scene.source import apply_settings, locator, tomllib

__all__ = [
    "PARAMETER_RANGES",
    "BranchSpec",
    "EntrySpec",
    "Key",
    "OrbitSpec",
    "OscillatorSpec",
    "OutputSpec",
    "PlotSpec",
    "RobustSpec",
    "Scene",
    "SceneError",
    "SimulationSpec",
    "apply_settings",
    "load_scene",
    "parse_scene",
    "scene_keys",
]


def _value_to_toml(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_value_to_toml(v) for v in value]
    if isinstance(value, dict):
        return {k: _value_to_toml(v) for k, v in value.items()}
    return value


def _spec_dict(spec: Any) -> dict[str, Any]:
    """The scene keys of a spec with their values, ``None`` left out (TOML has no null)."""
    return {name: _value_to_toml(getattr(spec, name)) for name in scene_keys(type(spec))
            if getattr(spec, name) is not None}


# ---------------------------------------------------------------------------------------------
# The oscillator
# ---------------------------------------------------------------------------------------------
_OMEGA = Real(0.0, low_open=True)
_NONNEGATIVE = Real(0.0)
_RESTITUTION = Real(0.0, 1.0)
#: Admissible values of each scalar model parameter.
PARAMETER_RANGES: dict[str, Real] = {"omega": _OMEGA, "b": Real(), "R": _RESTITUTION,
                                     "eta": _NONNEGATIVE, "alpha": _NONNEGATIVE,
                                     "beta": _NONNEGATIVE}


def _library_error_key(message: str, keys: Iterable[str]) -> str | None:
    """The argument a library error message starts with, if it is one of ``keys``."""
    first = re.split(r"[\s,;:]", message.strip(), maxsplit=1)[0]
    return first if first in keys else None


@dataclasses.dataclass(frozen=True, kw_only=True)
class OscillatorSpec:
    """``[oscillator]``: the machine of eq. (1)-(4).

    Give the stiffness as ``K`` (a full symmetric matrix) or ``springs`` (the
    chain of eq. 2), the mass as ``M`` or ``masses`` (default: unit masses),
    and the damping as ``eta`` (``C = 2 eta K``) or ``alpha``/``beta``
    (``C = alpha M + beta K``); none means undamped.
    """

    M: tuple | None = declare(RealArray(2), "mass matrix (symmetric positive definite)")
    K: tuple | None = declare(RealArray(2), "stiffness matrix (symmetric positive definite)")
    masses: tuple | None = declare(RealArray(1, positive=True), "chain masses m_1..m_n (eq. 2)")
    springs: tuple | None = declare(RealArray(1, positive=True), "chain springs k_1..k_n (eq. 2)")
    F: tuple = declare(RealArray(1), "forcing amplitude vector, length n", required=True)
    R: float = declare(_RESTITUTION, "coefficient of restitution (eq. 4)", required=True)
    b: float = declare(Real(), "gap: mass 1 meets the stop at x1 = b (eq. 3)", required=True)
    omega: float = declare(_OMEGA, "forcing frequency", required=True)
    eta: float | None = declare(_NONNEGATIVE, "damping C = 2 eta K (the paper's)")
    alpha: float | None = declare(_NONNEGATIVE, "Rayleigh damping C = alpha M + beta K")
    beta: float | None = declare(_NONNEGATIVE, "Rayleigh damping C = alpha M + beta K")

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
        if "eta" in values and ("alpha" in values or "beta" in values):
            key = "alpha" if "alpha" in values else "beta"
            raise where.key(key).error("give either eta or alpha/beta, not both",
                                       "eta (C = 2 eta K) or alpha, beta (C = alpha M + beta K)")
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
        params = {"F": list(self.F), "R": self.R, "b": self.b, "omega": self.omega, **damping}
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
def _defaults_of(func: Callable[..., Any]) -> dict[str, Any]:
    """Keyword defaults of a library function, so a scene never restates them."""
    return {name: p.default for name, p in inspect.signature(func).parameters.items()
            if p.default is not inspect.Parameter.empty}


@dataclasses.dataclass(frozen=True, kw_only=True)
class EntrySpec:
    """Base of one table of a section (``[[branches]]``, ...).

    Every entry has a ``name`` (unique in the scene; default
    ``<section><number>``) and may change the oscillator's parameters for
    itself: ``F``, ``R``, ``b``, ``omega``, ``eta``, ``alpha``, ``beta``.
    Subclasses add their keys and override :meth:`check` for the rules that
    involve several keys or the oscillator.
    """

    section: ClassVar[str] = ""

    name: str = declare(String(pattern=NAME_PATTERN, pattern_text=NAME_ALLOWED),
                     "entry name, unique in the scene (default <section><number>)", "")
    F: tuple | None = declare(RealArray(1), "forcing vector for this entry")
    R: float | None = declare(_RESTITUTION, "restitution for this entry")
    b: float | None = declare(Real(), "gap for this entry")
    omega: float | None = declare(_OMEGA, "forcing frequency for this entry")
    eta: float | None = declare(_NONNEGATIVE, "damping eta for this entry")
    alpha: float | None = declare(_NONNEGATIVE, "Rayleigh alpha for this entry")
    beta: float | None = declare(_NONNEGATIVE, "Rayleigh beta for this entry")

    #: The oscillator of this entry (the scene's with this entry's changes); set by parsing.
    oscillator: ImpactOscillator | None = dataclasses.field(default=None, repr=False,
                                                            compare=False)

    @property
    def changes(self) -> dict[str, Any]:
        """The oscillator parameters this entry changes."""
        out = {k: getattr(self, k) for k in ("F", "R", "b", "omega", "eta", "alpha", "beta")
               if getattr(self, k) is not None}
        if "F" in out:
            out["F"] = list(out["F"])
        return out

    @classmethod
    def parse(cls, raw: Any, where: Where, base: ImpactOscillator, index: int) -> EntrySpec:
        values = read_table(cls, raw, where)
        values.setdefault("name", f"{cls.section}{index + 1}")
        spec = cls(**values)
        try:
            osc = base.replace(**spec.changes)
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
        return _spec_dict(self)


def _check_damping_parameter(name: str, osc: ImpactOscillator, where: Where) -> None:
    if name == "eta" and osc.eta is None:
        raise where.error("'eta' needs the paper's damping C = 2 eta K; the oscillator uses "
                          "alpha/beta", "alpha, beta (the damping the oscillator uses)")
    if name in ("alpha", "beta") and osc.eta is not None:
        raise where.error(f"{name!r} needs Rayleigh damping; the oscillator uses eta",
                          "eta (the damping the oscillator uses)")


def _continuation_defaults() -> dict[str, Any]:
    from impactcont.branch import continuation

    return _defaults_of(continuation)


_CONT = _continuation_defaults()


@dataclasses.dataclass(frozen=True, kw_only=True)
class OrbitSpec(EntrySpec):
    """``[[orbits]]``: every root of eq. (15) at one parameter point, with G and its checks."""

    section: ClassVar[str] = "orbits"

    N: int = declare(Integer(1, 1000), "one impact every N forcing periods", 1)
    which: str = declare(String(("all", "physical", "stable")),
                      "which roots to keep: all (with their physical flag), only physical "
                      "ones, or only physical and stable ones", "all")


def _branch_parameters() -> tuple[str, ...]:
    from impactcont.problems import CONTINUABLE_PARAMETERS

    return tuple(CONTINUABLE_PARAMETERS)


def _special_labels() -> tuple[str, ...]:
    from impactcont.detection import LABELS

    return tuple(LABELS)


@dataclasses.dataclass(frozen=True, kw_only=True)
class BranchSpec(EntrySpec):
    """``[[branches]]``: a one-parameter branch of N-1 motions with its special points."""

    section: ClassVar[str] = "branches"

    N: int = declare(Integer(1, 1000), "one impact every N forcing periods", 1)
    parameter: str = declare(String(_branch_parameters()), "the continued parameter", "omega")
    bounds: tuple[float, float] = declare(Interval(), "range of the parameter", required=True)
    start: float | None = declare(Real(), "parameter value to start from (inside bounds)")
    root: int | None = declare(Integer(choices=(1, -1)), "root of eq. (15) to start on")
    detect: tuple[str, ...] = declare(StringList(_special_labels()),
                                   "special points to detect ([] for none)", _special_labels())
    ds: float = declare(Real(0.0, low_open=True), "initial arclength step", _CONT["ds"])
    ds_min: float = declare(Real(0.0, low_open=True), "smallest step", _CONT["ds_min"])
    ds_max: float = declare(Real(0.0, low_open=True), "largest step", _CONT["ds_max"])
    newton_tol: float = declare(Real(0.0, low_open=True), "Newton tolerance",
                             _CONT["newton_tol"])
    max_points: int = declare(Integer(2, 10_000_000), "largest number of points per direction",
                           _CONT["max_points"])
    both_directions: bool = declare(Boolean(), "continue both ways from the start",
                                 _CONT["both_directions"])

    def check(self, where: Where, osc: ImpactOscillator) -> None:
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
        if not self.ds_min <= self.ds <= self.ds_max:
            raise where.key("ds").error(
                f"{self.ds!r} with ds_min = {self.ds_min!r} and ds_max = {self.ds_max!r}",
                "ds_min <= ds <= ds_max")
        _check_damping_parameter(self.parameter, osc, where.key("parameter"))

    def continuation_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`impactcont.continuation` for this branch."""
        return {"N": self.N, "parameter": self.parameter, "bounds": self.bounds,
                "start": self.start, "root": self.root, "detect": self.detect, "ds": self.ds,
                "ds_min": self.ds_min, "ds_max": self.ds_max, "newton_tol": self.newton_tol,
                "max_points": self.max_points, "both_directions": self.both_directions}


_VARY_NAME = re.compile(r"^(b|omega|R|eta|alpha|beta|F\[\d+\])$")


class _Box(ValueType):
    """A table ``{name = [lo, hi], ...}`` of uncertain parameters."""

    allowed = ("a table {name = [lo, hi]} with names b, omega, R, eta, alpha, beta or "
               "\"F[i]\", and lo < hi")

    def check(self, value: Any, where: Where) -> dict[str, tuple[float, float]]:
        if not isinstance(value, dict) or not value:
            raise self.fail(value, where, "wrong type or empty")
        out = {}
        for name, interval in value.items():
            if not _VARY_NAME.match(name):
                close = difflib.get_close_matches(name, list(PARAMETER_RANGES), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise where.key(name).error(f"unknown parameter {name!r}{hint}", self.allowed)
            bound = PARAMETER_RANGES.get(name, Real())
            out[name] = Interval(bound).check(interval, where.key(name))
        return out


class _Point(ValueType):
    allowed = "a table {name = value} of real numbers"

    def check(self, value: Any, where: Where) -> dict[str, float]:
        if not isinstance(value, dict):
            raise self.fail(value, where, "wrong type")
        return {k: Real().check(v, where.key(k)) for k, v in value.items()}


def _robust_defaults() -> dict[str, Any]:
    from impactcont.orbit.robust import robust_stability

    return _defaults_of(robust_stability)


_ROBUST = _robust_defaults()


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
            m = re.match(r"^F\[(\d+)\]$", name)
            if m and int(m.group(1)) >= osc.n:
                raise where.key("vary").key(name).error(
                    f"indexes past F (length {osc.n})", f'"F[i]" with 0 <= i < {osc.n}')
            if not m:
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


def _simulate_defaults() -> dict[str, Any]:
    from impactcont.simulate import simulate

    return _defaults_of(simulate)


_SIM = _simulate_defaults()


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
            if self.state[0] > osc.b:
                raise where.key("state").error(f"x1 = {self.state[0]!r} is beyond the stop "
                                               f"b = {osc.b!r}", "x1 <= b")
        else:
            for key in ("state", "delta"):
                if getattr(self, key) is not None:
                    raise where.key(key).error("only used with start = \"state\"",
                                               "leave it out, or set start = \"state\"")


# ---------------------------------------------------------------------------------------------
# Plots and output
# ---------------------------------------------------------------------------------------------
def _plot_kinds() -> dict[str, Any]:
    from impactcont.scene.sections import plot_kinds

    return plot_kinds()


def _point_variables() -> tuple[str, ...]:
    return ("impact_velocity", "delta", "gap_min", "spectral_radius", "arclength", "omega", "b")


@dataclasses.dataclass(frozen=True, kw_only=True)
class PlotSpec:
    """``[[plots]]``: one PNG drawn from the data of computed entries."""

    section: ClassVar[str] = "plots"

    name: str = declare(String(pattern=NAME_PATTERN, pattern_text=NAME_ALLOWED),
                     "plot name; the file is <name>.png unless file is given", "")
    kind: str = declare(String(), "what to draw (see the list of plot kinds)", required=True)
    data: tuple[str, ...] | None = declare(Names(), "names of the entries to draw (default: all "
                                        "entries of the section the kind reads)")
    y: str = declare(String(_point_variables()), "bifurcation_diagram: the branch variable on "
                  "the vertical axis", "impact_velocity")
    yscale: str = declare(String(("linear", "log")), "multipliers: scale of the moduli", "linear")
    title: str | None = declare(String(), "figure title")
    file: str | None = declare(String(pattern=re.compile(r"^[^/\\]+\.png$"),
                                   pattern_text="a file name ending in .png, no directory"),
                            "PNG file name in the output directory")

    @property
    def filename(self) -> str:
        return self.file or f"{self.name}.png"

    def to_dict(self) -> dict[str, Any]:
        return _spec_dict(self)


@dataclasses.dataclass(frozen=True, kw_only=True)
class OutputSpec:
    """``[output]``: where and what to write."""

    directory: str = declare(String(), "output directory, relative to the scene file", "output")
    summary: bool = declare(Boolean(), "write summary.md", True)
    dpi: int = declare(Integer(30, 1200), "resolution of the PNG files", 150)

    def to_dict(self) -> dict[str, Any]:
        return _spec_dict(self)


# ---------------------------------------------------------------------------------------------
# The scene
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, kw_only=True)
class Scene:
    """A validated scene.

    Attributes
    ----------
    title, description : str
    oscillator : OscillatorSpec
        The ``[oscillator]`` table; :attr:`osc` is the built oscillator.
    sections : dict of str to tuple of EntrySpec
        The entries of every registered section, in registry order (empty
        tuples for sections the scene does not use).
    plots : tuple of PlotSpec
    output : OutputSpec
    source : pathlib.Path or None
        The scene file.
    output_dir : pathlib.Path
        Where the run writes (``output.directory`` relative to the scene file,
        or the directory given on the command line).
    """

    title: str
    description: str
    oscillator: OscillatorSpec
    sections: dict[str, tuple[EntrySpec, ...]]
    plots: tuple[PlotSpec, ...]
    output: OutputSpec
    source: Path | None
    output_dir: Path

    @property
    def osc(self) -> ImpactOscillator:
        """The scene's oscillator."""
        return self.oscillator.build()

    def entries(self, section: str) -> tuple[EntrySpec, ...]:
        """The entries of one section (empty if the scene has none)."""
        return self.sections.get(section, ())

    def to_dict(self) -> dict[str, Any]:
        """The resolved scene as TOML-able data: defaults filled in, overrides applied."""
        out: dict[str, Any] = {"title": self.title}
        if self.description:
            out["description"] = self.description
        out["oscillator"] = _spec_dict(self.oscillator)
        output = self.output.to_dict()
        output["directory"] = str(self.output_dir)
        out["output"] = output
        for key, entries in self.sections.items():
            if entries:
                out[key] = [e.to_dict() for e in entries]
        if self.plots:
            out["plots"] = [p.to_dict() for p in self.plots]
        return out

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON text (stored in the ``scene`` attribute of every output)."""
        return json.dumps(self.to_dict())


_TOP_KEYS = ("title", "description", "oscillator", "output", "plots")


def parse_scene(data: Mapping[str, Any], *, file: str | Path | None = None,
                text: str | None = None, output: str | Path | None = None,
                overridden: Iterable[str] = ()) -> Scene:
    """Validate scene data (as read from TOML) into a :class:`Scene`.

    Parameters
    ----------
    data : mapping
        The TOML document as a dict.
    file : str or pathlib.Path, optional
        The scene file: named in errors; relative output directories are
        resolved against its directory (else against the working directory).
    text : str, optional
        The TOML text, to find the line of a bad key.
    output : str or pathlib.Path, optional
        Output directory overriding ``output.directory`` (relative to the
        working directory).
    overridden : iterable of str
        Key paths set by ``--set``: errors under them get no line number.

    Raises
    ------
    SceneError
        The first problem found, naming the key path and what is allowed.
    """
    from impactcont.scene.sections import scene_sections

    fname = str(file) if file is not None else None
    root = Where(fname, "", locator(text, overridden))
    sections = scene_sections()
    allowed = [*_TOP_KEYS, *sections]
    if not isinstance(data, Mapping):
        raise root.error(f"a scene must be a TOML table; got {type_name(data)}")
    for key in data:
        if key not in allowed:
            raise unknown_key(key, allowed, root)
    title_default = (Path(fname).resolve().parent.name or Path(fname).stem) if fname \
        else "scene"
    title = String().check(data.get("title", title_default), root.key("title"))
    description = String().check(data.get("description", ""), root.key("description"))
    if "oscillator" not in data:
        raise root.key("oscillator").error("required table is missing",
                                           "an [oscillator] table with F, R, b, omega and "
                                           "K or springs")
    oscillator = OscillatorSpec.parse(data["oscillator"], root.key("oscillator"))
    osc = oscillator.build()
    output_spec = OutputSpec(**read_table(OutputSpec, data.get("output", {}),
                                           root.key("output")))

    parsed: dict[str, tuple[EntrySpec, ...]] = {}
    names: dict[str, str] = {}
    for key, section in sections.items():
        tables = _tables(data.get(key, []), root.key(key))
        entries = []
        for i, raw in enumerate(tables):
            entry = section.entry.parse(raw, root.key(key).item(i), osc, i)
            if entry.name in names:
                raise root.key(key).item(i).key("name").error(
                    f"{entry.name!r} is already the name of an entry of [[{names[entry.name]}]]",
                    "a name unique in the scene")
            names[entry.name] = key
            entries.append(entry)
        parsed[key] = tuple(entries)
    for key, entries in parsed.items():
        for i, entry in enumerate(entries):
            entry.check_scene(root.key(key).item(i), parsed)

    plots = []
    kinds = _plot_kinds()
    for i, raw in enumerate(_tables(data.get("plots", []), root.key("plots"))):
        where = root.key("plots").item(i)
        values = read_table(PlotSpec, raw, where)
        values.setdefault("name", f"plots{i + 1}")
        plot = PlotSpec(**values)
        _check_plot(plot, where, kinds, parsed)
        if plot.data is None:
            plot = dataclasses.replace(plot, data=tuple(
                e.name for e in parsed[kinds[plot.kind].section]))
        if plot.name in names:
            raise where.key("name").error(f"{plot.name!r} is already used in the scene",
                                          "a name unique in the scene")
        names[plot.name] = "plots"
        plots.append(plot)
    files = [p.filename for p in plots]
    for i, f in enumerate(files):
        if files.index(f) != i:
            raise root.key("plots").item(i).key("file").error(
                f"{f!r} is written by another plot too", "a file name unique in the scene")

    if output is not None:
        output_dir = Path(output)
    else:
        base = Path(fname).parent if fname else Path.cwd()
        output_dir = base / output_spec.directory
    return Scene(title=title, description=description, oscillator=oscillator, sections=parsed,
                 plots=tuple(plots), output=output_spec,
                 source=Path(fname) if fname else None, output_dir=output_dir.resolve())


def _tables(value: Any, where: Where) -> list[Any]:
    if isinstance(value, dict):
        name = where.path
        raise where.error(f"must be an array of tables: write [[{name}]], not [{name}]",
                          f"one or more [[{name}]] tables")
    if not isinstance(value, list):
        raise where.error(f"must be an array of tables; got {show(value)}",
                          f"one or more [[{where.path}]] tables")
    return value


def _check_plot(plot: PlotSpec, where: Where, kinds: Mapping[str, Any],
                parsed: Mapping[str, tuple[EntrySpec, ...]]) -> None:
    if plot.kind not in kinds:
        close = difflib.get_close_matches(plot.kind, list(kinds), n=1)
        hint = f"did you mean {close[0]!r}?" if close else "not a plot kind"
        raise where.key("kind").error(f"{plot.kind!r}: {hint}", ", ".join(kinds))
    kind = kinds[plot.kind]
    available = {e.name: e for e in parsed.get(kind.section, ())}
    names = plot.data if plot.data is not None else tuple(available)
    if not names:
        raise where.key("data").error(
            f"kind {plot.kind!r} draws [[{kind.section}]] entries and the scene has none",
            f"a scene with at least one [[{kind.section}]] table")
    for i, name in enumerate(names):
        if name not in available:
            close = difflib.get_close_matches(name, list(available), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise where.key("data").item(i).error(
                f"{name!r} is not a [[{kind.section}]] entry{hint}", ", ".join(available))
    if not kind.many and len(names) != 1:
        raise where.key("data").error(f"kind {plot.kind!r} draws exactly one entry; got "
                                      f"{len(names)}", "one name of " + ", ".join(available))
    if kind.section == "branches":
        parameters = {available[n].parameter for n in names}
        if len(parameters) > 1:
            raise where.key("data").error(
                f"branches continued in different parameters {sorted(parameters)}",
                "branches all continued in one parameter")
    if kind.check is not None:
        kind.check(plot, [available[n] for n in names], where)


def load_scene(path: str | Path, *, settings: Sequence[str] = (),
               output: str | Path | None = None) -> Scene:
    """Read, override and validate a scene file.

    Parameters
    ----------
    path : str or pathlib.Path
        A TOML scene file.
    settings : sequence of str
        ``key.path=value`` overrides (see :func:`apply_settings`).
    output : str or pathlib.Path, optional
        Output directory overriding the scene's.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file is missing, is not valid TOML, or the scene is malformed.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError("no such scene file", file=str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"cannot read the scene file: {exc}", file=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        line = int(m.group(1)) if m else (
            len(text.splitlines()) if "end of document" in str(exc) else None)
        raise SceneError(f"not valid TOML: {exc}", file=str(path), line=line) from None
    overridden = apply_settings(data, settings, file=str(path))
    return parse_scene(data, file=p, text=text, output=output, overridden=overridden)
