"""The documentation site: built once with ``mkdocs build --strict``, then read as HTML."""

from __future__ import annotations

import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import impactcont

pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install -e .[docs])")
pytest.importorskip("mkdocstrings", reason="mkdocstrings is not installed")

ROOT = Path(__file__).resolve().parents[2]
ROLE = re.compile(r":(func|class|meth|mod|data|attr|exc):\S")


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built from the working tree, strict (any warning fails the build)."""
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def _pages(site: Path) -> dict[Path, str]:
    return {p: p.read_text(encoding="utf-8") for p in site.rglob("*.html")}


def test_every_public_callable_has_an_api_entry(site):
    anchors = set()
    for text in _pages(site / "api").values():
        anchors.update(re.findall(r'id="(impactcont\.[^"]+)"', text))
    public = {name: getattr(impactcont, name) for name in impactcont.__all__}
    missing = [name for name, obj in public.items()
               if (inspect.isclass(obj) or inspect.isfunction(obj))
               and f"{obj.__module__}.{obj.__qualname__}" not in anchors]
    assert not missing, f"no API entry for {missing}"


def test_no_sphinx_role_reaches_the_html(site):
    raw = {}
    for path, text in _pages(site).items():
        body = re.sub(r"<[^>]+>", "", text)
        if found := ROLE.findall(body):
            raw[str(path.relative_to(site))] = len(found)
    assert not raw, f"raw Sphinx roles in {raw}"


def test_roles_become_cross_references(site):
    text = (site / "api" / "dataset" / "index.html").read_text(encoding="utf-8")
    # :func:`validate_branch_dataset` in the schema module's docstring.
    assert re.search(r'<a class="autorefs [^>]*href="#impactcont\.dataset\.schema\.'
                     r'validate_branch_dataset"', text)


def test_free_numpydoc_sections_render_definition_lists_as_lists(site):
    text = (site / "api" / "dataset" / "index.html").read_text(encoding="utf-8")
    section = text.split("<summary>Dimensions</summary>", 1)[1].split("</details>", 1)[0]
    items = re.findall(r"<li><code>(\w+)</code>:", section)
    assert items == ["point", "multiplier", "component", "special"]


def test_study_links_to_docs_pages_are_links(site):
    link = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s#]+)(#[^)\s]*)?\)")
    checked = 0
    for readme in sorted((ROOT / "studies").glob("*/README.md")):
        page = (site / "studies" / readme.parent.name / "index.html").read_text(
            encoding="utf-8")
        page = page.split("<article", 1)[1].split("</article>", 1)[0]  # not the nav
        for target, _fragment in link.findall(readme.read_text(encoding="utf-8")):
            path = (readme.parent / target).resolve()
            if path.suffix == ".md" and path.is_relative_to(ROOT / "docs") and path.is_file():
                url = os.path.relpath(path.with_suffix(""),
                                      ROOT / "docs" / "studies" / readme.parent.name)
                assert f'href="{Path(url).as_posix()}/' in page, (readme, target)
                checked += 1
    assert checked, "no study README links to a page of docs/"


def test_study_links_to_other_studies_are_links(site):
    """A study's README linking another study: to its page, or to the copy of its file."""
    link = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s#]+)(#[^)\s]*)?\)")
    checked = 0
    studies = ROOT / "studies"
    for readme in sorted(studies.glob("*/README.md")):
        page = (site / "studies" / readme.parent.name / "index.html").read_text(
            encoding="utf-8")
        page = page.split("<article", 1)[1].split("</article>", 1)[0]  # not the nav
        for target, _fragment in link.findall(readme.read_text(encoding="utf-8")):
            path = (readme.parent / target).resolve()
            if not (path.is_file() and path.is_relative_to(studies)) or \
                    path.parent == readme.parent:
                continue
            other = path.relative_to(studies)
            if other.name == "README.md":
                assert f'href="../{other.parts[0]}/' in page, (readme, target)
            else:
                assert f'href="../{other.as_posix()}"' in page, (readme, target)
                assert (site / "studies" / other).is_file(), (readme, target)
            checked += 1
    assert checked, "no study README links to another study"


#: A highlighted code block of a page (fenced in Markdown, with or without a language).
_HIGHLIGHT = re.compile(r'<div class="[^"]*\bhighlight\b[^"]*">\s*<pre>.*?</pre>\s*</div>', re.S)
#: A code block: fenced or indented in Markdown.
_PRE = re.compile(r"<pre[^>]*>(.*?)</pre>", re.S)
#: ASCII math in a code block: a line ``lhs = rhs`` written with marks no code example or
#: program output of these pages uses (primes, powers, sqrt, functions, indices), or
#: ending with an equation number like ``(12)`` or ``(W3)``.
_ASCII_MATH = re.compile(
    r"^(?=.*\S\s*=\s*\S)(?:.*(?:''|\^|\bsqrt\(|\bexp\(|\bcos\(|\bsin\(|\bdet\(|\bRe\(|"
    r"\bdiag\(|\bsum_|_\{)|.*\(\s*[A-Z]?\d+[a-z]?(?:,\s*[A-Z]?\d+[a-z]?)*\s*\)\s*$)", re.M)


def _text(fragment: str) -> str:
    import html
    return html.unescape(re.sub(r"<[^>]+>", "", fragment))


def test_no_rest_literal_reaches_the_html(site):
    """A reST literal ``x`` of a docstring is shown as code, never with its backticks.

    Fenced code blocks of the Markdown pages are left out: their text is shown as written.
    """
    raw = {}
    for path, text in _pages(site).items():
        body = _text(_HIGHLIGHT.sub("", text.split("<article", 1)[-1]))
        if found := re.findall(r"``[^`\s][^`]*``", body):
            raw[str(path.relative_to(site))] = found[:3]
    assert not raw, f"reST double-backtick literals in {raw}"


def test_equations_are_typeset(site):
    """The theory pages' equations go through arithmatex (MathJax), none stays ASCII code."""
    for page in ("theory", "equations", "two_sided", "multi_impact", "kernel", "machines"):
        text = (site / page / "index.html").read_text(encoding="utf-8")
        assert re.search(r'<(div|span) class="arithmatex">', text), page
        assert "mathjax" in text.lower(), f"{page} loads no MathJax"
    ascii_math, raw = {}, {}
    for path, text in _pages(site).items():
        article = text.split("<article", 1)[-1]
        prose = re.sub(r"<(pre|code)[^>]*>.*?</\1>", "", article, flags=re.S)
        prose = re.sub(r'<(span|div) class="arithmatex">.*?</\1>', "", prose, flags=re.S)
        if "$$" in _text(prose):  # a block arithmatex did not take (say, badly indented)
            raw[str(path.relative_to(site))] = _text(prose).count("$$")
        if path.relative_to(site).parts[0] == "api":
            continue  # docstrings: the modules' own text
        for block in _PRE.findall(article):
            if '<span class="' in block:
                continue  # code of a language (Python, TOML, console), tokenised
            if found := _ASCII_MATH.findall(_text(block)):
                ascii_math.setdefault(str(path.relative_to(site)), []).extend(found)
    assert not ascii_math, f"equations left as ASCII code blocks: {ascii_math}"
    assert not raw, f"$$ shown as text, not typeset: {raw}"


def test_continuation_api_page_opens_with_the_public_functions(site):
    text = (site / "api" / "continuation" / "index.html").read_text(encoding="utf-8")
    anchors = re.findall(r'id="(impactcont\.[\w.]+\.\w+)"', text)
    callables = [a for a in anchors if a.rsplit(".", 1)[1][0].islower()
                 and a not in {"impactcont.analysis.branch"}]
    assert callables[:3] == [f"impactcont.analysis.branch.{name}" for name in
                             ("continuation", "continuation_from", "extend")]
    internals = [a for a in anchors if a.rsplit(".", 1)[1].startswith(("check_", "_"))
                 or ".core.stepper" in a or ".core.corrector" in a or ".detection.locator" in a]
    assert not internals, f"internals listed on the page: {internals}"


def test_sphinx_math_of_docstrings_reaches_mathjax():
    """``:math:`` and ``.. math::`` in a docstring become arithmatex math (as in mkdocs.yml)."""
    import importlib.util

    import markdown
    import yaml

    spec = importlib.util.spec_from_file_location(
        "griffe_docstrings", ROOT / "docs" / "_hooks" / "griffe_docstrings.py")
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    docstring = ("Stable when :math:`\\rho(G) < 1`.\n\n.. math::\n   :label: g\n\n"
                 "   G_0^T P G_0 - P = -I\n\nThe end.")
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)
    arithmatex = [e for e in config["markdown_extensions"]
                  if isinstance(e, dict) and "pymdownx.arithmatex" in e]
    assert arithmatex, "mkdocs.yml loads no pymdownx.arithmatex"
    out = markdown.markdown(hook.rewrite_math(docstring), extensions=["pymdownx.arithmatex"],
                            extension_configs=arithmatex[0])
    assert '<span class="arithmatex">\\(\\rho(G) &lt; 1\\)</span>' in out
    assert re.search(r'<div class="arithmatex">\\\[\s*G_0\^T P G_0 - P = -I\s*\\\]</div>', out)
    assert ":label:" not in out and ":math:" not in out and "The end." in out
