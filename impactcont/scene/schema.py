"""The scene format: a TOML file describing one study, validated into dataclasses.

A scene names the oscillator (``[oscillator]``), what to compute (one
array of tables per section: ``[[orbits]]``, ``[[branches]]``, ... and the
sections of problems from other packages, all from the one registry
:mod:`impactcont.scene.plugins`), the figures (``[[plots]]``) and where to
write (``[output]``). The format is documented in ``docs/scenes.md``; the
entries of the built-in sections are in :mod:`impactcont.scene.entries`.

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
import json
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

from impactcont.model.oscillator import ImpactOscillator
from impactcont.scene.entries import (
    PARAMETER_RANGES,
    BranchSpec,
    EntrySpec,
    OrbitSpec,
    OscillatorSpec,
    RobustSpec,
    SimulationSpec,
    spec_dict,
)
from impactcont.scene.keys import (
    DPI_RANGE,
    ENTRY_NAME,
    Boolean,
    Integer,
    Key,
    Names,
    Real,
    SceneError,
    String,
    Where,
    declare,
    read_table,
    scene_keys,
    show,
    type_name,
    unknown_key,
)
from impactcont.scene.plugins import RESERVED_KEYS, PlotKind, plot_kinds, scene_sections
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


# ---------------------------------------------------------------------------------------------
# Plots and output
# ---------------------------------------------------------------------------------------------
def _point_variables() -> tuple[str, ...]:
    from impactcont.plots.branches import Y_VARIABLES

    return Y_VARIABLES


@dataclasses.dataclass(frozen=True, kw_only=True)
class PlotSpec:
    """``[[plots]]``: one PNG drawn from the data of computed entries."""

    section: ClassVar[str] = "plots"

    name: str = declare(ENTRY_NAME,
                     "plot name; the file is <name>.png unless file is given", "")
    kind: str = declare(String(), "what to draw (see the list of plot kinds)", required=True)
    data: tuple[str, ...] | None = declare(Names(), "names of the entries to draw (default: all "
                                        "entries of the section the kind reads)")
    y: str = declare(String(_point_variables()), "bifurcation_diagram: the branch variable on "
                  "the vertical axis", "impact_velocity")
    yscale: str = declare(String(("auto", "linear", "log")), "multipliers: scale of the moduli "
                       "(auto: logarithmic when a spike would flatten the rest)", "auto")
    width: float = declare(Real(2, 7.2), "figure width in inches (3.5: a journal's single "
                        "column, 7: double)", 7.0)
    title: str | None = declare(String(), "figure title")
    file: str | None = declare(String(pattern=re.compile(r"^[^/\\]+\.png$"),
                                   pattern_text="a file name ending in .png, no directory"),
                            "PNG file name in the output directory")

    @property
    def filename(self) -> str:
        return self.file or f"{self.name}.png"

    def to_dict(self) -> dict[str, Any]:
        return spec_dict(self)


@dataclasses.dataclass(frozen=True, kw_only=True)
class OutputSpec:
    """``[output]``: where and what to write."""

    directory: str = declare(String(), "output directory, relative to the scene file", "output")
    summary: bool = declare(Boolean(), "write summary.md", True)
    dpi: int = declare(Integer(*DPI_RANGE), "resolution of the PNG files (dots per inch)", 150)

    def to_dict(self) -> dict[str, Any]:
        return spec_dict(self)


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
        out["oscillator"] = spec_dict(self.oscillator)
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


_TOP_KEYS = RESERVED_KEYS


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
        entry_type = section.load_entry() if tables else None
        for i, raw in enumerate(tables):
            entry = entry_type.parse(raw, root.key(key).item(i), osc, i, section=key)
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
    kinds = plot_kinds()
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


def _entries_by_table(kind: PlotKind, parsed: Mapping[str, tuple[EntrySpec, ...]]) -> str:
    """The entries a plot kind may draw, each under its own table:
    ``"[[branches]]: a, b; [[multi_impact]]: c"``."""
    return "; ".join(f"[[{s}]]: " + ", ".join(e.name for e in parsed[s])
                     for s in kind.sections if parsed.get(s))


def _check_plot(plot: PlotSpec, where: Where, kinds: Mapping[str, PlotKind],
                parsed: Mapping[str, tuple[EntrySpec, ...]]) -> None:
    if plot.kind not in kinds:
        close = difflib.get_close_matches(plot.kind, list(kinds), n=1)
        hint = f"did you mean {close[0]!r}?" if close else "not a plot kind"
        raise where.key("kind").error(f"{plot.kind!r}: {hint}", ", ".join(kinds))
    kind = kinds[plot.kind]
    available = {e.name: e for s in kind.sections for e in parsed.get(s, ())}
    names = plot.data if plot.data is not None else tuple(available)
    if not names:
        raise where.key("data").error(
            f"kind {plot.kind!r} draws [[{kind.section}]] entries and the scene has none",
            f"a scene with at least one [[{kind.section}]] table")
    for i, name in enumerate(names):
        if name not in available:
            close = difflib.get_close_matches(name, list(available), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            tables = [f"[[{s}]]" for s in kind.sections]
            listed = tables[0] if len(tables) == 1 else \
                f"{', '.join(tables[:-1])} or {tables[-1]}"
            raise where.key("data").item(i).error(
                f"{name!r} is not an entry of {listed}{hint}", _entries_by_table(kind, parsed))
    if not kind.many and len(names) != 1:
        raise where.key("data").error(f"kind {plot.kind!r} draws exactly one entry; got "
                                      f"{len(names)}",
                                      "one name of " + _entries_by_table(kind, parsed))
    if kind.section == "branches":
        parameters = {_parameter(available[n], available) for n in names}
        if len(parameters) > 1:
            raise where.key("data").error(
                f"branches continued in different parameters {sorted(parameters)}",
                "branches all continued in one parameter")
    if kind.check is not None:
        kind.check(plot, [available[n] for n in names], where)


def _parameter(entry: EntrySpec, entries: Mapping[str, EntrySpec]) -> str:
    """The continued parameter of a branch, or of the branch a switch starts from."""
    while getattr(entry, "parameter", None) is None and getattr(entry, "start", None) in entries:
        entry = entries[entry.start]
    return getattr(entry, "parameter", "?")


_SCENE_FILE = "a TOML scene file (UTF-8 text)"


def _scene_text(path: Path, name: str) -> str:
    """The text of a scene file, refused with a :class:`SceneError` naming ``name`` when it
    is missing, a directory, unreadable, or not UTF-8 text (a binary file)."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneError("no such scene file", file=name) from None
    except IsADirectoryError:
        raise SceneError("is a directory, not a scene file", allowed=_SCENE_FILE,
                         file=name) from None
    except OSError as exc:
        raise SceneError(f"cannot read the scene file: {exc.strerror or exc}",
                         allowed=_SCENE_FILE, file=name) from None
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark, as some editors write, is dropped
    except UnicodeDecodeError as exc:
        raise SceneError(f"not a UTF-8 TOML scene: byte {raw[exc.start]:#04x} at offset "
                         f"{exc.start} is not UTF-8 text (a binary file?)", allowed=_SCENE_FILE,
                         file=name) from None
    if "\x00" in text:
        raise SceneError(f"not a TOML scene: it holds a NUL byte at offset "
                         f"{raw.index(0)} (a binary file?)", allowed=_SCENE_FILE,
                         file=name) from None
    return text


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
        The file is missing, is a directory, is not UTF-8 text, is not valid TOML, or
        the scene is malformed.
    """
    p = Path(path)
    text = _scene_text(p, str(path))
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        line = int(m.group(1)) if m else (
            len(text.splitlines()) if "end of document" in str(exc) else None)
        raise SceneError(f"not valid TOML: {exc}", file=str(path), line=line) from None
    overridden = apply_settings(data, settings, file=str(path))
    return parse_scene(data, file=p, text=text, output=output, overridden=overridden)
