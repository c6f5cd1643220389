"""Scene section ``[[switches]]``: branches born at PD, grazing and pitchfork points, chained."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.switching import pitchfork_branch
from impactcont.scene import SceneError, load_scene, read_output, run_scene
from tests._scene_data import OSCILLATOR, write

SCENE = OSCILLATOR.replace("b = 0.6", "b = 0.0").replace("omega = 1.0", "omega = 1.75") + """
[[branches]]
name = "N1"
bounds = [1.6, 1.9]
detect = ["PD"]

[[switches]]
name = "two"
start = "N1"
detect = ["PD", "GR"]

[[switches]]
name = "four"
start = "two"
ds_max = 0.02

[[plots]]
name = "cascade"
kind = "bifurcation_diagram"
data = ["N1", "two", "four"]
"""


def test_switches_chain_into_a_cascade_as_the_api_does(tmp_path: Path) -> None:
    result = run_scene(write(tmp_path, SCENE), output=tmp_path / "o")
    assert result.ok, result.failures
    out = read_output(tmp_path / "o" / "switches.nc")
    assert out.kind == "switches" and list(out.datasets) == ["two", "four"]
    two, four = out.datasets["two"], out.datasets["four"]
    assert (int(two.attrs["N"]), int(four.attrs["N"])) == (2, 4)
    assert four.attrs["start"] == "two" and two.attrs["born_at"] == "PD"
    # the same numbers as the public API called by hand
    branch = ic.continuation(load_scene(write(tmp_path, SCENE)).osc, N=1, bounds=(1.6, 1.9),
                             detect=("PD",))
    direct = ic.period_doubling_switch(branch, 0, detect=("PD", "GR"))
    assert np.allclose(two["special_omega"].values, direct["special_omega"].values,
                       rtol=0, atol=1e-10)
    assert float(two.attrs["born_at_value"]) == pytest.approx(1.70038303473, abs=1e-10)
    pd_four = float(four.attrs["born_at_value"])
    assert pd_four == pytest.approx(1.80053912289, abs=1e-10)
    assert (tmp_path / "o" / "cascade.png").stat().st_size > 1000
    summary = (tmp_path / "o" / "summary.md").read_text(encoding="utf-8")
    assert "## Branches switched at special points" in summary
    assert any(p["branch"] == "four" for p in result.special_points)


@pytest.mark.parametrize(("change", "key", "allowed"), [
    ('start = "two"', "switches[0].start", "N1"),           # not an earlier entry
    ('start = "nothing"', "switches[0].start", "N1"),
    ('b = 0.5', "switches[0].b", "leave out the oscillator parameters"),
    ('at = "NS"', "switches[0].at", '"PD", "GR", "BP"'),
    ('side = 0', "switches[0].side", "one of +1, -1"),
    ('ds = 0.5', "switches[0].ds", "ds_min <= ds <= ds_max"),
    ('both_directions = false', "switches[0].both_directions", "start, at, which"),
    # issue 28: a side only picks a motion of a pitchfork's pair; BP needs an N-p branch
    ('side = -1', "switches[0].side", 'leave side out, or set at = "BP"'),
    ('at = "GR"\nside = 1', "switches[0].side", 'leave side out, or set at = "BP"'),
    ('at = "BP"', "switches[0].at", "an N-1 motion is never symmetric"),
])
def test_switch_errors_name_the_key(tmp_path: Path, change: str, key: str,
                                    allowed: str) -> None:
    text = SCENE.replace('start = "N1"\ndetect', f'start = "N1"\n{change}\ndetect', 1)
    if change.startswith("start"):
        text = SCENE.replace('start = "N1"\ndetect', f'{change}\ndetect', 1)
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, text))
    assert info.value.key == key
    assert allowed in (info.value.allowed or "") + str(info.value)


def test_a_switch_whose_start_failed_fails_alone(tmp_path: Path) -> None:
    text = SCENE.replace('detect = ["PD"]', 'detect = []')  # no PD point to switch at
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    failed = {(f.section, f.name) for f in result.failures}
    assert ("switches", "two") in failed and ("switches", "four") in failed
    assert "was not computed" in next(f.error for f in result.failures if f.name == "four")
    assert read_output(tmp_path / "o" / "branches.nc").datasets["N1"].sizes["point"] > 2


MULTI = SCENE.split("[[switches]]")[0] + """
[[simulations]]
name = "settled"
omega = 1.8
periods = 200
perturbation = 1e-3

[[multi_impact]]
name = "seen"
start = "settled"
N = 2
p = 2
bounds = [1.6, 1.9]
ds_max = 0.02
"""


def test_a_simulated_attractor_becomes_a_branch(tmp_path: Path) -> None:
    result = run_scene(write(tmp_path, MULTI), output=tmp_path / "o")
    assert result.ok, result.failures
    seen = read_output(tmp_path / "o" / "multi_impact.nc").datasets["seen"]
    assert int(seen.attrs["N"]) == 2 and seen.sizes["impact"] == 2
    # the same motion as the 2-2 branch born at the PD of N1: its PD at 1.80053912289
    pd = [float(v) for v, label in zip(seen["special_omega"].values,
                                       seen["special_label"].values, strict=True)
          if str(label) == "PD"]
    assert any(abs(v - 1.80053912289) < 1e-10 for v in pd), pd


@pytest.mark.parametrize(("change", "key"), [
    ('start = "N1"', "multi_impact[0].start"),           # not a simulation
    ('bounds = [1.0, 1.5]', "multi_impact[0].bounds"),    # omega = 1.8 outside
    ('omega = 1.7', "multi_impact[0].omega"),
    ('parameter = "m9"', "multi_impact[0].parameter"),  # past n = 2 (issue 28)
])
def test_multi_impact_errors_name_the_key(tmp_path: Path, change: str, key: str) -> None:
    name = change.split(" =")[0]
    lines = [ln for ln in MULTI.split("[[multi_impact]]")[1].splitlines()
             if not ln.startswith(f"{name} =")]
    text = MULTI.split("[[multi_impact]]")[0] + "[[multi_impact]]\n" + change + "\n" + \
        "\n".join(lines)
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, text))
    assert info.value.key == key


BACKLASH = """
[oscillator]
masses = [1.0, 1.0]
springs = [1.0, 1.0]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.5
b_low = 0.5
R_low = 0.6
omega = 1.6

[[simulations]]
name = "settled"
start = "state"
state = [0.0, 0.0, 0.0, 0.0]
delta = 0.0
periods = 150

[[multi_impact]]
name = "symmetric"
start = "settled"
N = 1
p = 2
bounds = [1.2, 1.7]
ds_max = 0.02

[[switches]]
name = "mirror"
start = "symmetric"
at = "BP"
side = -1
max_points = 20
"""


def test_a_switch_at_a_pitchfork_of_a_multi_impact_branch(tmp_path: Path) -> None:
    """multi_impact entries are computed before switches, which may start from them."""
    result = run_scene(write(tmp_path, BACKLASH), output=tmp_path / "o")
    assert result.ok, result.failures
    symmetric = read_output(tmp_path / "o" / "multi_impact.nc").datasets["symmetric"]
    mirror = read_output(tmp_path / "o" / "switches.nc").datasets["mirror"]
    bp = [float(v) for v, label in zip(symmetric["special_omega"].values,
                                       symmetric["special_label"].values, strict=True)
          if str(label) == "BP"]
    assert len(bp) == 1 and abs(bp[0] - 1.3378193720929) < 1e-9
    assert mirror.attrs["born_at"] == "BP" and int(mirror.attrs["switch_side"]) == -1
    direct = pitchfork_branch(symmetric, 0, -1, max_points=20)
    np.testing.assert_allclose(mirror["state_k"].values, direct["state_k"].values, atol=1e-10)


def test_mirror_stop_key(tmp_path: Path) -> None:
    text = BACKLASH.replace("b_low = 0.5\nR_low = 0.6\n", "mirror_stop = true\n")
    osc = load_scene(write(tmp_path, text)).osc
    assert osc.stops.mirror and (osc.stops.b_low, osc.stops.R_low) == (0.5, 0.6)
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, text.replace("mirror_stop = true", "mirror_stop = true\n"
                                                "b_low = 0.4")))
    assert info.value.key == "oscillator.mirror_stop"


def test_a_multi_impact_entry_seeded_by_a_sticky_simulation_continues_the_sticky_motion(
        tmp_path: Path) -> None:
    """The riding damper of studies/sticking_motions (a plastic ball riding each wall): the
    entry's seed carries the simulation's sticking phases, so the motion continued is the
    one with sticking phases (pattern "lu"/"ul", stick times > 0), the motion
    ``multi_impact_orbit`` finds from the run itself. Before, the seed dropped the sticking
    phases and Newton went to the plain "LU" motion, not physical over most of the range."""
    study = Path(__file__).resolve().parents[2] / "studies" / "sticking_motions" / "scene.toml"
    text = study.read_text().split("[[plots]]")[0] + """
[[multi_impact]]
name = "ride"
start = "riding"
N = 1
p = 2
parameter = "omega"
bounds = [0.18, 0.22]
"""
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok, result.failures
    ds = result.datasets["multi_impact"]["ride"]
    assert ds.attrs["pattern"] in ("lu", "ul")
    assert float(ds["stick_time_k"].min()) > 0
    osc = ic.ImpactOscillator.from_json(result.datasets["simulations"]["riding"]
                                        .attrs["oscillator"])
    X0 = [1.033991380508828, 1.333991380508828, 0.026067009592659535, 0.026067009592659535]
    alone = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, X0, 0.0, 12 * 2 * np.pi / 0.2))
    assert alone.pattern == ds.attrs["pattern"]
    at = ds.sel(point=int(np.argmin(np.abs(ds["omega"].values - 0.2))))
    assert float(at["omega"]) == pytest.approx(0.2, abs=1e-12)
    np.testing.assert_allclose(at["stick_time_k"].values, alone.stick_times, rtol=1e-9)
