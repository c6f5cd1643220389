"""Periodic motions whose sticking phases are entered through complete chatter.

A lowercase letter on a stop with restitution ``0 < R < 1``: the landing impact starts a
chatter, resolved impact by impact by the shooting path's own flights and jumped over to
its accumulation point (:func:`impactcont.kernel.shooting._chatter_map`), then the held
phase and the release. Witnesses, none sharing code with the shooting path:

- the closed form of a one-mass preloaded oscillator (F_static = 1 into its stop b = 0,
  forced 3 cos, R = 0.5): the release is where ``3 cos(theta) + 1`` falls through 0,
  ``theta_r = arccos(-1/3)``, whatever the chatter before it;
- the simulator (:mod:`impactcont.simulate`, its own flow, chatter jump and sticking model)
  on the riding impact damper of studies/chatter_sticking (R = 0.3, eta = 0.3): the motion
  seeded from a run repeats the run's steady releases (times and states) within 1e-8 (the
  method's guarantee: the jump's error ``O(v_K^2)`` at the last resolved impact speed
  ``v_K <= 1e-5`` of the landing's is forgotten by the held flow, measured below to
  rounding), and G is the central difference of the simulated return map;
- the chatter tolerance itself: the motion at :data:`~impactcont.orbit.sticky.CHATTER_SPEED`
  and at a tenth of it agree to rounding.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
import impactcont.orbit.sticky as sticky
from impactcont.model.stops import Stops
from impactcont.orbit.flow import flow_of

TWO_PI = 2.0 * math.pi


def preloaded(omega: float) -> ic.ImpactOscillator:
    """One mass pushed into its stop b = 0 by F_static = 1, forced 3 cos, R = 0.5."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                               omega=omega, eta=0.05)


def damper(omega: float, R: float = 0.3) -> ic.ImpactOscillator:
    """The riding damper of studies/chatter_sticking: primary 1 on spring 1 (eta 0.3), a
    ball of mass 0.2 in |x2 - x1| <= 0.3 with restitution R on both walls."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=R, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


@functools.cache
def riding(omega: float):
    osc = damper(omega)
    res = ic.simulate(osc, riding_start(osc), 0.0, 12.0, trajectory=True)
    return osc, res, ic.multi_impact_orbit(osc, 1, 2, res)


@pytest.mark.parametrize("omega", [0.2, 0.7])
def test_the_preloaded_oscillator_releases_at_the_closed_form(omega):
    """The release of the one-mass held state depends on the forcing alone: cos(theta_r) =
    -1/3 to rounding, G = 0 (the stick forgets everything), the chatter resolved."""
    osc = preloaded(omega)
    res = ic.simulate(osc, [0.0, 0.0], 0.0, 4.0)
    orbit = ic.multi_impact_orbit(osc, 1, 1, res)
    assert orbit.pattern == "u" and orbit.physical, orbit.reason
    release = float(orbit.phases[0] + omega * orbit.stick_times[0])
    assert math.cos(release) == pytest.approx(-1.0 / 3.0, abs=1e-13) and math.sin(release) > 0
    assert np.abs(orbit.multipliers).max() < 1e-14
    period = TWO_PI / omega
    assert orbit.stick_times[0] + orbit.flight_times[0] == pytest.approx(period, rel=1e-14)
    sh = sticky.sticky_shooting(flow_of(osc), 1, "u", orbit.unknowns)
    assert sh.chatter_status[0] == sticky.chatter_impacts(0.5) and sh.chatter_times[0] > 0


@pytest.mark.parametrize("omega", [0.15, 0.2, 0.25])
def test_the_riding_damper_repeats_the_simulated_releases(omega):
    """Both sticking phases (one per wall) of the motion seeded from the run: the run's
    last two releases (phase and state) and the landings after them, within 1e-8."""
    _, res, orbit = riding(omega)
    assert orbit.pattern == "lu" and orbit.physical, orbit.reason
    assert np.all(orbit.pressing_min > 0) and np.all(orbit.landing_pressing > 0)
    released = [ph for ph in res.sticking if ph.ended_by == "release"][-2:]
    for ph in released:
        k = orbit.pattern.index(ph.stops.lower())
        mine = float(orbit.phases[k] + omega * orbit.stick_times[k])
        assert abs(math.remainder(omega * ph.end - mine, TWO_PI)) < 1e-8 * omega
        state = res.X[int(np.searchsorted(res.t, ph.end))]
        np.testing.assert_allclose(orbit.release_states[k], state, atol=1e-8)
    # G: two zero multipliers (the stick collapses the relative position and velocity)
    mu = np.sort(np.abs(orbit.multipliers))
    assert mu[:2].max() < 1e-12 and 0 < mu[-1] < 1


def test_the_chatter_tolerance_is_below_the_rounding_of_the_release(monkeypatch):
    """The motion with the chatter resolved to CHATTER_SPEED of its landing speed and to a
    tenth of it (two more impacts at R = 0.3): the same releases and G to 1e-12 (measured
    3e-15 and 1e-14: at 1e-3 against 1e-4, 3e-12)."""
    _, res, orbit = riding(0.2)
    monkeypatch.setattr(sticky, "CHATTER_SPEED", sticky.CHATTER_SPEED / 10.0)
    finer = ic.multi_impact_orbit(damper(0.2), 1, 2, res)  # a new flow: new held segments
    assert sticky.chatter_impacts(0.3) == 12
    np.testing.assert_allclose(finer.release_states, orbit.release_states, atol=1e-12)
    np.testing.assert_allclose(finer.stick_times, orbit.stick_times, atol=1e-12)
    np.testing.assert_allclose(finer.G, orbit.G, atol=1e-12)


def _landing_after(res, count: int, start: str) -> int:
    """The index of the `count`-th landing impact of a run started just after a landing on
    stop `start` (a landing: the first impact after a release or on another stop than the
    impact before it), counting from 1."""
    ends = sorted(ph.end for ph in res.sticking if ph.ended_by == "release")
    seen = 0
    before, t0 = start, -math.inf
    for i, t in enumerate(res.impact_times):
        new = res.impact_stops[i] != before or any(t0 < e < t for e in ends)
        before, t0 = res.impact_stops[i], t
        if new:
            seen += 1
            if seen == count:
                return i
    raise AssertionError("too few landings")


def _simulated_return(osc, orbit, z, theta):
    """The simulated return map on impact 0's section (its post-landing state, leaving the
    wall at R times the arrival speed): ``[z, theta]`` to the p-th landing after it."""
    X = np.insert(np.asarray(z, float), 1, 0.0)
    X[1] = X[0] + orbit.states[0, 1] - orbit.states[0, 0]  # on the wall's section
    res = ic.simulate(osc, X, theta, orbit.N * 1.3)
    i = _landing_after(res, orbit.p, orbit.pattern[0].upper())
    return np.concatenate([np.delete(res.impact_states[i], 1),
                           [theta + osc.omega * res.impact_times[i]]])


def test_G_is_the_derivative_of_the_simulated_return_map():
    """G (the chain rule through every resolved impact of both chatters and their jumps) is
    the central difference of the simulated return map along every direction of impact
    0's section, within what the differences resolve (1e-6 at h = 1e-6)."""
    osc, _, orbit = riding(0.2)
    z0 = np.delete(orbit.states[0], 1)
    theta0 = float(orbit.phases[0])
    base = _simulated_return(osc, orbit, z0, theta0)
    np.testing.assert_allclose(base[:3], np.delete(orbit.states[0], 1), atol=1e-8)
    h = 1e-6
    for direction in np.eye(4):
        e = h * direction
        hi = _simulated_return(osc, orbit, z0 + e[:3], theta0 + e[3])
        lo = _simulated_return(osc, orbit, z0 - e[:3], theta0 - e[3])
        np.testing.assert_allclose(orbit.G @ direction, (hi - lo) / (2 * h), atol=1e-6)


def test_the_shooting_jacobian_holds_the_chatter_maps_derivative():
    """dr/du of the compiled system (chain rule through the chatter) against central
    differences of its residual (2e-9 at h = 1e-6); the exact omega column (the chatter
    map's omega written out) against central differences of steps 1e-4 and 1e-5 omega:
    1.1e-6 and 1.1e-8, the differences' own h^2."""
    osc, _, orbit = riding(0.2)
    flow = flow_of(osc)
    u = orbit.unknowns
    J = sticky.sticky_shooting(flow, 1, "lu", u).jacobian
    h = 1e-6
    for c in range(u.size):
        e = np.zeros(u.size)
        e[c] = h
        fd = (sticky.sticky_shooting(flow, 1, "lu", u + e, jacobian=False).residual
              - sticky.sticky_shooting(flow, 1, "lu", u - e, jacobian=False).residual) / (2 * h)
        np.testing.assert_allclose(J[:, c], fd, atol=5e-9)
    column = sticky.sticky_omega_column(flow, 1, "lu", u)
    errors = []
    for step in (1e-4, 1e-5):
        d = step * osc.omega
        fd = (sticky.sticky_shooting(flow_of(damper(0.2 + d)), 1, "lu", u,
                                     jacobian=False).residual
              - sticky.sticky_shooting(flow_of(damper(0.2 - d)), 1, "lu", u,
                                       jacobian=False).residual) / (2 * d)
        errors.append(float(np.max(np.abs(column - fd))))
    # falling as h^2 (100x here), not levelling off: the column is exact, not a difference
    assert errors[1] < 1e-7 and errors[0] > 30.0 * errors[1], errors


def test_a_chatter_that_does_not_accumulate_is_not_physical():
    """Pulled off its stop (F_static = -1 away from b = 0, weak forcing), the mass bounces
    off and does not come back: the landing's chatter never accumulates, and the motion at
    any unknowns is flagged with that reason."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[0.5], F_static=[-1.0], R=0.5, b=0.0,
                              omega=0.7, eta=0.05)
    flow = flow_of(osc)
    u = np.array([0.0, 1.0, 0.2])  # [delta, s_0, x1'_0]
    sh = sticky.sticky_shooting(flow, 1, "u", u)
    assert sh.chatter_status[0] < 0 and sh.chatter_times[0] == 0.0
    orbit = sticky.sticky_orbit_from_unknowns(flow, 1, "u", u, sh, checks=False)
    assert not orbit.physical and "chatter" in orbit.reason


def test_a_stop_whose_impacts_cannot_accumulate_is_refused():
    osc = preloaded(0.7).replace(R=1.0)
    with pytest.raises(ic.ParameterError, match=r"restitution >= 1 they do not accumulate"):
        ic.multi_impact_orbit(osc, 1, 1, {"delta": 0.0, "flight_times": [1.0],
                                          "states": [[0.0, -0.1]], "pattern": "u",
                                          "stick_times": [1.0]})


@pytest.mark.parametrize("parameter", ["omega", "eta"])
def test_the_branch_is_the_solve_alone(parameter):
    """ic.continuation of the chatter-entered riding motion (the core's corrector, central
    differences in the chatter map's parameter): its end points are multi_impact_orbit
    solved alone at their parameter (1e-9)."""
    osc, _, orbit = riding(0.2)
    bounds = (0.2, 0.215) if parameter == "omega" else (0.3, 0.31)
    ds = ic.continuation(orbit, parameter=parameter, bounds=bounds, max_points=12)
    values = ds[parameter].values
    assert values.max() == pytest.approx(bounds[1]) and ds.physical.values.all()
    i = int(np.argmax(values))
    alone = ic.multi_impact_orbit(osc.replace(**{parameter: float(values[i])}), 1, 2, orbit)
    assert alone.pattern == ds.attrs["pattern"] == "lu" and alone.physical, alone.reason
    for name, mine in (("flight_time_k", alone.flight_times),
                       ("stick_time_k", alone.stick_times), ("state_k", alone.states)):
        assert ds[name].values[i] == pytest.approx(mine, abs=1e-9), name


def test_a_scene_seeds_the_chatter_entered_motion_from_its_simulation(tmp_path):
    """``[[multi_impact]]`` from a ``[[simulations]]`` entry of the riding damper at R = 0.3:
    the scene's seed folds each chatter's impacts into its landing, so the entry finds
    the chatter-entered motion (pattern "lu"/"ul", stick times > 0) and continues it."""
    from impactcont.scene import run_scene

    study = Path(__file__).resolve().parents[2] / "studies" / "sticking_motions" / "scene.toml"
    text = study.read_text().split("[[plots]]")[0].replace("R = 0.0\n", "R = 0.3\n") + """
[[multi_impact]]
name = "ride"
start = "riding"
N = 1
p = 2
parameter = "omega"
bounds = [0.2, 0.205]
"""
    path = tmp_path / "scene.toml"
    path.write_text(text)
    result = run_scene(path, output=tmp_path / "o")
    assert result.ok, result.failures
    ds = result.datasets["multi_impact"]["ride"]
    assert ds.attrs["pattern"] in ("lu", "ul") and float(ds["stick_time_k"].min()) > 0
    assert ds.physical.values.all()


@functools.cache
def narrow():
    """The riding motion continued in the clearance down to b = 0.05 (each solve seeded by
    the last): still physical, its bounces well inside the clearance."""
    osc, _, orbit = riding(0.2)
    for b in (0.2, 0.1, 0.05):
        orbit = ic.multi_impact_orbit(osc.replace(b=b), 1, 2, orbit)
    return orbit


def test_a_chatter_bounce_that_reaches_the_other_wall_is_not_physical():
    """A solved riding motion's bounces cannot reach the other wall (the landing's speed
    comes from the flight across the clearance, and a bounce rises about R^2 of it), so
    the shot at the narrow motion's unknowns with the landing's speed raised by 0.1: its
    first bounce (resolved by the chatter map, which sees only its own wall) rises past
    the upper wall and comes back, and the motion at those unknowns is not physical
    naming the upper stop. The simulator from the same landing state hits the upper wall
    first, before the bounce's apex."""
    orbit = narrow()
    assert orbit.physical, orbit.reason
    osc = orbit.oscillator
    flow = flow_of(osc)
    u = orbit.unknowns.copy()
    u[6] += 0.1  # x2' of the landing state (z_0 = [x1, x1', x2'])
    sh = sticky.sticky_shooting(flow, 1, "lu", u)
    assert sh.chatter_status[0] == sticky.chatter_impacts(0.3)
    shot = sticky.sticky_orbit_from_unknowns(flow, 1, "lu", u, sh)
    assert not shot.physical
    assert "impact 0: a bounce of the chatter on stop 'L' reaches stop 'U'" in shot.reason
    apex = float(shot.reason.split("after the landing")[0].rsplit("t=", 1)[1])
    first = shot.chatters[0]
    assert 0 < apex < first.times[0]
    assert first.reached == "U"  # the number of it
    assert all(c.reached == "" for c in shot.chatters[1:])
    run = ic.simulate(osc, sh.starts[0], float(sh.phases[0]), 0.2)
    assert run.impact_stops[0] == "U" and 0 < run.impact_times[0] < apex
    # at the solution itself the bounces stay below the upper wall (no such reason)
    solved = sticky.sticky_orbit_from_unknowns(flow, 1, "lu", orbit.unknowns)
    assert "reaches stop" not in solved.reason
    assert [c.reached for c in solved.chatters] == ["", ""]


def test_the_time_series_draws_the_chatter_and_the_simulated_motion():
    """The time series of the riding motion (both chatters' resolved bounces, then held
    from the accumulation point) against the simulator's trajectory of one period from
    impact 0's state: the stop coordinate at every simulated sample inside a drawn
    piece (each piece interpolated on its own 20001 samples, below 1e-9 of interpolation
    error) within 1e-8, the motion's guarantee against the simulator (measured 7e-10 over
    4038 samples; drawn held from the landing, as before, the bounces are 0.027 off)."""
    osc, _, orbit = riding(0.2)
    num = 20001
    t, X = orbit.time_series(num)
    pieces = t.size // num
    assert pieces == 2 * orbit.p + sum(c.times.size for c in orbit.chatters) == 24
    run = ic.simulate(osc, orbit.states[0], float(orbit.phases[0]), 1.0, trajectory=True,
                      samples_per_period=4000)
    s_run = run.X[:, 1] - run.X[:, 0]
    s = X[:, 1] - X[:, 0]
    worst, compared = 0.0, 0
    for j in range(pieces):
        ts, ss = t[j * num:(j + 1) * num], s[j * num:(j + 1) * num]
        inside = (run.t > ts[0]) & (run.t < ts[-1])
        if np.any(inside):
            worst = max(worst, float(np.max(np.abs(np.interp(run.t[inside], ts, ss)
                                                    - s_run[inside]))))
            compared += int(np.count_nonzero(inside))
    assert compared > 3000 and worst < 1e-8, (compared, worst)
    # the first bounce rises off the lower wall, the held phases sit on the walls
    first = orbit.chatters[0]
    rise = s[:num] + osc.b
    assert rise[0] == pytest.approx(0.0, abs=1e-12) and rise.max() > 0.02
    assert first.times.sum() < first.duration < orbit.stick_times[0]


def test_the_motion_keeps_the_chatter_maps_bounces():
    """MultiImpactOrbit.chatters: one per chatter-entered stick, its bounces those the
    chatter map resolved (K of them, the first from the landing state, each next one from
    the impact ending the last: same positions, phases advanced by the bounce), ending
    before the accumulation point, which is the shooting's."""
    osc, _, orbit = riding(0.2)
    sh = sticky.sticky_shooting(flow_of(osc), 1, "lu", orbit.unknowns)
    assert [c.impact for c in orbit.chatters] == [0, 1]
    assert [c.stop for c in orbit.chatters] == ["L", "U"]
    for c in orbit.chatters:
        k = c.impact
        assert c.times.size == sh.chatter_status[k] == sticky.chatter_impacts(0.3)
        np.testing.assert_array_equal(c.starts[0], sh.starts[k])
        np.testing.assert_array_equal(c.accumulation, sh.accumulations[k])
        np.testing.assert_allclose(c.starts[1:, :2], c.arrivals[:-1, :2], atol=1e-15)
        np.testing.assert_allclose(c.phases[1:], c.phases[:-1] + osc.omega * c.times[:-1],
                                   rtol=1e-15)
        assert np.all(np.diff(c.times) < 0) and 0 < c.duration - c.times.sum() < 1e-4
    plain = sticky.chatter_bounces(flow_of(osc.replace(R=0.0)), "lu", sh)
    assert plain == ()


def test_a_bounce_crossing_another_coordinates_stop_is_seen_at_its_end():
    """A stop on the primary (x1 <= -1.01) that x1 crosses monotonically late in the first
    bounce of the riding motion's lower chatter (x1 from -1.033 down to an interior minimum
    -1.045, then up to -0.996 at the bounce's end: no interior maximum to search): the
    shot at the motion's unknowns on that machine names the stop for the chatter (the
    bounce's end clearance), and the simulator from the landing state hits it inside
    the first bounce."""
    osc, _, orbit = riding(0.2)
    first = orbit.chatters[0]
    x1 = flow_of(osc).state(np.linspace(0.0, first.times[0], 201), first.starts[0],
                            first.phases[0])[:, 0]
    assert x1[0] < -1.01 < x1[-1] and np.argmin(x1) not in (0, 200)
    capped = ic.ImpactOscillator(M=osc.M, K=osc.K, F=[1.0, 0.0], R=0.3, b=0.3, omega=0.2,
                                 eta=0.3, stops=Stops(mass=2, relative_to=1, mirror=True,
                                                      extra=(ic.Stop("A", mass=1, gap=-1.01,
                                                                     restitution=0.5),)))
    shot = sticky.sticky_orbit_from_unknowns(flow_of(capped), 1, "lu", orbit.unknowns)
    assert "impact 0: a bounce of the chatter on stop 'L' reaches stop 'A': x1" in shot.reason
    run = ic.simulate(capped, first.starts[0], float(first.phases[0]), 0.1)
    assert run.impact_stops[0] == "A" and 0 < run.impact_times[0] < first.times[0]
