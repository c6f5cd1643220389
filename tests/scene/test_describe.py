"""``impactcont info`` (:mod:`impactcont.scene.describe`): what a file holds, in plain text
with Markdown tables: the section and its entries, who wrote it, the scene it came from, each
group's sizes and variables, the section's table and, for branches, the special points."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.scene import entries as e
from impactcont.scene import tasks as t
from impactcont.scene.describe import describe_file
from impactcont.scene.files import write_output
from impactcont.scene.keys import Where

OSC = {"K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "eta": 0.1, "b": 0.6,
       "omega": 1.0}
AT = Where("s.toml", "x")


@pytest.fixture(scope="module")
def base() -> ic.ImpactOscillator:
    return e.OscillatorSpec.parse(OSC, AT).build()


def test_a_scene_file_is_described_with_its_scene_and_table(base, tmp_path) -> None:
    ds = t.ORBITS.compute(e.OrbitSpec.parse({"name": "o1"}, AT, base, 0))
    scene = json.dumps({"title": "small", "orbits": [{"name": "o1"}], "plots": [{}, {}]})
    path = write_output(tmp_path / "orbits.nc", "orbits", {"o1": ds}, title="Orbits of small",
                        scene_json=scene, scene_file="small.toml")
    text = describe_file(path)
    lines = text.splitlines()
    assert lines[0] == f"{path}: periodic orbits (orbits), 1 entry"
    assert lines[1] == "title: Orbits of small"
    assert lines[2].startswith(f"written by: impactcont {ic.__version__}; ")
    assert lines[3] == ("scene: 'small' from small.toml (sections: orbits; plots: 2); the "
                        "resolved scene is in the 'scene' attribute")
    assert "  o1: orbit=2, component=4, g_row=4, g_col=4, multiplier=4; variables: root, " \
           "delta," in text
    assert "\n".join(t.ORBITS.describe({"o1": ds})) in text
    assert "special points:" not in text
    assert text.endswith("\n")


def test_a_branch_of_save_lists_its_special_points(base, tmp_path) -> None:
    branch = ic.continuation(base.replace(b=0.5), N=1, bounds=(1.1, 1.3), ds_max=0.05)
    path = ic.save(branch, tmp_path / "br.nc")
    text = describe_file(path)
    assert text.startswith(f"{path}: branches (branches), 1 entry\n")
    points = t.BRANCHES.special_points({"br": branch})
    assert len(points) == branch.sizes["special"] >= 1
    table = "\n".join(t.special_points_table(points))
    assert f"special points:\n{table}\n" in text
    for label, value in zip(branch["special_label"].values, branch["special_omega"].values,
                            strict=True):
        assert f"| {label} | omega = {value:.8g} |" in text


def test_two_entries_are_counted_and_a_file_that_is_not_ours_refused(base, tmp_path) -> None:
    datasets = {name: t.ORBITS.compute(e.OrbitSpec.parse({"name": name, "b": b}, AT, base, 0))
                for name, b in (("a", 0.6), ("c", 0.2))}
    path = write_output(tmp_path / "orbits.nc", "orbits", datasets, title="two")
    assert describe_file(path).splitlines()[0].endswith("(orbits), 2 entries")
    plain = tmp_path / "plain.nc"
    xr.Dataset({"x": ("i", np.zeros(2))}).to_netcdf(plain)
    with pytest.raises(ValueError, match="not a branch dataset"):
        describe_file(plain)
    with pytest.raises(FileNotFoundError):
        describe_file(tmp_path / "missing.nc")
