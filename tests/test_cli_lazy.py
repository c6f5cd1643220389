"""The command line answers ``--help`` and usage errors without the heavy imports; plain text.

The import tests run in a subprocess (a fresh ``sys.modules``).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import impactcont
from impactcont.cli import EXIT_OK, main, plain_text
from impactcont.scene.plugins import register_problem, unregister_problem

HEAVY = ("numba", "scipy", "xarray", "matplotlib")
SOURCE = Path(impactcont.__file__).resolve().parents[1]

#: Runs ``main(argv)`` and prints the heavy top-level modules then in ``sys.modules``.
#: With ``bare``, the package ``impactcont`` is an empty module (its ``__init__`` not run):
#: what the command line imports itself.
_PROBE = """
import json, sys, types
argv, bare = json.loads(sys.argv[1])
if bare:
    package = types.ModuleType("impactcont")
    package.__path__ = [{package!r}]
    package.__version__ = "0"
    sys.modules["impactcont"] = package
from impactcont.cli import main
code = main(argv)
heavy = sorted({{name.partition(".")[0] for name in sys.modules}} & set({heavy!r}))
print(json.dumps([code, heavy]))
"""


def _probe(argv: list[str], *, bare: bool) -> tuple[int, list[str]]:
    script = _PROBE.format(package=str(SOURCE / "impactcont"), heavy=HEAVY)
    run = subprocess.run([sys.executable, "-c", script, json.dumps([argv, bare])],
                         cwd=SOURCE, capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr
    code, heavy = json.loads(run.stdout.splitlines()[-1])
    return code, heavy


@pytest.mark.parametrize("argv, code", [
    (["--help"], 0), (["run", "--help"], 0), (["--version"], 0), ([], 2), (["frobnicate"], 2),
    (["run"], 2), (["plot", "a.nc", "--dpi", "many"], 2),
])
def test_the_command_line_itself_imports_nothing_heavy(argv: list[str], code: int) -> None:
    assert _probe(argv, bare=True) == (code, [])


def test_impactcont_help_imports_nothing_heavy() -> None:
    assert _probe(["--help"], bare=False) == (0, [])


class _Documented:
    """Follows :func:`~impactcont.curve` in ``[[x]]``, see :class:`the flow <impactcont.Flow>`.

    More text that list-problems does not show.
    """


def test_list_problems_prints_plain_text(capsys: pytest.CaptureFixture[str]) -> None:
    register_problem("documented", _Documented)
    try:
        assert main(["list-problems"]) == EXIT_OK
    finally:
        unregister_problem("documented")
    out = capsys.readouterr().out
    assert "Follows curve in [[x]], see the flow." in out
    assert "[[branches]]: a one-parameter branch" in out
    assert "`" not in out and ":func:" not in out and ":class:" not in out


@pytest.mark.parametrize("rst, text", [
    (":func:`impactcont.curve`", "impactcont.curve"),
    (":py:meth:`~impactcont.scene.SceneSection.check`", "check"),
    (":class:`Flow <impactcont.orbit.flow.Flow>`", "Flow"),
    (":math:`\\rho(G) < 1`", "\\rho(G) < 1"),
    ("``[[orbits]]``: every root", "[[orbits]]: every root"),
    ("`default role` and `a link <https://example.org>`_", "default role and a link"),
    ("**strong** and *emphasis*, but 2*x*y and a*", "strong and emphasis, but 2*x*y and a*"),
])
def test_plain_text(rst: str, text: str) -> None:
    assert plain_text(rst) == text
