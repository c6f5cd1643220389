"""Branch datasets: schema, NetCDF round trips, atomic writes and plots (fast, synthetic)."""

from __future__ import annotations

import json
import os
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import netCDF4
import numpy as np
import pytest
import xarray as xr

import impactcont
from impactcont import ImpactOscillator
from impactcont.dataset import (
    POINT_VARIABLES,
    SPECIAL_LABELS,
    branch_dataset,
    load,
    oscillator_from_dataset,
    save,
    validate_branch_dataset,
)
from impactcont.dataset import io as dataset_io
from impactcont.plots import (
    SEGMENT_STYLES,
    SPECIAL_MARKERS,
    bifurcation_diagram,
    multipliers_plot,
    stability_segments,
)
from impactcont.plots.branches import NONPHYSICAL_GREY

NPOINTS = 50
N_DOF = 2


@pytest.fixture
def osc() -> ImpactOscillator:
    return ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                            omega=1.0, eta=0.1)


def _radius() -> np.ndarray:
    """Spectral radius with runs: stable 0-19, unstable 20-34, (non-physical 35-44), stable."""
    r = np.empty(NPOINTS)
    r[:20] = np.linspace(0.4, 0.95, 20)
    r[20:35] = np.linspace(1.05, 1.3, 15)
    r[35:45] = 1.1
    r[45:] = np.linspace(0.9, 0.6, 5)
    return r


def _columns(n: int = N_DOF, npoints: int = NPOINTS) -> dict[str, np.ndarray]:
    """Made-up but consistent columns of a branch in omega."""
    p = np.arange(npoints)
    omega = np.linspace(0.8, 2.0, npoints)
    r = _radius()[:npoints]
    mult = np.empty((npoints, 2 * n), dtype=complex)
    mult[:, 0] = r * np.exp(0.4j)
    mult[:, 1] = r * np.exp(-0.4j)
    mult[:, 2:] = 0.05 * np.linspace(1.0, -1.0, 2 * n - 2)
    physical = np.ones(npoints, dtype=bool)
    physical[35:45] = False
    state = np.zeros((npoints, 2 * n))
    state[:, 0] = 0.0  # x1 = b right after impact
    state[:, 1:] = np.sin(p[:, None] * 0.1 + np.arange(1, 2 * n))
    return {
        "omega": omega,
        "b": np.zeros(npoints),
        "delta": np.linspace(-3.0, 3.0, npoints),
        "impact_velocity": 1.0 + 0.5 * np.sin(omega),
        "gap_min": np.where(physical, 0.2, -0.1),
        "spectral_radius": np.abs(mult).max(axis=1),
        "stable": np.abs(mult).max(axis=1) < 1.0,
        "physical": physical,
        "arclength": np.cumsum(np.full(npoints, 0.03)),
        "multipliers": mult,
        "state": state,
    }


def _special(label: str, point: int, columns: dict[str, np.ndarray], status: str = "located"
             ) -> dict:
    omega = columns["omega"]
    return {
        "label": label,
        "omega": 0.5 * (omega[point - 1] + omega[point]),
        "b": 0.0,
        "delta": float(columns["delta"][point]),
        "point": point,
        "bracket_lo": float(omega[point - 1]),
        "bracket_hi": float(omega[point]),
        "precision": 1e-9 if status == "located" else float(omega[point] - omega[point - 1]),
        "status": status,
        "multipliers": columns["multipliers"][point],
    }


def _specials(columns: dict[str, np.ndarray]) -> list[dict]:
    return [_special("NS", 20, columns), _special("GR", 35, columns, "bracketed"),
            _special("ZV", 45, columns)]


@pytest.fixture
def branch(osc) -> xr.Dataset:
    cols = _columns()
    return branch_dataset(parameter="omega", N=1, oscillator=osc,
                          options={"ds": 0.03, "max_steps": 50, "tol": np.float64(1e-10)},
                          columns=cols, special_points=_specials(cols))


# -- schema -------------------------------------------------------------------------------------
def test_schema_dims_coords_and_dtypes(branch):
    assert dict(branch.sizes) == {"point": NPOINTS, "multiplier": 4, "component": 4, "special": 3}
    assert branch["point"].dtype == np.int64
    np.testing.assert_array_equal(branch["point"].values, np.arange(NPOINTS))
    assert branch["component"].values.tolist() == ["x1", "x2", "v1", "v2"]
    # the points are labelled by the parameters (coordinates on point: plots take x="omega")
    assert set(branch.coords) == {"point", "component", "omega", "b"}
    assert branch["impact_velocity"].coords["omega"].dims == ("point",)
    for name in ("omega", "b", "delta", "impact_velocity", "gap_min", "spectral_radius",
                 "arclength"):
        assert branch[name].dims == ("point",)
        assert branch[name].dtype == np.float64
    assert branch["stable"].dtype == bool and branch["physical"].dtype == bool
    assert branch["multipliers"].dims == ("point", "multiplier")
    assert branch["multipliers"].dtype == np.complex128
    assert branch["state"].dims == ("point", "component")
    assert branch["special_label"].dims == ("special",)
    assert branch["special_label"].dtype == np.dtype("<U2")
    assert branch["special_label"].values.tolist() == ["NS", "GR", "ZV"]
    assert branch["special_status"].values.tolist() == ["located", "bracketed", "located"]
    assert branch["special_point"].dtype == np.int64
    assert branch["special_multipliers"].dims == ("special", "multiplier")
    assert branch["special_multipliers"].dtype == np.complex128
    for name in ("omega", "b", "delta", "bracket_lo", "bracket_hi", "precision"):
        assert branch[f"special_{name}"].dtype == np.float64


def test_schema_attributes(branch, osc):
    for name, var in branch.data_vars.items():
        assert {"long_name", "units", "description"} <= set(var.attrs), name
    assert branch["delta"].attrs["units"] == "rad"
    assert branch["special_delta"].attrs["units"] == "rad"
    assert branch["omega"].attrs["units"] == "1"
    attrs = branch.attrs
    assert attrs["N"] == 1 and attrs["parameter"] == "omega"
    assert attrs["Conventions"] == "CF-1.10"
    assert attrs["impactcont_version"] == impactcont.__version__
    assert json.loads(attrs["options"]) == {"ds": 0.03, "max_steps": 50, "tol": 1e-10}
    assert attrs["oscillator"] == osc.to_json()
    assert "omega" in attrs["title"] and attrs["history"]
    back = oscillator_from_dataset(branch)
    assert back.to_dict() == osc.to_dict()
    at10 = oscillator_from_dataset(branch, point=10)
    assert at10.omega == pytest.approx(float(branch["omega"][10]), abs=0.0)
    assert validate_branch_dataset(branch) is branch


def test_schema_other_parameter_and_no_special_points(osc):
    cols = _columns()
    cols["R"] = np.linspace(0.5, 0.9, NPOINTS)
    ds = branch_dataset(parameter="R", N=2, oscillator=osc, options={}, columns=cols,
                        special_points=[])
    assert ds.sizes["special"] == 0
    assert "R" in ds.coords and "special_R" in ds.data_vars
    assert ds.attrs["parameter"] == "R"
    assert abs(oscillator_from_dataset(ds, point=-1).R - 0.9) <= 1e-15
    validate_branch_dataset(ds)


def _bad(osc, **changes):
    cols = _columns()
    kw = {"parameter": "omega", "N": 1, "oscillator": osc, "options": {}, "columns": cols,
          "special_points": _specials(cols)}
    for key, value in changes.items():
        if key.startswith("col_"):
            name = key[4:]
            if value is None:
                del cols[name]
            else:
                cols[name] = value
        elif key.startswith("sp_"):
            kw["special_points"][0][key[3:]] = value
        else:
            kw[key] = value
    return branch_dataset(**kw)


@pytest.mark.parametrize(("changes", "error", "match"), [
    ({"col_gap_min": None}, ValueError, r"missing key\(s\) \['gap_min'\]"),
    ({"col_delta": np.zeros(NPOINTS - 1)}, ValueError, r"'delta' must have shape \(50,\)"),
    ({"col_multipliers": np.zeros((NPOINTS, 3))}, ValueError, r"'multipliers' .*\(50, 4\)"),
    ({"col_speed": np.zeros(NPOINTS)}, ValueError, r"unknown key\(s\) \['speed'\]"),
    ({"col_stable": np.full(NPOINTS, 2.0)}, ValueError, r"'stable' must be boolean"),
    ({"col_omega": np.full(NPOINTS, np.nan)}, ValueError, r"'omega' must be finite"),
    ({"sp_label": "XX"}, ValueError, r"\['label'\] must be one of .*got 'XX'"),
    ({"sp_status": "guessed"}, ValueError, r"\['status'\] .*got 'guessed'"),
    ({"sp_point": NPOINTS}, ValueError, r"\['point'\] must be an integer index .*got 50"),
    ({"sp_precision": -1.0}, ValueError, r"\['precision'\] must be >= 0.*-1.0"),
    ({"sp_bracket_lo": 5.0}, ValueError, r"bracket_lo=5.0"),
    ({"sp_multipliers": np.zeros(3)}, ValueError, r"special_points\[0\] key 'multipliers'"),
    ({"parameter": "mass"}, ValueError, r"parameter must be one of .*got 'mass'"),
    ({"N": 0}, ValueError, r"N .* got 0"),
    ({"oscillator": "osc"}, TypeError, r"oscillator must be an ImpactOscillator; got 'osc'"),
    ({"options": {"f": object}}, TypeError, r"options must be JSON-serialisable"),
])
def test_bad_inputs_raise_naming_the_value(osc, changes, error, match):
    with pytest.raises(error, match=match):
        _bad(osc, **changes)


def test_missing_special_key_is_named(osc):
    cols = _columns()
    sps = _specials(cols)
    del sps[1]["precision"]
    with pytest.raises(ValueError, match=r"special_points\[1\] is missing key\(s\) \['precision'"):
        branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                       special_points=sps)


def test_validate_rejects_incomplete_datasets(branch):
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['gap_min'\]"):
        validate_branch_dataset(branch.drop_vars("gap_min"))
    with pytest.raises(ValueError, match=r"missing attribute\(s\) \['oscillator'\]"):
        validate_branch_dataset(branch.drop_attrs(deep=False).assign_attrs(
            {k: v for k, v in branch.attrs.items() if k != "oscillator"}))
    with pytest.raises(ValueError, match="'stable' must have dtype kind 'b'"):
        validate_branch_dataset(branch.assign(stable=branch["stable"].astype(float)))
    with pytest.raises(TypeError, match="DataArray"):
        validate_branch_dataset(branch["omega"])
    assert set(POINT_VARIABLES) <= set(branch.variables)


# -- NetCDF I/O ---------------------------------------------------------------------------------
def test_single_branch_round_trip(branch, tmp_path):
    path = tmp_path / "branch.nc"
    assert save(branch, path) == path
    back = load(path)
    assert isinstance(back, xr.Dataset)
    xr.testing.assert_identical(back, branch)
    assert back["multipliers"].dtype == np.complex128
    np.testing.assert_array_equal(back["multipliers"].values, branch["multipliers"].values)
    assert back["stable"].dtype == bool and back["physical"].dtype == bool
    assert back["special_label"].dtype == np.dtype("<U2")
    assert oscillator_from_dataset(back).to_dict() == oscillator_from_dataset(branch).to_dict()
    # On disk: complex as real and imaginary float parts, booleans as int8 tagged dtype=bool.
    with netCDF4.Dataset(path) as nc:
        assert nc.data_model == "NETCDF4"
        assert "multipliers" not in nc.variables
        real, imag = nc.variables["multipliers_real"], nc.variables["multipliers_imag"]
        assert real.dtype == imag.dtype == np.float64
        assert real.dimensions == ("point", "multiplier")
        assert real.getncattr("long_name") == "real part of Floquet multipliers"
        assert imag.getncattr("impactcont_complex_part") == "imag"
        assert imag.getncattr("impactcont_complex_variable") == "multipliers"
        np.testing.assert_array_equal(real[:] + 1j * imag[:], branch["multipliers"].values)
        assert nc.variables["stable"].dtype == np.int8
        assert nc.variables["stable"].getncattr("dtype") == "bool"


def test_load_closes_file_so_it_can_be_overwritten(branch, tmp_path):
    path = tmp_path / "branch.nc"
    save(branch, path)
    first = load(path)
    changed = branch.assign(gap_min=branch["gap_min"] + 1.0)
    save(changed, path)
    xr.testing.assert_identical(load(path), changed)
    xr.testing.assert_identical(first, branch)


def test_empty_special_round_trip(osc, tmp_path):
    ds = branch_dataset(parameter="b", N=3, oscillator=osc, options={}, columns=_columns(),
                        special_points=[])
    save(ds, tmp_path / "e.nc")
    back = load(tmp_path / "e.nc")
    xr.testing.assert_identical(back, ds)
    assert back["special_label"].dtype == np.dtype("<U2")
    assert back["special_multipliers"].shape == (0, 4)


def test_multi_branch_round_trip(branch, osc, tmp_path):
    cols = _columns(npoints=30)
    other = branch_dataset(parameter="omega", N=2, oscillator=osc.replace(b=0.1),
                           options={"ds": -0.01}, columns=cols,
                           special_points=[_special("PD", 5, cols)])
    path = tmp_path / "many.nc"
    save({"N1": branch, "N2": other}, path)
    tree = load(path)
    assert isinstance(tree, xr.DataTree)
    assert set(tree.children) == {"N1", "N2"}
    xr.testing.assert_identical(tree["N1"].to_dataset(inherit=False), branch)
    xr.testing.assert_identical(tree["N2"].to_dataset(inherit=False), other)
    assert tree["N2"]["multipliers"].dtype == np.complex128
    assert tree["N2"]["physical"].dtype == bool
    # A DataTree is written as it is and reads back identical.
    save(tree, tmp_path / "tree.nc")
    xr.testing.assert_identical(load(tmp_path / "tree.nc"), tree)
    # A mapping with one branch is still a file of groups.
    save({"only": branch}, tmp_path / "one.nc")
    assert isinstance(load(tmp_path / "one.nc"), xr.DataTree)


def test_groups_named_like_variables_are_fully_loaded(branch, tmp_path):
    # A group "b" and a variable "b" in each group: all data must be in memory after load.
    path = tmp_path / "named.nc"
    save({"b": branch, "omega": branch}, path)
    tree = load(path)
    path.unlink()
    for name in ("b", "omega"):
        ds = tree[name].to_dataset(inherit=False)
        # Checked before any value is read: reading a closed netCDF4 file can crash.
        lazy = [k for k, var in ds.variables.items() if not var._in_memory]
        assert lazy == [], f"group {name}: {lazy} not loaded"
        xr.testing.assert_identical(ds, branch)


def _leftovers(directory):
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


@pytest.mark.parametrize("multi", [False, True])
def test_failed_write_leaves_old_file_and_no_temp(branch, tmp_path, monkeypatch, multi):
    path = tmp_path / "branch.nc"
    save(branch, path)
    before = path.read_bytes()

    def broken(self, target, *args, **kwargs):
        with open(target, "wb") as f:
            f.write(b"\x89HDF half a file")
        raise OSError("disk full")

    cls = xr.DataTree if multi else xr.Dataset
    monkeypatch.setattr(cls, "to_netcdf", broken)
    obj = {"a": branch} if multi else branch
    with pytest.raises(OSError, match="disk full"):
        save(obj, path)
    assert path.read_bytes() == before
    assert _leftovers(tmp_path) == []
    monkeypatch.undo()
    xr.testing.assert_identical(load(path), branch)


def test_failed_replace_removes_temp(branch, tmp_path, monkeypatch):
    def no_replace(src, dst):
        raise PermissionError(f"cannot replace {dst}")

    monkeypatch.setattr(dataset_io.os, "replace", no_replace)
    with pytest.raises(PermissionError):
        save(branch, tmp_path / "new.nc")
    assert list(tmp_path.iterdir()) == []


def test_io_bad_arguments(branch, tmp_path):
    with pytest.raises(TypeError, match=r"obj must be .* got int"):
        save(42, tmp_path / "x.nc")
    with pytest.raises(TypeError, match=r"path must be a str or os\.PathLike; got 123"):
        save(branch, 123)
    with pytest.raises(ValueError, match="not a directory"):
        save(branch, tmp_path)
    with pytest.raises(FileNotFoundError, match="nope"):
        save(branch, tmp_path / "nope" / "x.nc")
    with pytest.raises(ValueError, match=r"branch names .* got 'a/b'"):
        save({"a/b": branch}, tmp_path / "x.nc")
    with pytest.raises(TypeError, match=r"obj\['a'\] must be an xarray.Dataset; got int"):
        save({"a": 1}, tmp_path / "x.nc")
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['state'\]"):
        save(branch.drop_vars("state"), tmp_path / "x.nc")
    assert _leftovers(tmp_path) == [] and not (tmp_path / "x.nc").exists()
    missing = tmp_path / "missing.nc"
    with pytest.raises(FileNotFoundError, match=r"missing\.nc"):
        load(missing)
    garbage = tmp_path / "garbage.nc"
    garbage.write_bytes(b"not a netcdf file")
    with pytest.raises(ValueError, match=r"garbage\.nc"):
        load(garbage)
    other = tmp_path / "other.nc"
    xr.Dataset({"a": ("t", np.arange(3.0))}).to_netcdf(other, engine="netcdf4")
    with pytest.raises(ValueError, match=r"other.nc.*missing attribute"):
        load(other)
    assert os.path.exists(other)


# -- plots --------------------------------------------------------------------------------------
def test_stability_segments(branch):
    segs = stability_segments(branch)
    assert [k for k, _ in segs] == ["stable", "unstable", "non-physical", "stable"]
    assert [(s.start, s.stop) for _, s in segs] == [(0, 21), (20, 36), (35, 46), (45, 50)]


_SHAPES = {marker: label for label, marker in SPECIAL_MARKERS.items()}


def _is_marker(line) -> bool:
    return line.get_linestyle() in ("None", "none", " ", "")


def _curves(ax) -> list:
    """The lines drawn with a line style (branches, |mu| = 1, the unit circle)."""
    return [ln for ln in ax.get_lines() if not _is_marker(ln)]


def _markers(ax) -> list[tuple[str, np.ndarray, object]]:
    """``(label, xy, line)`` of every special-point marker drawn on ``ax``, one per point."""
    return [(_SHAPES[ln.get_marker()], xy, ln) for ln in ax.get_lines() if _is_marker(ln)
            for xy in ln.get_xydata()]


def _on_curve(ds: xr.Dataset, y: str) -> list[tuple[str, float, float]]:
    """``(label, parameter, y)`` of each special point on the polyline of ``y`` (omega rises)."""
    omega = ds["special_omega"].values
    return sorted(zip(ds["special_label"].values.tolist(), omega,
                      np.interp(omega, ds["omega"].values, ds[y].values), strict=True))


def _assert_same_points(drawn, expected) -> None:
    """Equal lists of ``(label, x, y)``: labels exactly, coordinates to rounding."""
    drawn, expected = sorted(drawn), sorted(expected)
    assert [d[0] for d in drawn] == [e[0] for e in expected]
    np.testing.assert_allclose([d[1:] for d in drawn], [e[1:] for e in expected],
                               rtol=0, atol=1e-12)


def test_bifurcation_diagram_renders(branch, tmp_path):
    ax = bifurcation_diagram(branch)
    lines = _curves(ax)
    assert [ln.get_linestyle() for ln in lines] == ["-", "--", ":", "-"]
    assert lines[2].get_alpha() == SEGMENT_STYLES["non-physical"]["alpha"]
    # every point drawn, the segments joined (one shared point at each of the 3 joins)
    assert sum(len(ln.get_xdata()) for ln in lines) == NPOINTS + 3
    np.testing.assert_array_equal(np.concatenate([ln.get_xdata() for ln in lines]),
                                  np.concatenate([branch["omega"].values[s] for _, s in
                                                  stability_segments(branch)]))
    assert all(ln.get_color() == "C0" for ln in lines)
    # one marker per special point, of its label's shape, in the branch's colour, sitting
    # on the drawn curve at its parameter value
    markers = _markers(ax)
    assert all(len(ln.get_xydata()) == 1 for _, _, ln in markers)
    _assert_same_points([(lab, *xy) for lab, xy, _ in markers],
                        _on_curve(branch, "impact_velocity"))
    assert all(ln.get_markeredgecolor() == "C0" for _, _, ln in markers)
    # one label per special point, anchored at its marker
    _assert_same_points([(t.get_text(), *t.xy) for t in ax.texts],
                        [(lab, *xy) for lab, xy, _ in markers])
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [
        "stable", "unstable", "non-physical", "NS Neimark-Sacker", "GR grazing",
        "ZV zero-velocity impact", "N = 1"]
    ax.figure.canvas.draw()
    assert legend.get_window_extent().y1 <= ax.get_window_extent().y0, "legend over the axes"
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel() == r"impact velocity $\dot{x}_1(T^-)$"  # no "(impact_velocity)"
    assert ax.get_title() == r"Periodic 1-1 motions, $b = 0$, $R = 0.6$, $\eta = 0.1$"
    out = tmp_path / "diagram.png"
    ax.figure.savefig(out)
    assert out.stat().st_size > 0
    plt.close(ax.figure)


def test_bifurcation_diagram_many_branches_and_y(branch, tmp_path):
    fig, ax = plt.subplots()
    shifted = branch.assign({name: branch[name] + 1 for name in (
        "omega", "special_omega", "special_bracket_lo", "special_bracket_hi")})
    tree = xr.DataTree.from_dict({"a": branch, "b": shifted})
    out = bifurcation_diagram(tree, y="delta", ax=ax, label_special=False)
    assert out is ax
    assert [ln.get_color() for ln in _curves(ax)] == ["C0"] * 4 + ["C1"] * 4
    assert len(ax.texts) == 0
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == ["a (N = 1)",
                                                                        "b (N = 1)"]
    assert ax.get_ylabel() == r"impact phase $\delta$ [rad]"
    # each branch's special points in its colour, at their stored (omega, delta)
    markers = _markers(ax)
    assert len(markers) == 2 * branch.sizes["special"]
    for ds, colour in ((branch, "C0"), (shifted, "C1")):
        expected = zip(ds["special_label"].values.tolist(), ds["special_omega"].values,
                       ds["special_delta"].values, strict=True)
        _assert_same_points([(lab, *xy) for lab, xy, ln in markers
                             if ln.get_markeredgecolor() == colour], list(expected))
    fig.savefig(tmp_path / "many.png")
    plt.close(fig)
    with pytest.raises(ValueError, match=r"y must name .* got 'max_x9'"):
        bifurcation_diagram(branch, y="max_x9")
    with pytest.raises(TypeError, match="datasets must be"):
        bifurcation_diagram(3.0)
    plt.close("all")


def test_multipliers_plot_renders(branch, tmp_path):
    ax_abs, ax_c = multipliers_plot(branch)
    # the spectral radius at every point and |mu| = 1; every modulus as a dot
    rho, unit = _curves(ax_abs)
    np.testing.assert_array_equal(rho.get_xydata(), np.column_stack(
        [branch["omega"].values, branch["spectral_radius"].values]))
    np.testing.assert_allclose(unit.get_ydata(), [1.0, 1.0], rtol=0, atol=0)
    assert len(ax_abs.collections) == 1
    assert ax_abs.collections[0].get_offsets().shape == (NPOINTS * 4, 2)
    # one marker per special point on the drawn spectral radius, labelled there
    markers = _markers(ax_abs)
    _assert_same_points([(lab, *xy) for lab, xy, _ in markers],
                        _on_curve(branch, "spectral_radius"))
    _assert_same_points([(t.get_text(), *t.xy) for t in ax_abs.texts],
                        [(lab, *xy) for lab, xy, _ in markers])
    # complex plane: the unit circle, every multiplier, and one marker line per special
    # label holding the multipliers of its special points (all inside the frame here)
    (circle,) = _curves(ax_c)
    np.testing.assert_allclose(np.hypot(*circle.get_xydata().T), 1.0, rtol=0, atol=1e-12)
    assert len(ax_c.collections) == 1
    drawn = np.asarray(ax_c.collections[0].get_offsets()) @ [1.0, 1.0j]
    mult = branch["multipliers"].values.ravel()
    framed = mult[np.abs(mult) <= ax_c.get_xlim()[1]]  # the frame's inscribed circle
    assert framed.size >= NPOINTS * 3 and drawn.size <= mult.size
    assert np.all(np.min(np.abs(framed[:, None] - drawn[None, :]), axis=1) <= 1e-12)
    labels = branch["special_label"].values
    assert set(labels.tolist()) <= set(SPECIAL_LABELS)
    lines = [ln for ln in ax_c.get_lines() if _is_marker(ln)]
    assert sorted(_SHAPES[ln.get_marker()] for ln in lines) == sorted(set(labels.tolist()))
    for ln in lines:
        drawn = ln.get_xydata() @ [1.0, 1.0j]
        expected = branch["special_multipliers"].values[labels == _SHAPES[ln.get_marker()]]
        np.testing.assert_allclose(np.sort_complex(drawn), np.sort_complex(expected.ravel()),
                                   rtol=0, atol=1e-12)
    # one legend names every mark
    assert [t.get_text() for t in ax_abs.get_legend().get_texts()] == [
        "spectral radius", r"$|\mu| = 1$", "NS Neimark-Sacker", "GR grazing",
        "ZV zero-velocity impact"]
    ax_abs.figure.savefig(tmp_path / "multipliers.png")
    plt.close(ax_abs.figure)
    with pytest.raises(TypeError, match="pair of matplotlib Axes"):
        multipliers_plot(branch, ax=ax_abs)


# -- figures a user can publish (issue 13) ----------------------------------------------------
def _crowded(osc) -> xr.Dataset:
    """Six special points on six neighbouring points: their labels would pile up."""
    cols = _columns()
    specials = [_special(label, p, cols) for label, p in
                zip(("SN", "PD", "NS", "GR", "ZV", "SN"), range(20, 26), strict=True)]
    return branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                          special_points=specials)


def _extents(fig, artists) -> list:
    """Window extents after drawing; of an annotation, its text only (not its leader line)."""
    from matplotlib.text import Annotation, Text

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return [Text.get_window_extent(a, renderer) if isinstance(a, Annotation)
            else a.get_window_extent(renderer) for a in artists]


#: Points closer than this on the page (a marker's size, in points) share one label.
ONE_PLACE = 8.0


@pytest.mark.parametrize("width", [3.5, 5.0, 7.0])
def test_special_point_labels_avoid_each_other(osc, width):
    """Crowded special points: no two labels overlap, and each label names its point(s).

    A label (on the axes or in a zoomed inset) is anchored at a special point and names
    only special points within one marker of that anchor; every special point is named
    by such a label.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ds = _crowded(osc)
    bifurcation_diagram(ds, ax=ax)
    panels = [ax, *[inset for inset in ax.child_axes if inset.get_visible()]]
    labels = [(panel, t) for panel in panels for t in panel.texts if t.get_text()]
    boxes = _extents(fig, [t for _, t in labels])
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), "two special-point labels overlap"
    specials = _on_curve(ds, "impact_velocity")
    assert len(specials) == 6
    named = set()
    for panel, t in labels:
        def points(xy, panel=panel):
            return panel.transData.transform(xy) * 72.0 / fig.dpi

        (x0, x1), (y0, y1) = sorted(panel.get_xlim()), sorted(panel.get_ylim())
        shown = [k for k, (_, x, y) in enumerate(specials) if x0 <= x <= x1 and y0 <= y <= y1]
        away = {k: float(np.hypot(*(points((specials[k][1], specials[k][2]))
                                    - points(t.xy)))) for k in shown}
        assert min(away.values()) < 0.5, f"{t.get_text()!r} is not at a special point"
        near = [k for k in shown if away[k] <= ONE_PLACE]
        names = t.get_text().split(", ")
        assert len(set(names)) == len(names), t.get_text()
        assert set(names) <= {specials[k][0] for k in near}, (
            f"{t.get_text()!r} names a point not within a marker of it")
        named.update(k for k in near if specials[k][0] in names)
    assert named == set(range(len(specials))), "a special point has no label"
    legend, frame = _extents(fig, [ax.get_legend(), ax])
    assert legend.y1 <= frame.y0, "the legend must not cover the curves"


def test_naive_offsets_would_overlap(osc):
    """The case above is a real collision: fixed offsets (the former layout) overlap."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ds = _crowded(osc)
    bifurcation_diagram(ds, ax=ax, label_special=False)
    naive = [ax.annotate(str(lab), (x, 0), xytext=(4, 4), textcoords="offset points",
                         fontsize="small")
             for lab, x in zip(ds["special_label"].values, ds["special_omega"].values,
                               strict=True)]
    boxes = _extents(fig, naive)
    assert any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])


def test_special_points_of_non_physical_motions_are_grey_and_unlabelled(osc):
    cols = _columns()
    ds = branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                        special_points=[_special("PD", 40, cols), _special("NS", 20, cols)])
    ax = bifurcation_diagram(ds)
    assert [t.get_text() for t in ax.texts] == ["NS"]
    markers = {lab: ln for lab, _, ln in _markers(ax)}
    assert sorted(markers) == ["NS", "PD"]
    assert markers["NS"].get_markeredgecolor() == "C0"  # physical: the branch's colour
    assert markers["PD"].get_markeredgecolor() == NONPHYSICAL_GREY  # inside the dotted run
    assert markers["PD"].get_markersize() < markers["NS"].get_markersize()
    legend = {t.get_text(): h for t, h in zip(ax.get_legend().get_texts(),
                                              ax.get_legend().legend_handles, strict=True)}
    assert legend["grey: on non-physical motion"].get_markeredgecolor() == NONPHYSICAL_GREY
    assert "PD period doubling" in legend
    plt.close(ax.figure)


def test_vertical_range_fits_the_physical_motions(branch):
    far = (branch["point"] > 36) & (branch["point"] < 43)  # inside the non-physical run
    wild = branch.assign(impact_velocity=branch["impact_velocity"].where(~far, 50.0))
    ax = bifurcation_diagram(wild)
    lo, hi = ax.get_ylim()
    physical = wild["impact_velocity"].values[wild["physical"].values]
    assert lo < physical.min() and physical.max() < hi < 5.0
    ax_all = bifurcation_diagram(wild, physical_range=False)
    assert ax_all.get_ylim()[1] > 50.0
    plt.close("all")


def _branch_at_gap(osc, b: float, N: int):
    """A synthetic branch of the test columns with every point at gap b."""
    cols = _columns()
    cols["b"] = np.full(NPOINTS, b)
    return branch_dataset(parameter="omega", N=N, oscillator=osc.replace(b=b), options={},
                          columns=cols, special_points=[])


def test_scene_diagram_has_one_panel_per_system(branch, osc):
    from impactcont.scene.figures import draw_bifurcation

    other = _branch_at_gap(osc, 0.5, N=2)
    fig = draw_bifurcation({"b0": branch, "b0p5": other})
    axes = fig.get_axes()
    assert [ax.get_title() for ax in axes] == ["$b = 0$", "$b = 0.5$"]
    assert fig._suptitle.get_text() == ("Bifurcation diagram: impact velocity against "
                                        "forcing frequency")
    # each panel draws its own branch only, named (by its N) in its legend
    for ax, ds in zip(axes, (branch, other), strict=True):
        np.testing.assert_array_equal(
            np.concatenate([ln.get_xdata() for ln in _curves(ax)]),
            np.concatenate([ds["omega"].values[s] for _, s in stability_segments(ds)]))
    assert [ax.get_legend().get_texts()[-1].get_text() for ax in axes] == ["N = 1", "N = 2"]
    assert [ax.get_xlabel() for ax in axes] == ["", r"forcing frequency $\omega$"]
    single = draw_bifurcation({"b0": branch, "again": branch.assign(omega=branch["omega"] + 1)})
    (ax,) = single.get_axes()
    assert ax.get_title() == r"Periodic 1-1 motions, $b = 0$, $R = 0.6$, $\eta = 0.1$"
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == ["b0 (N = 1)",
                                                                        "again (N = 1)"]


def test_one_axis_of_several_systems_names_the_system_of_each_branch(branch, osc):
    other = _branch_at_gap(osc, 0.5, N=1)
    ax = bifurcation_diagram({"a": branch, "c": other})
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == [
        "a (N = 1, b = 0)", "c (N = 1, b = 0.5)"]
    plt.close(ax.figure)


def test_multipliers_plot_keeps_components_apart_and_frames_poles(branch):
    component = np.where(np.arange(NPOINTS) < 30, 0, 1)
    mult = branch["multipliers"].values.copy()
    mult[10, 0] = -1e14  # the pole of G at a zero-velocity impact
    ds = branch.assign(connected_component=("point", component),
                       multipliers=(branch["multipliers"].dims, mult,
                                    branch["multipliers"].attrs))
    ax_abs, ax_c = multipliers_plot(ds)
    rho = _curves(ax_abs)[0].get_ydata()
    assert np.isnan(rho[30]) and rho.size == NPOINTS + 1  # no chord between the components
    np.testing.assert_array_equal(np.delete(rho, 30), ds["spectral_radius"].values)
    # the pole is framed out, the bulk framed in, and the title says what is not shown
    lo, hi = ax_c.get_xlim()
    assert ax_c.get_ylim() == (lo, hi) and -hi == lo and 1.0 < hi < 10.0
    note = re.fullmatch(r"\$\|\\mu\| > ([0-9.]+)\$ not shown", ax_c.get_title(loc="left"))
    assert note is not None, ax_c.get_title(loc="left")
    assert float(note.group(1)) == pytest.approx(hi, rel=5e-3)
    bulk = np.delete(mult.ravel(), 10 * mult.shape[1])  # every multiplier but the pole
    assert np.all(np.abs(bulk.real) <= hi) and np.all(np.abs(bulk.imag) <= hi)
    for ln in ax_c.get_lines():  # the special markers too stay inside the frame
        assert np.all(np.abs(ln.get_xydata()) <= hi)
    plt.close(ax_abs.figure)


def test_multipliers_plot_note_says_what_is_not_drawn(branch):
    """``|mu| > r not shown``: every dot drawn has ``|mu| <= r``, every one left out ``> r``."""
    ax_abs, ax_c = multipliers_plot(branch)
    mult = branch["multipliers"].values.ravel()
    drawn = np.asarray(ax_c.collections[0].get_offsets()) @ [1.0, 1.0j]
    note = re.fullmatch(r"\$\|\\mu\| > ([0-9.]+)\$ not shown", ax_c.get_title(loc="left"))
    if note is None:
        assert drawn.size == mult.size, "multipliers left out without a word"
    else:
        r = float(note.group(1))
        assert np.all(np.abs(drawn) <= r * (1 + 5e-3))
        assert drawn.size == np.count_nonzero(np.abs(mult) <= r * (1 + 5e-3))
    plt.close(ax_abs.figure)


def test_figures_leave_no_temporary_file(tmp_path):
    from matplotlib.figure import Figure

    from impactcont.scene.figures import save_figure

    fig = Figure()
    fig.add_subplot().plot([0, 1])
    assert save_figure(fig, tmp_path / "f.png", 40).read_bytes()[:4] == b"\x89PNG"
    assert save_figure(fig, tmp_path / "f.pdf", 40).read_bytes()[:4] == b"%PDF"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png"]


# -- robust datasets: element names 1-based; files of before element_indexing ---------------------
def _robust_dataset(attrs: dict) -> xr.Dataset:
    """A robust dataset as the scene's [[robust]] writes it (the attributes readers use)."""
    osc = ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.6,
                           omega=1.0, eta=0.1)
    return xr.Dataset({"epsilon": ((), 0.01), "epsilon0": ((), 0.3), "robust": ((), True)},
                      attrs={"title": "Robust stability of the N=1 motion", "name": "rb",
                             "impactcont_dataset": "robust", "N": 1, "root": -1,
                             "samples": 3, "evaluations": 9, "message": "robustly stable",
                             "oscillator": osc.to_json(), **attrs})


def test_old_robust_file_keeps_the_meaning_of_its_forcing_entries(tmp_path):
    """A file of before element_indexing, written by hand as the old writer did (0-based
    F[i]), reads with the 1-based names of the same masses: its nominal F[0] = 1.0 was mass
    1's forcing, which the 1-based F[1] of the stored oscillator is (F[2] would be 0)."""
    from impactcont.model.parameters import model_parameter

    old = _robust_dataset({
        "vary": json.dumps({"F[0]": [0.95, 1.05], "b": [0.5, 0.7]}),
        "nominal": json.dumps({"F[0]": 1.0, "b": 0.6}),
        "argmax": json.dumps({"0,0": {"F[0]": 1.05, "b": 0.5}, "1,1": {"F[0]": 0.95,
                                                                     "b": 0.7}})})
    path = tmp_path / "old_robust.nc"
    old.to_netcdf(path, engine="netcdf4")  # on disk as before, no element_indexing
    ds = impactcont.load(path)
    assert json.loads(ds.attrs["vary"]) == {"F[1]": [0.95, 1.05], "b": [0.5, 0.7]}
    assert json.loads(ds.attrs["nominal"]) == {"F[1]": 1.0, "b": 0.6}
    assert json.loads(ds.attrs["argmax"]) == {"0,0": {"F[1]": 1.05, "b": 0.5},
                                              "1,1": {"F[1]": 0.95, "b": 0.7}}
    assert ds.attrs["element_indexing"] == "1-based"
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    for name, value in json.loads(ds.attrs["nominal"]).items():
        assert model_parameter(osc, name).value(osc) == value
    # read again after saving: today's file, names unchanged
    impactcont.save(ds, tmp_path / "again.nc")
    again = impactcont.load(tmp_path / "again.nc")
    assert again.attrs["vary"] == ds.attrs["vary"] and again.attrs["argmax"] == ds.attrs["argmax"]


def test_new_robust_file_reads_its_names_as_written(tmp_path):
    from impactcont.dataset.schema import robust_attributes

    attrs = robust_attributes({"F[2]": (-0.1, 0.1), "k2": (0.9, 1.1)}, {"F[2]": 0.0, "k2": 1.0},
                              {(0, 1): {"F[2]": 0.1, "k2": 0.9}})
    impactcont.save(_robust_dataset(attrs), tmp_path / "new.nc")
    ds = impactcont.load(tmp_path / "new.nc")
    for key in ("vary", "nominal", "argmax", "element_indexing"):
        assert ds.attrs[key] == attrs[key]
    assert json.loads(ds.attrs["vary"]) == {"F[2]": [-0.1, 0.1], "k2": [0.9, 1.1]}


@pytest.mark.parametrize(("attrs", "pattern"), [
    ({"vary": json.dumps({"gap": [0.2, 1.0]}), "nominal": "{}"}, r"'vary'.*names \['gap'\]"),
    ({"vary": json.dumps({"x1": [0.2, 1.0]}), "nominal": "{}"}, r"'vary'.*names \['x1'\]"),
    ({"vary": json.dumps({"b": [0.2, 1.0]}), "nominal": "{}", "element_indexing": "0-based"},
     "'element_indexing' must be '1-based'"),
])
def test_robust_file_with_what_robust_cannot_vary_is_refused(tmp_path, attrs, pattern):
    path = tmp_path / "bad.nc"
    _robust_dataset(attrs).to_netcdf(path, engine="netcdf4")
    with pytest.raises(ValueError, match=pattern):
        impactcont.load(path)
