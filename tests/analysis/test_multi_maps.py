"""Stability maps of one N-p motion family over two parameters (``multi_impact_map``).

Independent witnesses: the branch through the same motion (``multi_impact_continuation``
in one parameter at a fixed value of the other: the stability and physical flags agree
except within one grid cell of a special point), the closed-form N-1 map
(``stability_map``: a 1-1 family seeded by the closed form covers the existence region
of its root with the same flags and spectral radius), and the event-driven simulator
(started on the map's stored motion at stable points, it reproduces its impacts).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.multi_maps import multi_impact_map, multi_impact_map_orbit
from impactcont.dataset.multi_maps import validate_multi_impact_map_dataset
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.symmetry import symmetry_defect

K2 = [[1.0, -1.0], [-1.0, 2.0]]
OMEGA = np.linspace(0.8, 1.8, 41)  # both pitchforks of the b = 0.5 backlash: 0.964, 1.338
B = np.linspace(0.3, 0.8, 11)
SPECIAL = ("SN", "PD", "NS", "BP", "GR", "ZV")


def mirrored(omega: float, b: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=b,
                               omega=omega, stops=Stops(mirror=True))


@pytest.fixture(scope="module")
def start():
    """The symmetric 1-2 motion the simulator settles on at omega = 1.6, b = 0.5."""
    osc = mirrored(1.6, 0.5)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))


@pytest.fixture(scope="module")
def sym_map(start):
    return multi_impact_map(start, ("omega", "b"), grid={"omega": OMEGA, "b": B})


def _flags_agree(map_line: xr.Dataset, branch: xr.Dataset, parameter: str) -> int:
    """Compare the map's flags on one grid line with the branch; return points compared.

    Each found map point is matched to the branch point within half a grid cell of it
    whose motion (state at impact 0) is nearest; a map point whose motion is on no part
    of the branch (a sheet of the family reached around a fold from other grid lines) is
    not compared. Points within one grid cell of a special point are not compared.
    """
    axis = map_line[parameter].values
    cell = float(np.max(np.diff(axis)))
    special = [float(v) for lab, v in zip(branch["special_label"].values,
                                          branch[f"special_{parameter}"].values, strict=True)
               if lab in SPECIAL]
    lam = branch[parameter].values
    states = branch["state_k"].values[:, 0]
    compared = 0
    for k, value in enumerate(axis):
        if not map_line["found"].values[k] or any(abs(value - s) <= cell for s in special):
            continue
        near = np.flatnonzero(np.abs(lam - value) <= cell / 2)
        distance = np.max(np.abs(states[near] - map_line["state_k"].values[k, 0]), axis=1)
        if not distance.size or distance.min() > 0.05:
            continue
        point = int(near[np.argmin(distance)])
        for flag in ("stable", "physical"):
            assert bool(map_line[flag].values[k]) == bool(branch[flag].values[point]), (
                flag, parameter, value)
        compared += 1
    return compared


def test_map_agrees_with_the_branch_in_omega(start, sym_map):
    """The row b = 0.5 against the symmetric branch in omega through the start (its two
    BP and its GR): flags equal away from them, and the map is found through both
    pitchforks (the half system is regular there) with asymmetry exactly 0."""
    branch = ic.multi_impact_continuation(start, "omega", (0.8, 1.8), both_directions=True,
                                          ds_max=0.02)
    labels = branch["special_label"].values.tolist()
    assert labels.count("BP") == 2
    row = sym_map.sel(b=0.5)
    assert bool(row["found"].all())
    assert np.all(row["asymmetry"].values == 0.0)
    assert _flags_agree(row, branch, "omega") > 30
    # the stability flips at each BP, as the branch says
    for w in branch["special_omega"].values[branch["special_label"].values == "BP"]:
        left, right = row.sel(omega=w, method="ffill"), row.sel(omega=w, method="bfill")
        assert bool(left["stable"]) != bool(right["stable"])


def test_map_agrees_with_the_branch_in_b(start, sym_map):
    """The column omega = 1.4 against the symmetric branch in b (mirrored stops), which
    folds back at b = 0.533 (SN) and loses stability at a BP near b = 0.406."""
    omega = 1.4
    column = multi_impact_map(start, ("omega", "b"),
                              grid={"omega": [1.38, 1.4, 1.42], "b": np.linspace(0.3, 0.8, 51)})
    seed = ic.multi_impact_orbit(mirrored(omega, 0.5), 1, 2, start)
    branch = ic.multi_impact_continuation(seed, "b", (0.3, 0.8), both_directions=True,
                                          ds_max=0.02)
    assert branch.attrs.get("pattern") == start.pattern
    assert {"SN", "BP"} <= set(branch["special_label"].values.tolist())
    assert _flags_agree(column.sel(omega=omega), branch, "b") >= 15


def test_map_points_are_the_motions(sym_map):
    """Re-solved by the full shooting Newton, a map point has the map's spectral radius,
    velocities and flags (G = H^2 of the half system), and is symmetric."""
    for omega, b in ((1.6, 0.5), (0.9, 0.35), (1.15, 0.7), (1.75, 0.8)):
        point = sym_map.sel(omega=omega, b=b, method="nearest")
        orbit = multi_impact_map_orbit(sym_map, omega=omega, b=b)
        assert symmetry_defect(orbit) < 1e-8
        assert orbit.spectral_radius == pytest.approx(float(point["spectral_radius"]),
                                                      rel=1e-8)
        np.testing.assert_allclose(orbit.impact_velocities, point["impact_velocity_k"].values,
                                   rtol=0, atol=1e-9)
        assert orbit.stable == bool(point["stable"])
        assert orbit.physical == bool(point["physical"])


def test_simulator_reproduces_stable_points(sym_map):
    """At stable physical points, the simulator started on the map's stored motion (state
    and phase at impact 0) reproduces its impact times, velocities and stops."""
    stable = sym_map["stable"] & sym_map["physical"]
    assert int(stable.sum()) > 50
    for omega, b in ((1.6, 0.5), (1.75, 0.35), (0.85, 0.75)):
        point = sym_map.sel(omega=omega, b=b, method="nearest")
        assert bool(point["stable"]) and bool(point["physical"])
        osc = mirrored(float(point["omega"]), float(point["b"]))
        res = ic.simulate(osc, point["state_k"].values[0], float(point["delta"]), 10.0)
        assert res.success
        k = res.impact_times.size
        assert k >= 19
        reps = k // 2 + 1
        taus, v = point["flight_time_k"].values, point["impact_velocity_k"].values
        pattern = sym_map.attrs["pattern"]
        assert res.impact_stops == ((pattern[1:] + pattern[0]) * reps)[:k]
        np.testing.assert_allclose(res.impact_times, np.cumsum(np.tile(taus, reps))[:k],
                                   rtol=0, atol=1e-9)
        np.testing.assert_allclose(res.impact_velocities, np.tile(np.roll(v, -1), reps)[:k],
                                   rtol=0, atol=1e-9)


def test_closed_form_seed_covers_the_existence_region_of_its_root():
    """A 1-1 family seeded by the closed form on the paper's one-stop system: found exactly
    where its root of eq. (15) exists (the fold c^2 + s^2 = b^2 ends it), with the closed
    form's flags and spectral radius (stability_map, the batched closed form)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=0.6,
                              omega=1.0)
    physical = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    W, Bs = np.linspace(0.6, 1.6, 21), np.linspace(0.0, 1.2, 13)
    ds = multi_impact_map(physical, ("omega", "b"), grid={"omega": W, "b": Bs})
    assert "asymmetry" not in ds  # one stop: no symmetric motions
    closed = ic.stability_map(osc, 1, W, Bs).sel(N=1)
    found = ds["found"].values
    np.testing.assert_array_equal(found, closed["exists"].values)
    assert found.sum() > 100 and not found.all()
    # the root followed: the one with the map's phase
    phase = np.abs(np.angle(np.exp(1j * (closed["delta"].values - ds["delta"].values[..., None]))))
    root = np.argmin(np.where(np.isnan(phase), np.inf, phase), axis=-1)[..., None]
    for key in ("stable", "physical"):
        np.testing.assert_array_equal(
            np.take_along_axis(closed[key].values, root, -1)[..., 0][found], ds[key].values[found])
    rho = np.take_along_axis(closed["spectral_radius"].values, root, -1)[..., 0]
    np.testing.assert_allclose(ds["spectral_radius"].values[found], rho[found], rtol=1e-7)


def test_not_found_points_are_nan_and_seed_nothing():
    """Where the family does not exist Newton fails: those points are NaN, -1 iterations,
    neither stable nor physical; the seed record says where the family was started."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=0.6,
                              omega=1.0)
    physical = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    ds = multi_impact_map(physical, ("b", "omega"),
                          grid={"b": np.linspace(0.0, 1.2, 7), "omega": [0.9, 1.0, 1.1]})
    assert ds["found"].dims == ("b", "omega")
    lost = ~ds["found"].values
    assert lost.any()
    assert np.all(np.isnan(ds["spectral_radius"].values[lost]))
    assert np.all(np.isnan(ds["state_k"].values[lost]))
    assert np.all(ds["newton_iterations"].values[lost] == -1)
    assert not (ds["stable"].values[lost].any() or ds["physical"].values[lost].any())
    seed = json.loads(ds.attrs["seed"])
    assert seed["omega"] == 1.0 and seed["b"] == pytest.approx(0.6)


def test_round_trip(sym_map, tmp_path):
    path = ic.save(sym_map, tmp_path / "map.nc")
    back = ic.load(path)
    validate_multi_impact_map_dataset(back)
    xr.testing.assert_equal(back, sym_map)
    for key in ("N", "impacts", "pattern", "parameters", "symmetric", "seed", "oscillator"):
        assert back.attrs[key] == sym_map.attrs[key]


def test_plot(sym_map):
    import matplotlib

    matplotlib.use("Agg")
    from impactcont.plots.multi_maps import multi_impact_map_diagram, multi_map_regions

    codes = multi_map_regions(sym_map)
    assert set(np.unique(codes.values).tolist()) <= {0, 1, 2, 3}
    assert (codes.values == 3).sum() == int((sym_map["stable"] & sym_map["physical"]).sum())
    ax = multi_impact_map_diagram(sym_map)
    assert r"$\omega$" in ax.get_xlabel() and "$b$" in ax.get_ylabel()
    assert "seed" in [t.get_text() for t in ax.get_legend().get_texts()]
    matplotlib.pyplot.close(ax.figure)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"parameters": ("omega", "omega")}, "two different"),
    ({"parameters": ("omega", "zeta")}, "zeta"),
    ({"parameters": "omega"}, "two parameter names"),
    ({"grid": {"omega": [1.0, 1.1]}}, "grid must map"),
    ({"grid": {"omega": [1.1, 1.0], "b": [0.5]}}, "strictly increasing"),
    ({"grid": {"omega": [1.0, np.nan], "b": [0.5]}}, "finite"),
    ({"grid": {"omega": [-1.0, 1.0], "b": [0.5]}}, "omega"),
    ({"grid": {"omega": [1.6], "b": [-0.1, 0.5]}}, r"oscillator at \{'b': -0.1\}.*b > 0"),
    ({"tol": -1.0}, "tol"),
    ({"max_iter": 0}, "max_iter"),
    ({"symmetric": "yes"}, "symmetric"),
])
def test_bad_input(start, kwargs, match):
    args = {"parameters": ("omega", "b"), "grid": {"omega": [1.5, 1.6], "b": [0.5]}, **kwargs}
    with pytest.raises(ParameterError, match=match):
        multi_impact_map(start, **args)


def test_refusals(start):
    with pytest.raises(TypeError, match="start must be"):
        multi_impact_map("orbit", grid={"omega": [1.6], "b": [0.5]})
    unmirrored = ic.multi_impact_orbit(
        ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=0.5, omega=1.6,
                            stops=Stops(b_low=0.5, R_low=0.6)), 1, 2, start)
    with pytest.raises(ParameterError, match="break the symmetry"):
        multi_impact_map(unmirrored, grid={"omega": [1.6], "b": [0.5]}, symmetric=True)
    # in (omega, b) without mirrored stops the symmetric start is followed as any N-p motion
    ds = multi_impact_map(unmirrored, grid={"omega": [1.55, 1.6], "b": [0.5, 0.55]})
    assert ds.attrs["symmetric"] == 0 and "asymmetry" not in ds and bool(ds["found"].all())
    with pytest.raises(ParameterError, match="no motion"):
        multi_impact_map_orbit(ds.assign(found=ds["found"] & False), omega=1.6, b=0.5)
    assert math.isfinite(float(ds["spectral_radius"].sel(omega=1.6, b=0.5)))


def test_damping_matrix_flow_in_omega_and_forcing():
    """A dashpot on mass 1 only (the first-order flow), both parameters changing the flow
    (one flow per grid point): the map's points are the motions re-solved by Newton."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.6,
                              C=[[0.3, 0.0], [0.0, 0.0]], stops=Stops(b_low=0.5, R_low=0.6))
    start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    ds = multi_impact_map(start, ("omega", "F0"),
                          grid={"omega": np.linspace(1.6, 1.8, 5), "F0": [0.8, 1.0, 1.2]})
    assert ds.attrs["symmetric"] == 1 and json.loads(ds.attrs["options"])["flows"] == 15
    assert bool(ds["found"].all())
    for omega, F0 in ((1.6, 1.0), (1.8, 0.8), (1.7, 1.2)):
        orbit = multi_impact_map_orbit(ds, omega=omega, F0=F0)
        point = ds.sel(omega=omega, F0=F0, method="nearest")
        assert orbit.spectral_radius == pytest.approx(float(point["spectral_radius"]),
                                                      rel=1e-8)
        assert orbit.physical == bool(point["physical"])
        np.testing.assert_allclose(orbit.states, point["state_k"].values, rtol=0, atol=1e-9)
