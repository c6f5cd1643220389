"""Every page of ``docs/`` and README run as a reader would run them: python blocks in order.

A reader copies a page's ```` ```python ```` blocks into one session, top to bottom. This
test does the same for every page but the tutorial (whose shown outputs
``test_tutorial.py`` checks too): one namespace per page, in a temporary working
directory, a ```` ```toml ```` block whose first line is ``# <name>.toml`` written to that
file first. A name a block uses must come from an earlier block of the same page, not
from the prose.

A block that cannot run on a test machine is marked by the HTML comment
``<!-- not run: <reason> -->`` on the line before its fence (the page shows nothing of
it). A marked block must still compile, and the reason must say what it needs (a dask
cluster at an address, ...). ``outputs.md`` reads the main job's files: the test writes
them first with the README's scene (``studies/main_job/scene.toml``).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
import types
import warnings
from pathlib import Path

import matplotlib
import pytest

from tests.integration.test_tutorial import TOML_NAME, fenced_blocks

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
NOT_RUN = re.compile(r"<!--\s*not run:\s*(?P<reason>[^>]*?)\s*-->\s*\Z")
#: Pages whose blocks read files a scene writes: (scene, output directory in the workdir).
SCENES = {"docs/outputs.md": ("studies/main_job/scene.toml", "output/main_job")}
PAGES = sorted(str(p.relative_to(ROOT)) for p in [ROOT / "README.md", *DOCS.rglob("*.md")]
               if p.name != "tutorial.md" and "```python" in p.read_text())


def _reason(text: str, start: int) -> str | None:
    """The reason of a ``<!-- not run: ... -->`` on the line before the fence at `start`."""
    before = text[:start].rstrip("\n").rsplit("\n", 1)[-1]
    match = NOT_RUN.search(before)
    return match["reason"] if match else None


def run_page(name: str, workdir: Path) -> list[tuple[int, str]]:
    """Run the python blocks of the page `name` (relative to the repository) in `workdir`.

    Returns
    -------
    list of (int, str)
        The line and the reason of each block marked not to run.
    """
    from impactcont.scene.plugins import list_problems, unregister_problem

    text = (ROOT / name).read_text()
    # a module of its own (dataclasses look their module up in sys.modules)
    module = types.ModuleType(f"docs_{Path(name).stem}")
    sys.modules[module.__name__] = module
    namespace = module.__dict__
    skipped = []
    before = set(list_problems())
    cwd = os.getcwd()
    os.chdir(workdir)
    try:
        if name in SCENES:
            from impactcont.scene.run import run_scene
            scene, out = SCENES[name]
            run_scene(ROOT / scene, output=workdir / out)
        for block in fenced_blocks(text):
            line = text[:block.start].count("\n") + 1
            if block.lang == "toml":
                first = block.body.splitlines()[0] if block.body.strip() else ""
                if (toml := TOML_NAME.match(first)):
                    Path(toml["name"]).write_text(block.body)
                continue
            if block.lang != "python":
                continue
            code = compile(block.body, f"{name}:{line}", "exec")
            if (reason := _reason(text, block.start)) is not None:
                skipped.append((line, reason))
                continue
            with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                exec(code, namespace)
    finally:
        os.chdir(cwd)
        del sys.modules[module.__name__]
        for added in set(list_problems()) - before:
            unregister_problem(added)
        import matplotlib.pyplot as plt

        plt.close("all")
    return skipped


@pytest.mark.parametrize("name", PAGES)
def test_every_python_block_of_a_page_runs_in_order(name, tmp_path):
    skipped = run_page(name, tmp_path)
    for line, reason in skipped:
        assert len(reason.split()) >= 3, (
            f"{name}:{line}: a block not run must say what it needs, not {reason!r}")


def test_the_pages_are_found_and_the_marker_is_read():
    pages = {"README.md", "docs/machines.md", "docs/outputs.md", "docs/api/simulate.md"}
    assert pages <= set(PAGES)
    text = "prose\n<!-- not run: needs a dask scheduler -->\n```python\nx = 1\n```\n"
    assert _reason(text, text.index("```python")) == "needs a dask scheduler"
    text = "<!-- not run: x -->\n\nprose\n```python\nx = 1\n```\n"
    assert _reason(text, text.index("```python")) is None
