"""The entries of the built-in scene sections (:mod:`impactcont.scene.entries`): the
``[oscillator]`` table builds the oscillator it describes, each entry changes it for itself,
writes itself back as a TOML table that parses to the same entry, takes the defaults of its
driver, and is refused with the key, the value and what is allowed."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.scene import entries as e
from impactcont.scene.keys import SceneError, Where

OSC = {"K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "eta": 0.1, "b": 0.6,
       "omega": 1.0}
AT_OSC = Where("s.toml", "oscillator")
AT = Where("s.toml", "branches[0]")


@pytest.fixture(scope="module")
def base() -> ic.ImpactOscillator:
    return e.OscillatorSpec.parse(OSC, AT_OSC).build()


def _refused(parse, raw: dict) -> str:
    with pytest.raises(SceneError) as info:
        parse(raw)
    return str(info.value)


# -- [oscillator] ----------------------------------------------------------------------------
def test_the_oscillator_table_builds_the_paper_system(paper, base) -> None:
    assert base.to_json() == paper.to_json()


def test_a_chain_with_masses_and_rayleigh_damping_is_built_as_eq_2() -> None:
    spec = e.OscillatorSpec.parse({"masses": [1.0, 2.0], "springs": [1.0, 3.0], "F": [1, 0],
                                   "R": 0.5, "alpha": 0.1, "beta": 0.01, "b": 0.2,
                                   "omega": 1.3, "F_imag": [0.0, 0.5]}, AT_OSC)
    osc = spec.build()
    np.testing.assert_array_equal(osc.M, np.diag([1.0, 2.0]))
    # mass 1 on mass 2 by k1, mass 2 on the ground by k2
    np.testing.assert_array_equal(osc.K, [[1.0, -1.0], [-1.0, 4.0]])
    np.testing.assert_array_equal(osc.F, [1.0, 0.5j])
    assert (osc.alpha, osc.beta, osc.eta) == (0.1, 0.01, None)
    again = e.OscillatorSpec.parse(e.spec_dict(spec), AT_OSC)  # written back, read again
    assert again == spec and again.build().to_json() == osc.to_json()


def test_stops_of_the_oscillator_table() -> None:
    osc = e.OscillatorSpec.parse({**OSC, "mirror_stop": True}, AT_OSC).build()
    assert osc.stops.two_sided and osc.stops.b_low == 0.6
    osc = e.OscillatorSpec.parse({**OSC, "stop_mass": 2, "b_low": 0.3, "R_low": 0.4},
                                 AT_OSC).build()
    assert (osc.stops.mass, osc.stops.b_low, osc.stops.R_low) == (2, 0.3, 0.4)


@pytest.mark.parametrize(("change", "message"), [
    ({"springs": [1, 1]}, "s.toml: oscillator.springs: give either K or springs, not both; "
                          "allowed: K (a matrix) or springs (the chain of eq. 2)"),
    ({"K": None}, "s.toml: oscillator.K: the stiffness is missing; allowed: K (a matrix) or "
                  "springs (the chain of eq. 2)"),
    ({"alpha": 0.1}, "s.toml: oscillator.alpha: give either eta or alpha/beta, not both; "
                     "allowed: eta (C = 2 eta K) or alpha, beta (C = alpha M + beta K)"),
    ({"stop_mass": 3}, "s.toml: oscillator.stop_mass: stops.mass must be in 1..2 (the "
                       "oscillator has n=2 masses); got 3"),
    ({"F": [1, 0, 0]}, "s.toml: oscillator.F: F must have shape (2,) to match M and K; got "
                       "shape (3,)"),
    ({"mirror_stop": True, "b": 0.0}, "s.toml: oscillator.b: mirrored stops x1 = +-b need "
                                      "b > 0"),
    ({"R": 1.5}, "s.toml: oscillator.R: out of range; got 1.5 (a float); allowed: a real "
                 "number in [0, 1]"),
    ({"gap": 1}, "s.toml: oscillator.gap: unknown key; not a key of this table; allowed: M, "
                 "K, masses, springs, F, R, b, omega"),
    ({"omgea": 1}, "s.toml: oscillator.omgea: unknown key; did you mean 'omega'?"),
])
def test_a_bad_oscillator_table_is_refused_at_its_key(change, message) -> None:
    raw = {**OSC, **change}
    raw = {k: v for k, v in raw.items() if v is not None}
    assert _refused(lambda r: e.OscillatorSpec.parse(r, AT_OSC), raw).startswith(message)


# -- entries ---------------------------------------------------------------------------------
def test_an_entry_changes_the_oscillator_for_itself_and_gets_a_default_name(base) -> None:
    spec = e.BranchSpec.parse({"bounds": [0.5, 2.0], "b": 0.5, "F_imag": [0.0, 0.2]}, AT,
                              base, 2)
    assert spec.name == "branches3"  # <section><number>
    assert spec.changes == {"F_imag": [0.0, 0.2], "b": 0.5}
    assert spec.oscillator.b == 0.5 and base.b == 0.6
    np.testing.assert_array_equal(spec.oscillator.F, [1.0, 0.2j])  # F kept, phases changed
    named = e.OrbitSpec.parse({"name": "o1"}, AT, base, 0, section="mine")
    assert named.name == "o1"
    assert e.OrbitSpec.parse({}, AT, base, 4, section="mine").name == "mine5"


@pytest.mark.parametrize(("cls", "raw"), [
    (e.OrbitSpec, {"N": 2, "which": "stable", "omega": 2.4}),
    (e.BranchSpec, {"bounds": [0.5, 2.0], "parameter": "b", "start": 1.0, "root": -1,
                    "detect": ["PD"], "ds_max": 0.1, "omega": 1.2}),
    (e.RobustSpec, {"vary": {"b": [0.5, 0.7], "omega": [0.9, 1.1]}, "nominal": {"b": 0.6},
                    "samples": 5}),
    (e.SimulationSpec, {"periods": 3.5, "start": "state", "state": [0.0, 0.0, 0.1, 0.0],
                        "delta": 0.3, "trajectory": True}),
])
def test_an_entry_written_back_as_toml_parses_to_the_same_entry(base, cls, raw) -> None:
    spec = cls.parse(raw, AT, base, 0)
    table = spec.to_dict()
    assert None not in table.values()  # TOML has no null
    again = cls.parse(table, AT, base, 0)
    assert again == spec
    assert again.oscillator.to_json() == spec.oscillator.to_json()
    for key, value in raw.items():
        assert table[key] == value


def test_the_continuation_keys_take_the_drivers_defaults(base) -> None:
    defaults = e.defaults_of(ic.continuation)
    spec = e.BranchSpec.parse({"bounds": [0.5, 2.0]}, AT, base, 0)
    for key in e.CONTINUATION_KEYS:
        assert getattr(spec, key) == defaults[key], key
    kwargs = spec.continuation_kwargs()
    assert kwargs["bounds"] == (0.5, 2.0) and kwargs["parameter"] == "omega"
    assert kwargs["detect"] == tuple(ic.detection.LABELS)
    assert {k: kwargs[k] for k in e.CONTINUATION_KEYS} == {k: defaults[k]
                                                          for k in e.CONTINUATION_KEYS}


@pytest.mark.parametrize(("cls", "raw", "message"), [
    (e.BranchSpec, {"bounds": [0.5, 2.0], "start": 3.0},
     "branches[0].start: 3.0 is outside bounds [0.5, 2.0]; allowed: a real number in [0.5, 2]"),
    (e.BranchSpec, {"bounds": [-1, 2.0]},
     "branches[0].bounds: [-1.0, 2.0] leaves the admissible values of omega; allowed: bounds "
     "inside the range of omega: a real number > 0"),
    (e.BranchSpec, {"bounds": [0.5, 2], "ds": 0.1, "ds_max": 0.01},
     "branches[0].ds: ds_min = 1e-08, ds = 0.1, ds_max = 0.01; allowed: ds_min <= ds <= "
     "ds_max"),
    (e.BranchSpec, {"bounds": [0.5, 2], "parameter": "alpha"},
     "branches[0].parameter: 'alpha' needs Rayleigh damping; the oscillator uses eta"),
    (e.BranchSpec, {"bounds": [0.5, 2], "alpha": 0.1},
     "branches[0].alpha: give either eta or alpha/beta, not both: [oscillator] has eta, so an "
     "entry cannot set alpha"),
    (e.BranchSpec, {"bounds": [0.5, 2], "parameter": "omga"},
     'branches[0].parameter: did you mean "omega"?'),
    (e.RobustSpec, {"vary": {"b": [0.5, 0.7]}, "nominal": {"b": 0.9}},
     "branches[0].nominal.b: 0.9 is outside the box; allowed: a real number in [0.5, 0.7]"),
    (e.RobustSpec, {"vary": {"b": [0.5, 0.7]}, "nominal": {"R": 0.5}},
     "branches[0].nominal.R: not a parameter of vary; allowed: b"),
    (e.RobustSpec, {"vary": {"b": [0.5, 0.7], "omega": [1, 2]}, "samples": 2000},
     "branches[0].samples: 2000 per parameter for 2 parameters is 4000000 grid points; "
     "allowed: at most 1000000 grid points"),
    (e.RobustSpec, {"vary": {"b": [0.5, 0.7]}, "b": 0.6},
     "branches[0].b: b is varied over the box, where its nominal value is nominal.b"),
    (e.SimulationSpec, {"periods": 3, "start": "state"},
     'branches[0].state: required with start = "state"'),
    (e.SimulationSpec, {"periods": 3, "start": "state", "state": [0, 0, 0], "delta": 0},
     "branches[0].state: has length 3; allowed: an array of 2n = 4 real numbers"),
    (e.SimulationSpec, {"periods": 3, "start": "state", "state": [0.7, 0, 0, 0], "delta": 0},
     "branches[0].state: x1 = 0.7 is beyond stop 'U' at 0.6; allowed: x1 <= 0.6"),
    (e.SimulationSpec, {"periods": 3, "state": [0, 0, 0, 0]},
     'branches[0].state: only used with start = "state"'),
    (e.SimulationSpec, {"periods": 0},
     "branches[0].periods: out of range; got 0 (an integer); allowed: a real number in (0, "
     "1e+07]"),
    (e.OrbitSpec, {"which": "none"},
     'branches[0].which: not a known value; got "none" (a string); allowed: one of "all", '
     '"physical", "stable"'),
])
def test_a_bad_entry_is_refused_at_its_key(base, cls, raw, message) -> None:
    text = _refused(lambda r: cls.parse(r, AT, base, 0), raw)
    assert text.startswith(f"s.toml: {message}"), text


def test_the_closed_form_sections_refuse_other_stops() -> None:
    mirrored = e.OscillatorSpec.parse({**OSC, "mirror_stop": True}, AT_OSC).build()
    text = _refused(lambda r: e.OrbitSpec.parse(r, AT, mirrored, 0), {})
    assert "the N-1 closed form" in text and "allowed: an [oscillator] without stop_mass" in text
    text = _refused(lambda r: e.SimulationSpec.parse(r, AT, mirrored, 0), {"periods": 2})
    assert text.startswith('s.toml: branches[0].start: "orbit" starts on the closed-form N-1 '
                           "motion, which handles one stop on mass 1 only")
    spec = e.SimulationSpec.parse({"periods": 2, "start": "state", "state": [0, 0, 0, 0],
                                   "delta": 0}, AT, mirrored, 0)
    assert spec.oscillator.stops.two_sided  # a given state: any stops


def test_library_check_reports_the_key_the_message_names() -> None:
    def check(N):
        raise ValueError(f"N must be >= 1; got {N}")

    with pytest.raises(SceneError, match=r"^s.toml: branches\[0\].N: N must be >= 1; got 0; "
                                         r"allowed: N >= 1$"):
        e.library_check(AT, check, 0, keys=("N",), allowed="N >= 1")
    with pytest.raises(SceneError, match=r"^s.toml: branches\[0\]: N must be"):
        e.library_check(AT, check, 0, keys=("bounds",))
    assert e.library_check(AT, lambda x: x + 1, 1) == 2


def test_refuse_changes_names_the_first_change(base) -> None:
    spec = e.OrbitSpec.parse({"omega": 1.2}, AT, base, 0)
    with pytest.raises(SceneError, match=r"branches\[0\].omega: takes the start's oscillator; "
                                         r"allowed: leave out the oscillator parameters"):
        e.refuse_changes(spec, AT, "takes the start's oscillator")
    e.refuse_changes(e.OrbitSpec.parse({}, AT, base, 0), AT, "unused")


# -- [[simulations]] start = "state": every stop's own coordinate (issue 28, item 1.7) --------
PAIR = {**OSC, "stop_mass": 2, "stop_relative_to": 1, "mirror_stop": True,
        "extra_stops": [{"name": "A", "mass": 1, "gap": 2.0, "restitution": 0.5},
                        {"name": "B", "mass": 2, "gap": 0.4, "restitution": 0.5,
                         "side": -1}]}


@pytest.mark.parametrize(("state", "message"), [
    ([1.0, 1.7, 0, 0], "x2 - x1 = 0.7 is beyond stop 'U' at 0.6; allowed: x2 - x1 <= 0.6"),
    ([1.0, 0.3, 0, 0], "x2 - x1 = -0.7 is beyond stop 'L' at -0.6; allowed: x2 - x1 >= -0.6"),
    ([2.5, 2.5, 0, 0], "x1 = 2.5 is beyond stop 'A' at 2.0; allowed: x1 <= 2.0"),
    ([-0.5, -0.45, 0, 0], "x2 = -0.45 is beyond stop 'B' at -0.4; allowed: x2 >= -0.4"),
])
def test_a_start_state_is_checked_on_each_stops_own_coordinate(state, message) -> None:
    osc = e.OscillatorSpec.parse(PAIR, AT_OSC).build()
    raw = {"periods": 3, "start": "state", "state": state, "delta": 0}
    text = _refused(lambda r: e.SimulationSpec.parse(r, AT, osc, 0), raw)
    assert text.startswith(f"s.toml: branches[0].state: {message}"), text


def test_a_start_state_inside_a_clearance_between_masses_is_accepted() -> None:
    # x2 = 5 is far above b = 0.6, but the clearance x2 - x1 = 0.1 is open
    osc = e.OscillatorSpec.parse(PAIR, AT_OSC).build()
    spec = e.SimulationSpec.parse({"periods": 3, "start": "state", "state": [1.5, 1.6, 0, 0],
                                   "delta": 0}, AT, osc, 0)
    assert spec.state == (1.5, 1.6, 0.0, 0.0)
    ic.simulate(osc, np.array(spec.state), 0.0, 0.5)  # and the run takes it
