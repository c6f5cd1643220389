"""Maps of motions whose impacts are on stops of several coordinates (issue 21): the compiled
sweep solves each impact's section for its own stop's mass and checks every flight against
every stop (U above mass 1, A above mass 2 of a two-mass chain, the layout of Wagg's
two-degree-of-freedom impact oscillator, illustrative numbers). Witnesses:
``multi_impact_orbit`` at every cell (the shooting path, which already took several stops)
and the event-driven simulator on cells of each class (stable, unstable, not physical)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.maps import multi_impact_map_orbit

M = np.eye(2)
K = np.array([[2.0, -1.0], [-1.0, 1.0]])  # a chain: wall - k - m1 - k - m2
OMEGA = np.linspace(0.75, 1.0, 6)
R = np.linspace(0.5, 0.95, 6)


def _wagg(omega=0.8, gap=0.6, **kw):
    params = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.8, "b": 0.3, "omega": omega,
              "eta": 0.05,
              "stops": ic.Stops(extra=(ic.Stop("A", mass=2, gap=gap, restitution=0.7),))}
    return ic.ImpactOscillator(**{**params, **kw})


@pytest.fixture(scope="module")
def two_mass_map():
    """The 1-2 motion with one impact on U (mass 1) and one on A (mass 2), mapped over
    (omega, R)."""
    osc = _wagg()
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 100.0))
    assert sorted(orbit.pattern) == ["A", "U"] and orbit.physical
    ds = ic.multi_impact_map(orbit, ("omega", "R"), {"omega": OMEGA, "R": R})
    return orbit, ds


def test_every_cell_is_the_shooting_motion_there(two_mass_map):
    orbit, ds = two_mass_map
    assert ds.attrs["pattern"] == orbit.pattern
    found = ds["found"].values
    assert found.all()
    # the three classes occur: the witness below is not vacuous
    stable, physical = ds["stable"].values, ds["physical"].values
    assert (stable & physical).any() and (~stable & physical).any() and (~physical).any()
    for i, w in enumerate(OMEGA):
        for k, r in enumerate(R):
            cell = ds.isel(omega=i, R=k)
            fresh = ic.multi_impact_orbit(_wagg(omega=float(w), R=float(r)), 1, 2, {
                "delta": float(cell["delta"]), "flight_times": cell["flight_time_k"].values,
                "states": cell["state_k"].values, "pattern": orbit.pattern})
            np.testing.assert_allclose(cell["state_k"].values, fresh.states, rtol=0,
                                       atol=1e-9)
            np.testing.assert_allclose(cell["flight_time_k"].values, fresh.flight_times,
                                       rtol=0, atol=1e-9)
            assert bool(cell["physical"]) == fresh.physical, fresh.reason
            assert bool(cell["stable"]) == (abs(fresh.multipliers[0]) < 1.0)
            assert float(cell["spectral_radius"]) == pytest.approx(
                abs(fresh.multipliers[0]), rel=1e-7)
            assert float(cell["gap_min"]) == pytest.approx(
                float(np.min(fresh.flight_gap_min)), abs=1e-8)
            np.testing.assert_allclose(cell["impact_velocity_k"].values,
                                       fresh.impact_velocities, rtol=1e-8)


def _distance(orbit, res, k):
    """Max-norm distance of the simulated state after impact k to the motion's state."""
    return float(np.max(np.abs(res.impact_states[k] - orbit.states[(k + 1) % orbit.p])))


def test_stable_physical_cells_hold_in_the_simulator(two_mass_map):
    _, ds = two_mass_map
    cells = [(i, k) for i in range(OMEGA.size) for k in range(R.size)
             if ds["stable"].values[i, k] and ds["physical"].values[i, k]]
    for i, k in cells[::5]:
        orbit = multi_impact_map_orbit(ds, omega=OMEGA[i], R=R[k])
        start = orbit.states[0] + 1e-5 * np.array([0.0, 1.0, 1.0, -1.0])
        if orbit.pattern[0] == "A":
            start[1] = orbit.states[0][1]  # on stop A
        else:
            start[0] = orbit.states[0][0]  # on stop U
        res = ic.simulate(orbit.oscillator, start, orbit.phases[0], 30.5)
        n = 2 * 30
        assert res.impact_stops[:n] == (orbit.pattern[1:] + orbit.pattern[0]) * 30
        assert _distance(orbit, res, n - 1) < 1e-7  # drawn back onto the motion


def test_an_unstable_physical_cell_is_left_in_the_simulator(two_mass_map):
    _, ds = two_mass_map
    i, k = OMEGA.size - 1, R.size - 1
    assert ds["physical"].values[i, k] and not ds["stable"].values[i, k]
    orbit = multi_impact_map_orbit(ds, omega=OMEGA[i], R=R[k])
    res = ic.simulate(orbit.oscillator, orbit.states[0], orbit.phases[0], 1.5, max_impacts=orbit.p)
    # one period on the motion (physical) ...
    assert res.impact_stops == orbit.pattern[1:] + orbit.pattern[0]
    np.testing.assert_allclose(res.impact_states[-1], orbit.states[0], rtol=0, atol=1e-8)
    # ... but a small deviation grows (rho > 1)
    start = orbit.states[0] + 1e-6 * np.array([0.0, 1.0, 1.0, -1.0])
    j = int(orbit.pattern[0] == "A")  # the own mass of the first impact's stop
    start[j] = orbit.states[0][j]
    res = ic.simulate(orbit.oscillator, start, orbit.phases[0], 200.0, max_impacts=400)
    pattern = orbit.pattern[1:] + orbit.pattern[0]
    early = max(_distance(orbit, res, 2 * q + 1) for q in range(3))
    left = [q for q in range(len(res.impact_stops) // 2)
            if res.impact_stops[2 * q:2 * q + 2] != pattern
            or _distance(orbit, res, 2 * q + 1) > 1e3 * early]
    assert early < 1e-4 and left


def test_a_not_physical_cell_crosses_a_stop_in_the_simulator(two_mass_map):
    _, ds = two_mass_map
    assert not ds["physical"].values[0, 0]
    orbit = multi_impact_map_orbit(ds, omega=OMEGA[0], R=R[0])
    assert "reaches a stop inside the flight" in orbit.reason
    res = ic.simulate(orbit.oscillator, orbit.states[0], orbit.phases[0], 1.5,
                      max_impacts=orbit.p)
    # the simulator meets a stop before the motion's next impact
    assert res.impact_times[0] < orbit.flight_times[0] - 1e-3
    k = int(np.argmin(orbit.flight_gap_min))
    assert res.impact_stops[0] == orbit.flight_gap_stops[k]


def test_a_map_in_b_moves_U_only_and_checks_every_stop(two_mass_map):
    orbit, _ = two_mass_map
    # b moves U only: A's impacts keep their section; still agrees with the shooting path
    ds = ic.multi_impact_map(orbit, ("omega", "b"), {"omega": [0.78, 0.8, 0.82],
                                                      "b": [0.28, 0.3, 0.32]})
    assert ds["found"].values.all()
    for w in (0.78, 0.82):
        for b in (0.28, 0.32):
            fresh = multi_impact_map_orbit(ds, omega=w, b=b)
            cell = ds.sel(omega=w, b=b)
            assert bool(cell["physical"]) == fresh.physical
            assert float(cell["gap_min"]) == pytest.approx(float(np.min(fresh.flight_gap_min)),
                                                           abs=1e-8)


def test_a_map_of_extra_stop_impacts_round_trips(two_mass_map, tmp_path):
    orbit, ds = two_mass_map
    ic.save(ds, tmp_path / "map.nc")
    back = ic.load(tmp_path / "map.nc")
    assert back.attrs["pattern"] == orbit.pattern
    np.testing.assert_array_equal(back["physical"].values, ds["physical"].values)
    again = multi_impact_map_orbit(back, omega=OMEGA[2], R=R[3])
    np.testing.assert_allclose(again.states, ds["state_k"].values[2, 3], rtol=0, atol=1e-9)


# -- a free mode held by an extra stop (model/oscillator.py: any stop touching it holds it) --
G_BALL, R_BALL = 0.5, 0.5


def _ball_on_extra_stop(F_ball: float = 1.0) -> ic.ImpactOscillator:
    """Holmes' (1982) bouncing ball as mass 2 (free, gravity G_BALL, its table the extra
    lower stop A at x2 = 0), beside mass 1 on a spring under the upper stop U far away."""
    return ic.ImpactOscillator(
        M=np.eye(2), K=np.diag([2.0, 0.0]), F=[0.3, F_ball], F_static=[0.0, -G_BALL], R=0.7,
        b=100.0, omega=1.0, eta=0.05,
        stops=ic.Stops(extra=(ic.Stop("A", mass=2, gap=0.0, restitution=R_BALL, side=-1),)))


def test_a_free_mass_held_only_by_an_extra_stop_is_accepted():
    osc = _ball_on_extra_stop()
    np.testing.assert_allclose(osc.free_modes.T, [[0.0, 1.0]], rtol=0, atol=1e-12)
    # without A nothing holds mass 2: refused, naming the free motion and the stops seen
    with pytest.raises(ic.ParameterError, match=r"free mode u = \[0\.0, 1\.0\] is held by "
                                                r"nothing.*s = x1 \(normal \[1\.0, 0\.0\]\)"):
        osc.replace(stops=ic.Stops())


def test_the_ball_on_the_extra_stop_is_holmes_period_one_motion():
    """Holmes' closed form (the ball leaves its table at ``v = R g T / (1 + R)``, the phase
    ``sin(delta) = pi g (R - 1) / ((1 + R) F)``) and the simulator."""
    osc = _ball_on_extra_stop()
    period = 2.0 * np.pi
    v = R_BALL * G_BALL * period / (1.0 + R_BALL)
    s = np.pi * G_BALL * (R_BALL - 1.0) / (1.0 + R_BALL)
    for delta in (np.arcsin(s), np.pi - np.arcsin(s)):
        orbit = ic.multi_impact_orbit(osc, 1, 1, {"delta": delta + 0.02,
                                                  "flight_times": [period * 1.01],
                                                  "states": [[0.0, 0.0, 0.0, v]],
                                                  "pattern": "A"})
        assert np.remainder(orbit.phases[0] - delta + np.pi, 2 * np.pi) - np.pi == \
            pytest.approx(0.0, abs=1e-10)
        assert orbit.states[0][3] == pytest.approx(v, abs=1e-10)  # leaves the table at v
        assert orbit.physical
        res = ic.simulate(osc, orbit.states[0], orbit.phases[0], 2.5)
        assert res.impact_stops == "AA"
        np.testing.assert_allclose(np.diff(np.append(0.0, res.impact_times)), period,
                                   rtol=0, atol=1e-8)


@pytest.mark.parametrize("stops, held", [
    # two free masses: a stop on each holds both
    (ic.Stops(extra=(ic.Stop("A", mass=2, gap=0.5, restitution=0.5),)), True),
    # one coordinate for two free modes: x2 moves freely
    (ic.Stops(b_low=0.5), False),
    # a clearance between them and a stop on mass 2: both held
    (ic.Stops(mass=2, relative_to=1, extra=(ic.Stop("A", mass=2, gap=0.5, restitution=0.5),)),
     True),
    # a clearance only: the masses move together, freely
    (ic.Stops(mass=2, relative_to=1, b_low=0.5), False),
])
def test_two_free_masses_need_two_stop_coordinates(stops, held):
    kw = dict(M=np.diag([1.0, 0.5]), K=np.zeros((2, 2)), F=[1.0, 0.0], R=0.7, b=0.3,
              omega=1.0, eta=0.05)
    if held:
        assert ic.ImpactOscillator(**kw, stops=stops).free_modes.shape == (2, 2)
    else:
        with pytest.raises(ic.ParameterError, match="is held by nothing"):
            ic.ImpactOscillator(**kw, stops=stops)


# -- the simulator's clearances against every stop (simulate/contact.py) ---------------------
def _three_extra_stops() -> ic.ImpactOscillator:
    """The chain of ``_wagg`` with A above mass 2, B below it (met moving down) and C on
    ``x2 - x1`` (a stop between the masses)."""
    return _wagg(stops=ic.Stops(extra=(
        ic.Stop("A", mass=2, gap=0.6, restitution=0.7),
        ic.Stop("B", mass=2, gap=0.5, restitution=0.5, side=-1),
        ic.Stop("C", mass=2, relative_to=1, gap=0.45, restitution=0.6))))


def _interior_top(t, y):
    """Highest interior local maximum of a densely sampled ``y`` and its time."""
    i = np.flatnonzero((y[1:-1] >= y[:-2]) & (y[1:-1] >= y[2:])) + 1
    k = i[np.argmax(y[i])]
    return float(y[k]), float(t[k])


def test_flight_clearances_against_every_stop(two_mass_map):
    from impactcont.orbit.flow import Flow
    from impactcont.simulate.contact import flight_clearances

    osc = _three_extra_stops()
    orbit = ic.multi_impact_orbit(osc, 1, 2, two_mass_map[0])  # the AU motion, B and C added
    assert not orbit.physical and "stop 'B'" in orbit.reason
    flow = Flow(osc)
    k = int(np.argmax(orbit.flight_times))  # the long flight (the other has no extremum)
    tau = float(orbit.flight_times[k])
    gap_u, t_u, gap_l, t_l, gap_x, t_x = flight_clearances(
        flow, orbit.states[k], float(orbit.phases[k]), tau, extra=True)
    assert len(flight_clearances(flow, orbit.states[k], float(orbit.phases[k]), tau)) == 4
    assert np.isinf(gap_l) and np.isnan(t_l)  # no lower stop L
    # a dense sampling of the exact flow (2e5 + 1 points: the sampled extremum is within
    # h^2 max|s''| / 8 < 1e-9 of the true one)
    t = np.linspace(0.0, tau, 200_001)
    X = flow.state(t, orbit.states[k], float(orbit.phases[k]))
    x1, x2 = X[:, 0], X[:, 1]
    for gap, when, (level, y) in zip(
            (gap_u, *gap_x), (t_u, *t_x),
            ((0.3, x1), (0.6, x2), (0.5, -x2), (0.45, x2 - x1)), strict=True):
        top, at = _interior_top(t, y)
        assert gap == pytest.approx(level - top, abs=1e-8)
        assert when == pytest.approx(at, abs=1e-4)
    assert np.min(gap_x) < 0.0 < min(gap_x[0], gap_u)  # B and C crossed, A and U clear
    # the kernel's check of the same flight (multi_impact_orbit): the nearest stop and gap
    gaps = {"U": gap_u, "A": gap_x[0], "B": gap_x[1], "C": gap_x[2]}
    nearest = min(gaps, key=gaps.get)
    assert orbit.flight_gap_stops[k] == nearest
    assert orbit.flight_gap_min[k] == pytest.approx(gaps[nearest], abs=1e-9)


def test_the_stop_geometry_of_a_pattern_on_two_masses_has_a_pivot_per_impact():
    from impactcont.orbit.stop_geometry import stop_geometry

    geo = stop_geometry(_wagg(), "AU")
    np.testing.assert_array_equal(geo.pivots, [1, 0])  # x2 on A's section, x1 on U's
    np.testing.assert_array_equal(geo.signs, [1.0, 1.0])
    np.testing.assert_array_equal(geo.positions, [0.6, 0.3])
    assert stop_geometry(_wagg(), "A").pivot == 1
    with pytest.raises(ic.ParameterError, match=r"pivots \[2, 1\].*StopGeometry.pivots"):
        _ = geo.pivot
