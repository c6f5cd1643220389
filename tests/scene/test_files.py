"""The files of a scene run (:mod:`impactcont.scene.files`): one section written atomically,
one group per entry, with the root attributes that say what it holds; read back by name with
the section, files of ``impactcont.save`` too; a file that is not impactcont's is refused."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset.attributes import check_file_attributes
from impactcont.scene import entries as e
from impactcont.scene import files as f
from impactcont.scene import tasks as t
from impactcont.scene.keys import Where

OSC = {"K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "eta": 0.1, "b": 0.6,
       "omega": 1.0}
AT = Where("s.toml", "orbits[0]")
SCENE = json.dumps({"title": "sc", "orbits": [{"name": "o1"}, {"name": "o2"}]})


@pytest.fixture(scope="module")
def orbits() -> dict[str, xr.Dataset]:
    base = e.OscillatorSpec.parse(OSC, AT).build()
    return {name: t.ORBITS.compute(e.OrbitSpec.parse({"name": name, **raw}, AT, base, 0))
            for name, raw in (("o1", {}), ("o2", {"N": 2, "b": 0.0, "omega": 2.4}))}


def test_a_section_is_written_one_group_per_entry_and_read_back(orbits, tmp_path) -> None:
    path = f.write_output(tmp_path / "orbits.nc", "orbits", orbits, title="T",
                          scene_json=SCENE, scene_file="s.toml")
    assert path == tmp_path / "orbits.nc"
    out = f.read_output(path)
    assert out.kind == "orbits" and list(out.datasets) == ["o1", "o2"]
    assert repr(out) == f"SceneOutput({str(path)!r}, kind='orbits', entries=['o1', 'o2'])"
    for name, ds in orbits.items():
        xr.testing.assert_identical(out.datasets[name], ds)
    assert out.attrs[f.KIND_ATTRIBUTE] == "orbits" == out.attrs["impactcont_kind"]
    assert out.attrs["title"] == "T" and out.attrs["scene_file"] == "s.toml"
    assert json.loads(out.attrs["scene"]) == json.loads(SCENE)
    assert out.attrs["Conventions"].startswith("CF-")
    assert out.attrs["history"].endswith("written by impactcont run")
    check_file_attributes(out.attrs)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["orbits.nc"]  # no temporary left


def test_a_failed_write_leaves_the_old_file_and_no_half_file(orbits, tmp_path) -> None:
    path = f.write_output(tmp_path / "orbits.nc", "orbits", {"o1": orbits["o1"]}, title="old")
    broken = orbits["o2"].copy()
    broken.attrs["oscillator"] = "{not json"
    with pytest.raises(ValueError, match=r"attribute 'oscillator' must be the oscillator as "
                                         r"JSON"):
        f.write_output(path, "orbits", {"o1": orbits["o1"], "o2": broken}, title="new")
    assert f.read_output(path).attrs["title"] == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["orbits.nc"]


def test_a_file_of_save_is_read_as_its_section(tmp_path) -> None:
    osc = ic.ImpactOscillator(M=[[1.0, 0.0], [0.0, 1.0]], K=[[1.0, -1.0], [-1.0, 2.0]],
                              F=[1.0, 0.0], R=0.6, b=0.5, omega=1.2, eta=0.1)
    branch = ic.continuation(osc, N=1, bounds=(1.1, 1.3), detect=())
    out = f.read_output(ic.save(branch, tmp_path / "br.nc"))
    assert out.kind == "branches" and list(out.datasets) == ["br"]  # named after the file
    xr.testing.assert_identical(out.datasets["br"], branch)
    grid = ic.stability_map(osc, [1], [1.0, 1.2], [0.4, 0.5])
    out = f.read_output(ic.save({"m": grid}, tmp_path / "maps.nc"))
    assert out.kind == "maps" and list(out.datasets) == ["m"]
    # a map of a motion's family (stability_map of a motion, its out= file): it was 'not a
    # file written by impactcont (... missing attribute(s) ['parameter'])'
    motion = ic.multi_impact_orbit(osc, 1, 1, next(o for o in ic.periodic_orbits(osc, 1)
                                                    if o.physical))
    family = ic.stability_map(motion, parameters=("omega", "b"),
                              grid={"omega": [1.15, 1.2], "b": [0.45, 0.5]})
    out = f.read_output(ic.save(family, tmp_path / "family.nc"))
    assert out.kind == "maps" and list(out.datasets) == ["family"]
    out = f.read_output(ic.save({"m": grid, "family": family}, tmp_path / "both.nc"))
    assert out.kind == "maps" and list(out.datasets) == ["m", "family"]
    # datasets of several kinds: said 'not a file written by impactcont'
    with pytest.raises(ValueError, match=r"holds datasets of several kinds \(branch, map\)"):
        f.read_output(ic.save({"b": branch, "m": grid}, tmp_path / "mixed.nc"))


def test_a_file_that_is_not_impactcont_s_is_refused(tmp_path) -> None:
    plain = tmp_path / "plain.nc"
    xr.Dataset({"x": ("i", [1.0])}).to_netcdf(plain)
    with pytest.raises(ValueError, match=r"plain.nc'?: not a branch dataset: missing "
                                         r"attribute\(s\)"):
        f.read_output(plain)
    with pytest.raises(FileNotFoundError):
        f.read_output(tmp_path / "missing.nc")


_HOLD_LOCK = """
import sys
from impactcont.scene.files import output_lock
with output_lock(sys.argv[1]):
    print("held", flush=True)
    sys.stdin.readline()
"""


def test_the_lock_of_a_killed_run_is_released_and_taken_over(tmp_path: Path) -> None:
    import signal
    import subprocess
    import sys

    from impactcont.scene.files import LOCK_FILE, OutputInUseError, output_lock

    holder = subprocess.Popen([sys.executable, "-c", _HOLD_LOCK, str(tmp_path)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                              cwd=Path(__file__).resolve().parents[2])
    try:
        assert holder.stdout.readline() == "held\n"
        expected = f"output folder {str(tmp_path)!r} is in use by another scene run (pid " \
            f"{holder.pid}, lock file"
        with pytest.raises(OutputInUseError, match=re.escape(expected)), output_lock(tmp_path):
            pass
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    assert (tmp_path / LOCK_FILE).exists()  # a killed run leaves its file, not its lock
    with output_lock(tmp_path) as path:
        assert path.read_text() == f"{os.getpid()}\n"
    assert not path.exists()
