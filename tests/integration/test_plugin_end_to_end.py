"""A third-party problem, installed through its entry point, runs from a scene and the CLI.

The plugin is the worked example of ``docs/plugins.md``: its module, its
``entry_points.txt`` and its scene are taken from that page, installed as a
``*.dist-info`` directory on ``PYTHONPATH`` (what pip would leave in
site-packages; ``importlib.metadata`` finds the entry point there) and run by
``python -m impactcont`` in a fresh process. A second, broken plugin is
installed beside it: it warns and the run still succeeds.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import impactcont
from impactcont.scene import read_output

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "plugins.md"
_BLOCK = re.compile(r"<!-- file: (?P<name>[\w.]+) -->\n```\w*\n(?P<body>.*?)\n```", re.S)


def doc_files() -> dict[str, str]:
    """The files of the worked example: ``name -> text``, from the page."""
    return {m["name"]: m["body"] + "\n" for m in _BLOCK.finditer(DOC.read_text("utf-8"))}


def _dist_info(site: Path, name: str, version: str, entry_points: str) -> None:
    info = site / f"{name.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n",
                                   encoding="utf-8")
    (info / "entry_points.txt").write_text(entry_points, encoding="utf-8")


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """A site directory holding the example plugin and a broken one; the environment to use."""
    files = doc_files()
    assert set(files) == {"impactcont_omega_sweep.py", "entry_points.txt", "scene.toml"}
    site = tmp_path_factory.mktemp("site")
    (site / "impactcont_omega_sweep.py").write_text(files["impactcont_omega_sweep.py"],
                                                    encoding="utf-8")
    _dist_info(site, "impactcont-omega-sweep", "0.1", files["entry_points.txt"])
    _dist_info(site, "broken-plugin", "1.0",
               "[impactcont.problems]\nbroken = tests_no_such_module_xyz:PROBLEM\n")
    work = tmp_path_factory.mktemp("work")
    (work / "scene.toml").write_text(files["scene.toml"], encoding="utf-8")
    source = Path(impactcont.__file__).resolve().parents[1]  # this tree, not an installed copy
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(source), str(site)])}
    return work, env


def _cli(args: list[str], env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "impactcont", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600, check=False)


def test_the_plugin_is_listed_and_the_broken_one_warns(installed) -> None:
    work, env = installed
    run = _cli(["list-problems"], env, work)
    assert run.returncode == 0, run.stderr
    line = next(x for x in run.stdout.splitlines() if x.startswith("omega_sweep "))
    assert "plugin impactcont-omega-sweep 0.1" in line and "[[omega_sweep]]" in line
    assert "the N-1 motions of eq. (15) on a grid of omega" in run.stdout
    assert "'broken'" in run.stderr and "ModuleNotFoundError" in run.stderr
    assert "broken " not in run.stdout


def test_the_plugin_runs_from_a_scene_through_the_cli(installed) -> None:
    work, env = installed
    check = _cli(["run", "scene.toml", "--check"], env, work)
    assert check.returncode == 0, check.stderr
    assert "1 omega_sweep" in check.stdout
    bad = _cli(["run", "scene.toml", "--check", "--set", "omega_sweep[0].points=1"], env, work)
    assert bad.returncode == 2 and "omega_sweep[0].points" in bad.stderr

    run = _cli(["run", "scene.toml", "--output", "out", "--set",
                "omega_sweep[sweep_N1].points=5"], env, work)
    assert run.returncode == 0, run.stderr
    assert "'broken'" in run.stderr  # the broken plugin warns; the run goes on
    out = read_output(work / "out" / "omega_sweep.nc")
    assert out.kind == "omega_sweep" and list(out.datasets) == ["sweep_N1"]
    ds = out.datasets["sweep_N1"]
    assert np.allclose(ds["omega"].values, np.linspace(0.8, 1.6, 5))
    at_1 = read_output(work / "out" / "orbits.nc").datasets["at_1"]
    # the plugin's closed-form values are the built-in section's at omega = 1.0
    v = ds["impact_velocity"].sel(omega=1.0, method="nearest").values
    assert np.allclose(sorted(v), sorted(at_1["impact_velocity"].values), rtol=1e-12)
    assert (work / "out" / "sweep.png").stat().st_size > 1000
    summary = (work / "out" / "summary.md").read_text(encoding="utf-8")
    assert "## Omega sweeps" in summary and "| sweep_N1 | 1 | 5 |" in summary
    info = _cli(["info", "out/omega_sweep.nc"], env, work)
    assert info.returncode == 0 and "omega sweeps (omega_sweep)" in info.stdout
