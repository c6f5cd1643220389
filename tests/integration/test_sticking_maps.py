"""Stability maps of motions with sticking phases (issue 30: "maps of where each kind of
motion exists"): ``ic.stability_map`` of a sticky motion follows its family over the grid
through the branch problem of its pattern, and says at each point why a motion found is
not physical. Witnessed by the closed forms of ``studies/sticking_motions/closed_form.py``
(mpmath, imports nothing from the package): the riding impact damper (pattern ``"lu"``)
and the preloaded one-mass oscillator (``"u"``, released at ``arccos(-F_static / F)``).

About 40 s: each closed-form motion of the damper about 1 s, each end of its ride
(``riding_end``) about 5 s.
"""

from __future__ import annotations

import functools
import json
import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.family_maps import multi_impact_map_orbit
from impactcont.dataset.maps import MAP_REASONS, STICKY_MAP_VARIABLES
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.plots.maps import multi_impact_map_diagram, multi_map_regions
from tests._study_files import study_file

#: The damper's map: the gap b (rows) by omega (columns) across the end of the ride.
GAPS = np.array([0.29, 0.3])
OMEGAS = np.linspace(2.2, 2.5, 16)  # step 0.02
#: The preloaded oscillator's map: omega by the forcing amplitude F[1] (F_static = 1).
PRELOADED_OMEGAS = np.linspace(0.6, 1.0, 11)
AMPLITUDES = np.linspace(1.5, 5.0, 6)


@pytest.fixture(scope="module")
def cf():
    with study_file("sticking_motions", "closed_form.py") as module:
        yield module


def damper(omega: float, b: float = 0.3) -> ic.ImpactOscillator:
    """Case (c) of the study: primary 1 on spring 1 (eta 0.3), plastic ball 0.2 in
    |x2 - x1| <= b."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=b, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


@functools.cache
def riding(omega: float = 2.3) -> ic.MultiImpactOrbit:
    osc = damper(omega)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 16.0))


@functools.cache
def riding_map(**options):
    return ic.stability_map(riding(), parameters=("b", "omega"),
                            grid={"b": GAPS, "omega": OMEGAS}, **options)


def preloaded(omega: float) -> ic.ImpactOscillator:
    """Case (a): one mass pushed into its stop b = 0 by F_static = 1, forced 3 cos."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                               omega=omega, eta=0.05)


@functools.cache
def preloaded_map():
    osc = preloaded(0.8)
    start = ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, [0.0, 0.0], 0.0, 3.0),
                                  pattern="u")
    return ic.stability_map(start, parameters=("omega", "F[1]"),
                            grid={"omega": PRELOADED_OMEGAS, "F[1]": AMPLITUDES})


def closed_form(cf, omega: float, b: float):
    """The closed form of the riding motion at (omega, b), followed from omega 2.2 in steps
    of at most 0.05, each solved from the release of the one before (its default start,
    the forced response, misses the motion near the end of the ride)."""
    motion = cf.riding_damper_motion(2.2, b=repr(b))
    steps = max(1, math.ceil((omega - 2.2) / 0.05 - 1e-9))
    for w in np.linspace(2.2, omega, steps + 1)[1:]:
        motion = cf.riding_damper_motion(float(w), b=repr(b), guess=cf.release_guess(motion))
    return motion


def wrapped_difference(a, b) -> np.ndarray:
    return np.abs(np.remainder(np.asarray(a) - np.asarray(b) + np.pi, 2 * np.pi) - np.pi)


def test_the_riding_damper_map_is_the_closed_form_at_grid_points(cf):
    """At three grid points the map's stick times, release phases, flight times and states
    are the closed form's to 1e-9 (the Newton tolerance 1e-11 on unknowns of order 1)."""
    ds = riding_map()
    assert ds.attrs["pattern"] in ("lu", "ul") and ds["found"].all()
    for b, omega in ((0.3, 2.2), (0.3, 2.36), (0.29, 2.3)):
        point = ds.sel(b=b, omega=omega, method="nearest")
        motion = closed_form(cf, float(point.omega), float(point.b)).rotated(
            ds.attrs["pattern"])
        assert point["stick_time_k"].values == pytest.approx(motion.floats("stick_times"),
                                                             abs=1e-9)
        assert wrapped_difference(point["release_phase_k"].values,
                                  motion.floats("release_phases")).max() < 1e-9
        assert point["flight_time_k"].values == pytest.approx(motion.floats("flight_times"),
                                                              abs=1e-9)
        assert point["state_k"].values == pytest.approx(
            np.array(motion.floats("landing_states")), abs=1e-9)
        assert point["pressing_min_k"].values == pytest.approx(
            motion.floats("pressing_min"), abs=1e-9)
        assert float(point["stick_time_min"]) == pytest.approx(min(
            motion.floats("stick_times")), abs=1e-9)
        assert bool(point["physical"]) and bool(point["stable"])


def test_the_riding_damper_map_ends_its_rides_where_the_closed_form_does(cf):
    """Each row of b: the points found turn from physical into "stick ended" (the SE side,
    reason bit stick_ended, stick_time_min < 0) once, between the two grid values of omega
    around the closed form's end of the ride (riding_end), within one grid step of it."""
    ds = riding_map()
    step = OMEGAS[1] - OMEGAS[0]
    for b in GAPS:
        row = ds.sel(b=b)
        ended = (row["reason"].values & MAP_REASONS["stick_ended"]) != 0
        assert np.array_equal(ended, row["stick_time_min"].values <= 0)
        assert np.array_equal(ended, ~row["physical"].values)
        j = int(np.argmax(ended))
        assert j > 0 and ended[j:].all() and not ended[:j].any()
        guess = closed_form(cf, 2.3, float(b))
        end = float(cf.riding_end(guess, b=repr(float(b)))[0])
        assert OMEGAS[j - 1] < end <= OMEGAS[j]
        assert abs(end - 0.5 * (OMEGAS[j - 1] + OMEGAS[j])) <= step
        # the smallest pressing force (RG's test) falls through 0 at the same place: the
        # landing there is a release
        assert (row["pressing_min"].values[:j] > 0).all()
        assert (row["pressing_min"].values[j:] < 0).all()


def test_the_preloaded_oscillator_map_releases_at_the_closed_forms_phase(cf):
    """The map in (omega, F) of the preloaded oscillator ("u"): found everywhere, released
    at arccos(-F_static / F) to 1e-9 at every point, and at two points the closed form's
    stick time and flight time; every multiplier is zero (the stick forgets the past)."""
    ds = preloaded_map()
    assert ds.attrs["pattern"] == "u" and ds["found"].all() and ds["physical"].all()
    release = np.arccos(-1.0 / AMPLITUDES)
    assert wrapped_difference(ds["release_phase_k"].values[:, :, 0],
                              release[None, :]).max() < 1e-9
    assert float(ds["spectral_radius"].max()) < 1e-12 and ds["stable"].all()
    for omega, amplitude in ((0.7, 3.0), (1.0, 5.0)):
        point = ds.sel({"omega": omega, "F[1]": amplitude}, method="nearest")
        motion = cf.preloaded_motion(float(point.omega), F=repr(float(point["F[1]"])))
        assert point["stick_time_k"].values == pytest.approx(motion.floats("stick_times"),
                                                             abs=1e-9)
        assert point["flight_time_k"].values == pytest.approx(motion.floats("flight_times"),
                                                              abs=1e-9)
        assert float(point["pressing_min"]) == pytest.approx(
            motion.floats("pressing_min")[0], abs=1e-9)


def test_a_sticky_map_round_trips_and_re_solves_a_point(tmp_path):
    """NetCDF round trip of every sticky variable (the reason's CF flag attributes kept);
    multi_impact_map_orbit re-solves a grid point from the map into the same motion."""
    ds = riding_map()
    for key, spec in STICKY_MAP_VARIABLES.items():
        assert ds[key].dims[:2] == ("b", "omega") and ds[key].attrs["long_name"] == \
            spec.long_name, key
    back = ic.load(ic.save(ds, tmp_path / "riding_map.nc"))
    for key in STICKY_MAP_VARIABLES:
        assert np.array_equal(back[key].values, ds[key].values, equal_nan=True), key
    assert back["reason"].attrs["flag_meanings"].split() == list(MAP_REASONS)
    assert list(back["reason"].attrs["flag_masks"]) == list(MAP_REASONS.values())
    orbit = multi_impact_map_orbit(back, b=0.3, omega=2.3)
    point = ds.sel(b=0.3, omega=2.3, method="nearest")
    assert orbit.pattern == ds.attrs["pattern"]
    assert orbit.stick_times == pytest.approx(point["stick_time_k"].values, abs=1e-10)


def test_a_sticky_map_on_a_process_pool_is_the_serial_map():
    """The same map by two workers, a task per row (rows_per_task=1), equals the serial
    one with the same bands: the sweep runs as the MapRunner's tasks."""
    serial = riding_map(rows_per_task=1)
    pooled = riding_map(rows_per_task=1, executor="process", max_workers=2)
    for key in ("found", "physical", "stable", "reason", "stick_time_k", "release_phase_k"):
        assert np.array_equal(pooled[key].values, serial[key].values, equal_nan=True), key
    assert json.loads(pooled.attrs["options"])["executor"].startswith("process")


def test_the_sticky_map_draws_its_reasons():
    """The figure shades the SE side as its own region, named in the legend."""
    ds = riding_map()
    regions = multi_map_regions(ds).values
    ended = (ds["reason"].values & MAP_REASONS["stick_ended"]) != 0
    assert np.array_equal(regions == 5, ended) and set(np.unique(regions)) == {3, 5}
    ax = multi_impact_map_diagram(ds)
    legend = ax.get_legend() or ax.figure.legends[0]
    assert "found, not physical: a stick ended (SE side)" in [t.get_text()
                                                               for t in legend.get_texts()]
    plt.close(ax.figure)


def test_refusals_of_a_sticky_map():
    """symmetric=True (the half system solves no sticking phases) and a parameter that
    changes the restitution of the stop the ball sticks on are refused, naming them."""
    with pytest.raises(ParameterError, match="symmetric=True"):
        ic.stability_map(riding(), parameters=("b", "omega"),
                         grid={"b": GAPS, "omega": OMEGAS}, symmetric=True)
    with pytest.raises(ParameterError, match="restitution"):
        ic.stability_map(riding(), parameters=("R", "omega"),
                         grid={"R": [0.0, 0.1], "omega": OMEGAS})


def test_a_chatter_bounce_reaching_another_stop_has_its_own_reason():
    """The riding damper with an elastic ball (R = 0.3: each stick entered through complete
    chatter, pattern "lu") at omega 0.2, under a stop A on the primary (x1 <= 1.04) that
    the first bounce of the upper wall's chatter crosses while the flights and the rides
    stay below it (the solved riding motion's bounces never reach the other wall: the
    landing's speed comes from the flight across the clearance). The map over (omega, b)
    flags those points bounce_reaches_stop (and interior_contact: the bounce's clearance is
    the motion's gap_min), not "other"; exactly where the re-solved motion names the bounce
    reaching A. Witness: the simulator from the chatter's first
    bounce hits A before it returns to the upper wall there, and the wall where the bit is
    clear."""
    osc = damper(0.2).replace(R=0.3)
    ride = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 12.0))
    capped = ic.ImpactOscillator(M=osc.M, K=osc.K, F=[1.0, 0.0], R=0.3, b=0.3, omega=0.2,
                                 eta=0.3, stops=Stops(mass=2, relative_to=1, mirror=True,
                                                      extra=(ic.Stop("A", mass=1, gap=1.04,
                                                                     restitution=0.5),)))
    start = ic.multi_impact_orbit(capped, 1, 2, ride)
    assert start.pattern == "lu" and not start.physical
    ds = ic.stability_map(start, parameters=("omega", "b"),
                          grid={"omega": [0.19, 0.2, 0.21], "b": [0.25, 0.3, 0.35]})
    bit = MAP_REASONS["bounce_reaches_stop"]
    found = ds["found"].values
    bounced = found & ((ds["reason"].values & bit) != 0)
    assert bounced.any() and ds["physical"].values.any()
    # the bounce's clearance is also the motion's gap_min (GR sees it): interior_contact,
    # never "other"
    contact = MAP_REASONS["interior_contact"]
    assert np.array_equal(ds["reason"].values[bounced], np.full(bounced.sum(), bit | contact))
    assert (ds["gap_min"].values[bounced] < 0).all()
    for i, omega in enumerate(ds["omega"].values):
        for j, b in enumerate(ds["b"].values):
            if not found[i, j]:
                continue
            orbit = multi_impact_map_orbit(ds, omega=omega, b=b)
            assert ("a bounce of the chatter on stop 'U' reaches stop 'A'" in orbit.reason) \
                == bounced[i, j]
            upper = next(c for c in orbit.chatters if c.stop == "U")
            run = ic.simulate(orbit.oscillator, upper.starts[0], float(upper.phases[0]),
                              float(upper.times[0]) * 1.01)
            assert run.impact_stops[0] == ("A" if bounced[i, j] else "U")


SCENE = """title = "a map of the riding motion"
[oscillator]
M = [[1.0, 0.0], [0.0, 0.2]]
K = [[1.0, 0.0], [0.0, 0.0]]
F = [1.0, 0.0]
R = 0.0
eta = 0.3
b = 0.3
omega = 2.3
stop_mass = 2
stop_relative_to = 1
mirror_stop = true

[[simulations]]
name = "riding"
start = "state"
state = [%r, %r, %r, %r]
delta = 0.0
periods = 16

[[maps]]
name = "ride_map"
start = "riding"
N = 1
p = 2
ranges = { b = [0.29, 0.3], omega = [2.2, 2.5] }
points = [16, 2]  # in the order of the parameters: (omega, b)
"""


def test_a_scene_maps_the_family_of_a_simulation_that_settled_on_a_sticky_motion(tmp_path):
    """[[maps]] with start = a simulation that settled on the riding motion: the scene's
    map is stability_map's of that motion over the same grid (the sticky variables
    included)."""
    from impactcont.scene import read_output, run_scene

    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE % tuple(float(v) for v in riding_start(damper(2.3))))
    result = run_scene(scene, output=tmp_path / "out")
    assert result.ok
    ds = read_output(tmp_path / "out" / "maps.nc").datasets["ride_map"]
    ds = ds.transpose("b", "omega", ...)  # the scene's order of the two parameters
    mine = riding_map()
    assert sorted(ds.attrs["pattern"]) == ["l", "u"]
    assert np.array_equal(ds["found"].values, mine["found"].values)
    assert np.array_equal(ds["reason"].values, mine["reason"].values)
    np.testing.assert_allclose(np.sort(ds["stick_time_k"].values, axis=-1),
                               np.sort(mine["stick_time_k"].values, axis=-1), atol=1e-9, rtol=0)
