"""A simulation's dataset (issue 30: "sticking intervals and contact forces in the result and
in its dataset"): ``impactcont.save`` writes a SimulationResult as it, the file reads back
with every impact, sticking phase, contact-force sample and accumulation point of the
result, and the command line describes and draws it."""

from __future__ import annotations

import json

import numpy as np
import pytest

import impactcont as ic
from impactcont.dataset.simulation import simulation_dataset
from impactcont.errors import ParameterError
from impactcont.scene.files import read_output
from impactcont.simulate import SimulationStatus
from impactcont.simulate.simulator import SimulationResult


@pytest.fixture(scope="module")
def preloaded_run() -> SimulationResult:
    """The preloaded oscillator (F_static into its stop at b = 0, R = 0.5): complete chatter
    into sticking phases every period."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                              omega=0.7, eta=0.05)
    return ic.simulate(osc, np.array([-0.5, 0.0]), 0.3, 4.0, trajectory=True)


def test_a_saved_simulation_reads_back_with_its_sticking_phases_and_chatter(preloaded_run,
                                                                            tmp_path):
    res = preloaded_run
    assert len(res.sticking) > 0 and len(res.chatter) > 0  # the case has both
    ds = ic.load(ic.save(res, tmp_path / "sim.nc"))
    events = res.sticking_arrays()
    assert ds.attrs["impactcont_dataset"] == "simulation"
    np.testing.assert_array_equal(ds["impact_times"].values, res.impact_times)
    np.testing.assert_array_equal(ds["impact_states"].values, res.impact_states)
    np.testing.assert_array_equal(ds["sticking_start"].values, events["sticking_start"])
    np.testing.assert_array_equal(ds["sticking_end"].values, events["sticking_end"])
    np.testing.assert_array_equal(ds["contact_force"].values, events["force"])
    np.testing.assert_array_equal(ds["chatter_time"].values, events["chatter_time"])
    assert list(ds["sticking_ended_by"].values) == list(events["sticking_ended_by"])
    np.testing.assert_array_equal(ds["X"].values, res.X)
    np.testing.assert_array_equal(ds["start_state"].values, [-0.5, 0.0])
    assert ds.attrs["start_delta"] == 0.3 and ds.attrs["periods"] == 4.0
    assert ds.attrs["status"] == SimulationStatus.COMPLETED.name
    assert ic.ImpactOscillator.from_json(ds.attrs["oscillator"]).to_json() == \
        res.oscillator.to_json()
    assert float(ds["omega"]) == 0.7 and json.loads(ds.attrs["oscillator"])["R"] == 0.5


def test_the_result_records_where_it_started(preloaded_run):
    res = preloaded_run
    assert res.start_phase == 0.3 and res.periods == 4.0
    np.testing.assert_array_equal(res.start_state, [-0.5, 0.0])
    assert res.final_time == pytest.approx(4.0 * 2 * np.pi / 0.7)


def test_a_saved_simulation_is_a_file_the_command_line_reads(preloaded_run, tmp_path):
    out = read_output(ic.save(preloaded_run, tmp_path / "run.nc"))
    assert out.kind == "simulations" and list(out.datasets) == ["run"]


def test_what_is_not_a_simulation_is_refused_by_name():
    with pytest.raises(ParameterError, match="result must be a SimulationResult"):
        simulation_dataset({"impact_times": []})
    empty = np.zeros(0)
    by_hand = SimulationResult(empty, empty, empty, np.zeros((0, 2)), 0.0, np.zeros(2), 0.0,
                               SimulationStatus.COMPLETED)
    with pytest.raises(ParameterError, match="does not record its oscillator"):
        simulation_dataset(by_hand)
    with pytest.raises(TypeError, match="a SimulationResult; got list"):
        ic.save([1, 2], "never.nc")
