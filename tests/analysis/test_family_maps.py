"""Stability maps of one N-p motion family over two parameters (``multi_impact_map``, the
sweep of :mod:`impactcont.analysis.family_maps`).

Independent witnesses: the branch through the same motion (``multi_impact_continuation``
in one parameter at a fixed value of the other: the stability and physical flags agree
except within one grid cell of a special point), the closed-form N-1 map
(``stability_map``: a 1-1 family seeded by the closed form covers the existence region
of its root with the same flags and spectral radius), and the event-driven simulator
(started on the map's stored motion at stable points, it reproduces its impacts).

Stability maps (``multi_impact_map``) of the machines of issue 21: an impact damper (a free
ball in the cavity of a primary mass: a symmetric clearance between masses, solved on its
half system), an impact pair on two springs (an asymmetric clearance between masses), a
constant force ``F_static`` (on wall stops and on a pair) and a free mass pushed by it (a
ball bouncing on the primary under gravity).

Independent witnesses: Newton (``multi_impact_orbit``) on oscillators built afresh from
their data at sampled grid points, the event-driven simulator started on a stable map
point, and the exact identity "a constant force on a system held by springs (K positive
definite) is the stops shifted by ``n . K^-1 F_static``": the map with the force and the
map without it over the shifted stops agree pointwise.
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.maps import multi_impact_map, multi_impact_map_orbit
from impactcont.dataset.maps import validate_multi_impact_map_dataset
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
    ds = multi_impact_map(physical, ("omega", "b"), grid={"omega": W, "b": Bs},
                          evaluator="shooting")
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
                          grid={"b": np.linspace(0.0, 1.2, 7), "omega": [0.9, 1.0, 1.1]},
                          evaluator="shooting")
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
    from impactcont.plots.maps import multi_impact_map_diagram, multi_map_regions

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


MU = 0.2  # mass ratio ball / primary


PAIR_K = [[2.0, -1.0], [-1.0, 2.0]]


# ------------------------------------------------------------------------------------------
# The machines, built afresh from their data (the witnesses never reuse the map's model)
# ------------------------------------------------------------------------------------------
def damper(omega: float = 1.5, b: float = 1.0, m2: float = MU) -> ic.ImpactOscillator:
    """Primary mass on a spring, a free ball of mass m2 in a cavity s = x2 - x1 in [-b, b]."""
    return ic.ImpactOscillator(M=np.diag([1.0, m2]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[1.0, 0.0], R=0.8, b=b, omega=omega, eta=0.05,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def pair(omega: float = 1.6, b: float = 0.5) -> ic.ImpactOscillator:
    """Two masses on springs with a clearance -0.4 < x2 - x1 < b."""
    return ic.ImpactOscillator(M=np.eye(2), K=PAIR_K, F=[1.0, 0.0], R=0.7, b=b, omega=omega,
                               eta=0.05, stops=Stops(mass=2, relative_to=1, b_low=0.4,
                                                     R_low=0.6))


def ball(omega: float = 1.6, F0: float = 1.0) -> ic.ImpactOscillator:
    """A free ball (mass MU) under gravity bouncing on a primary mass on a spring."""
    return ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                               F=[F0, 0.0], F_static=[0.0, -MU * 1.0], R=0.7, b=50.0,
                               omega=omega, eta=0.05,
                               stops=Stops(mass=2, relative_to=1, b_low=0.0, R_low=0.7))


def settled(osc: ic.ImpactOscillator, N: int, p: int, X0, periods: float, **kw):
    return ic.multi_impact_orbit(osc, N, p, ic.simulate(osc, np.asarray(X0, float), 0.0,
                                                        periods), **kw)


def resolved(ds, osc: ic.ImpactOscillator, point) -> ic.MultiImpactOrbit:
    """Newton on the fresh `osc` from what the map stored at `point`."""
    guess = {"delta": float(point["delta"]), "flight_times": point["flight_time_k"].values,
             "states": point["state_k"].values, "pattern": ds.attrs["pattern"]}
    return ic.multi_impact_orbit(osc, int(ds.attrs["N"]), int(ds.attrs["impacts"]), guess)


def assert_same_motion(ds, point, orbit: ic.MultiImpactOrbit) -> None:
    """The map's point is the motion Newton finds on a fresh oscillator: the map solves to
    tol = 1e-11 relative, so states and flight times agree to 1e-8 and the spectral radius
    to 1e-7 (G's sensitivity); flags agree away from rho = 1."""
    assert orbit.pattern == ds.attrs["pattern"]
    np.testing.assert_allclose(orbit.states, point["state_k"].values, rtol=0, atol=1e-8)
    np.testing.assert_allclose(orbit.flight_times, point["flight_time_k"].values, rtol=0,
                               atol=1e-8)
    np.testing.assert_allclose(orbit.impact_velocities, point["impact_velocity_k"].values,
                               rtol=0, atol=1e-8)
    rho = float(point["spectral_radius"])
    assert orbit.spectral_radius == pytest.approx(rho, rel=1e-7)
    if abs(rho - 1.0) > 1e-6:
        assert orbit.stable == bool(point["stable"])
    assert orbit.physical == bool(point["physical"])
    assert ("interior contact not checked" in orbit.reason) == (
        not bool(point["contact_checked"]))


def assert_simulated(ds, point, osc: ic.ImpactOscillator, periods: float = 10.0) -> None:
    """The simulator started on the map's stored motion stays on it (stops, times, states)."""
    assert bool(point["stable"]) and bool(point["physical"])
    res = ic.simulate(osc, point["state_k"].values[0], float(point["delta"]), periods)
    assert res.success
    pattern, p = ds.attrs["pattern"], int(ds.attrs["impacts"])
    k = res.impact_times.size
    assert k >= p * (periods - 1) / int(ds.attrs["N"])
    reps = k // p + 1
    assert res.impact_stops == ((pattern[1:] + pattern[0]) * reps)[:k]
    np.testing.assert_allclose(res.impact_times,
                               np.cumsum(np.tile(point["flight_time_k"].values, reps))[:k],
                               rtol=0, atol=1e-8)
    states = np.roll(point["state_k"].values, -1, axis=0)
    np.testing.assert_allclose(res.impact_states, np.tile(states, (reps, 1))[:k], rtol=0,
                               atol=1e-7)


def sample(ds, where) -> list:
    return [ds.sel(where_k, method="nearest") for where_k in where]


# ------------------------------------------------------------------------------------------
# The impact damper: a symmetric clearance between masses, a free mass
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def damper_map():
    start = settled(damper(), 1, 2, [0.0, 0.0, 0.0, 1.0], 150.0)
    return multi_impact_map(start, ("omega", "b"), grid={"omega": np.linspace(1.2, 1.8, 7),
                                                         "b": np.linspace(0.6, 1.4, 9)})


def test_impact_damper_map_points_are_the_motions_of_fresh_oscillators(damper_map):
    ds = damper_map
    assert ds.attrs["symmetric"] == 1  # mirrored cavity: solved on the half system
    assert bool(ds["found"].all()) and bool(ds["contact_checked"].all())
    stable = ds["stable"] & ds["physical"]
    assert 0 < int(stable.sum()) < ds["found"].size  # stable and unstable motions
    assert float(np.abs(ds["asymmetry"]).max()) == 0.0
    for point in sample(ds, [{"omega": 1.2, "b": 0.6}, {"omega": 1.8, "b": 1.4},
                             {"omega": 1.5, "b": 1.0}, {"omega": 1.3, "b": 1.3},
                             {"omega": 1.7, "b": 0.7}]):
        orbit = resolved(ds, damper(float(point["omega"]), float(point["b"])), point)
        assert_same_motion(ds, point, orbit)
        assert symmetry_defect(orbit) < 1e-8
        # two-body law: the stop coordinate x2 - x1 sits on +-b at every impact
        s = orbit.states[:, 1] - orbit.states[:, 0]
        np.testing.assert_allclose(np.abs(s), float(point["b"]), rtol=0, atol=1e-12)


def test_impact_damper_stable_map_point_stays_under_simulation(damper_map):
    point = damper_map.sel(omega=1.6, b=1.3, method="nearest")
    assert_simulated(damper_map, point, damper(float(point["omega"]), float(point["b"])))


def test_impact_damper_map_over_the_mass_ratio_uses_each_masses_impact_law():
    """A map over (omega, m2): the two-body impact law of the cavity depends on the masses,
    so each grid value of m2 has its own impact matrices; points re-solved on fresh
    oscillators with that ball mass."""
    start = settled(damper(), 1, 2, [0.0, 0.0, 0.0, 1.0], 150.0)
    ds = multi_impact_map(start, ("omega", "m2"), grid={"omega": np.linspace(1.4, 1.6, 3),
                                                        "m2": np.linspace(0.1, 0.4, 4)})
    assert ds.attrs["symmetric"] == 1 and bool(ds["found"].all())
    for point in sample(ds, [{"omega": 1.4, "m2": 0.1}, {"omega": 1.6, "m2": 0.4},
                             {"omega": 1.5, "m2": 0.3}]):
        osc = damper(float(point["omega"]), m2=float(point["m2"]))
        assert_same_motion(ds, point, resolved(ds, osc, point))


def test_map_without_contact_checks_says_so_and_is_never_physical():
    """checks=False: every found point is 'interior contact not checked' (contact_checked
    False, its own region), never physical; the multipliers are still those of the motion."""
    from impactcont.plots.maps import multi_map_regions

    start = settled(damper(), 1, 2, [0.0, 0.0, 0.0, 1.0], 150.0)
    grid = {"omega": np.linspace(1.4, 1.6, 3), "b": np.linspace(0.9, 1.1, 3)}
    ds = multi_impact_map(start, ("omega", "b"), grid=grid, checks=False)
    assert bool(ds["found"].all())
    assert not bool(ds["contact_checked"].any()) and not bool(ds["physical"].any())
    assert bool(np.isnan(ds["gap_min"]).all())
    assert bool((multi_map_regions(ds) == 4).all())
    checked = multi_impact_map(start, ("omega", "b"), grid=grid)
    np.testing.assert_allclose(ds["spectral_radius"], checked["spectral_radius"], rtol=1e-12)
    assert bool(checked["contact_checked"].all())


# ------------------------------------------------------------------------------------------
# An impact pair on two springs: an asymmetric clearance between masses
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pair_map():
    start = settled(pair(), 1, 1, [0.0, 0.0, 0.0, 0.5], 200.0)
    return multi_impact_map(start, ("omega", "b"), grid={"omega": np.linspace(1.3, 1.9, 7),
                                                         "b": np.linspace(0.3, 0.7, 9)})


def test_impact_pair_map_points_are_the_motions_of_fresh_oscillators(pair_map):
    ds = pair_map
    assert ds.attrs["symmetric"] == 0 and "asymmetry" not in ds
    assert bool(ds["found"].all()) and bool(ds["contact_checked"].all())
    physical = ds["physical"]
    assert 0 < int(physical.sum()) < physical.size  # the upper stop is crossed at small b
    for point in sample(ds, [{"omega": 1.3, "b": 0.3}, {"omega": 1.9, "b": 0.7},
                             {"omega": 1.6, "b": 0.5}, {"omega": 1.4, "b": 0.65},
                             {"omega": 1.8, "b": 0.35}]):
        orbit = resolved(ds, pair(float(point["omega"]), float(point["b"])), point)
        assert_same_motion(ds, point, orbit)


def test_impact_pair_stable_map_point_stays_under_simulation(pair_map):
    point = pair_map.sel(omega=1.5, b=0.65, method="nearest")
    assert_simulated(pair_map, point, pair(float(point["omega"]), float(point["b"])))


# ------------------------------------------------------------------------------------------
# A constant force: the shifted-stops identity, pointwise over the map
# ------------------------------------------------------------------------------------------
FS = np.array([0.2, -0.1])


def backlash(omega: float, b: float, force: bool) -> ic.ImpactOscillator:
    """Stops on mass 1 at x1 = b and x1 = -b_low; with the force, or shifted by x_s1."""
    shift = 0.0 if force else np.linalg.solve(K2, FS)[0]
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               eta=0.1, F_static=FS if force else [0.0, 0.0],
                               stops=Stops(b_low=0.5 + shift, R_low=0.6))


def loaded_pair(omega: float, b: float, force: bool) -> ic.ImpactOscillator:
    """The pair with one stop x2 - x1 = b, under F_static or without it."""
    return ic.ImpactOscillator(M=np.eye(2), K=PAIR_K, F=[1.0, 0.0], R=0.7, b=b, omega=omega,
                               eta=0.05, F_static=FS if force else [0.0, 0.0],
                               stops=Stops(mass=2, relative_to=1))


MACHINES = {
    # build, K, stop normal, (N, p, X0, periods), omega grid, b grid (with the force)
    "wall stops": (backlash, K2, [1.0, 0.0], (1, 2, [0.0] * 4, 150.0),
                   np.linspace(1.5, 1.7, 5), np.linspace(0.4, 0.6, 5)),
    "pair clearance": (loaded_pair, PAIR_K, [-1.0, 1.0], (1, 1, [0.0, 0.0, 0.0, 0.5], 200.0),
                       np.linspace(1.5, 1.7, 5), np.linspace(0.4, 0.6, 5)),
}


@pytest.mark.parametrize("machine", MACHINES)
def test_constant_force_map_equals_the_shifted_stops_map(machine):
    """K positive definite: F_static displaces every motion by x_s = K^-1 F_static, which is
    the system without it with the stops moved by -n . x_s. The map with the force over b
    and the map without it over b - n . x_s agree pointwise (exact identity; to Newton's
    tolerance)."""
    build, K, normal, (N, p, X0, periods), omegas, bs = MACHINES[machine]
    xs = np.linalg.solve(K, FS)
    shift = float(np.dot(normal, xs))
    offset = np.append(xs, [0.0, 0.0])
    ref_start = settled(build(1.6, 0.5 - shift, False), N, p, X0, periods)
    guess = {"delta": ref_start.delta, "flight_times": ref_start.flight_times,
             "states": ref_start.states + offset, "pattern": ref_start.pattern}
    start = ic.multi_impact_orbit(build(1.6, 0.5, True), N, p, guess)
    ds = multi_impact_map(start, ("omega", "b"), grid={"omega": omegas, "b": bs})
    ref = multi_impact_map(ref_start, ("omega", "b"), grid={"omega": omegas, "b": bs - shift})
    assert ds.attrs["symmetric"] == 0 and ref.attrs["symmetric"] == 0
    found = ds["found"].values
    assert found.sum() >= 0.8 * found.size
    np.testing.assert_array_equal(found, ref["found"].values)
    np.testing.assert_allclose(ds["state_k"].values[found], ref["state_k"].values[found]
                               + offset, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(ds["physical"].values, ref["physical"].values)
    assert int(ds["physical"].sum()) > 0
    rho, rho_ref = ds["spectral_radius"].values, ref["spectral_radius"].values
    np.testing.assert_allclose(rho[found], rho_ref[found], rtol=1e-7)
    away = found & (np.abs(rho_ref - 1.0) > 1e-6)
    np.testing.assert_array_equal(ds["stable"].values[away], ref["stable"].values[away])
    np.testing.assert_allclose(ds["flight_time_k"].values[found],
                               ref["flight_time_k"].values[found], rtol=0, atol=1e-8)
    np.testing.assert_allclose(ds["gap_min"].values[found], ref["gap_min"].values[found],
                               rtol=0, atol=1e-8)
    # and a point re-solved on a fresh oscillator with the force
    point = ds.sel(omega=1.65, b=0.45, method="nearest")
    assert_same_motion(ds, point, resolved(ds, build(float(point["omega"]),
                                                     float(point["b"]), True), point))


# ------------------------------------------------------------------------------------------
# A free mass pushed by the constant force: a ball bouncing on the primary under gravity
# ------------------------------------------------------------------------------------------
def test_free_mass_under_a_constant_force_map_says_what_it_checked():
    """Every found point's physical flag and contact check are those of multi_impact_orbit on
    a fresh oscillator: a point whose interior contact is not checked (a free mode pushed by
    F_static) is never physical, and says so (contact_checked False)."""
    # the run chatters onto the primary and rides it each period (its seed reads 'l'): the
    # plain 1-1 motion is seeded by the last two impacts as they are
    run = ic.simulate(ball(), np.array([0.0, 0.1, 0.0, 0.5]), 0.0, 300.0)
    guess = {"delta": float(run.impact_phases[-2]), "states": run.impact_states[-2:-1],
             "flight_times": np.diff(run.impact_times[-2:]), "pattern": "L"}
    start = ic.multi_impact_orbit(ball(), 1, 1, guess, pattern="L")
    assert start.physical and start.pattern == "L"
    ds = multi_impact_map(start, ("omega", "F0"), grid={"omega": np.linspace(1.5, 1.7, 3),
                                                        "F0": np.linspace(0.9, 1.1, 3)})
    assert bool(ds["found"].all())
    assert not bool((ds["physical"] & ~ds["contact_checked"]).any())
    for point in sample(ds, [{"omega": 1.5, "F0": 0.9}, {"omega": 1.7, "F0": 1.1}]):
        orbit = resolved(ds, ball(float(point["omega"]), float(point["F0"])), point)
        assert_same_motion(ds, point, orbit)


# -- a map written to a file: out=, or larger than memory_limit; Ctrl-C kept (issue 31) -----
_PAPER_FAMILY = {"omega": np.linspace(1.0, 1.4, 9), "b": np.linspace(0.1, 0.5, 7)}


@pytest.fixture(scope="module")
def closed_form_start():
    """An N-1 motion of the closed form, mapped by shooting (evaluator="shooting") in the
    tests of the sweep's files and interrupts."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.3, omega=1.2,
                              eta=0.1)
    return next(o for o in ic.periodic_orbits(osc, 1) if o.physical and o.stable)


@pytest.fixture(scope="module")
def family_in_memory(closed_form_start):
    return multi_impact_map(closed_form_start, ("omega", "b"), _PAPER_FAMILY, rows_per_task=2,
                            evaluator="shooting")


def test_a_map_written_to_a_file_equals_the_map_in_memory(closed_form_start, family_in_memory,
                                                         tmp_path, caplog):
    pytest.importorskip("dask")
    lazy = multi_impact_map(closed_form_start, ("omega", "b"), _PAPER_FAMILY, rows_per_task=2,
                            out=tmp_path / "family.nc", evaluator="shooting")
    assert hasattr(lazy["found"].data, "dask")  # nothing read yet
    xr.testing.assert_identical(lazy.load().drop_attrs(), family_in_memory.drop_attrs())
    assert json.loads(lazy.attrs["options"])["tasks"] == 5  # the sweeps' counts, at the end
    lazy.close()
    xr.testing.assert_identical(ic.load(tmp_path / "family.nc").drop_attrs(),
                                family_in_memory.drop_attrs())
    # larger than memory_limit: a temporary file (it was refused before any work)
    with caplog.at_level("WARNING"):
        lazy = multi_impact_map(closed_form_start, ("omega", "b"), _PAPER_FAMILY,
                                rows_per_task=2, memory_limit=1e3, evaluator="shooting")
    path = Path(lazy.encoding["source"])
    assert f"it is written to {path}" in caplog.text and path.is_file()
    xr.testing.assert_identical(lazy.load().drop_attrs(), family_in_memory.drop_attrs())
    lazy.close()
    assert not path.exists()


def _interrupted_after(k: int, real, *args):
    _interrupted_after.calls += 1
    if _interrupted_after.calls == k:
        raise KeyboardInterrupt
    return real(*args)


def test_ctrl_c_keeps_a_map_written_to_a_file_as_the_map_in_memory(closed_form_start,
                                                                  family_in_memory,
                                                                  monkeypatch, tmp_path):
    pytest.importorskip("dask")
    from impactcont.analysis import family_maps

    real = family_maps._band_task
    monkeypatch.setattr(family_maps, "_band_task",
                        functools.partial(_interrupted_after, 3, real))
    _interrupted_after.calls = 0
    in_memory = multi_impact_map(closed_form_start, ("omega", "b"), _PAPER_FAMILY,
                                 rows_per_task=2, evaluator="shooting")
    _interrupted_after.calls = 0
    target = tmp_path / "family.nc"
    lazy = multi_impact_map(closed_form_start, ("omega", "b"), _PAPER_FAMILY, rows_per_task=2,
                            out=target, evaluator="shooting")
    assert [p.name for p in tmp_path.iterdir()] == ["family.nc"]  # no temporary left
    kept = lazy.load()
    lazy.close()
    assert kept.attrs["interrupted"] == 1 and kept.attrs["points_computed"] == 2 * 2 * 7
    xr.testing.assert_identical(kept.drop_attrs(), in_memory.drop_attrs())
    computed = kept["computed"]
    xr.testing.assert_identical(kept.drop_vars("computed").where(computed).drop_attrs(),
                                family_in_memory.where(computed).drop_attrs())
    assert not kept["found"].where(~computed, False).any()
    assert ic.load(target).attrs["interrupted"] == 1


# -- motions with sticking phases ----------------------------------------------------------
def riding_damper(omega: float = 2.3, b: float = 0.3, eta: float = 0.3) -> ic.ImpactOscillator:
    """The impact damper of studies/sticking_motions: primary 1 on spring 1, plastic ball
    0.2 in |x2 - x1| <= b."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=b, omega=omega, eta=eta,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


@pytest.fixture(scope="module")
def riding_start():
    """The ball riding each wall (pattern 'lu' or 'ul'), from its simulated steady state."""
    osc = riding_damper()
    amplitude = 1.0 / (1.0 - 1.2 * osc.omega**2 + 1j * osc.C[0, 0] * osc.omega)
    x1, v1 = amplitude.real, (1j * osc.omega * amplitude).real
    res = ic.simulate(osc, np.array([x1, x1 + osc.b, v1, v1]), 0.0, 16.0)
    return ic.multi_impact_orbit(osc, 1, 2, res)


def test_a_sticky_map_without_omega_is_newton_on_the_branch_problem(riding_start):
    """A pair without omega, (b, eta): each problem's flows built anew (no cheap flow at a
    new omega). Each point is the motion multi_impact_orbit solves alone on the oscillator
    with both values set (a solve from the simulated start, not from a neighbour) to 1e-9,
    the stick times and the release phases (the impact phase plus omega times the stick)
    included."""
    grid = {"b": np.linspace(0.28, 0.32, 3), "eta": np.linspace(0.28, 0.32, 3)}
    ds = multi_impact_map(riding_start, ("b", "eta"), grid=grid)
    assert ds["found"].all() and ds["physical"].all() and ds.attrs["pattern"] == \
        riding_start.pattern
    assert (ds["reason"] == 0).all()
    # a Newton solve at every point; at (0.3, 0.3), the start's own oscillator, the start may
    # already meet the tolerance (0 iterations on some processors, 1 on others)
    iterations = ds["newton_iterations"].transpose("b", "eta").values.ravel()
    assert (np.delete(iterations, 4) > 0).all()  # all but the centre (b, eta) = (0.3, 0.3)
    for b, eta in ((0.28, 0.32), (0.32, 0.28)):
        point = ds.sel(b=b, eta=eta)
        alone = ic.multi_impact_orbit(riding_damper(b=b, eta=eta), 1, 2, riding_start)
        assert alone.pattern == riding_start.pattern
        assert point["stick_time_k"].values == pytest.approx(alone.stick_times, abs=1e-9)
        assert point["flight_time_k"].values == pytest.approx(alone.flight_times, abs=1e-9)
        assert point["state_k"].values == pytest.approx(alone.states, abs=1e-9)
        release = alone.phases + 2.3 * alone.stick_times
        assert np.abs(np.remainder(point["release_phase_k"].values - release + np.pi,
                                   2 * np.pi) - np.pi).max() < 1e-9
        assert float(point["spectral_radius"]) == pytest.approx(alone.spectral_radius,
                                                                abs=1e-9)
        assert float(point["stick_time_min"]) == pytest.approx(min(alone.stick_times),
                                                               abs=1e-9)


def test_a_sticky_map_reason_names_the_sticking_phase_and_the_plain_checks(riding_start):
    """Past the end of the ride (omega beyond 2.3934 at b = 0.3) the reason is the stick
    that ended, and nothing else: the found points that are not physical are exactly those
    with a negative stick; without the contact search every found point is "not checked"
    (never physical), the stick ended added where it did."""
    grid = {"b": np.array([0.3]), "omega": np.linspace(2.36, 2.44, 5)}
    ds = multi_impact_map(riding_start, ("b", "omega"), grid=grid)
    ended = ds["stick_time_min"].values <= 0
    assert ended.any() and not ended.all()
    assert np.array_equal(ds["reason"].values, np.where(ended, 1, 0))
    assert np.array_equal(ds["physical"].values, ~ended)
    unchecked = multi_impact_map(riding_start, ("b", "omega"), grid=grid, checks=False)
    assert not unchecked["physical"].any() and not unchecked["contact_checked"].any()
    assert np.array_equal(unchecked["reason"].values, np.where(ended, 1 | 64, 64))


def test_a_sticky_map_in_bands_is_the_one_sweep(riding_start):
    """rows_per_task=1 (each row of b a task from the spine on the seed's column) finds what
    the one sweep finds, to the Newton tolerance."""
    grid = {"b": np.linspace(0.28, 0.32, 3), "omega": np.linspace(2.25, 2.35, 3)}
    one = multi_impact_map(riding_start, ("b", "omega"), grid=grid)
    bands = multi_impact_map(riding_start, ("b", "omega"), grid=grid, rows_per_task=1)
    assert json.loads(bands.attrs["options"])["tasks"] == 3
    assert np.array_equal(one["found"].values, bands["found"].values)
    np.testing.assert_allclose(bands["stick_time_k"].values, one["stick_time_k"].values,
                               atol=1e-9, rtol=0)


def test_a_sticky_map_refuses_the_half_system_and_a_bad_symmetric(riding_start):
    grid = {"b": np.array([0.3]), "omega": np.array([2.3])}
    with pytest.raises(ParameterError, match="symmetric=True: the motion has sticking"):
        multi_impact_map(riding_start, ("b", "omega"), grid=grid, symmetric=True)
    with pytest.raises(ParameterError, match="symmetric must be True, False or None"):
        multi_impact_map(riding_start, ("b", "omega"), grid=grid, symmetric="yes")


def test_ctrl_c_and_a_file_keep_a_sticky_map_as_every_map(riding_start, monkeypatch, tmp_path):
    """A sticky map written to a file (out=) equals the one in memory, its sticky
    variables included; a Ctrl-C at its third band returns the two bands done, marked
    (interrupted, computed), the rest not found, with its sticky variables NaN there."""
    pytest.importorskip("dask")
    from impactcont.analysis import family_maps

    grid = {"b": np.linspace(0.28, 0.32, 4), "omega": np.linspace(2.25, 2.35, 3)}
    in_memory = multi_impact_map(riding_start, ("b", "omega"), grid=grid, rows_per_task=1)
    lazy = multi_impact_map(riding_start, ("b", "omega"), grid=grid, rows_per_task=1,
                            out=tmp_path / "sticky.nc")
    on_disk = lazy.load()
    lazy.close()
    xr.testing.assert_identical(on_disk.drop_attrs(), in_memory.drop_attrs())
    real = family_maps._band_task
    monkeypatch.setattr(family_maps, "_band_task",
                        functools.partial(_interrupted_after, 3, real))
    _interrupted_after.calls = 0
    kept = multi_impact_map(riding_start, ("b", "omega"), grid=grid, rows_per_task=1)
    assert kept.attrs["interrupted"] == 1 and kept.attrs["points_computed"] == 2 * 3
    computed = kept["computed"].values
    assert computed.sum() == 6
    assert not kept["found"].values[~computed].any()
    assert np.isnan(kept["stick_time_min"].values[~computed]).all()
    np.testing.assert_array_equal(kept["stick_time_k"].values[computed],
                                  in_memory["stick_time_k"].values[computed])
