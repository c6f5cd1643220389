"""Scenes: validation messages, overrides, the resolved scene, and a run that writes files."""

from __future__ import annotations

import dataclasses
import json
import re
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from _scene_data import ORBITS_SCENE, OSCILLATOR, SMALL_SCENE, write

import impactcont as ic
from impactcont.scene import (
    SceneError,
    SceneSection,
    apply_settings,
    load_scene,
    parse_scene,
    read_output,
    register_section,
    run_scene,
    scene_sections,
)
from impactcont.scene.keys import Integer, declare
from impactcont.scene.plugins import list_problems, register_problem, unregister_problem
from impactcont.scene.schema import EntrySpec, scene_keys

ROOT = Path(__file__).resolve().parents[1]


def scene_error(tmp_path: Path, text: str, settings: tuple[str, ...] = ()) -> SceneError:
    path = write(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path, settings=settings)
    return info.value


# ---------------------------------------------------------------------------------------------
# The scenes of the studies (every study has one: tests/test_study_scenes.py)
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
    assert err.key == "plots[0].data[0]" and err.allowed == "a"
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


# ---------------------------------------------------------------------------------------------
# The resolved scene
# ---------------------------------------------------------------------------------------------
def test_resolved_scene_round_trips(tmp_path: Path) -> None:
    scene = load_scene(write(tmp_path, SMALL_SCENE))
    resolved = scene.to_dict()
    assert resolved["branches"][0]["detect"] == ["SN", "PD", "NS", "GR", "ZV", "BP"]  # default
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


# ---------------------------------------------------------------------------------------------
# Running a scene
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small_run(tmp_path_factory: pytest.TempPathFactory):
    directory = tmp_path_factory.mktemp("scene")
    return run_scene(write(directory, SMALL_SCENE), output=directory / "out")


def test_run_writes_every_requested_file(small_run) -> None:
    names = {p.name for p in small_run.files}
    assert small_run.ok, small_run.failures
    assert names == {"orbits.nc", "branches.nc", "robust.nc", "simulations.nc", "bif.png",
                     "mult.png", "orb.png", "rob.png", "simp.png", "summary.md"}
    assert all(p.is_file() and p.stat().st_size > 0 for p in small_run.files)
    assert not list(small_run.output_dir.glob(".*tmp*"))  # atomic writes left nothing behind


def test_every_netcdf_holds_the_resolved_scene(small_run) -> None:
    for path in small_run.output_dir.glob("*.nc"):
        out = read_output(path)
        assert out.kind == path.stem
        assert json.loads(out.attrs["scene"]) == small_run.scene.to_dict()
        assert set(out.datasets) == {e.name for e in small_run.scene.entries(out.kind)}


def test_branches_file_is_a_library_branch_file(small_run) -> None:
    tree = ic.load(small_run.output_dir / "branches.nc")
    ds = tree["br"].to_dataset()
    assert ds.attrs["parameter"] == "omega"
    labels = set(np.asarray(ds["special_label"].values).tolist())
    assert {"NS", "ZV", "SN"} <= labels
    omega = np.asarray(ds["omega"].values)
    assert omega.min() >= 1.1 - 1e-12 and omega.max() <= 1.3 + 1e-12


def test_orbits_match_the_library(small_run) -> None:
    ds = read_output(small_run.output_dir / "orbits.nc").datasets["o1"]
    orbits = ic.periodic_orbits(small_run.scene.osc, 1)
    assert ds.sizes["orbit"] == len(orbits) == 2
    np.testing.assert_allclose(ds["delta"].values, [o.delta for o in orbits], rtol=0,
                               atol=1e-14)
    np.testing.assert_allclose(ds["G"].values[1], orbits[1].G, rtol=0, atol=1e-14)
    assert ds["multipliers"].dtype.kind == "c"
    assert abs(float(ds["amplitude_squared"]) - 1.7435511) < 1e-6  # the paper's 1.74355
    assert float(ds["omega"]) == 1.0 and float(ds["b"]) == 0.6  # variables, not only JSON


def test_robust_and_simulation_files(small_run) -> None:
    rob = read_output(small_run.output_dir / "robust.nc").datasets["rb"]
    assert bool(rob["robust"]) and float(rob["epsilon"]) < float(rob["epsilon0"])
    assert float(np.max(rob["Gamma"].values)) == pytest.approx(1.0, abs=1e-15)
    sim = read_output(small_run.output_dir / "simulations.nc").datasets["sim"]
    # 3.5 periods from the motion's impact: 3 impacts (at a whole number of periods the last
    # impact would fall on the horizon, counted or not by rounding)
    assert sim.sizes["impact"] == 3 and "X" in sim  # trajectory asked for
    # started on the stable periodic motion: every impact velocity is the same
    np.testing.assert_allclose(sim["impact_velocities"].values,
                               sim["impact_velocities"].values[0], rtol=1e-9)


def test_summary_lists_the_special_points(small_run) -> None:
    text = (small_run.output_dir / "summary.md").read_text(encoding="utf-8")
    assert text.startswith("# small")
    assert "## Special points" in text
    for label in ("NS", "ZV", "SN"):
        assert re.search(rf"\| br \| 1 \| {label} \| omega = 1\.21", text)
    assert "## Robust stability" in text and "## Files" in text
    branch = small_run.datasets["branches"]["br"]
    assert len(small_run.special_points) == branch.sizes["special"] >= 3
    rows = re.findall(r"\| br \| 1 \| (?:SN|PD|NS|GR|ZV) \|", text)
    assert len(rows) == branch.sizes["special"]  # one row each


def test_scene_stores_only_what_it_asks_for(tmp_path: Path) -> None:
    text = OSCILLATOR + '[output]\nsummary = false\n[[orbits]]\nname = "fig3"\nN = 2\nb = 0.0\n' \
        'omega = 2.4\n'
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["orbits.nc"]
    ds = read_output(tmp_path / "o" / "orbits.nc").datasets["fig3"]
    assert int(ds.attrs["N"]) == 2
    assert bool(ds["physical"].values[1]) and bool(ds["stable"].values[1])


def test_simulation_without_trajectory_stores_no_time_history(tmp_path: Path) -> None:
    text = OSCILLATOR + '[[simulations]]\nname = "s"\nperiods = 2.5\n'  # 2 impacts, not on the end
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    ds = result.datasets["simulations"]["s"]
    assert "X" not in ds and "t" not in ds and ds.sizes["impact"] == 2


def test_a_failing_entry_does_not_stop_the_others(tmp_path: Path) -> None:
    text = ORBITS_SCENE + ('[[simulations]]\nname = "nowhere"\nb = 100.0\nperiods = 2\n'
                           '[[plots]]\nname = "p"\nkind = "simulation"\n')
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert not result.ok
    assert [(f.section, f.name) for f in result.failures] == [("simulations", "nowhere"),
                                                              ("plots", "p")]
    assert "NoPeriodicMotionError" in result.failures[0].error
    assert (tmp_path / "o" / "orbits.nc").is_file()
    assert not (tmp_path / "o" / "simulations.nc").exists()
    summary = (tmp_path / "o" / "summary.md").read_text(encoding="utf-8")
    assert "## Failures" in summary and "`nowhere`" in summary
    with pytest.raises(ic.NoPeriodicMotionError):
        run_scene(write(tmp_path, text), output=tmp_path / "o2", fail_fast=True)


# ---------------------------------------------------------------------------------------------
# The section registry: a new section plugs in without touching the parser or the runner
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, kw_only=True)
class _CountSpec(EntrySpec):
    section = "counts"
    upto: int = declare(Integer(1, 10), "how far to count", required=True)


class _CountHandler:
    def compute(self, entry: _CountSpec, context: object) -> xr.Dataset:
        return xr.Dataset({"k": ("k", np.arange(entry.upto))}, attrs={"name": entry.name})

    def describe(self, datasets):
        return [f"- {name}: {ds.sizes['k']}" for name, ds in datasets.items()]

    def special_points(self, datasets):
        return []


COUNT_HANDLER = _CountHandler()


@pytest.fixture
def counts_section() -> Iterator[SceneSection]:
    section = SceneSection("counts", _CountSpec, f"{__name__}:COUNT_HANDLER.compute", "Counts",
                           describe=COUNT_HANDLER.describe)
    register_section(section)
    yield section
    unregister_problem("counts")


def test_registered_section_is_validated_and_run(tmp_path: Path,
                                                 counts_section: SceneSection) -> None:
    with pytest.raises(ValueError, match="already registered"):
        register_section(SceneSection("counts", _CountSpec, "x:y", "Counts"))
    with pytest.raises(ValueError, match=r"\[\[branches\]\] is already brought by problem "
                                         r"'branches'"):
        register_problem("other", SceneSection("branches", _CountSpec, "x:y", "Other"))
    for key in ("plots", "Bad-key"):
        with pytest.raises(ValueError, match=f"section key '{key}' is"):
            register_problem("other", SceneSection(key, _CountSpec, "x:y", "Other"))
    assert list_problems()["counts"].origin == "registered"
    err = scene_error(tmp_path, OSCILLATOR + "[[counts]]\nupto = 11\n")
    assert err.key == "counts[0].upto" and err.allowed == "an integer in [1, 10]"
    result = run_scene(write(tmp_path, OSCILLATOR + "[[counts]]\nupto = 3\n"),
                       output=tmp_path / "o")
    out = read_output(tmp_path / "o" / "counts.nc")
    assert out.kind == "counts" and out.datasets["counts1"].sizes["k"] == 3
    assert "## Counts" in (tmp_path / "o" / "summary.md").read_text(encoding="utf-8")
    assert result.ok


# -- malformed systems (issue 13) ---------------------------------------------------------------
PAPER = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "b": 0.6,
         "omega": 1.0, "eta": 0.1}


@pytest.mark.parametrize(("name", "value"), [
    ("K", [[1 + 1j, -1.0], [-1.0, 2.0]]),
    ("K", np.array([[1.0, -1.0], [-1.0, 2.0]], dtype=complex)),  # even with zero imaginary parts
    ("M", np.eye(2) * (1 + 0.5j)),
])  # a complex F is accepted: per-mass forcing phases (tests/test_forcing_phase.py)
def test_complex_system_matrices_are_refused(name: str, value: object) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not merely a ComplexWarning
        with pytest.raises(TypeError, match=rf"^{name} must be a real .* with real entries; got "
                                            rf"complex values"):
            ic.ImpactOscillator(**{**PAPER, name: value})


def test_zero_forcing_is_refused(tmp_path: Path) -> None:
    match = r"F must have a nonzero entry: .* F = 0 gives no motion at all; got F = \[0.0, 0.0\]"
    with pytest.raises(ic.ParameterError, match=match):
        ic.ImpactOscillator(**{**PAPER, "F": [0, 0]})
    with pytest.raises(ic.ParameterError, match=match):
        ic.ImpactOscillator(**PAPER).replace(F=np.zeros(2))
    err = scene_error(tmp_path, ORBITS_SCENE.replace("F = [1.0, 0.0]", "F = [0.0, 0.0]"))
    assert err.key == "oscillator.F" and "nonzero entry" in str(err)


def test_a_gap_out_of_reach_says_why(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    text = (OSCILLATOR + '[[orbits]]\nname = "far"\nb = 100.0\n'
            '[[orbits]]\nname = "stable_only"\nwhich = "stable"\nN = 3\nb = 0.0\nomega = 2.6\n'
            '[[branches]]\nname = "br"\nb = 100.0\nbounds = [0.5, 3.0]\n'
            '[[plots]]\nname = "orb"\nkind = "orbits"\ndata = ["far"]\n')
    with caplog.at_level("WARNING", logger="impactcont"):
        result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    far = ("no motion: c^2 + s^2 = 1.74355 < b^2 = 10000 (eq. 15), the stop at b = 100 is out "
           "of reach of the forced motion; N-1 motions exist here only for b between -1.32044 "
           "and 1.32044")
    assert result.datasets["orbits"]["far"].attrs["note"] == far
    assert f"orbits far: {far}" in caplog.text
    stable = result.datasets["orbits"]["stable_only"].attrs["note"]
    assert stable.startswith("no motion kept (which = stable): none of the 2 roots is physical "
                             "and stable (root +1: not physical, unstable (rho(G) = 6.782)")
    (failure,) = result.failures
    assert failure.name == "br" and "NoPeriodicMotionError" in failure.error
    assert re.search(r"closest at omega = 0\.61\d+, where c\^2 \+ s\^2 = 237\.\d+ against "
                     r"b\^2 = 10000 \(eq\. 15\): the stop is out of reach", failure.error)
    summary = (tmp_path / "o" / "summary.md").read_text(encoding="utf-8")
    assert far in summary and "closest at omega = 0.61" in summary
    assert "no motion kept (which = all)" not in summary


# -- BLAS threads (issue 13) --------------------------------------------------------------------
def test_blas_threads_are_limited_inside_the_library_and_restored(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from threadpoolctl import threadpool_info, threadpool_limits

    from impactcont.threads import blas_limited, limit_blas_threads

    def blas_threads() -> set[int]:
        return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}

    with threadpool_limits(limits=2, user_api="blas"):
        if blas_threads() != {2}:
            pytest.skip("the BLAS here does not run 2 threads, so no limit can be seen")
        seen = []
        work = blas_limited(lambda: seen.append(blas_threads()) or 42)
        assert work() == 42 and seen == [{1}]
        with limit_blas_threads():
            with limit_blas_threads():  # nested: one limit, lifted by the outermost only
                assert blas_threads() == {1}
            assert blas_threads() == {1}
        assert blas_threads() == {2}
        monkeypatch.setenv("IMPACTCONT_BLAS_THREADS", "none")
        with limit_blas_threads():
            assert blas_threads() == {2}
        monkeypatch.setenv("IMPACTCONT_BLAS_THREADS", "lots")
        with pytest.raises(ValueError, match="IMPACTCONT_BLAS_THREADS must be a positive "
                                             "integer or 'none'; got 'lots'"):
            limit_blas_threads().__enter__()
        assert blas_threads() == {2}


def test_a_scene_runs_with_one_blas_thread(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                           ) -> None:
    from threadpoolctl import threadpool_info, threadpool_limits

    from impactcont.scene import tasks

    seen = []
    compute = tasks.Orbits.compute

    def spy(self, entry, context=None):
        seen.append({lib["num_threads"] for lib in threadpool_info()
                     if lib["user_api"] == "blas"})
        return compute(self, entry, context)

    monkeypatch.setattr(tasks.Orbits, "compute", spy)
    with threadpool_limits(limits=2, user_api="blas"):
        run_scene(write(tmp_path, ORBITS_SCENE), output=tmp_path / "o")
    assert seen == [{1}, {1}]


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


def test_a_robust_scene_file_keeps_its_1_based_forcing_entry(tmp_path: Path) -> None:
    # F[1] is mass 1's forcing (1-based, as every element name): the file says so
    # (element_indexing), so reading it back does not take it for an old 0-based file
    text = OSCILLATOR + ('[output]\nsummary = false\n[[robust]]\nname = "rb"\n'
                         'vary = { "F[1]" = [0.9, 1.1] }\nsamples = 3\n')
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok
    ds = read_output(tmp_path / "o" / "robust.nc").datasets["rb"]
    assert list(json.loads(ds.attrs["vary"])) == ["F[1]"]
    assert ds.attrs["element_indexing"] == "1-based"
