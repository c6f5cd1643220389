"""Every stop at every impact (issue 28, item 1.1): a stop crossed at the end of a flight.

The interior-contact search of eq. (16) looks at the interior extrema of each stop
coordinate; a coordinate still moving towards its stop when the flight ends on a
*different* stop has none there. Every path now checks every stop's clearance at both
ends of every flight (the impact states), and the smallest clearance over a flight, its
interior extrema and its ends, is the GR test function, so the grazing where a coordinate
reaches its stop exactly at another stop's impact is located.

The witness is the event-driven simulator (:func:`impactcont.simulate`); the grazing
frequency is checked against an independent shooting built here on the exact flow of the
first-order system (``scipy.linalg.expm`` of the system with the forcing as two more
states), with ``scipy.optimize.root`` and ``brentq``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, root

import impactcont as ic

# the reproducer of the issue: two masses, U on x1, A on x1 - x2
M = np.diag([1.9509503548057374, 1.0684389244485462])
K = np.array([[3.3856859144467917, -0.6820621880811502],
              [-0.6820621880811502, 0.6820621880811502]])
C = 0.13375577765512228 * np.array([[1.0, -1.0], [-1.0, 1.0]])
F = np.array([0.0, 1.0])
R, B, OMEGA = 0.5164044450566732, 0.05752272035652022, 2.4027041388644625
GAP_A, R_A = 0.21291538036219732, 0.8735671847153306
GUESS = {"delta": -2.6817, "pattern": "UAUUA",
         "flight_times": [2.95998, 2.01896, 1.86219, 1.00942, 2.60965],
         "states": [[0.0575227, 0.11021, -0.268249, -0.185886],
                    [0.0617681, -0.151147, -0.207357, 0.409103],
                    [0.0575227, 1.028042, -0.191523, 0.056407],
                    [0.0575227, 0.094964, -0.024984, -0.165802],
                    [-0.0056492, -0.218565, -0.461035, 0.008696]]}


def _osc(omega=OMEGA, gap=GAP_A):
    return ic.ImpactOscillator(
        M=M, K=K, C=C, F=F, R=R, b=B, omega=omega,
        stops=ic.Stops(extra=(ic.Stop("A", mass=1, relative_to=2, gap=gap,
                                      restitution=R_A),)))


@pytest.fixture(scope="module")
def orbit():
    return ic.multi_impact_orbit(_osc(), 4, 5, GUESS)


# -- an independent shooting of the UAUUA motion on the exact flow (expm) --------------------
_NA = np.array([1.0, -1.0])  # the coordinate x1 - x2 of stop A


def _jump(stop):
    """Velocity jump of an impact on U (eq. 4: -R on x1') or A (two-body law on x1 - x2)."""
    if stop == "U":
        return np.diag([-R, 1.0])
    Mi = np.linalg.inv(M)
    return np.eye(2) - (1.0 + R_A) * np.outer(Mi @ _NA, _NA) / (_NA @ Mi @ _NA)


def _flight(omega, X0, theta, t):
    """State after time t from X0 at forcing phase theta: M x'' + C x' + K x = F cos(phase),
    the forcing carried as ``(cos, sin)`` of the phase, the whole flow one matrix exponential."""
    Mi = np.linalg.inv(M)
    A = np.zeros((6, 6))
    A[0:2, 2:4] = np.eye(2)
    A[2:4, 0:2] = -Mi @ K
    A[2:4, 2:4] = -Mi @ C
    A[2:4, 4] = Mi @ F
    A[4, 5] = -omega
    A[5, 4] = omega
    return (expm(A * t) @ np.concatenate([X0, [math.cos(theta), math.sin(theta)]]))[:4]


def _residual(v, omega, pattern="UAUUA", N=4):
    """``v = [delta, tau_0..tau_3, X_0..X_4]``: the flights, the impact laws and the sections."""
    p = len(pattern)
    delta, taus = v[0], np.append(v[1:p], 2 * math.pi * N / omega - np.sum(v[1:p]))
    X = v[p:].reshape(p, 4)
    out, theta = [], delta
    for k in range(p):
        nxt = (k + 1) % p
        end = _flight(omega, X[k], theta, taus[k])
        out.extend(end[:2] - X[nxt, :2])
        out.extend(_jump(pattern[nxt]) @ end[2:] - X[nxt, 2:])
        theta += omega * taus[k]
    for k in range(p):
        out.append(X[k, 0] - B if pattern[k] == "U" else X[k] @ np.append(_NA, [0, 0]) - GAP_A)
    return np.array(out)


def _reference_clearance(omega, v0):
    """``b - x1`` at the end of flight 0 (just before the A impact) of the motion solved
    independently at `omega` from `v0`; returns it and the solution."""
    sol = root(_residual, v0, args=(omega,), method="hybr", options={"xtol": 1e-13})
    assert sol.success and np.max(np.abs(_residual(sol.x, omega))) < 1e-11
    X0 = sol.x[5:9]
    return B - _flight(omega, X0, sol.x[0], sol.x[1])[0], sol.x


def _unknowns(o):
    return np.concatenate([[o.delta], o.flight_times[:-1], o.states.ravel()])


# -- the orbit ------------------------------------------------------------------------------
def test_orbit_past_a_stop_at_the_end_of_a_flight_is_not_physical(orbit):
    """x1 = 0.0618 > b when flight 0 ends on A: not physical, the reason names x1, U and the
    impact; the simulator from the orbit's first impact hits U before the A impact the
    orbit claims."""
    assert orbit.residual < 1e-12 and orbit.pattern == "UAUUA"
    assert orbit.states[1][0] > B  # the finding, unchanged
    assert not orbit.physical
    assert "impact 1 (stop 'A'): x1 is past stop 'U'" in orbit.reason
    assert orbit.gap_min == pytest.approx(B - orbit.states[1][0], rel=1e-9)
    assert orbit.flight_gap_stops[0] == "U"
    assert orbit.flight_gap_min_times[0] == pytest.approx(orbit.flight_times[0], rel=1e-12)
    # the witness: the first impact after impact 0 is on U, before the claimed A impact
    res = ic.simulate(orbit.oscillator, orbit.states[0], float(orbit.phases[0]), 2.0)
    assert res.impact_stops[0] == "U"
    assert 0.0 < res.impact_times[0] < orbit.flight_times[0] - 1e-3
    # the independent flow: the end of flight 0 is past U by the same amount
    end = _flight(OMEGA, orbit.states[0], float(orbit.phases[0]), float(orbit.flight_times[0]))
    assert B - end[0] == pytest.approx(orbit.gap_min, abs=1e-9)


def test_continuation_locates_the_end_of_flight_grazing(orbit):
    """From the orbit up in omega the branch turns physical at a GR, located between its
    bracketing points to its claimed precision, at the omega where ``b - x1`` at the A
    impact vanishes: found here by brentq on an independent expm shooting."""
    ds = ic.multi_impact_continuation(orbit, "omega", (2.40, 2.41), direction=1)
    labels = ds["special_label"].values.tolist()
    assert "GR" in labels
    i = labels.index("GR")
    assert str(ds["special_status"].values[i]) == "located"
    w = float(ds["special_omega"].values[i])
    lo, hi = (float(ds[f"special_bracket_{s}"].values[i]) for s in ("lo", "hi"))
    assert min(lo, hi) <= w <= max(lo, hi)
    precision = float(ds["special_precision"].values[i])
    assert precision < 1e-8
    # physical on the far side only
    om, phys = ds["omega"].values, ds["physical"].values
    assert not phys[om < w - 1e-9].any() and phys[om > w + 1e-9].all()
    assert (om < w).any() and (om > w).any()
    # the reference: brentq on b - x1(end of flight 0) of the independent shooting
    v0 = _unknowns(orbit)
    g0, v0 = _reference_clearance(OMEGA, v0)
    assert g0 == pytest.approx(orbit.gap_min, abs=1e-9)  # the same motion
    g1, _ = _reference_clearance(2.41, v0)
    assert g0 < 0.0 < g1
    guess = {"v": v0}

    def clearance(om_):
        g, guess["v"] = _reference_clearance(om_, guess["v"])
        return g

    w_ref = brentq(clearance, OMEGA, 2.41, xtol=1e-13, rtol=1e-14)
    assert w_ref == pytest.approx(2.4066, abs=1e-4)  # the value
    # the located GR within its claimed precision (plus the reference's error: its
    # clearance is solved to ~1e-13 and changes by ~1 per unit of omega)
    assert abs(w - w_ref) <= precision + 1e-11


def test_gr_curve_follows_the_end_of_flight_grazing(orbit):
    """The located GR followed in (omega, b) (the minimally augmented curve on gap_min):
    at every curve point the independent flow puts x1 at b exactly when flight 0 ends
    on A."""
    ds = ic.multi_impact_continuation(orbit, "omega", (2.40, 2.41), direction=1)
    cv = ic.multi_impact_curve(ds, "GR", 0, parameter="b",
                               bounds={"omega": (2.38, 2.43), "b": (0.055, 0.06)},
                               ds_max=0.002, max_points=20)
    assert cv.sizes["point"] > 5 and np.ptp(cv["b"].values) > 2e-3
    for i in range(0, cv.sizes["point"], 4):
        om_, b = float(cv["omega"].values[i]), float(cv["b"].values[i])
        X0 = cv["state_k"].values[i, 0]
        end = _flight(om_, X0, float(cv["delta_k"].values[i, 0]),
                      float(cv["flight_time_k"].values[i, 0]))
        assert abs(b - end[0]) < 1e-9  # x1 at U ...
        assert end[0] - end[1] == pytest.approx(GAP_A, abs=1e-9)  # ... at the A impact


# -- the map --------------------------------------------------------------------------------
def test_map_marks_the_motions_past_a_stop_at_an_impact(orbit):
    """The compiled map sweep checks the impact states too: the points below the grazing
    frequency are not physical, those above are, and gap_min is the end clearance."""
    omegas = np.array([2.402, 2.404, 2.409, 2.411])
    m = ic.multi_impact_map(orbit, ("omega", "b"), {"omega": omegas, "b": np.array([B])})
    assert m["found"].values.all()
    physical = m["physical"].values[:, 0]
    gap = m["gap_min"].values[:, 0]
    assert physical.tolist() == [False, False, True, True]
    assert (gap[:2] < 0).all() and (gap[2:] > 0).all()
    # the same as the orbit path at each point
    for i, om_ in enumerate(omegas):
        o = ic.multi_impact_orbit(_osc(om_), 4, 5, orbit)
        assert o.physical == physical[i]
        assert o.gap_min == pytest.approx(gap[i], abs=1e-9)


# -- an N-1 motion whose impact state is past another stop ------------------------------------
def _n1_case():
    """A stable 1-1 motion of the paper's form (U on x1, both masses forced) whose coordinate
    ``x1 - x2`` rises all flight long and peaks at the impact (its velocity reversed there):
    the motion, ``x1 - x2`` at the impact and the time and state of its lowest value."""
    osc = ic.ImpactOscillator(M=M, K=K, C=C, F=[1.0, 1.0], R=R, b=B, omega=2.0)
    found = [o for o in ic.periodic_orbits(osc, 1) if o.physical and o.stable]
    assert len(found) == 1
    o = ic.multi_impact_orbit(osc, 1, 1, found[0])
    t, X = o.time_series(2001)
    s = X[:, 0] - X[:, 1]
    i = int(np.argmin(s))
    assert np.all(np.diff(s[i:]) > 0)  # rising from its minimum to the impact
    return osc, o, float(s[0]), float(t[i]), X[i]


def _with_a(osc, gap):
    return osc.replace(stops=ic.Stops(extra=(ic.Stop("A", mass=1, relative_to=2, gap=gap,
                                                     restitution=R_A),)))


def test_n1_motion_with_its_impact_state_past_an_extra_stop_is_not_physical():
    """An extra stop A on x1 - x2 just below the value of x1 - x2 at the impact, where it
    peaks: x1 - x2 has no interior maximum, so the interior search sees nothing; the
    impact state is past A. The closed form refuses the system (one stop on mass 1 only),
    so the N-1 motion is the shooting path's with p = 1, and it says not physical; the
    simulator from the lowest point of x1 - x2 meets A before U."""
    osc, o, s_impact, t_low, X_low = _n1_case()
    gap = s_impact - 0.01
    extra = _with_a(osc, gap)
    with pytest.raises(ic.ParameterError, match="closed form"):
        ic.periodic_orbits(extra, 1)
    o2 = ic.multi_impact_orbit(extra, 1, 1, o)
    assert o2.residual < 1e-12
    assert not o2.physical
    assert "x1 - x2 is past stop 'A'" in o2.reason
    assert o2.gap_min == pytest.approx(gap - s_impact, rel=1e-9)
    # the witness: from the lowest point of x1 - x2 the simulator meets A first
    res = ic.simulate(extra, X_low, float(o.delta + extra.omega * t_low), 1.0)
    assert res.impact_stops[0] == "A"
    # with A just past the impact value the motion is physical again
    assert ic.multi_impact_orbit(_with_a(osc, s_impact + 1e-3), 1, 1, o).physical


def test_a_one_impact_motion_on_an_extra_stop_past_u_is_not_physical():
    """Found by a scan of random machines' attractors: the simulator settles on a 2-2 UA
    motion; asked for p = 1 from it, the shooting converges to a 1-1 motion on A alone
    whose x1 rises through b and peaks at the A impact (no interior maximum): x1 is past
    U at its one impact state. Not physical (it was before), and the simulator from
    inside its flight meets U before the A impact it claims; the 2-2 UA attractor is
    physical."""
    osc = ic.ImpactOscillator(
        M=np.diag([1.1453207564562706, 1.1274569750313486]),
        K=[[3.21689407610177, -2.5255641805516147], [-2.5255641805516147, 2.5255641805516147]],
        C=[[0.126300889579772, -0.10630088957977202], [-0.10630088957977202, 0.126300889579772]],
        F=[1.0, 0.0], R=0.31806886768997017, b=0.08308003500672473, omega=1.7947248150253279,
        stops=ic.Stops(extra=(ic.Stop("A", mass=1, relative_to=2, gap=0.4285910209962266,
                                      restitution=0.7152853022552419),)))
    res = ic.simulate(osc, np.zeros(4), 0.0, 300.0)
    assert res.impact_stops[-4:] in ("AUAU", "UAUA")
    attractor = ic.multi_impact_orbit(osc, 2, 2, res)
    assert attractor.physical and attractor.stable
    one = ic.multi_impact_orbit(osc, 1, 1, res)
    assert one.pattern == "A" and one.residual < 1e-12
    assert one.states[0][0] > osc.b + 0.01
    assert not one.physical
    assert "impact 0 (stop 'A'): x1 is past stop 'U'" in one.reason
    assert one.gap_min == pytest.approx(osc.b - one.states[0][0], rel=1e-9)
    t, X = one.time_series(201)
    sim = ic.simulate(osc, X[20], float(one.delta + osc.omega * t[20]), 1.0)
    assert sim.impact_stops[0] == "U" and t[20] + sim.impact_times[0] < one.period - 0.01


def test_the_rounding_of_an_impact_state_is_not_a_crossing():
    """A stop exactly at the impact value of its coordinate (the motion at its grazing
    point, up to rounding): the clearance is within the tolerance relative to the motion's
    size and the motion stays physical; a clearance below it is a crossing."""
    from impactcont.kernel.shooting import end_clearances

    osc, o, s_impact, _, _ = _n1_case()
    o2 = ic.multi_impact_orbit(_with_a(osc, s_impact), 1, 1, o)
    assert abs(o2.gap_min) < 1e-13
    assert o2.physical, o2.reason
    # the kernel's tolerance scales with the motion's size, not an absolute 1e-12
    normal = np.array([1.0, 0.0])
    na = np.array([[1.0, -1.0]])
    for size in (1e-6, 1.0, 1e6):
        state = np.array([[size, 0.5 * size, 0.0, 0.0]])
        for shift, crossed in ((-1e-14, False), (-1e-12, True)):
            gap, stop, tol = end_clearances(normal, False, size, 0.0, normal[None, :],
                                            np.array([1.0]), na, np.array([1.0]),
                                            np.array([0.5 * size * (1.0 + shift)]), state,
                                            state.copy())
            assert stop[0, 0] == 2 and gap[0, 0] < 0.0
            assert (gap[0, 0] < -tol[0, 0]) == crossed, (size, shift)
