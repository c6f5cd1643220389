"""Branch datasets: schema, NetCDF round trips, atomic writes and plots (fast, synthetic)."""

from __future__ import annotations

import json
import os

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
    bifurcation_diagram,
    multipliers_plot,
    stability_segments,
)

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
    assert set(branch.coords) == {"point", "component"}
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
    assert {"R", "special_R"} <= set(ds.data_vars)
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
    assert set(POINT_VARIABLES) <= set(branch.data_vars)


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


def test_bifurcation_diagram_renders(branch, tmp_path):
    ax = bifurcation_diagram(branch)
    lines = ax.get_lines()
    assert len(lines) == 4
    assert [ln.get_linestyle() for ln in lines] == ["-", "--", ":", "-"]
    assert lines[2].get_alpha() == SEGMENT_STYLES["non-physical"]["alpha"]
    assert sum(len(ln.get_xdata()) for ln in lines) == NPOINTS + 3
    assert len(ax.collections) == 3  # one marker set per special label present
    assert sorted(t.get_text() for t in ax.texts) == ["GR", "NS", "ZV"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["stable", "unstable", "non-physical", "NS Neimark-Sacker", "GR grazing",
                      "ZV zero-velocity impact", "N = 1"]
    # Special markers sit on the drawn curve at their parameter value.
    offsets = np.vstack([c.get_offsets() for c in ax.collections])
    np.testing.assert_allclose(np.sort(offsets[:, 0]), np.sort(branch["special_omega"].values),
                               rtol=0, atol=1e-12)
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel() == r"impact velocity $\dot{x}_1(T^-)$"  # no "(impact_velocity)"
    assert ax.get_title() == "Periodic 1-1 motions at b = 0"
    out = tmp_path / "diagram.png"
    ax.figure.savefig(out)
    assert out.stat().st_size > 0
    plt.close(ax.figure)


def test_bifurcation_diagram_many_branches_and_y(branch, tmp_path):
    fig, ax = plt.subplots()
    tree = xr.DataTree.from_dict({"a": branch, "b": branch.assign(omega=branch["omega"] + 1)})
    out = bifurcation_diagram(tree, y="delta", ax=ax, label_special=False)
    assert out is ax
    assert len(ax.get_lines()) == 8 and len(ax.texts) == 0
    assert {ln.get_color() for ln in ax.get_lines()} == {"C0", "C1"}
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == ["a (N = 1)",
                                                                        "b (N = 1)"]
    assert ax.get_ylabel() == r"impact phase $\delta$ [rad]"
    np.testing.assert_allclose(ax.collections[0].get_offsets()[:, 1],
                               branch["special_delta"].values[:1], rtol=0, atol=1e-12)
    fig.savefig(tmp_path / "many.png")
    plt.close(fig)
    with pytest.raises(ValueError, match=r"y must name .* got 'max_x9'"):
        bifurcation_diagram(branch, y="max_x9")
    with pytest.raises(TypeError, match="datasets must be"):
        bifurcation_diagram(3.0)
    plt.close("all")


def test_multipliers_plot_renders(branch, tmp_path):
    ax_abs, ax_c = multipliers_plot(branch)
    # spectral radius line, |mu| = 1 line, one vertical line per special point
    assert len(ax_abs.get_lines()) == 2 + branch.sizes["special"]
    assert len(ax_abs.collections) == 1
    assert ax_abs.collections[0].get_offsets().shape == (NPOINTS * 4, 2)
    np.testing.assert_allclose(ax_abs.get_lines()[1].get_ydata(), [1.0, 1.0], rtol=0, atol=0)
    # unit circle + all multipliers + one marker set per special label
    assert len(ax_c.get_lines()) == 1
    assert len(ax_c.collections) == 1 + len(set(branch["special_label"].values.tolist()))
    assert set(branch["special_label"].values.tolist()) <= set(SPECIAL_LABELS)
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


def test_special_point_labels_avoid_each_other(osc):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ds = _crowded(osc)
    bifurcation_diagram(ds, ax=ax)
    labels = [t for t in ax.texts if t.get_text() in SPECIAL_LABELS]
    assert sorted(t.get_text() for t in labels) == sorted(["SN", "PD", "NS", "GR", "ZV", "SN"])
    boxes = _extents(fig, labels)
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), "two special-point labels overlap"
    # each label still names its point
    np.testing.assert_allclose(sorted(t.xy[0] for t in labels),
                               np.sort(ds["special_omega"].values), rtol=0, atol=1e-12)
    legend, frame = _extents(fig, [ax.get_legend(), ax])
    assert legend.x0 >= frame.x1, "the legend must not cover the curves"


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
    edges = {tuple(np.round(c.get_edgecolor()[0][:3], 2)) for c in ax.collections}
    assert edges == {(0.0, 0.0, 0.0), (0.6, 0.6, 0.6)}
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
    assert [ax.get_title() for ax in axes] == ["b = 0", "b = 0.5"]
    assert fig._suptitle.get_text() == ("Bifurcation diagram: impact velocity against "
                                        "forcing frequency")
    assert [ax.get_legend().get_texts()[-1].get_text() for ax in axes] == [
        "b0 (N = 1)", "b0p5 (N = 2)"]
    single = draw_bifurcation({"b0": branch, "again": branch.assign(omega=branch["omega"] + 1)})
    (ax,) = single.get_axes()
    assert ax.get_title() == "Periodic 1-1 motions at b = 0"


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
    rho = ax_abs.get_lines()[0].get_ydata()
    assert np.isnan(rho[30]) and rho.size == NPOINTS + 1  # no chord between the components
    assert ax_c.get_xlim()[1] < 10.0
    assert any("outside the frame" in t.get_text() for t in ax_c.texts)
    plt.close(ax_abs.figure)


def test_figures_leave_no_temporary_file(tmp_path):
    from matplotlib.figure import Figure

    from impactcont.scene.figures import save_figure

    fig = Figure()
    fig.add_subplot().plot([0, 1])
    assert save_figure(fig, tmp_path / "f.png", 40).read_bytes()[:4] == b"\x89PNG"
    assert save_figure(fig, tmp_path / "f.pdf", 40).read_bytes()[:4] == b"%PDF"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png"]
