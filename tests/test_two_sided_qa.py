"""QA of the two-sided stops as a user meets them: what was silently wrong or unclear.

Each test pins one problem found by trying the API (issue 14 item 2): the
witness is the event-driven simulator or the refusal's own message.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _scene_data import write

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.scene import SceneError, load_scene
from impactcont.simulate import next_impact

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def paper2(**kw) -> ic.ImpactOscillator:
    """The paper's 2-DOF system (section 4), parameters overridden by `kw`."""
    params = dict(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8, omega=0.8, eta=0.1)
    params.update(kw)
    return ic.ImpactOscillator(**params)


# ------------------------------------------------------------------------------------------
# next_impact (public in impactcont.simulate) ignored osc.stops: it followed x1 to x1 = b
# ------------------------------------------------------------------------------------------
def test_next_impact_follows_the_stop_mass():
    """Stop on mass 2: the first impact is the simulator's (x2 = b), not x1's crossing."""
    osc = paper2(F=[0.0, 1.0], b=0.2, stops=Stops(mass=2))
    X = np.zeros(4)
    tau, X_minus = next_impact(Flow(osc), X, 0.0, 50.0)
    res = ic.simulate(osc, X, 0.0, 3.0)
    assert tau == pytest.approx(res.impact_times[0], abs=1e-10)
    assert X_minus[1] == pytest.approx(0.2, abs=1e-12)


def test_next_impact_refuses_two_stops():
    """With a lower stop next_impact cannot say which stop is hit: refused, naming next_contact."""
    osc = paper2(stops=Stops(b_low=0.8))
    with pytest.raises(ParameterError, match="next_contact"):
        next_impact(Flow(osc), np.array([-0.7, 0.0, -1.0, 0.0]), 0.0, 50.0)


# ------------------------------------------------------------------------------------------
# Scene: a bad stop key was reported at [oscillator], not at the key the user wrote
# ------------------------------------------------------------------------------------------
_SCENE = """
[oscillator]
K = [[1.0, -1.0], [-1.0, 2.0]]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.7
omega = 0.9
{extra}
"""


@pytest.mark.parametrize("extra, key", [
    ("stop_mass = 3", "oscillator.stop_mass"),
    ("R_low = 0.5", "oscillator.R_low"),
    ("b_low = -0.7", "oscillator.b_low"),
])
def test_scene_stop_errors_point_at_the_key(tmp_path: Path, extra: str, key: str):
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, _SCENE.format(extra=extra)))
    assert info.value.key == key, str(info.value)


# ------------------------------------------------------------------------------------------
# Scene outputs: a [[simulations]] + [[multi_impact]] scene with two stops
# ------------------------------------------------------------------------------------------
_RUN = _SCENE.format(extra="b_low = 0.5\nR_low = 0.8") + """
[[simulations]]
name = "sim"
periods = 200
start = "state"
state = [0.0, 0.0, 0.0, 0.0]
delta = 0.0

[[multi_impact]]
name = "mi"
start = "sim"
N = 1
p = 2
bounds = [0.85, 0.95]
max_points = 40
"""


@pytest.fixture(scope="module")
def two_stop_run(tmp_path_factory):
    from impactcont.scene import run_scene

    tmp = tmp_path_factory.mktemp("run")
    result = run_scene(write(tmp, _RUN), output=tmp / "o")
    assert result.ok, result.failures
    return tmp / "o"


def test_scene_simulation_describes_its_impact_velocities(two_stop_run):
    """The stored speeds are towards the stop hit (x_j' at U, -x_j' at L), not mass 1's velocity."""
    from impactcont.scene import read_output

    sim = read_output(two_stop_run / "simulations.nc").datasets["sim"]
    stops = sim.attrs["impact_stops"]
    assert set(stops) == {"U", "L"}
    v = sim["impact_velocities"].values
    assert np.all(v > 0)
    assert "mass 1" not in sim["impact_velocities"].attrs["description"]
    assert "stop" in sim["impact_velocities"].attrs["description"]


def test_scene_info_shows_the_impact_pattern(two_stop_run):
    """``impactcont info`` of an N-p branch names p and the pattern (here 'LU')."""
    from impactcont.scene.describe import describe_file

    text = describe_file(two_stop_run / "multi_impact.nc")
    assert "LU" in text, text


# ------------------------------------------------------------------------------------------
# A failed Newton names the impact sequence it tried
# ------------------------------------------------------------------------------------------
def test_newton_failure_names_the_pattern():
    """Complex F, two stops: the attractor is a 1-4 motion; asking for a 1-2 one fails, and
    the message says which sequence of stops was tried (the simulation's last impacts)."""
    osc = paper2(F=np.array([1.0, 0.5j]), b=0.7, omega=0.9,
                 stops=Stops(b_low=0.5, R_low=0.8))
    res = ic.simulate(osc, np.zeros(4), 0.0, 300.0)
    assert len(set(res.impact_stops[-8:])) == 2
    with pytest.raises(ic.NoPeriodicMotionError,
                       match=f"pattern {res.impact_stops[-3:-1]!r}"):
        ic.multi_impact_orbit(osc, 1, 2, res)
    orbit = ic.multi_impact_orbit(osc, 1, 4, res)  # the motion it settled on
    assert orbit.physical and orbit.stable
    assert sorted(orbit.pattern) == sorted(res.impact_stops[-5:-1])


# ------------------------------------------------------------------------------------------
# The "returned to its parent" stop of an N-p branch compared halves with different stops
# ------------------------------------------------------------------------------------------
def test_asymmetry_ignores_halves_on_different_stops():
    """A 2-2 motion "UL" can never be a 1-1 motion repeated: its halves hit different stops,
    so the parent test (halves equal, or swapped) must not apply. Its phase difference
    sits at +-pi, whose sign flips by rounding and would end the branch spuriously."""
    from types import SimpleNamespace

    from impactcont.analysis.multi_branch import _asymmetry

    def orbit(pattern, dphase):
        return SimpleNamespace(N=2, p=2, pattern=pattern, phases=np.array([0.0, dphase]),
                               states=np.array([[0.8, 0.1, 0.3, 0.2], [-0.8, -0.1, -0.3, -0.2]]),
                               flight_times=np.array([3.0, 3.0]))

    assert _asymmetry(orbit("UL", np.pi)) is None
    assert _asymmetry(orbit("UU", np.pi)) is not None  # same stops: the test applies


# ------------------------------------------------------------------------------------------
# Datasets: a pattern with lower-stop impacts needs an oscillator with a lower stop
# ------------------------------------------------------------------------------------------
def test_dataset_refuses_a_lower_stop_pattern_without_a_lower_stop(tmp_path: Path):
    """A branch saved with pattern 'LU' but an oscillator with one stop was accepted, and
    failed only later (special_orbit, switching) with a message about the orbit."""
    import json

    from impactcont.dataset.multi import validate_multi_impact_dataset

    osc = paper2(b=0.7, omega=0.9, stops=Stops(b_low=0.5, R_low=0.8))
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 200.0))
    assert orbit.pattern == "LU"
    ds = ic.multi_impact_continuation(orbit, "omega", (0.88, 0.92), max_points=5)
    validate_multi_impact_dataset(ds)
    data = json.loads(ds.attrs["oscillator"])
    del data["stops"]
    bad = ds.copy()
    bad.attrs["oscillator"] = json.dumps(data)
    with pytest.raises(ValueError, match="lower stop"):
        validate_multi_impact_dataset(bad)


# ------------------------------------------------------------------------------------------
# Scene [[simulations]]: the start state is checked against the stops of stop_mass
# ------------------------------------------------------------------------------------------
_SIM = """
[[simulations]]
name = "sim"
periods = 5
{start}
"""


def test_scene_simulation_state_on_another_mass_is_accepted(tmp_path: Path):
    """stop_mass = 2: x1 = 0.75 > b is allowed (mass 1 meets no stop); it was refused."""
    text = (_SCENE.format(extra="stop_mass = 2")
            + _SIM.format(start='start = "state"\nstate = [0.75, 0.0, 0.0, 0.0]\ndelta = 0.0'))
    load_scene(write(tmp_path, text))


@pytest.mark.parametrize("extra, state, what", [
    ("stop_mass = 2", "[0.0, 0.75, 0.0, 0.0]", "x2 = 0.75"),
    ("b_low = 0.5", "[-0.6, 0.0, 0.0, 0.0]", "x1 = -0.6"),
])
def test_scene_simulation_state_beyond_a_stop_is_refused(tmp_path: Path, extra, state, what):
    text = (_SCENE.format(extra=extra)
            + _SIM.format(start=f'start = "state"\nstate = {state}\ndelta = 0.0'))
    with pytest.raises(SceneError, match=what) as info:
        load_scene(write(tmp_path, text))
    assert info.value.key.endswith("state")


def test_scene_simulation_orbit_start_with_stops_is_refused_at_start(tmp_path: Path):
    """start = "orbit" needs the closed-form N-1 motion (one stop on mass 1): refused when
    the scene is read, at the key start, naming start = "state"."""
    text = _SCENE.format(extra="b_low = 0.5") + _SIM.format(start="")
    with pytest.raises(SceneError, match='start = "state"') as info:
        load_scene(write(tmp_path, text))
    assert info.value.key.endswith("start")


def test_scene_info_shows_the_simulation_stops(two_stop_run):
    """``impactcont info`` of a two-stop simulation shows the stops of its last impacts."""
    from impactcont.scene import read_output
    from impactcont.scene.describe import describe_file

    stops = read_output(two_stop_run / "simulations.nc").datasets["sim"].attrs["impact_stops"]
    text = describe_file(two_stop_run / "simulations.nc")
    assert stops[-8:] in text, text


# ------------------------------------------------------------------------------------------
# simulate: numpy integers for periods / delta were refused as "not a finite number"
# ------------------------------------------------------------------------------------------
def test_simulate_accepts_numpy_numbers():
    osc = paper2(stops=Stops(b_low=0.8))
    ref = ic.simulate(osc, np.zeros(4), 0.0, 20.0)
    res = ic.simulate(osc, np.zeros(4), np.int64(0), np.int64(20))
    np.testing.assert_array_equal(res.impact_times, ref.impact_times)
    assert res.impact_stops == ref.impact_stops
    with pytest.raises(ParameterError, match="periods"):
        ic.simulate(osc, np.zeros(4), 0.0, np.float64("nan"))
    with pytest.raises(ParameterError, match="periods"):
        ic.simulate(osc, np.zeros(4), 0.0, True)
