"""What the documentation promises, read from its Markdown sources (no site build).

Every page of ``docs/`` and every study README: its relative links resolve, the
package files and modules it names exist, the names it gives as ``ic.<name>`` or
``impactcont.<module>.<name>`` can be imported, the ``*.md`` files it names in code
text exist, and it calls no required dependency optional. The built site (math
typeset, no reST literal left) is checked in ``test_docs_site.py``.
"""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

import pytest

import impactcont

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
STUDIES = ROOT / "studies"

PAGES = sorted(p for p in DOCS.rglob("*.md") if "_hooks" not in p.parts) + sorted(
    STUDIES.glob("*/README.md")) + [ROOT / "README.md"]

_FENCE = re.compile(r"^```.*?^```", re.S | re.M)
_LINK = re.compile(r"(?<!\\)\[[^\]]*\]\(([^)\s]+)\)")
_CODE = re.compile(r"`([^`\n]+)`")
_PACKAGE_PATH = re.compile(r"\bimpactcont/[\w/]*\w(?:\.py|/)?")
_DOTTED = re.compile(r"\bimpactcont(?:\.[A-Za-z_]\w*)+")
_IC = re.compile(r"\bic\.([A-Za-z_]\w*)")
_MD_NAME = re.compile(r"^[\w./-]+\.md$")
#: Markdown files the package or a study writes (outputs, not committed): named, not linked.
_WRITTEN_MD = {"summary.md", "special_points.md", "table.md", "benchmark.md", "pd_table.md"}


def _rel(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


def _prose(page: Path) -> str:
    """The page without its fenced code blocks (examples may name anything)."""
    return _FENCE.sub("", page.read_text(encoding="utf-8"))


def _site_page(target: Path) -> bool:
    """A page the docs hook makes: ``docs/studies/index.md``, ``docs/studies/<name>/...``."""
    if not target.is_relative_to(DOCS / "studies"):
        return False
    rel = target.relative_to(DOCS / "studies")
    if rel.as_posix() == "index.md":
        return True
    study = STUDIES / rel.parts[0]
    return study.is_dir() and (len(rel.parts) == 1 or rel.parts[1:] == ("index.md",)
                               or (study / Path(*rel.parts[1:])).exists())


def test_pages_are_found():
    assert len(PAGES) > 20
    assert DOCS / "index.md" in PAGES


def test_home_page_layout_lists_every_subpackage():
    """The home page's layout table: each subpackage of ``impactcont/`` has a row."""
    text = (DOCS / "index.md").read_text(encoding="utf-8")
    layout = text.split("## Layout", 1)[1]
    named = set(re.findall(r"`impactcont/(\w+)/`", layout))
    subpackages = {p.parent.name for p in (ROOT / "impactcont").glob("*/__init__.py")}
    assert subpackages - named == set(), f"docs/index.md omits {sorted(subpackages - named)}"


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_relative_links_resolve(page):
    broken = []
    for target in _LINK.findall(_prose(page)):
        if re.match(r"^[a-z][a-z0-9+.-]*:|^#|^/", target):
            continue  # a URL, an anchor of the page itself or a site-absolute path
        path = (page.parent / target.partition("#")[0]).resolve()
        if not (path.exists() or _site_page(path)):
            broken.append(target)
    assert not broken, f"{_rel(page)} links to files that do not exist: {broken}"


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_named_package_files_exist(page):
    missing = sorted({m for m in _PACKAGE_PATH.findall(_prose(page))
                      if not (ROOT / m).exists()})
    assert not missing, f"{_rel(page)} names files of the package that do not exist: {missing}"


def _resolves(dotted: str) -> bool:
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_named_modules_and_objects_import(page):
    text = _prose(page)
    missing = sorted({m for m in _DOTTED.findall(text) if not _resolves(m)})
    missing += sorted({f"ic.{m}" for m in _IC.findall(text) if not hasattr(impactcont, m)})
    assert not missing, f"{_rel(page)} names what impactcont does not have: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_named_markdown_files_exist(page):
    """``EQUATIONS.md`` in code text, when the page is ``docs/equations.md``, misleads."""
    missing = []
    for code in _CODE.findall(_prose(page)):
        if not _MD_NAME.match(code) or Path(code).name in _WRITTEN_MD:
            continue
        if not any((base / code).is_file() for base in (page.parent, ROOT, DOCS)):
            missing.append(code)
    assert not missing, f"{_rel(page)} names Markdown files that do not exist: {missing}"


def _required_dependencies() -> set[str]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return {re.split(r"[<>=!;\[ ]", dep, maxsplit=1)[0].lower()
            for dep in project["dependencies"]}


@pytest.mark.parametrize("page", PAGES, ids=_rel)
def test_no_required_dependency_called_optional(page):
    required = _required_dependencies()
    assert "tqdm" in required  # the progress bars are not optional
    text = re.sub(r"\s+", " ", _prose(page))
    wrong = []
    for sentence in re.split(r"(?<=[.;:])\s", text):
        if "optional" not in sentence.lower():
            continue
        if {w.lower() for w in re.findall(r"[\w-]+", sentence)} & required:
            wrong.append(sentence.strip())
    assert not wrong, f"{_rel(page)} calls a required dependency optional: {wrong}"


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def test_citation_file_cites_the_package_and_the_paper():
    yaml = pytest.importorskip("yaml")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0"
    assert cff["type"] == "software"
    assert cff["title"].startswith("impactcont")
    assert str(cff["version"]) == _project()["version"]
    assert cff["license"] == _project()["license"]
    papers = [ref for ref in cff["references"] if ref["type"] == "article"]
    assert [a["family-names"] for a in papers[0]["authors"]] == ["Cao", "Shu"]
    assert "robust stability" in papers[0]["title"].lower()
    assert "Acta Mechanica Sinica" in papers[0]["journal"]


def test_changelog_has_the_current_version_and_an_unreleased_section():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    headings = re.findall(r"^## \[([^\]]+)\](?: - (\d{4}-\d{2}-\d{2}))?\s*$", text, re.M)
    assert headings[0] == ("Unreleased", "")
    versions = [v for v, _date in headings[1:]]
    assert versions and versions[0] == _project()["version"], versions
    assert all(date for _v, date in headings[1:]), "a release without its date"
    assert "keepachangelog.com" in text


@pytest.mark.parametrize("page", ["README.md", "docs/index.md"])
def test_citing_section_points_to_the_citation_file(page):
    text = (ROOT / page).read_text(encoding="utf-8")
    assert re.search(r"^## Citing\b", text, re.M), f"{page} has no Citing section"
    section = text.split("## Citing", 1)[1].split("\n## ", 1)[0]
    assert "CITATION.cff" in section and "Cao" in section and "Shu" in section
