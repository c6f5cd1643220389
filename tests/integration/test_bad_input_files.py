"""Files nothing is silently wrong about (issue 19): tampered attributes refused by load and
by ``impactcont info``/``plot``, files of ``save(validate=False)``, and a save killed with
``kill -9`` leaving no process nor temporary file behind."""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any

import netCDF4
import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.cli import EXIT_USAGE, main
from impactcont.dataset import branch_dataset, oscillator_from_dataset, validate_branch_dataset
from impactcont.dataset import io as dataset_io
from impactcont.dataset.curves import CURVE_VARIABLES, curve_dataset, validate_curve_dataset
from impactcont.dataset.maps import map_dataset
from impactcont.dataset.multi import impacts_of, multi_impact_dataset, pattern_of
from impactcont.model.stops import Stops
from impactcont.scene.files import write_output
from tests.dataset.test_io import _start_save, _temporaries
from tests.dataset.test_schema import _columns, _specials

OSC = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0, omega=1.0,
                          eta=0.1)
TWO_SIDED = OSC.replace(stops=Stops(b_low=0.5))


def _np_branch(osc: ic.ImpactOscillator = OSC, N: int = 2, p: int = 2,
               pattern: str | None = None) -> xr.Dataset:
    """A made-up but consistent N-p branch (flight times summing to 2 pi N / omega, each
    state on the stop of its letter of the pattern)."""
    cols = _columns(npoints=10)
    period = 2 * np.pi * N / cols["omega"]
    impacts = {"delta_k": np.zeros((10, p)), "impact_velocity_k": np.ones((10, p)),
               "flight_time_k": np.repeat(period[:, None] / p, p, axis=1),
               "gap_min_k": np.ones((10, p)), "state_k": np.zeros((10, p, 4))}
    special = {"delta_k": np.zeros((0, p)), "impact_velocity_k": np.zeros((0, p)),
               "flight_time_k": np.zeros((0, p)), "state_k": np.zeros((0, p, 4))}
    return _consistent(multi_impact_dataset(
        parameter="omega", N=N, p=p, oscillator=osc, options={}, columns=cols,
        impact_columns=impacts, special_points=[], special_impact_columns=special,
        pattern=pattern))


def _tamper(path: Path, group: str | None, **attrs: Any) -> None:
    """Set (None: delete) attributes of a group (None: the root) of a file in place."""
    with netCDF4.Dataset(path, "a") as nc:
        target = nc if group is None else nc.groups[group]
        for name, value in attrs.items():
            if value is None:
                target.delncattr(name)
            else:
                target.setncattr(name, value)


@pytest.fixture
def multi_file(tmp_path: Path) -> Path:
    """``multi_impact.nc`` of a scene run with one 2-2 branch, group ``m``."""
    return write_output(tmp_path / "multi_impact.nc", "multi_impact", {"m": _np_branch()},
                        title="N-p branches")


# -- item 6: a tampered file is refused, by load and by the command line -----------------------
def test_info_and_plot_refuse_a_pattern_of_letters_no_stop_has(multi_file: Path, tmp_path: Path,
                                                               capsys) -> None:
    _tamper(multi_file, "m", pattern="XX")
    png = tmp_path / "m.png"
    for argv in (["info", str(multi_file)], ["plot", str(multi_file), "-o", str(png)]):
        assert main(argv) == EXIT_USAGE
        out, err = capsys.readouterr()
        assert "XX" not in out
        assert (f"file {str(multi_file)!r}, group '/m': attribute 'pattern' must be 2 letters "
                "(one per impact) from 'U' (upper stop): the oscillator has no lower stop; "
                "got 'XX'") in err
    assert not png.exists()
    for validate in (True, False):
        with pytest.raises(ValueError, match=r"multi_impact\.nc', group '/m': attribute "
                                             r"'pattern' .* got 'XX'"):
            ic.load(multi_file, validate=validate)


_OSC_3 = ic.ImpactOscillator(M=np.eye(3), K=2 * np.eye(3), F=[1, 0, 0], R=0.6, b=0.0,
                             omega=1.0, eta=0.1).to_json()


@pytest.mark.parametrize(("group", "name", "value", "allowed"), [
    ("m", "pattern", "U", r"2 letters \(one per impact\) from 'U'.*got 'U'"),
    ("m", "pattern", "UL", r"no lower stop; got 'UL'"),
    ("m", "pattern", np.int64(5), r"2 letters .* got np.int64\(5\)"),
    ("m", "impacts", np.int64(3), r"'impacts' must equal .* 'impact' has size 2; got np.int64\(3"),
    ("m", "impacts", "2", r"'impacts' must be an integer >= 1 .* got '2'"),
    ("m", "N", np.int64(0), r"'N' must be an integer >= 1 .* got np.int64\(0\)"),
    ("m", "N", "two", r"'N' must be an integer >= 1 .* got 'two'"),
    ("m", "N", np.int64(3), r"'N' = 3 does not match .* gives N = \[2\]; allowed: 2"),
    ("m", "oscillator", "{bad json", r"'oscillator' must be the oscillator as JSON .* got "
                                     r"'\{bad json', which is not JSON"),
    ("m", "oscillator", "[1, 2]", r"'oscillator' must be .* a JSON object; got '\[1, 2\]'"),
    ("m", "oscillator", '{"M": [[1.0]]}', r"'oscillator' must be .* not a valid oscillator"),
    ("m", "oscillator", _OSC_3, r"'oscillator' has n=3 masses, but dimension 'component' has "
                                r"size 4"),
    ("m", "parameter", "mass", r"'parameter' must be one of \['omega', 'b', .* got 'mass'"),
    ("m", "parameter", "R", r"'parameter' = 'R' names no variable"),
    ("m", "parameter", None, r"\['parameter'\] missing"),
    ("m", "options", "{not json", r"'options' must be a JSON object .* not JSON"),
    ("m", "options", "[1]", r"'options' must be a JSON object \(text\); got '\[1\]'"),
    ("m", "impactcont_dataset", "orbits", r"'impactcont_dataset' must be absent \(a branch\) "
                                          r"in a file of section 'multi_impact'; got 'orbits'"),
    ("m", "title", np.array([1, 2]), r"'title' must be a text; got array"),
    (None, "scene", "{bad", r"root group: attribute 'scene' must be the resolved scene as a "
                            r"JSON object"),
    (None, "impactcont_kind", np.int64(3), r"'impactcont_kind' must be the name of a scene"),
])
def test_every_attribute_read_is_checked_on_load(multi_file: Path, group: str | None, name: str,
                                                 value: Any, allowed: str) -> None:
    _tamper(multi_file, group, **{name: value})
    where = "" if group is None else f"group '/{group}': "
    with pytest.raises(ValueError, match=rf"multi_impact\.nc', {where}.*{allowed}") as info:
        ic.load(multi_file, validate=False)
    assert name in str(info.value)
    assert not isinstance(info.value, json.JSONDecodeError)


def test_the_stops_of_a_two_sided_branch_are_checked(tmp_path: Path) -> None:
    path = write_output(tmp_path / "multi_impact.nc", "multi_impact",
                        {"m": _np_branch(TWO_SIDED, pattern="UL")}, title="t")
    assert pattern_of(ic.load(path)["m"].to_dataset()) == "UL"
    _tamper(path, "m", pattern="UX")
    with pytest.raises(ValueError, match=r"from 'U' \(upper stop\) and 'L' \(lower stop\); "
                                         r"got 'UX'"):
        ic.load(path)
    _tamper(path, "m", pattern=None)  # read as 'UU' it would be another motion
    with pytest.raises(ValueError, match=r"'pattern' is missing: the oscillator has a lower "
                                         r"stop"):
        ic.load(path)


def _section_file(tmp_path: Path, section: str, ds: xr.Dataset) -> Path:
    tree = xr.DataTree.from_dict({"/": xr.Dataset(attrs={"impactcont_kind": section}),
                                  "/x": ds})
    return ic.save(tree, tmp_path / f"{section}.nc", validate=False)


_ROBUST = {"impactcont_dataset": "robust", "N": 1, "vary": '{"b": [0.5, 0.7]}',
           "nominal": '{"b": 0.6}', "oscillator": OSC.to_json()}
_SIMULATION = {"impactcont_dataset": "simulation", "start": "state", "periods": 3.0,
               "status": "COMPLETED", "impact_stops": "UUU", "oscillator": OSC.to_json()}
_ORBITS = {"impactcont_dataset": "orbits", "N": 1, "oscillator": OSC.to_json()}
_CURVE = {"impactcont_dataset": "curve", "kind": "SN", "N": 1, "parameters": "omega,b",
          "oscillator": OSC.to_json()}


@pytest.mark.parametrize(("section", "attrs", "name", "value", "allowed"), [
    ("robust", _ROBUST, "vary", "{}", r"'vary' must be a JSON object of parameter name to "
                                      r"\[low, high\].* \(no parameter varies\)"),
    ("robust", _ROBUST, "vary", '{"b": [0.7, 0.5]}', r"'vary' must be"),
    ("robust", _ROBUST, "nominal", '{"b": "x"}', r"'nominal' must be a JSON object of"),
    ("robust", _ROBUST, "vary", None, r"\['vary'\] missing: a robust dataset of a scene file "
                                      r"carries \['oscillator', 'N', 'vary', 'nominal'\]"),
    ("simulations", _SIMULATION, "periods", -1.0, r"'periods' must be a finite number > 0"),
    ("simulations", _SIMULATION, "impact_stops", "UU", r"'impact_stops' must be 3 letters"),
    ("simulations", _SIMULATION, "impact_stops", "ULU", r"no lower stop; got 'ULU'"),
    ("simulations", _SIMULATION, "status", np.int64(3), r"'status' must be a text"),
    ("orbits", _ORBITS, "N", np.int64(2), r"'N' = 2 does not match .* gives N = \[1\]"),
    ("orbits", _ORBITS, "note", np.array([1, 2]), r"'note' must be a text"),
    ("curves", _CURVE, "kind", "XY", r"'kind' must be one of \['SN', 'PD', 'NS', 'GR', 'ZV'\]"),
    ("curves", _CURVE, "parameters", "omega", r"'parameters' must be two different names"),
    ("curves", _CURVE, "parameters", "omega,R", r"'parameters' = 'omega,R' names \['R'\]"),
])
def test_the_attributes_of_every_section_are_checked(tmp_path: Path, section: str, attrs: dict,
                                                      name: str, value: Any,
                                                      allowed: str) -> None:
    ds = xr.Dataset({"omega": 1.0, "period": ("orbit", [2 * np.pi]),
                     "impact_times": ("impact", [1.0, 2.0, 3.0])}, attrs=attrs)
    if section == "curves":
        ds = xr.Dataset({"omega": ("point", [1.0]), "b": ("point", [0.5])}, attrs=attrs)
    path = _section_file(tmp_path, section, ds)
    assert set(ic.load(path, validate=False)["x"].attrs) == set(attrs)
    _tamper(path, "x", **{name: value})
    with pytest.raises(ValueError, match=rf"{section}\.nc', group '/x': .*{allowed}"):
        ic.load(path, validate=False)


def test_save_refuses_what_load_would_refuse(tmp_path: Path) -> None:
    ds = _np_branch().assign_attrs(pattern="XX")
    for validate in (True, False):
        with pytest.raises(ValueError, match=r"attribute 'pattern' must be 2 letters"):
            ic.save(ds, tmp_path / "x.nc", validate=validate)
    assert not (tmp_path / "x.nc").exists()


# -- item 8: files of save(validate=False), a corrupt oscillator -------------------------------
def test_a_map_without_eigenvalues_saves_and_loads_back(tmp_path: Path) -> None:
    """stability_map(..., spectral_radius=False) leaves two variables out: still a map."""
    shape = {"N": 1, "omega": 3, "b": 2, "root": 2}
    dims = {"amplitude_squared": ("N", "omega"), "exists": ("N", "omega", "b"),
            "n_physical": ("N", "omega", "b"), "n_stable": ("N", "omega", "b")}
    values = {k: np.zeros([shape[d] for d in dims.get(k, ("N", "omega", "b", "root"))],
                          dtype=bool if k in ("exists", "physical", "stable")
                          else int if k.startswith("n_") else float)
              for k in ("amplitude_squared", "exists", "n_physical", "n_stable", "delta",
                        "impact_velocity", "gap_min", "physical", "stable")}
    ds = map_dataset(oscillator=OSC, N=[1], omega=np.linspace(1, 2, 3), b=np.zeros(2),
                     values=values, options={})
    assert "spectral_radius" not in ds
    back = ic.load(ic.save(ds, tmp_path / "map.nc"))
    xr.testing.assert_identical(back, ds)


def test_a_file_saved_without_validation_loads_without_it(tmp_path: Path) -> None:
    ds = _np_branch().drop_vars("gap_min")
    path = ic.save(ds, tmp_path / "partial.nc", validate=False)
    xr.testing.assert_identical(ic.load(path, validate=False), ds)
    with pytest.raises(ValueError, match=r"partial\.nc': not a branch dataset: missing "
                                         r"variable\(s\) \['gap_min'\]. "
                                         r"impactcont\.load\(path, validate=False\) reads it"):
        ic.load(path)


def test_the_branches_of_every_branch_section_follow_the_schema(multi_file: Path) -> None:
    """The N-p layout is checked in multi_impact.nc and switches.nc too (it was not at all)."""
    tree = ic.load(multi_file).to_dict()
    tree["/m"] = tree["/m"].drop_vars("flight_time_k")
    path = ic.save(xr.DataTree.from_dict(tree), multi_file.parent / "partial.nc",
                   validate=False)
    with pytest.raises(ValueError, match=r"group '/m': not a N-p branch dataset: missing "
                                         r"variable\(s\) \['flight_time_k'\]"):
        ic.load(path)
    assert "flight_time_k" not in ic.load(path, validate=False)["m"]


def test_a_corrupt_oscillator_is_named_not_a_json_traceback(tmp_path: Path) -> None:
    ds = _np_branch().assign_attrs(oscillator='{"M": [[1.0, 0.0], [0.0, 1.0]], "K": ')
    for call in (oscillator_from_dataset, validate_branch_dataset):
        with pytest.raises(ValueError, match=r"attribute 'oscillator' must be the oscillator as "
                                             r"JSON text .* which is not JSON") as info:
            call(ds)
        assert not isinstance(info.value, json.JSONDecodeError)
    path = ic.save(_np_branch(), tmp_path / "b.nc")
    _tamper(path, None, oscillator="{")
    with pytest.raises(ValueError, match=r"b\.nc': attribute 'oscillator' .* not JSON") as info:
        ic.load(path)
    assert not isinstance(info.value, json.JSONDecodeError)


# -- other bad input found in the loaders --------------------------------------------------------
def test_the_real_and_imaginary_parts_must_match(tmp_path: Path) -> None:
    path = ic.save(_np_branch(), tmp_path / "b.nc")
    with xr.open_dataset(path) as plain:
        ds = plain.load()
    ds["multipliers_imag"] = ds["multipliers_imag"].isel(multiplier=0)
    ds.to_netcdf(tmp_path / "c.nc", engine="netcdf4")
    with pytest.raises(ValueError, match=r"variables 'multipliers_real' and 'multipliers_imag' "
                                         r"\(the real and imaginary parts of 'multipliers'\) "
                                         r"must be real numbers of the same dimensions"):
        ic.load(tmp_path / "c.nc", validate=False)


def test_readers_of_attributes_name_them() -> None:
    ds = _np_branch()
    with pytest.raises(ValueError, match=r"'impacts' must be an integer >= 1 .* got 'two'"):
        impacts_of(ds.assign_attrs(impacts="two"))
    with pytest.raises(ValueError, match=r"'pattern' must be 2 letters .* got 'U'"):
        pattern_of(ds.assign_attrs(pattern="U"))
    with pytest.raises(ValueError, match=r"'parameter' must be one of .* got array"):
        validate_branch_dataset(ds.assign_attrs(parameter=np.array(["omega", "b"])))
    with pytest.raises(ValueError, match=r"'special_status' must hold statuses in "
                                         r"\['located', 'bracketed'\]; got \['guessed'\]"):
        validate_branch_dataset(_branch_with_status("guessed"))


def _branch_with_status(status: str) -> xr.Dataset:
    cols = _columns()
    specials = _specials(cols)
    ds = branch_dataset(parameter="omega", N=1, oscillator=OSC, options={}, columns=cols,
                        special_points=specials)
    return ds.assign(special_status=("special", np.array([status] * len(specials))))


# -- a killed save -----------------------------------------------------------------------------
def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                status = Path(f"/proc/{entry}/status").read_text()
            except OSError:
                continue
            fields = dict(line.split(":\t", 1) for line in status.splitlines() if ":\t" in line)
            if fields.get("PPid", "").strip() == str(pid):
                out.append(int(entry))
    return out


def _alive(pid: int) -> bool:
    """``pid`` runs (a zombie has ended: it only waits to be reaped by init)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_kill_9_of_a_saving_process_ends_its_writer_and_removes_the_temporary(
        tmp_path: Path) -> None:
    """The write of a large dataset runs in a child process: it must end with its parent.

    It once went on as an orphan, writing the temporary file to the end (1 GB in the
    report), which only the next save in that directory removed.
    """
    target = tmp_path / "big.nc"
    proc = _start_save(target, 6, "fork")  # 60 MB in memory: about 2 s of writing in a child
    (writer,) = _children(proc.pid)
    try:
        start = time.monotonic()
        proc.kill()
        proc.wait(timeout=30)  # not communicate(): the writer holds the same pipes
        while (_alive(writer) or _temporaries(tmp_path)) and time.monotonic() - start < 3.0:
            time.sleep(0.01)
        assert not _alive(writer), "the writing child survived its parent's kill -9"
        assert _temporaries(tmp_path) == [], "the killed save left its temporary file"
        assert not target.exists()
    finally:
        if _alive(writer):  # only before the fix: do not leave it writing
            os.kill(writer, signal.SIGKILL)
        proc.communicate(timeout=30)


def test_a_variable_that_cannot_be_decoded_is_named(tmp_path: Path) -> None:
    path = ic.save(_np_branch(), tmp_path / "b.nc")
    with netCDF4.Dataset(path, "a") as nc:
        nc["omega"].setncattr("scale_factor", "x")  # CF decoding multiplies by it
    with pytest.raises(ValueError, match=r"cannot read '.*b\.nc': a variable cannot be decoded "
                                         r"from its attributes .*TypeError"):
        ic.load(path)


def test_open_lazy_checks_the_attributes_too(tmp_path: Path) -> None:
    pytest.importorskip("dask")
    path = ic.save(_np_branch(), tmp_path / "b.nc")
    _tamper(path, None, pattern="XX")
    with pytest.raises(ValueError, match=r"b\.nc': attribute 'pattern' must be 2 letters"):
        dataset_io.open_lazy(path)


def _curve(**changes: Any) -> xr.Dataset:
    """A made-up SN curve in (omega, b) of three points with one codim-2 point."""
    kinds = {"root": int, "physical": bool, "stable_side": bool}
    columns = {key: np.zeros((3, 4) if key in ("multipliers", "state") else 3,
                             dtype=kinds.get(key, complex if key == "multipliers" else float))
               for key in CURVE_VARIABLES}
    codim2 = {"label": "R1", "omega": 1.0, "b": 0.5, "delta": 0.0, "point": 1, "precision": 0.0,
              "status": "located", "multipliers": np.zeros(4)}
    kwargs = {"kind": "SN", "N": 1, "parameters": ("omega", "b"), "oscillator": OSC,
              "options": {}, "columns": columns, "codim2_points": [codim2],
              "end_status": "bounds"}
    for key, value in changes.items():
        if key.startswith("cp_"):
            codim2[key.removeprefix("cp_")] = value
        else:
            kwargs[key] = value
    return curve_dataset(**kwargs)


@pytest.mark.parametrize(("changes", "error", "match"), [
    ({"parameters": ("omega", "mass")}, ValueError, r"parameter must be one of .* got 'mass'"),
    ({"parameters": ("omega", "omega")}, ValueError, r"two different parameters"),
    ({"N": 0}, ValueError, r"N must be an integer >= 1 \(forcing periods per impact\); got 0"),
    ({"cp_status": "located precisely"}, ValueError,
     r"codim2 statuses must be in \('located', 'bracketed'\); got \['located precisely'\]"),
    ({"codim2_points": [5]}, TypeError, r"codim2_points\[0\] must be a dict; got 5"),
])
def test_curve_datasets_refuse_bad_input_naming_it(changes: dict, error: type,
                                                   match: str) -> None:
    assert validate_curve_dataset(_curve()).attrs["parameters"] == "omega,b"
    with pytest.raises(error, match=match):
        _curve(**changes)


def test_map_datasets_refuse_bad_input_naming_it() -> None:
    with pytest.raises(TypeError, match=r"oscillator must be an ImpactOscillator; got 'osc'"):
        map_dataset(oscillator="osc", N=[1], omega=[1.0], b=[0.5], values={}, options={})
    with pytest.raises(ValueError,
                       match=r"N must be an integer >= 1 \(forcing periods per impact\); got 0"):
        map_dataset(oscillator=OSC, N=[0], omega=[1.0], b=[0.5], values={}, options={})


def test_info_names_a_branch_file_whose_variable_was_dropped(multi_file: Path, capsys) -> None:
    """``impactcont info`` read files without the schema check: a dropped variable ended in
    a raw KeyError inside the description."""
    with netCDF4.Dataset(multi_file, "a") as nc:
        nc.groups["m"].renameVariable("stable", "stable_was_here")
    assert main(["info", str(multi_file)]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "multi_impact.nc" in err and "stable" in err
    assert "Traceback" not in err and "KeyError" not in err


# -- issue 28 item 7: grouped files opened lazily, a pattern against its data, NaN parameters ---
def _consistent(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` (of :func:`_np_branch`) with each stored state on the stop its letter names."""
    osc = oscillator_from_dataset(ds)
    state = ds["state_k"].values.copy()
    for k, letter in enumerate(pattern_of(ds)):
        stop = osc.stops.stop(letter, osc.M, osc.b, osc.R)
        j = stop.pivot
        state[:, k, j] = stop.position - (state[:, k, :osc.n] @ stop.normal - state[:, k, j])
    return ds.assign(state_k=(ds["state_k"].dims, state, ds["state_k"].attrs))


def test_open_lazy_of_a_file_of_groups_opens_the_group_asked_for(tmp_path: Path) -> None:
    pytest.importorskip("dask")
    a, b = _np_branch(), _np_branch(N=3, p=1)
    path = ic.save({"a": a, "b": b}, tmp_path / "two.nc")
    with pytest.raises(ValueError, match=r"two\.nc' holds groups \['a', 'b'\].*"
                                         r"open_lazy\(path, group=NAME\)"):
        dataset_io.open_lazy(path)
    with dataset_io.open_lazy(path, group="b") as lazy:
        assert lazy["state_k"].chunks is not None  # lazy, not read
        xr.testing.assert_identical(lazy.load(), b)
    with pytest.raises(ValueError, match=r"group 'c'.*allowed: one of \['a', 'b'\]"):
        dataset_io.open_lazy(path, group="c")
    one = ic.save(a, tmp_path / "one.nc")
    with pytest.raises(ValueError, match=r"one\.nc' has no groups.*got group='a'"):
        dataset_io.open_lazy(one, group="a")
    scene = write_output(tmp_path / "multi_impact.nc", "multi_impact", {"m": a}, title="t")
    with dataset_io.open_lazy(scene, group="/m") as lazy:
        xr.testing.assert_identical(lazy.load(), a)
    _tamper(scene, "m", pattern="XX")  # the attributes are checked as by load
    with pytest.raises(ValueError, match=r"multi_impact\.nc', group '/m': attribute 'pattern'"):
        dataset_io.open_lazy(scene, group="m")


@pytest.mark.parametrize(("osc", "stored", "tampered"), [
    (TWO_SIDED, "UL", "LU"),
    (OSC.replace(b=1.0, stops=Stops(mass=2, relative_to=1, mirror=True)), "UL", "LU"),
    (OSC.replace(stops=Stops(b_low=0.5)), "UU", "LU"),
])
def test_a_pattern_that_contradicts_the_stored_states_is_refused(
        tmp_path: Path, osc: ic.ImpactOscillator, stored: str, tampered: str) -> None:
    ds = _np_branch(osc, pattern=stored)
    path = ic.save(ds, tmp_path / "b.nc")
    xr.testing.assert_identical(ic.load(path), ds)
    _tamper(path, None, pattern=tampered)
    for validate in (True, False):
        with pytest.raises(ValueError, match=rf"b\.nc': attribute 'pattern' = '{tampered}' "
                                             rf"contradicts the states stored.*the states say "
                                             rf"'{stored}'"):
            ic.load(path, validate=validate)
    with pytest.raises(ValueError, match=rf"'pattern' = '{tampered}' contradicts"):
        ic.save(ds.assign_attrs(pattern=tampered), tmp_path / "c.nc")
    assert not (tmp_path / "c.nc").exists()


def test_a_pattern_is_checked_where_the_stops_move_with_the_parameter(tmp_path: Path) -> None:
    ds = _np_branch(TWO_SIDED, pattern="UL")
    b = np.linspace(0.1, 0.4, ds.sizes["point"])
    ds = ds.assign_coords(b=("point", b, ds["b"].attrs)).assign_attrs(parameter="b")
    state = ds["state_k"].values.copy()
    state[:, 0, 0], state[:, 1, 0] = b, -0.5  # x1 = b on U, x1 = -b_low on L
    ds = ds.assign(state_k=(ds["state_k"].dims, state, ds["state_k"].attrs))
    path = ic.save(ds, tmp_path / "b.nc")
    assert pattern_of(ic.load(path)) == "UL"
    _tamper(path, None, pattern="LU")
    with pytest.raises(ValueError, match=r"'LU' contradicts .* impact 0 .*"
                                         r"the states say 'UL'"):
        ic.load(path)


@pytest.mark.parametrize("name", ["omega", "b"])
def test_a_branch_file_with_a_nan_parameter_is_refused_naming_the_point(
        tmp_path: Path, name: str) -> None:
    path = ic.save(_np_branch(), tmp_path / "b.nc")
    with netCDF4.Dataset(path, "a") as nc:
        nc[name][3] = np.nan
        nc[name][7] = np.nan
    for validate in (True, False):
        with pytest.raises(ValueError, match=rf"b\.nc': variable {name!r} .* must be finite "
                                             rf"at every point; got nan at point 3 \(2 points "
                                             rf"not finite\)"):
            ic.load(path, validate=validate)
    pytest.importorskip("dask")
    with pytest.raises(ValueError, match=rf"variable {name!r} .* got nan at point 3"):
        dataset_io.open_lazy(path)


def test_nan_in_a_physical_quantity_of_a_branch_still_loads(tmp_path: Path) -> None:
    ds = _np_branch()
    for key in ("impact_velocity", "gap_min", "spectral_radius", "delta"):
        values = ds[key].values.copy()
        values[2] = np.nan
        ds[key] = (ds[key].dims, values, ds[key].attrs)
    xr.testing.assert_identical(ic.load(ic.save(ds, tmp_path / "b.nc")), ds)
