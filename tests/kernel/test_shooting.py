"""The compiled N-p shooting (impactcont.kernel.shooting) against the numpy flow."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stop, Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import (
    multi_impact_orbit,
    omega_partials,
    orbit_from_unknowns,
    shooting,
)
from impactcont.orbit.stop_geometry import stop_geometry
from impactcont.simulate.contact import flight_clearances

K2 = [[1.0, -1.0], [-1.0, 2.0]]
K3 = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
CASES = {
    # (oscillator, N, pattern)
    "paper 2-2": (ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.0,
                                      omega=1.75, eta=0.1), 2, "UU"),
    "backlash 1-2": (ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8,
                                         omega=0.8, eta=0.1, stops=Stops(b_low=0.8)), 1, "LU"),
    "mass 2, unequal stops": (ic.ImpactOscillator(M=np.eye(3), K=K3, F=[1.0, 0.0, 0.0], R=0.7,
                                                  b=0.5, omega=1.4, eta=0.15,
                                                  stops=Stops(mass=2, b_low=0.4, R_low=0.8)),
                              2, "ULU"),
    "damper on mass 1 (any C)": (ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6,
                                                     b=0.8, omega=0.8, C=[[0.3, 0.0], [0.0, 0.0]],
                                                     stops=Stops(b_low=0.8)), 1, "LU"),
    # free modes C leaves undamped (issue 30, item 5): the first-order flow's polynomial part
    "impact damper, undamped ball (any C)": (
        ic.ImpactOscillator(M=np.diag([1.0, 0.5, 0.2]), K=[[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0],
                                                            [0.0, 0.0, 0.0]],
                            C=np.diag([0.1, 0.0, 0.0]), F=[1.0, 0.0, 0.0], R=0.6, b=0.3,
                            omega=0.9, stops=Stops(mass=3, relative_to=2, mirror=True)), 1, "UL"),
}

# the flights alone (the contact test's reference knows U and L only and wants an interior
# extremum): a ball under gravity (monotone flights from generic unknowns) and two free
# balls, each in its own cavity of the primary (one stop coordinate each)
FLIGHT_CASES = {
    **CASES,
    "ball under gravity in a cavity (any C)": (
        ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                            C=[[0.1, 0.0], [0.0, 0.0]], F_static=[0.0, -0.1], R=0.7, b=0.5,
                            omega=1.3, stops=Stops(mass=2, relative_to=1, b_low=0.0,
                                                   R_low=0.7)), 1, "LUL"),
    "two free balls (any C)": (
        ic.ImpactOscillator(M=np.diag([1.0, 0.3, 0.2]), K=np.diag([1.0, 0.0, 0.0]),
                            C=np.diag([0.05, 0.0, 0.0]), F=[1.0, 0.0, 0.0],
                            F_static=[0.0, 0.0, -0.05], R=0.6, b=0.4, omega=1.1,
                            stops=Stops(mass=2, relative_to=1, mirror=True,
                                        extra=(Stop("A", mass=3, gap=0.5, restitution=0.5,
                                                    relative_to=1),
                                               Stop("B", mass=3, gap=0.5, restitution=0.5,
                                                    side=-1, relative_to=1)))), 1, "UL"),
}


def _unknowns(osc, N, pattern):
    """Unknowns of a generic (unsolved) shooting point: flights of unequal length."""
    p, n = len(pattern), osc.n
    period = 2 * math.pi * N / osc.omega
    taus = period * np.linspace(1.0, 2.0, p) / np.linspace(1.0, 2.0, p).sum()
    rng = np.random.default_rng(7)
    return np.concatenate([[0.3], taus[:-1], 0.4 * rng.standard_normal(p * (2 * n - 1))])


def _numpy_shooting(flow, N, p, u, pattern):
    """The shooting system from the numpy flow (Flow.matrices, Flow.state_derivative)."""
    osc = flow.osc
    m, omega = 2 * osc.n, osc.omega
    geo = stop_geometry(osc, pattern)
    j, n = geo.pivot, osc.n
    taus = np.append(u[1:p], 2 * math.pi * N / omega - np.sum(u[1:p]))
    starts = np.empty((p, m))
    starts[:, np.delete(np.arange(m), j)] = u[p:].reshape(p, m - 1)
    others = np.delete(np.arange(n), j)  # on the section n . x = c_k
    starts[:, j] = (geo.positions - starts[:, others] @ geo.normals[0, others]) / geo.normals[0, j]
    phases = u[0] + omega * np.concatenate([[0.0], np.cumsum(taus[:-1])])
    out = {"transitions": [], "arrivals": [], "phase_columns": [], "arrival_rates": []}
    for k in range(p):
        trans, forcing, static = flow.matrices(taus[k], static=True)
        c, s = math.cos(phases[k]), math.sin(phases[k])
        out["transitions"].append(trans)
        out["arrivals"].append(trans @ starts[k] + forcing @ [c, s] + static)
        out["phase_columns"].append(forcing @ [-s, c])
        out["arrival_rates"].append(flow.state_derivative(taus[k], starts[k], phases[k])[0])
    out = {key: np.array(v) for key, v in out.items()}
    out["residual"] = (np.einsum("kij,kj->ki", np.roll(geo.matrices, -1, axis=0),
                                 out["arrivals"]) - np.roll(starts, -1, axis=0)).ravel()
    out.update(starts=starts, phases=phases, flight_times=taus)
    return out


@pytest.mark.parametrize("case", FLIGHT_CASES)
def test_shooting_matches_the_numpy_flow(case):
    """Every field of Shooting as the numpy flow gives it, for both flows, both stops and a
    stop on mass 2 (one rounding of the exact flow: 1e-12 of the sizes involved)."""
    osc, N, pattern = FLIGHT_CASES[case]
    flow, p = Flow(osc), len(pattern)
    u = _unknowns(osc, N, pattern)
    sh = shooting(flow, N, p, u, pattern=pattern)
    ref = _numpy_shooting(flow, N, p, u, pattern)
    for key, value in ref.items():
        got = getattr(sh, key)
        assert got.shape == value.shape, key
        np.testing.assert_allclose(got, value, rtol=0, atol=1e-12 * max(1.0, np.abs(value).max()),
                                   err_msg=key)


@pytest.mark.parametrize("case", FLIGHT_CASES)
def test_jacobian_is_the_derivative_of_the_residual(case):
    """The exact Jacobian against central differences (step 1e-6: error ~1e-9)."""
    osc, N, pattern = FLIGHT_CASES[case]
    flow, p = Flow(osc), len(pattern)
    u = _unknowns(osc, N, pattern)
    J = shooting(flow, N, p, u, pattern=pattern).jacobian
    h = 1e-6
    columns = [(shooting(flow, N, p, u + h * e, pattern=pattern, jacobian=False).residual
                - shooting(flow, N, p, u - h * e, pattern=pattern, jacobian=False).residual)
               / (2 * h) for e in np.eye(u.size)]
    np.testing.assert_allclose(J, np.array(columns).T, rtol=0, atol=1e-7 * np.abs(J).max())


@pytest.mark.parametrize("case", FLIGHT_CASES)
def test_omega_partials_match_the_flow(case):
    """dX^-/d omega of every flight at once, as Flow.omega_partial gives each."""
    osc, N, pattern = FLIGHT_CASES[case]
    flow, p = Flow(osc), len(pattern)
    sh = shooting(flow, N, p, _unknowns(osc, N, pattern), pattern=pattern, jacobian=False)
    ref = np.array([flow.omega_partial(float(sh.flight_times[k]), sh.starts[k],
                                       float(sh.phases[k])) for k in range(p)])
    np.testing.assert_allclose(omega_partials(flow, sh), ref, rtol=0,
                               atol=1e-12 * np.abs(ref).max())


def _end_gaps(osc, pattern, sh, k):
    """``[(clearance, time)]`` at both ends of flight k against every stop U, L but the one
    hit there (the impact states), from the states in numpy."""
    s = osc.stops.normal(osc.n)
    out = []
    for end, state, hit in ((0, sh.starts[k], pattern[k]),
                            (1, sh.arrivals[k], pattern[(k + 1) % len(pattern)])):
        x = float(np.dot(s, state[:osc.n]))
        if hit != "U":
            out.append((osc.b - x, 0.0 if end == 0 else float(sh.flight_times[k])))
        if hit != "L" and osc.stops.two_sided:
            out.append((x + osc.stops.b_low, 0.0 if end == 0 else float(sh.flight_times[k])))
    return out


@pytest.mark.parametrize("case", CASES)
def test_contact_search_matches_the_reference_search(case):
    """The compiled search of eq. (16) against both stops (the kernel's grid and polish)
    finds the same extrema as the simulator's numpy search (flight_clearances): the same
    clearance to each stop within the polish's precision, at the same time; a flight's
    gap is the smallest of those and of every other stop's clearance at its two ends."""
    osc, N, pattern = CASES[case]
    flow, p = Flow(osc), len(pattern)
    sh = shooting(flow, N, p, _unknowns(osc, N, pattern), pattern=pattern, jacobian=False)
    orbit = orbit_from_unknowns(flow, N, p, _unknowns(osc, N, pattern), sh, pattern=pattern)
    found_lower = False
    for k in range(p):
        gap_u, t_u, gap_l, t_l = flight_clearances(flow, sh.starts[k], float(sh.phases[k]),
                                                   float(sh.flight_times[k]))
        gap, time = min([(gap_u, t_u), (gap_l, t_l), *_end_gaps(osc, pattern, sh, k)],
                        key=lambda c: c[0])
        assert orbit.flight_gap_lower[k] == pytest.approx(gap_l, rel=0, abs=1e-10)
        assert orbit.flight_gap_min[k] == pytest.approx(gap, rel=0, abs=1e-10)
        if math.isfinite(gap):
            assert orbit.flight_gap_min_times[k] == pytest.approx(time, rel=0, abs=1e-7)
        found_lower |= math.isfinite(gap_l)
    assert found_lower == osc.stops.two_sided


def test_solved_motions_of_both_flows_compile_each_entry_point_once():
    """A modal and a first-order motion share one compiled version of each entry point
    (fixed argument types: the flows pass empty arrays for the other flow's inputs)."""
    from impactcont.kernel import shooting as shooting_kernel

    for case in ("backlash 1-2", "damper on mass 1 (any C)"):
        osc, N, pattern = CASES[case]
        res = ic.simulate(osc, np.zeros(2 * osc.n), 0.0, 60.0)
        orbit = multi_impact_orbit(osc, N, len(pattern), res)
        assert orbit.physical and orbit.residual < 1e-12
    for name in ("newton_solve", "motion_checks"):
        assert len(getattr(shooting_kernel, name).signatures) == 1, name


def test_orbit_code_does_not_import_the_simulator():
    """The simulator is the independent witness of the orbit code: orbit/ imports nothing
    from impactcont.simulate."""
    orbit_dir = Path(ic.__file__).parent / "orbit"
    for path in orbit_dir.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([node.module or ""] if isinstance(node, ast.ImportFrom)
                     else [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            assert not any(n.startswith("impactcont.simulate") for n in names), path.name
