"""Scenes (:mod:`impactcont.scene.schema`): validation messages, the resolved scene, and
the studies' scenes."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.scene import SceneError, load_scene, parse_scene, scene_sections
from impactcont.scene.schema import scene_keys
from tests._scene_data import ORBITS_SCENE, OSCILLATOR, SMALL_SCENE, write

ROOT = Path(__file__).resolve().parents[2]


def scene_error(tmp_path: Path, text: str, settings: tuple[str, ...] = ()) -> SceneError:
    path = write(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path, settings=settings)
    return info.value


# ---------------------------------------------------------------------------------------------
# The scenes of the studies (every study has one: tests/studies/test_study_scenes.py)
# ---------------------------------------------------------------------------------------------
def test_main_job_asks_for_the_readme_main_job() -> None:
    scene = load_scene(ROOT / "studies/main_job/scene.toml")
    branches = scene.entries("branches")
    assert sorted((e.N, e.oscillator.b) for e in branches) == [
        (N, b) for N in (1, 2, 3) for b in (0.0, 0.5)]
    assert all(e.bounds == (0.5, 6.0) and e.parameter == "omega" for e in branches)
    (robust,) = scene.entries("robust")
    assert robust.vary == {"b": (0.2, 1.0)} and robust.nominal == {"b": 0.6}
    orbits = {(e.N, e.oscillator.omega, e.oscillator.b) for e in scene.entries("orbits")}
    assert {(1, 1.0, 0.6), (1, 1.2, 0.0), (2, 2.4, 0.0), (3, 2.6, 0.0)} <= orbits
    assert {p.kind for p in scene.plots} >= {"bifurcation_diagram", "orbits", "robust"}


# ---------------------------------------------------------------------------------------------
# Malformed scenes: one test per kind of error; the message names the key and what is allowed
# ---------------------------------------------------------------------------------------------
def test_unknown_key_suggests_the_close_one(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[[branches]]\nbound = [1, 2]\n")
    text = str(err)
    assert err.key == "branches[0].bound"
    assert "did you mean 'bounds'?" in text
    assert "allowed:" in text and "bounds" in text and "detect" in text
    assert text.startswith(str(tmp_path / "scene.toml"))
    assert err.line == 10  # the `bound = ...` line


def test_unknown_top_level_key(tmp_path: Path) -> None:
    err = scene_error(tmp_path, 'titel = "x"\n' + OSCILLATOR)
    assert err.key == "titel" and "did you mean 'title'?" in str(err)
    assert "oscillator" in err.allowed and "branches" in err.allowed


def test_wrong_type(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + '[[orbits]]\nN = "two"\n')
    assert err.key == "orbits[0].N"
    assert "wrong type" in str(err) and '"two"' in str(err)
    assert err.allowed == "an integer in [1, 1000]"


def test_boolean_is_not_a_number(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR.replace("R = 0.6", "R = true"))
    assert err.key == "oscillator.R" and "a real number in [0, 1]" in str(err)


def test_out_of_range(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR.replace("R = 0.6", "R = 1.5"))
    assert err.key == "oscillator.R"
    assert "out of range" in str(err) and "1.5" in str(err)
    assert err.allowed == "a real number in [0, 1]"
    assert err.line == 5


def test_bad_interval(tmp_path: Path) -> None:
    text = OSCILLATOR + "[[branches]]\nbounds = [1, 2]\n[[branches]]\nbounds = [2, 1]\n"
    err = scene_error(tmp_path, text)
    assert err.key == "branches[1].bounds"
    assert "lo must be < hi" in str(err) and "a pair [lo, hi]" in str(err)
    assert err.line == 12


def test_bounds_outside_the_admissible_parameter_range(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + '[[branches]]\nparameter = "R"\nbounds = [0.5, 2]\n')
    assert err.key == "branches[0].bounds" and "a real number in [0, 1]" in str(err)


def test_unknown_choice(tmp_path: Path) -> None:
    text = OSCILLATOR + '[[branches]]\nparameter = "omegaa"\nbounds = [1, 2]\n'
    err = scene_error(tmp_path, text)
    assert err.key == "branches[0].parameter"
    assert 'did you mean "omega"?' in str(err)
    for name in ic.problems.CONTINUABLE_PARAMETERS:
        assert f'"{name}"' in err.allowed


def test_unknown_special_point_label(tmp_path: Path) -> None:
    text = OSCILLATOR + '[[branches]]\nbounds = [1, 2]\ndetect = ["SN", "HB"]\n'
    err = scene_error(tmp_path, text)
    assert err.key == "branches[0].detect[1]"
    assert all(label in err.allowed for label in ("SN", "PD", "NS", "GR", "ZV"))


def test_missing_required_key(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[[branches]]\nN = 1\n")
    assert err.key == "branches[0].bounds" and "required" in str(err)
    err = scene_error(tmp_path, '[[orbits]]\nN = 1\n')
    assert err.key == "oscillator" and "required" in str(err)


def test_single_table_instead_of_array(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[branches]\nbounds = [1, 2]\n")
    assert err.key == "branches" and "write [[branches]], not [branches]" in str(err)


def test_library_errors_are_mapped_to_the_key(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR.replace("[[1.0, -1.0], [-1.0, 2.0]]",
                                                   "[[1.0, 2.0], [2.0, 1.0]]"))
    assert err.key == "oscillator.K" and "positive semi-definite" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + "[[orbits]]\nF = [1.0]\n")
    assert err.key == "orbits[0].F" and "shape" in str(err)


def test_exclusive_keys(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "alpha = 0.1\n")
    assert err.key == "oscillator.alpha" and "either eta or alpha/beta" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + '[[branches]]\nparameter = "alpha"\nbounds = [0, 1]\n')
    assert err.key == "branches[0].parameter" and "Rayleigh" in str(err)


def test_cross_key_rules(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[[branches]]\nbounds = [1, 2]\nstart = 3\n")
    assert err.key == "branches[0].start" and "[1, 2]" in err.allowed
    err = scene_error(tmp_path, OSCILLATOR + "[[branches]]\nbounds = [1, 2]\nds = 0.5\n")
    assert err.key == "branches[0].ds" and "ds_min <= ds <= ds_max" in err.allowed
    err = scene_error(tmp_path, OSCILLATOR
                      + "[[robust]]\nvary = { b = [0.2, 1.0] }\nnominal = { b = 2 }\n")
    assert err.key == "robust[0].nominal.b" and "[0.2, 1]" in err.allowed
    err = scene_error(tmp_path, OSCILLATOR + '[[robust]]\nvary = { "F[3]" = [0, 1] }\n')
    assert err.key == "robust[0].vary" and "F[3]" in str(err) and "n=2" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + "[[robust]]\nvary = { gap = [0, 1] }\n")
    assert err.key.startswith("robust[0].vary") and "gap" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + '[[simulations]]\nperiods = 2\nstart = "state"\n')
    assert err.key == "simulations[0].state" and "required" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + "[[simulations]]\nperiods = 2\ndelta = 0.1\n")
    assert err.key == "simulations[0].delta" and "only used with" in str(err)


def test_duplicate_names(tmp_path: Path) -> None:
    text = OSCILLATOR + '[[orbits]]\nname = "a"\n[[branches]]\nname = "a"\nbounds = [1, 2]\n'
    err = scene_error(tmp_path, text)
    assert err.key == "branches[0].name" and "[[orbits]]" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + '[[orbits]]\nname = "1st"\n')
    assert err.key == "orbits[0].name" and "starts with a letter" in err.allowed


def test_plot_references(tmp_path: Path) -> None:
    base = OSCILLATOR + '[[branches]]\nname = "a"\nbounds = [1, 2]\n'
    err = scene_error(tmp_path, base + '[[plots]]\nkind = "bifurcation"\n')
    assert err.key == "plots[0].kind" and "did you mean 'bifurcation_diagram'?" in str(err)
    assert "multipliers" in err.allowed
    err = scene_error(tmp_path, base + '[[plots]]\nkind = "bifurcation_diagram"\ndata = ["b"]\n')
    assert err.key == "plots[0].data[0]" and err.allowed == "[[branches]]: a"
    err = scene_error(tmp_path, base + '[[plots]]\nkind = "orbits"\n')
    assert err.key == "plots[0].data" and "[[orbits]]" in str(err)
    two = base + '[[branches]]\nname = "c"\nbounds = [1, 2]\n'
    err = scene_error(tmp_path, two + '[[plots]]\nkind = "multipliers"\n')
    assert err.key == "plots[0].data" and "exactly one" in str(err)
    mixed = base + '[[branches]]\nname = "c"\nparameter = "b"\nbounds = [0, 1]\n'
    err = scene_error(tmp_path, mixed + '[[plots]]\nkind = "bifurcation_diagram"\n')
    assert "one parameter" in err.allowed


def test_toml_syntax_error_has_the_line(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[[orbits]]\nN = = 1\n[[orbits]]\n")
    assert err.line == 10 and "not valid TOML" in str(err)
    err = scene_error(tmp_path, OSCILLATOR + "[[orbits]]\nN = [1\n")
    assert err.line == 10
    assert re.match(rf"^{re.escape(str(tmp_path / 'scene.toml'))}:\d+: ", str(err))


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene(tmp_path / "nope.toml")


# ---------------------------------------------------------------------------------------------
# The resolved scene
# ---------------------------------------------------------------------------------------------
def test_resolved_scene_round_trips(tmp_path: Path) -> None:
    scene = load_scene(write(tmp_path, SMALL_SCENE))
    resolved = scene.to_dict()
    assert resolved["branches"][0]["detect"] == ["SN", "PD", "NS", "GR", "ZV", "BP", "SE", "RG",
                                                 "SO", "FT"]  # default: every kind
    assert resolved["branches"][0]["ds"] == 0.02
    again = parse_scene(json.loads(scene.to_json()))
    assert again.to_dict() == resolved


def test_chain_and_matrix_forms_agree(tmp_path: Path) -> None:
    chain = OSCILLATOR.replace("K = [[1.0, -1.0], [-1.0, 2.0]]",
                               "masses = [1.0, 1.0]\nsprings = [1.0, 1.0]")
    a = load_scene(write(tmp_path, chain, "a.toml")).osc
    b = load_scene(write(tmp_path, OSCILLATOR, "b.toml")).osc
    np.testing.assert_allclose(a.K, b.K, atol=0)
    np.testing.assert_allclose(a.M, b.M, atol=0)


def test_every_scene_key_is_documented() -> None:
    doc = (ROOT / "docs" / "scenes.md").read_text(encoding="utf-8")
    from impactcont.scene.schema import OscillatorSpec, OutputSpec, PlotSpec

    classes = [OscillatorSpec, OutputSpec, PlotSpec,
               *(s.entry for s in scene_sections().values())]
    missing = [f"{cls.__name__}.{key}" for cls in classes for key in scene_keys(cls)
               if f"`{key}`" not in doc]
    assert not missing


# -- malformed systems (issue 13) ---------------------------------------------------------------
PAPER = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "b": 0.6,
         "omega": 1.0, "eta": 0.1}


@pytest.mark.parametrize(("name", "value"), [
    ("K", [[1 + 1j, -1.0], [-1.0, 2.0]]),
    ("K", np.array([[1.0, -1.0], [-1.0, 2.0]], dtype=complex)),  # even with zero imaginary parts
    ("M", np.eye(2) * (1 + 0.5j)),
])  # a complex F is accepted: per-mass forcing phases (tests/model/test_modal.py)
def test_complex_system_matrices_are_refused(name: str, value: object) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not merely a ComplexWarning
        with pytest.raises(TypeError, match=rf"^{name} must be a real .* with real entries; got "
                                            rf"complex values"):
            ic.ImpactOscillator(**{**PAPER, name: value})


def test_zero_forcing_is_refused_by_periodic_entries(tmp_path: Path) -> None:
    """F = 0 is a machine (simulated from a state, issue 28); periodic motions need F != 0."""
    assert not np.any(ic.ImpactOscillator(**{**PAPER, "F": [0, 0]}).F)
    err = scene_error(tmp_path, ORBITS_SCENE.replace("F = [1.0, 0.0]", "F = [0.0, 0.0]"))
    assert err.key == "orbits[0]" and "F = [0.0, 0.0] (no harmonic forcing)" in str(err)
    assert "stop_mass" not in str(err)  # not the closed form's stop layout: the forcing


def test_machines_of_issue_21_in_a_scene(tmp_path: Path) -> None:
    # an impact damper: a free ball (mass 1: its chain spring k1 = 0) in the cavity of a
    # primary mass on a spring (mass 2), stops on x1 - x2, under a constant force
    table = ('[oscillator]\nmasses = [0.2, 1.0]\nsprings = [0.0, 1.0]\nF = [0.0, 1.0]\n'
             'R = 0.6\nb = 0.5\nomega = 1.1\neta = 0.02\nstop_mass = 1\n'
             'stop_relative_to = 2\nmirror_stop = true\nF_static = [-0.1, 0.0]\n')
    path = tmp_path / "scene.toml"
    path.write_text(table + '[[simulations]]\nstart = "state"\nstate = [0.0, 0.0, 0.0, 0.0]\n'
                    'delta = 0.0\nperiods = 2\n', encoding="utf-8")
    osc = load_scene(path).oscillator.build()
    assert osc.stops.relative_to == 2 and osc.stops.mass == 1 and osc.stops.mirror
    assert osc.F_static.tolist() == [-0.1, 0.0]
    assert osc.free_modes.shape == (2, 1)
    err = scene_error(tmp_path, table.replace("stop_relative_to = 2", "stop_relative_to = 1"))
    assert err.key == "oscillator.stop_relative_to" and "itself" in str(err)
    err = scene_error(tmp_path, table.replace("springs = [0.0, 1.0]", "springs = [-1.0, 1.0]"))
    assert err.key == "oscillator.springs" and ">= 0" in str(err)
