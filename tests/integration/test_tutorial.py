"""The outputs shown in ``docs/tutorial.md`` are those of running its code.

The tutorial's ```` ```python ```` blocks are executed in order, in one
namespace, in a temporary working directory (files the tutorial writes go
there); a ```` ```toml ```` block whose first line is ``# <name>.toml`` is
written to that file first. What a python block prints is shown in the
```` ```text ```` block that follows it (only blank lines between); a block
that prints nothing has none. The test compares each shown block with the
printed text exactly, after stripping trailing whitespace.

To regenerate the shown outputs after changing the tutorial or the library::

    .venv/bin/python tests/integration/test_tutorial.py --write

(run from the repository root; it rewrites the ```` ```text ```` blocks of
``docs/tutorial.md`` in place, then check the diff). The tutorial prints only
what does not vary by machine or run: no timings or paths, and floats rounded
to what the method guarantees.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

TUTORIAL = Path(__file__).resolve().parents[2] / "docs" / "tutorial.md"
FENCE = re.compile(r"^```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)^```[ \t]*$", re.M | re.S)
TOML_NAME = re.compile(r"#\s*(?P<name>[\w.-]+\.toml)\s*$")


@dataclass
class Block:
    """One fenced code block of the tutorial: its language, text and span in the file."""

    lang: str
    body: str
    start: int
    end: int


def fenced_blocks(text: str) -> list[Block]:
    """Return the fenced code blocks of a Markdown ``text`` in order."""
    return [Block(m["lang"], m["body"], m.start(), m.end()) for m in FENCE.finditer(text)]


def _tidy(output: str) -> str:
    """Output lines without trailing whitespace, without trailing blank lines."""
    return "\n".join(line.rstrip() for line in output.splitlines()).rstrip("\n")


def _shown_output(text: str, blocks: list[Block], i: int) -> Block | None:
    """The ``text`` block right after block ``i`` (only blank lines between), if any."""
    after = blocks[i + 1] if i + 1 < len(blocks) else None
    if after is not None and after.lang == "text" and not text[blocks[i].end:after.start].strip():
        return after
    return None


def run_tutorial(text: str, workdir: Path) -> list[tuple[Block, Block | None, str]]:
    """Execute the tutorial's python blocks in order in ``workdir``.

    Parameters
    ----------
    text : str
        The tutorial's Markdown.
    workdir : Path
        Working directory for the files the tutorial writes.

    Returns
    -------
    list of (Block, Block or None, str)
        Per python block: the block, the output block shown after it, and
        what it printed (tidied).
    """
    blocks = fenced_blocks(text)
    namespace: dict = {"__name__": "__tutorial__"}
    results = []
    cwd = os.getcwd()
    os.chdir(workdir)
    try:
        for i, block in enumerate(blocks):
            if block.lang == "toml":
                name = TOML_NAME.match(block.body.splitlines()[0])
                if name:
                    Path(name["name"]).write_text(block.body)
            elif block.lang == "python":
                out = io.StringIO()
                with contextlib.redirect_stdout(out):
                    exec(compile(block.body, f"{TUTORIAL.name}:block{i}", "exec"), namespace)
                results.append((block, _shown_output(text, blocks, i), _tidy(out.getvalue())))
    finally:
        os.chdir(cwd)
    return results


def write_outputs(path: Path = TUTORIAL) -> None:
    """Rewrite the ``text`` blocks of the tutorial at ``path`` with its real outputs."""
    text = path.read_text()
    with tempfile.TemporaryDirectory() as tmp:
        results = run_tutorial(text, Path(tmp))
    # edit from the end so that the earlier spans stay valid
    for block, shown, printed in reversed(results):
        new = f"```text\n{printed}\n```" if printed else ""
        if shown is not None:
            start, end = block.end, shown.end
        else:
            start = end = block.end
        text = text[:start] + ("\n\n" + new if new else "") + text[end:]
    path.write_text(text)


def test_tutorial_outputs_are_its_real_outputs(tmp_path):
    text = TUTORIAL.read_text()
    blocks = fenced_blocks(text)
    assert any(b.lang == "python" for b in blocks)
    results = run_tutorial(text, tmp_path)
    # every output block is a python block's output: none is written by hand
    shown_starts = {shown.start for _, shown, _ in results if shown is not None}
    for block in blocks:
        if block.lang == "text":
            assert block.start in shown_starts, (
                f"docs/tutorial.md: output block follows no python block:\n{block.body}")
    for block, shown, printed in results:
        where = f"docs/tutorial.md, block:\n{block.body}"
        if shown is None:
            assert not printed, f"{where}\nprints output that is not shown:\n{printed}"
        else:
            assert _tidy(shown.body) == printed, (
                f"{where}\nshown output differs from the real one (regenerate with "
                f"`python tests/integration/test_tutorial.py --write`)")


if __name__ == "__main__":
    if sys.argv[1:] == ["--write"]:
        write_outputs()
    else:
        sys.exit("usage: python tests/integration/test_tutorial.py --write")
