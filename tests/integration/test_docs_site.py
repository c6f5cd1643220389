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
