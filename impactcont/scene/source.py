"""The TOML text of a scene: reading it, finding the line of a key, ``--set`` overrides."""

from __future__ import annotations

import re
import sys
from collections.abc import Callable, Iterable
from typing import Any

from impactcont.scene.keys import SceneError, Where

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["apply_settings", "line_finder", "locator"]


def line_finder(text: str) -> Callable[[str], int | None]:
    """Best-effort map from key paths (``branches[1].bounds``) to 1-based line numbers.

    tomllib does not report where a key is; this reads table headers and
    ``key =`` lines (skipping the inside of multi-line arrays and inline
    tables) and returns the line of the longest known prefix of a path.
    """
    lines: dict[str, int] = {}
    counts: dict[str, int] = {}
    table = ""
    depth = 0
    header = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-\s\"]+?)\s*\]\]?\s*(#.*)?$")
    keyline = re.compile(r"^\s*([A-Za-z0-9_\-\"]+(?:\s*\.\s*[A-Za-z0-9_\-\"]+)*)\s*=")
    for number, line in enumerate(text.splitlines(), start=1):
        if depth > 0:
            depth += _bracket_balance(line)
            continue
        m = header.match(line)
        if m:
            parts = [p.strip().strip('"') for p in m.group(2).split(".")]
            first = parts[0]
            if m.group(1) == "[[" and len(parts) == 1:
                counts[first] = counts.get(first, 0) + 1
                table = f"{first}[{counts[first] - 1}]"
            else:
                head = f"{first}[{counts[first] - 1}]" if first in counts else first
                table = ".".join([head, *parts[1:]])
            lines.setdefault(table, number)
            continue
        m = keyline.match(line)
        if m:
            key = ".".join(p.strip().strip('"') for p in m.group(1).split("."))
            lines.setdefault(f"{table}.{key}" if table else key, number)
            depth = _bracket_balance(line[m.end():])

    def locate(path: str) -> int | None:
        while path:
            if path in lines:
                return lines[path]
            shorter = re.sub(r"(\.[^.\[\]]+|\[[^\]]*\])$", "", path)
            if shorter == path:
                return None
            path = shorter
        return None

    return locate


def locator(text: str | None, overridden: Iterable[str]) -> Callable[[str], int | None]:
    if not text:
        return lambda path: None
    finder = line_finder(text)
    changed = [c for c in overridden if c]

    def locate(path: str) -> int | None:
        if any(path == c or path.startswith((c + ".", c + "[")) for c in changed):
            return None  # the value came from --set, not from the file
        return finder(path)

    return locate


def _bracket_balance(text: str) -> int:
    text = re.sub(r'"(?:[^"\\]|\\.)*"|\'[^\']*\'|#.*$', "", text)
    return text.count("[") + text.count("{") - text.count("]") - text.count("}")



_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_\-]*)(?:\[([^\]]+)\])?$")


def _parse_setting_value(text: str) -> Any:
    """A ``--set`` value as TOML (``0.5``, ``[1, 2]``, ``true``, ``"x"``), else a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_settings(data: dict[str, Any], settings: Iterable[str], *,
                   file: str | None = None) -> list[str]:
    """Apply ``key.path=value`` overrides (``--set``) to scene data, in place.

    A path is dotted keys; an array of tables is indexed by position or by
    entry name: ``oscillator.b=0.5``, ``branches[0].bounds=[0.5, 3]``,
    ``branches[N1_b0].N=2``. Values are TOML values; anything that is not
    valid TOML is taken as a string (``output.directory=out/run1``). Missing
    tables on the way are created.

    Returns
    -------
    list of str
        The key paths set, arrays indexed by position (``branches[0].N``).

    Raises
    ------
    SceneError
        A malformed setting or a path into a missing array entry.
    """
    paths: list[str] = []
    for setting in settings:
        key, sep, text = setting.partition("=")
        key = key.strip()
        where = Where(file, key or setting)
        if not sep or not key:
            raise SceneError(f"--set {setting!r}: expected key=value",
                             allowed="e.g. --set oscillator.b=0.5 or "
                                     "--set 'branches[0].bounds=[0.5, 3]'", file=file)
        segments = key.split(".")
        node: Any = data
        resolved: list[str] = []
        for depth, segment in enumerate(segments):
            m = _SEGMENT.match(segment.strip())
            if not m:
                raise where.error(f"--set: {segment!r} is not a key",
                                  "dotted keys, arrays indexed as name[0] or name[entry]")
            name, index = m.group(1), m.group(2)
            last = depth == len(segments) - 1
            if isinstance(node, list):  # an array of tables named without an index
                before = ".".join(segments[:depth])
                names = [str(item["name"]) for item in node
                         if isinstance(item, dict) and "name" in item]
                # simulations.riding.periods: the entry named as a key
                entry, rest = ((segment, segments[depth + 1:]) if segment in names
                               and not last else ("0", segments[depth:]))
                raise where.error(
                    f"--set: {before} is an array of tables ([[{before}]]): index it by "
                    f"position or entry name", ".".join([f"{before}[{entry}]", *rest]))
            if not isinstance(node, dict):
                raise where.error(f"--set: {'.'.join(segments[:depth])} is not a table")
            if index is None:
                resolved.append(name)
                if last:
                    node[name] = _parse_setting_value(text.strip())
                else:
                    node = node.setdefault(name, {})
                continue
            items = node.get(name)
            if not isinstance(items, list):
                raise where.error(f"--set: {name} is not an array in the scene",
                                  f"a key path into existing [[{name}]] tables")
            position = _array_position(items, index.strip(), name, where)
            resolved.append(f"{name}[{position % len(items)}]")
            if last:
                items[position] = _parse_setting_value(text.strip())
            else:
                node = items[position]
        paths.append(".".join(resolved))
    return paths


def _array_position(items: list[Any], index: str, name: str, where: Where) -> int:
    if re.fullmatch(r"-?\d+", index):
        i = int(index)
        if not -len(items) <= i < len(items):
            raise where.error(f"--set: {name}[{i}] does not exist; the scene has "
                              f"{len(items)}", f"an index in [0, {len(items) - 1}]")
        return i
    named = [k for k, item in enumerate(items) if isinstance(item, dict)
             and item.get("name") == index]
    if not named:
        known = [str(item.get("name")) for item in items
                 if isinstance(item, dict) and "name" in item]
        raise where.error(f"--set: no [[{name}]] entry is named {index!r}",
                          ", ".join(known) or "an index")
    return named[0]


