"""Griffe extension: numpydoc docstrings written for Sphinx, rendered by mkdocstrings.

The docstrings of ``impactcont`` use Sphinx roles (``:func:`load```,
``:class:`~xarray.Dataset```) and free numpydoc sections such as
"Dimensions" laid out as definition lists. Markdown knows neither: the roles
came out as raw text and a definition list as one paragraph. Once the package
is loaded (before any docstring is parsed) this extension rewrites every
docstring's text:

* a role becomes inline code wrapped in an optional autorefs cross-reference
  (``<autoref identifier=... optional>``): a link when the target is rendered
  somewhere in the site, plain code otherwise, never a strict-mode warning;
  the target is resolved from the docstring's own scope, as Sphinx does, and
  ``~`` keeps only the last component as the shown text;
* in a section that is not a numpydoc standard one, a block of
  ``term`` / indented description pairs, or of lines ``term  description``
  (term in double backticks, two or more spaces), becomes a Markdown list;
* math written for Sphinx, the role ``:math:`x^2``` and the directive
  ``.. math::`` with its indented block, becomes ``\\(x^2\\)`` and a ``$$`` block,
  which ``pymdownx.arithmatex`` (``mkdocs.yml``) hands to MathJax like the
  equations of the pages.

Registered under ``plugins.mkdocstrings.handlers.python.options.extensions``
in ``mkdocs.yml`` (path relative to the repository root, where mkdocs runs).
"""

from __future__ import annotations

import html
import re

import griffe

ROLE = re.compile(r":(?:py:)?(func|class|meth|mod|data|attr|exc|obj|const):`(~?)([^`]+)`")
MATH_ROLE = re.compile(r":math:`([^`]+)`")
MATH_DIRECTIVE = re.compile(r"^(?P<indent>\s*)\.\. math::\s*(?P<first>.*)$")

#: Numpydoc sections griffe parses itself; every other titled section is free text.
STANDARD_SECTIONS = frozenset({
    "parameters", "other parameters", "params", "arguments", "args", "returns", "return",
    "yields", "receives", "raises", "warns", "warnings", "see also", "notes", "references",
    "examples", "attributes", "methods", "functions", "classes", "modules", "deprecated",
    "type parameters", "type aliases",
})
_UNDERLINE = re.compile(r"^\s*-{3,}\s*$")
_COLUMN_ITEM = re.compile(r"^(``[^`]+``)\s{2,}(\S.*)$")


def _target(obj: griffe.Object, name: str, collection) -> str:
    """Full path of ``name`` seen from ``obj`` (the name itself when unresolvable)."""
    head, _, rest = name.partition(".")
    path = name
    if head != "impactcont":
        try:
            path = obj.resolve(head) + (f".{rest}" if rest else "")
        except griffe.NameResolutionError:  # not in scope: kept as written
            return name
    try:
        found = collection[path]
        return found.final_target.path if found.is_alias else found.path
    except (KeyError, ValueError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        # outside the package (xarray.Dataset) or not found: the resolved path
        return path


def rewrite_roles(text: str, obj: griffe.Object, collection) -> str:
    """Replace every Sphinx role of ``text`` with an optional cross-reference in code."""

    def replace(match: re.Match[str]) -> str:
        _role, tilde, name = match.groups()
        name = name.strip()
        shown = name.rsplit(".", 1)[-1] if tilde else name
        identifier = html.escape(_target(obj, name, collection), quote=True)
        return (f'<autoref identifier="{identifier}" optional>'
                f"<code>{html.escape(shown)}</code></autoref>")

    return ROLE.sub(replace, text)


def rewrite_math(text: str) -> str:
    """Sphinx math of ``text`` as arithmatex reads it: ``\\(...\\)`` inline, ``$$`` blocks."""
    text = MATH_ROLE.sub(lambda m: f"\\({m[1]}\\)", text)
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        match = MATH_DIRECTIVE.match(lines[i])
        if match is None:
            out.append(lines[i])
            i += 1
            continue
        indent = match["indent"]
        body = [match["first"]] if match["first"].strip() else []
        i += 1
        while i < len(lines) and (not lines[i].strip()
                                  or len(lines[i]) - len(lines[i].lstrip()) > len(indent)):
            line = lines[i].strip()
            if line and not re.match(r"^:\w+:", line):  # options such as :label: dropped
                body.append(line)
            i += 1
        out.extend([f"{indent}$$", *(f"{indent}{line}" for line in body), f"{indent}$$", ""])
    return "\n".join(out)


def _as_list(block: list[str]) -> list[str] | None:
    """The Markdown list for a definition-list block, or ``None`` if it is prose."""
    if all(_COLUMN_ITEM.match(line) for line in block) and len(block) > 1:
        return [f"- {m[1]}: {m[2]}" for m in map(_COLUMN_ITEM.match, block)]
    items: list[list[str]] = []
    for line in block:
        if not line[:1].isspace():
            items.append([line.strip(), ""])
        elif items:
            items[-1][1] = f"{items[-1][1]} {line.strip()}".strip()
        else:
            return None
    if not items or any(not desc for _term, desc in items):
        return None
    return [f"- {term if '`' in term else f'``{term}``'}: {desc}" for term, desc in items]


def rewrite_sections(text: str) -> str:
    """Turn definition lists in non-standard numpydoc sections into Markdown lists."""
    lines = text.split("\n")
    out: list[str] = []
    free = False
    block: list[str] = []

    def flush() -> None:
        listed = _as_list(block) if free and block else None
        out.extend(listed if listed is not None else block)
        block.clear()

    for i, line in enumerate(lines):
        is_title = (i + 1 < len(lines) and line.strip() and not _UNDERLINE.match(line)
                    and _UNDERLINE.match(lines[i + 1]))
        if is_title:
            flush()
            free = line.strip().lower() not in STANDARD_SECTIONS
            out.append(line)
        elif not line.strip() or _UNDERLINE.match(line):
            flush()
            out.append(line)
        else:
            block.append(line)
    flush()
    return "\n".join(out)


class SphinxDocstrings(griffe.Extension):
    """Rewrite the Sphinx-isms of every docstring of a package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader,
                   **kwargs) -> None:
        collection = loader.modules_collection
        seen: set[int] = set()
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if obj.docstring is not None:
                text = rewrite_math(rewrite_sections(obj.docstring.value))
                obj.docstring.value = rewrite_roles(text, obj, collection)
            stack.extend(m for m in obj.members.values() if not m.is_alias)
