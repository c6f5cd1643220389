"""The vocabulary of scene keys: value types that say what they allow, and SceneError.

Each key of a scene table is declared once, as a dataclass field made by
:func:`declare` with a value type (:class:`Real`, :class:`Integer`,
:class:`String`, ...) in its metadata; :func:`read_table` checks a TOML table
against those declarations and raises :class:`SceneError` naming the key
path, the value received and what is allowed.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
import re
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from impactcont.errors import ImpactcontError
from impactcont.vocabulary import ELEMENT_FAMILIES, PARAMETERS

__all__ = [
    "DPI_RANGE",
    "ENTRY_NAME",
    "NAME_ALLOWED",
    "NAME_PATTERN",
    "Boolean",
    "Integer",
    "Interval",
    "Key",
    "Names",
    "ParameterName",
    "Real",
    "RealArray",
    "SceneError",
    "String",
    "StringList",
    "ValueType",
    "Where",
    "declare",
    "read_table",
    "scene_keys",
    "show",
    "type_name",
    "unknown_key",
]

#: Dots per inch a figure may be drawn at (``[output] dpi``, ``impactcont plot --dpi``).
DPI_RANGE = (10, 1200)

#: Names of entries (``name = ...``): they become NetCDF group names and file names.
NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
NAME_ALLOWED = "a name of letters, digits and '_' that starts with a letter"


# ---------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------
class SceneError(ImpactcontError, ValueError):
    """A scene is malformed: unknown key, wrong type, value out of range, bad reference.

    Parameters
    ----------
    problem : str
        What is wrong, with the value received.
    key : str
        Key path in the scene, e.g. ``"branches[1].bounds"`` (``""`` for the
        whole file).
    allowed : str, optional
        What is allowed there.
    file : str, optional
        The scene file.
    line : int, optional
        1-based line of the key in the file, when it could be found.
    """

    def __init__(self, problem: str, *, key: str = "", allowed: str | None = None,
                 file: str | None = None, line: int | None = None) -> None:
        self.problem = problem
        self.key = key
        self.allowed = allowed
        self.file = file
        self.line = line
        super().__init__(self._text())

    def _text(self) -> str:
        where = self.file or "<scene>"
        if self.line is not None:
            where = f"{where}:{self.line}"
        text = f"{where}: {self.key}: {self.problem}" if self.key else f"{where}: {self.problem}"
        if self.allowed:
            text += f"; allowed: {self.allowed}"
        return text

    def __str__(self) -> str:
        return self._text()


def show(value: Any) -> str:
    """A value as it would read in TOML."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {show(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(show(v) for v in value) + "]"
    return repr(value)


def type_name(value: Any) -> str:
    names = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    return names.get(type(value), type(value).__name__)


@dataclasses.dataclass(frozen=True)
class Where:
    """Where a value sits in the scene: file, key path and a line finder."""

    file: str | None
    path: str
    locate: Callable[[str], int | None] = dataclasses.field(default=lambda path: None,
                                                            repr=False, compare=False)

    def key(self, name: str) -> Where:
        return dataclasses.replace(self, path=f"{self.path}.{name}" if self.path else name)

    def item(self, index: int | str) -> Where:
        return dataclasses.replace(self, path=f"{self.path}[{index}]")

    def error(self, problem: str, allowed: str | None = None) -> SceneError:
        return SceneError(problem, key=self.path, allowed=allowed, file=self.file,
                          line=self.locate(self.path))


# ---------------------------------------------------------------------------------------------
# Value types: each checks one TOML value and says what it allows
# ---------------------------------------------------------------------------------------------
class ValueType:
    """A checker of one TOML value; :attr:`allowed` says in words what it accepts."""

    allowed = "a value"

    def check(self, value: Any, where: Where) -> Any:  # pragma: no cover - interface
        raise NotImplementedError

    def fail(self, value: Any, where: Where, why: str = "") -> SceneError:
        got = f"got {show(value)} ({type_name(value)})"
        return where.error(f"{why}; {got}" if why else got, self.allowed)


class Real(ValueType):
    """A finite real number (TOML integer or float), optionally in a range."""

    def __init__(self, low: float | None = None, high: float | None = None, *,
                 low_open: bool = False, high_open: bool = False) -> None:
        self.low, self.high, self.low_open, self.high_open = low, high, low_open, high_open
        if low is not None and high is not None:
            left, right = "(" if low_open else "[", ")" if high_open else "]"
            self.allowed = f"a real number in {left}{low:g}, {high:g}{right}"
        elif low is not None:
            self.allowed = f"a real number {'>' if low_open else '>='} {low:g}"
        elif high is not None:
            self.allowed = f"a real number {'<' if high_open else '<='} {high:g}"
        else:
            self.allowed = "a finite real number"

    def inside(self, x: float) -> bool:
        if self.low is not None and (x <= self.low if self.low_open else x < self.low):
            return False
        return not (self.high is not None and (x >= self.high if self.high_open
                                               else x > self.high))

    def check(self, value: Any, where: Where) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(value, where, "wrong type")
        x = float(value)
        if not math.isfinite(x) or not self.inside(x):
            raise self.fail(value, where, "out of range")
        return x


class Integer(ValueType):
    """A TOML integer, optionally in a range or one of a few values."""

    def __init__(self, low: int | None = None, high: int | None = None, *,
                 choices: Sequence[int] | None = None) -> None:
        self.low, self.high, self.choices = low, high, choices
        if choices is not None:
            self.allowed = "one of " + ", ".join(f"{c:+d}" if c else "0" for c in choices)
        elif low is not None and high is not None:
            self.allowed = f"an integer in [{low}, {high}]"
        elif low is not None:
            self.allowed = f"an integer >= {low}"
        else:
            self.allowed = "an integer"

    def check(self, value: Any, where: Where) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(value, where, "wrong type")
        bad = ((self.choices is not None and value not in self.choices)
               or (self.low is not None and value < self.low)
               or (self.high is not None and value > self.high))
        if bad:
            raise self.fail(value, where, "out of range")
        return int(value)


class Boolean(ValueType):
    allowed = "true or false"

    def check(self, value: Any, where: Where) -> bool:
        if not isinstance(value, bool):
            raise self.fail(value, where, "wrong type")
        return value


class String(ValueType):
    """A string, optionally one of a few choices or matching a pattern."""

    def __init__(self, choices: Iterable[str] | None = None, *,
                 pattern: re.Pattern[str] | None = None, pattern_text: str = "") -> None:
        self.choices = tuple(choices) if choices is not None else None
        self.pattern = pattern
        if self.choices is not None:
            self.allowed = "one of " + ", ".join(json.dumps(c) for c in self.choices)
        elif pattern is not None:
            self.allowed = pattern_text or f"a string matching {pattern.pattern}"
        else:
            self.allowed = "a string"

    def check(self, value: Any, where: Where) -> str:
        if not isinstance(value, str):
            raise self.fail(value, where, "wrong type")
        if self.choices is not None and value not in self.choices:
            close = difflib.get_close_matches(value, self.choices, n=1, cutoff=0.6)
            why = f"did you mean {json.dumps(close[0])}?" if close else "not a known value"
            raise self.fail(value, where, why)
        if self.pattern is not None and not self.pattern.match(value):
            raise self.fail(value, where, "invalid")
        return value


class ParameterName(ValueType):
    """A continuable parameter's name: every name :data:`impactcont.vocabulary.PARAMETERS`
    resolves, the named parameters (``omega``, ``b``, ..., ``b_low``, ``R_low``, ``gap``)
    and the elements (``m<j>``, ``k<j>``, ``c<j>``, ``M[i,j]``, ``K[i,j]``, ``C[i,j]``,
    ``F[j]``, 1-based). Whether it applies to the oscillator is the driver's check."""

    allowed = ("one of " + ", ".join(json.dumps(name) for name in PARAMETERS)
               + " or an element name " + ", ".join(ELEMENT_FAMILIES)
               + ' (1-based, e.g. "k2", "M[1,2]", "F[2]")')

    def check(self, value: Any, where: Where) -> str:
        if not isinstance(value, str):
            raise self.fail(value, where, "wrong type")
        if value not in PARAMETERS:
            spaceless = re.sub(r"\s+", "", value)
            close = [spaceless] if spaceless in PARAMETERS else difflib.get_close_matches(
                value, list(PARAMETERS), n=1, cutoff=0.6)
            why = f"did you mean {json.dumps(close[0])}?" if close else "not a known parameter"
            raise self.fail(value, where, why)
        return value


class StringList(ValueType):
    """An array of distinct strings taken from a set of choices."""

    def __init__(self, choices: Iterable[str]) -> None:
        self.item = String(choices)
        self.allowed = f"an array of distinct values, each {self.item.allowed}"

    def check(self, value: Any, where: Where) -> tuple[str, ...]:
        if not isinstance(value, list):
            raise self.fail(value, where, "wrong type")
        out = tuple(self.item.check(v, where.item(i)) for i, v in enumerate(value))
        if len(set(out)) != len(out):
            raise self.fail(value, where, "repeated value")
        return out


#: The value type of entry and plot names (``name = ...``).
ENTRY_NAME = String(pattern=NAME_PATTERN, pattern_text=NAME_ALLOWED)


class Names(ValueType):
    """An array of entry names (references to other tables of the scene)."""

    allowed = f"an array of entry names ({NAME_ALLOWED})"

    def check(self, value: Any, where: Where) -> tuple[str, ...]:
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not value:
            raise self.fail(value, where, "wrong type or empty")
        item = ENTRY_NAME
        out = tuple(item.check(v, where.item(i)) for i, v in enumerate(value))
        if len(set(out)) != len(out):
            raise self.fail(value, where, "repeated name")
        return out


class RealArray(ValueType):
    """A vector (``ndim=1``) or a matrix (``ndim=2``, array of rows) of real numbers."""

    def __init__(self, ndim: int, *, positive: bool = False, nonnegative: bool = False
                 ) -> None:
        self.ndim, self.positive, self.nonnegative = ndim, positive, nonnegative
        what = "a non-empty array of real numbers" if ndim == 1 else \
            "a non-empty square matrix written as an array of rows of real numbers"
        self.allowed = what + (", all > 0" if positive else ", all >= 0" if nonnegative
                               else "")

    def check(self, value: Any, where: Where) -> tuple:
        item = (Real(0.0, low_open=True) if self.positive else Real(0.0) if self.nonnegative
                else Real())
        if not isinstance(value, list) or not value:
            raise self.fail(value, where, "wrong type or empty")
        if self.ndim == 1:
            return tuple(self._item(item, v, value, where) for v in value)
        if not all(isinstance(row, list) and len(row) == len(value) for row in value):
            raise self.fail(value, where, "not a square array of rows")
        return tuple(tuple(self._item(item, v, value, where) for v in row) for row in value)

    def _item(self, item: Real, v: Any, whole: Any, where: Where) -> float:
        try:
            return item.check(v, where)
        except SceneError:
            raise self.fail(whole, where, f"entry {show(v)} is not allowed") from None


class Interval(ValueType):
    """A pair ``[lo, hi]`` of real numbers with ``lo < hi`` inside an admissible range."""

    def __init__(self, bound: Real | None = None) -> None:
        self.bound = bound or Real()
        inside = self.bound.allowed.replace("a real number", "each").replace(
            "a finite real number", "")
        self.allowed = "a pair [lo, hi] of real numbers with lo < hi" + (
            f", {inside}" if inside.strip() else "")

    def check(self, value: Any, where: Where) -> tuple[float, float]:
        if not isinstance(value, list) or len(value) != 2:
            raise self.fail(value, where, "not a pair")
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
            raise self.fail(value, where, "wrong type")
        lo, hi = (float(v) for v in value)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise self.fail(value, where, "not finite")
        if not lo < hi:
            raise self.fail(value, where, "lo must be < hi")
        if not (self.bound.inside(lo) and self.bound.inside(hi)):
            raise self.fail(value, where, "out of range")
        return lo, hi


@dataclasses.dataclass(frozen=True)
class Key:
    """Declaration of one scene key: its type, whether it is required, its documentation."""

    type: ValueType
    doc: str
    required: bool = False


def declare(type_: ValueType, doc: str, default: Any = None, *, required: bool = False) -> Any:
    """A dataclass field declaring a scene key."""
    meta = {"scene": Key(type_, doc, required)}
    return dataclasses.field(default=default, metadata=meta)


def scene_keys(cls: type) -> dict[str, Key]:
    """The scene keys of a spec dataclass: ``name -> Key``, in declaration order."""
    return {f.name: f.metadata["scene"] for f in dataclasses.fields(cls)
            if "scene" in f.metadata}


def unknown_key(key: str, allowed: Sequence[str], where: Where) -> SceneError:
    lowered = {a.lower(): a for a in allowed}
    close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
    if not close and key.lower() in lowered:
        close = [lowered[key.lower()]]
    hint = f"did you mean {close[0]!r}?" if close else "not a key of this table"
    return where.key(key).error(f"unknown key; {hint}", ", ".join(allowed))


def read_table(cls: type, raw: Any, where: Where, *, extra: Sequence[str] = ()
                ) -> dict[str, Any]:
    """Check a TOML table against the keys of ``cls``; return ``name -> checked value``."""
    keys = scene_keys(cls)
    if not isinstance(raw, dict):
        raise where.error(f"must be a table; got {show(raw)} ({type_name(raw)})",
                          "keys " + ", ".join(keys))
    for name in raw:
        if name not in keys and name not in extra:
            raise unknown_key(name, [*keys, *extra], where)
    values: dict[str, Any] = {}
    for name, key in keys.items():
        if name in raw:
            values[name] = key.type.check(raw[name], where.key(name))
        elif key.required:
            raise where.key(name).error("required key is missing", key.type.allowed)
    return values
