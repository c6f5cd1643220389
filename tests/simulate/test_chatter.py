"""Complete chatter (:mod:`impactcont.simulate.chatter`): the accumulation point of the
impacts taken by the geometric estimate (Budd & Dux 1994; Nordmark & Piiroinen 2009) and
the sticking phase after it, against closed forms and against the chatter resolved impact
by impact."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont import ParameterError, SimulationStatus, simulate
from impactcont.model.stops import Stops
from impactcont.simulate.chatter import accumulation
from impactcont.simulate.flight import Flight
from impactcont.simulate.sticking import HeldFlight

EPS = float(np.finfo(float).eps)


def _ball(R=0.6, g=1.0, A=0.0, omega=1.0):
    """A ball of unit mass under gravity g above a table at height 0 vibrating as
    A cos(theta): its height over the table obeys y'' = -g + A omega^2 cos(theta)."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[A * omega**2], F_static=[-g], R=R,
                               b=1e3, omega=omega, eta=0.0, stops=Stops(b_low=0.0, R_low=R))


def test_ball_on_a_fixed_floor_accumulates_in_closed_form():
    """Dropped from h at rest: first impact at sqrt(2 h / g) at speed sqrt(2 g h); the
    bounces form the geometric series exactly (constant acceleration), accumulating at
    t_1 + 2 R v_1 / (g (1 - R)); then the ball lies on the floor, pressed by g."""
    g, h, R = 1.0, 0.5, 0.6
    res = simulate(_ball(R, g), [h, 0.0], 0.0, 2.0, trajectory=True)
    assert res.success and len(res.chatter) == 1
    t1, v1 = math.sqrt(2 * h / g), math.sqrt(2 * g * h)
    k = res.impact_times.size
    speeds = v1 * R ** np.arange(k)
    np.testing.assert_allclose(res.impact_velocities, speeds, rtol=64 * EPS)
    np.testing.assert_allclose(res.impact_times, t1 + np.cumsum(np.append(0, 2 * speeds[1:]
                                                                          / g)), rtol=64 * EPS)
    point = res.chatter[0]
    assert point.stop == "L" and point.last_velocity == res.impact_velocities[-1]
    # the remaining bounces summed: the geometric series of (C1), exact here
    assert point.time == pytest.approx(t1 + 2 * R * v1 / (g * (1 - R)), rel=64 * EPS)
    # the jump is taken once the bounces are small (apex below 1e-6 a (2 pi / omega)^2)
    apex = (R * point.last_velocity) ** 2 / (2 * g)
    assert apex <= 1e-6 * g * (2 * math.pi) ** 2 < apex / R**2
    (lying,) = res.sticking
    assert lying.start == point.time and lying.ended_by == "end"
    np.testing.assert_allclose(lying.forces[:, 0], g, rtol=1e-14)
    assert res.X[:, 0].min() >= -4 * EPS


def test_locked_ball_on_a_vibrating_table_leaves_at_the_closed_form_phase():
    """Luck & Mehta 1993 (Phys. Rev. E 48, 3988): on a table vibrating with Gamma =
    A w^2 / g > 1 the ball chatters, locks onto the table, and is released each time the
    table's acceleration reaches -g: at the phase theta_r = -arccos(1 / Gamma) (mod 2 pi),
    wherever the locking began."""
    g, A, om = 1.0, 1.5, 1.0
    res = simulate(_ball(0.5, g, A, om), [0.0, 0.0], -0.5 * math.pi, 6.0)
    assert res.success and res.chatter
    releases = [p for p in res.sticking if p.ended_by == "release"]
    assert len(releases) >= 3
    theta_r = -math.acos(g / (A * om**2))
    for phase in releases:
        theta = om * phase.end - 0.5 * math.pi
        assert math.remainder(theta - theta_r, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
        assert phase.forces[-1, 0] == pytest.approx(0.0, abs=1e-13)
    # each lock begins at an accumulation point of the chatter before it
    starts = {p.start for p in res.sticking}
    assert all(c.time in starts for c in res.chatter)


def _one_dof():
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[1.0], R=0.5, b=0.5, omega=0.1,
                               eta=0.05, stops=Stops(b_low=0.5, R_low=0.5))


def test_chatter_at_the_lower_stop_goes_through():
    """The chatter that used to end the run (CHATTER): the impacts on L decrease by R_low,
    accumulate, the mass lies on the stop until the force lifts it off; stop_at=("chatter",)
    keeps the old end."""
    res = simulate(_one_dof(), [-0.5, 0.05], math.pi, 1.0)
    assert res.success
    point = res.chatter[0]
    before = res.impact_times <= point.last_impact
    v = res.impact_velocities[before]
    np.testing.assert_allclose(v[1:] / v[:-1], 0.5, rtol=5e-3)
    phase = res.sticking[0]
    assert (phase.start, phase.stops, phase.ended_by) == (point.time, "L", "release")
    # released where F cos(theta) + b_low = 0 (x = -0.5 at rest: x'' = cos(theta) + 0.5)
    theta = 0.1 * phase.end + math.pi
    assert math.cos(theta) + 0.5 == pytest.approx(0.0, abs=1e-13)
    stopped = simulate(_one_dof(), [-0.5, 0.05], math.pi, 1.0, stop_at=("chatter",))
    assert stopped.status is SimulationStatus.CHATTER
    assert stopped.final_time == point.last_impact
    with pytest.raises(ParameterError, match="chatter_tolerance must be a number in"):
        simulate(_one_dof(), [-0.5, 0.05], math.pi, 1.0, chatter_tolerance=0.0)


def test_jump_agrees_with_the_chatter_resolved_impact_by_impact():
    """The paper's two masses, mass 1 pushed into its stop by F_static: a chatter, a stick,
    a release, impacts. Jumping earlier (a looser chatter_tolerance, a larger last impact
    speed v_k) moves the accumulation time and everything after it by O(v_k^2) against a
    chatter resolved down to v_k ~ 6e-6: the error shrinks with v_k and stays below v_k^2."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                              omega=0.5, eta=0.1, F_static=[0.5, 0.0])

    def run(tol):
        return simulate(osc, [-0.5, 0, 0, 0], 0.0, 2.0, chatter_tolerance=tol)

    ref = run(1e-5)
    assert ref.chatter[0].last_velocity < 1e-5
    errors = []
    for tol in (1e-1, 1e-2, 1e-3):
        res = run(tol)
        v_k = res.chatter[0].last_velocity
        assert res.impact_times.size - res.impact_times.searchsorted(res.chatter[0].time) == \
            ref.impact_times.size - ref.impact_times.searchsorted(ref.chatter[0].time)
        error = max(abs(res.chatter[0].time - ref.chatter[0].time),
                    abs(res.sticking[0].end - ref.sticking[0].end),
                    abs(res.impact_times[-1] - ref.impact_times[-1]),
                    float(np.abs(res.final_state - ref.final_state).max()))
        assert error <= v_k**2, (tol, v_k, error)
        errors.append(error)
    assert errors[0] > errors[1] > errors[2]


def test_incomplete_chatter_is_resolved_impact_by_impact():
    """The jump is taken only when the accumulation comes before the contact force
    reverses: just before the release of the preloaded oscillator (pressing
    3 cos(theta) + 1), a bounce whose accumulation would come after it is not jumped."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                              omega=0.7, eta=0.0)
    view = osc.stops.stop("U", osc.M, osc.b, osc.R)
    theta_r = math.acos(-1.0 / 3.0)
    theta = theta_r - 0.01  # the force reverses 0.01 / omega later; a = 3 cos + 1 ~ 0.028
    a = 3 * math.cos(theta) + 1
    flight, held = Flight(osc), HeldFlight(osc, ["U"])

    def jump(u):  # condition (i) set aside: only the sign of the force decides
        return accumulation(flight, lambda: held, np.array([0.0, -u]), theta, view, [], 10.0,
                            1e9)

    t_rel = 0.01 / osc.omega
    u_c = a * (1 - osc.R) * t_rel / 2  # the bounce speed whose accumulation is at t_rel
    assert jump(1.2 * u_c) is None
    assert jump(0.8 * u_c) is not None
    assert jump(0.1 * u_c)[0] == pytest.approx(0.1 * t_rel, rel=1e-12)


def test_chatter_while_another_stop_is_held():
    """Mass 2 held on its stop A (plastic) while mass 1 chatters on U (R = 0.5): each U
    impact is the impulse law with A kept, the accumulation point on U starts a phase
    holding both, and the A phases follow each other without a gap until then."""
    osc = ic.ImpactOscillator(
        M=np.eye(2), K=[[2, -1], [-1, 2]], F=[3.0, 0], F_static=[1.0, 0.5], R=0.5, b=0.0,
        omega=0.7, eta=0.05,
        stops=Stops(extra=(ic.Stop("A", mass=2, gap=0.0, restitution=0.0),)))
    res = simulate(osc, np.zeros(4), math.pi, 1.2, trajectory=True)
    assert res.success and res.chatter and res.chatter[0].stop == "U"
    phases = res.sticking
    both = next(k for k, p in enumerate(phases) if p.stops == "UA")
    assert phases[both].start == res.chatter[0].time
    first_u = res.impact_times[res.impact_stops.index("U")]
    run = [p for p in phases[:both] if p.start >= first_u - 1e-12]
    assert run and all(p.stops == "A" for p in run)
    assert all(a.end == b.start for a, b in zip(run, [*run[1:], phases[both]], strict=True))
    assert res.X[:, 0].max() <= 1e-14 and res.X[:, 1].max() <= 1e-14
