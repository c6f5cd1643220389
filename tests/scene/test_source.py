"""The TOML text of a scene (:mod:`impactcont.scene.source`): ``--set`` overrides."""

from __future__ import annotations

from pathlib import Path

import pytest

from impactcont.scene import SceneError, apply_settings, load_scene
from tests._scene_data import ORBITS_SCENE, write


# ---------------------------------------------------------------------------------------------
# --set overrides
# ---------------------------------------------------------------------------------------------
def test_apply_settings() -> None:
    data = {"oscillator": {"b": 0.6}, "branches": [{"name": "a"}, {"name": "c", "N": 1}]}
    paths = apply_settings(data, ["oscillator.b=0.5", "branches[c].N=2",
                                  "branches[0].bounds=[0.5, 3]", "output.directory=out/run 1",
                                  'title="x = y"'])
    assert data["oscillator"]["b"] == 0.5
    assert data["branches"][1]["N"] == 2
    assert data["branches"][0]["bounds"] == [0.5, 3]
    assert data["output"]["directory"] == "out/run 1"  # not TOML: taken as a string
    assert data["title"] == "x = y"
    assert paths[1] == "branches[1].N"


@pytest.mark.parametrize(("setting", "fragment"), [
    ("oscillator.b", "expected key=value"),
    ("branches[3].N=1", "does not exist"),
    ("branches[zz].N=1", "no [[branches]] entry is named 'zz'"),
    ("orbits[0].N=1", "orbits is not an array"),
    # an array of tables named as a table: it said only 'branches is not a table'
    ("branches.a.N=1", "branches is an array of tables ([[branches]]): index it by position "
                       "or entry name; allowed: branches[a].N"),
    ("branches.N=1", "allowed: branches[0].N"),
])
def test_bad_settings(setting: str, fragment: str) -> None:
    with pytest.raises(SceneError) as info:
        apply_settings({"branches": [{"name": "a"}]}, [setting])
    assert fragment in str(info.value)


def test_settings_override_the_file_and_have_no_line(tmp_path: Path) -> None:
    path = write(tmp_path, ORBITS_SCENE)
    scene = load_scene(path, settings=["orbits[paper].omega=1.5", "oscillator.R=0.7"])
    paper = scene.entries("orbits")[0]
    assert paper.oscillator.omega == 1.5 and paper.oscillator.R == 0.7
    with pytest.raises(SceneError) as info:
        load_scene(path, settings=["oscillator.R=2"])
    assert info.value.key == "oscillator.R" and info.value.line is None
