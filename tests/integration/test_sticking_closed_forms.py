"""Periodic motions with sticking phases: closed forms (mpmath, 30 digits) as witnesses.

Three machines whose motion with a plastic impact (``R = 0``) and a sticking phase is known
in closed form from the equation of motion alone (``studies/sticking_motions/closed_form.py``,
which imports nothing from the package, issue 30 items 4 and 6):

(a) a preloaded one-mass oscillator held on its stop ``b = 0``, released where
    ``F cos(theta) + F_static`` falls to zero, flying, landing plastically, held again;
(b) Luck & Mehta's completely inelastic ball on a vibrating table (Phys. Rev. E 48, 3988,
    1993), locked, released at ``cos(theta_r) = 1 / Gamma``, landing;
(c) the impact damper of ``docs/machines.md`` with a plastic ball riding each wall in turn
    (the motion a fixed point of the closed-form return map, solved at 30 digits).

Held against the event-driven simulator (``ic.simulate``, which shares no code with the
shooting path) run to its steady state: every landing and release time to 1e-9. The
simulator locates a release and an impact to a few ulps of the time on its exact flow, so
its distance from the closed form is what the transient leaves (the largest multiplier to
the power of the periods run: about 1e-13 here) plus rounding, and 1e-9 is the issue's bar.
The multipliers of (c) against the simulator's own finite differences of its period map
(central, step 1e-6: truncation 1e-12, rounding 1e-10).

Then against the shooting path, ``multi_impact_orbit`` with a lowercase (sticking) pattern
seeded from the simulation: phases, stick and flight times, release and landing states,
impact speeds and the smallest pressing force to 1e-10. Newton solves the shooting system to
its rounding, and the solution's own error estimate (``|J^-1 r| + cond eps |u|``, condition
numbers 3 to 2e3 here) is below 1e-11, so 1e-10 is what the method guarantees with a margin;
the closed form is exact to 30 digits. The multipliers: (a) and (b) are zero (the release
phase forgets everything: n = 1, both directions collapse; to rounding, 1e-14), (c) the two
nonzero ones equal the eigenvalues of the closed-form return map's Jacobian (central
differences at 30 digits, error ~1e-20) to 1e-10, the two the ride collapses below 1e-12
(rounding of the saltation product, not structural zeros).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from tests._study_files import study_file

#: Largest landing/release time difference allowed against the simulator (issue 30).
TIME_TOL = 1e-9


@pytest.fixture(scope="module")
def cf():
    with study_file("sticking_motions", "closed_form.py") as module:
        yield module


@pytest.fixture(scope="module")
def riding(cf):
    """Case (c)'s closed form by omega, computed once per module (about 1 s each)."""
    return functools.cache(cf.riding_damper_motion)


def preloaded(omega: float) -> ic.ImpactOscillator:
    """Case (a): one mass pushed into its stop b = 0 by F_static = 1, forced 3 cos."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                               omega=omega, eta=0.05)


def ball(gamma: float) -> ic.ImpactOscillator:
    """Case (b) in the table's frame: y'' = -1 + Gamma cos(theta) over the stop y = 0."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[gamma], F_static=[-1.0], R=0.0,
                               b=1e3, omega=1.0, eta=0.0, stops=Stops(b_low=0.0, R_low=0.0))


def damper(omega: float) -> ic.ImpactOscillator:
    """Case (c): primary 1 on spring 1 (eta 0.3), plastic ball 0.2 in |x2 - x1| <= 0.3."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response at
    phase 0 (a start that is not the periodic motion: the simulator converges to it)."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


def time_apart(t: float, phase: float, omega: float, delta: float) -> float:
    """How far time `t` of a run started at phase `delta` is from the closed form's
    `phase` (mod one forcing period), in time."""
    return abs(math.remainder(delta + omega * t - phase, 2 * math.pi)) / omega


def check_against_run(motion, res, omega: float, delta: float, *, last: int) -> None:
    """The last `last` sticking phases of `res` against the closed form `motion`: each
    starts at a landing of the closed form on the same stop and ends at its release, with
    the closed form's stick time; the flight after it lasts the closed form's flight."""
    phases = [p for p in res.sticking if p.ended_by == "release"][-last:]
    assert len(phases) == last
    for held, after in zip(phases, [*phases[1:], None], strict=True):
        k = motion.pattern.index(held.stops.lower())
        assert time_apart(held.start, float(motion.phases[k]), omega, delta) < TIME_TOL
        assert time_apart(held.end, float(motion.release_phases[k]), omega, delta) < TIME_TOL
        assert held.duration == pytest.approx(float(motion.stick_times[k]), abs=TIME_TOL)
        # the landing: the stop's pressing force right after the plastic impact
        assert held.forces[0, 0] == pytest.approx(float(motion.landing_pressing[k]),
                                                  rel=1e-9)
        assert held.start_state == pytest.approx(motion.floats("landing_states")[k],
                                                 abs=1e-9)
        if after is not None:
            assert after.start - held.end == pytest.approx(float(motion.flight_times[k]),
                                                           abs=TIME_TOL)


@pytest.mark.parametrize("omega", [0.7, 2.0])
def test_preloaded_oscillator_closed_form_is_the_simulated_steady_motion(cf, omega):
    """(a) From rest on the stop at phase 0 the first release already starts the periodic
    motion (the release phase arccos(-1/3) forgets the history): three periods of held,
    released, landing at the closed form's phase with its speed, held again."""
    motion = cf.preloaded_motion(omega)
    assert float(motion.release_phases[0]) == pytest.approx(math.acos(-1.0 / 3.0), abs=1e-15)
    assert float(motion.period) == pytest.approx(2 * math.pi / omega, rel=1e-15)
    res = ic.simulate(preloaded(omega), [0.0, 0.0], 0.0, 4.0)
    assert not res.chatter  # plastic: every landing sticks at once
    check_against_run(motion, res, omega, 0.0, last=3)
    speeds = res.impact_velocities[-3:]
    assert speeds == pytest.approx([float(motion.impact_velocities[0])] * 3, rel=1e-9)


@pytest.mark.parametrize("gamma", [1.2, 2.0, 3.0])
def test_locked_ball_closed_form_is_the_simulated_steady_motion(cf, gamma):
    """(b) Luck & Mehta's ball with R = 0 locks on every landing: released at
    theta_r = -arccos(1/Gamma), landing at the first return of the parabola relative to the
    table, within one period for Gamma up to 3 (at 3.3 the flight outlasts the period)."""
    motion = cf.locked_ball_motion(gamma)
    assert float(motion.release_phases[0]) == pytest.approx(-math.acos(1.0 / gamma),
                                                            abs=1e-15)
    res = ic.simulate(ball(gamma), [0.0, 0.0], -0.5 * math.pi, 5.0)
    check_against_run(motion, res, 1.0, -0.5 * math.pi, last=3)
    with pytest.raises(ValueError, match="no return to the stop"):
        cf.locked_ball_motion(3.3)


def test_riding_damper_closed_form_is_the_simulated_steady_motion(riding):
    """(c) The plastic ball rides the upper wall, is released where the primary's
    acceleration changes sign, crosses the clearance, lands on the lower wall, rides it,
    ...: the simulator from the held forced response converges to the closed form's fixed
    point (multipliers 0.016 and 1.4e-4 besides the stick's zeros: the error shrinks 64
    times a period, 12 periods leave ~1e-13)."""
    omega = 0.2
    motion = riding(omega)
    assert motion.pattern == "lu"
    assert float(motion.period) == pytest.approx(2 * math.pi / omega, rel=1e-15)
    # the symmetric motion: half a period apart, the mirror image
    assert math.remainder(float(motion.phases[1] - motion.phases[0]) - math.pi,
                          2 * math.pi) == pytest.approx(0.0, abs=1e-20)
    osc = damper(omega)
    res = ic.simulate(osc, riding_start(osc), 0.0, 12.0)
    assert not res.chatter
    check_against_run(motion, res, omega, 0.0, last=4)


def test_riding_damper_multipliers_are_the_simulators_finite_differences(riding):
    """(c) at omega = 0.5 (a complex pair): on the section in the middle of the ride on the
    upper wall the state is (x1, x1'); one period of the simulator from the closed form's
    state returns to it (to rounding), and its central differences give the 2 x 2 Jacobian
    whose eigenvalues are the closed form's nonzero multipliers."""
    omega, h = 0.5, 1e-6
    motion = riding(omega)
    osc, k = damper(omega), motion.pattern.index("u")
    half = float(motion.stick_times[k]) / 2
    theta0 = float(motion.phases[k]) + omega * half
    landing = np.asarray(motion.floats("landing_states")[k])
    x0 = ic.simulate(osc, landing, float(motion.phases[k]), half * omega / (2 * math.pi))
    base = x0.final_state[[0, 2]]

    def period_map(y):
        state = np.array([y[0], y[0] + osc.b, y[1], y[1]])
        return ic.simulate(osc, state, theta0, 1.0).final_state[[0, 2]]

    assert period_map(base) == pytest.approx(base, abs=1e-14)
    J = np.column_stack([(period_map(base + e) - period_map(base - e)) / (2 * h)
                         for e in np.eye(2) * h])
    simulated = sorted(np.linalg.eigvals(J), key=lambda z: z.imag)
    exact = sorted((complex(z) for z in motion.multipliers[:2]), key=lambda z: z.imag)
    assert abs(exact[0].imag) > 0.03  # a complex pair
    assert simulated == pytest.approx(exact, abs=1e-8)


def check_shooting(motion, orbit) -> None:
    """`orbit` (``multi_impact_orbit``) against the closed form, impact by impact."""
    assert orbit.pattern == motion.pattern and orbit.physical, orbit.reason
    assert orbit.error_estimate < 1e-11
    phases = np.array(motion.floats("phases"))
    assert np.abs(np.remainder(orbit.phases - phases + np.pi, 2 * np.pi) - np.pi).max() < 1e-10
    for name, mine in (("stick_times", "stick_times"), ("flight_times", "flight_times"),
                       ("release_states", "release_states"), ("states", "landing_states"),
                       ("impact_velocities", "impact_velocities"),
                       ("pressing_min", "pressing_min")):
        assert getattr(orbit, name) == pytest.approx(np.array(motion.floats(mine)), abs=1e-10,
                                                     rel=0), name


@pytest.mark.parametrize("omega", [0.7, 2.0])
def test_preloaded_oscillator_shooting_is_the_closed_form(cf, omega):
    """(a) multi_impact_orbit(pattern="u") from the simulation: the closed form, and both
    multipliers zero (to rounding: G is a product through the stick's collapse, and seeds
    from 4 periods or more leave 1.5e-31 on its diagonal)."""
    motion = cf.preloaded_motion(omega)
    res = ic.simulate(preloaded(omega), [0.0, 0.0], 0.0, 3.0)
    orbit = ic.multi_impact_orbit(preloaded(omega), 1, 1, res, pattern="u")
    check_shooting(motion, orbit)
    assert np.abs(orbit.multipliers).max() < 1e-14


@pytest.mark.parametrize("gamma", [1.2, 3.0])
def test_locked_ball_shooting_is_the_closed_form(cf, gamma):
    """(b) multi_impact_orbit(pattern="l") from the simulation: the closed form, and both
    multipliers zero to rounding (Luck & Mehta's locked motion forgets its history)."""
    motion = cf.locked_ball_motion(gamma)
    res = ic.simulate(ball(gamma), [0.0, 0.0], -0.5 * math.pi, 3.0)
    orbit = ic.multi_impact_orbit(ball(gamma), 1, 1, res, pattern="l")
    check_shooting(motion, orbit)
    assert np.abs(orbit.multipliers).max() < 1e-14


@pytest.mark.parametrize("omega", [0.2, 0.5])
def test_riding_damper_shooting_is_the_closed_form(riding, omega):
    """(c) multi_impact_orbit(pattern="lu") from the simulation: the closed form, the two
    nonzero multipliers those of the closed-form return map (real at 0.2, a complex pair at
    0.5), the other two the ride's collapsed directions."""
    motion = riding(omega)
    osc = damper(omega)
    res = ic.simulate(osc, riding_start(osc), 0.0, 12.0)
    orbit = ic.multi_impact_orbit(osc, 1, 2, res, pattern="lu")
    check_shooting(motion, orbit)
    mu = sorted(orbit.multipliers, key=lambda z: (-abs(z), z.imag))
    exact = sorted((complex(z) for z in motion.multipliers), key=lambda z: (-abs(z), z.imag))
    assert mu[:2] == pytest.approx(exact[:2], abs=1e-10)
    assert np.abs(mu[2:]).max() < 1e-12


def test_riding_damper_ends_where_the_shooting_stick_time_vanishes(cf):
    """(c) in omega: the ride shrinks to nothing where the ball lands as the wall stops
    pressing it; the closed form of that end (the landing is a release: three equations in
    theta, x1', omega, solved from the shooting's release near it) is omega* = 2.39342...
    The shooting, followed from omega = 2.3, keeps a positive stick time and a physical
    motion 1e-7 below omega* and has a negative one, flagged non-physical, 1e-7 above it
    (the stick time's slope there is about -0.6 per unit of omega: +-6e-8, far above the
    rounding)."""
    osc = damper(2.3)
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 16.0))

    def follow(orbit, omega):
        scale = orbit.oscillator.omega / omega
        return ic.multi_impact_orbit(damper(omega), 1, 2, {
            "delta": orbit.delta, "flight_times": orbit.flight_times * scale,
            "stick_times": orbit.stick_times * scale, "states": orbit.states,
            "pattern": orbit.pattern})

    orbit = follow(orbit, 2.39)
    k = orbit.pattern.index("u")
    release = orbit.release_states[k]
    theta_r = orbit.phases[k] + orbit.oscillator.omega * orbit.stick_times[k]
    omega_end = float(cf.riding_end((theta_r, release[2], 2.39))[0])
    assert 2.39 < omega_end < 2.4
    below = follow(orbit, omega_end - 1e-7)
    above = follow(below, omega_end + 1e-7)
    assert below.pattern.islower() and above.pattern.islower()
    assert below.physical and np.all(below.stick_times > 0)
    assert not above.physical and np.all(above.stick_times < 0)
    assert "duration" in above.reason


def test_locked_ball_motion_ends_at_its_closed_form_limit(cf):
    """(b) The locked motion of one table period exists up to Gamma_1 = sqrt(1 + pi^2),
    where the flight fills the period (derived in closed_form.locked_ball_limit): just
    below, the stick is short (it vanishes linearly) and the shooting finds it; just above,
    no landing within the period."""
    limit = float(cf.locked_ball_limit())
    assert limit == pytest.approx(math.sqrt(1 + math.pi**2), rel=1e-15)
    near = cf.locked_ball_motion(limit - 1e-4)
    assert 0 < float(near.stick_times[0]) < 1e-3
    res = ic.simulate(ball(limit - 1e-4), [0.0, 0.0], -0.5 * math.pi, 4.0)
    check_shooting(near, ic.multi_impact_orbit(ball(limit - 1e-4), 1, 1, res, pattern="l"))
    with pytest.raises(ValueError, match="no return to the stop"):
        cf.locked_ball_motion(limit + 1e-6)
