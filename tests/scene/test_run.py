"""Running a scene (:mod:`impactcont.scene.run`): a run writes the files it asks for, each
holding the resolved scene and what the library computes; a failing entry does not stop
the others; a registered section is validated and run."""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.scene import (
    SceneError,
    SceneSection,
    load_scene,
    read_output,
    register_section,
    run_scene,
)
from impactcont.scene.keys import Integer, declare
from impactcont.scene.plugins import list_problems, register_problem, unregister_problem
from impactcont.scene.schema import EntrySpec
from tests._scene_data import ORBITS_SCENE, OSCILLATOR, SMALL_SCENE, write


def scene_error(tmp_path: Path, text: str, settings: tuple[str, ...] = ()) -> SceneError:
    path = write(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path, settings=settings)
    return info.value


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


# -- one run per output folder (issue 28) -----------------------------------------------------
_HOLD = """
import sys
import impactcont.scene.run as run
write = run.write_output

def held(*args, **kwargs):
    print("running", flush=True)
    sys.stdin.readline()  # until the test lets it go on
    return write(*args, **kwargs)

run.write_output = held
print(run.run_scene(sys.argv[1], output=sys.argv[2]).ok, flush=True)
"""


def test_two_runs_into_one_folder_do_not_mix(tmp_path: Path) -> None:
    import subprocess
    import sys

    from impactcont.scene.files import LOCK_FILE, OutputInUseError

    scene, out = write(tmp_path, ORBITS_SCENE), tmp_path / "o"
    other = subprocess.Popen([sys.executable, "-c", _HOLD, str(scene), str(out)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                             cwd=Path(__file__).resolve().parents[2])
    try:
        assert other.stdout.readline() == "running\n"  # it holds the folder, mid-run
        with pytest.raises(OutputInUseError) as info:
            run_scene(scene, output=out)
        text = str(info.value)
        assert str(out) in text and f"pid {other.pid}" in text, text
        assert not (out / "summary.md").exists()  # the refused run wrote nothing
        other.stdin.write("\n")
        other.stdin.flush()
        assert other.stdout.readline() == "True\n"
        assert other.wait(timeout=60) == 0
    finally:
        other.kill()
        other.wait()
    # released at exit: the folder is free again, and no lock file is left in it
    assert run_scene(scene, output=out).ok
    assert sorted(p.name for p in out.iterdir()) == ["orbits.nc", "summary.md"]
    assert LOCK_FILE.startswith(".")


def test_the_summary_names_in_words_the_kinds_beyond_the_five_it_always_names(small_run) -> None:
    """A branch's SE (the end of a sticking phase) is named in the summary's sentence on
    special points in its words (Label.words); a run without one reads as before."""
    from impactcont.scene.run import summary_markdown

    assert small_run.special_points
    row = {**small_run.special_points[0], "label": "SE"}
    text = summary_markdown(dataclasses.replace(
        small_run, special_points=[*small_run.special_points, row]))
    assert "ZV zero-velocity impact, SE end of a sticking phase; `located`" in text
    assert "ZV zero-velocity impact; `located`" in summary_markdown(small_run)
