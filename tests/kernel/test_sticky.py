"""The compiled corrector of a branch in omega of a motion with sticking phases
(:mod:`impactcont.kernel.sticky`): the step of the continuation core from a predicted point,
against the same bordered Newton in numpy on the residual and omega column of each omega's
oscillator built afresh."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel.shooting import CONVERGED, REFUSED
from impactcont.model.stops import Stops
from impactcont.orbit.flow import flow_of
from impactcont.orbit.sticky import (
    sticky_omega_column,
    sticky_palc_step,
    sticky_shooting,
)


def _damper(omega: float, **damping) -> ic.ImpactOscillator:
    """The impact damper of studies/sticking_motions (case c): the ball rides each wall."""
    damping = damping or {"eta": 0.3}
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega,
                               stops=Stops(mass=2, relative_to=1, mirror=True), **damping)


@pytest.fixture(scope="module")
def riding():
    """The ball riding each wall ("lu") at omega 1.2, from its simulated steady state."""
    osc = _damper(1.2)
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    start = np.array([x1, x1 + osc.b, v1, v1])
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, start, 0.0, 16.0))
    assert orbit.pattern == "lu" and orbit.physical
    return orbit


def _linearized(omega: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The residual and ``[J | dr/domega]`` from the oscillator at `omega` built afresh."""
    flow = flow_of(_damper(omega))
    sh = sticky_shooting(flow, 1, "lu", u)
    return sh.residual, np.column_stack([sh.jacobian, sticky_omega_column(flow, 1, "lu", u,
                                                                          sh)])


def _numpy_corrector(predicted, tangent, weights, tol, max_iter):
    """The bordered Newton of the continuation core (``palc_correct``'s arithmetic) in
    numpy, each iterate's flow and held systems built afresh."""
    state = predicted.copy()
    border = weights * tangent
    for _ in range(max_iter):
        residual, extended = _linearized(state[-1], state[:-1])
        A = np.vstack([extended, border])
        rhs = -np.concatenate([residual, [border @ (state - predicted)]])
        update = np.linalg.solve(A, rhs)
        state += update
        if np.max(np.abs(update)) <= tol:
            return state
    raise AssertionError("the numpy corrector did not converge")


def test_the_compiled_step_is_the_bordered_newton_of_the_core(riding):
    """From a point predicted 0.05 along the tangent of the riding motion's branch: the
    compiled step converges to the point of the numpy Newton (1e-10), on the arclength
    hyperplane, with the residual of the oscillator at its omega under 1e-10, and returns
    the tangent there (``[J | dr/domega] t = 0``, ``W t0 . t = 1``)."""
    u0 = riding.unknowns
    residual, extended = _linearized(1.2, u0)
    assert np.max(np.abs(residual)) < 1e-10
    tangent = np.linalg.svd(extended)[2][-1]
    tangent *= np.sign(tangent[-1])
    weights = np.ones(tangent.size)
    predicted = np.concatenate([u0, [1.2]]) + 0.05 * tangent
    out = sticky_palc_step(flow_of(riding.oscillator), 1, "lu", predicted, tangent, weights,
                           1e-12, 10, 1e12)
    assert out.status == CONVERGED and 1 <= out.iterations <= 6
    assert out.omega == out.state[-1] and abs(out.omega - 1.2) > 0.005
    reference = _numpy_corrector(predicted, tangent, weights, 1e-13, 10)
    np.testing.assert_allclose(out.state, reference, rtol=0, atol=1e-10)
    residual, extended = _linearized(out.omega, out.state[:-1])
    assert np.max(np.abs(residual)) < 1e-10
    assert abs((weights * tangent) @ (out.state - predicted)) < 1e-12
    t = out.tangent
    assert np.max(np.abs(extended @ t)) < 1e-9 * np.max(np.abs(t))
    assert (weights * tangent) @ t == pytest.approx(1.0, abs=1e-12)


def test_the_compiled_step_refuses_what_it_cannot_do(riding):
    """An iterate at omega <= 0 is REFUSED; hyperplane mode stops on the update alone; a
    first-order flow (dashpot on the primary only) is refused naming the flow, and
    arrays of another size naming them."""
    u0 = np.concatenate([riding.unknowns, [1.2]])
    flow = flow_of(riding.oscillator)
    e = np.zeros(u0.size)
    e[-1] = 1.0
    off = u0.copy()
    off[-1] = -0.5
    out = sticky_palc_step(flow, 1, "lu", off, e, np.ones(u0.size), 1e-12, 5, 1e12)
    assert out.status == REFUSED and out.omega == -0.5
    moved = u0.copy()
    moved[-1] = 1.21
    out = sticky_palc_step(flow, 1, "lu", moved, e, np.ones(u0.size), 1e-12, 10, 1e12,
                           hyperplane=True)
    assert out.status == CONVERGED and out.state[-1] == 1.21
    assert np.max(np.abs(_linearized(1.21, out.state[:-1])[0])) < 1e-10
    general = flow_of(_damper(1.2, C=[[0.3, 0.0], [0.0, 0.0]]))
    with pytest.raises(ic.ParameterError, match="flow must be a modal flow"):
        sticky_palc_step(general, 1, "lu", u0, e, np.ones(u0.size), 1e-12, 5, 1e12)
    with pytest.raises(ic.ParameterError, match=r"tangent must have shape \(11,\)"):
        sticky_palc_step(flow, 1, "lu", u0, e[:-1], np.ones(u0.size), 1e-12, 5, 1e12)


def _capped_riding() -> tuple[ic.ImpactOscillator, np.ndarray]:
    """The riding damper with R = 0.3 at omega 0.8 under a stop A on the primary at x1 =
    -1.80 that the lower chatter's bounces reach (tests/orbit/test_sticky.py), and the
    unknowns of its motion without A."""
    osc = _damper(0.8).replace(R=0.3)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.array([-0.5, -0.2, 0.0,
                                                                         0.0]), 0.0, 8.0))
    assert motion.physical and motion.pattern == "lu", motion.reason
    extra = (ic.Stop("A", mass=1, gap=1.80, restitution=0.5, side=-1),)
    return osc.replace(stops=Stops(mass=2, relative_to=1, mirror=True, extra=extra)), \
        motion.unknowns


def test_chatter_checks_are_the_flights_checks_of_the_replayed_bounces():
    """:func:`impactcont.kernel.sticky.chatter_checks` on the capped riding damper: its
    bounces are bitwise the shooting path's replay (``kernel.shooting.chatter_bounces``),
    and each stop's smallest clearance, its time from the landing and whether a bounce
    crosses it are those of the bounces checked as flights (``motion_checks``' interior
    extrema, ``end_clearances``' ends) reduced in numpy: A crossed, U not."""
    from impactcont.kernel import shooting
    from impactcont.kernel.arrays import MotionChecks
    from impactcont.kernel.sticky import chatter_checks
    from impactcont.orbit.multi_impact import Shooting as Flights
    from impactcont.orbit.multi_impact import (
        _geometry,
        checked_flights,
        contact_stops,
        impact_sequence,
    )
    from impactcont.orbit.sticky import held_segments

    osc, u = _capped_riding()
    flow = flow_of(osc)
    sh = sticky_shooting(flow, 1, "lu", u)
    geo = _geometry(flow, "LU")
    held = held_segments(flow, "lu")
    X0 = np.array(sh.starts[0])
    out = chatter_checks(tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
                         tuple(impact_sequence(geo)), held, tuple(contact_stops(geo)), 0, 1,
                         X0, float(sh.phases[0]), True)
    *log, count, gap, when, crossed, present = out
    *replay, replayed = shooting.chatter_bounces(
        flow.flight_arrays(), tuple(flow.forcing_arrays()), tuple(impact_sequence(geo)), held,
        0, X0, float(sh.phases[0]))
    assert count == replayed > 0
    for mine, theirs in zip(log, replay, strict=True):
        np.testing.assert_array_equal(mine, theirs)
    starts, phases, times, arrivals, transitions, pcols, rates = (a[:count] for a in log)
    own = _geometry(flow, "L" * count)
    checked = MotionChecks._make(shooting.motion_checks(
        tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
        tuple(impact_sequence(own)), tuple(contact_stops(own)),
        tuple(checked_flights(Flights(phases=phases, flight_times=times, starts=starts,
                                      arrivals=arrivals, arrival_rates=rates,
                                      transitions=transitions, phase_columns=pcols,
                                      residual=np.zeros(0), jacobian=None))), True))
    end_gap, end_stop, end_tol = shooting.end_clearances(
        own.normal, own.two_sided, own.b, own.b_low, own.normals, own.signs,
        own.extra_normals, own.extra_signs, own.extra_positions, starts, arrivals)
    offsets = np.concatenate(([0.0], np.cumsum(times)[:-1]))
    inner = {0: (checked.gap_upper, checked.time_upper),
             2: (checked.gap_extra[:, 0], checked.time_extra[:, 0])}
    for stop in (0, 2):  # U and A (L is the chatter's own stop)
        gaps, at = inner[stop]
        kept = ~np.isposinf(gaps)
        ends = end_stop == stop
        entries = np.concatenate([gaps[kept], end_gap[ends]])
        times_of = np.concatenate([offsets[kept] + at[kept],
                                   (offsets[:, None] + np.array([0.0, 1.0]) * times[:, None])
                                   [ends]])
        hits = np.concatenate([~(gaps[kept] > 0.0), end_gap[ends] < -end_tol[ends]])
        assert present[stop] == (entries.size > 0)
        i = int(np.argmin(entries))
        assert gap[stop] == entries[i] and when[stop] == times_of[i]
        assert crossed[stop] == hits.any()
    assert crossed[2] and not crossed[0] and not present[1]


def test_the_compiled_step_returns_the_converged_point_s_shot(riding):
    """``with_shot``: the shot the compiled step made at its converged point is
    :func:`sticky_shooting`'s there on the oscillator at its omega built afresh (residual,
    Jacobian, releases and stick times to 1e-12); none on the hyperplane (its last update
    follows its last shot)."""
    u0 = riding.unknowns
    e = np.zeros(u0.size + 1)
    e[-1] = 1.0
    predicted = np.concatenate([u0, [1.21]])
    flow = flow_of(riding.oscillator)
    out, shot = sticky_palc_step(flow, 1, "lu", predicted, e, np.ones(e.size), 1e-12, 10,
                                 1e12, with_shot=True)
    assert out.status == CONVERGED and shot is not None
    fresh = sticky_shooting(flow_of(_damper(out.omega)), 1, "lu", out.state[:-1])
    for name in ("residual", "jacobian", "releases", "stick_times", "arrivals",
                 "transitions"):
        np.testing.assert_allclose(getattr(shot, name), getattr(fresh, name), rtol=0,
                                   atol=1e-12, err_msg=name)
    _, none = sticky_palc_step(flow, 1, "lu", predicted, e, np.ones(e.size), 1e-12, 10, 1e12,
                               hyperplane=True, with_shot=True)
    assert none is None


def test_sticky_motions_compile_each_entry_point_once(riding):
    """A plastic ride and a ride entered through complete chatter (R 0.3, omega 0.2), each
    solved at a nearby omega and checked, share one compiled version of each entry point of
    a motion with sticking phases (the Newton loop is the one of ``newton_solve``,
    ``_newton``, compiled for the sticky system; ``sticky_jacobians`` G from the shot)."""
    from impactcont.kernel import shooting as shooting_kernel

    chatter_osc = _damper(0.2).replace(R=0.3)
    m, c, omega = chatter_osc.M[1, 1], chatter_osc.C[0, 0], chatter_osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    chatter = ic.multi_impact_orbit(chatter_osc, 1, 2, ic.simulate(
        chatter_osc, np.array([x1, x1 + chatter_osc.b, v1, v1]), 0.0, 12.0))
    assert chatter.pattern == "lu" and chatter.physical
    for start in (riding, chatter):
        osc = start.oscillator.replace(omega=start.oscillator.omega + 0.005)
        orbit = ic.multi_impact_orbit(osc, 1, 2, start)
        assert orbit.physical and orbit.residual < 1e-12
    for name in ("sticky_newton_solve", "sticky_jacobians"):
        assert len(getattr(shooting_kernel, name).signatures) == 1, name
