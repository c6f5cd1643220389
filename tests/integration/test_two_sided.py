"""Two stops (a lower stop with its own restitution) and a stop on any mass.

Each motion is checked against an independent witness: the event-driven
simulator (impact times and velocities over 50 periods), finite differences of
the simulated impact map (the multipliers), a dense evaluation of the exact flow
(the grazing of the lower stop), the mirror symmetry of a symmetric system, and
the closed form of the same chain with its masses relabelled (a stop on mass k).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.switching import grazing_switch, special_orbit
from impactcont.dataset.multi import pattern_of, validate_multi_impact_dataset
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops, check_pattern
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import multi_impact_orbit, shooting
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.scene import SceneError, load_scene
from impactcont.simulate import SimulationStatus, next_impact
from tests._scene_data import write

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def paper2(b: float, omega: float, **stops) -> ic.ImpactOscillator:
    """The paper's 2-DOF system (section 4) with the given stops."""
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               eta=0.1, stops=Stops(**stops))


def settled_orbit(osc: ic.ImpactOscillator, N: int, p: int, periods: float = 200.0):
    """The N-p motion the simulation from rest settles on (its last p+1 impacts seed Newton)."""
    res = ic.simulate(osc, np.zeros(2 * osc.n), 0.0, periods)
    return multi_impact_orbit(osc, N, p, res)


@pytest.fixture(scope="module")
def symmetric():
    """A symmetric motion: b_low = b, one impact on each stop per period."""
    return settled_orbit(paper2(0.8, 0.8, b_low=0.8), 1, 2)


@pytest.fixture(scope="module")
def asymmetric():
    """An asymmetric 1-2 motion of the same symmetric system (other omega and gap)."""
    return settled_orbit(paper2(0.5, 1.3, b_low=0.5), 1, 2)


@pytest.fixture(scope="module")
def unequal():
    """Unequal stops and restitutions: b = 0.7, b_low = 0.5, R_low = 0.8."""
    return settled_orbit(paper2(0.7, 0.9, b_low=0.5, R_low=0.8), 1, 2)


@pytest.fixture(scope="module")
def damper():
    """A non-proportional damper on mass 1 only (first-order flow) with b_low = b."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8, omega=0.8,
                              C=[[0.3, 0.0], [0.0, 0.0]], stops=Stops(b_low=0.8))
    assert osc.general
    return settled_orbit(osc, 1, 2)


def _stop_positions(osc, pattern):
    return np.array([osc.stops.position(s, osc.b) for s in pattern])


# ------------------------------------------------------------------------------------------
# The simulator confirms the motions
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["symmetric", "asymmetric", "unequal", "damper"])
def test_simulator_confirms_two_sided_motion(name, request):
    orbit = request.getfixturevalue(name)
    assert orbit.physical, orbit.reason
    assert sorted(orbit.pattern) == ["L", "U"]
    osc = orbit.oscillator
    res = ic.simulate(osc, orbit.states[0], float(orbit.phases[0]), 50.0)
    assert res.success
    k = res.impact_times.size
    assert k >= 99  # two impacts per period over 50 periods
    reps = k // orbit.p + 1
    expected_t = np.cumsum(np.tile(orbit.flight_times, reps))[:k]
    expected_v = np.tile(np.roll(orbit.impact_velocities, -1), reps)[:k]
    expected_s = (orbit.pattern[1:] + orbit.pattern[0]) * reps
    assert res.impact_stops == expected_s[:k]
    np.testing.assert_allclose(res.impact_times, expected_t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.impact_velocities, expected_v, rtol=0, atol=1e-9)
    # every post-impact state sits on its stop and equals the orbit's
    expected_x = np.tile(np.roll(orbit.states, -1, axis=0), (reps, 1))[:k]
    np.testing.assert_allclose(res.impact_states, expected_x, rtol=0, atol=1e-9)
    j = osc.stops.index
    np.testing.assert_array_equal(res.impact_states[:, j],
                                  _stop_positions(osc, res.impact_stops))


def _simulated_map(osc, p, stop, j, z, theta):
    """The impact map over p impacts by simulation, from the section of `stop`."""
    X = np.insert(z, j, osc.stops.position(stop, osc.b))
    res = ic.simulate(osc, X, float(theta), 100.0, max_impacts=p)
    assert res.impact_stops[-1] == stop
    return np.delete(res.impact_states[-1], j), float(res.impact_phases[-1])


@pytest.mark.parametrize("name", ["symmetric", "asymmetric", "unequal", "damper"])
def test_multipliers_match_finite_differences_of_the_simulated_map(name, request):
    orbit = request.getfixturevalue(name)
    osc = orbit.oscillator
    j = osc.stops.index
    z0 = np.delete(orbit.states[0], j)
    theta0 = float(orbit.phases[0])
    m = z0.size + 1
    G_fd = np.empty((m, m))
    h = 1e-6
    for c in range(m):
        out = []
        for sign in (1.0, -1.0):
            z, th = z0.copy(), theta0
            if c < m - 1:
                z[c] += sign * h
            else:
                th += sign * h
            zz, tt = _simulated_map(osc, orbit.p, orbit.pattern[0], j, z, th)
            tt = theta0 + math.remainder(tt - theta0, 2 * math.pi)
            out.append(np.append(zz, tt))
        G_fd[:, c] = (out[0] - out[1]) / (2 * h)
    scale = float(np.max(np.abs(orbit.G)))
    assert np.max(np.abs(G_fd - orbit.G)) <= 1e-6 * scale
    mu_fd = np.linalg.eigvals(G_fd)
    for mu in orbit.multipliers:
        assert np.min(np.abs(mu_fd - mu)) <= 1e-6 * max(orbit.spectral_radius, 1e-3)


# ------------------------------------------------------------------------------------------
# Symmetry
# ------------------------------------------------------------------------------------------
def test_symmetric_motion_of_a_symmetric_system(symmetric):
    """b_low = b and the forcing flips sign every half period: X_1 = -X_0, tau_k = T/2."""
    o = symmetric
    T = 2 * math.pi / o.oscillator.omega
    np.testing.assert_allclose(o.states[1], -o.states[0], rtol=0, atol=1e-10)
    np.testing.assert_allclose(o.flight_times, [T / 2, T / 2], rtol=0, atol=1e-10)
    assert abs(math.remainder(o.phases[1] - o.phases[0] - math.pi, 2 * math.pi)) <= 1e-10
    assert o.impact_velocities[0] == pytest.approx(o.impact_velocities[1], abs=1e-10)
    # G = H^2 with H the half-map: flight U -> L followed by the reflection
    reflect = np.diag([-1.0] * (2 * o.oscillator.n - 1) + [1.0])
    H = reflect @ o.jacobians[0]
    np.testing.assert_allclose(o.jacobians[1], reflect @ o.jacobians[0] @ reflect, atol=1e-10)
    mu2 = np.sort_complex(np.linalg.eigvals(H) ** 2)
    np.testing.assert_allclose(mu2, np.sort_complex(o.multipliers), atol=1e-10)


def test_asymmetric_motion_comes_with_its_mirror_image(asymmetric):
    o = asymmetric
    assert abs(o.impact_velocities[0] - o.impact_velocities[1]) > 1e-2  # not symmetric
    mirror = {"delta": float(o.phases[1]) + math.pi, "flight_times": o.flight_times[::-1],
              "states": -o.states[::-1], "pattern": o.pattern}
    m = multi_impact_orbit(o.oscillator, 1, 2, mirror)
    assert m.physical
    # the mirror: impact velocities swapped stops, same multipliers
    np.testing.assert_allclose(m.impact_velocities, o.impact_velocities[::-1], atol=1e-10)
    np.testing.assert_allclose(np.sort_complex(m.multipliers), np.sort_complex(o.multipliers),
                               atol=1e-10)
    assert np.max(np.abs(m.states - o.states)) > 1e-2


# ------------------------------------------------------------------------------------------
# Continuation and grazing of the lower stop
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def upper_branch():
    """The N-1 motion on the upper stop of a two-sided system, continued in omega.

    Seeded by the closed form of the one-sided system (the same motion while it
    keeps off the lower stop); its minimum reaches the lower stop at a GR point.
    """
    one = paper2(0.3, 1.5)
    seed = max(ic.periodic_orbits(one, 1), key=lambda o: o.impact_velocity)
    osc = paper2(0.3, 1.5, b_low=1.3, R_low=0.8)
    orbit = multi_impact_orbit(osc, 1, 1, seed)
    return multi_impact_continuation(orbit, "omega", (0.8, 1.6), both_directions=True,
                                     detect=["GR", "PD"])


def _lower_clearance(osc, state, phase, tau):
    """min x_j + b_low over a flight by a dense grid and a bounded polish (no extrema code)."""
    flow = Flow(osc)
    j = osc.stops.index
    t = np.linspace(0.0, tau, 20001)
    x = flow.state(t, state, phase)[:, j]
    i = int(np.argmin(x))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
    best = scipy.optimize.minimize_scalar(lambda s: flow.state(s, state, phase)[0, j],
                                          bounds=(lo, hi), method="bounded",
                                          options={"xatol": 1e-14})
    return float(best.fun) + osc.stops.b_low


def test_grazing_of_the_lower_stop_is_located(upper_branch):
    ds = upper_branch
    validate_multi_impact_dataset(ds)
    assert pattern_of(ds) == "U"
    labels = list(ds["special_label"].values)
    assert "GR" in labels
    grazes = [special_orbit(ds, "GR", w) for w in range(labels.count("GR"))]
    lower = [o for o in grazes if abs(o.gap_lower) < 1e-6]
    assert len(lower) == 1, [(o.oscillator.omega, o.gap_lower) for o in grazes]
    g = lower[0]
    k = labels.index("GR") + [o is g for o in grazes].index(True)
    assert ds["special_status"].values[k] == "located"
    assert ds["special_precision"].values[k] <= 1e-9
    # recomputed there, independently of the extremum search: the lower clearance is ~0
    clearance = _lower_clearance(g.oscillator, g.states[0], float(g.phases[0]),
                                 float(g.flight_times[0]))
    assert abs(clearance) <= 1e-9
    assert abs(g.gap_lower) <= 1e-9
    assert g.flight_gap_min[0] == g.gap_lower  # the lower stop is the one grazed
    # across the graze the motion crosses the lower stop: flagged, with the reason
    omega_g = g.oscillator.omega
    inside = ds["omega"].values
    side = np.sign(ds["gap_min"].values)
    beyond = inside[side < 0]
    assert beyond.size and np.all(np.abs(beyond - omega_g) > 0)
    o = multi_impact_orbit(g.oscillator.replace(omega=float(beyond[np.argmin(np.abs(
        beyond - omega_g))])), 1, 1, g)
    assert not o.physical and "reaches a stop" in o.reason and o.gap_lower < 0


def test_grazing_switch_at_the_lower_stop_adds_an_impact_there(upper_branch):
    labels = list(upper_branch["special_label"].values)
    which = [abs(special_orbit(upper_branch, "GR", w).gap_lower) < 1e-6
             for w in range(labels.count("GR"))].index(True)
    new = grazing_switch(upper_branch, which, max_points=20)
    assert new is not None and new.attrs["pattern"] == "UL"
    assert bool(new["physical"].values[1])
    # a point of the new branch is a 1-2 motion with one impact on each stop, confirmed by
    # the simulator
    i = new.sizes["point"] // 2
    o = multi_impact_orbit(ic.dataset.oscillator_from_dataset(new, i), 1, 2, {
        "delta": float(new["delta_k"].values[i, 0]),
        "flight_times": new["flight_time_k"].values[i], "states": new["state_k"].values[i],
        "pattern": "UL"})
    res = ic.simulate(o.oscillator, o.states[0], o.delta, 10.0)
    assert res.impact_stops[:4] == "LULU"
    np.testing.assert_allclose(res.impact_times[:2], np.cumsum(o.flight_times), atol=1e-9)


def test_two_sided_branch_derivatives_are_exact(unequal):
    """dF/du and dF/dlam (omega, b, R) of the LU shooting system against differences."""
    osc = unequal.oscillator
    u = unequal.unknowns
    for parameter in ("omega", "b", "R"):
        problem = MultiImpactBranchProblem(osc, 1, 2, parameter, pattern=unequal.pattern)
        lam = float(getattr(osc, parameter))
        assert np.max(np.abs(problem.residual(u, lam))) <= 1e-11
        h = 1e-6
        fd = (problem.residual(u, lam + h) - problem.residual(u, lam - h)) / (2 * h)
        np.testing.assert_allclose(problem.dparam(u, lam), fd, rtol=0, atol=1e-8)
    J = shooting(Flow(osc), 1, 2, u, pattern=unequal.pattern).jacobian
    for c in range(u.size):
        e = np.zeros(u.size)
        e[c] = 1e-6
        fd = (problem.residual(u + e, lam) - problem.residual(u - e, lam)) / 2e-6
        np.testing.assert_allclose(J[:, c], fd, rtol=0, atol=1e-8)


def test_two_sided_branch_in_omega_round_trip(tmp_path, symmetric):
    ds = multi_impact_continuation(symmetric, "omega", (0.7, 0.9), max_points=30)
    validate_multi_impact_dataset(ds)
    assert pattern_of(ds) == symmetric.pattern
    path = tmp_path / "two_sided.nc"
    ic.save(ds, path)
    back = ic.load(path)
    assert back.attrs["pattern"] == symmetric.pattern
    osc = ic.dataset.oscillator_from_dataset(back)
    assert osc.stops == symmetric.oscillator.stops
    # the stored motions are motions of the two-sided system
    i = ds.sizes["point"] // 2
    again = multi_impact_orbit(ic.dataset.oscillator_from_dataset(back, i), 1, 2, {
        "delta": float(back["delta_k"].values[i, 0]),
        "flight_times": back["flight_time_k"].values[i], "states": back["state_k"].values[i],
        "pattern": pattern_of(back)})
    np.testing.assert_allclose(again.impact_velocities, back["impact_velocity_k"].values[i],
                               atol=1e-10)


def test_two_sided_branch_in_b_moves_the_upper_stop_only(unequal):
    ds = multi_impact_continuation(unequal, "b", (0.6, 0.8), max_points=12,
                                   both_directions=True)
    assert ds.sizes["point"] >= 5 and pattern_of(ds) == unequal.pattern
    j = unequal.pattern.index("U")
    for i in (0, ds.sizes["point"] - 1):
        osc = ic.dataset.oscillator_from_dataset(ds, i)
        assert osc.stops == unequal.oscillator.stops  # b_low, R_low unchanged
        states = ds["state_k"].values[i]
        assert states[j, 0] == pytest.approx(osc.b, abs=1e-12)
        assert states[1 - j, 0] == pytest.approx(-0.5, abs=1e-12)
        o = multi_impact_orbit(osc, 1, 2, {"delta": float(ds["delta_k"].values[i, 0]),
                                           "flight_times": ds["flight_time_k"].values[i],
                                           "states": states, "pattern": unequal.pattern})
        np.testing.assert_allclose(o.states, states, atol=1e-10)


def test_branch_in_R_low_lands_on_the_bound_one(unequal):
    """R_low up to 1.0: the problem refuses R_low > 1, so every step past the bound was
    refused and the branch ended 'step size fell below ds_min' at R_low = 0.99999999; it
    lands on R_low = 1 now. The motion there, re-solved on a fresh oscillator built with
    R_low = 1, is repeated by the simulator (elastic lower impacts)."""
    ds = multi_impact_continuation(unequal, "R_low", (0.5, 1.0), max_points=60,
                                   both_directions=False)
    record = json.loads(ds.attrs["options"])
    assert record["status"] == ["BOUNDS_REACHED"]
    assert record["message"] == "parameter bound reached: R_low = 1"
    last = ds.sizes["point"] - 1
    assert ds["R_low"].values[last] == 1.0
    assert ic.dataset.oscillator_from_dataset(ds, last).stops.R_low == 1.0
    fresh = paper2(0.7, 0.9, b_low=0.5, R_low=1.0)
    states = ds["state_k"].values[last]
    orbit = multi_impact_orbit(fresh, 1, 2, {"delta": float(ds["delta_k"].values[last, 0]),
                                             "flight_times": ds["flight_time_k"].values[last],
                                             "states": states, "pattern": unequal.pattern})
    assert orbit.physical and orbit.stable
    np.testing.assert_allclose(orbit.states, states, atol=1e-10)
    np.testing.assert_allclose(orbit.flight_times, ds["flight_time_k"].values[last],
                               atol=1e-10)
    res = ic.simulate(fresh, orbit.states[0], float(orbit.phases[0]), 10.0)
    k = res.impact_times.size
    assert res.success and k >= 19
    reps = k // orbit.p + 1
    np.testing.assert_allclose(res.impact_times,
                               np.cumsum(np.tile(orbit.flight_times, reps))[:k], atol=1e-9)
    np.testing.assert_allclose(res.impact_velocities,
                               np.tile(np.roll(orbit.impact_velocities, -1), reps)[:k],
                               atol=1e-9)


# ------------------------------------------------------------------------------------------
# A stop on mass k of a chain
# ------------------------------------------------------------------------------------------
def _swap(n, k):
    perm = np.arange(n)
    perm[[0, k]] = perm[[k, 0]]
    return perm


def test_stop_on_mass_k_agrees_with_the_relabelled_closed_form(make_chain):
    """A stop on mass 2 of a 3-mass chain is a stop on mass 1 of the relabelled chain."""
    base = make_chain(3, b=0.05, omega=1.1)
    n, k = 3, 1
    perm = _swap(n, k)
    P = np.eye(n)[perm]
    relabelled = ic.ImpactOscillator(M=P @ base.M @ P.T, K=P @ base.K @ P.T, F=P @ base.F,
                                     R=base.R, b=base.b, omega=base.omega, eta=base.eta)
    osc = base.replace(stops=Stops(mass=k + 1))
    with pytest.raises(ParameterError, match="closed form"):
        ic.periodic_orbits(osc, 1)
    closed = [o for o in ic.periodic_orbits(relabelled, 1) if o.physical]
    assert closed
    for ref in closed:
        state_perm = np.concatenate([ref.state[:n][perm], ref.state[n:][perm]])  # P^-1 = P
        guess = {"delta": ref.delta, "flight_times": [ref.period], "states": [state_perm]}
        o = multi_impact_orbit(osc, 1, 1, guess)
        assert o.physical
        assert o.delta == pytest.approx(ref.delta, abs=1e-10)
        np.testing.assert_allclose(o.states[0], state_perm, rtol=0, atol=1e-10)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-10)
        assert o.gap_min == pytest.approx(ref.gap_min, abs=1e-10)
        np.testing.assert_allclose(np.sort_complex(o.multipliers),
                                   np.sort_complex(ref.multipliers), atol=1e-10)
        res = ic.simulate(osc, o.states[0], o.delta, 50.0)
        assert res.success and set(res.impact_stops) == {"U"}
        T = 2 * math.pi / osc.omega
        np.testing.assert_allclose(res.impact_times, T * np.arange(1, res.impact_times.size + 1),
                                   rtol=0, atol=1e-9)
        np.testing.assert_allclose(res.impact_velocities, o.impact_velocity, rtol=0, atol=1e-9)
        np.testing.assert_allclose(res.impact_states[:, k], osc.b, rtol=0, atol=0)


def test_two_sided_stop_on_mass_2_confirmed_by_simulation(make_chain):
    osc = make_chain(3, b=0.5, omega=1.4, eta=0.15, stops=Stops(mass=2, b_low=0.4, R_low=0.8))
    res = ic.simulate(osc, np.zeros(6), 0.0, 150.0)
    assert res.success and set(res.impact_stops[-40:]) == {"U", "L"}
    # the period of the settled motion: the smallest p whose pattern and velocities repeat
    for p in range(2, 9):
        v = res.impact_velocities
        if np.max(np.abs(v[-p:] - v[-2 * p:-p])) < 1e-6:
            break
    N = round((res.impact_times[-1] - res.impact_times[-1 - p]) * osc.omega / (2 * math.pi))
    o = multi_impact_orbit(osc, N, p, res)
    assert o.physical and o.pattern == res.impact_stops[-p - 1:-1]
    again = ic.simulate(osc, o.states[0], o.delta, 50.0)
    reps = again.impact_times.size // p + 1
    expected_t = np.cumsum(np.tile(o.flight_times, reps))[:again.impact_times.size]
    np.testing.assert_allclose(again.impact_times, expected_t, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(again.impact_states[:, 1],
                                  _stop_positions(osc, again.impact_stops))


# ------------------------------------------------------------------------------------------
# Sticking and chatter at the lower stop
# ------------------------------------------------------------------------------------------
def one_dof(**kw):
    params = {"M": [[1.0]], "K": [[1.0]], "F": [1.0], "R": 0.5, "b": 0.5, "omega": 0.1,
              "eta": 0.05, "stops": Stops(b_low=0.5, R_low=0.5)}
    params.update(kw)
    return ic.ImpactOscillator(**params)


def test_sticking_at_the_lower_stop():
    # at rest on x = -b_low with x'' = F cos(pi) + b_low = -0.5 < 0: pushed into the stop
    res = ic.simulate(one_dof(), [-0.5, 0.0], math.pi, 1.0, stop_at=("sticking",))
    assert res.status is SimulationStatus.STICKING
    # not asked to stop: held on the stop from t = 0 (issue 30)
    res = ic.simulate(one_dof(), [-0.5, 0.0], math.pi, 1.0)
    assert res.sticking[0].stops == "L" and res.sticking[0].start == 0.0
    # at rest there with the force pulling away (x'' = 1.5): it leaves the stop, and its
    # first impact is on the upper stop, after a flight across the clearance
    res = ic.simulate(one_dof(), [-0.5, 0.0], 0.0, 0.2)
    assert res.impact_stops[0] == "U" and res.impact_times[0] > 1.0


def test_chatter_at_the_lower_stop():
    res = ic.simulate(one_dof(), [-0.5, 0.05], math.pi, 1.0, stop_at=("chatter",))
    assert res.status is SimulationStatus.CHATTER
    assert set(res.impact_stops) == {"L"}
    v = res.impact_velocities
    np.testing.assert_allclose(v[1:] / v[:-1], 0.5, rtol=5e-3)  # R_low per bounce


# ------------------------------------------------------------------------------------------
# The model: round trips and bad input
# ------------------------------------------------------------------------------------------
def test_stops_round_trip_and_replace():
    osc = paper2(0.5, 1.3, mass=2, b_low=0.35, R_low=0.85)
    back = ic.ImpactOscillator.from_json(osc.to_json())
    assert back.stops == osc.stops == Stops(mass=2, b_low=0.35, R_low=0.85)
    assert json.loads(osc.to_json())["stops"] == {"mass": 2, "b_low": 0.35, "R_low": 0.85}
    assert osc.replace(omega=1.0).stops == osc.stops
    assert osc.replace(b=0.1).stops == osc.stops
    assert "stops" not in paper2(0.5, 1.3).to_dict()  # the paper's model is unchanged
    assert paper2(0.5, 1.3).stops.paper
    # R_low defaults to R
    assert paper2(0.5, 1.3, b_low=0.2).stops.R_low == 0.6
    D = osc.D
    assert D[3, 3] == -0.6 and D[2, 2] == 1.0  # -R on the velocity of mass 2
    # a mapping is accepted for stops
    assert ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1, 0], R=0.6, b=0.5, omega=1.0,
                               stops={"mass": 2}).stops == Stops(mass=2)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"mass": 0}, "stops.mass must be an integer >= 1"),
    ({"mass": 1.5}, "stops.mass must be an integer >= 1"),
    ({"mass": True}, "stops.mass must be an integer >= 1"),
    ({"R_low": 0.5}, "needs a lower stop"),
    ({"b_low": math.nan}, "stops.b_low must be a finite real number"),
    ({"b_low": 0.5, "R_low": 1.5}, r"stops.R_low must be in \[0, 1\]"),
])
def test_bad_stops(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Stops(**kwargs)


def test_bad_stops_for_the_oscillator():
    with pytest.raises(ParameterError, match=r"stops.mass must be in 1..2"):
        paper2(0.5, 1.0, mass=3)
    with pytest.raises(ParameterError, match="must lie below the upper stop"):
        paper2(0.5, 1.0, b_low=-0.6)
    osc = paper2(0.5, 1.0, b_low=0.2)
    with pytest.raises(ParameterError, match="must lie below the upper stop"):
        osc.replace(b=-0.3)
    with pytest.raises(ParameterError, match="unknown key"):
        ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1, 0], R=0.6, b=0.5, omega=1.0,
                            stops={"mass": 1, "gap": 0.1})
    with pytest.raises(TypeError, match="stops must be a Stops or a mapping"):
        ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1, 0], R=0.6, b=0.5, omega=1.0, stops=2)


def test_bad_patterns_and_states():
    two = Stops(b_low=0.5)
    assert check_pattern(None, 3, two) == "UUU"
    with pytest.raises(ParameterError, match="pattern must be 2 letters"):
        check_pattern("UX", 2, two)
    with pytest.raises(ParameterError, match="pattern must be 2 letters"):
        check_pattern("ULU", 2, two)
    with pytest.raises(ParameterError, match="the oscillator has none"):
        check_pattern("UL", 2, Stops())
    with pytest.raises(TypeError, match="pattern must be a string"):
        check_pattern(["U", "L"], 2, two)
    osc = paper2(0.5, 1.0, b_low=0.5)
    with pytest.raises(ParameterError, match="beyond the lower stop"):
        ic.simulate(osc, [-0.6, 0.0, 0.0, 0.0], 0.0, 1.0)
    with pytest.raises(ParameterError, match="differs from the guess's impact sequence"):
        multi_impact_orbit(osc, 1, 2, {"delta": 0.0, "flight_times": [1.0, 1.0],
                                       "states": np.zeros((2, 4)), "pattern": "UL"},
                           pattern="LU")
    for what in (lambda: ic.continuation(osc, 1, "omega", (0.5, 1.5)),
                 lambda: ic.stability_map(osc, 1, omega=[1.0], b=[0.5])):
        with pytest.raises(ParameterError, match=r"closed form of eq\. \(12\)-\(16\)"):
            what()


# ==========================================================================================
# QA of the two-sided stops as a user meets them: what was silently wrong or unclear.
#
# Each test pins one problem found by trying the API (issue 14 item 2): the
# witness is the event-driven simulator or the refusal's own message.
# ==========================================================================================
def paper_system(**kw) -> ic.ImpactOscillator:
    """The paper's 2-DOF system (section 4), parameters overridden by `kw`."""
    params = dict(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8, omega=0.8, eta=0.1)
    params.update(kw)
    return ic.ImpactOscillator(**params)


# ------------------------------------------------------------------------------------------
# next_impact (public in impactcont.simulate) ignored osc.stops: it followed x1 to x1 = b
# ------------------------------------------------------------------------------------------
def test_next_impact_follows_the_stop_mass():
    """Stop on mass 2: the first impact is the simulator's (x2 = b), not x1's crossing."""
    osc = paper_system(F=[0.0, 1.0], b=0.2, stops=Stops(mass=2))
    X = np.zeros(4)
    tau, X_minus = next_impact(Flow(osc), X, 0.0, 50.0)
    res = ic.simulate(osc, X, 0.0, 3.0)
    assert tau == pytest.approx(res.impact_times[0], abs=1e-10)
    assert X_minus[1] == pytest.approx(0.2, abs=1e-12)


def test_next_impact_refuses_two_stops():
    """With a lower stop next_impact cannot say which stop is hit: refused, naming next_contact."""
    osc = paper_system(stops=Stops(b_low=0.8))
    with pytest.raises(ParameterError, match="next_contact"):
        next_impact(Flow(osc), np.array([-0.7, 0.0, -1.0, 0.0]), 0.0, 50.0)


# ------------------------------------------------------------------------------------------
# Scene: a bad stop key was reported at [oscillator], not at the key the user wrote
# ------------------------------------------------------------------------------------------
_SCENE = """
[oscillator]
K = [[1.0, -1.0], [-1.0, 2.0]]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.7
omega = 0.9
{extra}
"""


@pytest.mark.parametrize("extra, key", [
    ("stop_mass = 3", "oscillator.stop_mass"),
    ("R_low = 0.5", "oscillator.R_low"),
    ("b_low = -0.7", "oscillator.b_low"),
])
def test_scene_stop_errors_point_at_the_key(tmp_path: Path, extra: str, key: str):
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, _SCENE.format(extra=extra)))
    assert info.value.key == key, str(info.value)


# ------------------------------------------------------------------------------------------
# Scene outputs: a [[simulations]] + [[multi_impact]] scene with two stops
# ------------------------------------------------------------------------------------------
_RUN = _SCENE.format(extra="b_low = 0.5\nR_low = 0.8") + """
[[simulations]]
name = "sim"
periods = 200
start = "state"
state = [0.0, 0.0, 0.0, 0.0]
delta = 0.0

[[multi_impact]]
name = "mi"
start = "sim"
N = 1
p = 2
bounds = [0.85, 0.95]
max_points = 40
"""


@pytest.fixture(scope="module")
def two_stop_run(tmp_path_factory):
    from impactcont.scene import run_scene

    tmp = tmp_path_factory.mktemp("run")
    result = run_scene(write(tmp, _RUN), output=tmp / "o")
    assert result.ok, result.failures
    return tmp / "o"


def test_scene_simulation_describes_its_impact_velocities(two_stop_run):
    """The stored speeds are towards the stop hit (x_j' at U, -x_j' at L), not mass 1's velocity."""
    from impactcont.scene import read_output

    sim = read_output(two_stop_run / "simulations.nc").datasets["sim"]
    stops = sim.attrs["impact_stops"]
    assert set(stops) == {"U", "L"}
    v = sim["impact_velocities"].values
    assert np.all(v > 0)
    assert "mass 1" not in sim["impact_velocities"].attrs["description"]
    assert "stop" in sim["impact_velocities"].attrs["description"]


def test_scene_info_shows_the_impact_pattern(two_stop_run):
    """``impactcont info`` of an N-p branch names p and the pattern (here 'LU')."""
    from impactcont.scene.describe import describe_file

    text = describe_file(two_stop_run / "multi_impact.nc")
    assert "LU" in text, text


# ------------------------------------------------------------------------------------------
# A failed Newton names the impact sequence it tried
# ------------------------------------------------------------------------------------------
def test_newton_failure_names_the_pattern():
    """Complex F, two stops: the attractor is a 1-4 motion; asking for a 1-2 one fails, and
    the message says which sequence of stops was tried (the simulation's last impacts)."""
    osc = paper_system(F=np.array([1.0, 0.5j]), b=0.7, omega=0.9,
                 stops=Stops(b_low=0.5, R_low=0.8))
    res = ic.simulate(osc, np.zeros(4), 0.0, 300.0)
    assert len(set(res.impact_stops[-8:])) == 2
    with pytest.raises(ic.NoPeriodicMotionError,
                       match=f"pattern {res.impact_stops[-3:-1]!r}"):
        ic.multi_impact_orbit(osc, 1, 2, res)
    orbit = ic.multi_impact_orbit(osc, 1, 4, res)  # the motion it settled on
    assert orbit.physical and orbit.stable
    assert sorted(orbit.pattern) == sorted(res.impact_stops[-5:-1])


# ------------------------------------------------------------------------------------------
# The "returned to its parent" stop of an N-p branch compared halves with different stops
# ------------------------------------------------------------------------------------------
def test_asymmetry_ignores_halves_on_different_stops():
    """A 2-2 motion "UL" can never be a 1-1 motion repeated: its halves hit different stops,
    so the parent test (halves equal, or swapped) must not apply. Its phase difference
    sits at +-pi, whose sign flips by rounding and would end the branch spuriously."""
    from types import SimpleNamespace

    from impactcont.analysis.branch import _asymmetry

    def orbit(pattern, dphase):
        return SimpleNamespace(N=2, p=2, pattern=pattern, phases=np.array([0.0, dphase]),
                               states=np.array([[0.8, 0.1, 0.3, 0.2], [-0.8, -0.1, -0.3, -0.2]]),
                               flight_times=np.array([3.0, 3.0]))

    assert _asymmetry(orbit("UL", np.pi)) is None
    assert _asymmetry(orbit("UU", np.pi)) is not None  # same stops: the test applies


# ------------------------------------------------------------------------------------------
# Datasets: a pattern with lower-stop impacts needs an oscillator with a lower stop
# ------------------------------------------------------------------------------------------
def test_dataset_refuses_a_lower_stop_pattern_without_a_lower_stop(tmp_path: Path):
    """A branch saved with pattern 'LU' but an oscillator with one stop was accepted, and
    failed only later (special_orbit, switching) with a message about the orbit."""
    import json

    from impactcont.dataset.multi import validate_multi_impact_dataset

    osc = paper_system(b=0.7, omega=0.9, stops=Stops(b_low=0.5, R_low=0.8))
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 200.0))
    assert orbit.pattern == "LU"
    ds = ic.multi_impact_continuation(orbit, "omega", (0.88, 0.92), max_points=5)
    validate_multi_impact_dataset(ds)
    data = json.loads(ds.attrs["oscillator"])
    del data["stops"]
    bad = ds.copy()
    bad.attrs["oscillator"] = json.dumps(data)
    with pytest.raises(ValueError, match="lower stop"):
        validate_multi_impact_dataset(bad)


# ------------------------------------------------------------------------------------------
# Scene [[simulations]]: the start state is checked against the stops of stop_mass
# ------------------------------------------------------------------------------------------
_SIM = """
[[simulations]]
name = "sim"
periods = 5
{start}
"""


def test_scene_simulation_state_on_another_mass_is_accepted(tmp_path: Path):
    """stop_mass = 2: x1 = 0.75 > b is allowed (mass 1 meets no stop); it was refused."""
    text = (_SCENE.format(extra="stop_mass = 2")
            + _SIM.format(start='start = "state"\nstate = [0.75, 0.0, 0.0, 0.0]\ndelta = 0.0'))
    load_scene(write(tmp_path, text))


@pytest.mark.parametrize("extra, state, what", [
    ("stop_mass = 2", "[0.0, 0.75, 0.0, 0.0]", "x2 = 0.75"),
    ("b_low = 0.5", "[-0.6, 0.0, 0.0, 0.0]", "x1 = -0.6"),
])
def test_scene_simulation_state_beyond_a_stop_is_refused(tmp_path: Path, extra, state, what):
    text = (_SCENE.format(extra=extra)
            + _SIM.format(start=f'start = "state"\nstate = {state}\ndelta = 0.0'))
    with pytest.raises(SceneError, match=what) as info:
        load_scene(write(tmp_path, text))
    assert info.value.key.endswith("state")


def test_scene_simulation_orbit_start_with_stops_is_refused_at_start(tmp_path: Path):
    """start = "orbit" needs the closed-form N-1 motion (one stop on mass 1): refused when
    the scene is read, at the key start, naming start = "state"."""
    text = _SCENE.format(extra="b_low = 0.5") + _SIM.format(start="")
    with pytest.raises(SceneError, match='start = "state"') as info:
        load_scene(write(tmp_path, text))
    assert info.value.key.endswith("start")


def test_scene_info_shows_the_simulation_stops(two_stop_run):
    """``impactcont info`` of a two-stop simulation shows the stops of its last impacts."""
    from impactcont.scene import read_output
    from impactcont.scene.describe import describe_file

    stops = read_output(two_stop_run / "simulations.nc").datasets["sim"].attrs["impact_stops"]
    text = describe_file(two_stop_run / "simulations.nc")
    assert stops[-8:] in text, text


# ------------------------------------------------------------------------------------------
# simulate: numpy integers for periods / delta were refused as "not a finite number"
# ------------------------------------------------------------------------------------------
def test_simulate_accepts_numpy_numbers():
    osc = paper_system(stops=Stops(b_low=0.8))
    ref = ic.simulate(osc, np.zeros(4), 0.0, 20.0)
    res = ic.simulate(osc, np.zeros(4), np.int64(0), np.int64(20))
    np.testing.assert_array_equal(res.impact_times, ref.impact_times)
    assert res.impact_stops == ref.impact_stops
    with pytest.raises(ParameterError, match="periods"):
        ic.simulate(osc, np.zeros(4), 0.0, np.float64("nan"))
    with pytest.raises(ParameterError, match="periods"):
        ic.simulate(osc, np.zeros(4), 0.0, True)
