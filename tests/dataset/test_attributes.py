"""The attributes impactcont reads back (:mod:`impactcont.dataset.attributes`): each check
refuses a value a reader would misread, naming the attribute, the value and what is
allowed; the right values pass and are returned as read; old robust files are upgraded."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import attributes as at
from impactcont.model.stops import Stops


@pytest.fixture(scope="module")
def branch() -> xr.Dataset:
    """An N-1 branch of the paper's system at b = 0 through its period doubling."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              R=0.6, b=0.0, omega=1.75, eta=0.1)
    return ic.continuation(osc, N=1, bounds=(1.6, 1.9), detect=("PD",))


@pytest.fixture(scope="module")
def two(branch) -> xr.Dataset:
    """The 2-2 branch born at its period doubling: N = 2, p = 2 impacts."""
    return ic.period_doubling_switch(branch, 0, ds_max=0.05)


def _with(ds: xr.Dataset, **attrs) -> xr.Dataset:
    out = ds.copy()
    out.attrs.update(attrs)
    return out


# -- the oscillator ---------------------------------------------------------------------------
def test_the_oscillator_is_read_back_as_written(branch) -> None:
    osc = at.oscillator_attribute(branch)
    assert osc.to_json() == branch.attrs["oscillator"]
    assert osc.n == 2 and osc.omega == 1.75


@pytest.mark.parametrize(("value", "match"), [
    (None, r"attribute 'oscillator' is missing: it must be the oscillator as JSON"),
    ("{not json", r"attribute 'oscillator' must be the oscillator as JSON .*which is not JSON"),
    ("[1, 2]", r"attribute 'oscillator' must be .*a JSON object; got '\[1, 2\]'"),
    ('{"M": 3}', r"attribute 'oscillator' must be .*which is not a valid oscillator"),
    (7, r"attribute 'oscillator' must be the oscillator as JSON text.*; got 7"),
])
def test_a_bad_oscillator_is_named(branch, value, match) -> None:
    ds = branch.copy()
    if value is None:
        del ds.attrs["oscillator"]
    else:
        ds.attrs["oscillator"] = value
    with pytest.raises(ValueError, match=match):
        at.oscillator_attribute(ds)


def test_an_oscillator_of_another_size_than_the_state_is_refused(branch) -> None:
    three = ic.ImpactOscillator.chain(masses=[1, 1, 1], springs=[1, 1, 1], F=[1, 0, 0],
                                      R=0.6, b=0.0, omega=1.75, eta=0.1)
    with pytest.raises(ValueError, match=r"n=3 masses, but dimension 'component' has size 4; "
                                         r"allowed: an oscillator of 2 masses"):
        at.oscillator_attribute(_with(branch, oscillator=three.to_json()))


# -- impacts and pattern ---------------------------------------------------------------------
def test_impacts_is_one_without_the_impact_dimension_and_p_with_it(branch, two) -> None:
    assert at.impacts_attribute(branch) == 1
    assert at.impacts_attribute(two) == 2 == two.sizes["impact"]


@pytest.mark.parametrize(("value", "match"), [
    (3, r"attribute 'impacts' must equal the impacts per motion: the dimension 'impact' has "
        r"size 2; got 3"),
    (0, r"attribute 'impacts' must be an integer >= 1 \(impacts per motion\); got 0"),
    (True, r"attribute 'impacts' must be an integer >= 1.*; got True"),
    ("2", r"attribute 'impacts' must be an integer >= 1.*; got '2'"),
])
def test_a_wrong_impacts_is_named(two, value, match) -> None:
    with pytest.raises(ValueError, match=match):
        at.impacts_attribute(_with(two, impacts=value))


def test_impacts_on_a_branch_without_the_impact_dimension_must_be_one(branch) -> None:
    with pytest.raises(ValueError, match=r"the dataset has no dimension 'impact' \(p = 1\); "
                                         r"got 2"):
        at.impacts_attribute(_with(branch, impacts=2))


def test_a_pattern_is_p_letters_of_the_stops_there_are() -> None:
    assert at.check_pattern_attribute("UU", 2) == "UU"
    assert at.check_pattern_attribute("UL", 2, two_sided=True) == "UL"
    assert at.check_pattern_attribute("UXU", 3, two_sided=True, extra="X") == "UXU"
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 2 letters \(one per "
                                         r"impact\) from 'U' \(upper stop\): the oscillator "
                                         r"has no lower stop; got 'UL'"):
        at.check_pattern_attribute("UL", 2, two_sided=False)
    with pytest.raises(ValueError, match=r"must be 3 letters .*'U' \(upper stop\) and 'L' "
                                         r"\(lower stop\); got 'UL'"):
        at.check_pattern_attribute("UL", 3, two_sided=True)
    with pytest.raises(ValueError, match=r"attribute 'impact_stops' must be 1 letter "
                                         r"\(one per impact\).*got 'XX'"):
        at.check_pattern_attribute("XX", 1, name="impact_stops")
    with pytest.raises(ValueError, match=r"got \['U'\]"):
        at.check_pattern_attribute(["U"], 1)


def test_a_two_sided_branch_must_say_which_stop_each_impact_hit(branch) -> None:
    osc = at.oscillator_attribute(branch).replace(b=0.5, stops=Stops(mirror=True))
    ds = _with(branch, oscillator=osc.to_json())
    with pytest.raises(ValueError, match=r"attribute 'pattern' is missing: the oscillator has "
                                         r"a lower stop"):
        at.check_attributes(ds, "branch")
    with pytest.raises(ValueError, match=r"'pattern' = 'L' contradicts the states stored "
                                         r"\(variable 'state'\): right after impact 0 the "
                                         r"motion is at x1 = \S+, not on the stop 'L' \(x1 = "
                                         r"-0.5\) \(point 0\); the states say '\?'; "
                                         r"allowed: none"):
        at.check_attributes(_with(ds, pattern="L"), "branch")  # x1 = 0: on neither stop
    state = ds["state"].values.copy()
    state[:, 0] = -0.5  # x1 = -b_low: on the lower stop
    on_lower = ds.assign(state=(ds["state"].dims, state, ds["state"].attrs))
    at.check_attributes(_with(on_lower, pattern="L"), "branch")  # the lower stop: allowed now
    with pytest.raises(ValueError, match=r"'pattern' = 'U' contradicts.*the states say 'L'"):
        at.check_attributes(_with(on_lower, pattern="U"), "branch")


# -- parameters ------------------------------------------------------------------------------
@pytest.mark.parametrize(("text", "names"), [
    ("omega,b", ["omega", "b"]),
    ("omega,M[1,2]", ["omega", "M[1,2]"]),
    ("K[1,2],F[2]", ["K[1,2]", "F[2]"]),
    ("omega", ["omega"]),
])
def test_split_parameters_keeps_the_commas_inside_an_element_name(text, names) -> None:
    assert at.split_parameters(text) == names


def test_the_continued_parameter_must_be_one_with_its_column(branch) -> None:
    at.check_attributes(branch, "branch")  # as written: right
    with pytest.raises(ValueError, match=r"attribute 'parameter' must be one of \[.*'omega'"
                                         r".*\(1-based, e.g. 'k2', 'M\[1,2\]', 'F\[2\]'\); "
                                         r"got 'speed'"):
        at.check_attributes(_with(branch, parameter="speed"), "branch")
    with pytest.raises(ValueError, match=r"attribute 'parameter' = 'R' names no variable of "
                                         r"the dataset; allowed: .*\['omega', 'b'\]"):
        at.check_attributes(_with(branch, parameter="R"), "branch")


def test_the_period_of_the_motions_stored_fixes_N(two) -> None:
    """The flight times of an N-p motion sum to 2 pi N / omega: a wrong N is named with the
    N the stored motions give."""
    at.check_attributes(two, "branch")
    assert two.attrs["N"] == 2
    np.testing.assert_allclose(two["flight_time_k"].sum("impact") * two["omega"] / (2 * np.pi),
                               2.0, rtol=1e-10)
    with pytest.raises(ValueError, match=r"attribute 'N' = 3 does not match the motions "
                                         r"stored: .* gives N = \[2\]; allowed: 2"):
        at.check_attributes(_with(two, N=3), "branch")
    with pytest.raises(ValueError, match=r"attribute 'N' must be an integer >= 1 \(forcing "
                                         r"periods per impact\); got 2.0"):
        at.check_attributes(_with(two, N=2.0), "branch")


@pytest.mark.parametrize(("attrs", "match"), [
    ({"options": "[1]"}, r"attribute 'options' must be a JSON object \(text\); got '\[1\]'"),
    ({"options": "{"}, r"attribute 'options' must be a JSON object.*which is not JSON"),
    ({"title": 3}, r"attribute 'title' must be a text; got 3"),
    ({"history": b"x"}, r"attribute 'history' must be a text; got b'x'"),
])
def test_options_and_texts_are_checked(branch, attrs, match) -> None:
    with pytest.raises(ValueError, match=match):
        at.check_attributes(_with(branch, **attrs), "branch")


def test_a_curve_kind_and_its_two_parameters_are_checked(branch) -> None:
    curve = _with(branch, impactcont_dataset="curve", kind="PD", parameters="omega,b")
    del curve.attrs["parameter"]
    at.check_attributes(curve, "curve")
    with pytest.raises(ValueError, match=r"attribute 'kind' must be one of \['SN', 'PD', 'NS', "
                                         r"'GR', 'ZV'\] \(the kind of curve\); got 'XY'"):
        at.check_attributes(_with(curve, kind="XY"), "curve")
    with pytest.raises(ValueError, match=r"attribute 'parameters' must be two different names "
                                         r".*; got 'omega,omega'"):
        at.check_attributes(_with(curve, parameters="omega,omega"), "curve")
    with pytest.raises(ValueError, match=r"attribute 'parameters' = 'omega,R' names \['R'\], "
                                         r"which the dataset has no variable of"):
        at.check_attributes(_with(curve, parameters="omega,R"), "curve")


# -- kinds, sections, file roots -------------------------------------------------------------
def test_the_kind_of_a_dataset_is_its_tag_or_a_branch(branch) -> None:
    assert at.dataset_tag(branch) is None
    assert at.dataset_kind(branch) == "branch"
    assert at.dataset_kind(_with(branch, impactcont_dataset="curve")) == "curve"
    assert at.dataset_kind(_with(branch, impactcont_dataset="plugin thing")) is None
    assert at.dataset_kind(xr.Dataset()) is None
    with pytest.raises(ValueError, match=r"attribute 'impactcont_dataset' must be a text "
                                         r"naming the layout.*; got 5"):
        at.dataset_tag(_with(branch, impactcont_dataset=5))


def test_in_a_scene_file_the_kind_is_the_sections(branch) -> None:
    assert at.dataset_kind(branch, "branches") == "branch"
    assert at.dataset_kind(_with(branch, impactcont_dataset="map"), "maps") == "map"
    with pytest.raises(ValueError, match=r"attribute 'impactcont_dataset' must be absent \(a "
                                         r"branch\) in a file of section 'switches'; got 'map'"):
        at.dataset_kind(_with(branch, impactcont_dataset="map"), "switches")
    with pytest.raises(ValueError, match=r"attribute 'impactcont_dataset' must be 'curve' or "
                                         r"'branch' in a file of section 'curves'; got None"):
        at.dataset_kind(branch, "curves")
    # a curve followed by shooting is an N-p branch dataset with its curve_kind
    assert at.dataset_kind(_with(branch, curve_kind="PD"), "curves") == "branch"


def test_a_dataset_of_a_scene_section_carries_what_its_description_reads(branch) -> None:
    ds = branch.copy()
    del ds.attrs["N"]
    at.check_attributes(ds, "branch")  # a dataset of save(): its schema says what it needs
    with pytest.raises(ValueError, match=r"attribute\(s\) \['N'\] missing: a branch dataset of "
                                         r"a scene file carries \['oscillator', 'N', "
                                         r"'parameter'\]"):
        at.check_attributes(ds, "branch", in_section=True)


@pytest.mark.parametrize(("attrs", "match"), [
    ({"impactcont_kind": 3}, r"attribute 'impactcont_kind' must be the name of a scene "
                             r"section \(text\); got 3"),
    ({"impactcont_kind": ""}, r"attribute 'impactcont_kind' must be the name"),
    ({"scene_file": 1.5}, r"attribute 'scene_file' must be a text \(the scene file's path\); "
                          r"got 1.5"),
    ({"scene": "[]"}, r"attribute 'scene' must be the resolved scene as a JSON object"),
    ({"title": ["a"]}, r"attribute 'title' must be a text; got \['a'\]"),
])
def test_the_root_of_a_scene_file_is_checked(attrs, match) -> None:
    at.check_file_attributes({"impactcont_kind": "branches", "scene": '{"a": 1}',
                              "scene_file": "s.toml"})
    at.check_file_attributes({})
    with pytest.raises(ValueError, match=match):
        at.check_file_attributes(attrs)


def test_save_refuses_and_load_refuses_what_the_check_refuses(two, tmp_path) -> None:
    path = ic.save(two, tmp_path / "two.nc")
    with pytest.raises(ValueError, match=r"attribute 'N' = 5 does not match"):
        ic.save(_with(two, N=5), tmp_path / "wrong.nc")
    assert not (tmp_path / "wrong.nc").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["two.nc"]  # no half file
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        nc.setncattr("pattern", "UX")
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 2 letters.*got 'UX'"):
        ic.load(path)


# -- robust datasets -------------------------------------------------------------------------
def test_old_robust_attributes_count_the_forcing_from_one() -> None:
    old = {"vary": json.dumps({"F[0]": [0.5, 1.5], "b": [0.1, 0.2]}),
           "nominal": json.dumps({"F[0]": 1.0, "b": 0.15}),
           "argmax": json.dumps({"x": {"F[1]": 2.0}}), "N": 1}
    new = at.upgrade_robust_attributes(old)
    assert json.loads(new["vary"]) == {"F[1]": [0.5, 1.5], "b": [0.1, 0.2]}
    assert json.loads(new["nominal"]) == {"F[1]": 1.0, "b": 0.15}
    assert json.loads(new["argmax"]) == {"x": {"F[2]": 2.0}}
    assert new[at.ROBUST_INDEXING_ATTRIBUTE] == at.ROBUST_INDEXING == "1-based"
    assert "element_indexing" not in old  # the input is left as it was
    assert at.upgrade_robust_attributes(new) == new  # already 1-based: as it is
    plain = {"vary": json.dumps({"b": [0.1, 0.2]})}
    assert at.upgrade_robust_attributes(plain) == plain  # no F[i]: same in both conventions
    with pytest.raises(ValueError, match=r"attribute 'element_indexing' must be '1-based'.*; "
                                         r"got '0-based'"):
        at.upgrade_robust_attributes({"element_indexing": "0-based"})
